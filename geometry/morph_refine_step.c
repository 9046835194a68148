/* Where the morph refinement's new vertices go (morph_refine.h): the first coarser edge
 * a weight-1 chord crosses, the next coarser vertex of a shortest path along coarser
 * edges where the chord crosses none, and the coarser vertex a triangle spans. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/morph_refine_core.h"
#include "geometry/vec3.h"

static void face_normal(const refine *R, uint32_t g, double n[3])
{
    double q[3][3], e1[3], e2[3];
    for (int k = 0; k < 3; k++)
        mr_corner(R->c, g, k, q[k]);
    for (int k = 0; k < 3; k++)
        e1[k] = q[1][k] - q[0][k], e2[k] = q[2][k] - q[0][k];
    sl_cross3(e1, e2, n);
    double len = sqrt(sl_dot3(n, n));
    for (int k = 0; k < 3; k++)
        n[k] = len > 0 ? n[k] / len : 0;
}

/* The coarser triangle other than g with corners p and q (the first one), or NONE. */
static uint32_t across(const refine *R, uint32_t g, uint32_t p, uint32_t q)
{
    for (uint32_t i = R->ring_start[p]; i < R->ring_start[p + 1]; i++) {
        uint32_t h = R->ring[i];
        const uint32_t *t = R->c->triangles + 3 * (uint64_t)h;
        if (h != g && (t[0] == q || t[1] == q || t[2] == q))
            return h;
    }
    return NONE;
}

/* Where the chord from u's target (in coarser triangle g) to w's leaves g: the chord
 * parameter at which it crosses the plane through one of g's edges that halves the
 * dihedral angle there (the plane through the edge along the sum of the two triangles'
 * normals; g's normal at a boundary), the first such crossing. 0 when the chord does not
 * leave g through the inside of one. */
static double chord_exit(const refine *R, uint32_t g, const double tu[3], const double d[3],
                         int *edge)
{
    double n[3], exit = INFINITY;
    face_normal(R, g, n);
    if (!(sl_dot3(n, n) > 0))
        return 0;
    const uint32_t *t = R->c->triangles + 3 * (uint64_t)g;
    for (int k = 0; k < 3; k++) {
        double p[3], q[3], pq[3], rel[3], m[3], o[3];
        mr_corner(R->c, g, k, p), mr_corner(R->c, g, (k + 1) % 3, q);
        uint32_t h = across(R, g, t[k], t[(k + 1) % 3]);
        double nh[3] = {0, 0, 0};
        if (h != NONE)
            face_normal(R, h, nh);
        for (int j = 0; j < 3; j++)
            pq[j] = q[j] - p[j], rel[j] = p[j] - tu[j], m[j] = n[j] + nh[j];
        if (sl_dot3(m, n) <= 0.05) /* folded flat onto itself: g's own normal */
            memcpy(m, n, sizeof m);
        sl_cross3(pq, m, o); /* outward for a counter-clockwise triangle */
        double den = sl_dot3(d, o);
        if (den > 0 && sl_dot3(rel, o) / den < exit)
            exit = sl_dot3(rel, o) / den, *edge = k;
    }
    return isfinite(exit) && exit > 0 ? exit : 0;
}

/* The first coarser edge the weight-1 chord from u's target to w's crosses, walking from
 * the coarser triangle of u's it leaves last: the chord parameter (0: none) and there
 * *g, *e (edge e of g). */
static double chord_step(const refine *R, uint32_t u, uint32_t w, uint32_t *g, int *e)
{
    double tu[3], tw[3], d[3], best = 0;
    uint32_t m[MEMBERS_MAX];
    int n = mr_members(R, u, m);
    mr_target_of(R, u, tu), mr_target_of(R, w, tw);
    for (int k = 0; k < 3; k++)
        d[k] = tw[k] - tu[k];
    for (int i = 0; i < n; i++) {
        int edge = 0;
        double l = chord_exit(R, m[i], tu, d, &edge);
        if (l > best)
            best = l, *g = m[i], *e = edge;
    }
    /* a step must leave both ends by more than "lies in": no splits closing in on one */
    double len = sqrt(sl_dot3(d, d)), eps = sqrt(R->eps2);
    return best * len > eps && (1 - best) * len > eps ? best : 0;
}

