/* samples stage: which grid vertices get a sample (paper 1 section 2.1: the vertices of the
 * cubes that contain points; ARCHITECTURE section 5: one sample per grid vertex).
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

int samples_occupied_cubes(const sl_samples_plan *plan, const sl_pointset *ps, samples_keys *out,
                           sl_error *err)
{
    out->keys = NULL;
    out->count = 0;
    uint64_t n = ps->count;
    uint64_t *keys = malloc(n * sizeof *keys + 1);
    if (!keys)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for %llu cube keys",
                            (unsigned long long)n);
    const float *p = ps->positions;
#pragma omp parallel for schedule(static) if (n > 65536)
    for (int64_t i = 0; i < (int64_t)n; i++)
        keys[i] = sl_vertex_key(samples_cube_of(plan, p[3 * i], 0),
                                 samples_cube_of(plan, p[3 * i + 1], 1),
                                 samples_cube_of(plan, p[3 * i + 2], 2));
    if (sl_sort_keys(keys, n, 3 * SL_COORD_BITS) != 0) {
        free(keys);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory sorting %llu cube keys",
                            (unsigned long long)n);
    }
    out->count = sl_unique_keys(keys, n);
    uint64_t *shrunk = realloc(keys, out->count * sizeof *keys + 1);
    out->keys = shrunk ? shrunk : keys;
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
