/* Data-dependent edge flips of a retriangulated patch (Dyn, Levin and Rippa, "Data
 * dependent triangulations for piecewise linear interpolation", IMA J. Numer. Anal. 10,
 * 1990; Garland and Heckbert's terrain simplifier uses them after greedy insertion).
 *
 * A Delaunay triangulation of the projected points is the best-shaped one in the plane,
 * not the closest to the surface: on a cylinder it cuts across the axis where the
 * surface wants long triangles along it. So, after the constrained Delaunay
 * triangulation, every unconstrained edge whose quad is strictly convex in projection is
 * flipped when that lowers the sum of squared distances of the removed vertices under
 * the two triangles to their planes, and the new triangles pass the normal check. A
 * flip strictly lowers the sum, so the queue (FIFO, in edge order: deterministic) ends.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/predicates.h"
#include "stages/segment/segment_internal.h"

#define NONE UINT32_MAX

static uint32_t next_he(uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }

typedef struct flipper {
    const seg_flip_input *in;
    uint32_t *tri;      /* 3 per triangle, point ids (rewritten) */
    uint32_t *twin;     /* per half-edge */
    uint8_t *fixed;     /* per half-edge: on a loop */
    uint32_t *head;     /* per triangle: first candidate */
    uint32_t *next;     /* per candidate */
    double *cost;       /* per triangle */
    uint32_t *queue;
    uint8_t *queued;
    uint64_t qhead, qtail, qcap;
} flipper;

