/* samples stage: which grid vertices get a sample (paper 1 section 2.1: the vertices of the
 * cubes that contain points; ARCHITECTURE section 5: one sample per grid vertex).
 *
 * Method: sets of cubes and vertices are sorted arrays of packed keys (sl_vertex_key:
 * x << 40 | y << 20 | z), so memory follows the surface, never the bounding volume, and
 * the order is the (x, y, z) lexicographic order the samples file wants. The occupied
 * cubes are the only set that needs a sort (the key tables' LSD radix sort). Everything
 * after is a dilation, done one axis at a time: the
 * union of copies of a sorted array shifted by constants is a k-way merge of sorted
 * arrays, O(n k) with no sort. The band is the occupied set dilated by -band..band along
 * x, then y, then z (= the 26-neighbourhood, applied band times); the vertices of a set
 * of cubes are the set dilated by 0..1 along each axis. Each merge counts its result
 * first and refuses it above the cap before allocating it.
 */
#include <stdlib.h>
#include <string.h>

#include "stages/samples/samples_internal.h"

enum { MAX_OFFSETS = 2 * SL_SAMPLES_MAX_BAND + 1 };

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
#pragma omp parallel for schedule(static)
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

/* One k-way merge of `src` shifted by `delta[0..m)` (ascending): writes the union into
 * dst (if not NULL) and returns its size. */
static uint64_t merge_shifted(const uint64_t *src, uint64_t n, const int64_t *delta, int m,
                              uint64_t *dst)
{
    uint64_t at[MAX_OFFSETS] = {0}, count = 0, last = 0;
    for (;;) {
        uint64_t best = UINT64_MAX;
        for (int j = 0; j < m; j++)
            if (at[j] < n && src[at[j]] + (uint64_t)delta[j] < best)
                best = src[at[j]] + (uint64_t)delta[j];
        if (best == UINT64_MAX)
            return count;
        for (int j = 0; j < m; j++)
            if (at[j] < n && src[at[j]] + (uint64_t)delta[j] == best)
                at[j]++;
        if (count == 0 || best != last) {
            if (dst)
                dst[count] = best;
            count++;
            last = best;
        }
    }
}

int samples_dilate(samples_keys *k, int axis, const int *offsets, int offset_count,
                   uint64_t max_count, sl_error *err)
{
    int64_t delta[MAX_OFFSETS];
    int64_t stride = (int64_t)1 << (SL_COORD_BITS * (2 - axis));
    if (offset_count < 1 || offset_count > MAX_OFFSETS)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "dilation by %d offsets", offset_count);
    for (int j = 0; j < offset_count; j++)
        delta[j] = offsets[j] * stride; /* two's complement: adding wraps to a subtraction */
    uint64_t n = merge_shifted(k->keys, k->count, delta, offset_count, NULL);
    if (n > max_count)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "the band needs more than %llu grid vertices ([samples] "
                            "max_samples); set a larger [octree] leaf_size or a smaller depth",
                            (unsigned long long)max_count);
    uint64_t *dst = malloc(n * sizeof *dst + 1);
    if (!dst)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for %llu keys",
                            (unsigned long long)n);
    merge_shifted(k->keys, k->count, delta, offset_count, dst);
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
