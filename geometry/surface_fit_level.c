/* The level as the fit sees it (surface_fit_internal.h): checked, welded (vertices at
 * bit-identical positions become one unknown, so a texture seam cannot open), its edges
 * (the matrix's pattern and the open border), each vertex's corners, and the triangles'
 * normals and shapes as given, which the guards compare against.
 */
#include <math.h>
#include <meshoptimizer.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/key_table.h"
#include "geometry/surface_fit_internal.h"
#include "geometry/vec3.h"

double fit_quality(const double a[3], const double b[3], const double c[3], double n[3])
{
    double u[3], v[3], w[3];
    for (int i = 0; i < 3; i++) {
        u[i] = b[i] - a[i];
        v[i] = c[i] - a[i];
        w[i] = c[i] - b[i];
    }
    sl_cross3(u, v, n);
    double edges = sl_dot3(u, u) + sl_dot3(v, v) + sl_dot3(w, w);
    return edges > 0.0 ? 2.0 * sqrt(3.0) * sqrt(sl_dot3(n, n)) / edges : 0.0;
}

void fit_corner(const fit_level *lv, const float *pos, uint32_t t, int k, double out[3])
{
    const float *p = &pos[3 * (uint64_t)lv->tri[3 * (uint64_t)t + k]];
    out[0] = p[0];
    out[1] = p[1];
    out[2] = p[2];
}

/* Every edge of a non-degenerate corner as (lo << 32 | hi, corner id), sorted by key. */
static int edge_pairs(const uint32_t *tri, uint64_t triangle_count, sl_key_pair **out,
                      uint64_t *count, sl_error *err)
{
    sl_key_pair *pairs = malloc((3 * triangle_count + 1) * sizeof *pairs);
    if (!pairs)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: edges of %llu triangles",
                            (unsigned long long)triangle_count);
    uint64_t n = 0;
    for (uint32_t c = 0; c < 3 * triangle_count; c++) {
        uint64_t a = tri[c], b = tri[fit_next_corner(c)];
        if (a != b)
            pairs[n++] = (sl_key_pair){a < b ? a << 32 | b : b << 32 | a, c};
    }
    if (sl_sort_pairs(pairs, n, 64) != 0) {
        free(pairs);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: sorting edges");
    }
    *out = pairs;
    *count = n;
    return SL_OK;
}

int fit_open_edges(const uint32_t *tri, uint64_t triangle_count, uint32_t **open,
                   uint64_t *count, sl_error *err)
{
    sl_key_pair *pairs;
    uint64_t n;
    *open = NULL;
    *count = 0;
    int rc = edge_pairs(tri, triangle_count, &pairs, &n, err);
    if (rc != SL_OK)
        return rc;
    for (uint64_t i = 0, run; i < n; i += run) { /* open edges first to the front */
        for (run = 1; i + run < n && pairs[i + run].key == pairs[i].key; run++)
            ;
        if (run == 1)
            pairs[(*count)++] = pairs[i];
    }
    if (*count) {
        *open = malloc(*count * sizeof **open);
        if (!*open)
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: open edges");
        for (uint64_t e = 0; *open && e < *count; e++)
            (*open)[e] = (uint32_t)pairs[e].value;
    }
    free(pairs);
    return rc;
}

/* The matrix pattern: row v holds v and its neighbours, ascending. */
static int build_rows(fit_level *lv, const sl_key_pair *pairs, uint64_t n, sl_error *err)
{
    uint32_t nv = lv->vertex_count;
    lv->row_start = calloc((size_t)nv + 1, sizeof *lv->row_start);
    if (!lv->row_start)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: matrix rows");
    for (uint64_t i = 0; i < n; i++)
        if (i == 0 || pairs[i].key != pairs[i - 1].key) {
            lv->row_start[(pairs[i].key >> 32) + 1]++;
            lv->row_start[(uint32_t)pairs[i].key + 1]++;
        }
    for (uint32_t v = 0; v < nv; v++)
        lv->row_start[v + 1] += lv->row_start[v] + 1; /* + 1: the diagonal */
    lv->col = malloc(((size_t)lv->row_start[nv] + 1) * sizeof *lv->col);
    uint32_t *fill = malloc(((size_t)nv + 1) * sizeof *fill);
    if (!lv->col || !fill) {
        free(fill);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: matrix columns");
    }
    for (uint32_t v = 0; v < nv; v++) {
        fill[v] = lv->row_start[v] + 1;
        lv->col[lv->row_start[v]] = v;
    }
    for (uint64_t i = 0; i < n; i++)
        if (i == 0 || pairs[i].key != pairs[i - 1].key) {
            uint32_t a = (uint32_t)(pairs[i].key >> 32), b = (uint32_t)pairs[i].key;
            lv->col[fill[a]++] = b;
            lv->col[fill[b]++] = a;
        }
    free(fill);
#pragma omp parallel for schedule(static) if (nv > FIT_CHUNK)
    for (uint32_t v = 0; v < nv; v++) /* insertion sort: a row has a handful of entries */
        for (uint32_t i = lv->row_start[v] + 1; i < lv->row_start[v + 1]; i++)
            for (uint32_t j = i; j > lv->row_start[v] && lv->col[j - 1] > lv->col[j]; j--) {
                uint32_t t = lv->col[j];
                lv->col[j] = lv->col[j - 1];
                lv->col[j - 1] = t;
            }
    return SL_OK;
}

