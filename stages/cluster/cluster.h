/* cluster stage and method (paper 2: Hsu, Tseng, Cheng, "Morphing on Clustering-Based
 * Hierarchical Level-of-Detail with Bounded Error"; the passes after Tseng and Cheng,
 * ICS 1998; docs/clustering.md has the design and the proof of the bound).
 *
 * A pass, with tolerance eps (world units):
 *   clustering      faces grow into clusters: a face joins when its normal is within
 *                   max_angle of the cluster's direction n and the cluster's vertices stay
 *                   in a slab of width w <= slab_share * eps across n;
 *   straightening   each border between two corner vertices (where three or more clusters
 *                   or a mesh boundary meet) is simplified by Douglas-Peucker: a vertex
 *                   goes when it lies within sqrt(eps^2 - w^2) of its segment, w the wider
 *                   slab of the border's two clusters;
 *   triangulation   each cluster's straightened polygon (its borders, no interior vertex)
 *                   is triangulated in the cluster's plane (geometry/cdt.h) and lifted
 *                   back to the vertices' own positions.
 * The pass proves its own bound beta = max over clusters of sqrt(w_A^2 + d_A^2) (d_A the
 * largest distance of a removed border vertex of A to its segment) on the symmetric
 * Hausdorff distance between its input and output; passes chain (each takes the previous
 * one's output) and their bounds add up (the triangle inequality).
 *
 * Morphing (paper 2, section 4): between a pass's input M and output M', intermediate
 * model j of m (t = j / (m + 1)) moves every border vertex the fraction t of the way to
 * its projection on its straightened segment, straightens those intermediate borders
 * again (tolerance theta_j (1 - t) d_c for border c, d_c its deviation in M', theta_j the
 * j / (m + 1) quantile of the dropped vertices' offsets / d_c; nested, so that every vertex
 * an intermediate drops stays dropped), and triangulates: the intermediates are simplified
 * too, their triangle counts never rise with j, and each is within the pass's bound.
 *
 * Every level uses a subset of the input's vertices, unmoved (indices into the input, so
 * colours carry over); intermediates have moved border vertices and their own arrays.
 * Open boundaries are borders like the others (straightened within the bound); edges in
 * three or more triangles and non-manifold vertices are corners, kept as they are;
 * SL_CLUSTER_STRICT refuses all three, and triangles with a repeated corner.
 *
 * Parallel over clusters and borders with OpenMP; the result does not depend on the
 * thread count (every decision is ordered by an index, every reduction serial).
 */
#ifndef SCANLOD_STAGES_CLUSTER_H
#define SCANLOD_STAGES_CLUSTER_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "pipeline/stage.h"

#define SL_CLUSTER_MAX_PASSES 16
#define SL_CLUSTER_MAX_INTERMEDIATES 100
#define SL_CLUSTER_MAX_ANGLE 89.0 /* degrees: a cluster must project onto its plane */

/* The resolved [cluster] section (options: stages/cluster/cluster_stage.c). */
typedef struct sl_cluster_config {
    uint32_t passes;        /* clustering passes per level, [1, SL_CLUSTER_MAX_PASSES]; each
                               takes the previous one's output; default 1 */
    uint32_t intermediates; /* stage only: intermediate models between consecutive levels,
                               [0, SL_CLUSTER_MAX_INTERMEDIATES]; default 0 */
    double max_angle;       /* degrees, (0, SL_CLUSTER_MAX_ANGLE]: a face joins a cluster when
                               its normal is within this of the cluster's direction */
    double slab_share;      /* (0, 1]: the share of a pass tolerance eps the clusters' slab
                               width may take (w <= slab_share eps); straightening gets
                               sqrt(eps^2 - w^2) on each border */
    uint32_t search_steps;  /* bisection steps of a triangle budget's search, [1, 64] */
} sl_cluster_config;

/* The section at its option table's defaults (sl_stage_default_config). */
sl_cluster_config sl_cluster_default_config(void);

/* Checks the ranges above; SL_E_USAGE with a message naming the field. */
int sl_cluster_check_config(const sl_cluster_config *cfg, sl_error *err);

enum sl_cluster_flags {
    /* Refuse (SL_E_BADINPUT, one message naming the first one) open boundaries, edges in
     * three or more triangles or in two running the same way, non-manifold vertices, and
     * triangles with a repeated corner, instead of keeping them. */
    SL_CLUSTER_STRICT = 1u << 0
};

/* The mesh to simplify: welded (vertices shared by index), triangles counter-clockwise. */
typedef struct sl_cluster_input {
    uint64_t vertex_count;
    const float *positions;    /* 3 * vertex_count, world */
    uint64_t triangle_count;
    const uint32_t *triangles; /* 3 * triangle_count, < vertex_count */
    double base_bound;         /* world: a bound the input already has to the reference
                                  (a level simplified further: its bound); 0 for a scan */
    double diagonal;           /* world: the reference's bounding-box diagonal, the unit of
                                  every fraction; 0 = that of the vertices `triangles` use */
    uint32_t flags;            /* enum sl_cluster_flags */
} sl_cluster_input;

