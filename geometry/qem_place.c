/* Where a collapse puts its vertex and what that costs.
 *
 * Placement (Garland and Heckbert 1997, section 4): the minimiser of the merged quadric
 * Q = Q_a + Q_b solves A x = b. On a flat or evenly curved patch A is (nearly) rank one and
 * the minimiser runs off along the tangent plane, so the system is regularised towards the
 * edge's midpoint m: (A + lambda I) x = b + lambda m with lambda a small fraction of A's
 * trace. Directions where the surface is well defined (normals, creases, corners) keep the
 * exact optimum; the others settle at the midpoint, which also keeps triangles even. A
 * solution farther from m than the edge is long is not trusted (a nearly singular A on a
 * thin part): then the best of the endpoints and the midpoint is taken. A collapse along
 * an open border takes the better endpoint (as meshoptimizer does): border vertices stay
 * input vertices, so a border only ever loses vertices, never drifts off its line.
 *
 * Attributes (Hoppe 1999, in the form meshoptimizer uses): each wedge keeps the
 * area-weighted sum of its triangles' linear attribute fields, f(x) = g . x + g0 per
 * attribute; merging wedges adds the sums, and a moved wedge takes the merged field's
 * value at its new position, clamped to the range of the merged values (no overshoot out
 * of a texture chart). The cost adds, per merged wedge, its area times the squared change
 * of its attributes, times attribute_scale.
 */
#include <math.h>
#include <string.h>

#include "geometry/qem_internal.h"
#include "geometry/vec3.h"

#define QEM_REGULARISATION 1e-5 /* lambda / trace(A); measured against 1e-4 .. 1e-2 (docs/simplify.md) */

static double distance_sq(const double p[3], const double q[3])
{
    double d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    return sl_dot3(d, d);
}

/* The merged quadric of two points: the sum of theirs, without the area and mass point
 * sl_qef carries (this runs for every queued edge: no copy of what is not needed). */
typedef struct pair_quadric {
    double a[6], b[3], c;
} pair_quadric;

static void pair_sum(const sl_qef *p, const sl_qef *q, pair_quadric *out)
{
    for (int i = 0; i < 6; i++)
        out->a[i] = p->a[i] + q->a[i];
    for (int i = 0; i < 3; i++)
        out->b[i] = p->b[i] + q->b[i];
    out->c = p->c + q->c;
}

/* Q(x) = x^T A x - 2 b^T x + c (as sl_qef_eval), never below 0. */
static double pair_eval(const pair_quadric *q, const double x[3])
{
    const double *a = q->a;
    double ax0 = a[0] * x[0] + a[1] * x[1] + a[2] * x[2];
    double ax1 = a[1] * x[0] + a[3] * x[1] + a[4] * x[2];
    double ax2 = a[2] * x[0] + a[4] * x[1] + a[5] * x[2];
    double e = x[0] * (ax0 - 2 * q->b[0]) + x[1] * (ax1 - 2 * q->b[1]) +
               x[2] * (ax2 - 2 * q->b[2]) + q->c;
    return e > 0 ? e : 0;
}

/* x = (A + lambda I)^-1 (b + lambda m) by Cramer's rule (symmetric positive definite for
 * lambda > 0). Returns 0 when A is empty (no surface: nothing to solve). */
static int solve_regularised(const pair_quadric *q, const double m[3], double x[3])
{
    double trace = q->a[0] + q->a[3] + q->a[5];
    if (!(trace > 0))
        return 0;
    double lambda = QEM_REGULARISATION * trace;
    double a00 = q->a[0] + lambda, a01 = q->a[1], a02 = q->a[2];
    double a11 = q->a[3] + lambda, a12 = q->a[4], a22 = q->a[5] + lambda;
    double r[3] = {q->b[0] + lambda * m[0], q->b[1] + lambda * m[1], q->b[2] + lambda * m[2]};
    double c00 = a11 * a22 - a12 * a12, c01 = a02 * a12 - a01 * a22,
           c02 = a01 * a12 - a02 * a11;
    double det = a00 * c00 + a01 * c01 + a02 * c02;
    if (!(det > 0))
        return 0;
    double c11 = a00 * a22 - a02 * a02, c12 = a01 * a02 - a00 * a12,
           c22 = a00 * a11 - a01 * a01;
    x[0] = (c00 * r[0] + c01 * r[1] + c02 * r[2]) / det;
    x[1] = (c01 * r[0] + c11 * r[1] + c12 * r[2]) / det;
    x[2] = (c02 * r[0] + c12 * r[1] + c22 * r[2]) / det;
    return isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]);
}

