/* Quadric edge-collapse simplification: Garland and Heckbert, "Surface simplification
 * using quadric error metrics", SIGGRAPH 1997 (area-weighted face quadrics, the optimal
 * position of a collapse, a greedy priority queue), with the topology and attribute rules
 * of meshoptimizer's simplifier and Hoppe, "New quadric metric for simplifying meshes
 * with appearance attributes", 1999 (per-corner attribute fields). docs/simplify.md has
 * the method, the choices and the measured figures.
 *
 * Vertices are welded by exact position; an attribute seam is two or more input vertices
 * ("wedges") at one position, and stays a seam: a seam point only collapses along its
 * seam. Every collapse keeps the topology: the link condition (Dey et al. 1999) with the
 * open borders closed by a virtual vertex, so no edge gets a third triangle, no handle,
 * hole or component is closed, merged or split; a closed input stays closed. Borders
 * collapse only along themselves; no triangle turns over or becomes a needle.
 * Non-manifold input (edges in 3+ triangles, two fans at a vertex, orientations that
 * disagree) is not refused: its vertices are locked.
 *
 * Relaxed rules (cfg.allow_topology_change, qem_relax.c), for a budget the topology
 * alone puts out of reach: the non-manifold points are freed, the link condition is not
 * asked (a hole, a handle or a small component may close; an edge may get a third
 * triangle), a border point may move across or into the interior. Still no triangle turns
 * over, none repeats a point (triangles laid onto one another are removed), the caller's
 * locks and the seams hold, and it never lands more than 1 % below the target. They apply
 * from the first collapse, or only once the strict ones run dry (a last phase).
 *
 * Determinism: the output bytes depend only on the input and the config, not on the
 * OpenMP thread count (the parallel set-up sums in a fixed order; the queue breaks ties
 * by vertex index).
 * Thread safety: reentrant; runs its own OpenMP loops for the set-up.
 * Cost: O(n log n), about 1.3-2.2 s per million input triangles on one thread and 180
 * bytes per input triangle at the peak (docs/simplify.md has the measurements).
 */
#ifndef SCANLOD_GEOMETRY_QEM_SIMPLIFY_H
#define SCANLOD_GEOMETRY_QEM_SIMPLIFY_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"

/* Input: borrowed arrays. Output: malloc'd arrays, released by sl_qem_mesh_release. */
typedef struct sl_qem_mesh {
    uint64_t vertex_count;
    float *positions;   /* 3 per vertex, world */
    uint8_t *colors;    /* 4 per vertex RGBA, or NULL */
    float *texcoords;   /* 2 per vertex (u, v), or NULL; a seam is distinct vertices at one
                           position */
    uint64_t triangle_count;
    uint32_t *triangles; /* 3 per triangle, counter-clockwise */
    uint32_t *source;   /* output only: per vertex, the input vertex it descends from (its
                           normal, its other attributes); NULL in an input */
} sl_qem_mesh;

typedef struct sl_qem_config {
    uint64_t target_triangles; /* stop at this many (a last interior collapse may land one
                                  below); default 0: as far as the topology allows */
    double max_error;          /* also stop before a collapse whose error (the RMS distance
                                  from the new vertex to its merged planes) exceeds this,
                                  in world units; 0 = no such stop (default) */
    int optimal_placement;     /* 1 (default): the quadric's minimiser, regularised towards
                                  the edge's midpoint; 0: the better endpoint, so every
                                  output vertex is an input vertex (positions and
                                  attributes exact, `source` exact) */
    double border_weight;      /* weight of the planes through open border edges (and,
                                  halved, attribute seams), perpendicular to their
                                  triangle, against the surface's own planes; default 10 */
    double attribute_weight;   /* a full-range change of colour (0..255) or of a texture
                                  coordinate (1) costs as much as moving that area by this
                                  fraction of the bounding-box diagonal; default 0.02 */
    const uint8_t *locked;     /* NULL, or per input vertex: nonzero = never moved or
                                  removed (brick borders); its position's other wedges too */
    int allow_topology_change; /* enum sl_qem_topology; default SL_QEM_TOPOLOGY_KEEP */
    double diagonal;           /* the bounding-box diagonal the attribute weight and the
                                  queue's keys are scaled by, world; 0 (default) = the
                                  input's own (a brick of a larger mesh gives the whole's,
                                  so its costs compare with its neighbours') */
    float *error_curve;        /* NULL, or room for the input's triangle count + 1 entries:
                                  entry c set to the largest collapse error (world) made
                                  before the live triangles first fell to c or below, for
                                  c from the input's count down to the output's (the
                                  others left as they were; non-increasing in c): what a
                                  brick tells its pass (qem_bricked.c) */
} sl_qem_config;

