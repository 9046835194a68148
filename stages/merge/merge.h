/* merge stage (paper 1, section 2.2): signed samples -> marching-cube octree.
 *
 * Leaf nodes are the leaf-grid cubes whose 8 corners all carry a sample; their vertex signs
 * are the samples' signs and their edge ratios come from "simple divide" of the two
 * distances. Parents are built bottom-up, level by level: a parent corner takes the sign of
 * the corresponding child vertex (case A), else of the adjacent child vertices (B: edge
 * midpoints), else the diagonal ones (C: face centres), else the centre (D), as in the
 * paper's Figure 2 -- looked up in the level's global vertex table, so that every parent
 * sharing a corner agrees. A parent's crossing on an edge is the child's crossing on the
 * half-edge where the sign flips (ratio extension); only when no child crossing exists is
 * a new one made at the half's middle (counted as a fallback). Output: `octree.slot`.
 */
#ifndef SCANLOD_STAGES_MERGE_H
#define SCANLOD_STAGES_MERGE_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "pipeline/stage.h"
#include "runtime/octree.h"

#define SL_OCTREE_FILE "octree.slot"

extern const sl_stage sl_merge_stage;

/* The resolved [merge] section (options: stages/merge/merge_stage.c). */
typedef struct sl_merge_config {
    uint64_t max_samples; /* refuse sample grids with more samples (a memory guard) */
    int qef_vertices;     /* [octree] vertices = qef: dual vertices from quadrics (else mc:
                             paper 1's marching-cube triangles) */
    double qef_tau;       /* [octree] qef_tau: the solve's truncation (sl_qef_solve) */
} sl_merge_config;

/* The section at its option table's defaults (sl_stage_default_config). */
sl_merge_config sl_merge_default_config(void);

/* Signed samples on the leaf grid (the samples stage's output, read back). */
typedef struct sl_sample_grid {
    uint64_t count;
    const int32_t *coords;  /* 3 * count, leaf-grid vertex coordinates */
    const float *distance;  /* signed distance, world units, < 0 inside */
    const uint8_t *colors;  /* 4 * count RGBA, or NULL */
    double leaf_size;       /* the leaf cubes' edge, world units */
    double origin[3];       /* world position of grid vertex (0, 0, 0) */
} sl_sample_grid;

/* Builds the octree; deterministic whatever the thread count. */
int sl_octree_build(const sl_sample_grid *samples, sl_octree *out, sl_progress *progress,
                    sl_error *err);
/* The same, calling release(owner) as soon as the leaves are built, success or not: the
 * samples' arrays are read no more (only the grid's scalars are), so they need not be
 * held beside the level tables and the octree being assembled (the merge stage's peak:
 * at 1 M triangles 54 of its 244 MB). */
int sl_octree_build_releasing(const sl_sample_grid *samples, void (*release)(void *owner),
                              void *owner, sl_octree *out, sl_progress *progress, sl_error *err);

/* The input surface the vertices are fitted to: triangles (positions indexed by
 * triangles), or oriented points each standing for `point_area` of surface. */
typedef struct sl_surface {
    uint64_t point_count;
    const float *positions; /* 3 * point_count, world */
    const float *normals;   /* 3 * point_count (points only; may be NULL with triangles) */
    const uint8_t *colors;  /* 4 * point_count RGBA, or NULL */
    uint64_t triangle_count;
    const uint32_t *triangles;
    double point_area;      /* world^2 per point, when there are no triangles */
    int open;               /* trim the loops of cells that hold none of the surface (an
                               open scan: no surface across its holes) */
} sl_surface;

/* The level of the vertex bricks' roots the merge stage uses: a brick (the subtree under
 * one node of that level) is 64 leaf cubes wide, holds about 10^4 leaves of a smooth
 * surface and repeats the cutting of the few triangles across its faces. */
#define SL_VERTEX_BRICK_LEVEL 6u

/* Dual vertices of every node from the quadrics of `s` (octree_vertices.c; octree.h
 * "Vertices"): fills vertex_first, vertex_position, vertex_color (when the tree has
 * colours and `s` has), node_error and node_area. `tau`: sl_qef_solve's truncation. The
 * levels below `brick_level` are built brick by brick (a brick: the subtree under one node
 * of that level; clamped to 1 .. the root's level). Byte-identical whatever the brick
 * level and the thread count. */
int sl_octree_vertices(sl_octree *t, const sl_surface *s, double tau, uint32_t brick_level,
                       sl_error *err);

#endif