/* Two triangles on the same three vertices (a double-sided fin a simplifier left) stay
 * where they are: the fin has no side to be pulled to, and the tip of one on armadillo
 * at 20 % by simplifyWithUpdate drifted 0.6 % of the diagonal off the surface when it was
 * fitted. They share every edge, so they are found among the triangles of one edge:
 * two with the same third corner. */
static void fix_fins(fit_level *lv, const sl_key_pair *pairs, uint64_t n)
{
    for (uint64_t i = 0, run; i < n; i += run) {
        for (run = 1; i + run < n && pairs[i + run].key == pairs[i].key; run++)
            ;
        for (uint64_t j = i; j < i + run; j++)
            for (uint64_t k = j + 1; k < i + run; k++) {
                uint32_t cj = (uint32_t)pairs[j].value, ck = (uint32_t)pairs[k].value;
                if (lv->tri[fit_next_corner(fit_next_corner(cj))] !=
                    lv->tri[fit_next_corner(fit_next_corner(ck))])
                    continue;
                for (int c = 0; c < 3; c++)
                    lv->fixed[lv->tri[cj / 3u * 3u + (uint32_t)c]] = 1;
            }
    }
}

/* Rows, open border and border flags from the welded triangles' edges. */
static int build_edges(fit_level *lv, sl_error *err)
{
    sl_key_pair *pairs = NULL;
    uint64_t n;
    int rc = edge_pairs(lv->tri, lv->triangle_count, &pairs, &n, err);
    if (rc == SL_OK)
        rc = build_rows(lv, pairs, n, err);
    if (rc == SL_OK)
        fix_fins(lv, pairs, n);
    free(pairs);
    uint64_t open_count = 0;
    if (rc == SL_OK)
        rc = fit_open_edges(lv->tri, lv->triangle_count, &lv->border_edges, &open_count, err);
    lv->border_edge_count = (uint32_t)open_count;
    for (uint32_t e = 0; rc == SL_OK && e < lv->border_edge_count; e++) {
        lv->border[lv->tri[lv->border_edges[e]]] = 1;
        lv->border[lv->tri[fit_next_corner(lv->border_edges[e])]] = 1;
    }
    return rc;
}

/* Each vertex's corners 3 t + k, ascending (a counting sort). */
static int build_corners(fit_level *lv, sl_error *err)
{
    uint32_t nv = lv->vertex_count, nc = 3 * lv->triangle_count;
    lv->corner_start = calloc((size_t)nv + 1, sizeof *lv->corner_start);
    lv->corners = malloc((size_t)nc * sizeof *lv->corners);
    if (!lv->corner_start || !lv->corners)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: corners");
    for (uint32_t c = 0; c < nc; c++)
        lv->corner_start[lv->tri[c] + 1]++;
    for (uint32_t v = 0; v < nv; v++)
        lv->corner_start[v + 1] += lv->corner_start[v];
    for (uint32_t c = 0; c < nc; c++)
        lv->corners[lv->corner_start[lv->tri[c]]++] = c;
    for (uint32_t v = nv; v > 0; v--) /* the fill moved each start to the next one's */
        lv->corner_start[v] = lv->corner_start[v - 1];
    lv->corner_start[0] = 0;
    return SL_OK;
}

