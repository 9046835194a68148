/* Test polygons for the constrained Delaunay triangulation and a brute-force checker of
 * its contract (tests/unit/test_cdt.c). The checker uses only the exact predicates and
 * the input, never the triangulation's own bookkeeping:
 *  - every triangle counter-clockwise with positive area, indices in range;
 *  - every loop edge, split at the input points exactly on it, an edge of the output;
 *  - edge-manifold: a directed edge at most once, a loop piece in one triangle, every
 *    other edge in two; Euler characteristic V - E + F = 1 - holes;
 *  - tiling: the triangles' areas sum to the polygon's, no centroid outside the outer loop
 *    or inside a hole (exact crossing-number test);
 *  - constrained Delaunay: every interior non-loop edge locally Delaunay, and by brute
 *    force no used point strictly inside a triangle's circumcircle and visible from
 *    sample points of its interior (loop pieces block sight).
 */
#ifndef SCANLOD_TESTS_CDT_CHECKS_H
#define SCANLOD_TESTS_CDT_CHECKS_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/cdt.h"
#include "geometry/predicates.h"
#include "tests/check.h"

typedef struct poly {
    uint32_t n, cap;
    double *xy;
    uint32_t loops, nidx, idxcap;
    uint32_t start[65];
    uint32_t *idx;
} poly;

static void poly_init(poly *p)
{
    memset(p, 0, sizeof *p);
}

static void poly_release(poly *p)
{
    free(p->xy);
    free(p->idx);
    poly_init(p);
}

static uint32_t poly_point(poly *p, double x, double y)
{
    if (p->n == p->cap) {
        p->cap = p->cap ? 2 * p->cap : 64;
        p->xy = realloc(p->xy, 2 * (size_t)p->cap * sizeof *p->xy);
    }
    p->xy[2 * p->n] = x, p->xy[2 * p->n + 1] = y;
    return p->n++;
}

/* Appends point v to the loop being built (loops end with poly_close). */
static void poly_loop_add(poly *p, uint32_t v)
{
    if (p->nidx == p->idxcap) {
        p->idxcap = p->idxcap ? 2 * p->idxcap : 64;
        p->idx = realloc(p->idx, p->idxcap * sizeof *p->idx);
    }
    p->idx[p->nidx++] = v;
}

static void poly_close(poly *p)
{
    p->start[++p->loops] = p->nidx;
}

static sl_cdt_input poly_input(const poly *p)
{
    sl_cdt_input in = {p->n, p->xy, p->loops, p->start, p->idx};
    return in;
}

static const double *P(const poly *p, uint32_t v)
{
    return p->xy + 2 * (size_t)v;
}

/* Exact even-odd test of q against every loop (q on no loop edge). */
static int poly_contains(const poly *p, const double *q)
{
    int inside = 0;
    for (uint32_t l = 0; l < p->loops; l++)
        for (uint32_t k = p->start[l]; k < p->start[l + 1]; k++) {
            uint32_t nk = k + 1 == p->start[l + 1] ? p->start[l] : k + 1;
            const double *a = P(p, p->idx[k]), *b = P(p, p->idx[nk]);
            if ((a[1] <= q[1]) != (b[1] <= q[1])) {
                int o = sl_orient2d(a, b, q);
                inside ^= b[1] > a[1] ? o > 0 : o < 0;
            }
        }
    return inside;
}

static double poly_area(const poly *p)
{
    double area = 0;
    const double *o = p->n ? P(p, 0) : NULL; /* relative to a point: no cancellation */
    for (uint32_t l = 0; l < p->loops; l++)
        for (uint32_t k = p->start[l]; k < p->start[l + 1]; k++) {
            uint32_t nk = k + 1 == p->start[l + 1] ? p->start[l] : k + 1;
            const double *a = P(p, p->idx[k]), *b = P(p, p->idx[nk]);
            area += 0.5 * ((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]));
        }
    return area; /* outer counter-clockwise, holes clockwise: the net area */
}

/* Closed segments a-b and c-d share a point. */
static int segments_touch(const double *a, const double *b, const double *c, const double *d)
{
    int o1 = sl_orient2d(a, b, c), o2 = sl_orient2d(a, b, d);
    int o3 = sl_orient2d(c, d, a), o4 = sl_orient2d(c, d, b);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return 1;
    const double *s[4][3] = {{a, b, c}, {a, b, d}, {c, d, a}, {c, d, b}};
    int o[4] = {o1, o2, o3, o4};
    for (int i = 0; i < 4; i++) /* a collinear endpoint within the other segment */
        if (o[i] == 0 && fmin(s[i][0][0], s[i][1][0]) <= s[i][2][0] &&
            s[i][2][0] <= fmax(s[i][0][0], s[i][1][0]) &&
            fmin(s[i][0][1], s[i][1][1]) <= s[i][2][1] && s[i][2][1] <= fmax(s[i][0][1], s[i][1][1]))
            return 1;
    return 0;
}

