/* Quadric error functions (qef.h). */
#include "geometry/qef.h"

#include <math.h>
#include <string.h>

void sl_qef_add_plane(sl_qef *q, const double n[3], const double point[3], double w)
{
    double d = n[0] * point[0] + n[1] * point[1] + n[2] * point[2];
    q->a[0] += w * n[0] * n[0];
    q->a[1] += w * n[0] * n[1];
    q->a[2] += w * n[0] * n[2];
    q->a[3] += w * n[1] * n[1];
    q->a[4] += w * n[1] * n[2];
    q->a[5] += w * n[2] * n[2];
    for (int i = 0; i < 3; i++) {
        q->b[i] += w * d * n[i];
        q->mass[i] += w * point[i];
    }
    q->c += w * d * d;
    q->area += w;
}

void sl_qef_add(sl_qef *q, const sl_qef *r)
{
    for (int i = 0; i < 6; i++)
        q->a[i] += r->a[i];
    for (int i = 0; i < 3; i++) {
        q->b[i] += r->b[i];
        q->mass[i] += r->mass[i];
    }
    q->c += r->c;
    q->area += r->area;
}

static void mat_vec(const double a[6], const double x[3], double y[3])
{
    y[0] = a[0] * x[0] + a[1] * x[1] + a[2] * x[2];
    y[1] = a[1] * x[0] + a[3] * x[1] + a[4] * x[2];
    y[2] = a[2] * x[0] + a[4] * x[1] + a[5] * x[2];
}

/* With x_from = x_to + t:  Q = x_to^T A x_to - 2 (b - A t)^T x_to + (c - 2 b.t + t^T A t),
 * and every point p_to = p_from - t. */
void sl_qef_shift(sl_qef *q, const double t[3])
{
    double at[3];
    mat_vec(q->a, t, at);
    double bt = q->b[0] * t[0] + q->b[1] * t[1] + q->b[2] * t[2];
    double tat = t[0] * at[0] + t[1] * at[1] + t[2] * at[2];
    for (int i = 0; i < 3; i++) {
        q->b[i] -= at[i];
        q->mass[i] -= q->area * t[i];
    }
    q->c += tat - 2 * bt;
}

double sl_qef_eval(const sl_qef *q, const double x[3])
{
    double ax[3];
    mat_vec(q->a, x, ax);
    return x[0] * ax[0] + x[1] * ax[1] + x[2] * ax[2] -
           2 * (q->b[0] * x[0] + q->b[1] * x[1] + q->b[2] * x[2]) + q->c;
}

void sl_sym3_eigen(const double a_in[3][3], double w[3], double v[3][3])
{
    double a[3][3];
    memcpy(a, a_in, sizeof a);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            v[i][j] = i == j;
    for (int sweep = 0; sweep < 32; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (off <= 1e-15 * diag || off == 0)
            break;
        for (int p = 0; p < 2; p++)
            for (int r = p + 1; r < 3; r++) {
                if (a[p][r] == 0)
                    continue;
                double theta = (a[r][r] - a[p][p]) / (2 * a[p][r]);
                double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; k++) { /* a = a J (columns p, r) */
                    double akp = a[k][p], akr = a[k][r];
                    a[k][p] = c * akp - s * akr;
                    a[k][r] = s * akp + c * akr;
                }
                for (int k = 0; k < 3; k++) { /* a = J^T a (rows p, r) */
                    double apk = a[p][k], ark = a[r][k];
                    a[p][k] = c * apk - s * ark;
                    a[r][k] = s * apk + c * ark;
                }
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkr = v[k][r];
                    v[k][p] = c * vkp - s * vkr;
                    v[k][r] = s * vkp + c * vkr;
                }
            }
    }
    for (int i = 0; i < 3; i++)
        w[i] = a[i][i];
}

int sl_qef_solve(const sl_qef *q, double tau, const double lo[3], const double hi[3], double x[3])
{
    if (!(q->area > 0)) {
        for (int i = 0; i < 3; i++)
            x[i] = 0.5 * (lo[i] + hi[i]);
        return 0;
    }
    double m[3] = {q->mass[0] / q->area, q->mass[1] / q->area, q->mass[2] / q->area};
    double a[3][3] = {{q->a[0], q->a[1], q->a[2]}, {q->a[1], q->a[3], q->a[4]},
                      {q->a[2], q->a[4], q->a[5]}};
    double w[3], v[3][3], am[3], r[3];
    sl_sym3_eigen(a, w, v);
    mat_vec(q->a, m, am);
    for (int i = 0; i < 3; i++)
        r[i] = q->b[i] - am[i]; /* -gradient / 2 at m */
    double wmax = fmax(fabs(w[0]), fmax(fabs(w[1]), fabs(w[2])));
    memcpy(x, m, 3 * sizeof *x);
    for (int k = 0; k < 3; k++) {
        if (!(w[k] > tau * wmax))
            continue;
        double step = (v[0][k] * r[0] + v[1][k] * r[1] + v[2][k] * r[2]) / w[k];
        for (int i = 0; i < 3; i++)
            x[i] += step * v[i][k];
    }
    int moved = 0;
    for (int i = 0; i < 3; i++) {
        if (!(x[i] >= lo[i])) { /* also catches NaN */
            x[i] = lo[i];
            moved = 1;
        } else if (x[i] > hi[i]) {
            x[i] = hi[i];
            moved = 1;
        }
    }
    return moved;
}
