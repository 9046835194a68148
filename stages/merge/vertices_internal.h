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

/* The quadrics of the leaves in `leaves` (a run of level 0) from the input's items (its
 * triangles, or the points of a cloud) items[0 .. count), or 0 .. count when items is
 * NULL: their pieces in other leaves are dropped (octree_pieces.c). Serial: a brick is
 * one thread's. */
void sl_vertices_leaf_quadrics(const sl_octree *t, const sl_surface *s, level_slots *leaves,
                               const uint32_t *items, uint64_t count);

/* The vertex bricks (octree_bricks.c): the subtrees under the nodes of one level, brick k
 * under node level_first[level] + k; its items (triangles, or points of a cloud) are
 * those whose box meets its cube, ascending: item[item_first[k] .. item_first[k + 1]). */
typedef struct vertex_bricks {
    uint32_t level;
    uint32_t count;
    uint64_t *item_first;   /* count + 1 */
    uint32_t *item;
} vertex_bricks;

/* The level of the bricks' roots for a wanted one: within 1 .. the root's level (0 for a
 * tree of one node). */
uint32_t sl_vertex_brick_level(const sl_octree *t, uint32_t wanted);
/* Bins s's items to the bricks of `level` (>= 1; needs t->morton). Deterministic. */
int sl_vertex_bricks_bin(const sl_octree *t, const sl_surface *s, uint32_t level,
                         vertex_bricks *out, sl_error *err);
void sl_vertex_bricks_release(vertex_bricks *b);

#endif