/* What the collapses may do to the topology (the relaxed rules above). */
enum sl_qem_topology {
    SL_QEM_TOPOLOGY_KEEP = 0,   /* never change it */
    SL_QEM_TOPOLOGY_RELAX_LAST, /* keep it until no such collapse is left above the target,
                                   then the relaxed rules for the rest of the way */
    SL_QEM_TOPOLOGY_RELAX       /* the relaxed rules from the first collapse: the greedy
                                   order decides which handles, holes and specks go first
                                   (what a caller whose strict run stopped above the target
                                   does again: docs/simplify.md measures both) */
};

enum sl_qem_stop {
    SL_QEM_STOP_TARGET = 0,    /* reached target_triangles */
    SL_QEM_STOP_MAX_ERROR,     /* the next collapse would exceed max_error */
    SL_QEM_STOP_TOPOLOGY       /* no legal collapse is left (each would break a rule above;
                                  with allow_topology_change, a rule of the relaxed phase) */
};

typedef struct sl_qem_stats {
    uint64_t input_triangles;
    uint64_t degenerate_triangles; /* two corners at one position: dropped */
    uint64_t points;               /* welded positions used by a triangle */
    uint64_t seam_points;          /* of them, with two or more wedges */
    uint64_t border_points;        /* on an open border */
    uint64_t locked_points;        /* by cfg->locked or non-manifold input */
    uint64_t nonmanifold_points;   /* on an edge of 3+ triangles, two fans, or an edge two
                                      triangles run the same way: locked */
    uint64_t collapses;
    uint64_t relaxed_collapses;    /* of them, ones the strict rules refuse (0: topology kept) */
    uint64_t cancelled_triangles;  /* removed by the relaxed rules as laid onto another */
    uint64_t queued;               /* entries pushed on the queue (initial edges included) */
    uint64_t rejected_topology;    /* link condition, border or seam rule */
    uint64_t rejected_flip;        /* a triangle would turn over */
    uint64_t rejected_shape;       /* a triangle would become a needle or sliver */
    uint64_t output_triangles, output_vertices;
    int stop;                      /* enum sl_qem_stop */
    double last_error;             /* world: the error of the last collapse made */
} sl_qem_stats;

sl_qem_config sl_qem_default_config(void);

/* Simplifies `in` to cfg->target_triangles (cfg NULL = the defaults). On success *out
 * holds new arrays (colours and texcoords when the input has them, `source` always;
 * vertices in the order of the input vertices they descend from, triangles in input
 * order); release with sl_qem_mesh_release. `stats` and `progress` may be NULL.
 * Returns 0; SL_E_BADINPUT (an index out of range, a non-finite coordinate at a used
 * vertex, a config out of range), SL_E_LIMIT (more than 2^32 - 2 vertices or
 * SL_ADJACENCY_MAX_TRIANGLES triangles), SL_E_NOMEM, SL_E_INTERRUPTED. An empty mesh
 * gives an empty mesh. On failure *out is zeroed. */
int sl_qem_simplify(const sl_qem_mesh *in, const sl_qem_config *cfg,
                    sl_qem_mesh *out /* OUT */, sl_qem_stats *stats /* OUT */,
                    sl_progress *progress, sl_error *err);

/* The same by bricks (qem_bricked.c; docs/simplify.md "By bricks"), for a mesh too large
 * to simplify whole in memory or on one thread: bricks of at most `brick_triangles`
 * triangles, consecutive in the Morton order of their centroids, each simplified alone and
 * in parallel (OpenMP) with the points it shares with another brick and the ring around
 * them locked, all stopping at one collapse error (a sample of the bricks' error curves
 * brings the count there);
 * then passes on strips around the borders, cut into bricks elsewhere; once the mesh fits
 * one brick, sl_qem_simplify on the whole. Peak memory: about 180 bytes per triangle of a
 * brick per thread, plus the passes' meshes. RMS within about 20 % of the whole's, often
 * closer; a count within 1 % below, as the relaxed rules allow (docs/simplify.md). Output
 * as sl_qem_simplify's (vertices in the order of the
 * input vertices they descend from; triangles brick by brick); stats summed over bricks
 * and passes, `stop` that of the whole. brick_triangles 0, or at least the input's:
 * exactly sl_qem_simplify. Same errors. */
int sl_qem_simplify_bricked(const sl_qem_mesh *in, const sl_qem_config *cfg,
                            uint64_t brick_triangles, sl_qem_mesh *out /* OUT */,
                            sl_qem_stats *stats /* OUT */, sl_progress *progress,
                            sl_error *err);

void sl_qem_mesh_release(sl_qem_mesh *m); /* frees every array and zeroes *m */

#endif
