/* PLY body: allocation of the mesh from the checked header counts, the element loop, and
 * the sinks both formats feed (vertex values, face lists with fan triangulation, camera,
 * range grid).
 *
 * Arrays are sized from declared counts that the header check already bounded by the
 * bytes in the file; triangles start at the number of triangle rows the bytes could hold
 * and grow by doubling (polygons yield several), so memory stays proportional to what the
 * file really contains.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "formats/ply_internal.h"

#define HUGE_PAGE ((size_t)2 << 20)

static uint64_t line_of(const ply_reader *r)
{
    uint64_t line = 1;
    for (const unsigned char *s = r->data; s < r->p;) {
        const unsigned char *nl = memchr(s, '\n', (size_t)(r->p - s));
        if (!nl)
            break;
        line++;
        s = nl + 1;
    }
    return line;
}

int sl_ply_body_error(ply_reader *r, int code, const char *fmt, ...)
{
    char where[160], row[96], msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (r->h->format == SL_PLY_ASCII)
        snprintf(where, sizeof where, "line %llu", (unsigned long long)line_of(r));
    else
        snprintf(where, sizeof where, "byte %llu", (unsigned long long)(r->p - r->data));
    row[0] = 0;
    if (r->elem && r->elem->kind == KIND_VERTEX)
        snprintf(row, sizeof row, ", vertex %llu", (unsigned long long)r->row);
    else if (r->elem && r->elem->kind == KIND_FACE)
        snprintf(row, sizeof row, ", face %llu", (unsigned long long)r->row);
    else if (r->elem)
        snprintf(row, sizeof row, ", element %s row %llu", r->elem->name,
                 (unsigned long long)r->row);
    return sl_error_set(r->err, code, 0, r->name, "%s%s: %s", where, row, msg);
}

static uint8_t color_byte(int type, double v)
{
    if (type == PLY_FLOAT32 || type == PLY_FLOAT64)
        v *= 255.0; /* float colours are 0..1 */
    else if (type == PLY_UINT16 || type == PLY_INT16)
        v /= 257.0; /* 16-bit colours are 0..65535 */
    if (!(v > 0))
        return 0;
    return v >= 255.0 ? 255 : (uint8_t)(v + 0.5);
}

void sl_ply_store_vertex(ply_reader *r, uint64_t row, int role, int type, double v)
{
    sl_mesh *m = r->mesh;
    switch (role) {
    case ROLE_X: case ROLE_Y: case ROLE_Z:
        m->positions[3 * row + (unsigned)(role - ROLE_X)] = sl_ply_to_float(v);
        break;
    case ROLE_NX: case ROLE_NY: case ROLE_NZ:
        if (m->normals)
            m->normals[3 * row + (unsigned)(role - ROLE_NX)] = sl_ply_to_float(v);
        break;
    case ROLE_RED: case ROLE_GREEN: case ROLE_BLUE: case ROLE_ALPHA:
        if (m->colors)
            m->colors[4 * row + (unsigned)(role - ROLE_RED)] = color_byte(type, v);
        break;
    case ROLE_U: case ROLE_V:
        if (m->texcoords)
            m->texcoords[2 * row + (unsigned)(role - ROLE_U)] = sl_ply_to_float(v);
        break;
    case ROLE_VIEW_X: case ROLE_VIEW_Y: case ROLE_VIEW_Z:
        if (row == 0) { /* the first camera states the viewpoint */
            r->camera[role - ROLE_VIEW_X] = v;
            r->have_camera |= 1 << (role - ROLE_VIEW_X);
        }
        break;
    default:
        break;
    }
}

float *sl_ply_float_column(sl_mesh *m, int role, size_t *stride)
{
    *stride = 3;
    if (role >= ROLE_X && role <= ROLE_Z && m->positions) /* NULL for 0 vertices */
        return m->positions + (role - ROLE_X);
    if (role >= ROLE_NX && role <= ROLE_NZ && m->normals)
        return m->normals + (role - ROLE_NX);
    *stride = 2;
    if ((role == ROLE_U || role == ROLE_V) && m->texcoords)
        return m->texcoords + (role - ROLE_U);
    return NULL;
}

