/* Internals of the quadric vertices, shared by stages/merge/octree_vertices.c (levels,
 * output) and octree_pieces.c (the input surface cut along the leaf grid). Not an
 * interface: merge.h is. */
#ifndef SCANLOD_STAGES_MERGE_VERTICES_INTERNAL_H
#define SCANLOD_STAGES_MERGE_VERTICES_INTERNAL_H

#include <stdint.h>

#include "geometry/qef.h"
#include "stages/merge/merge.h"

/* One level's vertex slots: max(loops, 1) per node, node i's at first[i]. */
typedef struct level_slots {
    uint32_t node0, nodes;  /* the level's nodes in the octree */
    uint32_t *first;        /* nodes + 1 */
    sl_qef *qef;
    double *color;          /* 4 per slot: sum of w * RGBA (0..255), or NULL (no colours) */
    double *x;              /* 3 per slot: the solved vertex, grid units from the corner */
} level_slots;

/* Loops of node n (the dual uniform table's), its corner in leaf-grid units, a crossing
 * relative to a corner, and the loop nearest to a point (grid units from the corner). */
int sl_vertices_node_loops(const sl_octree_node *n);
void sl_vertices_node_corner(const sl_octree_node *n, double c[3]);
void sl_vertices_crossing_local(const sl_octree *t, uint32_t id, const double corner[3],
                                double p[3]);
int sl_vertices_nearest_loop(const sl_octree *t, const sl_octree_node *n, const double p[3]);

/* The leaves' quadrics from the input surface (octree_pieces.c). */
int sl_vertices_leaf_quadrics(const sl_octree *t, const sl_surface *s, level_slots *leaves,
                              sl_error *err);

#endif
