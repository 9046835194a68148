/* The vertex bricks (vertices_internal.h): the input's items (triangles, or the points of
 * a cloud) binned to the subtrees under the nodes of one level, so that the leaves'
 * quadrics are summed one brick at a time (docs/bricks.md, "The merge's vertices by
 * bricks").
 *
 * An item goes to every brick its box meets, since its pieces (octree_pieces.c) lie in
 * the leaf cubes of its box; a triangle across a brick face is cut in each brick and each
 * keeps the pieces in its own leaves. Each brick's list is ascending, so a leaf's pieces
 * are summed in the same order as in one pass over all items: the quadrics, and so the
 * octree, are byte-identical whatever the brick level and the thread count. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/alloc.h"
#include "stages/merge/vertices_internal.h"

/* Items are binned in this many runs, whatever the thread count (the lists do not depend
 * on it: each run's entries follow the previous run's in every brick). */
#define BIN_RUNS 16

#define GRID_LIMIT 1048576.0 /* 2^20: sl_morton3's coordinates */

/* The box of item i in leaf cubes, clamped to the grid; 0 when it meets no cube of the
 * grid (outside it, or not finite: such an item has no piece either). */
static int item_cubes(const sl_octree *t, const sl_surface *s, uint64_t i, uint32_t lo[3],
                      uint32_t hi[3])
{
    double a[3] = {INFINITY, INFINITY, INFINITY}, z[3] = {-INFINITY, -INFINITY, -INFINITY};
    int corners = s->triangle_count ? 3 : 1;
    for (int k = 0; k < corners; k++) {
        uint64_t p = s->triangle_count ? s->triangles[3 * i + (uint64_t)k] : i;
        for (int d = 0; d < 3; d++) {
            double v = (s->positions[3 * p + (uint64_t)d] - t->origin[d]) / t->leaf_size;
            if (!isfinite(v))
                return 0;
            a[d] = fmin(a[d], v);
            z[d] = fmax(z[d], v);
        }
    }
    for (int d = 0; d < 3; d++) {
        double f0 = floor(a[d]), f1 = floor(z[d]);
        if (f1 < 0 || f0 >= GRID_LIMIT)
            return 0;
        lo[d] = (uint32_t)fmax(f0, 0);
        hi[d] = (uint32_t)fmin(f1, GRID_LIMIT - 1);
    }
    return 1;
}

/* The brick (index into the level) whose root has Morton code `key`, or UINT32_MAX. */
static uint32_t brick_of(const sl_octree *t, uint32_t level, uint64_t key)
{
    uint32_t lo = t->level_first[level], node = sl_octree_search(t, lo, lo + t->level_count[level], key);
    return node == SL_OCTREE_NONE ? UINT32_MAX : node - lo;
}

/* Visits the bricks item i goes to: counts them (fill == NULL) or appends i to their
 * lists at cursor[brick]. */
static void bin_item(const sl_octree *t, const sl_surface *s, uint32_t level, uint64_t i,
                     uint64_t *count, uint64_t *cursor, uint32_t *fill)
{
    uint32_t lo[3], hi[3];
    if (!item_cubes(t, s, i, lo, hi))
        return;
    for (uint32_t x = lo[0] >> level; x <= hi[0] >> level; x++)
        for (uint32_t y = lo[1] >> level; y <= hi[1] >> level; y++)
            for (uint32_t z = lo[2] >> level; z <= hi[2] >> level; z++) {
                uint32_t k = brick_of(t, level, sl_morton3(x, y, z));
                if (k == UINT32_MAX)
                    continue;
                if (fill)
                    fill[cursor[k]++] = (uint32_t)i;
                else
                    count[k]++;
            }
}

int sl_vertex_bricks_bin(const sl_octree *t, const sl_surface *s, uint32_t level,
                         vertex_bricks *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    uint64_t items = s->triangle_count ? s->triangle_count : s->point_count;
    if (items > UINT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "%llu input items: the vertex bricks index at most 2^32",
                            (unsigned long long)items);
    if (!t->morton)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "vertex bricks need the octree's index");
    uint32_t bricks = t->level_count[level];
    out->level = level;
    out->count = bricks;
    out->item_first = malloc(((size_t)bricks + 1) * sizeof *out->item_first);
    uint64_t *counts = sl_alloc_zeroed((size_t)BIN_RUNS * bricks, sizeof *counts);
    if (!out->item_first || !counts) {
        free(counts);
        sl_vertex_bricks_release(out);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory binning the input to bricks");
    }
    uint64_t per_run = (items + BIN_RUNS - 1) / BIN_RUNS;
#pragma omp parallel for schedule(dynamic, 1)
    for (int r = 0; r < BIN_RUNS; r++)
        for (uint64_t i = (uint64_t)r * per_run; i < items && i < (uint64_t)(r + 1) * per_run; i++)
            bin_item(t, s, level, i, counts + (size_t)r * bricks, NULL, NULL);
    /* Brick-major, run-minor: counts[r][k] becomes run r's first slot in brick k. */
    uint64_t total = 0;
    for (uint32_t k = 0; k < bricks; k++) {
        out->item_first[k] = total;
        for (int r = 0; r < BIN_RUNS; r++) {
            uint64_t c = counts[(size_t)r * bricks + k];
            counts[(size_t)r * bricks + k] = total;
            total += c;
        }
    }
    out->item_first[bricks] = total;
    out->item = malloc((total ? total : 1) * sizeof *out->item);
    if (!out->item) {
        free(counts);
        sl_vertex_bricks_release(out);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory binning the input to bricks");
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (int r = 0; r < BIN_RUNS; r++)
        for (uint64_t i = (uint64_t)r * per_run; i < items && i < (uint64_t)(r + 1) * per_run; i++)
            bin_item(t, s, level, i, NULL, counts + (size_t)r * bricks, out->item);
    free(counts);
    return 0;
}

void sl_vertex_bricks_release(vertex_bricks *b)
{
    free(b->item_first);
    free(b->item);
    memset(b, 0, sizeof *b);
}

uint32_t sl_vertex_brick_level(const sl_octree *t, uint32_t wanted)
{
    if (t->depth == 0)
        return 0;
    if (wanted < 1)
        wanted = 1;
    return wanted < t->depth ? wanted : t->depth;
}