int sl_ply_check_index(ply_reader *r, double v, uint32_t *index)
{
    if (v >= 0 && v < (double)r->mesh->vertex_count) {
        *index = (uint32_t)v;
        return 0;
    }
    return sl_ply_body_error(r, SL_E_BADINPUT, "vertex index %.0f is out of range (%llu vertices)",
                             v, (unsigned long long)r->mesh->vertex_count);
}

static void *realloc_array(void *ptr, uint64_t n, size_t item)
{
    size_t bytes;
    if (n > SIZE_MAX || __builtin_mul_overflow((size_t)n, item, &bytes))
        return NULL;
    return realloc(ptr, bytes ? bytes : 1);
}

static int nomem(ply_reader *r, uint64_t n, size_t item)
{
    return sl_error_set(r->err, SL_E_NOMEM, 0, r->name, "out of memory for %llu items of %zu bytes",
                        (unsigned long long)n, item);
}

/* Makes *ptr hold at least `need` items of `item` bytes (grown by doubling). */
static int reserve(ply_reader *r, void **ptr, uint64_t *cap, uint64_t need, size_t item)
{
    if (need <= *cap)
        return 0;
    uint64_t n = *cap * 2 > need ? *cap * 2 : need;
    void *p = realloc_array(*ptr, n, item);
    if (!p)
        return nomem(r, n, item);
    *ptr = p;
    *cap = n;
    return 0;
}

static int grow_triangles(ply_reader *r)
{
    sl_mesh *m = r->mesh;
    uint64_t cap = r->tri_cap >= 512 ? r->tri_cap * 2 : 1024;
    uint32_t *t = realloc_array(m->triangles, cap, 3 * sizeof *t);
    if (!t)
        return nomem(r, cap, 3 * sizeof *t);
    m->triangles = t;
    if (m->face_texcoords) {
        float *f = realloc_array(m->face_texcoords, cap, 6 * sizeof *f);
        if (!f)
            return nomem(r, cap, 6 * sizeof *f);
        m->face_texcoords = f;
    }
    r->tri_cap = cap;
    return 0;
}

int sl_ply_push_triangle(ply_reader *r, uint32_t a, uint32_t b, uint32_t c)
{
    sl_mesh *m = r->mesh;
    int rc;
    if (m->triangle_count == r->tri_cap && (rc = grow_triangles(r)))
        return rc;
    uint32_t *t = m->triangles + 3 * m->triangle_count++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    return 0;
}

int sl_ply_begin_list(ply_reader *r, int role, uint64_t n)
{
    uint64_t max = r->lim->max_face_corners;
    if (role == ROLE_INDICES) {
        if (n > max)
            return sl_ply_body_error(r, SL_E_LIMIT, "face has %llu corners (limit %llu)",
                                     (unsigned long long)n, (unsigned long long)max);
        return reserve(r, (void **)&r->corners, &r->corners_cap, n, sizeof *r->corners);
    }
    if (role == ROLE_TEXCOORD) {
        if (n > 2 * max)
            return sl_ply_body_error(r, SL_E_LIMIT, "texcoord list has %llu values (limit %llu)",
                                     (unsigned long long)n, (unsigned long long)(2 * max));
        r->corner_uv_len = n;
        return reserve(r, (void **)&r->corner_uv, &r->corner_uv_cap, n, sizeof *r->corner_uv);
    }
    return 0;
}

int sl_ply_store_list_item(ply_reader *r, int role, uint64_t i, double v)
{
    uint32_t index = 0;
    int rc;
    switch (role) {
    case ROLE_INDICES:
        if ((rc = sl_ply_check_index(r, v, &index)))
            return rc;
        r->corners[i] = index;
        return 0;
    case ROLE_TEXCOORD:
        r->corner_uv[i] = sl_ply_to_float(v);
        return 0;
    case ROLE_GRID_INDICES:
        if ((rc = sl_ply_check_index(r, v, &index)))
            return rc;
        if (i == 0 && r->mesh->grid_index) /* Stanford cells hold 0 or 1 vertex */
            r->mesh->grid_index[r->row] = index;
        return 0;
    default:
        return 0;
    }
}

