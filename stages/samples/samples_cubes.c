/* samples stage: which grid vertices get a sample (paper 1 section 2.1: the vertices of the
 * cubes that contain points; docs/samples-stage.md, "Method": one sample per grid vertex).
 *
 * Method: sets of cubes and vertices are sorted arrays of packed keys (sl_vertex_key:
 * x << 40 | y << 20 | z), so memory follows the surface, never the bounding volume, and
 * the order is the (x, y, z) lexicographic order the samples file wants. The occupied
 * cubes are the only set that needs a sort (the key tables' LSD radix sort). Everything
 * after is a dilation, done one axis at a time: the union of copies of a sorted array
 * shifted by constants is a k-way merge of sorted arrays, O(n k) with no sort, and it runs
 * in parallel over ranges of output keys (counted first, then written at their prefix-sum
 * offsets). The band is the occupied set dilated by -band..band along
 * x, then y, then z (= the 26-neighbourhood, applied band times); the vertices of a set
 * of cubes are the set dilated by 0..1 along each axis. Each merge counts its result
 * first and refuses it above the cap before allocating it.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/samples/samples_internal.h"

enum { MAX_OFFSETS = 2 * SL_SAMPLES_MAX_BAND + 1, MAX_CHUNKS = 256 };

void samples_keys_release(samples_keys *k)
{
    free(k->keys);
    k->keys = NULL;
    k->count = 0;
}

/* Steps per edge of the grid of points laid on triangle t: ceil(longest edge / leaf),
 * capped so the count cannot overflow (such a triangle is refused by the caller's cap). */
static uint32_t triangle_steps(const sl_samples_plan *plan, const sl_pointset *ps, uint64_t t)
{
    const uint32_t *tri = ps->triangles + 3 * t;
    double longest = 0;
    for (int k = 0; k < 3; k++) {
        const float *p = ps->positions + 3 * (uint64_t)tri[k];
        const float *q = ps->positions + 3 * (uint64_t)tri[(k + 1) % 3];
        double d2 = 0;
        for (int a = 0; a < 3; a++)
            d2 += ((double)q[a] - p[a]) * ((double)q[a] - p[a]);
        longest = d2 > longest ? d2 : longest;
    }
    double steps = ceil(sqrt(longest) / plan->leaf_size);
    return steps <= 1 ? 1u : steps > 1e6 ? 1000000u : (uint32_t)steps;
}

/* Points of an n-step grid on a triangle, corners excluded (they are points already). */
static uint64_t grid_points(uint32_t n)
{
    return n <= 1 ? 0 : (uint64_t)(n + 1) * (n + 2) / 2 - 3;
}

/* Writes the cube keys of the grid points of triangle t (grid_points(n) of them). */
static void triangle_keys(const sl_samples_plan *plan, const sl_pointset *ps, uint64_t t,
                          uint32_t n, uint64_t *out)
{
    const uint32_t *tri = ps->triangles + 3 * t;
    const float *a = ps->positions + 3 * (uint64_t)tri[0];
    const float *b = ps->positions + 3 * (uint64_t)tri[1];
    const float *c = ps->positions + 3 * (uint64_t)tri[2];
    uint64_t at = 0;
    for (uint32_t i = 0; i <= n; i++)
        for (uint32_t j = 0; i + j <= n; j++) {
            if ((i == 0 && j == 0) || i == n || j == n)
                continue; /* corners */
            double u = (double)i / n, v = (double)j / n, w = 1 - u - v;
            uint32_t g[3];
            for (int k = 0; k < 3; k++)
                g[k] = samples_cube_of(plan, w * a[k] + u * b[k] + v * c[k], k);
            out[at++] = sl_vertex_key(g[0], g[1], g[2]);
        }
}

int samples_occupied_cubes(const sl_samples_plan *plan, const sl_pointset *ps, int use_triangles,
                           uint64_t max_count, samples_keys *out, uint64_t *extra_keys,
                           sl_error *err)
{
    out->keys = NULL;
    out->count = 0;
    *extra_keys = 0;
    uint64_t n = ps->count, t_count = use_triangles ? ps->triangle_count : 0, extra = 0;
    uint32_t *steps = t_count ? malloc(t_count * sizeof *steps) : NULL;
    if (t_count && !steps)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for %llu triangles",
                            (unsigned long long)t_count);
#pragma omp parallel for schedule(static) reduction(+ : extra) if (t_count > 65536)
    for (int64_t t = 0; t < (int64_t)t_count; t++) {
        steps[t] = triangle_steps(plan, ps, (uint64_t)t);
        extra += grid_points(steps[t]);
    }
    if (extra > max_count) {
        free(steps);
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "triangles much larger than the leaf (%g) need %llu occupancy "
                            "points, above [samples] max_samples %llu; set a larger "
                            "[octree] leaf_size", plan->leaf_size, (unsigned long long)extra,
                            (unsigned long long)max_count);
    }
    uint64_t *keys = malloc((n + extra) * sizeof *keys + 1);
    if (!keys) {
        free(steps);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for %llu cube keys",
                            (unsigned long long)(n + extra));
    }
    const float *p = ps->positions;
