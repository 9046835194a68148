/* Ascii PLY bodies: a whitespace-separated token stream read row by row.
 *
 * Rows are not required to sit on one line each (writers disagree); a row is just the
 * next tokens. Values the mesh does not use are skipped without being parsed; used
 * values go through the exact fast parsers in ply_number.c, integers are range-checked
 * against their declared type, and list lengths are checked against the bytes left (an
 * item takes at least two bytes) before anything is reserved for them.
 */
#include <string.h>

#include "formats/ply_row.h"

static inline int is_ws(unsigned char c)
{
    return c == ' ' || (unsigned)(c - '\t') < 5u; /* \t \n \v \f \r */
}

static int end_of_data(ply_reader *r)
{
    return sl_ply_body_error(r, SL_E_BADINPUT, "file ends inside element %s (%llu rows declared)",
                             r->elem->name, (unsigned long long)r->elem->count);
}

/* Skips whitespace; nonzero when a token follows. */
static inline const unsigned char *skip_ws(const unsigned char *p, const unsigned char *end)
{
    while (p < end && is_ws(*p))
        p++;
    return p;
}

/* (Cursor moves go through locals: a byte read could alias r->p, so the compiler would
 * otherwise store and reload it for every character.) */
static inline int at_token(ply_reader *r)
{
    r->p = skip_ws(r->p, r->end);
    return r->p < r->end;
}

static int bad_token(ply_reader *r, const ply_property *p, int type)
{
    char show[40];
    size_t n = 0;
    for (const unsigned char *s = r->p; s < r->end && !is_ws(*s) && n < sizeof show - 4; s++)
        show[n++] = *s < 32 || *s > 126 ? '?' : (char)*s;
    show[n] = 0;
    return sl_ply_body_error(r, SL_E_BADINPUT, "property '%s': '%s' is not a valid %s", p->name,
                             show, sl_ply_type_name(type));
}

static int int_in_range(int type, int64_t v)
{
    static const int64_t lo[] = {0, -128, 0, -32768, 0, -2147483648LL, 0};
    static const int64_t hi[] = {0, 127, 255, 32767, 65535, 2147483647LL, 4294967295LL};
    return type >= PLY_INT8 && type <= PLY_UINT32 && v >= lo[type] && v <= hi[type];
}

static int read_value(ply_reader *r, const ply_property *p, int type, double *out)
{
    if (!at_token(r))
        return end_of_data(r);
    const char *s = (const char *)r->p, *end = (const char *)r->end, *q;
    if (type == PLY_FLOAT32) {
        float f = 0;
        q = sl_ply_parse_float(s, end, &f);
        *out = f;
    } else if (type == PLY_FLOAT64) {
        q = sl_ply_parse_double(s, end, out);
    } else {
        int64_t v = 0;
        q = sl_ply_scan_int(s, end, &v);
        if (q && !int_in_range(type, v))
            return sl_ply_body_error(r, SL_E_BADINPUT, "property '%s': %lld is out of range for %s",
                                     p->name, (long long)v, sl_ply_type_name(type));
        *out = (double)v;
    }
    if (!q)
        return bad_token(r, p, type);
    r->p = (const unsigned char *)q;
    return 0;
}

static int skip_value(ply_reader *r)
{
    const unsigned char *p = skip_ws(r->p, r->end), *end = r->end;
    if (p == end) {
        r->p = p;
        return end_of_data(r);
    }
    while (p < end && !is_ws(*p))
        p++;
    r->p = p;
    return 0;
}

/* Values the mesh does not use are skipped unparsed. */
static int ascii_value(ply_reader *r, const ply_property *p, int type, double *out)
{
    return out ? read_value(r, p, type, out) : skip_value(r);
}

/* Every ascii item takes a digit and a separator, the last maybe only the digit. */
static uint64_t ascii_room(const ply_reader *r, int type)
{
    (void)type;
    return (uint64_t)(r->end - r->p) / 2 + 1;
}

