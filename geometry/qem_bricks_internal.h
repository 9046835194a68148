/* Quadric edge collapse by bricks: what its files share (qem_simplify.h's
 * sl_qem_simplify_bricked; docs/simplify.md "By bricks"). qem_bricks_cut.c cuts a pass's
 * bricks and finds what each must lock; qem_bricks_run.c simplifies the bricks in parallel,
 * shares the count out by error and joins them; qem_bricked.c runs the passes. Not a
 * public header. */
#ifndef SCANLOD_GEOMETRY_QEM_BRICKS_INTERNAL_H
#define SCANLOD_GEOMETRY_QEM_BRICKS_INTERNAL_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/qem_simplify.h"

/* One pass's bricks: triangle indices in brick order, brick b = order[first[b] ..
 * first[b + 1]). */
typedef struct brick_cut {
    uint32_t *order;
    uint64_t *first;
    uint64_t count;
} brick_cut;

void qem_brick_cut_release(brick_cut *c);

/* What locks a vertex in a pass (bits of qem_brick_locks' array). */
enum {
    LOCK_CALLER = 1,  /* the caller's */
    LOCK_BORDER = 2,  /* its position is used by triangles of two bricks */
    LOCK_OUTSIDE = 4, /* ... by a brick's and a triangle the pass leaves alone */
    LOCK_RING = 8     /* shares a triangle with such a point (qem_bricks_cut.c) */
};

enum brick_task {
    TASK_NONE = 0,       /* nothing (this round) */
    TASK_CURVE,          /* a run to `want` recording its error curve */
    TASK_FINAL           /* the run to `want`, or to `max_error` first when that is set */
};

typedef struct brick_result {
    int task;            /* enum brick_task, this round */
    uint64_t want;       /* the count the run stops at */
    double max_error;    /* ... or the error it stops before (0: none) */
    float *curve;        /* the curve run's error_curve, triangles + 1 entries */
    uint64_t triangles;  /* the brick's */
    uint64_t share;      /* its share of the pass's count, in proportion to its triangles */
    uint64_t reached;    /* the curve run's count */
    sl_qem_mesh mesh;
    sl_qem_stats stats;
    int rc;
    sl_error err;
} brick_result;

/* --- qem_bricks_cut.c --------------------------------------------------------------- */

/* The box of the corners of m's triangles. */
void qem_mesh_box(const sl_qem_mesh *m, double lo[3], double hi[3]);
/* Bricks of at most `brick_triangles` of the `active` triangles (NULL: all), consecutive
 * in the Morton order of their centroids on a grid shifted by `shift` of a brick's cell.
 * -1 when out of memory. */
int qem_cut_bricks(const sl_qem_mesh *m, const uint8_t *active, uint64_t brick_triangles,
                   double shift, brick_cut *out);
/* Per vertex, the LOCK_ bits of the cut (and the caller's `locked`); *border_triangles:
 * the active triangles with a corner on a border or its ring. NULL when out of memory. */
uint8_t *qem_brick_locks(const sl_qem_mesh *m, const brick_cut *cut, const uint8_t *active,
                         const uint8_t *locked, uint64_t *border_triangles);
/* The triangles within STRIP_RINGS rings of the marked vertices and enough more to hold
 * STRIP_ROOM times `excess`; *count of them. NULL when out of memory. */
uint8_t *qem_brick_strip(const sl_qem_mesh *m, const uint8_t *marked, uint64_t excess,
                         uint64_t *count);

/* --- qem_bricks_run.c --------------------------------------------------------------- */

/* Each brick's task in parallel (round 0 or 1 of the pass, for the progress); 0, or the
 * first error in brick order. */
int qem_run_bricks(const sl_qem_mesh *m, const brick_cut *cut, const uint8_t *locked,
                   const sl_qem_config *cfg, brick_result *r, int round, sl_progress *progress,
                   sl_error *err);
/* The fewest triangles brick r has after collapses of error at most e (its curve). */
uint64_t qem_count_within(const brick_result *r, double e);
/* Every brick's count from all their curves, together exactly `target` where they reach. */
void qem_share_by_error(brick_result *r, uint64_t bricks, uint64_t target);
/* The error that brings every `stride`-th brick's curve, scaled to all, to `target`. */
double qem_sampled_error(const brick_result *r, uint64_t bricks, uint64_t stride,
                         uint64_t target);
/* The bricks' meshes and the triangles left alone joined; `source` names m's vertices. */
int qem_stitch_bricks(const sl_qem_mesh *m, const uint8_t *active, brick_result *r,
                      uint64_t bricks, sl_qem_mesh *out, sl_error *err);

#endif
