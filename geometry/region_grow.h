/* Normal-angle region growing: the mesh segmentation of paper 3, section 3.1.
 *
 * A triangle T_i next to segment S_k joins it when (paper, equation 1)
 *     max over T_j in S_k of ang(T_j, T_i) <= delta_seg,
 * the angle between unit face normals: every pair of triangles of a segment is within
 * delta_seg of each other, not just neighbours (so a segment cannot creep around a
 * cylinder). The test is exact and costs O(h), h the vertex count of a small convex
 * hull: the segment's normals are kept as their convex hull in the gnomonic projection
 * on the tangent plane of the seed's normal (great circles become lines there), and for
 * delta_seg < 90 degrees the normals within delta_seg of T_i's form a convex region of
 * that plane, so the largest angle to T_i over the segment is taken at a hull vertex.
 *
 * The two problems of the paper:
 *  - Min-#: for a given delta_seg, few segments. Greedy: seeds are taken flattest first
 *    (the largest angle to an edge neighbour, quantised, then triangle index), and each
 *    segment grows best-first (closest normal to the seed's first, then triangle index)
 *    across edges with a twin (mesh_adjacency.h), until no neighbour passes equation 1.
 *  - Min-delta: for a given number of segments, the smallest delta_seg: bisection over
 *    delta_seg of the Min-# growth for the smallest delta whose count is within the
 *    target (the greedy count is nearly but not strictly monotone in delta).
 * Triangles without a normal (zero area, or left out of the adjacency as degenerate)
 * are segments of their own.
 *
 * Determinism: serial, and every choice is ordered by an index: the same input gives the
 * same segments on any machine and thread count.
 * Cost: O(n log n) for the heap, O(h) per test (h is typically 5-60), 32 bytes per
 * triangle. Thread safety: reentrant.
 */
#ifndef SCANLOD_GEOMETRY_REGION_GROW_H
#define SCANLOD_GEOMETRY_REGION_GROW_H

#include <stdint.h>

#include "core/error.h"
#include "geometry/mesh_adjacency.h"

#define SL_REGION_GROW_MAX_DELTA 89.0 /* degrees: the convexity argument needs < 90 */

typedef struct sl_region_grow_config {
    double delta_seg;          /* equation 1 threshold, degrees, (0, SL_REGION_GROW_MAX_DELTA];
                                  Min-#; default 30 */
    uint32_t target_segments;  /* 0: Min-# with delta_seg; >= 1: Min-delta, the smallest
                                  delta in [min_delta, max_delta] giving at most this many
                                  segments (or max_delta's count if none does) */
    double min_delta, max_delta; /* Min-delta search range, degrees; default 0.5, 89 */
    uint32_t search_steps;     /* Min-delta bisection steps; default 16 */
} sl_region_grow_config;

sl_region_grow_config sl_region_grow_default_config(void);

typedef struct sl_segmentation {
    uint32_t triangle_count;
    uint32_t segment_count;
    uint32_t *segment;       /* triangle_count: segment id; ids in order of their seeds */
    uint32_t *seed;          /* segment_count: the seed triangle of each segment */
    double delta_seg;        /* the threshold used, degrees (Min-delta: the one found) */
    uint64_t without_normal; /* triangles without a normal, each its own segment */
} sl_segmentation;

/* Segments the triangles of `adj` (positions: 3 floats per vertex). OUT: *out (release
 * with sl_segmentation_release). Returns 0, SL_E_BADINPUT (delta out of range, or a
 * non-finite coordinate), SL_E_NOMEM. */
int sl_region_grow(const sl_mesh_adjacency *adj, const float *positions,
                   const sl_region_grow_config *cfg, sl_segmentation *out, sl_error *err);

void sl_segmentation_release(sl_segmentation *s);

/* Unit face normals in double (3 per triangle); zero for a triangle without one
 * (zero-area or degenerate). Used by the growth; exposed for its callers' checks. */
void sl_face_normals(const sl_mesh_adjacency *adj, const float *positions, double *normals);

#endif