static void corner_uv(const ply_reader *r, uint64_t k, float *dst)
{
    dst[0] = r->corner_uv[2 * k];
    dst[1] = r->corner_uv[2 * k + 1];
}

int sl_ply_end_face(ply_reader *r, uint64_t n)
{
    sl_mesh *m = r->mesh;
    uint64_t uv = r->corner_uv_len;
    int rc;
    r->corner_uv_len = 0;
    if (uv && uv != 2 * n)
        return sl_ply_body_error(r, SL_E_BADINPUT, "texcoord list has %llu values for %llu corners",
                                 (unsigned long long)uv, (unsigned long long)n);
    if (n < 3) {
        m->stats.faces_too_short++;
        return 0;
    }
    m->stats.polygons_triangulated += n > 3;
    m->stats.texcoord_faces += uv > 0;
    for (uint64_t k = 1; k + 1 < n; k++) { /* fan around corner 0 */
        if ((rc = sl_ply_push_triangle(r, r->corners[0], r->corners[k], r->corners[k + 1])))
            return rc;
        if (!m->face_texcoords)
            continue;
        float *t = m->face_texcoords + 6 * (m->triangle_count - 1);
        if (!uv) {
            memset(t, 0, 6 * sizeof *t);
            continue;
        }
        corner_uv(r, 0, t);
        corner_uv(r, k, t + 2);
        corner_uv(r, k + 1, t + 4);
    }
    return 0;
}

int sl_ply_tick(ply_reader *r)
{
    sl_progress *p = r->progress;
    if (!p)
        return 0;
    if (sl_progress_interrupted(p))
        return sl_error_set(r->err, SL_E_INTERRUPTED, 0, r->name, "interrupted while reading");
    /* reported directly: the reader depends on nothing but error.c (fuzz target) */
    if (p->report)
        p->report(p->ctx, "read", (double)(r->p - r->body) / (double)(r->end - r->body + 1));
    return 0;
}

/* Large arrays on 2 MiB boundaries with transparent huge pages asked for: the reader
 * writes every byte of them once, and 4 KiB page faults on fresh memory would cost more
 * than parsing a binary file (measured: scripts/bench/bench_ply_read.sh). */
static void *alloc_big(size_t bytes)
{
    void *p = NULL;
    if (posix_memalign(&p, HUGE_PAGE, bytes) != 0)
        return NULL;
    madvise(p, bytes & ~(size_t)(HUGE_PAGE - 1), MADV_HUGEPAGE);
    return p;
}

static void *alloc_items(ply_reader *r, uint64_t n, size_t item, int *rc)
{
    size_t bytes;
    if (n == 0 || *rc)
        return NULL;
    void *p = NULL;
    if (n <= SIZE_MAX && !__builtin_mul_overflow((size_t)n, item, &bytes))
        p = bytes >= 2 * HUGE_PAGE ? alloc_big(bytes) : malloc(bytes);
    if (!p)
        *rc = nomem(r, n, item);
    return p;
}

/* Triangle rows the body could hold at most: the first capacity of mesh->triangles. */
static uint64_t triangle_capacity(const ply_reader *r, const ply_element *f)
{
    const ply_property *p = &r->h->props[f->first_prop];
    uint64_t index_bytes = 4;
    for (int i = 0; i < f->nprops; i++)
        if (p[i].role == ROLE_INDICES)
            index_bytes = (uint64_t)sl_ply_type_size(p[i].type);
    uint64_t row = f->min_row_bytes + (r->h->format == SL_PLY_ASCII ? 6 : 3 * index_bytes);
    uint64_t cap = (uint64_t)(r->end - r->body) / row + 1;
    return cap < f->count ? cap : f->count;
}

