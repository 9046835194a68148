/* Binary PLY bodies (little and big endian).
 *
 * Elements without lists have fixed-size rows: one size check for the whole element,
 * then vertex properties are converted column by column over blocks of rows (a tight
 * typed loop per property instead of a type switch per value). The usual face layout,
 * one `list uchar int` of three indices, has its own loop; every other row (polygons,
 * extra properties, errors) goes through the general row reader, which checks each list
 * length against the bytes left before touching them.
 */
#include <string.h>

#include "formats/ply_row.h"

#define BLOCK_ROWS 4096

static inline uint16_t load16(const unsigned char *p, int swap)
{
    uint16_t v;
    memcpy(&v, p, sizeof v);
    return swap ? __builtin_bswap16(v) : v;
}

static inline uint32_t load32(const unsigned char *p, int swap)
{
    uint32_t v;
    memcpy(&v, p, sizeof v);
    return swap ? __builtin_bswap32(v) : v;
}

static inline uint64_t load64(const unsigned char *p, int swap)
{
    uint64_t v;
    memcpy(&v, p, sizeof v);
    return swap ? __builtin_bswap64(v) : v;
}

static inline double load_scalar(const unsigned char *p, int type, int swap)
{
    uint32_t b32;
    uint64_t b64;
    float f;
    double d;
    switch (type) {
    case PLY_INT8: return (int8_t)p[0];
    case PLY_UINT8: return p[0];
    case PLY_INT16: return (int16_t)load16(p, swap);
    case PLY_UINT16: return load16(p, swap);
    case PLY_INT32: return (int32_t)load32(p, swap);
    case PLY_UINT32: return load32(p, swap);
    case PLY_FLOAT32:
        b32 = load32(p, swap);
        memcpy(&f, &b32, sizeof f);
        return f;
    case PLY_FLOAT64:
        b64 = load64(p, swap);
        memcpy(&d, &b64, sizeof d);
        return d;
    default: return 0;
    }
}

/* dst[i * dst_stride] = column value of row i, for n rows of `stride` bytes. */
static void column_to_float(const unsigned char *src, size_t stride, size_t n, int type,
                            int swap, float *dst, size_t dst_stride)
{
    if (type == PLY_FLOAT32 && !swap) {
        for (size_t i = 0; i < n; i++)
            memcpy(&dst[i * dst_stride], src + i * stride, sizeof(float));
    } else if (type == PLY_FLOAT32) {
        for (size_t i = 0; i < n; i++) {
            uint32_t b = __builtin_bswap32(load32(src + i * stride, 0));
            memcpy(&dst[i * dst_stride], &b, sizeof b);
        }
    } else {
        for (size_t i = 0; i < n; i++)
            dst[i * dst_stride] = sl_ply_to_float(load_scalar(src + i * stride, type, swap));
    }
}

static const ply_property *find_role(const ply_reader *r, const ply_element *e, int role)
{
    for (int k = 0; k < e->nprops; k++)
        if (r->h->props[e->first_prop + k].role == role)
            return &r->h->props[e->first_prop + k];
    return NULL;
}

/* x y z (or nx ny nz) stored as three native floats side by side: one 12-byte copy per
 * row, or one copy of the whole block when that is all a row holds. */
static int copy_triplets(const ply_reader *r, const ply_element *e, int role,
                         const unsigned char *block, size_t n, float *dst)
{
    const ply_property *a = find_role(r, e, role), *b = find_role(r, e, role + 1),
                       *c = find_role(r, e, role + 2);
    if (!dst || !a || !b || !c || r->swap || a->type != PLY_FLOAT32 ||
        b->type != PLY_FLOAT32 || c->type != PLY_FLOAT32 || b->offset != a->offset + 4 ||
        c->offset != a->offset + 8)
        return 0;
    size_t stride = (size_t)e->row_bytes;
    if (stride == 12) {
        memcpy(dst, block, 12 * n);
        return 1;
    }
    for (size_t i = 0; i < n; i++)
        memcpy(dst + 3 * i, block + i * stride + a->offset, 12);
    return 1;
}

static void convert_block(ply_reader *r, const ply_element *e, const unsigned char *block,
                          uint64_t row, size_t n)
{
    const ply_property *props = &r->h->props[e->first_prop];
    size_t stride = (size_t)e->row_bytes, dst_stride;
    sl_mesh *m = r->mesh;
    int vertex = e->kind == KIND_VERTEX; /* (a camera fills no arrays) */
    int xyz = vertex && copy_triplets(r, e, ROLE_X, block, n, m->positions + 3 * row);
    int nxyz = vertex && m->normals && copy_triplets(r, e, ROLE_NX, block, n, m->normals + 3 * row);
    for (int k = 0; k < e->nprops; k++) {
        const ply_property *p = &props[k];
        if (p->role == ROLE_SKIP || (xyz && p->role >= ROLE_X && p->role <= ROLE_Z) ||
            (nxyz && p->role >= ROLE_NX && p->role <= ROLE_NZ))
            continue;
        float *dst = sl_ply_float_column(m, p->role, &dst_stride);
        if (dst) {
            column_to_float(block + p->offset, stride, n, p->type, r->swap,
                            dst + row * dst_stride, dst_stride);
            continue;
        }
        for (size_t i = 0; i < n; i++)
            sl_ply_store_vertex(r, row + i, p->role, p->type,
                                load_scalar(block + i * stride + p->offset, p->type, r->swap));
    }
}

