/* Surface-to-surface distance between two triangle meshes, and edge topology.
 *
 * Method (docs/fidelity.md): each mesh is sampled uniformly by area -- a fixed sample
 * budget is spread over the triangles in proportion to their area (stratified: the
 * counts are the rounded differences of the cumulative area, so they add up exactly),
 * with positions inside each triangle drawn from a counter-based hash of (seed,
 * triangle, sample) -- plus every vertex that a triangle uses. For each sample the
 * exact closest point on the other mesh is found through a BVH (geometry/triangle_bvh.h).
 * One-sided figures A->B come from A's samples against B's surface, B->A the reverse.
 *
 *   hausdorff  max over area samples and vertices (vertices catch spikes)
 *   mean, rms  over the area samples only, so they estimate the area-weighted integrals
 *              (1/|A|) int_A d and sqrt((1/|A|) int_A d^2) however the vertices are spread
 *
 * Symmetric figures are the worse of the two directions. Distances are in world units
 * and again as fractions of A's bounding-box diagonal (the box of the vertices that A's
 * triangles use), so 0.01 means 1% of the diagonal.
 *
 * Determinism: the samples and their per-chunk reductions depend only on the inputs, the
 * seed and fixed chunk sizes; partial results are combined in chunk order, so every
 * figure is bit-identical for any OpenMP thread count.
 *
 * Thread safety: reentrant; runs its own OpenMP parallel regions.
 */
#ifndef SCANLOD_GEOMETRY_MESH_DISTANCE_H
#define SCANLOD_GEOMETRY_MESH_DISTANCE_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/mesh.h"

#define SL_MESH_DISTANCE_DEFAULT_SAMPLES 1000000u

typedef struct sl_mesh_distance_config {
    uint64_t samples; /* area samples on each mesh (vertices come on top); >= 1;
                         default SL_MESH_DISTANCE_DEFAULT_SAMPLES */
    uint64_t seed;    /* sample positions inside triangles; default 1 */
} sl_mesh_distance_config;

sl_mesh_distance_config sl_mesh_distance_default_config(void);

/* Distances from the samples of one mesh to the surface of the other. */
typedef struct sl_distance_figures {
    double hausdorff;          /* max distance */
    double mean;               /* mean over area samples */
    double rms;                /* root mean square over area samples */
} sl_distance_figures;

typedef struct sl_distance_side {
    sl_distance_figures world;     /* world units */
    sl_distance_figures fraction;  /* world / A's diagonal */
    uint64_t area_samples;         /* samples drawn on triangles */
    uint64_t vertex_samples;       /* vertices used by a triangle */
} sl_distance_side;

typedef struct sl_mesh_distance {
    double diagonal;               /* A's bounding-box diagonal, world */
    int a_is_points;               /* A had no triangles: a_to_b is from its points (mean
                                      and rms over them), b_to_a is not measured (0), and
                                      the symmetric figures are a_to_b's */
    sl_distance_side a_to_b, b_to_a;
    sl_distance_figures world;     /* symmetric: each figure the max of both sides */
    sl_distance_figures fraction;  /* the same / diagonal */
} sl_mesh_distance;

/* Edge topology after welding vertices at exactly equal positions (-0 equals +0). */
typedef struct sl_mesh_topology {
    uint64_t welded_vertices;      /* distinct positions used by a triangle */
    uint64_t degenerate_triangles; /* two corners at one position; left out of the edges */
    uint64_t edges;                /* distinct undirected edges */
    uint64_t boundary_edges;       /* in exactly one triangle */
    uint64_t nonmanifold_edges;    /* in three or more triangles */
    int watertight;                /* every edge in exactly two triangles (and >= 1 edge) */
    uint64_t components;           /* parts connected through shared welded vertices
                                      (degenerate triangles left out) */
    double area;                   /* total area of the non-degenerate triangles */
    double largest_component_area; /* area of the part with the most of it; a thumbnail
                                      that holds together has nearly all of `area` here */
} sl_mesh_topology;

/* Distances between the surfaces of `a` and `b`. Both need at least one triangle of
 * nonzero area and finite coordinates at every vertex a triangle uses, else
 * SL_E_BADINPUT with a message naming the mesh ("A" or "B") and the cause -- except that
 * A may be a point cloud (no triangles, at least one point, all finite): then only its
 * points' distances to B are measured (out->a_is_points); `cfg` may be
 * NULL for the defaults; `progress` (may be NULL) is polled for an interrupt
 * (SL_E_INTERRUPTED). Also fails with SL_E_NOMEM, SL_E_LIMIT (> 2^32 - 1 triangles). */
int sl_mesh_distance_compute(const sl_mesh *a, const sl_mesh *b,
                             const sl_mesh_distance_config *cfg,
                             sl_mesh_distance *out /* OUT */, sl_progress *progress,
                             sl_error *err);

