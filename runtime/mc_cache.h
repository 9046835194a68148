/* A small cache of transition-cell triangulations for extraction.
 *
 * sl_mc_triangulate is a pure function of the cell's signs (corner, split-edge midpoint and
 * split-face centre signs; 44 bits), and a model's transition cells repeat a few hundred
 * configurations, so extraction looks them up instead of pairing crossings face by face
 * each time: at 1-20 % budgets the general triangulation was a quarter of the cost per
 * triangle. Direct-mapped, one 64-byte line per entry; only configurations of at most
 * SL_MC_CACHE_TRIANGLES triangles without centroid vertices are kept (the rest are
 * recomputed). Not thread-safe: one per model, used by one extraction at a time.
 */
#ifndef SCANLOD_RUNTIME_MC_CACHE_H
#define SCANLOD_RUNTIME_MC_CACHE_H

#include "runtime/mc_cube.h"

#define SL_MC_CACHE_TRIANGLES 18

typedef struct sl_mc_cache sl_mc_cache;

sl_mc_cache *sl_mc_cache_new(void); /* NULL when out of memory */
void sl_mc_cache_free(sl_mc_cache *cache);

/* As sl_mc_triangulate, except that on a cached configuration only count, points and
 * centroids (0) are written: read loops only when centroids is non-zero. `cache` may be
 * NULL (then it is sl_mc_triangulate). */
void sl_mc_triangulate_cached(sl_mc_cache *cache, const sl_mc_cell *cell,
                              sl_mc_triangles *out);

#endif