static int rows_fit(ply_reader *r, const ply_element *e)
{
    uint64_t remain = (uint64_t)(r->end - r->p), bytes;
    if (!__builtin_mul_overflow(e->count, e->row_bytes, &bytes) && bytes <= remain)
        return 0;
    r->row = remain / e->row_bytes;
    r->p += r->row * e->row_bytes;
    return sl_ply_body_error(r, SL_E_BADINPUT, "file ends inside element %s (%llu rows declared)",
                             e->name, (unsigned long long)e->count);
}

static int fixed_element(ply_reader *r, const ply_element *e)
{
    int rc = rows_fit(r, e);
    if (rc)
        return rc;
    const unsigned char *start = r->p;
    if (e->kind == KIND_VERTEX || (e->kind == KIND_CAMERA && e->count > 0)) {
        uint64_t rows = e->kind == KIND_CAMERA ? 1 : e->count;
        for (uint64_t row = 0; row < rows; row += BLOCK_ROWS) {
            size_t n = rows - row < BLOCK_ROWS ? (size_t)(rows - row) : BLOCK_ROWS;
            r->p = start + row * e->row_bytes;
            r->row = row;
            if ((row & PLY_TICK_ROWS) == 0 && (rc = sl_ply_tick(r)))
                return rc;
            convert_block(r, e, r->p, row, n);
        }
    }
    r->p = start + e->count * e->row_bytes;
    return 0;
}

static int binary_value(ply_reader *r, const ply_property *p, int type, double *out)
{
    int size = sl_ply_type_size(type);
    if (r->end - r->p < size)
        return sl_ply_body_error(r, SL_E_BADINPUT, "file ends inside property '%s' (%llu rows "
                                 "declared)", p->name, (unsigned long long)r->elem->count);
    if (out)
        *out = load_scalar(r->p, type, r->swap);
    r->p += size;
    return 0;
}

static uint64_t binary_room(const ply_reader *r, int type)
{
    return (uint64_t)(r->end - r->p) / (uint64_t)sl_ply_type_size(type);
}

/* `list uchar int|uint vertex_indices` and nothing else: the layout of nearly every file. */
static int is_plain_face(const ply_reader *r, const ply_element *e)
{
    const ply_property *p = &r->h->props[e->first_prop];
    return e->kind == KIND_FACE && e->nprops == 1 && p->role == ROLE_INDICES &&
           (p->count_type == PLY_UINT8 || p->count_type == PLY_INT8) &&
           (p->type == PLY_INT32 || p->type == PLY_UINT32) && !r->mesh->face_texcoords;
}

/* Consecutive rows `3 a b c` with a, b, c < limit, at most `rows` of them: copied to t.
 * Returns how many; stops before the first row that is anything else. */
static inline __attribute__((always_inline)) uint64_t
triangle_run(ply_reader *r, uint64_t rows, uint64_t limit, int swap, uint32_t *t)
{
    const unsigned char *p = r->p;
    uint64_t fit = (uint64_t)(r->end - p) / 13, i = 0;
    for (rows = rows < fit ? rows : fit; i < rows; i++, p += 13) {
        uint32_t a = load32(p + 1, swap), b = load32(p + 5, swap), c = load32(p + 9, swap);
        if ((p[0] != 3) | (a >= limit) | (b >= limit) | (c >= limit))
            break;
        t[3 * i] = a;
        t[3 * i + 1] = b;
        t[3 * i + 2] = c;
    }
    r->p = p;
    return i;
}

static uint64_t native_triangles(ply_reader *r, uint64_t rows, uint64_t limit, uint32_t *t)
{
    return triangle_run(r, rows, limit, 0, t);
}

static uint64_t swapped_triangles(ply_reader *r, uint64_t rows, uint64_t limit, uint32_t *t)
{
    return triangle_run(r, rows, limit, 1, t);
}

static int plain_faces(ply_reader *r, const ply_element *e)
{
    uint64_t limit = r->mesh->vertex_count; /* a negative int32 must not pass as a big uint32 */
    if (r->h->props[e->first_prop].type == PLY_INT32 && limit > 0x80000000u)
        limit = 0x80000000u;
    return ply_read_triangles(r, e, limit, r->swap ? swapped_triangles : native_triangles,
                              binary_value, binary_room);
}

int sl_ply_binary_element(ply_reader *r, const ply_element *e)
{
    r->swap = (r->h->format == SL_PLY_BINARY_BE) == (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__);
    if (e->nprops == 0 || e->count == 0)
        return 0;
    if (e->fixed_row)
        return fixed_element(r, e);
    if (is_plain_face(r, e))
        return plain_faces(r, e);
    return ply_read_rows(r, e, binary_value, binary_room);
}
