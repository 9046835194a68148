/* Extreme normals in a gnomonic chart (normal_hull.h). */
#include "geometry/normal_hull.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/predicates.h"
#include "geometry/vec3.h"

void sl_normal_hull_init(sl_normal_hull *h)
{
    memset(h, 0, sizeof *h);
}

void sl_normal_hull_release(sl_normal_hull *h)
{
    free(h->p);
    free(h->n);
    free(h->id);
    free(h->scratch_p);
    free(h->scratch_n);
    free(h->scratch_id);
    free(h->order);
    memset(h, 0, sizeof *h);
}

static int reserve(sl_normal_hull *h, uint32_t need)
{
    if (need <= h->cap)
        return 0;
    uint32_t cap = h->cap ? h->cap : 16;
    while (cap < need)
        cap *= 2;
    double *p = realloc(h->p, 2 * (size_t)cap * sizeof *p);
    if (p)
        h->p = p;
    double *n = realloc(h->n, 3 * (size_t)cap * sizeof *n);
    if (n)
        h->n = n;
    uint32_t *id = realloc(h->id, cap * sizeof *id);
    if (id)
        h->id = id;
    double *sp = realloc(h->scratch_p, 2 * (size_t)cap * sizeof *sp);
    if (sp)
        h->scratch_p = sp;
    double *sn = realloc(h->scratch_n, 3 * (size_t)cap * sizeof *sn);
    if (sn)
        h->scratch_n = sn;
    uint32_t *si = realloc(h->scratch_id, cap * sizeof *si);
    if (si)
        h->scratch_id = si;
    uint32_t *o = realloc(h->order, cap * sizeof *o);
    if (o)
        h->order = o;
    if (!p || !n || !id || !sp || !sn || !si || !o)
        return -1;
    h->cap = cap;
    return 0;
}

void sl_normal_hull_start(sl_normal_hull *h, const double s[3])
{
    memcpy(h->s, s, sizeof h->s);
    /* e1: s x (the axis least aligned with s), normalised; e2 = s x e1 */
    double ax[3] = {0, 0, 0};
    ax[fabs(s[0]) <= fabs(s[1]) && fabs(s[0]) <= fabs(s[2]) ? 0 : fabs(s[1]) <= fabs(s[2]) ? 1 : 2] = 1.0;
    double e[3] = {s[1] * ax[2] - s[2] * ax[1], s[2] * ax[0] - s[0] * ax[2],
                   s[0] * ax[1] - s[1] * ax[0]};
    double len = sqrt(sl_dot3(e, e));
    for (int i = 0; i < 3; i++)
        h->e1[i] = e[i] / len;
    h->e2[0] = s[1] * h->e1[2] - s[2] * h->e1[1];
    h->e2[1] = s[2] * h->e1[0] - s[0] * h->e1[2];
    h->e2[2] = s[0] * h->e1[1] - s[1] * h->e1[0];
    h->count = 0;
}

static void gnomonic(const sl_normal_hull *h, const double *n, double p[2])
{
    double d = sl_dot3(n, h->s);
    p[0] = sl_dot3(n, h->e1) / d;
    p[1] = sl_dot3(n, h->e2) / d;
}

/* Is p inside or on the hull? (count >= 3: a counter-clockwise polygon) */
static int contains(const sl_normal_hull *h, const double p[2])
{
    if (h->count < 3) {
        for (uint32_t i = 0; i < h->count; i++)
            if (h->p[2 * i] == p[0] && h->p[2 * i + 1] == p[1])
                return 1;
        return 0;
    }
    for (uint32_t i = 0; i < h->count; i++) {
        uint32_t j = i + 1 == h->count ? 0 : i + 1;
        if (sl_orient2d(h->p + 2 * i, h->p + 2 * j, p) < 0)
            return 0;
    }
    return 1;
}

static void put(sl_normal_hull *h, uint32_t k, const double *p, const double *n, uint32_t id)
{
    h->p[2 * k] = p[0];
    h->p[2 * k + 1] = p[1];
    memcpy(h->n + 3 * (size_t)k, n, 3 * sizeof *n);
    h->id[k] = id;
}

/* Monotone chain over the current vertices plus (p, n, id); duplicate and collinear
 * points are dropped (of equal points the lowest id stays). */
static void rebuild(sl_normal_hull *h, const double p[2], const double *n, uint32_t id)
{
    uint32_t count = h->count + 1;
    double *pts = h->scratch_p, *nrm = h->scratch_n;
    uint32_t *ids = h->scratch_id, *o = h->order;
    memcpy(pts, h->p, 2 * (size_t)h->count * sizeof *pts);
    memcpy(nrm, h->n, 3 * (size_t)h->count * sizeof *nrm);
    memcpy(ids, h->id, h->count * sizeof *ids);
    pts[2 * h->count] = p[0];
    pts[2 * h->count + 1] = p[1];
    memcpy(nrm + 3 * (size_t)h->count, n, 3 * sizeof *n);
    ids[h->count] = id;
    for (uint32_t i = 0; i < count; i++) { /* insertion sort by (x, y, id): count is small */
        uint32_t j = i;
        for (; j > 0; j--) {
            const double *a = pts + 2 * o[j - 1], *b = pts + 2 * i;
            int less = b[0] < a[0] ||
                       (b[0] == a[0] && (b[1] < a[1] || (b[1] == a[1] && ids[i] < ids[o[j - 1]])));
            if (!less)
                break;
            o[j] = o[j - 1];
        }
        o[j] = i;
    }
    uint32_t m = 0; /* distinct points, in order */
    for (uint32_t i = 0; i < count; i++)
        if (!m || pts[2 * o[i]] != pts[2 * o[m - 1]] || pts[2 * o[i] + 1] != pts[2 * o[m - 1] + 1])
            o[m++] = o[i];
    if (m == 1) {
        put(h, 0, pts + 2 * o[0], nrm + 3 * (size_t)o[0], ids[o[0]]);
        h->count = 1;
        return;
    }
    uint32_t k = 0; /* lower chain, then upper chain back to the first point (room: m + 1) */
    for (uint32_t step = 0; step < m; step++) {
        const double *q = pts + 2 * o[step];
        while (k >= 2 && sl_orient2d(h->p + 2 * (k - 2), h->p + 2 * (k - 1), q) <= 0)
            k--;
        put(h, k++, q, nrm + 3 * (size_t)o[step], ids[o[step]]);
    }
    uint32_t lower = k + 1;
    for (uint32_t step = m - 1; step-- > 0;) {
        const double *q = pts + 2 * o[step];
        while (k >= lower && sl_orient2d(h->p + 2 * (k - 2), h->p + 2 * (k - 1), q) <= 0)
            k--;
        put(h, k++, q, nrm + 3 * (size_t)o[step], ids[o[step]]);
    }
    h->count = k - 1; /* the last point is the first */
}

int sl_normal_hull_add(sl_normal_hull *h, const double n[3], uint32_t id)
{
    double p[2];
    gnomonic(h, n, p);
    if (contains(h, p))
        return 0;
    if (reserve(h, 2 * h->count + 4))
        return -1;
    if (h->count == 0) {
        put(h, 0, p, n, id);
        h->count = 1;
        return 0;
    }
    rebuild(h, p, n, id);
    return 0;
}

double sl_normal_hull_min_dot(const sl_normal_hull *h, const double m[3])
{
    double lo = 1.0;
    for (uint32_t i = 0; i < h->count; i++) {
        double d = sl_dot3(m, h->n + 3 * (size_t)i);
        lo = d < lo ? d : lo;
    }
    return lo;
}
