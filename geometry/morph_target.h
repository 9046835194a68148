/* Morph targets between levels of detail (docs/morphing.md): where each vertex of a finer
 * level goes on the next coarser one, so a viewer can blend the two (glTF morph targets,
 * three.js morphTargetInfluences) instead of popping from one to the other.
 *
 * The method-agnostic target is the closest point of the coarser level's surface: at
 * weight 1 every vertex lies on the coarser surface (to float rounding), at weight 0 the
 * level is itself. Where the two levels share a vertex (an octree crossing both cuts
 * keep, a cluster corner), its closest point is itself: it does not move.
 *
 * Thread safety: reentrant; the queries run in parallel (OpenMP), the result does not
 * depend on the thread count.
 */
#ifndef SCANLOD_GEOMETRY_MORPH_TARGET_H
#define SCANLOD_GEOMETRY_MORPH_TARGET_H

#include <stdint.h>

#include "core/error.h"
#include "geometry/mesh.h"

/* For each of the `count` points `positions` (3 floats each, world), its closest point
 * on the triangles of `coarser` into `out` (OUT: 3 * count floats, caller-allocated; may
 * not alias `positions`). `coarser` needs at least one triangle and finite positions (the
 * caller checks: sl_mesh_check_writable). Returns 0, SL_E_NOMEM, or SL_E_BADINPUT for a
 * coarser mesh without triangles. *max_move (OUT, may be NULL): the largest distance a
 * point moves, world. */
int sl_morph_closest_points(const sl_mesh *coarser, const float *positions, uint64_t count,
                            float *out, double *max_move, sl_error *err);

/* The mesh at weight w of a morph: p + w (t - p) per coordinate into `out` (3 * count),
 * with w = 0 giving p and w = 1 giving t exactly (bit for bit, -0 included). */
void sl_morph_blend(const float *positions, const float *targets, uint64_t count, double w,
                    float *out);

#endif
