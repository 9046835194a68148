/* STL reader, binary and ascii (docs/inputs.md, "STL").
 *
 * Binary: an 80-byte header, a u32 triangle count, 50 bytes per triangle (facet normal,
 * three corners, as little-endian float32, and a 2-byte attribute that is not read). The
 * count is checked against the file size before anything is allocated; bytes after the
 * last triangle are a warning (some writers pad), fewer bytes than declared an error.
 * Ascii: `solid` ... `facet normal n n n` `outer loop` `vertex x y z` ... `endloop`
 * `endfacet` ... `endsolid` (keywords in any case, several solids per file); a loop of more
 * than three vertices is fan-triangulated; any other line is an error.
 * Binary or ascii: binary when the size is exactly 84 + 50 x count; else ascii when the
 * file starts with "solid" and has no control bytes after the header (binary headers often
 * start with "solid" too); else binary, and its size is wrong.
 *
 * STL stores each triangle's corners on their own, so the mesh has 3 vertices per
 * triangle, each with its facet's normal; the range stage welds the equal ones.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/artifact.h"
#include "formats/scan_internal.h"

#define HEADER 84u
#define ROW 50u
#define TICK_ROWS 0xffff

static int looks_ascii(const unsigned char *data, size_t size)
{
    size_t i = 0;
    while (i < size && (data[i] == ' ' || data[i] == '\t' || data[i] == '\r' || data[i] == '\n'))
        i++;
    if (size - i < 5 || strncasecmp((const char *)data + i, "solid", 5) != 0)
        return 0;
    for (size_t k = 80; k < size && k < 1024; k++)
        if (data[k] < 0x09 || (data[k] > 0x0d && data[k] < 0x20))
            return 0;
    return 1;
}

int sl_stl_is_binary(const unsigned char *data, size_t size)
{
    return size >= HEADER && HEADER + ROW * (uint64_t)sl_get_u32(data + 80) == size;
}

static int use_binary(const unsigned char *data, size_t size)
{
    return sl_stl_is_binary(data, size) || !looks_ascii(data, size);
}

static void header_text(const unsigned char *data, size_t size, char *out, size_t out_size)
{
    size_t n = size < 80 ? size : 80, k = 0;
    while (n > 0 && (data[n - 1] == 0 || data[n - 1] == ' '))
        n--;
    for (size_t i = 0; i < n && k + 1 < out_size && k < 60; i++)
        out[k++] = data[i] >= 0x20 && data[i] < 0x7f ? (char)data[i] : '.';
    out[k] = 0;
}

static int binary_count(const scan_src *s, uint64_t *count)
{
    if (s->size < HEADER)
        return scan_error(s, SL_E_BADINPUT, 0, "%zu bytes: too short for a binary STL "
                          "(84-byte header) and not an ascii one", s->size);
    *count = sl_get_u32(s->data + 80);
    uint64_t need = HEADER + ROW * *count; /* < 2^38: no overflow */
    if (need > s->size)
        return scan_error(s, SL_E_BADINPUT, 0, "declares %llu triangles (%llu bytes) but holds "
                          "%zu bytes", (unsigned long long)*count, (unsigned long long)need,
                          s->size);
    int rc = scan_check_limit(s, "triangles", *count, s->lim->max_faces);
    return rc ? rc : scan_check_limit(s, "vertices", 3 * *count, s->lim->max_vertices);
}

static void binary_info(const scan_src *s, uint64_t count, sl_scan_info *info)
{
    char head[64];
    header_text(s->data, s->size, head, sizeof head);
    snprintf(info->format, sizeof info->format, "stl");
    snprintf(info->detail, sizeof info->detail, "binary STL, %llu triangles, header '%s'",
             (unsigned long long)count, head);
    info->declared_vertices = 3 * count;
    info->declared_faces = count;
    info->has_normals = 1;
}

static int read_binary(const scan_src *s, sl_mesh *m, sl_scan_info *info)
{
    uint64_t count;
    int rc = binary_count(s, &count);
    if (rc)
        return rc;
    if (info)
        binary_info(s, count, info);
    if (s->size > HEADER + ROW * count)
        sl_mesh_warn(m, "%llu bytes after the last triangle",
                     (unsigned long long)(s->size - HEADER - ROW * count));
    m->vertex_count = 3 * count;
    m->positions = scan_alloc(s, count, 9 * sizeof(float), &rc);
    m->normals = scan_alloc(s, count, 9 * sizeof(float), &rc);
    m->triangles = scan_alloc(s, count, 3 * sizeof(uint32_t), &rc);
    for (uint64_t t = 0; !rc && t < count; t++) {
        const unsigned char *row = s->data + HEADER + ROW * t;
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++) {
                m->normals[9 * t + 3 * c + k] = sl_get_f32(row + 4 * k);
                m->positions[9 * t + 3 * c + k] = sl_get_f32(row + 12 * (c + 1) + 4 * k);
            }
        for (int c = 0; c < 3; c++)
            m->triangles[3 * t + c] = (uint32_t)(3 * t + c);
        if ((t & TICK_ROWS) == TICK_ROWS)
            rc = scan_tick(s, row);
    }
    m->triangle_count = rc ? 0 : count;
    return rc;
}

/* ---- ascii ---- */

enum { KW_SOLID, KW_FACET, KW_OUTER, KW_VERTEX, KW_ENDLOOP, KW_ENDFACET, KW_ENDSOLID, KW_NONE };

static int keyword(const char *p, const char *q)
{
    static const char *const words[] = {"solid", "facet", "outer", "vertex", "endloop",
                                        "endfacet", "endsolid"};
    for (int k = 0; k < KW_NONE; k++)
        if ((size_t)(q - p) == strlen(words[k]) && strncasecmp(p, words[k], (size_t)(q - p)) == 0)
            return k;
    return KW_NONE;
}