static void init_colors(sl_mesh *m, int have_alpha)
{
    memset(m->colors, 0, 4 * m->vertex_count);
    if (!have_alpha)
        for (uint64_t i = 0; i < m->vertex_count; i++)
            m->colors[4 * i + 3] = 255;
}

static int alloc_grid(ply_reader *r, sl_mesh *m)
{
    int rc = 0;
    const ply_element *g = &r->h->elements[r->h->grid_element];
    m->grid_index = alloc_items(r, g->count, sizeof *m->grid_index, &rc);
    if (rc)
        return rc;
    for (uint64_t i = 0; i < g->count; i++)
        m->grid_index[i] = -1;
    m->grid_cols = (uint32_t)r->h->grid_cols;
    m->grid_rows = (uint32_t)r->h->grid_rows;
    return 0;
}

static int alloc_mesh(ply_reader *r)
{
    const ply_header *h = r->h;
    sl_mesh *m = r->mesh;
    int rc = 0;
    m->vertex_count = h->vertex_element >= 0 ? h->elements[h->vertex_element].count : 0;
    uint64_t n = m->vertex_count;
    m->positions = alloc_items(r, n, 3 * sizeof(float), &rc);
    if (sl_ply_wants_normals(h))
        m->normals = alloc_items(r, n, 3 * sizeof(float), &rc);
    if (sl_ply_wants_colors(h) && (m->colors = alloc_items(r, n, 4, &rc)))
        init_colors(m, h->role_seen[ROLE_ALPHA]);
    if (sl_ply_wants_texcoords(h))
        m->texcoords = alloc_items(r, n, 2 * sizeof(float), &rc);
    if (h->face_element >= 0) {
        r->tri_cap = triangle_capacity(r, &h->elements[h->face_element]);
        m->triangles = alloc_items(r, r->tri_cap, 3 * sizeof(uint32_t), &rc);
        if (sl_ply_wants_face_texcoords(h))
            m->face_texcoords = alloc_items(r, r->tri_cap, 6 * sizeof(float), &rc);
        if (!m->triangles || (sl_ply_wants_face_texcoords(h) && !m->face_texcoords))
            r->tri_cap = 0; /* a zero-size start grows on the first triangle */
    }
    if (!rc && sl_ply_wants_grid(h))
        rc = alloc_grid(r, m);
    snprintf(m->texture_file, sizeof m->texture_file, "%s", h->texture_file);
    m->has_viewpoint = h->has_viewpoint;
    memcpy(m->viewpoint, h->viewpoint, sizeof m->viewpoint);
    memcpy(m->units, h->units, sizeof m->units);
    m->up_axis = h->up_axis;
    return rc;
}

static int check_trailing(ply_reader *r)
{
    if (r->h->format != SL_PLY_ASCII) {
        if (r->p == r->end)
            return 0;
        return sl_ply_body_error(r, SL_E_BADINPUT,
                                 "%llu bytes after the last element (the header does not "
                                 "describe the body)", (unsigned long long)(r->end - r->p));
    }
    while (r->p < r->end && (*r->p == ' ' || (unsigned)(*r->p - '\t') < 5u))
        r->p++;
    if (r->p == r->end)
        return 0;
    return sl_ply_body_error(r, SL_E_BADINPUT, "unexpected data after the last element");
}

int sl_ply_read_body(ply_reader *r)
{
    int rc = alloc_mesh(r);
    if (rc)
        return rc;
    for (int i = 0; i < r->h->nelements; i++) {
        r->elem = &r->h->elements[i];
        r->row = 0;
        rc = r->h->format == SL_PLY_ASCII ? sl_ply_ascii_element(r, r->elem)
                                          : sl_ply_binary_element(r, r->elem);
        if (rc)
            return rc;
        if ((rc = sl_ply_tick(r)))
            return rc;
    }
    r->elem = NULL;
    if (r->have_camera == 7) { /* a camera element beats a viewpoint comment */
        r->mesh->has_viewpoint = 1;
        memcpy(r->mesh->viewpoint, r->camera, sizeof r->camera);
    }
    return check_trailing(r);
}
