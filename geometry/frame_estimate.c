/* A scan's frame from its geometry (frame_estimate.h): the footprint rule for up, the
 * diagonal rule for units. */
#include "geometry/frame_estimate.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct point2 {
    double x, y;
} point2;

static int by_xy(const void *a, const void *b)
{
    const point2 *p = a, *q = b;
    return p->x < q->x ? -1 : p->x > q->x ? 1 : p->y < q->y ? -1 : p->y > q->y;
}

static double turn(point2 o, point2 a, point2 b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/* Area of the convex hull of p[0..n) (Andrew's monotone chain; sorts p, uses hull[2n]). */
static double hull_area(point2 *p, size_t n, point2 *hull)
{
    if (n < 3)
        return 0;
    qsort(p, n, sizeof *p, by_xy);
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        while (k >= 2 && turn(hull[k - 2], hull[k - 1], p[i]) <= 0)
            k--;
        hull[k++] = p[i];
    }
    for (size_t i = n - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && turn(hull[k - 2], hull[k - 1], p[i]) <= 0)
            k--;
        hull[k++] = p[i];
    }
    double area = 0;
    for (size_t i = 0; i + 1 < k; i++)
        area += hull[i].x * hull[i + 1].y - hull[i + 1].x * hull[i].y;
    return area / 2;
}

const char *sl_frame_direction_name(int direction)
{
    static const char *const names[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
    return direction >= 0 && direction < 6 ? names[direction] : "?";
}

/* Footprint share of direction (axis, its lowest end when !top, else its highest). */
static double support(const sl_mesh *m, const double lo[3], const double hi[3], int axis,
                      int top, point2 *p, point2 *hull)
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    double slab = SL_FRAME_SLAB * (hi[axis] - lo[axis]);
    double section = (hi[u] - lo[u]) * (hi[v] - lo[v]);
    size_t n = 0;
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        const float *q = m->positions + 3 * i;
        double depth = top ? hi[axis] - q[axis] : q[axis] - lo[axis];
        if (isfinite(q[0]) && isfinite(q[1]) && isfinite(q[2]) && depth <= slab)
            p[n++] = (point2){q[u], q[v]};
    }
    return section > 0 ? hull_area(p, n, hull) / section : 0;
}

int sl_frame_estimate_compute(const sl_mesh *m, sl_frame_estimate *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        const float *q = m->positions + 3 * i;
        if (!isfinite(q[0]) || !isfinite(q[1]) || !isfinite(q[2]))
            continue;
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], q[k]), hi[k] = fmax(hi[k], q[k]);
    }
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    if (!(d2 > 0) || !isfinite(d2))
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "no extent to estimate a frame from");
    out->diagonal = sqrt(d2);
    size_t n = (size_t)m->vertex_count;
    point2 *p = malloc(n * sizeof *p), *hull = malloc(2 * n * sizeof *hull);
    if (!p || !hull) {
        free(p), free(hull);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    }
    for (int d = 0; d < 6; d++) {
        out->support[d] = support(m, lo, hi, d / 2, d % 2, p, hull);
        if (out->support[d] > out->support[out->best])
            out->best = d;
    }
    free(p), free(hull);
    out->up = out->support[4] > out->support[2] ? 'z' : 'y';
    snprintf(out->units, sizeof out->units, "%s",
             out->diagonal >= SL_FRAME_MM_DIAGONAL ? "mm" : "m");
    return 0;
}
