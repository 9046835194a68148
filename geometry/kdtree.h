/* A static k-d tree over float points for k-nearest-neighbour and closest-point queries
 * (range stage PCA normals and spacing, samples stage closest points, compare tool).
 *
 * Results are exact and deterministic: neighbours come sorted by (squared distance,
 * index), so equal distances are broken by the lower point index, and the same query
 * gives the same answer on any thread count.
 *
 * Sizes: at most SL_KDTREE_MAX_POINTS points (indices are uint32_t).
 * Ownership: the tree copies the points it needs (the caller's array may be freed).
 * Thread safety: build runs OpenMP tasks inside (same tree on any thread count); queries
 * on a built tree are read-only and may run concurrently from any number of threads
 * (e.g. inside `omp parallel for`).
 */
#ifndef SCANLOD_GEOMETRY_KDTREE_H
#define SCANLOD_GEOMETRY_KDTREE_H

#include <stdint.h>

#include "core/error.h"

#define SL_KDTREE_MAX_POINTS 0xfffffffeu

typedef struct sl_kdtree sl_kdtree;

/* Builds a tree over `count` points (xyz, 3 * count floats; all finite).
 * Returns 0, SL_E_NOMEM, or SL_E_LIMIT when count > SL_KDTREE_MAX_POINTS. */
int sl_kdtree_build(sl_kdtree **out, const float *points, uint64_t count, sl_error *err);

/* The k nearest points to `query` (the query point itself included when it is one of
 * the points). OUT: out_idx[k], out_dist2[k] (squared distances, ascending; may be NULL).
 * Returns the number found, min(k, count). */
uint32_t sl_kdtree_knn(const sl_kdtree *tree, const float query[3], uint32_t k,
                       uint32_t *out_idx, float *out_dist2);

/* The closest point's index (lowest index among equals); OUT: *dist2 (may be NULL).
 * Returns UINT32_MAX on an empty tree. */
uint32_t sl_kdtree_nearest(const sl_kdtree *tree, const float query[3], float *dist2);

uint64_t sl_kdtree_count(const sl_kdtree *tree);

void sl_kdtree_free(sl_kdtree *tree); /* NULL is fine */

#endif
