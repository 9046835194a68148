/* Step (b) of a round (surface_fit_internal.h): the linear least-squares problem in the
 * displacements D of the level's vertices,
 *     min  sum_terms weight |r - sum_k w_k D_k|^2 + kappa sum_edges |D_u - D_v|^2
 *          + mu sum_v |D_v|^2,
 * through its normal equations A D = B: A is the level's vertex adjacency pattern (one
 * row per vertex: itself and its neighbours), shared by x, y and z, B has three columns.
 *
 * Why displacements and this spring: Hoppe et al.'s E_spring pulls edges to zero length,
 * which shrinks the surface and biases the distance it is meant to help (the paper lowers
 * kappa to 1e-8 by the end). Smoothness of the displacement instead costs nothing when
 * nothing moves, keeps a vertex with few samples moving with its neighbours, and so
 * keeps steps from tearing triangles apart; mu (1e-6 of the spring's scale) only makes
 * A definite where no term reaches. Both are relative to the mean data weight of a
 * vertex (A's mean diagonal before them), so `spring` does not depend on units or sample
 * counts.
 *
 * Assembly is deterministic without atomics: the terms are summed per triangle (each
 * thread owns a fixed range of triangles and reads every term in order), then each row
 * gathers from its vertex's corners in order. CG: Jacobi-preconditioned, the three
 * columns side by side, dot products summed per fixed chunk of rows and the chunks in
 * order. The energy 1/2 x^T A x - B^T x falls at every CG step (what CG guarantees; the
 * residual's norm need not), which Debug builds assert.
 */
#include <assert.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/surface_fit_internal.h"

#define CG_MAX_ITERATIONS 200
#define CG_TOLERANCE 1e-8     /* on r^T M^-1 r, relative to its start */
#define MU 1e-6
#define ROWS 1024             /* rows per chunk of a dot product: the sums' fixed order */

int fit_solver_init(fit_solver *s, const fit_level *lv, sl_error *err)
{
    size_t nv = lv->vertex_count, chunks = (nv + ROWS - 1) / ROWS;
    memset(s, 0, sizeof *s);
    s->lv = lv;
    s->q = malloc(18 * (size_t)lv->triangle_count * sizeof *s->q);
    s->val = malloc(((size_t)lv->row_start[nv] + 1) * sizeof *s->val);
    s->rhs = malloc(3 * nv * sizeof *s->rhs);
    s->x = malloc(3 * nv * sizeof *s->x);
    s->cg = malloc(13 * nv * sizeof *s->cg);
    s->partial = malloc(6 * (chunks + 1) * sizeof *s->partial); /* also fit_run's */
    if (!s->q || !s->val || !s->rhs || !s->x || !s->cg || !s->partial)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: solver of %zu vertices", nv);
    return SL_OK;
}

void fit_solver_release(fit_solver *s)
{
    free(s->q);
    free(s->val);
    free(s->rhs);
    free(s->x);
    free(s->cg);
    free(s->partial);
    memset(s, 0, sizeof *s);
}

/* q[t] = sum over t's terms of weight w w^T (9) and weight w_k r (9), in term order. */
static void sum_per_triangle(fit_solver *s, const fit_term *terms, uint64_t n)
{
    uint32_t nt = s->lv->triangle_count;
    memset(s->q, 0, 18 * (size_t)nt * sizeof *s->q);
#pragma omp parallel if (nt > FIT_CHUNK)
    {
        uint64_t threads = (uint64_t)omp_get_num_threads(), id = (uint64_t)omp_get_thread_num();
        uint32_t lo = (uint32_t)(nt * id / threads), hi = (uint32_t)(nt * (id + 1) / threads);
        for (uint64_t i = 0; i < n; i++) {
            const fit_term *e = &terms[i];
            if (e->triangle < lo || e->triangle >= hi || !(e->weight > 0.0f))
                continue;
            double *q = &s->q[18 * (size_t)e->triangle], wgt = e->weight;
            for (int k = 0; k < 3; k++) {
                double wk = wgt * e->w[k];
                for (int l = 0; l < 3; l++)
                    q[3 * k + l] += wk * e->w[l];
                for (int a = 0; a < 3; a++)
                    q[9 + 3 * k + a] += wk * e->r[a];
            }
        }
    }
}