/* The next token as an unsigned decimal of 1..8 digits followed by whitespace (12 bytes
 * of data needed); NULL for anything else: the general path then decides. */
static inline const unsigned char *next_index(const unsigned char *p, const unsigned char *end,
                                              uint64_t *out)
{
    p = skip_ws(p, end);
    if (end - p < 12)
        return NULL;
    int n = sl_ply_digits8((const char *)p, out);
    return n > 0 && n < 8 && is_ws(p[n]) ? p + n : NULL;
}

/* Rows "3 a b c" with every index < limit, at most `rows` of them, into t; stops before
 * any other row. */
static uint64_t triangle_run(ply_reader *r, uint64_t rows, uint64_t limit, uint32_t *t)
{
    const unsigned char *p = r->p, *end = r->end, *q;
    uint64_t i = 0, a, b, c;
    for (; i < rows; i++, p = q) {
        q = skip_ws(p, end);
        if (end - q < 2 || q[0] != '3' || !is_ws(q[1]) || !(q = next_index(q + 1, end, &a)) ||
            !(q = next_index(q, end, &b)) || !(q = next_index(q, end, &c)) || a >= limit ||
            b >= limit || c >= limit)
            break;
        t[3 * i] = (uint32_t)a, t[3 * i + 1] = (uint32_t)b, t[3 * i + 2] = (uint32_t)c;
    }
    r->p = p;
    return i;
}

static int plain_faces(ply_reader *r, const ply_element *e)
{
    static const uint64_t type_limit[] = {0, 128, 256, 32768, 65536, 1ull << 31, 1ull << 32};
    uint64_t limit = type_limit[r->h->props[e->first_prop].type];
    limit = r->mesh->vertex_count < limit ? r->mesh->vertex_count : limit;
    return ply_read_triangles(r, e, limit, triangle_run, ascii_value, ascii_room);
}

static int read_float_into(ply_reader *r, const ply_property *p, float *dst)
{
    const char *q;
    if (!at_token(r))
        return end_of_data(r);
    if (!(q = sl_ply_parse_float((const char *)r->p, (const char *)r->end, dst)))
        return bad_token(r, p, PLY_FLOAT32);
    r->p = (const unsigned char *)q;
    return 0;
}

/* Rows of scalars (vertices): float properties parse straight into the mesh arrays. */
static int scalar_rows(ply_reader *r, const ply_element *e)
{
    const ply_property *props = &r->h->props[e->first_prop];
    float *column[PLY_MAX_PROPERTIES];
    size_t stride[PLY_MAX_PROPERTIES];
    for (int k = 0; k < e->nprops; k++)
        column[k] = props[k].type == PLY_FLOAT32 && e->kind == KIND_VERTEX
                        ? sl_ply_float_column(r->mesh, props[k].role, &stride[k]) : NULL;
    int rc;
    double v;
    for (uint64_t row = 0; row < e->count; row++) {
        r->row = row;
        if ((row & PLY_TICK_ROWS) == 0 && (rc = sl_ply_tick(r)))
            return rc;
        for (int k = 0; k < e->nprops; k++) {
            const ply_property *p = &props[k];
            if (column[k])
                rc = read_float_into(r, p, column[k] + row * stride[k]);
            else if (p->role == ROLE_SKIP)
                rc = skip_value(r);
            else if (!(rc = read_value(r, p, p->type, &v)))
                sl_ply_store_vertex(r, row, p->role, p->type, v);
            if (rc)
                return rc;
        }
    }
    return 0;
}

static int is_plain_face(const ply_reader *r, const ply_element *e)
{
    return e->kind == KIND_FACE && e->nprops == 1 &&
           r->h->props[e->first_prop].role == ROLE_INDICES;
}

int sl_ply_ascii_element(ply_reader *r, const ply_element *e)
{
    if (e->nprops == 0)
        return 0;
    if (e->fixed_row)
        return scalar_rows(r, e);
    if (is_plain_face(r, e))
        return plain_faces(r, e);
    return ply_read_rows(r, e, ascii_value, ascii_room);
}
