/* Surface fit: move the vertices of a simplified level (connectivity fixed) so that its
 * surface approaches the input it approximates, in the least-squares sense of Hoppe,
 * DeRose, Duchamp, McDonald and Stuetzle, "Mesh optimization", SIGGRAPH 1993, section 4.2
 * ("optimization over V for fixed K"). docs/surface-fit.md has the method and figures.
 *
 * The energy is the one scanlod measures (geometry/mesh_distance.h), the symmetric
 * area-sampled squared distance, as the sum of both directions' means:
 *   E(V) = (1/N) sum_i |p_i - L_i(V)|^2        input samples p_i -> level
 *        + sum_j w_j |q_j - L_j(V)|^2          level samples -> input (w_j: area weights)
 *        + border terms (open inputs) + spring (smoothness of the displacement)
 * where L(V) is a barycentric combination of one level triangle's corners: the closest
 * point of p_i on the level (input -> level) or a fixed barycentric sample of the level
 * (level -> input), and q_j the closest point of that sample on the input. Each round
 * (a) projects every sample, then (b) solves the linear least-squares problem in V by
 * conjugate gradients on the sparse normal equations (one matrix, three right-hand
 * sides), its step extrapolated by Anderson acceleration. Guards halve the step of each
 * vertex whose move flips a triangle or makes a sliver; vertices on the level's open
 * border are snapped onto the input's. The best state seen (by the fit's own symmetric
 * RMS estimate) is returned: never worse than the start.
 *
 * A point-set input has no surface to project the level onto: only its points are
 * pulled to the level (Hoppe's original E_dist), as `scanlod compare` measures it.
 *
 * Determinism: bit-identical output for any OpenMP thread count (fixed chunks, reductions
 * in chunk order, CG dot products in a fixed order).
 * Thread safety: a built reference is read-only; fits of different levels against one
 * reference may run concurrently. Each call runs its own OpenMP parallel regions.
 * Memory: the reference holds the input's BVH (about 56 bytes per input triangle) and
 * 12 bytes per sample drawn; a fit about 32 bytes per input sample it uses, 48 per level
 * sample and 460 per level triangle (docs/surface-fit.md, "Cost").
 */
#ifndef SCANLOD_GEOMETRY_SURFACE_FIT_H
#define SCANLOD_GEOMETRY_SURFACE_FIT_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/mesh.h"

#define SL_FIT_MAX_SAMPLES (1ull << 31)   /* any sample count, SL_E_LIMIT above */
#define SL_FIT_MAX_ITERATIONS 100

typedef struct sl_fit_config {
    /* --- the reference (sl_fit_reference_build) ------------------------------------- */
    uint64_t samples;        /* area samples drawn on the input; 0 = automatic: 4 per input
                                triangle, at least 100 k, at most 4 M. A point set uses its
                                points instead. */
    uint64_t seed;           /* their positions (default 0x5f17: not `compare`'s seed 1, so
                                a fit is never judged on the samples it was fitted to) */
    const struct sl_triangle_bvh *surface_tree; /* NULL, or a tree sl_triangle_bvh_build
                                made over this input's triangles (sl_distance_reference_tree),
                                borrowed for the reference's life instead of a second one
                                (56 bytes per input triangle) */
    /* --- each fit (sl_surface_fit) --------------------------------------------------- */
    uint32_t input_per_triangle; /* input samples used per level triangle (default 8, at
                                    least 100 k, at most all of the reference's) */
    uint32_t level_per_triangle; /* level samples per level triangle (default 4, at least
                                    100 k or the reference's sample count if smaller) */
    int iterations;          /* projection + solve rounds (default 8, at most 100) */
    double spring;           /* displacement smoothness per edge, relative to the mean
                                data weight of a vertex (default 0.01; >= 0) */
    double border_weight;    /* the border terms against the surface terms (default 1) */
    const uint8_t *locked;   /* NULL, or per level vertex: nonzero = never moved */
} sl_fit_config;

sl_fit_config sl_fit_default_config(void);

/* What a fit did. RMS figures are the fit's own estimate, in world units: the symmetric
 * figure (the worse direction) from its samples, as mesh_distance.h defines it. */
typedef struct sl_fit_stats {
    double rms_before;            /* symmetric RMS of the level as given */
    double rms_after;             /* ... of the level returned (<= rms_before) */
    double rms_input_to_level;    /* the two directions of rms_after (level -> input is 0 */
    double rms_level_to_input;    /*   for a point-set input: not measured) */
    double diagonal;              /* the input's bounding-box diagonal, world */
    int iterations;               /* rounds run */
    int best_iteration;           /* the round whose result was returned; 0 = the start */
    uint64_t vertices_moved;      /* level vertices whose position changed */
    uint64_t vertices_backtracked;/* vertex steps a guard shortened, summed over rounds */
    uint64_t cg_iterations;       /* summed over rounds */
    uint64_t input_samples, level_samples, border_samples; /* used per round */
    uint64_t border_vertices;     /* on the level's open border (kept on the input's) */
    uint64_t fixed_vertices;      /* not moved: locked, or on a fin (welded vertices) */
} sl_fit_stats;

/* A prepared input: its BVH, area samples and border, reusable by every level of one
 * item. Built from a triangle mesh (sl_mesh_check_surface's precondition) or a point set
 * (no triangles, at least one point, all finite). Only the config's `samples` and `seed`
 * are read (NULL: defaults). The mesh may be freed afterwards. Fails with SL_E_BADINPUT
 * (the cause in the message), SL_E_LIMIT (more than (2^32 - 2) / 3 triangles, more than
 * SL_FIT_MAX_SAMPLES samples or points), SL_E_NOMEM. */
typedef struct sl_fit_reference sl_fit_reference;
int sl_fit_reference_build(const sl_mesh *input, const sl_fit_config *cfg,
                           sl_fit_reference **out /* OUT */, sl_error *err);
void sl_fit_reference_free(sl_fit_reference *ref); /* NULL is fine */

/* Fits the level (`positions`: 3 floats per vertex, IN/OUT; `triangles`: 3 indices each)
 * to `ref`. Vertices at bit-identical positions are moved as one (seams stay closed);
 * vertices no triangle uses, `cfg->locked` ones and the corners of two triangles on the
 * same three vertices (a double-sided fin has no side to be pulled to) stay where they
 * are. On any failure `positions` is left as given. `stats` and `progress` may be NULL.
 * Fails with SL_E_BADINPUT (no triangles, an index out of range, a non-finite
 * coordinate, zero area), SL_E_LIMIT (2^32 - 1 or more vertices, (2^32 - 2) / 3 or more
 * triangles), SL_E_USAGE (a config field out of range), SL_E_NOMEM, SL_E_INTERRUPTED. */
int sl_surface_fit(const sl_fit_reference *ref, float *positions /* IN/OUT */,
                   uint64_t vertex_count, const uint32_t *triangles, uint64_t triangle_count,
                   const sl_fit_config *cfg, sl_fit_stats *stats /* OUT */,
                   sl_progress *progress, sl_error *err);

#endif