/* What a level is asked to be: exactly one of max_error and triangles. */
typedef struct sl_cluster_target {
    double max_error;       /* > 0: the level's Hausdorff bound to the reference (base_bound
                               included) at most this fraction of the diagonal, (0, 1] */
    uint64_t triangles;     /* > 0: at most this many triangles, with the smallest bound the
                               search finds (a budget below what max_angle allows is
                               "not reached": the coarsest level found is returned) */
    uint32_t intermediates; /* m intermediate models between the last pass's input and the
                               level, [0, SL_CLUSTER_MAX_INTERMEDIATES] */
} sl_cluster_target;

/* Checks a target: exactly one of max_error (finite, in (0, 1]) and triangles (>= 1), and
 * intermediates in range; SL_E_USAGE naming the value. */
int sl_cluster_check_target(const sl_cluster_target *target, sl_error *err);

/* What one pass saw and did. Distances in world units. */
typedef struct sl_cluster_pass_stats {
    double tolerance;         /* eps: the pass's share of the bound */
    double bound;             /* beta: the proven bound on the pass's Hausdorff distance */
    double max_slab;          /* largest cluster slab width w_A */
    double max_deviation;     /* largest distance of a removed border vertex to its segment */
    uint32_t clusters;
    uint32_t clusters_kept;   /* left with their input triangles (their polygon would not
                                 triangulate even unstraightened) */
    uint64_t corners;         /* corner vertices (never removed) */
    uint64_t borders;         /* borders between corners */
    uint64_t borders_reverted; /* straightening undone because a polygon would not triangulate */
    uint64_t forced_splits;   /* segments split to keep polygons and edges distinct */
    uint64_t triangulation_failures; /* polygons the triangulation refused (then retried) */
    uint32_t regrowths;       /* clusterings redone with a smaller angle where a cluster's
                                 own polygon folded in projection */
    uint64_t removed_interior; /* vertices inside clusters, gone */
    uint64_t removed_border;   /* border vertices gone by straightening */
    uint64_t triangles_in, triangles_out;
} sl_cluster_pass_stats;

/* An intermediate model: its own vertices (border vertices moved). */
typedef struct sl_cluster_intermediate {
    uint64_t vertex_count;
    float *positions;         /* 3 * vertex_count, world */
    uint32_t *source;         /* vertex_count: the input vertex each is (or was moved from) */
    uint64_t triangle_count;
    uint32_t *triangles;      /* 3 * triangle_count, into positions */
    double bound;             /* world: Hausdorff bound to the reference (<= the level's) */
} sl_cluster_intermediate;

typedef struct sl_cluster_level {
    uint64_t triangle_count;
    uint32_t *triangles;      /* 3 * triangle_count, into the input's vertices */
    double bound;             /* world: Hausdorff bound to the reference: base_bound + the
                                 passes' bounds */
    double bound_fraction;    /* bound / diagonal */
    double diagonal;          /* world: the unit of the fractions */
    int reached;              /* the target was met */
    uint32_t search_steps;    /* passes-sets run by a budget's search (0 for max_error) */
    uint32_t pass_count;
    sl_cluster_pass_stats pass[SL_CLUSTER_MAX_PASSES];
    uint32_t intermediate_count;
    sl_cluster_intermediate *intermediates; /* from the last pass's input (j = 1) to the
                                               level (j = m) */
    /* What the input held (kept, or in strict mode refused). */
    uint64_t boundary_edges, nonmanifold_edges, nonmanifold_vertices, degenerate_triangles;
} sl_cluster_level;

/* Simplifies `in` to `target` with `cfg`. OUT: *level (release with
 * sl_cluster_level_release; zeroed on failure). A target the input already meets (a
 * budget >= its triangles, a bound it cannot spend because base_bound uses it) returns
 * the input's triangles unchanged. Returns 0, SL_E_USAGE (config or target), SL_E_BADINPUT
 * (no triangle, an index out of range, a non-finite coordinate, a zero-size bounding box;
 * in strict mode the topology above), SL_E_LIMIT (more than 2^31 triangles), SL_E_NOMEM,
 * SL_E_INTERRUPTED, SL_E_INTERNAL (a check of the result failed: a bug). */
int sl_cluster_simplify(const sl_cluster_config *cfg, const sl_cluster_input *in,
                        const sl_cluster_target *target, sl_cluster_level *level,
                        sl_progress *progress, sl_error *err);

void sl_cluster_level_release(sl_cluster_level *level);

/* --- the stage ([lod] method = cluster) ----------------------------------------------- *
 * Reads the range stage's welded mesh, builds a level per rung of the ladder ([levels]: a
 * share P % = at most P % of the input's triangles), each from the next finer one, and
 * writes them with their bounds (and [cluster] intermediates models between consecutive
 * levels) as a level list (levels/level.h); docs/formats.md has the format. */

extern const sl_stage sl_cluster_stage;

#endif
