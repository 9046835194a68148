/* The surface fit's parts (geometry/surface_fit.h; docs/surface-fit.md):
 *
 *   surface_fit_reference.c  the input: validation, BVH, area samples, open border
 *   surface_fit_level.c      the level: welding, edges, border, matrix pattern, samples
 *   surface_fit_project.c    step (a): every sample's closest point, as a term
 *   surface_fit_solve.c      step (b): per-triangle sums, normal equations, CG
 *   surface_fit_guard.c      the guards and the per-vertex step halving
 *   surface_fit.c            the rounds, the keep-the-best rule, the API
 *
 * Every piece of the energy is a *term*: a weight, a point L = sum_k w_k V_k of one level
 * triangle (its corners' barycentric weights) and the residual r = target - L at the
 * current positions. Minimising sum weight |r - sum_k w_k D_k|^2 over the displacements
 * D is the same linear least-squares problem for every kind of sample, so one
 * accumulation serves them all.
 */
#ifndef SCANLOD_GEOMETRY_SURFACE_FIT_INTERNAL_H
#define SCANLOD_GEOMETRY_SURFACE_FIT_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/mesh_distance.h"
#include "geometry/surface_fit.h"
#include "geometry/triangle_bvh.h"

#define FIT_CHUNK 4096          /* samples or rows per work chunk (not per thread) */
#define FIT_BORDER_PER_EDGE 4   /* samples along each open edge of the level */

struct sl_fit_reference {
    int is_points;             /* a point set: no surface, no border */
    uint64_t sample_count;
    float *samples;            /* 3 per sample: area samples in triangle order, or the
                                  points */
    const sl_triangle_bvh *surface; /* the input's triangles: own_surface or the config's
                                       surface_tree (empty for a point set) */
    sl_triangle_bvh own_surface;
    sl_triangle_bvh border;    /* its open edges as triangles (a, b, b): the BVH's closest
                                  point of a degenerate triangle is on its longest edge */
    uint64_t border_sample_count;
    float *border_samples;     /* 3 per sample, evenly spaced along the open edges */
    double diagonal;           /* bounding box of the input, world */
};

/* One piece of the energy (see the file comment). */
typedef struct fit_term {
    uint32_t triangle;   /* level triangle */
    float w[3];          /* barycentric weights of its corners */
    float r[3];          /* target - L at the current positions, world */
    float weight;        /* > 0; 0 = no term (a sample that found nothing) */
} fit_term;

/* The level, welded: vertices at bit-identical positions are one unknown. */
typedef struct fit_level {
    uint32_t vertex_count;     /* welded vertices */
    uint32_t triangle_count;
    uint32_t *group;           /* per given vertex: its welded vertex, UINT32_MAX unused */
    uint32_t *tri;             /* 3 per triangle, welded indices */
    float *pos;                /* 3 per welded vertex: current positions */
    float *start;              /* 3 per welded vertex: as given */
    uint8_t *fixed;            /* per welded vertex: locked, or on a fin: never moved */
    uint8_t *border;           /* per welded vertex: on an open edge */
    uint32_t *corner_start;    /* vertex_count + 1: each vertex's corners in `corners` */
    uint32_t *corners;         /* 3 * triangle_count corner ids 3 t + k, by vertex, t */
    uint32_t *row_start;       /* vertex_count + 1: the matrix's rows (CSR) */
    uint32_t *col;             /* its columns: the vertex and its neighbours, ascending */
    uint32_t border_edge_count;
    uint32_t *border_edges;    /* per open edge: the corner id 3 t + k it starts at */
    float *start_normal;       /* 3 per triangle: (b - a) x (c - a) as given */
    float *start_quality;      /* per triangle: compactness as given (fit_quality) */
    uint64_t sample_count;     /* level samples, fixed barycentrics for the whole fit */
    sl_area_sample *samples;
    uint32_t *per_triangle;    /* samples on each triangle */
} fit_level;

