/* OFF reader (Geomview's Object File Format; docs/inputs.md, "OFF").
 *
 * Header: an optional keyword `[ST][C][N]OFF` (texture coordinates, colours, normals per
 * vertex), then `vertices faces [edges]` (on the keyword's line or the next one). Vertex
 * lines: x y z, then nx ny nz with N, r g b [a] with C (floats in [0, 1] or 0..255), s t
 * with ST. Face lines: `k i1 .. ik`, anything after the indices (a face colour) ignored;
 * polygons fan-triangulated. `#` starts a comment anywhere; blank lines are skipped. One
 * vertex or face per line, as every writer does (the format's free token layout would make
 * a face colour indistinguishable from the next face). `4OFF`, `nOFF` (other dimensions)
 * and `OFF BINARY` are refused as unsupported.
 *
 * The declared counts are checked against the bytes after the header before anything is
 * allocated: a vertex line takes at least 6 bytes ("0 0 0\n"), a face line 2.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/scan_internal.h"

#define MAX_COLUMNS 16
#define TICK_ROWS 0xffff

typedef struct off_reader {
    const scan_src *s;
    sl_mesh *m;
    text_cursor c;             /* its eol: the current line's end, before any comment */
    int st, color, normal;     /* the keyword's prefixes */
    int color_channels;        /* 3 or 4, from the first vertex */
    uint64_t nv, nf;
    float *rgba;               /* 4 per vertex as written */
    uint64_t tri_cap;
    uint32_t *poly;
    uint64_t poly_cap;
    char keyword[16];
} off_reader;

/* The next line with content, its comment cut off (c.eol moved to the '#'); 0 at the end
 * of the file. */
static int next_content(off_reader *r)
{
    while (text_next_line(&r->c)) {
        const char *hash = memchr(r->c.line, '#', (size_t)(r->c.eol - r->c.line));
        if (hash)
            r->c.eol = hash;
        if (text_skip(r->c.line, r->c.eol) < r->c.eol)
            return 1;
    }
    return 0;
}

/* `[ST][C][N][4][n]OFF [BINARY]` at [p, q): 1 when it is one, the flags set. */
static int parse_keyword(off_reader *r, const char *p, const char *q, int *refused)
{
    size_t n = (size_t)(q - p);
    if (n < 3 || n > 10 || memcmp(q - 3, "OFF", 3) != 0)
        return 0;
    snprintf(r->keyword, sizeof r->keyword, "%.*s", (int)n, p);
    const char *k = p;
    if (q - 3 - k >= 2 && !memcmp(k, "ST", 2))
        r->st = 1, k += 2;
    if (k < q - 3 && *k == 'C')
        r->color = 1, k++;
    if (k < q - 3 && *k == 'N')
        r->normal = 1, k++;
    *refused = k != q - 3; /* 4, n (other dimensions) or unknown letters */
    return 1;
}

static int read_counts(off_reader *r, const char *p)
{
    double v[3];
    int k = 0;
    while (k < 3 && text_double(&r->c, &p, NULL, &v[k]) == 1)
        k++;
    if (k < 2 || !(v[0] >= 0 && v[0] < 1e19 && v[0] == floor(v[0])) ||
        !(v[1] >= 0 && v[1] < 1e19 && v[1] == floor(v[1])))
        return scan_error(r->s, SL_E_BADINPUT, r->c.number,
                          "expected the vertex and face counts");
    r->nv = (uint64_t)v[0];
    r->nf = (uint64_t)v[1];
    return 0;
}

