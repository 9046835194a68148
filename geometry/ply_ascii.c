/* Ascii PLY bodies: a whitespace-separated token stream read row by row.
 *
 * Rows are not required to sit on one line each (writers disagree); a row is just the
 * next tokens. Values the mesh does not use are skipped without being parsed; used
 * values go through the exact fast parsers in ply_number.c, integers are range-checked
 * against their declared type, and list lengths are checked against the bytes left (an
 * item takes at least two bytes) before anything is reserved for them.
 */
#include <string.h>

#include "geometry/ply_row.h"

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
static inline int at_token(ply_reader *r)
{
    while (r->p < r->end && is_ws(*r->p))
        r->p++;
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
        q = sl_ply_parse_int(s, end, &v);
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
    if (!at_token(r))
        return end_of_data(r);
    while (r->p < r->end && !is_ws(*r->p))
        r->p++;
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
    return (uint64_t)(r->end - r->p) / 2 + 1;
}

int sl_ply_ascii_element(ply_reader *r, const ply_element *e)
{
    return e->nprops == 0 ? 0 : ply_read_rows(r, e, ascii_value, ascii_room);
}
