/* samples stage (paper 1, section 2.1 "Marching Cube Node"; docs/samples-stage.md, "Method"
 * "Samples").
 *
 * Oriented points and triangles (the range stage's points.slpts) -> signed samples at the grid vertices
 * of the leaf cubes, written as sparse OpenVDB grids (samples.vdb, shim/vdb_shim.h):
 *   - leaf size: [octree] leaf_size, or from [octree] depth, or spacing_factor x the
 *     mean nearest-neighbour spacing of the points (docs/samples-stage.md);
 *   - occupied cubes = leaf cubes holding at least one point (meshes: also points laid
 *     on every triangle longer than a leaf); the band = occupied cubes dilated by
 *     [samples] band cubes (26-neighbourhood); every grid vertex of every band cube is
 *     sampled once (one sample per vertex, shared by the cubes meeting there, so
 *     neighbouring cubes agree and the surface closes);
 *   - meshes ([samples] closest = triangles): p = the closest point of the triangles
 *     (geometry/triangle_bvh.h), sign from the pseudonormal of the face, edge or vertex
 *     it lies on, sample = the exact signed distance; on closed meshes the signs are then
 *     made consistent by the distance balls (samples_signs.c);
 *   - point clouds (or closest = points, the paper): p = the closest point (exact,
 *     geometry/kdtree.h), sign s = sign((v - p) . n_p) with 0 -> +, distance |v - p|
 *     (paper, `euclidean`) or |(v - p) . n_p| (`tangent`); stored s * d;
 *   - colour = p's colour.
 *
 * Grid (all samples inside one octree root): index (0,0,0) is at `origin` = bounding-box
 * minimum - band * leaf_size; the occupied cubes' indices start at `band`; every sample
 * coordinate lies in [0, 2^depth] on each axis, where depth is the smallest with
 * 2^depth >= (cubes spanned by the bounding box on its longest axis) + 2 * band. So the
 * merge stage can take the octree's root as the cube [0, 2^depth]^3 of grid vertices.
 *
 * Memory grows with the surface: occupied cubes, band cubes and vertices are sorted
 * arrays of packed keys (sl_vertex_key, 20 bits per axis), never a dense 3D array; every
 * size is checked
 * against [samples] max_samples before it is allocated.
 * Determinism: vertices are sorted before the parallel closest-point phase, which writes
 * into arrays indexed by vertex position; ties go to the lower point index.
 */
#ifndef SCANLOD_STAGES_SAMPLES_H
#define SCANLOD_STAGES_SAMPLES_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/mesh.h"
#include "pipeline/stage.h"
#include "shim/vdb_shim.h"
#include "stages/range/range.h"

#define SL_SAMPLES_FILE "samples.vdb"
#define SL_SAMPLES_MAX_DEPTH 19 /* vertex coordinates <= 2^19 fit the 20-bit fields of
                                   the key tables (geometry/key_table.h) */
#define SL_SAMPLES_MAX_BAND 8
/* The automatic leaf (from the point spacing) is at most the bounding box's diagonal
 * divided by this: a mesh of a few large triangles has vertices as far apart as its
 * own size, and 1.5 x that spacing would be a leaf with no sample inside the shape
 * (docs/samples-stage.md, "The grid"). */
#define SL_SAMPLES_DIAGONAL_LEAVES 16

extern const sl_stage sl_samples_stage;

enum sl_samples_distance {
    SL_SAMPLES_EUCLIDEAN = 0, /* |v - p| (paper 1 section 2.1) */
    SL_SAMPLES_TANGENT = 1    /* |(v - p) . n_p|: distance to p's tangent plane */
};

enum sl_samples_closest {
    SL_SAMPLES_CLOSEST_TRIANGLES = 0, /* nearest point of the input's triangles (meshes) */
    SL_SAMPLES_CLOSEST_POINTS = 1     /* nearest input point (paper 1 section 2.1) */
};

/* The resolved [octree] + [samples] options (table: stages/samples/samples_stage.c). */
typedef struct sl_samples_config {
    double leaf_size;      /* world units; 0 = from depth, else from spacing */
    int depth;             /* octree depth when > 0 (and leaf_size is 0) */
    double spacing_factor; /* auto leaf size = this x mean point spacing */
    int max_depth;         /* refuse leaf sizes needing a deeper octree (SL_E_LIMIT) */
    int closest;           /* enum sl_samples_closest; point clouds always use points */
    int distance;          /* enum sl_samples_distance */
    int band;              /* dilation of the occupied cubes, in cubes (0 = paper) */
    uint64_t max_samples;  /* refuse more samples than this (SL_E_LIMIT) */
    int sign_neighbours;   /* 1 = paper (closest point's normal); k > 1: weighted vote of
                              the k nearest points' normals */
} sl_samples_config;