static uint32_t slot_of(const fit_level *lv, uint32_t row, uint32_t column)
{
    uint32_t lo = lv->row_start[row], hi = lv->row_start[row + 1];
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (lv->col[mid] < column)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* A and B from the per-triangle sums: each row from its vertex's corners, in order. */
static void gather_rows(fit_solver *s)
{
    const fit_level *lv = s->lv;
#pragma omp parallel for schedule(static) if (lv->vertex_count > FIT_CHUNK)
    for (uint32_t v = 0; v < lv->vertex_count; v++) {
        double *rhs = &s->rhs[3 * (size_t)v];
        rhs[0] = rhs[1] = rhs[2] = 0.0;
        for (uint32_t i = lv->row_start[v]; i < lv->row_start[v + 1]; i++)
            s->val[i] = 0.0;
        for (uint32_t i = lv->corner_start[v]; i < lv->corner_start[v + 1]; i++) {
            uint32_t c = lv->corners[i], t = c / 3u, k = c % 3u;
            const double *q = &s->q[18 * (size_t)t];
            for (int l = 0; l < 3; l++)
                s->val[slot_of(lv, v, lv->tri[3 * (size_t)t + l])] += q[3 * k + l];
            for (int a = 0; a < 3; a++)
                rhs[a] += q[9 + 3 * k + a];
        }
    }
}

/* Mean diagonal of the free vertices' rows: the data's scale. */
static double mean_diagonal(fit_solver *s)
{
    const fit_level *lv = s->lv;
    uint64_t chunks = ((uint64_t)lv->vertex_count + ROWS - 1) / ROWS;
#pragma omp parallel for schedule(static) if (chunks > 1)
    for (uint64_t ch = 0; ch < chunks; ch++) {
        double sum = 0.0, count = 0.0;
        for (uint64_t v = ch * ROWS; v < lv->vertex_count && v < (ch + 1) * ROWS; v++)
            if (!lv->fixed[v]) {
                sum += s->val[slot_of(lv, (uint32_t)v, (uint32_t)v)];
                count += 1.0;
            }
        s->partial[2 * ch] = sum;
        s->partial[2 * ch + 1] = count;
    }
    double sum = 0.0, count = 0.0;
    for (uint64_t ch = 0; ch < chunks; ch++) {
        sum += s->partial[2 * ch];
        count += s->partial[2 * ch + 1];
    }
    return count > 0.0 ? sum / count : 0.0;
}

/* The spring and mu on every free row; a fixed vertex's row and column become the
 * identity's (its D is 0), so A stays symmetric. */
static void add_spring_and_locks(fit_solver *s, double kappa, double mu)
{
    const fit_level *lv = s->lv;
#pragma omp parallel for schedule(static) if (lv->vertex_count > FIT_CHUNK)
    for (uint32_t v = 0; v < lv->vertex_count; v++) {
        uint32_t diag = slot_of(lv, v, v);
        for (uint32_t i = lv->row_start[v]; i < lv->row_start[v + 1]; i++) {
            if (i == diag)
                continue;
            if (lv->fixed[v] || lv->fixed[lv->col[i]])
                s->val[i] = 0.0;
            else
                s->val[i] -= kappa;
            s->val[diag] += kappa;
        }
        s->val[diag] += mu;
        if (lv->fixed[v]) {
            s->val[diag] = 1.0;
            s->rhs[3 * (size_t)v] = s->rhs[3 * (size_t)v + 1] = s->rhs[3 * (size_t)v + 2] = 0.0;
        }
    }
}

/* out = A in, three columns; returns in . out per column in `dot` (chunk order). */
static void multiply(fit_solver *s, const double *in, double *out, double dot[3])
{
    const fit_level *lv = s->lv;
    uint64_t chunks = ((uint64_t)lv->vertex_count + ROWS - 1) / ROWS;
#pragma omp parallel for schedule(static) if (chunks > 1)
    for (uint64_t ch = 0; ch < chunks; ch++) {
        double d[3] = {0.0, 0.0, 0.0};
        for (uint64_t v = ch * ROWS; v < lv->vertex_count && v < (ch + 1) * ROWS; v++) {
            double y[3] = {0.0, 0.0, 0.0};
            for (uint32_t i = lv->row_start[v]; i < lv->row_start[v + 1]; i++)
                for (int a = 0; a < 3; a++)
                    y[a] += s->val[i] * in[3 * (size_t)lv->col[i] + a];
            for (int a = 0; a < 3; a++) {
                out[3 * v + a] = y[a];
                d[a] += in[3 * v + a] * y[a];
            }
        }
        memcpy(&s->partial[3 * ch], d, sizeof d);
    }
    dot[0] = dot[1] = dot[2] = 0.0;
    for (uint64_t ch = 0; ch < chunks; ch++)
        for (int a = 0; a < 3; a++)
            dot[a] += s->partial[3 * ch + a];
}

/* x += alpha p, r -= alpha Ap, z = M^-1 r; returns r . z per column. */
static void step(fit_solver *s, const double alpha[3], double rz[3])
{
    size_t nv = s->lv->vertex_count;
    double *r = s->cg, *z = r + 3 * nv, *p = z + 3 * nv, *ap = p + 3 * nv, *inv = ap + 3 * nv;
    uint64_t chunks = (nv + ROWS - 1) / ROWS;
#pragma omp parallel for schedule(static) if (chunks > 1)
    for (uint64_t ch = 0; ch < chunks; ch++) {
        double d[3] = {0.0, 0.0, 0.0};
        for (uint64_t i = 3 * ch * ROWS; i < 3 * nv && i < 3 * (ch + 1) * ROWS; i++) {
            int a = (int)(i % 3);
            s->x[i] += alpha[a] * p[i];
            r[i] -= alpha[a] * ap[i];
            z[i] = inv[i / 3] * r[i];
            d[a] += r[i] * z[i];
        }
        memcpy(&s->partial[3 * ch], d, sizeof d);
    }
    rz[0] = rz[1] = rz[2] = 0.0;
    for (uint64_t ch = 0; ch < chunks; ch++)
        for (int a = 0; a < 3; a++)
            rz[a] += s->partial[3 * ch + a];
}

#ifndef NDEBUG
/* 1/2 x^T A x - B^T x = -1/2 x^T (B + r), per column (serial: Debug only). */
static void energy(const fit_solver *s, double e[3])
{
    e[0] = e[1] = e[2] = 0.0;
    for (size_t i = 0; i < 3 * (size_t)s->lv->vertex_count; i++)
        e[i % 3] -= 0.5 * s->x[i] * (s->rhs[i] + s->cg[i]);
}
#endif

/* Jacobi-preconditioned CG from x = 0, the three columns together. */
static void conjugate_gradients(fit_solver *s)
{
    size_t nv = s->lv->vertex_count;
    double *r = s->cg, *z = r + 3 * nv, *p = z + 3 * nv, *ap = p + 3 * nv, *inv = ap + 3 * nv;
    double rz[3], rz0[3], alpha[3] = {0.0, 0.0, 0.0}, p_ap[3], next[3];
    for (size_t v = 0; v < nv; v++) {
        double d = s->val[slot_of(s->lv, (uint32_t)v, (uint32_t)v)];
        inv[v] = d > 0.0 ? 1.0 / d : 0.0;
    }
    memset(s->x, 0, 3 * nv * sizeof *s->x);
    memcpy(r, s->rhs, 3 * nv * sizeof *r);
    memset(p, 0, 6 * nv * sizeof *p); /* p and ap: the step below multiplies them by 0 */
    step(s, alpha, rz);                /* alpha 0: z = M^-1 r and r . z */
    memcpy(p, z, 3 * nv * sizeof *p);
    memcpy(rz0, rz, sizeof rz);
#ifndef NDEBUG
    double e_before[3] = {0.0, 0.0, 0.0}, e_after[3];
#endif
    for (s->iterations = 0; s->iterations < CG_MAX_ITERATIONS; s->iterations++) {
        int active = 0;
        for (int a = 0; a < 3; a++)
            active |= rz[a] > CG_TOLERANCE * rz0[a];
        if (!active)
            break;
        multiply(s, p, ap, p_ap);
        for (int a = 0; a < 3; a++)
            alpha[a] = rz[a] > CG_TOLERANCE * rz0[a] && p_ap[a] > 0.0 ? rz[a] / p_ap[a] : 0.0;
        step(s, alpha, next);
#ifndef NDEBUG
        energy(s, e_after);
        for (int a = 0; a < 3; a++)
            assert(e_after[a] <= e_before[a] + 1e-9 * fabs(e_before[a]) + 1e-300);
        memcpy(e_before, e_after, sizeof e_after);
#endif
        double beta[3];
        for (int a = 0; a < 3; a++) {
            beta[a] = alpha[a] > 0.0 ? next[a] / rz[a] : 0.0;
            rz[a] = alpha[a] > 0.0 ? next[a] : 0.0;
        }
#pragma omp parallel for schedule(static) if (nv > FIT_CHUNK)
        for (size_t i = 0; i < 3 * nv; i++)
            p[i] = z[i] + beta[i % 3] * p[i];
    }
}

void fit_solve(fit_solver *s, const fit_term *terms, uint64_t term_count, double spring)
{
    sum_per_triangle(s, terms, term_count);
    gather_rows(s);
    double scale = mean_diagonal(s);
    s->iterations = 0;
    if (!(scale > 0.0)) { /* no term reached a free vertex: nothing to move */
        memset(s->x, 0, 3 * (size_t)s->lv->vertex_count * sizeof *s->x);
        return;
    }
    add_spring_and_locks(s, spring * scale, MU * scale);
    conjugate_gradients(s);
}