static int parse_header(off_reader *r)
{
    text_begin(&r->c, r->s);
    if (!next_content(r))
        return scan_error(r->s, SL_E_BADINPUT, 0, "empty OFF file");
    const char *p = text_skip(r->c.line, r->c.eol), *q = text_token_end(p, r->c.eol);
    int refused = 0;
    if (parse_keyword(r, p, q, &refused)) {
        const char *b = text_skip(q, r->c.eol), *e = text_token_end(b, r->c.eol);
        if (refused || text_token_is(b, e, "BINARY"))
            return scan_error(r->s, SL_E_UNSUPPORTED, r->c.number, "'%s%s' is not supported "
                              "(only ascii 3D OFF: [ST][C][N]OFF)", r->keyword,
                              text_token_is(b, e, "BINARY") ? " BINARY" : "");
        p = b; /* the counts on the keyword's line, or on the next one */
        if (b == r->c.eol) {
            if (!next_content(r))
                return scan_error(r->s, SL_E_BADINPUT, r->c.number, "no counts after '%s'",
                                  r->keyword);
            p = r->c.line;
        }
    } else {
        snprintf(r->keyword, sizeof r->keyword, "(none)");
    }
    return read_counts(r, p);
}

/* The counts against the bytes that follow them and the limits. */
static int check_counts(off_reader *r)
{
    const scan_src *s = r->s;
    uint64_t rest = (uint64_t)(r->c.end - r->c.p) + 1, need;
    uint64_t face_bytes = 2 * (r->nf < UINT64_MAX / 2 ? r->nf : UINT64_MAX / 2);
    if (__builtin_mul_overflow(r->nv, (uint64_t)6, &need) ||
        __builtin_add_overflow(need, face_bytes, &need) || need > rest)
        return scan_error(s, SL_E_BADINPUT, r->c.number, "declares %llu vertices and %llu faces "
                          "but only %llu bytes follow", (unsigned long long)r->nv,
                          (unsigned long long)r->nf, (unsigned long long)(rest - 1));
    int rc = scan_check_limit(s, "vertices", r->nv, s->lim->max_vertices);
    return rc ? rc : scan_check_limit(s, "faces", r->nf, s->lim->max_faces);
}

static int read_vertex(off_reader *r, uint64_t v)
{
    float x[MAX_COLUMNS];
    const char *p = r->c.line;
    int n = 0, rc;
    while ((rc = text_float(&r->c, &p, NULL, &x[n < MAX_COLUMNS ? n : 0])) == 1)
        n++;
    int fixed = 3 + 3 * r->normal + 2 * r->st, channels = r->color ? n - fixed : 0;
    if (rc < 0 || n < fixed || n > MAX_COLUMNS ||
        (r->color && channels != 3 && channels != 4) ||
        (r->color && r->color_channels && channels != r->color_channels))
        return scan_error(r->s, SL_E_BADINPUT, r->c.number, "vertex %llu: %d numbers do not fit "
                          "'%s'", (unsigned long long)v, n, r->keyword);
    sl_mesh *m = r->m;
    memcpy(m->positions + 3 * v, x, 3 * sizeof(float));
    if (r->normal)
        memcpy(m->normals + 3 * v, x + 3, 3 * sizeof(float));
    if (r->color) {
        r->color_channels = channels;
        memcpy(r->rgba + 4 * v, x + 3 + 3 * r->normal, (size_t)channels * sizeof(float));
    }
    if (r->st)
        memcpy(m->texcoords + 2 * v, x + 3 + 3 * r->normal + channels, 2 * sizeof(float));
    return 0;
}

/* An integer token (a count or an index) below `below`, into *out. */
static int read_index(off_reader *r, const char **p, uint64_t below, const char *what,
                      uint64_t *out)
{
    double v;
    if (text_double(&r->c, p, NULL, &v) != 1 || v != floor(v))
        return scan_error(r->s, SL_E_BADINPUT, r->c.number, "%s: not an integer", what);
    if (!(v >= 0 && v < (double)below))
        return scan_error(r->s, SL_E_BADINPUT, r->c.number, "%s %.0f is out of range (%llu)",
                          what, v, (unsigned long long)below);
    *out = (uint64_t)v;
    return 0;
}