/* Both sections at their option table's defaults (sl_stage_default_config). */
sl_samples_config sl_samples_default_config(void);

/* The grid the samples live on. */
typedef struct sl_samples_plan {
    double leaf_size;   /* world units */
    double origin[3];   /* world position of grid vertex (0,0,0) */
    double bbox_min[3], bbox_max[3]; /* of the points, world */
    int depth;          /* octree levels: the root is 2^depth leaf cubes wide */
    uint32_t cells[3];  /* leaf cubes the bounding box spans per axis (>= 1) */
    int band;
} sl_samples_plan;

/* What the stage did (the report; seconds are in the log, not the report). */
typedef struct sl_samples_counts {
    sl_samples_plan plan;
    uint64_t points;
    uint64_t triangles;           /* triangles the samples were measured against (0: the
                                     points were) */
    uint64_t triangle_keys;       /* extra occupancy keys from triangles larger than a leaf */
    uint64_t occupied_cubes, band_cubes, samples;
    uint64_t inside, outside;     /* samples with value < 0 / >= 0 */
    uint64_t sign_flips;          /* sign_neighbours > 1: votes that overruled the
                                     closest point's sign */
    int closed_surface;           /* the triangles are closed and consistently wound */
    uint64_t sign_repairs;        /* closest = triangles: signs outvoted by their region
                                     (stages/samples/samples_signs.c) */
    double seconds_plan, seconds_cubes; /* wall time per phase: grid; cubes and vertices */
    double seconds_tree, seconds_samples; /* k-d tree build; closest points (parallel) */
} sl_samples_counts;

/* Chooses leaf size, origin and depth for `ps` (no allocation). SL_E_BADINPUT when no
 * leaf size can be derived (no points, non-finite coordinates, zero spacing), SL_E_LIMIT
 * when the leaf size needs more than cfg->max_depth levels. */
int sl_samples_plan_make(const sl_samples_config *cfg, const sl_pointset *ps,
                         sl_samples_plan *plan, sl_error *err);

/* The whole computation in memory: OUT: *out (release with sl_vdb_samples_release),
 * *counts. Returns 0, SL_E_BADINPUT, SL_E_LIMIT, SL_E_NOMEM or SL_E_INTERRUPTED. */
int sl_samples_compute(const sl_samples_config *cfg, const sl_pointset *ps, sl_vdb_samples *out,
                       sl_samples_counts *counts, sl_progress *progress, sl_error *err);

/* A split of the computation into parts (the engine's parts, docs/engine.md: one work
 * item each). The vertices are cut into `parts` runs of whole blocks of the sorted
 * order (sl_samples_part_range); a part evaluates its run only (out is allocated for
 * every vertex; [first, end) is filled, closed_surface and sign_flips are the part's, no
 * sign repair, no inside/outside counts); the join (fill set) makes the vertices, then
 * `fill` puts every part's values in place (and says whether the surface is closed and
 * how many signs the votes flipped), and repairs and counts as the whole pass does: the
 * result is byte-identical to sl_samples_compute. */
typedef struct sl_samples_split {
    int part, parts; /* a part: part in [0, parts) */
    /* NULL for a part; for the join: fills out->distance (and colors) of every vertex */
    int (*fill)(void *ctx, sl_vdb_samples *out, int *closed, uint64_t *flips, sl_error *err);
    void *ctx;
} sl_samples_split;

/* The vertices [*first, *end) of `part` of `parts` among n sorted vertices. */
void sl_samples_part_range(uint64_t n, int part, int parts, uint64_t *first, uint64_t *end);

/* sl_samples_compute for a part or the join of a split (NULL: the whole computation). */
int sl_samples_compute_split(const sl_samples_config *cfg, const sl_pointset *ps,
                             const sl_samples_split *split, sl_vdb_samples *out,
                             sl_samples_counts *counts, sl_progress *progress, sl_error *err);

/* Plain marching cubes over the samples, as a reference for tests and measurements:
 * every cube whose 8 corners are samples is triangulated with the runtime's 256-case
 * table (runtime/mc_cube.h, consistent between face neighbours), one vertex per
 * sign-changing grid edge at the linear zero crossing, triangles facing outwards (from
 * < 0 to >= 0). Coordinates must lie in [0, 2^20 - 1) (SL_E_LIMIT). OUT: *out positions
 * (world) and triangles. Returns 0, SL_E_NOMEM or SL_E_LIMIT. */
int sl_samples_marching_cubes(const sl_vdb_samples *s, sl_mesh *out, sl_error *err);

#endif
