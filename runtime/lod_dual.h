/* A cut drawn as the dual of its marching-cube surface ([octree] vertices = qef; docs/lod.md
 * "Vertices from quadrics").
 *
 * The marching-cube surface of a cut is a closed polygon mesh: its faces are the cells'
 * loops, its vertices the crossings. Its dual has one vertex per loop (the node's vertex
 * placed by the quadric of the surface the loop stands for, octree.h) and one polygon per
 * crossing, joining the loops around it in their order around the crossing, cut into
 * degree - 2 triangles. A loop is drawn when it has at least 3 crossings and its node has
 * vertices (an open scan's cells beyond its border have none: no surface across its
 * holes). Since every cell of a cut draws the same segments on a shared face as its
 * neighbour (the face rule, mc_cube.h), each segment joins exactly two loops, the loops
 * around a crossing close into one cycle, and the dual of a watertight cut is watertight.
 *
 * Triangles of a cut: the sum over its crossings of max(0, degree - 2), degree = the drawn
 * loops holding the crossing (what the crack stage's accumulation table counts).
 */
#ifndef SCANLOD_RUNTIME_LOD_DUAL_H
#define SCANLOD_RUNTIME_LOD_DUAL_H

#include <stdint.h>

#include "runtime/lod_mesh.h"
#include "runtime/mc_cube.h"
#include "runtime/octree.h"

/* The loops a dual cut draws for a cell: its marching-cube loops (sl_mc_triangulate),
 * a loop that passes one face twice split in two (sl_mc_split_double_passes). Only the
 * loops of *out are meaningful. */
void sl_dual_loops(const sl_mc_cell *cell, sl_mc_triangles *out /* OUT */);
/* Those of the 256 uniform cells (points are edge ids); a node's vertices follow their
 * loops' order. At most 4 loops and 12 points. */
const sl_mc_triangles *sl_dual_uniform_table(void);
/* The same as rows: row c = loop count of corner configuration c, the 4 loop sizes, then
 * the loops' edge ids one after another. */
#define SL_DUAL_UNIFORM_ROW 20
const uint8_t (*sl_dual_uniform_loops(void))[SL_DUAL_UNIFORM_ROW];

/* Loops around one crossing that are joined into its polygon, at most (the accumulation
 * table counts with the same cap). */
#define SL_DUAL_MAX_DEGREE 32

static inline int sl_dual_polygon_triangles(int degree)
{
    degree = degree < SL_DUAL_MAX_DEGREE ? degree : SL_DUAL_MAX_DEGREE;
    return degree > 2 ? degree - 2 : 0;
}

/* A loop's vertex: a vertex id, or one of these. */
#define SL_DUAL_NOT_DRAWN SL_OCTREE_NONE    /* fewer than 3 crossings, or its node has no vertex */
#define SL_DUAL_EXTRA (SL_OCTREE_NONE - 1u) /* drawn, but none of its node's vertices is its own:
                                               one goes at its crossings' centroid */

/* The vertex of each loop of node n's cell drawn as `tri` (point ids mapped to crossing
 * ids by point_crossing): each loop takes the vertex of the node's uniform loop with
 * which it shares the most crossings (each at most once; a node without uniform loops
 * offers its one vertex to the first loop). */
void sl_dual_loop_vertices(const sl_octree *t, uint32_t n, const sl_mc_triangles *tri,
                           const uint32_t point_crossing[SL_MC_MAX_POINTS],
                           uint32_t vertex[SL_MC_MAX_LOOPS] /* OUT */);

/* Puts the builder in dual mode: loops added with sl_mesh_builder_add_loop name vertices
 * of this table (positions 3 floats, colours RGBA or NULL, `count` entries); the
 * triangles are made by sl_mesh_builder_finish. Returns -1 when out of memory. */
int sl_mesh_builder_dual(sl_mesh_builder *b, const float *positions, const uint8_t *colors,
                         uint32_t count);
/* A drawn loop: its vertex and its n crossings in order (counter-clockwise seen from
 * outside). */
void sl_mesh_builder_add_loop(sl_mesh_builder *b, uint32_t vertex, const uint32_t *crossings,
                              int n);
/* The polygons around the crossings the loops touched, as triangles (lod_mesh.c calls it
 * from sl_mesh_builder_finish). */
void sl_mesh_builder_dual_polygons(sl_mesh_builder *b);

#endif