typedef struct stl_ascii {
    const scan_src *s;
    sl_mesh *m;
    uint64_t vertices, triangles; /* counted by the first pass: the arrays' sizes */
    uint64_t loop_start, loop_size;
    float normal[3];
} stl_ascii;

/* Closes a loop: its vertices fan-triangulated (a loop of < 3 is dropped, counted). */
static int end_loop(stl_ascii *a, const text_cursor *c)
{
    sl_mesh *m = a->m;
    uint64_t n = a->loop_size;
    a->loop_size = 0;
    if (!m) { /* counting */
        a->triangles += n >= 3 ? n - 2 : 0;
        return 0;
    }
    if (n < 3) {
        m->stats.faces_too_short++;
        return 0;
    }
    if (m->triangle_count + n - 2 > a->triangles)
        return scan_error(a->s, SL_E_INTERNAL, c->number, "more triangles than counted");
    m->stats.polygons_triangulated += n > 3;
    for (uint64_t k = 1; k + 1 < n; k++) {
        uint32_t *t = m->triangles + 3 * m->triangle_count++;
        t[0] = (uint32_t)a->loop_start;
        t[1] = (uint32_t)(a->loop_start + k);
        t[2] = (uint32_t)(a->loop_start + k + 1);
    }
    return 0;
}

static int read_numbers(const stl_ascii *a, const text_cursor *c, const char *p, float *x)
{
    for (int k = 0; k < 3; k++)
        if (text_float(c, &p, NULL, &x[k]) != 1)
            return scan_error(a->s, SL_E_BADINPUT, c->number, "expected three numbers");
    return 0;
}

static int ascii_vertex(stl_ascii *a, const text_cursor *c, const char *p)
{
    sl_mesh *m = a->m;
    if (!m) {
        a->vertices++;
        a->loop_size++;
        return 0;
    }
    if (m->vertex_count >= a->vertices)
        return scan_error(a->s, SL_E_INTERNAL, c->number, "more vertices than counted");
    uint64_t v = m->vertex_count++;
    if (a->loop_size++ == 0)
        a->loop_start = v;
    memcpy(m->normals + 3 * v, a->normal, sizeof a->normal);
    return read_numbers(a, c, p, m->positions + 3 * v);
}

static int ascii_line(stl_ascii *a, const text_cursor *c)
{
    const char *p = text_skip(c->line, c->eol), *q = text_token_end(p, c->eol);
    if (p == c->eol)
        return 0;
    switch (keyword(p, q)) {
    case KW_FACET:
        if (a->m) {
            const char *n = text_skip(q, c->eol), *nq = text_token_end(n, c->eol);
            if (!text_token_is(n, nq, "normal") && !text_token_is(n, nq, "NORMAL"))
                return scan_error(a->s, SL_E_BADINPUT, c->number, "expected 'facet normal'");
            return read_numbers(a, c, nq, a->normal);
        }
        return 0;
    case KW_VERTEX:
        return ascii_vertex(a, c, q);
    case KW_ENDLOOP:
    case KW_ENDFACET:
        return a->loop_size ? end_loop(a, c) : 0;
    case KW_SOLID: case KW_OUTER: case KW_ENDSOLID:
        return 0;
    default:
        return scan_error(a->s, SL_E_BADINPUT, c->number, "unexpected '%.*s' in an ascii STL",
                          (int)(q - p < 40 ? q - p : 40), p);
    }
}

static int ascii_pass(stl_ascii *a)
{
    text_cursor c;
    text_begin(&c, a->s);
    int rc = 0;
    while (!rc && text_next_line(&c)) {
        rc = ascii_line(a, &c);
        if (!rc && (c.number & TICK_ROWS) == 0)
            rc = scan_tick(a->s, c.p);
    }
    if (!rc && a->loop_size) /* a last loop left open */
        rc = end_loop(a, &c);
    return rc;
}

static int ascii_count(const scan_src *s, stl_ascii *a, sl_scan_info *info)
{
    *a = (stl_ascii){.s = s};
    int rc = ascii_pass(a);
    if (!rc && info) {
        snprintf(info->format, sizeof info->format, "stl");
        snprintf(info->detail, sizeof info->detail, "ascii STL, %llu triangles",
                 (unsigned long long)a->triangles);
        info->declared_vertices = a->vertices;
        info->declared_faces = a->triangles;
        info->has_normals = 1;
    }
    if (!rc)
        rc = scan_check_limit(s, "vertices", a->vertices, s->lim->max_vertices);
    return rc ? rc : scan_check_limit(s, "triangles", a->triangles, s->lim->max_faces);
}

static int read_ascii(const scan_src *s, sl_mesh *m, sl_scan_info *info)
{
    stl_ascii a;
    int rc = ascii_count(s, &a, info);
    if (rc)
        return rc;
    m->positions = scan_alloc(s, a.vertices, 3 * sizeof(float), &rc);
    m->normals = scan_alloc(s, a.vertices, 3 * sizeof(float), &rc);
    m->triangles = scan_alloc(s, a.triangles, 3 * sizeof(uint32_t), &rc);
    if (rc)
        return rc;
    a.m = m;
    return ascii_pass(&a);
}

int sl_stl_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info)
{
    return use_binary(s->data, s->size) ? read_binary(s, out, info) : read_ascii(s, out, info);
}

int sl_stl_info_source(const scan_src *s, sl_scan_info *info)
{
    uint64_t count;
    stl_ascii a;
    if (use_binary(s->data, s->size)) {
        int rc = binary_count(s, &count);
        if (!rc)
            binary_info(s, count, info);
        return rc;
    }
    return ascii_count(s, &a, info);
}
