/* The level as the fit sees it (surface_fit_internal.h): checked, welded (vertices at
 * bit-identical positions become one unknown, so a texture seam cannot open), its edges
 * (the matrix's pattern and the open border), each vertex's corners, and the triangles'
 * normals and shapes as given, which the guards compare against.
 */
#include <assert.h>
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

static int key_order(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

/* Sorts a bucket of corner ids by their edge's upper end, then by id, through `keys`
 * (grown to the largest bucket): by insertion for the usual few edges, by qsort for a
 * vertex in many triangles (a fan's apex), which insertion would make quadratic. */
static int sort_bucket(const uint32_t *tri, uint32_t *bucket, uint32_t size, uint64_t **keys,
                       uint32_t *capacity)
{
    if (size > *capacity) {
        uint64_t *grown = realloc(*keys, (size_t)size * sizeof *grown);
        if (!grown)
            return -1;
        *keys = grown;
        *capacity = size;
    }
    for (uint32_t i = 0; i < size; i++) {
        uint32_t a = tri[bucket[i]], b = tri[fit_next_corner(bucket[i])];
        (*keys)[i] = (uint64_t)(a > b ? a : b) << 32 | bucket[i];
    }
    if (size > 32)
        qsort(*keys, size, sizeof **keys, key_order);
    for (uint32_t i = 1; size <= 32 && i < size; i++) { /* buckets hold about 3 edges */
        uint64_t k = (*keys)[i];
        uint32_t j = i;
        for (; j > 0 && (*keys)[j - 1] > k; j--)
            (*keys)[j] = (*keys)[j - 1];
        (*keys)[j] = k;
    }
    for (uint32_t i = 0; i < size; i++)
        bucket[i] = (uint32_t)(*keys)[i];
    return 0;
}

/* The open corners of a sorted bucket: written to `out` when given; returns their count. */
static uint32_t bucket_open(const uint32_t *tri, const uint32_t *bucket, uint32_t size,
                            uint32_t *out)
{
    uint32_t count = 0;
    for (uint32_t i = 0, run; i < size; i += run) {
        uint32_t a = tri[bucket[i]], b = tri[fit_next_corner(bucket[i])];
        uint32_t upper = a > b ? a : b;
        for (run = 1; i + run < size; run++) {
            uint32_t c = tri[bucket[i + run]], d = tri[fit_next_corner(bucket[i + run])];
            if ((c > d ? c : d) != upper)
                break;
        }
        if (run == 1) {
            if (out)
                out[count] = bucket[i];
            count++;
        }
    }
    return count;
}

#define OPEN_CHUNKS 256 /* vertex runs counted, then filled, in parallel */

/* The corners of non-degenerate edges bucketed by the edge's lower end (a counting sort),
 * each bucket sorted by the upper end: an edge met once is open. The open corners come
 * out in ascending (lower, upper) order, as sorting every edge by its pair gave them, in
 * 4 bytes a corner instead of two arrays of 16 (a 20 M-triangle input: 240 MB instead of
 * 1.9 GB, the refine stage's peak when its first fit prepared the input). */
int fit_open_edges(const uint32_t *tri, uint64_t triangle_count, uint32_t vertex_count,
                   uint32_t **open, uint64_t *count, sl_error *err)
{
    *open = NULL;
    *count = 0;
    uint64_t corners = 3 * triangle_count;
    if (corners >= UINT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "fit: %llu triangles",
                            (unsigned long long)triangle_count);
    uint32_t *start = calloc((size_t)vertex_count + 1, sizeof *start);
    uint32_t *bucket = malloc((corners ? corners : 1) * sizeof *bucket);
    uint64_t *found = calloc(OPEN_CHUNKS + 1, sizeof *found);
    if (!start || !bucket || !found) {
        free(start);
        free(bucket);
        free(found);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: edges of %llu triangles",
                            (unsigned long long)triangle_count);
    }
    for (uint32_t c = 0; c < corners; c++) {
        uint32_t a = tri[c], b = tri[fit_next_corner(c)];
        assert(a < vertex_count && b < vertex_count);
        if (a != b)
            start[a < b ? a : b]++;
    }
    uint32_t sum = 0;
    for (uint32_t v = 0; v <= vertex_count; v++) { /* start[v]: the end of v's bucket */
        sum += start[v];
        start[v] = sum;
    }
    for (uint32_t c = corners; c-- > 0;) { /* filled backwards: each bucket ascending */
        uint32_t a = tri[c], b = tri[fit_next_corner(c)];
        if (a != b)
            bucket[--start[a < b ? a : b]] = c;
    }
    int failed = 0;
    for (int pass = 0; pass < 2 && !failed; pass++) {
        if (pass == 1) { /* the chunks' offsets, and the array they fill */
            for (int k = 0; k < OPEN_CHUNKS; k++)
                found[k + 1] += found[k];
            *count = found[OPEN_CHUNKS];
            if (*count == 0)
                break;
            *open = malloc(*count * sizeof **open);
            if (!*open) {
                failed = 1;
                break;
            }
        }
#pragma omp parallel for schedule(dynamic, 1)
        for (int k = 0; k < OPEN_CHUNKS; k++) {
            uint32_t v0 = (uint32_t)((uint64_t)vertex_count * k / OPEN_CHUNKS);
            uint32_t v1 = (uint32_t)((uint64_t)vertex_count * (k + 1) / OPEN_CHUNKS);
            uint64_t *keys = NULL, at = pass ? found[k] : 0;
            uint32_t capacity = 0;
            for (uint32_t v = v0; v < v1; v++) {
                uint32_t *b = bucket + start[v], size = start[v + 1] - start[v];
                if (pass == 0 && sort_bucket(tri, b, size, &keys, &capacity)) {
#pragma omp atomic write
                    failed = 1;
                    break;
                }
                at += bucket_open(tri, b, size, pass ? *open + at : NULL);
            }
            if (pass == 0)
                found[k + 1] = at;
            free(keys);
        }
    }
    free(start);
    free(bucket);
    free(found);
    if (failed) {
        free(*open);
        *open = NULL;
        *count = 0;
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: open edges");
    }
    return SL_OK;
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
    uint64_t n = 0;
    int rc = edge_pairs(lv->tri, lv->triangle_count, &pairs, &n, err);
    if (rc == SL_OK)
        rc = build_rows(lv, pairs, n, err);
    if (rc == SL_OK)
        fix_fins(lv, pairs, n);
    free(pairs);
    uint64_t open_count = 0;
    if (rc == SL_OK)
        rc = fit_open_edges(lv->tri, lv->triangle_count, lv->vertex_count, &lv->border_edges,
                            &open_count, err);
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