#pragma omp parallel for schedule(static) if (n > 65536)
    for (int64_t i = 0; i < (int64_t)n; i++)
        keys[i] = sl_vertex_key(samples_cube_of(plan, p[3 * i], 0),
                                 samples_cube_of(plan, p[3 * i + 1], 1),
                                 samples_cube_of(plan, p[3 * i + 2], 2));
    for (uint64_t t = 0, at = n; extra && t < t_count; t++) /* few triangles: serial */
        if (steps[t] > 1) {
            triangle_keys(plan, ps, t, steps[t], keys + at);
            at += grid_points(steps[t]);
        }
    free(steps);
    if (sl_sort_keys(keys, n + extra, 3 * SL_COORD_BITS) != 0) {
        free(keys);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory sorting %llu cube keys",
                            (unsigned long long)(n + extra));
    }
    out->count = sl_unique_keys(keys, n + extra);
    uint64_t *shrunk = realloc(keys, out->count * sizeof *keys + 1);
    out->keys = shrunk ? shrunk : keys;
    *extra_keys = extra;
    return SL_OK;
}

/* First index i with src[i] + delta >= key (src ascending; keys and shifted keys are
 * below 2^61, so signed arithmetic cannot overflow). */
static uint64_t lower_bound_shifted(const uint64_t *src, uint64_t n, int64_t delta, int64_t key)
{
    uint64_t lo = 0, hi = n;
    while (lo < hi) {
        uint64_t mid = lo + (hi - lo) / 2;
        if ((int64_t)src[mid] + delta < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The k-way merge of `src` shifted by `delta[0..m)`, restricted to output keys in
 * [lo, hi): writes the union into dst (if not NULL) and returns its size. */
static uint64_t merge_shifted(const uint64_t *src, uint64_t n, const int64_t *delta, int m,
                              int64_t lo, int64_t hi, uint64_t *dst)
{
    uint64_t at[MAX_OFFSETS], count = 0;
    for (int j = 0; j < m; j++)
        at[j] = lower_bound_shifted(src, n, delta[j], lo);
    int64_t last = -1;
    for (;;) {
        int64_t best = INT64_MAX;
        for (int j = 0; j < m; j++)
            if (at[j] < n && (int64_t)src[at[j]] + delta[j] < best)
                best = (int64_t)src[at[j]] + delta[j];
        if (best >= hi)
            return count;
        for (int j = 0; j < m; j++)
            if (at[j] < n && (int64_t)src[at[j]] + delta[j] == best)
                at[j]++;
        if (best != last) {
            if (dst)
                dst[count] = (uint64_t)best;
            count++;
            last = best;
        }
    }
}

/* Output key ranges for the parallel merge: chunk c covers [split[c], split[c + 1]),
 * cut at evenly spaced input keys. Any cut gives the same union, so the result does not
 * depend on the number of chunks or threads. */
static int merge_splits(const uint64_t *src, uint64_t n, int64_t delta0, int64_t *split)
{
    int chunks = (int)(n / 16384);
    chunks = chunks < 1 ? 1 : chunks > MAX_CHUNKS ? MAX_CHUNKS : chunks;
    split[0] = INT64_MIN;
    for (int c = 1; c < chunks; c++)
        split[c] = (int64_t)src[n / (uint64_t)chunks * (uint64_t)c] + delta0;
    split[chunks] = INT64_MAX;
    return chunks;
}

int samples_dilate(samples_keys *k, int axis, const int *offsets, int offset_count,
                   uint64_t max_count, sl_error *err)
{
    int64_t delta[MAX_OFFSETS], split[MAX_CHUNKS + 1];
    uint64_t start[MAX_CHUNKS + 1] = {0};
    int64_t stride = (int64_t)1 << (SL_COORD_BITS * (2 - axis));
    if (offset_count < 1 || offset_count > MAX_OFFSETS)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "dilation by %d offsets", offset_count);
    for (int j = 0; j < offset_count; j++)
        delta[j] = offsets[j] * stride; /* offsets ascend, so do the deltas */
    int chunks = merge_splits(k->keys, k->count, delta[0], split);
#pragma omp parallel for schedule(dynamic, 1) if (chunks > 1)
    for (int c = 0; c < chunks; c++)
        start[c + 1] = merge_shifted(k->keys, k->count, delta, offset_count, split[c],
                                     split[c + 1], NULL);
    for (int c = 0; c < chunks; c++)
        start[c + 1] += start[c];
    uint64_t n = start[chunks];
    if (n > max_count)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "the band needs more than %llu grid vertices ([samples] "
                            "max_samples); set a larger [octree] leaf_size or a smaller depth",
                            (unsigned long long)max_count);
    uint64_t *dst = malloc(n * sizeof *dst + 1);
    if (!dst)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for %llu keys",
                            (unsigned long long)n);
#pragma omp parallel for schedule(dynamic, 1) if (chunks > 1)
    for (int c = 0; c < chunks; c++)
        merge_shifted(k->keys, k->count, delta, offset_count, split[c], split[c + 1],
                      dst + start[c]);
    free(k->keys);
    k->keys = dst;
    k->count = n;
    return SL_OK;
}

int samples_band_vertices(const sl_samples_plan *plan, samples_keys *cubes, uint64_t max_count,
                          uint64_t *band_cubes, sl_error *err)
{
    int band[MAX_OFFSETS], corner[2] = {0, 1}, rc = SL_OK;
    for (int j = 0; j <= 2 * plan->band; j++)
        band[j] = j - plan->band;
    /* A set of cubes has at least as many vertices as cubes (each cube owns its minimum
     * corner), so the vertex cap also bounds every intermediate set. */
    for (int axis = 0; axis < 3 && rc == SL_OK && plan->band > 0; axis++)
        rc = samples_dilate(cubes, axis, band, 2 * plan->band + 1, max_count, err);
    *band_cubes = cubes->count;
    for (int axis = 0; axis < 3 && rc == SL_OK; axis++)
        rc = samples_dilate(cubes, axis, corner, 2, max_count, err);
    return rc;
}