static int read_face(off_reader *r)
{
    const char *p = r->c.line;
    uint64_t n, index;
    int rc = read_index(r, &p, (uint64_t)r->s->lim->max_face_corners + 1, "corner count", &n);
    if (rc || (rc = scan_reserve(r->s, (void **)&r->poly, &r->poly_cap, n + 1, sizeof *r->poly)))
        return rc;
    for (uint64_t k = 0; k < n; k++) {
        if ((rc = read_index(r, &p, r->nv, "vertex index", &index)))
            return rc;
        r->poly[k] = (uint32_t)index;
    }
    sl_mesh *m = r->m;
    if (n < 3) {
        m->stats.faces_too_short++;
        return 0;
    }
    if ((rc = scan_reserve(r->s, (void **)&m->triangles, &r->tri_cap, m->triangle_count + n - 2,
                           3 * sizeof(uint32_t))) ||
        (rc = scan_check_limit(r->s, "triangles", m->triangle_count + n - 2, r->s->lim->max_faces)))
        return rc;
    m->stats.polygons_triangulated += n > 3;
    for (uint64_t k = 1; k + 1 < n; k++) {
        uint32_t *t = m->triangles + 3 * m->triangle_count++;
        t[0] = r->poly[0], t[1] = r->poly[k], t[2] = r->poly[k + 1];
    }
    return 0;
}

static int alloc_vertices(off_reader *r)
{
    sl_mesh *m = r->m;
    int rc = 0;
    m->vertex_count = r->nv;
    m->positions = scan_alloc(r->s, r->nv, 3 * sizeof(float), &rc);
    if (r->normal)
        m->normals = scan_alloc(r->s, r->nv, 3 * sizeof(float), &rc);
    if (r->st)
        m->texcoords = scan_alloc(r->s, r->nv, 2 * sizeof(float), &rc);
    if (r->color && !rc && (r->rgba = scan_alloc(r->s, r->nv, 4 * sizeof(float), &rc)))
        m->colors = scan_alloc(r->s, r->nv, 4, &rc);
    return rc;
}

static int read_rows(off_reader *r, uint64_t rows, int (*row)(off_reader *, uint64_t),
                     const char *what)
{
    for (uint64_t i = 0; i < rows; i++) {
        int rc;
        if (!next_content(r))
            return scan_error(r->s, SL_E_BADINPUT, r->c.number, "the file ends after %llu of "
                              "%llu %s", (unsigned long long)i, (unsigned long long)rows, what);
        if ((rc = row(r, i)) || ((i & TICK_ROWS) == TICK_ROWS && (rc = scan_tick(r->s, r->c.p))))
            return rc;
    }
    return 0;
}

static int face_row(off_reader *r, uint64_t i)
{
    (void)i;
    return read_face(r);
}

static void fill_info(const off_reader *r, sl_scan_info *info)
{
    snprintf(info->format, sizeof info->format, "off");
    snprintf(info->detail, sizeof info->detail, "%s: %llu vertices, %llu faces", r->keyword,
             (unsigned long long)r->nv, (unsigned long long)r->nf);
    info->declared_vertices = r->nv;
    info->declared_faces = r->nf;
    info->has_normals = r->normal;
    info->has_colors = r->color;
    info->has_texcoords = r->st;
}

int sl_off_info_source(const scan_src *s, sl_scan_info *info)
{
    off_reader r = {.s = s};
    int rc = parse_header(&r);
    if (!rc)
        fill_info(&r, info);
    return rc ? rc : check_counts(&r);
}

int sl_off_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info)
{
    off_reader r = {.s = s, .m = out};
    int rc = parse_header(&r);
    if (!rc && info)
        fill_info(&r, info);
    if (!rc && !(rc = check_counts(&r)) && !(rc = alloc_vertices(&r)) &&
        !(rc = read_rows(&r, r.nv, read_vertex, "vertices")) &&
        !(rc = read_rows(&r, r.nf, face_row, "faces")) && next_content(&r))
        rc = scan_error(s, SL_E_BADINPUT, r.c.number, "unexpected data after the last face");
    if (!rc && r.color)
        scan_float_colors(r.rgba, 4, r.color_channels, r.nv, out->colors);
    free(r.rgba);
    free(r.poly);
    return rc;
}

int sl_off_sniff(const unsigned char *data, size_t size)
{
    size_t n = 0;
    while (n < size && n < 16 && data[n] > ' ')
        n++;
    return n >= 3 && n < 16 && memcmp(data + n - 3, "OFF", 3) == 0;
}