static int cmp_u64_(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

static uint64_t ukey(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

static int has_key(const uint64_t *keys, size_t n, uint64_t k)
{
    return bsearch(&k, keys, n, sizeof *keys, cmp_u64_) != NULL;
}

/* Strictly between a and b on their (exact) line. */
static int strictly_between(const double *a, const double *b, const double *x)
{
    int axis = a[0] != b[0] ? 0 : 1;
    return fmin(a[axis], b[axis]) < x[axis] && x[axis] < fmax(a[axis], b[axis]);
}

/* The loop edges split at the points lying on them, as sorted undirected keys. */
static uint64_t *loop_pieces(const poly *p, size_t *count)
{
    uint64_t *keys = NULL;
    size_t n = 0, cap = 0;
    uint32_t *on = malloc((p->n + 2) * sizeof *on);
    for (uint32_t l = 0; l < p->loops; l++)
        for (uint32_t k = p->start[l]; k < p->start[l + 1]; k++) {
            uint32_t a = p->idx[k], b = p->idx[k + 1 == p->start[l + 1] ? p->start[l] : k + 1];
            uint32_t m = 0;
            on[m++] = a;
            for (uint32_t v = 0; v < p->n; v++)
                if (v != a && v != b && sl_orient2d(P(p, a), P(p, b), P(p, v)) == 0 &&
                    strictly_between(P(p, a), P(p, b), P(p, v)))
                    on[m++] = v;
            on[m++] = b;
            int axis = P(p, a)[0] != P(p, b)[0] ? 0 : 1, up = P(p, b)[axis] > P(p, a)[axis];
            for (uint32_t i = 2; i + 1 < m; i++) /* insertion sort along the edge */
                for (uint32_t j = i; j > 1; j--) {
                    double x0 = P(p, on[j - 1])[axis], x1 = P(p, on[j])[axis];
                    if (up ? x1 < x0 : x1 > x0) {
                        uint32_t t = on[j];
                        on[j] = on[j - 1], on[j - 1] = t;
                    }
                }
            for (uint32_t i = 0; i + 1 < m; i++) {
                if (n == cap)
                    keys = realloc(keys, (cap = cap ? 2 * cap : 256) * sizeof *keys);
                keys[n++] = ukey(on[i], on[i + 1]);
            }
        }
    free(on);
    qsort(keys, n, sizeof *keys, cmp_u64_);
    *count = n;
    return keys;
}

/* q strictly inside triangle t */
static int inside_triangle(const double *a, const double *b, const double *c, const double *q)
{
    return sl_orient2d(a, b, q) > 0 && sl_orient2d(b, c, q) > 0 && sl_orient2d(c, a, q) > 0;
}

/* The segment q-v meets a loop piece anywhere but at v. */
static int sight_blocked(const poly *p, const uint64_t *pieces, size_t npieces, const double *q,
                         uint32_t v)
{
    const double *pv = P(p, v);
    for (size_t i = 0; i < npieces; i++) {
        uint32_t a = (uint32_t)(pieces[i] >> 32), b = (uint32_t)pieces[i];
        if (a == v || b == v) {
            uint32_t o = a == v ? b : a; /* only blocks if the piece runs along q-v */
            if (sl_orient2d(q, pv, P(p, o)) == 0 && strictly_between(q, pv, P(p, o)))
                return 1;
            continue;
        }
        if (segments_touch(q, pv, P(p, a), P(p, b)))
            return 1;
    }
    return 0;
}

/* Checks r against every property above; `holes` for the Euler characteristic (< 0 to
 * skip); `brute` runs the O(triangles x points) circumcircle test. Returns failures. */
static int cdt_verify(const char *name, const poly *p, const sl_cdt_result *r, int holes,
                      int brute)
{
    int before = check_failed_;
    uint64_t T = r->triangle_count;
    const uint32_t *t = r->triangles;
    size_t npieces;
    uint64_t *pieces = loop_pieces(p, &npieces);
    uint64_t *dir = malloc((3 * T + 1) * sizeof *dir), *und = malloc((3 * T + 1) * sizeof *und);
    uint8_t *used = calloc(p->n + 1, 1);
    int bad_ccw = 0, bad_centroid = 0;
    double area = 0;
    for (uint64_t i = 0; i < T; i++) {
        const uint32_t *v = t + 3 * i;
        if (v[0] >= p->n || v[1] >= p->n || v[2] >= p->n) {
            CHECK_MSG(0, "%s: triangle %llu has an index out of range", name,
                      (unsigned long long)i);
            goto out;
        }
        bad_ccw += sl_orient2d(P(p, v[0]), P(p, v[1]), P(p, v[2])) <= 0;
        const double *a = P(p, v[0]), *b = P(p, v[1]), *c = P(p, v[2]);
        area += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
        double g[2] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3};
        if (inside_triangle(a, b, c, g)) /* a sliver's rounded centroid may fall outside */
            bad_centroid += !poly_contains(p, g);
        for (int k = 0; k < 3; k++) {
            dir[3 * i + k] = (uint64_t)v[k] << 32 | v[(k + 1) % 3];
            und[3 * i + k] = ukey(v[k], v[(k + 1) % 3]);
            used[v[k]] = 1;
        }
    }
    CHECK_MSG(bad_ccw == 0, "%s: %d triangles not counter-clockwise", name, bad_ccw);
    CHECK_MSG(bad_centroid == 0, "%s: %d centroids outside the polygon or in a hole", name,
              bad_centroid);
    double want = poly_area(p), tol = 1e-12 * fabs(want) + 1e-300;
    CHECK_MSG(fabs(area - want) <= tol, "%s: triangles cover %.17g, the polygon %.17g", name,
              area, want);
    qsort(dir, 3 * T, sizeof *dir, cmp_u64_);
    qsort(und, 3 * T, sizeof *und, cmp_u64_);
    int twice = 0, bad_count = 0, missing = 0;
    for (uint64_t i = 1; i < 3 * T; i++)
        twice += dir[i] == dir[i - 1];
    uint64_t edges = 0;
    for (uint64_t i = 0; i < 3 * T;) {
        uint64_t j = i;
        while (j < 3 * T && und[j] == und[i])
            j++;
        bad_count += (j - i) != (has_key(pieces, npieces, und[i]) ? 1u : 2u);
        edges++;
        i = j;
    }
    for (size_t i = 0; i < npieces; i++)
        missing += !has_key(und, 3 * T, pieces[i]);
    CHECK_MSG(twice == 0, "%s: %d directed edges in two triangles", name, twice);
    CHECK_MSG(bad_count == 0, "%s: %d edges with the wrong number of triangles", name,
              bad_count);
    CHECK_MSG(missing == 0, "%s: %d of %zu loop pieces are not triangle edges", name, missing,
              npieces);
    uint64_t nv = 0;
    for (uint32_t v = 0; v < p->n; v++)
        nv += used[v];
    if (holes >= 0)
        CHECK_MSG((int64_t)nv - (int64_t)edges + (int64_t)T == 1 - holes,
                  "%s: V - E + F = %lld, want %d", name,
                  (long long)nv - (long long)edges + (long long)T, 1 - holes);
    /* Local Delaunay across every non-loop edge: the apex over the twin edge is not
     * inside. Directed edges carry their triangle (low bits: 3 * triangle + corner). */
    int not_local = 0;
    for (uint64_t i = 0; i < 3 * T; i++)
        dir[i] = (uint64_t)t[i] << 40 | (uint64_t)t[i - i % 3 + (i + 1) % 3] << 20 | i;
    qsort(dir, 3 * T, sizeof *dir, cmp_u64_);
    for (uint64_t i = 0; i < 3 * T && p->n < (1u << 20) && 3 * T < (1u << 20); i++) {
        uint32_t a = t[i], b = t[i - i % 3 + (i + 1) % 3];
        if (has_key(pieces, npieces, ukey(a, b)))
            continue;
        uint64_t lo = 0, hi = 3 * T, want_key = (uint64_t)b << 40 | (uint64_t)a << 20;
        while (lo < hi) { /* the first directed edge b -> a */
            uint64_t mid = (lo + hi) / 2;
            if (dir[mid] < want_key)
                lo = mid + 1;
            else
                hi = mid;
        }
        if (lo == 3 * T || dir[lo] >> 20 != want_key >> 20)
            continue; /* counted above as an edge with one triangle */
        uint64_t j = dir[lo] & 0xfffff, base = i - i % 3;
        not_local += sl_incircle(P(p, t[base]), P(p, t[base + 1]), P(p, t[base + 2]),
                                 P(p, t[j - j % 3 + (j + 2) % 3])) > 0;
    }
    CHECK_MSG(not_local == 0, "%s: %d edges not locally Delaunay", name, not_local);
    int visible_bad = 0;
    for (uint64_t i = 0; brute && i < T; i++) {
        const uint32_t *v = t + 3 * i;
        const double *a = P(p, v[0]), *b = P(p, v[1]), *c = P(p, v[2]);
        for (uint32_t q = 0; q < p->n; q++) {
            if (!used[q] || sl_incircle(a, b, c, P(p, q)) <= 0)
                continue;
            double g[2] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3}, s[7][2];
            for (int k = 0; k < 3; k++) {
                const double *x = P(p, v[k]), *y = P(p, v[(k + 1) % 3]);
                s[k][0] = (x[0] + g[0]) / 2, s[k][1] = (x[1] + g[1]) / 2;
                s[3 + k][0] = ((x[0] + y[0]) / 2 + g[0]) / 2;
                s[3 + k][1] = ((x[1] + y[1]) / 2 + g[1]) / 2;
            }
            s[6][0] = g[0], s[6][1] = g[1];
            int seen = 0;
            for (int k = 0; k < 7 && !seen; k++)
                seen = inside_triangle(a, b, c, s[k]) && !sight_blocked(p, pieces, npieces, s[k], q);
            visible_bad += seen;
        }
    }
    CHECK_MSG(visible_bad == 0, "%s: %d visible points inside circumcircles", name, visible_bad);
out:
    free(pieces);
    free(dir);
    free(und);
    free(used);
    return check_failed_ - before;
}

#endif