/* A binary heap of coarser vertices by path length, with lazy deletion. */
static void heap_push(refine *R, uint32_t v, double key)
{
    if (R->heap_n == R->heap_cap) {
        uint64_t cap = 2 * R->heap_cap + 256;
        void *a = realloc(R->heap_v, cap * sizeof *R->heap_v), *b = a ? realloc(R->heap_k, cap * sizeof *R->heap_k) : NULL;
        if (a)
            R->heap_v = a;
        if (!b)
            return; /* out of memory: the path search only ends sooner */
        R->heap_k = b, R->heap_cap = cap;
    }
    uint64_t i = R->heap_n++;
    while (i && R->heap_k[(i - 1) / 2] > key) {
        R->heap_v[i] = R->heap_v[(i - 1) / 2], R->heap_k[i] = R->heap_k[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    R->heap_v[i] = v, R->heap_k[i] = key;
}

static uint32_t heap_pop(refine *R)
{
    for (;;) {
        uint32_t v = R->heap_v[0];
        double key = R->heap_k[0];
        uint32_t lv = R->heap_v[--R->heap_n];
        double lk = R->heap_k[R->heap_n];
        uint64_t i = 0;
        for (;;) {
            uint64_t c = 2 * i + 1;
            if (c >= R->heap_n)
                break;
            if (c + 1 < R->heap_n && R->heap_k[c + 1] < R->heap_k[c])
                c++;
            if (R->heap_k[c] >= lk)
                break;
            R->heap_v[i] = R->heap_v[c], R->heap_k[i] = R->heap_k[c], i = c;
        }
        if (R->heap_n)
            R->heap_v[i] = lv, R->heap_k[i] = lk;
        if (key <= R->dist[v] || !R->heap_n)
            return v;
    }
}

static void relax(refine *R, uint32_t v, double d, uint32_t from)
{
    if (R->stamp[v] == R->stamp_now && R->dist[v] <= d)
        return;
    R->stamp[v] = R->stamp_now, R->dist[v] = d, R->prev[v] = from;
    heap_push(R, v, d);
}

/* Across a gap of the closest-point map (u's and w's targets on sheets of the coarser
 * surface whose chord crosses no coarser edge from either end): the first coarser vertex,
 * beyond u's target, of the shortest path along coarser edges from the corners of u's
 * triangles to a corner of w's (Dijkstra, at most MORPH_PATH_SETTLE vertices settled).
 * Returns the fraction of the path's length it is at (0: no path), *p the vertex, *g a
 * triangle of it. */
#define MORPH_PATH_SETTLE 4096
static double path_step(refine *R, uint32_t u, uint32_t w, uint32_t *p, uint32_t *g)
{
    uint32_t mu[MEMBERS_MAX], mw[MEMBERS_MAX];
    int nu = mr_members(R, u, mu), nw = mr_members(R, w, mw);
    double tu[3], tw[3];
    mr_target_of(R, u, tu), mr_target_of(R, w, tw);
    R->stamp_now++;
    R->heap_n = 0;
    for (int i = 0; i < nu; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = R->c->triangles[3 * (uint64_t)mu[i] + k];
            double c[3], d2 = 0;
            const float *q = R->c->positions + 3 * (uint64_t)v;
            c[0] = q[0], c[1] = q[1], c[2] = q[2];
            for (int j = 0; j < 3; j++)
                d2 += (c[j] - tu[j]) * (c[j] - tu[j]);
            relax(R, v, sqrt(d2), NONE);
        }
    for (int settled = 0; R->heap_n && settled < MORPH_PATH_SETTLE; settled++) {
        uint32_t v = heap_pop(R);
        int goal = 0;
        for (int i = 0; i < nw && !goal; i++)
            for (int k = 0; k < 3; k++)
                goal |= R->c->triangles[3 * (uint64_t)mw[i] + k] == v;
        if (goal) {
            double end[3], rest = 0;
            const float *q = R->c->positions + 3 * (uint64_t)v;
            end[0] = q[0], end[1] = q[1], end[2] = q[2];
            for (int j = 0; j < 3; j++)
                rest += (end[j] - tw[j]) * (end[j] - tw[j]);
            double total = R->dist[v] + sqrt(rest);
            uint32_t first = v; /* the path's first vertex more than eps from tu */
            for (uint32_t x = v; x != NONE; x = R->prev[x])
                if (R->dist[x] > sqrt(R->eps2))
                    first = x;
            if (!(total > 0) || !(R->dist[first] > sqrt(R->eps2)))
                return 0;
            *p = first, *g = R->ring[R->ring_start[first]];
            return R->dist[first] / total;
        }
        for (uint32_t i = R->ring_start[v]; i < R->ring_start[v + 1]; i++)
            for (int k = 0; k < 3; k++) {
                uint32_t x = R->c->triangles[3 * (uint64_t)R->ring[i] + k];
                const float *a = R->c->positions + 3 * (uint64_t)v, *b = R->c->positions + 3 * (uint64_t)x;
                double l = sqrt(((double)a[0] - b[0]) * ((double)a[0] - b[0]) + ((double)a[1] - b[1]) * ((double)a[1] - b[1]) + ((double)a[2] - b[2]) * ((double)a[2] - b[2]));
                relax(R, x, R->dist[v] + l, v);
            }
    }
    return 0;
}

/* The fraction along edge (u, w) at weight 0 closest to point t, inside (0, 1): where a
 * new vertex of the edge targeting t goes, so that it travels as little as the edge
 * allows (any fraction keeps the weight-0 surface, and the targets decide the splits). */
static double nearest_fraction(const refine *R, uint32_t u, uint32_t w, const double t[3])
{
    double pu[3], pw[3], d[3], rel[3];
    mr_position_of(R, u, pu), mr_position_of(R, w, pw);
    for (int k = 0; k < 3; k++)
        d[k] = pw[k] - pu[k], rel[k] = t[k] - pu[k];
    double dd = sl_dot3(d, d), s = dd > 0 ? sl_dot3(rel, d) / dd : 0.5;
    return s < 1e-6 ? 1e-6 : s > 1 - 1e-6 ? 1 - 1e-6 : s;
}

/* Whether a vertex at fraction s of edge (u, w) may target t: travels no farther than
 * the bound. */
static int travel_ok(const refine *R, uint32_t u, uint32_t w, double s, const double t[3])
{
    double pu[3], pw[3], d2 = 0;
    mr_position_of(R, u, pu), mr_position_of(R, w, pw);
    for (int k = 0; k < 3; k++) {
        double d = pu[k] + s * (pw[k] - pu[k]) - t[k];
        d2 += d * d;
    }
    return d2 <= R->travel2;
}

/* The vertex splitting edge (u, w) where its weight-1 chord crosses the first coarser
 * edge from u's end (or, failing that, the last before w's): its target is that point of
 * the coarser edge, its weight-0 position the point of (u, w) nearest to it. NONE when the
 * chord crosses no coarser edge from either end: the targets are on sheets of the coarser
 * surface that do not meet there (a fold, a thin part), which no split mends. */
uint32_t mr_split_edge(refine *R, uint32_t u, uint32_t w)
{
    uint32_t g = NONE, v[2] = {u, w};
    int e = 0;
    double s = chord_step(R, u, w, &g, &e), from[3], to[3], a[3], b[3], q[3], t[3];
    mr_target_of(R, u, from), mr_target_of(R, w, to);
    if (s == 0 && (s = chord_step(R, w, u, &g, &e)) > 0)
        s = 1 - s;
    if (s > 0) {
        for (int k = 0; k < 3; k++)
            q[k] = from[k] + s * (to[k] - from[k]);
    } else {
        uint32_t pv = 0;
        if ((s = path_step(R, u, w, &pv, &g)) == 0)
            return NONE;
        const float *c = R->c->positions + 3 * (uint64_t)pv;
        for (int k = 0; k < 3; k++)
            t[k] = c[k];
        s = nearest_fraction(R, u, w, t);
        if (!travel_ok(R, u, w, s, t))
            return NONE;
        double f[2] = {1 - s, s};
        return mr_add_vertex(R, 2, v, f, t, g);
    }
    mr_corner(R->c, g, e, a), mr_corner(R->c, g, (e + 1) % 3, b);
    sl_closest_point_triangle(q, a, b, b, t); /* onto the coarser edge itself */
    s = nearest_fraction(R, u, w, t);
    if (!travel_ok(R, u, w, s, t))
        return NONE;
    double f[2] = {1 - s, s};
    return mr_add_vertex(R, 2, v, f, t, g);
}

/* The barycentrics in triangle v[0..2] at weight 0 of its point nearest to p, each at
 * least 1e-6 (the new vertex stays inside): where a vertex targeting p goes. */
static void weight0_barycentrics(const refine *R, const uint32_t v[3], const double p[3],
                                 double l[3])
{
    double x[3][3], q[3], n[3], e1[3], e2[3], sum = 0;
    for (int j = 0; j < 3; j++)
        mr_position_of(R, v[j], x[j]);
    sl_closest_point_triangle(p, x[0], x[1], x[2], q);
    for (int k = 0; k < 3; k++)
        e1[k] = x[1][k] - x[0][k], e2[k] = x[2][k] - x[0][k];
    sl_cross3(e1, e2, n);
    for (int j = 0; j < 3; j++) { /* sub-triangle areas, signed along n */
        double u[3], w[3], c[3];
        for (int k = 0; k < 3; k++)
            u[k] = x[(j + 1) % 3][k] - q[k], w[k] = x[(j + 2) % 3][k] - q[k];
        sl_cross3(u, w, c);
        l[j] = sl_dot3(c, n);
        l[j] = l[j] > 0 ? l[j] : 0;
        sum += l[j];
    }
    for (int j = 0; j < 3; j++)
        l[j] = sum > 0 ? l[j] / sum : 1.0 / 3;
    sum = 0;
    for (int j = 0; j < 3; j++)
        sum += l[j] = l[j] < 1e-6 ? 1e-6 : l[j];
    for (int j = 0; j < 3; j++)
        l[j] /= sum;
}

/* Triangle (a, b, c) spans a coarser vertex that a triangle of each target's has: a
 * vertex targeting it, inside (a, b, c), or NONE when there is none. */
uint32_t mr_split_triangle(refine *R, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t ma[MEMBERS_MAX], mb[MEMBERS_MAX], mc[MEMBERS_MAX];
    int na = mr_members(R, a, ma), nb = mr_members(R, b, mb), nc = mr_members(R, c, mc);
    for (int i = 0; i < na; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t cv = R->c->triangles[3 * (uint64_t)ma[i] + k];
            int in_b = 0, in_c = 0;
            for (int j = 0; j < nb * 3 && !in_b; j++)
                in_b = R->c->triangles[3 * (uint64_t)mb[j / 3] + j % 3] == cv;
            for (int j = 0; j < nc * 3 && !in_c; j++)
                in_c = R->c->triangles[3 * (uint64_t)mc[j / 3] + j % 3] == cv;
            if (!in_b || !in_c)
                continue;
            double p[3], t[3][3], l[3];
            const float *q = R->c->positions + 3 * (uint64_t)cv;
            p[0] = q[0], p[1] = q[1], p[2] = q[2];
            mr_target_of(R, a, t[0]), mr_target_of(R, b, t[1]), mr_target_of(R, c, t[2]);
            int there = 0; /* a corner targets it already: another vertex there mends nothing */
            for (int j = 0; j < 3; j++) {
                double d2 = 0;
                for (int h = 0; h < 3; h++)
                    d2 += (t[j][h] - p[h]) * (t[j][h] - p[h]);
                there |= d2 <= R->eps2;
            }
            if (there)
                continue;
            double e1[3], e2[3], n[3], sum = 0;
            for (int j = 0; j < 3; j++)
                e1[j] = t[1][j] - t[0][j], e2[j] = t[2][j] - t[0][j];
            sl_cross3(e1, e2, n);
            for (int j = 0; j < 3; j++) { /* barycentrics from sub-triangle areas */
                double u[3], w[3], s[3];
                for (int h = 0; h < 3; h++)
                    u[h] = t[(j + 1) % 3][h] - p[h], w[h] = t[(j + 2) % 3][h] - p[h];
                sl_cross3(u, w, s);
                l[j] = sl_dot3(s, n);
                sum += l[j];
            }
            int inside = sum > 0;
            for (int j = 0; j < 3; j++)
                inside &= l[j] >= -1e-9 * sum;
            /* the weight-1 triangle reaches over the vertex, or nothing else mends it */
            if (!inside && !(mr_share(R, a, b, NONE) && mr_share(R, b, c, NONE) && mr_share(R, c, a, NONE)))
                continue;
            uint32_t v[3] = {a, b, c};
            weight0_barycentrics(R, v, p, l);
            { /* no farther than the travel bound */
                double x[3] = {0, 0, 0}, y[3], d2 = 0;
                for (int j = 0; j < 3; j++) {
                    mr_position_of(R, v[j], y);
                    for (int h = 0; h < 3; h++)
                        x[h] += l[j] * y[h];
                }
                for (int h = 0; h < 3; h++)
                    d2 += (x[h] - p[h]) * (x[h] - p[h]);
                if (d2 > R->travel2)
                    continue;
            }
            return mr_add_vertex(R, 3, v, l, p, ma[i]);
        }
    return NONE;
}