/* What one projection pass measured: mean squared distances, world^2. */
typedef struct fit_measure {
    double input_to_level;
    double level_to_input;     /* 0 for a point-set input */
} fit_measure;

/* The corner after corner id c = 3 t + k in its triangle. */
static inline uint32_t fit_next_corner(uint32_t c)
{
    return c % 3u == 2u ? c - 2u : c + 1u;
}

/* --- surface_fit_level.c --- */
/* The open edges of welded triangles (in exactly one triangle that is not degenerate),
 * each as the corner id 3 t + k it starts at (the edge runs to the next corner), sorted by
 * their vertex pair; every index below vertex_count. OUT: *open (free it; NULL when
 * none), *count. */
int fit_open_edges(const uint32_t *tri, uint64_t triangle_count, uint32_t vertex_count,
                   uint32_t **open, uint64_t *count, sl_error *err);
int fit_level_build(fit_level *lv, const float *positions, uint64_t vertex_count,
                    const uint32_t *triangles, uint64_t triangle_count, const uint8_t *locked,
                    sl_error *err);
int fit_level_samples(fit_level *lv, uint64_t count, uint64_t seed, sl_error *err);
void fit_level_release(fit_level *lv);
/* Compactness 4 sqrt(3) area / (sum of squared edges): 1 equilateral, 0 degenerate. */
double fit_quality(const double a[3], const double b[3], const double c[3], double n[3]);
void fit_corner(const fit_level *lv, const float *pos, uint32_t t, int k, double out[3]);

/* --- surface_fit_project.c --- */
typedef struct fit_project {
    const sl_fit_reference *ref;
    const fit_level *lv;
    uint64_t input_stride;     /* every input_stride-th reference sample is used */
    uint64_t input_count;      /* how many that makes */
    double border_weight;
    int borders;               /* both the level and the input have open edges */
    fit_term *terms;           /* input | level | level border | input border */
    uint32_t *level_hint;      /* per level sample: its last closest input triangle */
} fit_project;
uint64_t fit_term_count(const fit_project *p);
/* Projects every sample on the current positions into p->terms; OUT: *m. */
int fit_project_all(fit_project *p, fit_measure *m, sl_progress *progress, sl_error *err);

/* --- surface_fit_solve.c --- */
typedef struct fit_solver {
    const fit_level *lv;
    double *q;                 /* 18 per triangle: sum weight w w^T (3 x 3), then
                                  sum weight w_k r (3 x 3) */
    double *val;               /* matrix values, lv->col's layout */
    double *rhs, *x;           /* 3 per vertex: right-hand sides, the solution D */
    double *cg;                /* 4 * 3 per vertex + 1 per vertex: r, z, p, Ap, M^-1 */
    double *partial;           /* 6 per chunk of 1024 rows: per-chunk sums */
    uint64_t iterations;       /* CG iterations of the last solve */
} fit_solver;
int fit_solver_init(fit_solver *s, const fit_level *lv, sl_error *err);
void fit_solver_release(fit_solver *s);
/* Sums the terms, builds the normal equations with the spring and solves for x. */
void fit_solve(fit_solver *s, const fit_term *terms, uint64_t term_count, double spring);

/* --- surface_fit_guard.c --- */
typedef struct fit_guard {
    float *before;             /* 3 per vertex: positions at the step's start */
    uint8_t *halvings;         /* per vertex: how often its step was halved */
    uint8_t *bad;              /* per triangle: failed this round */
} fit_guard;
int fit_guard_init(fit_guard *g, const fit_level *lv, sl_error *err);
void fit_guard_release(fit_guard *g);
/* Moves lv->pos by the step x (3 per vertex) as far as the guards allow; returns how many
 * vertices went less than the whole step. */
uint64_t fit_guarded_step(fit_level *lv, fit_guard *g, const sl_fit_reference *ref,
                          const double *x);

#endif