/* One A measured against many B (a search over candidate levels of one input): A's
 * checks, tree and area samples made once. sl_distance_reference_compute with `vertices`
 * gives every figure bit-identical to sl_mesh_distance_compute(A, B) with the same config
 * (the same samples, the same chunks summed in the same order); without, the vertex
 * samples are left out (they only raise the Hausdorff distance: its figure is then over
 * the area samples alone, and the cost is bounded by the samples and B's tree, not A's
 * vertices). sl_distance_reference_rms gives only the symmetric RMS as a fraction of A's
 * diagonal (no vertex samples). A must have triangles (not a point cloud). Errors as for
 * sl_mesh_distance_compute. The reference is read-only once built: reentrant. */
typedef struct sl_distance_reference sl_distance_reference;
int sl_distance_reference_build(const sl_mesh *a, const sl_mesh_distance_config *cfg,
                                sl_distance_reference **out /* OUT */, sl_error *err);
int sl_distance_reference_rms(const sl_distance_reference *ref, const sl_mesh *b,
                              double *rms /* OUT */, sl_progress *progress, sl_error *err);
int sl_distance_reference_compute(const sl_distance_reference *ref, const sl_mesh *b,
                                  int vertices, sl_mesh_distance *out /* OUT */,
                                  sl_progress *progress, sl_error *err);
void sl_distance_reference_free(sl_distance_reference *ref);
/* A's tree inside the reference (read-only, valid until it is freed): for another user of a
 * tree over A (geometry/surface_fit.h, `surface_tree`). */
const struct sl_triangle_bvh *sl_distance_reference_tree(const sl_distance_reference *ref);

/* The area samples that sl_mesh_distance_compute draws on a mesh (the same stratified
 * counts per triangle, the same positions for the same seed), as records for a caller
 * that needs to know where each one lies (geometry/surface_fit.h): in triangle order,
 * a sample at b * corner 1 + c * corner 2 + (1 - b - c) * corner 0 of `triangle`. */
typedef struct sl_area_sample {
    uint32_t triangle; /* index in the mesh */
    float b, c;        /* barycentric weights of corners 1 and 2 */
} sl_area_sample;
/* Room `out` needs for `samples` (the per-chunk rounding may give a few more). */
uint64_t sl_mesh_area_samples_bound(const sl_mesh *m, uint64_t samples);
/* Draws `samples` (>= 1) area samples of `m` into `out` (sl_mesh_area_samples_bound
 * entries); OUT: *count, at most the bound. `m` must pass sl_mesh_check_surface. Serial
 * (the positions come from a counter-based hash, the order is the triangles'). Fails
 * only with SL_E_NOMEM. */
int sl_mesh_area_samples(const sl_mesh *m, uint64_t samples, uint64_t seed,
                         sl_area_sample *out /* OUT */, uint64_t *count /* OUT */,
                         sl_error *err);

/* The precondition above: at least one triangle, indices in range, finite coordinates
 * at every vertex a triangle uses, a nonzero total area. Otherwise SL_E_BADINPUT with
 * the cause as message and `file` (may be NULL) as the error's file; SL_E_NOMEM. */
int sl_mesh_check_surface(const sl_mesh *m, const char *file, sl_error *err);

/* Edge topology of `m` (any triangle mesh; NaN positions weld only with bit-identical
 * NaNs). Fails only with SL_E_NOMEM or SL_E_LIMIT (> 2^32 - 1 vertices). */
int sl_mesh_topology_compute(const sl_mesh *m, sl_mesh_topology *out /* OUT */, sl_error *err);

/* Welds the vertices that a triangle uses by exactly equal position (-0 equals +0; NaNs
 * only when bit-identical): weld[v] (the caller's array of vertex_count entries) = a dense
 * id, numbered in order of each position's first vertex, or UINT32_MAX for a vertex no
 * triangle uses. Indices must be in range. Returns the number of ids, or -1 when out of
 * memory. */
int64_t sl_mesh_weld_positions(const sl_mesh *m, uint32_t *weld /* OUT */);

/* The connected parts of `m` (through shared welded positions, as `components` above,
 * degenerate triangles joined to the part they touch): part_of_triangle[t] (the caller's
 * array of triangle_count entries) numbers them in order of their first triangle;
 * *part_area (freed by the caller) holds each one's area. Indices must be in range.
 * Fails only with SL_E_NOMEM or SL_E_LIMIT. */
int sl_mesh_parts(const sl_mesh *m, uint32_t *part_of_triangle /* OUT */,
                  double **part_area /* OUT */, uint64_t *part_count /* OUT */, sl_error *err);

#endif