static void plane_of(const seg_flip_input *in, uint32_t a, uint32_t b, uint32_t c, double n[3],
                     int *ok)
{
    const double *pa = in->pos + 3 * (size_t)a, *pb = in->pos + 3 * (size_t)b,
                 *pc = in->pos + 3 * (size_t)c;
    double u[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
    double w[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    *ok = len > 0;
    for (int k = 0; k < 3; k++)
        n[k] = len > 0 ? n[k] / len : 0;
    if (*ok && in->point_normal)
        for (int q = 0; q < 3; q++) {
            const double *vn = in->point_normal + 3 * (size_t)(q == 0 ? a : q == 1 ? b : c);
            if (n[0] * vn[0] + n[1] * vn[1] + n[2] * vn[2] < in->cos_max_deviation)
                *ok = 0;
        }
}

static double dist2_to(const seg_flip_input *in, uint32_t a, const double n[3], uint32_t cand)
{
    const double *pa = in->pos + 3 * (size_t)a, *q = in->cand_pos + 3 * (size_t)cand;
    double d = (q[0] - pa[0]) * n[0] + (q[1] - pa[1]) * n[1] + (q[2] - pa[2]) * n[2];
    return d * d;
}

static double triangle_cost(const flipper *f, uint32_t t)
{
    double n[3];
    int ok;
    const uint32_t *c = f->tri + 3 * (size_t)t;
    plane_of(f->in, c[0], c[1], c[2], n, &ok);
    double sum = 0;
    for (uint32_t q = f->head[t]; q != NONE; q = f->next[q])
        sum += dist2_to(f->in, c[0], n, q);
    return sum;
}

static void push(flipper *f, uint32_t h)
{
    uint32_t t = f->twin[h];
    if (t == NONE || f->fixed[h])
        return;
    uint32_t e = h < t ? h : t;
    if (f->queued[e])
        return;
    f->queued[e] = 1;
    f->queue[f->qtail++ % f->qcap] = e;
}

static int cmp_key(const void *x, const void *y)
{
    const uint64_t *a = x, *b = y;
    return a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : (a[1] > b[1]) - (a[1] < b[1]);
}

/* Twins by sorting (undirected key, half-edge); loop edges marked fixed. */
static int link_twins(flipper *f, uint32_t nt)
{
    const seg_flip_input *in = f->in;
    uint64_t nh = 3 * (uint64_t)nt, nl = 0;
    for (uint32_t l = 0; l < in->loop_count; l++)
        nl += in->loop_start[l + 1] - in->loop_start[l];
    uint64_t (*key)[2] = malloc((nh + nl + 1) * sizeof *key);
    if (!key)
        return -1;
    uint64_t n = 0;
    for (uint64_t h = 0; h < nh; h++) {
        uint64_t a = f->tri[h], b = f->tri[next_he((uint32_t)h)];
        key[n][0] = a < b ? a << 32 | b : b << 32 | a;
        key[n++][1] = h;
    }
    for (uint32_t l = 0; l < in->loop_count; l++) { /* loop edges: marker entries */
        uint32_t b0 = in->loop_start[l], e0 = in->loop_start[l + 1];
        for (uint32_t i = b0; i < e0; i++) {
            uint64_t a = in->loop_points[i], b = in->loop_points[i + 1 < e0 ? i + 1 : b0];
            if (a == b)
                continue;
            key[n][0] = a < b ? a << 32 | b : b << 32 | a;
            key[n++][1] = UINT64_MAX;
        }
    }
    qsort(key, n, sizeof *key, cmp_key);
    for (uint64_t h = 0; h < nh; h++) {
        f->twin[h] = NONE;
        f->fixed[h] = 0;
    }
    for (uint64_t i = 0; i < n;) {
        uint64_t j = i;
        while (j < n && key[j][0] == key[i][0])
            j++;
        uint32_t hs[2], nhs = 0;
        int on_loop = 0;
        for (uint64_t q = i; q < j; q++) {
            if (key[q][1] == UINT64_MAX)
                on_loop = 1;
            else if (nhs < 2)
                hs[nhs++] = (uint32_t)key[q][1];
        }
        for (uint32_t q = 0; q < nhs; q++)
            f->fixed[hs[q]] = (uint8_t)on_loop;
        if (nhs == 2 && !on_loop) {
            f->twin[hs[0]] = hs[1];
            f->twin[hs[1]] = hs[0];
        }
        i = j;
    }
    free(key);
    return 0;
}

/* Tries to flip the edge of half-edge h; returns 1 if flipped. */
static int try_flip(flipper *f, uint32_t h)
{
    const seg_flip_input *in = f->in;
    uint32_t g = f->twin[h];
    if (g == NONE || f->fixed[h])
        return 0;
    uint32_t t1 = h / 3, t2 = g / 3;
    /* t1 = (a, b, c) from h = a->b; t2 = (b, a, d) from g = b->a */
    uint32_t a = f->tri[h], b = f->tri[next_he(h)], c = f->tri[next_he(next_he(h))];
    uint32_t d = f->tri[next_he(next_he(g))];
    const double *ua = in->uv + 2 * (size_t)a, *ub = in->uv + 2 * (size_t)b,
                 *uc = in->uv + 2 * (size_t)c, *ud = in->uv + 2 * (size_t)d;
    if (sl_orient2d(ua, ud, uc) <= 0 || sl_orient2d(ud, ub, uc) <= 0)
        return 0; /* not strictly convex: the flip would fold */
    /* The two surfaces differ most where the diagonals cross: at most max_error there. */
    if (in->h) {
        double ex = ub[0] - ua[0], ey = ub[1] - ua[1], fx = ud[0] - uc[0], fy = ud[1] - uc[1];
        double den = ex * fy - ey * fx;
        if (den == 0)
            return 0;
        double s1 = ((uc[0] - ua[0]) * fy - (uc[1] - ua[1]) * fx) / den; /* along a-b */
        double s2 = ((uc[0] - ua[0]) * ey - (uc[1] - ua[1]) * ex) / den; /* along c-d */
        double h_ab = in->h[a] + s1 * (in->h[b] - in->h[a]), h_cd = in->h[c] + s2 * (in->h[d] - in->h[c]);
        if (fabs(h_ab - h_cd) > in->max_error)
            return 0;
    }
    double n1[3], n2[3];
    int ok1, ok2;
    plane_of(in, a, d, c, n1, &ok1);
    plane_of(in, d, b, c, n2, &ok2);
    if (!ok1 || !ok2)
        return 0;
    double before = f->cost[t1] + f->cost[t2], after1 = 0, after2 = 0;
    double limit = in->max_error * in->max_error, worst_before = 0, worst_after = 0;
    const uint32_t *o1 = f->tri + 3 * (size_t)t1, *o2 = f->tri + 3 * (size_t)t2;
    double m1[3], m2[3];
    int okm1, okm2;
    plane_of(in, o1[0], o1[1], o1[2], m1, &okm1);
    plane_of(in, o2[0], o2[1], o2[2], m2, &okm2);
    for (int side = 0; side < 2; side++)
        for (uint32_t q = f->head[side ? t2 : t1]; q != NONE; q = f->next[q]) {
            double old = side ? dist2_to(in, o2[0], m2, q) : dist2_to(in, o1[0], m1, q), now;
            if (sl_orient2d(ud, uc, in->cand_uv + 2 * (size_t)q) >= 0)
                after1 += now = dist2_to(in, a, n1, q);
            else
                after2 += now = dist2_to(in, d, n2, q);
            worst_before = fmax(worst_before, old);
            worst_after = fmax(worst_after, now);
        }
    if (!(after1 + after2 < before * (1 - 1e-9)))
        return 0;
    if (worst_after > fmax(limit, worst_before))
        return 0; /* no vertex farther than the bound (or than before) */
    /* outer half-edges and their twins and marks, before rewriting */
    uint32_t h_bc = next_he(h), h_ca = next_he(h_bc), g_ad = next_he(g), g_db = next_he(g_ad);
    uint32_t o_bc = f->twin[h_bc], o_ca = f->twin[h_ca], o_ad = f->twin[g_ad], o_db = f->twin[g_db];
    uint8_t x_bc = f->fixed[h_bc], x_ca = f->fixed[h_ca], x_ad = f->fixed[g_ad], x_db = f->fixed[g_db];
    uint32_t *T1 = f->tri + 3 * (size_t)t1, *T2 = f->tri + 3 * (size_t)t2;
    T1[0] = a, T1[1] = d, T1[2] = c; /* a->d, d->c, c->a */
    T2[0] = d, T2[1] = b, T2[2] = c; /* d->b, b->c, c->d */
    uint32_t e[6] = {3 * t1, 3 * t1 + 1, 3 * t1 + 2, 3 * t2, 3 * t2 + 1, 3 * t2 + 2};
    uint32_t tw[6] = {o_ad, e[5], o_ca, o_db, o_bc, e[1]};
    uint8_t fx[6] = {x_ad, 0, x_ca, x_db, x_bc, 0};
    for (int i = 0; i < 6; i++) {
        f->twin[e[i]] = tw[i];
        f->fixed[e[i]] = fx[i];
        if (tw[i] != NONE && i != 1 && i != 5)
            f->twin[tw[i]] = e[i];
    }
    /* candidates: into the new triangles */
    uint32_t list = NONE;
    for (int side = 0; side < 2; side++) {
        uint32_t q = f->head[side ? t2 : t1];
        while (q != NONE) {
            uint32_t nx = f->next[q];
            f->next[q] = list;
            list = q;
            q = nx;
        }
    }
    f->head[t1] = f->head[t2] = NONE;
    while (list != NONE) {
        uint32_t nx = f->next[list];
        uint32_t t = sl_orient2d(ud, uc, in->cand_uv + 2 * (size_t)list) >= 0 ? t1 : t2;
        f->next[list] = f->head[t];
        f->head[t] = list;
        list = nx;
    }
    f->cost[t1] = triangle_cost(f, t1);
    f->cost[t2] = triangle_cost(f, t2);
    push(f, e[0]);
    push(f, e[2]);
    push(f, e[3]);
    push(f, e[4]);
    return 1;
}

int seg_flip_optimize(const seg_flip_input *in, uint32_t *triangles, uint32_t triangle_count,
                      uint64_t *flips)
{
    *flips = 0;
    uint32_t nt = triangle_count;
    uint64_t nh = 3 * (uint64_t)nt;
    if (nt < 2 || !in->cand_count)
        return 0;
    flipper f;
    memset(&f, 0, sizeof f);
    f.in = in;
    f.tri = triangles;
    f.twin = malloc(nh * sizeof *f.twin);
    f.fixed = malloc(nh);
    f.head = malloc(nt * sizeof *f.head);
    f.next = malloc(in->cand_count * sizeof *f.next);
    f.cost = malloc(nt * sizeof *f.cost);
    f.qcap = nh + 1;
    f.queue = malloc(f.qcap * sizeof *f.queue);
    f.queued = calloc(nh, 1);
    int rc = -1;
    if (f.twin && f.fixed && f.head && f.next && f.cost && f.queue && f.queued && link_twins(&f, nt) == 0) {
        for (uint32_t t = 0; t < nt; t++)
            f.head[t] = NONE;
        for (uint32_t q = in->cand_count; q-- > 0;) {
            uint32_t t = in->cand_tri[q];
            f.next[q] = NONE;
            if (t == NONE)
                continue;
            f.next[q] = f.head[t];
            f.head[t] = q;
        }
        for (uint32_t t = 0; t < nt; t++)
            f.cost[t] = triangle_cost(&f, t);
        for (uint32_t h = 0; h < nh; h++)
            push(&f, h);
        uint64_t budget = 50 * nh + 100; /* a guard; each flip lowers the cost anyway */
        while (f.qhead != f.qtail && budget--) {
            uint32_t e = f.queue[f.qhead++ % f.qcap];
            f.queued[e] = 0;
            *flips += (uint64_t)try_flip(&f, e);
        }
        rc = 0;
    }
    free(f.twin);
    free(f.fixed);
    free(f.head);
    free(f.next);
    free(f.cost);
    free(f.queue);
    free(f.queued);
    return rc;
}