/* Welded vertices, their positions and locks; welded triangles. */
static int weld(fit_level *lv, const float *positions, uint64_t vertex_count,
                const uint32_t *triangles, const uint8_t *locked, sl_error *err)
{
    size_t nc = 3 * (size_t)lv->triangle_count;
    lv->group = malloc(vertex_count * sizeof *lv->group);
    lv->tri = malloc(nc * sizeof *lv->tri);
    if (!lv->group || !lv->tri)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: welding the level");
    lv->vertex_count = (uint32_t)meshopt_generateVertexRemap(lv->group, triangles, nc, positions,
                                                             vertex_count, 3 * sizeof(float));
    uint32_t nv = lv->vertex_count;
    lv->pos = malloc(3 * (size_t)nv * sizeof *lv->pos);
    lv->start = malloc(3 * (size_t)nv * sizeof *lv->start);
    lv->fixed = calloc(nv, 1);
    lv->border = calloc(nv, 1);
    if (!lv->pos || !lv->start || !lv->fixed || !lv->border)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: %u level vertices", nv);
    for (size_t c = 0; c < nc; c++)
        lv->tri[c] = lv->group[triangles[c]];
    for (uint64_t v = 0; v < vertex_count; v++) {
        uint32_t g = lv->group[v];
        if (g == UINT32_MAX)
            continue;
        memcpy(&lv->pos[3 * (size_t)g], &positions[3 * v], 3 * sizeof(float));
        if (locked && locked[v])
            lv->fixed[g] = 1;
    }
    memcpy(lv->start, lv->pos, 3 * (size_t)nv * sizeof *lv->pos);
    return SL_OK;
}

static int shapes_as_given(fit_level *lv, sl_error *err)
{
    lv->start_normal = malloc(3 * (size_t)lv->triangle_count * sizeof *lv->start_normal);
    lv->start_quality = malloc((size_t)lv->triangle_count * sizeof *lv->start_quality);
    if (!lv->start_normal || !lv->start_quality)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: triangle shapes");
#pragma omp parallel for schedule(static) if (lv->triangle_count > FIT_CHUNK)
    for (uint32_t t = 0; t < lv->triangle_count; t++) {
        double a[3], b[3], c[3], n[3];
        fit_corner(lv, lv->start, t, 0, a);
        fit_corner(lv, lv->start, t, 1, b);
        fit_corner(lv, lv->start, t, 2, c);
        lv->start_quality[t] = (float)fit_quality(a, b, c, n);
        for (int i = 0; i < 3; i++)
            lv->start_normal[3 * (size_t)t + i] = (float)n[i];
    }
    return SL_OK;
}

int fit_level_build(fit_level *lv, const float *positions, uint64_t vertex_count,
                    const uint32_t *triangles, uint64_t triangle_count, const uint8_t *locked,
                    sl_error *err)
{
    memset(lv, 0, sizeof *lv);
    if (vertex_count >= UINT32_MAX || triangle_count >= (UINT32_MAX - 1u) / 3u)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "fit level: %llu vertices, %llu triangles (at most 2^32 - 2 and "
                            "(2^32 - 2) / 3)", (unsigned long long)vertex_count,
                            (unsigned long long)triangle_count);
    sl_error why;
    sl_error_init(&why);
    sl_mesh view = sl_mesh_view(vertex_count, (float *)positions, NULL, NULL, triangle_count,
                                (uint32_t *)triangles); /* read only */
    if (sl_mesh_check_surface(&view, "level", &why) != SL_OK) /* "level": the message alone */
        return sl_error_set(err, why.code, 0, NULL, "fit level: %s", why.message);
    lv->triangle_count = (uint32_t)triangle_count;
    int rc = weld(lv, positions, vertex_count, triangles, locked, err);
    if (rc == SL_OK)
        rc = build_edges(lv, err);
    if (rc == SL_OK)
        rc = build_corners(lv, err);
    if (rc == SL_OK)
        rc = shapes_as_given(lv, err);
    return rc;
}

int fit_level_samples(fit_level *lv, uint64_t count, uint64_t seed, sl_error *err)
{
    sl_mesh view = sl_mesh_view(lv->vertex_count, lv->start, NULL, NULL, lv->triangle_count,
                                lv->tri);
    uint64_t bound = sl_mesh_area_samples_bound(&view, count);
    lv->samples = bound <= SIZE_MAX / sizeof *lv->samples ? malloc(bound * sizeof *lv->samples)
                                                          : NULL;
    lv->per_triangle = calloc(lv->triangle_count, sizeof *lv->per_triangle);
    if (!lv->samples || !lv->per_triangle)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: %llu level samples",
                            (unsigned long long)count);
    int rc = sl_mesh_area_samples(&view, count, seed, lv->samples, &lv->sample_count, err);
    for (uint64_t i = 0; rc == SL_OK && i < lv->sample_count; i++)
        lv->per_triangle[lv->samples[i].triangle]++;
    return rc;
}

void fit_level_release(fit_level *lv)
{
    free(lv->group);
    free(lv->tri);
    free(lv->pos);
    free(lv->start);
    free(lv->fixed);
    free(lv->border);
    free(lv->corner_start);
    free(lv->corners);
    free(lv->row_start);
    free(lv->col);
    free(lv->border_edges);
    free(lv->start_normal);
    free(lv->start_quality);
    free(lv->samples);
    free(lv->per_triangle);
    memset(lv, 0, sizeof *lv);
}