/* The cheapest of the candidates (first wins a tie). */
static double best_candidate(const pair_quadric *q, const double *cand[], int count, double x[3])
{
    double best = INFINITY;
    memcpy(x, cand[0], 3 * sizeof *x); /* (even if every error is NaN) */
    for (int i = 0; i < count; i++) {
        double e = pair_eval(q, cand[i]);
        if (e < best) {
            best = e;
            memcpy(x, cand[i], 3 * sizeof *x);
        }
    }
    return best;
}

double qem_place(const qem_state *st, uint32_t a, uint32_t b, int mode, double x[3])
{
    const double *pa = st->point[a].position, *pb = st->point[b].position;
    pair_quadric q;
    pair_sum(&st->point[a].quadric, &st->point[b].quadric, &q);
    if (mode == QEM_TO_A || mode == QEM_TO_B) {
        memcpy(x, mode == QEM_TO_A ? pa : pb, 3 * sizeof *x);
        return pair_eval(&q, x);
    }
    double m[3] = {(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2};
    int free = st->cfg.optimal_placement && !(st->point[a].flags & st->point[b].flags & QEM_BORDER);
    if (free && solve_regularised(&q, m, x) && distance_sq(x, m) <= distance_sq(pa, pb))
        return pair_eval(&q, x);
    const double *cand[3] = {pa, pb, m};
    return best_candidate(&q, cand, free ? 3 : 2, x);
}

/* The merged field of wedges w and v at x, attribute k, clamped to [lo, hi]. */
static double field_value(const qem_state *st, uint32_t w, uint32_t v, int k, const double x[3],
                          double lo, double hi)
{
    int stride = 1 + 4 * st->attribute_count;
    const double *fw = st->field + (uint64_t)w * stride, *fv = st->field + (uint64_t)v * stride;
    double area = fw[0] + fv[0];
    if (!(area > 0))
        return (lo + hi) / 2;
    const double *gw = fw + 1 + 4 * k, *gv = fv + 1 + 4 * k;
    double value = 0;
    for (int i = 0; i < 3; i++)
        value += (gw[i] + gv[i]) * x[i];
    value = (value + gw[3] + gv[3]) / area;
    return value < lo ? lo : value > hi ? hi : value;
}

void qem_merged_attributes(const qem_state *st, uint32_t from, uint32_t to, const double x[3],
                           double *out)
{
    int n = st->attribute_count;
    const double *af = st->attribute + (uint64_t)from * n, *at = st->attribute + (uint64_t)to * n;
    for (int k = 0; k < n; k++)
        out[k] = field_value(st, from, to, k, x, fmin(af[k], at[k]), fmax(af[k], at[k]));
}

static double change_cost(const qem_state *st, uint32_t w, const double *value)
{
    int n = st->attribute_count;
    const double *a = st->attribute + (uint64_t)w * n;
    double sum = 0;
    for (int k = 0; k < n; k++)
        sum += (value[k] - a[k]) * (value[k] - a[k]);
    return st->field[(uint64_t)w * (1 + 4 * n)] * sum;
}

double qem_attribute_cost(const qem_state *st, const qem_plan *plan)
{
    if (!st->attribute_count || !(st->attribute_scale > 0))
        return 0;
    double sum = 0, value[6];
    for (int i = 0; i < plan->wedge_pairs; i++) {
        uint32_t from = plan->wedge_from[i], to = plan->wedge_to[i];
        if (plan->mode == QEM_OPTIMAL) {
            qem_merged_attributes(st, from, to, plan->x, value);
            sum += change_cost(st, from, value) + change_cost(st, to, value);
        } else {
            sum += change_cost(st, from, st->attribute + (uint64_t)to * st->attribute_count);
        }
    }
    return st->attribute_scale * sum;
}
