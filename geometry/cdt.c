/* Constrained Delaunay triangulation, part 1: input checks, point insertion, the
 * inside/outside classification and the output (loop edges: cdt_constrain.c).
 *
 * Method. Points are inserted one by one into a bounding triangle (Lawson's algorithm:
 * locate, split the triangle or edge hit, flip edges whose opposite vertex is inside the
 * new triangle's circumcircle until all are locally Delaunay). They come in Hilbert-curve
 * order, and each walk starts from the previous point's triangle, so a walk crosses a few
 * triangles and insertion is O(n log n) for the sort plus O(n) expected work. Then the
 * loop edges are forced in (cdt_constrain.c), and a flood fill from the bounding triangle
 * counts signed loop crossings: the winding number of every triangle, from which its
 * inside/outside state and any fold follow, with no point-in-polygon geometry.
 *
 * Every geometric decision is an exact predicate (geometry/predicates.h), so the
 * combinatorics cannot contradict each other; degenerate input (cocircular grids,
 * collinear runs) only chooses among equally valid triangulations, always the same way.
 */
#include "geometry/cdt.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/cdt_internal.h"
#include "geometry/predicates.h"

static int check_input(cdt_work *w, const sl_cdt_input *in)
{
    if (in->point_count > SL_CDT_MAX_POINTS)
        return sl_error_set(w->err, SL_E_LIMIT, 0, NULL,
                            "triangulation of %u points: at most %u", in->point_count,
                            SL_CDT_MAX_POINTS);
    if ((in->point_count && !in->points) || (in->loop_count && !in->loop_start))
        return sl_error_set(w->err, SL_E_BADINPUT, 0, NULL, "triangulation input: NULL array");
    for (uint32_t i = 0; i < in->point_count; i++) {
        double x = in->points[2 * (uint64_t)i], y = in->points[2 * (uint64_t)i + 1];
        if (!(fabs(x) <= SL_CDT_MAX_COORDINATE && fabs(y) <= SL_CDT_MAX_COORDINATE))
            return cdt_refuse(w, SL_CDT_NONFINITE, i, CDT_NONE, CDT_NONE, CDT_NONE,
                              "point %u is (%g, %g): not finite or beyond 2^500", i, x, y);
    }
    if (in->loop_count == 0)
        return SL_OK;
    uint32_t total = in->loop_start[in->loop_count];
    if (total > SL_CDT_MAX_LOOP_POINTS)
        return sl_error_set(w->err, SL_E_LIMIT, 0, NULL, "%u loop points: at most %u", total,
                            SL_CDT_MAX_LOOP_POINTS);
    if (total && !in->loop_points)
        return sl_error_set(w->err, SL_E_BADINPUT, 0, NULL, "triangulation input: NULL loops");
    for (uint32_t l = 0; l < in->loop_count; l++) {
        uint32_t s = in->loop_start[l], e = in->loop_start[l + 1];
        if ((l == 0 && s != 0) || e < s || e > total)
            return cdt_refuse(w, SL_CDT_BAD_INDEX, l, CDT_NONE, CDT_NONE, CDT_NONE,
                              "loop %u: start offsets %u..%u are not ascending from 0", l, s, e);
        for (uint32_t k = s; k < e; k++)
            if (in->loop_points[k] >= in->point_count)
                return cdt_refuse(w, SL_CDT_BAD_INDEX, l, in->loop_points[k], CDT_NONE,
                                  CDT_NONE, "loop %u names point %u of %u", l,
                                  in->loop_points[k], in->point_count);
    }
    return SL_OK;
}

static int allocate(cdt_work *w, uint32_t n)
{
    /* Every insertion adds two triangles to the first one; loop edges add none. */
    uint64_t tri_cap = 1 + 2 * (uint64_t)n, bytes;
    w->n = n;
    w->xy = malloc(2 * ((uint64_t)n + 3) * sizeof *w->xy);
    if (!__builtin_mul_overflow(tri_cap, sizeof *w->tri, &bytes))
        w->tri = malloc(bytes);
    w->vt = malloc(((uint64_t)n + 3) * sizeof *w->vt);
    w->rep = malloc(((uint64_t)n + 1) * sizeof *w->rep);
    w->stack = malloc(tri_cap * sizeof *w->stack);
    w->crossed = malloc(tri_cap * sizeof *w->crossed);
    if (!w->xy || !w->tri || !w->vt || !w->rep || !w->stack || !w->crossed)
        return sl_error_set(w->err, SL_E_NOMEM, 0, NULL, "triangulation of %u points", n);
    for (uint32_t v = 0; v < n + 3; v++)
        w->vt[v] = CDT_NONE;
    for (uint32_t v = 0; v < n; v++)
        w->rep[v] = v;
    return SL_OK;
}

/* The bounding triangle: 20 bounding-box sizes around the points (never thinner than
 * 2^-40 of the coordinates' magnitude, so its corners differ from the centre after
 * rounding). Its corners only need to contain the points: every triangle touching them is
 * outside the loops and never output. */
static int place_super_triangle(cdt_work *w, const double *pts)
{
    uint32_t n = w->n;
    double lo[2] = {0, 0}, hi[2] = {0, 0};
    for (uint32_t i = 0; i < n; i++)
        for (int a = 0; a < 2; a++) {
            double x = pts[2 * (uint64_t)i + a];
            lo[a] = i == 0 || x < lo[a] ? x : lo[a];
            hi[a] = i == 0 || x > hi[a] ? x : hi[a];
        }
    if (n)
        memcpy(w->xy, pts, 2 * (uint64_t)n * sizeof *pts);
    double cx = 0.5 * lo[0] + 0.5 * hi[0], cy = 0.5 * lo[1] + 0.5 * hi[1];
    double d = fmax(hi[0] - lo[0], hi[1] - lo[1]);
    d = fmax(d, fmax(fabs(cx), fabs(cy)) * 0x1p-40);
    d = fmax(d, 0x1p-1000);
    double *s = w->xy + 2 * (uint64_t)n;
    s[0] = cx - 20 * d, s[1] = cy - 10 * d;
    s[2] = cx + 20 * d, s[3] = cy - 10 * d;
    s[4] = cx, s[5] = cy + 20 * d;
    for (uint32_t i = 0; i < n; i++)
        for (int e = 0; e < 3; e++)
            if (sl_orient2d(s + 2 * e, s + 2 * ((e + 1) % 3), cdt_xy(w, i)) <= 0)
                return sl_error_set(w->err, SL_E_INTERNAL, 0, NULL,
                                    "bounding triangle does not contain point %u", i);
    cdt_tri *t = &w->tri[0];
    t->v[0] = n, t->v[1] = n + 1, t->v[2] = n + 2;
    t->n[0] = t->n[1] = t->n[2] = CDT_NONE;
    t->flags = 0;
    w->tri_count = 1;
    w->vt[n] = w->vt[n + 1] = w->vt[n + 2] = 0;
    return SL_OK;
}

/* Distance along a Hilbert curve filling a 2^16 x 2^16 grid. */
static uint32_t hilbert_index(uint32_t x, uint32_t y)
{
    const uint32_t side = 1u << 16;
    uint32_t d = 0;
    for (uint32_t s = side / 2; s > 0; s /= 2) {
        uint32_t rx = (x & s) != 0, ry = (y & s) != 0;
        d += s * s * ((3 * rx) ^ ry);
        if (ry == 0) { /* rotate the quadrant so the curve stays connected */
            if (rx == 1) {
                x = side - 1 - x;
                y = side - 1 - y;
            }
            uint32_t t = x;
            x = y;
            y = t;
        }
    }
    return d;
}

static int cmp_u64(const void *p, const void *q)
{
    uint64_t a = *(const uint64_t *)p, b = *(const uint64_t *)q;
    return (a > b) - (a < b);
}

/* Insertion order: Hilbert index, then point index (so equal points are consecutive,
 * the lowest first). OUT: order[n] (point index in the low 32 bits). */
static void spatial_order(const cdt_work *w, uint64_t *order)
{
    double lo[2], hi[2];
    for (int a = 0; a < 2; a++) {
        lo[a] = hi[a] = w->xy[a];
        for (uint32_t i = 1; i < w->n; i++) {
            lo[a] = fmin(lo[a], w->xy[2 * (uint64_t)i + a]);
            hi[a] = fmax(hi[a], w->xy[2 * (uint64_t)i + a]);
        }
    }
    double extent = fmax(hi[0] - lo[0], hi[1] - lo[1]);
    double scale = extent > 0 ? 65535.0 / extent : 0;
    for (uint32_t i = 0; i < w->n; i++) {
        uint32_t q[2];
        for (int a = 0; a < 2; a++) {
            double g = (w->xy[2 * (uint64_t)i + a] - lo[a]) * scale;
            q[a] = g >= 65535.0 ? 65535u : (uint32_t)g;
        }
        order[i] = (uint64_t)hilbert_index(q[0], q[1]) << 32 | i;
    }
    qsort(order, w->n, sizeof *order, cmp_u64);
}

static void replace_neighbour(cdt_work *w, uint32_t t, uint32_t old, uint32_t now)
{
    if (t == CDT_NONE)
        return;
    cdt_tri *T = &w->tri[t];
    for (int i = 0; i < 3; i++)
        if (T->n[i] == old)
            T->n[i] = now;
}

static uint64_t coin(cdt_work *w)
{
    w->rng ^= w->rng << 13, w->rng ^= w->rng >> 7, w->rng ^= w->rng << 17;
    return w->rng;
}

/* Where p is in triangle t: 0 inside, 1 + i on edge i, 4 + i on vertex v[i]; -1 if
 * outside (the edge to cross is then *exit). Edges are tried from a random one: a walk
 * that always tried them in the same order could cycle in a non-Delaunay mesh. */
static int classify_point(const cdt_work *w, uint32_t t, const double *p, int first, int *exit)
{
    const cdt_tri *T = &w->tri[t];
    int zeros = 0, zero_edge = 0;
    for (int k = 0; k < 3; k++) {
        int i = (first + k) % 3;
        int o = sl_orient2d(cdt_xy(w, T->v[(i + 1) % 3]), cdt_xy(w, T->v[(i + 2) % 3]), p);
        if (o < 0) {
            *exit = i;
            return -1;
        }
        if (o == 0)
            zeros++, zero_edge += i;
    }
    if (zeros == 0)
        return 0;
    return zeros == 1 ? 1 + zero_edge : 4 + (3 - zero_edge); /* two zero edges meet at the third vertex */
}

/* The triangle containing p, walking from t; OUT: *where as classify_point says. */
static uint32_t locate(cdt_work *w, const double *p, uint32_t t, int *where)
{
    for (uint64_t steps = 0; steps <= w->tri_count; steps++) {
        int exit;
        *where = classify_point(w, t, p, (int)(coin(w) % 3), &exit);
        if (*where >= 0)
            return t;
        t = w->tri[t].n[exit];
        if (t == CDT_NONE)
            break;
    }
    for (t = 0; t < w->tri_count; t++) { /* never seen; kept so a bug cannot loop forever */
        int exit;
        if ((*where = classify_point(w, t, p, 0, &exit)) >= 0)
            return t;
    }
    return CDT_NONE;
}

/* Lawson's flip of the edge between t = (p, a, b) (p at 0) and u, whose vertex q at j is
 * opposite: t becomes (p, a, q), u becomes (p, q, b). */
static void flip(cdt_work *w, uint32_t t, uint32_t u, int j)
{
    cdt_tri *T = &w->tri[t], *U = &w->tri[u];
    uint32_t p = T->v[0], a = T->v[1], b = T->v[2], q = U->v[j];
    /* Lawson flips only the diagonal of a strictly convex quadrilateral (q is in p's
     * circumcircle of (p, a, b)): both new triangles turn counter-clockwise. */
    assert(sl_orient2d(cdt_xy(w, p), cdt_xy(w, a), cdt_xy(w, q)) > 0);
    assert(sl_orient2d(cdt_xy(w, p), cdt_xy(w, q), cdt_xy(w, b)) > 0);
    assert(T->n[0] == u && U->n[j] == t); /* they are neighbours across edge a-b */
    uint32_t n_aq = U->n[(j + 1) % 3], n_qb = U->n[(j + 2) % 3];
    uint32_t n_pa = T->n[2], n_bp = T->n[1];
    T->v[0] = p, T->v[1] = a, T->v[2] = q;
    T->n[0] = n_aq, T->n[1] = u, T->n[2] = n_pa;
    U->v[0] = p, U->v[1] = q, U->v[2] = b;
    U->n[0] = n_qb, U->n[1] = n_bp, U->n[2] = t;
    replace_neighbour(w, n_aq, u, t);
    replace_neighbour(w, n_bp, t, u);
    w->vt[a] = t, w->vt[b] = u;
}

/* Flips until every triangle on the stack (each has the new point at v[0]) is locally
 * Delaunay across the edge opposite it. */
static void legalize(cdt_work *w, uint32_t sp)
{
    while (sp > 0) {
        uint32_t t = w->stack[--sp];
        cdt_tri *T = &w->tri[t];
        uint32_t u = T->n[0];
        if (u == CDT_NONE)
            continue;
        const cdt_tri *U = &w->tri[u];
        int j = 3 - cdt_index_of(U, T->v[1]) - cdt_index_of(U, T->v[2]);
        if (sl_incircle(cdt_xy(w, T->v[0]), cdt_xy(w, T->v[1]), cdt_xy(w, T->v[2]),
                        cdt_xy(w, U->v[j])) > 0) {
            flip(w, t, u, j);
            w->stack[sp++] = t;
            w->stack[sp++] = u;
        }
    }
}

/* p strictly inside t = (a, b, c): three triangles (p, b, c), (p, c, a), (p, a, b). */
static void split_triangle(cdt_work *w, uint32_t t, uint32_t p)
{
    cdt_tri old = w->tri[t];
    for (int k = 0; k < 3; k++) /* p is strictly inside: every new triangle has area */
        assert(sl_orient2d(cdt_xy(w, old.v[(k + 1) % 3]), cdt_xy(w, old.v[(k + 2) % 3]),
                           cdt_xy(w, p)) > 0);
    uint32_t id[3] = {t, w->tri_count, w->tri_count + 1};
    w->tri_count += 2;
    for (int k = 0; k < 3; k++) {
        cdt_tri *T = &w->tri[id[k]];
        T->v[0] = p, T->v[1] = old.v[(k + 1) % 3], T->v[2] = old.v[(k + 2) % 3];
        T->n[0] = old.n[k], T->n[1] = id[(k + 1) % 3], T->n[2] = id[(k + 2) % 3];
        T->flags = 0;
        if (k > 0)
            replace_neighbour(w, old.n[k], t, id[k]);
        w->vt[old.v[(k + 1) % 3]] = id[k];
        w->stack[k] = id[k];
    }
    w->vt[p] = t;
    legalize(w, 3);
}

static void set_tri(cdt_tri *T, uint32_t v0, uint32_t v1, uint32_t v2, uint32_t n0,
                    uint32_t n1, uint32_t n2)
{
    T->v[0] = v0, T->v[1] = v1, T->v[2] = v2;
    T->n[0] = n0, T->n[1] = n1, T->n[2] = n2;
    T->flags = 0;
}

/* p on edge i of t = (a, b, c) (edge b-c), shared with u = (d, c, b): four triangles
 * A = (p, a, b), B = (p, c, a), C = (p, d, c), D = (p, b, d). */
static void split_edge(cdt_work *w, uint32_t t, int i, uint32_t p)
{
    cdt_tri T = w->tri[t];
    uint32_t u = T.n[i];
    cdt_tri U = w->tri[u];
    uint32_t a = T.v[i], b = T.v[(i + 1) % 3], c = T.v[(i + 2) % 3];
    int j = 3 - cdt_index_of(&U, b) - cdt_index_of(&U, c);
    uint32_t d = U.v[j];
    uint32_t n_ab = T.n[(i + 2) % 3], n_ca = T.n[(i + 1) % 3];
    uint32_t n_dc = U.n[(j + 2) % 3], n_bd = U.n[(j + 1) % 3];
    uint32_t A = t, B = w->tri_count, C = u, D = w->tri_count + 1;
    w->tri_count += 2;
    set_tri(&w->tri[A], p, a, b, n_ab, D, B);
    set_tri(&w->tri[B], p, c, a, n_ca, A, C);
    set_tri(&w->tri[C], p, d, c, n_dc, B, D);
    set_tri(&w->tri[D], p, b, d, n_bd, C, A);
    replace_neighbour(w, n_ca, t, B);
    replace_neighbour(w, n_bd, u, D);
    w->vt[p] = A, w->vt[a] = A, w->vt[b] = A, w->vt[c] = B, w->vt[d] = C;
    w->stack[0] = A, w->stack[1] = B, w->stack[2] = C, w->stack[3] = D;
    legalize(w, 4);
}

static int insert_points(cdt_work *w, uint32_t flags, uint64_t *merged)
{
    uint64_t *order = malloc(((uint64_t)w->n + 1) * sizeof *order);
    if (!order)
        return sl_error_set(w->err, SL_E_NOMEM, 0, NULL, "triangulation of %u points", w->n);
    spatial_order(w, order);
    w->rng = 0x9e3779b97f4a7c15ull;
    uint32_t hint = 0;
    int rc = SL_OK;
    for (uint32_t k = 0; k < w->n && rc == SL_OK; k++) {
        uint32_t p = (uint32_t)order[k];
        int where;
        uint32_t t = locate(w, cdt_xy(w, p), hint, &where);
        if (t == CDT_NONE) {
            rc = sl_error_set(w->err, SL_E_INTERNAL, 0, NULL, "point %u not located", p);
        } else if (where >= 4) {
            uint32_t q = w->tri[t].v[where - 4]; /* inserted earlier, so q < p */
            if (flags & SL_CDT_MERGE_DUPLICATES) {
                w->rep[p] = q;
                (*merged)++;
            } else {
                rc = cdt_refuse(w, SL_CDT_DUPLICATE_POINT, q, p, CDT_NONE, CDT_NONE,
                                "points %u and %u coincide at (%.17g, %.17g)", q, p,
                                cdt_xy(w, p)[0], cdt_xy(w, p)[1]);
            }
        } else {
            if (where == 0)
                split_triangle(w, t, p);
            else
                split_edge(w, t, where - 1, p);
            hint = w->vt[p];
        }
    }
    free(order);
    return rc;
}

/* The links are symmetric and a loop edge is marked the same on both sides, opposite ways
 * (O(n) integer work, always run: a wrong link would otherwise show only as a wrong
 * winding much later, or not at all). Builds without NDEBUG also check every orientation. */
static int check_links(const cdt_work *w)
{
    for (uint32_t t = 0; t < w->tri_count; t++) {
        const cdt_tri *T = &w->tri[t];
        for (int i = 0; i < 3; i++) {
            uint32_t u = T->n[i], p = T->v[(i + 1) % 3], q = T->v[(i + 2) % 3];
            if (u == CDT_NONE)
                continue;
            const cdt_tri *U = &w->tri[u];
            int ip = cdt_index_of(U, p), iq = cdt_index_of(U, q), j = 3 - ip - iq;
            int ok = ip < 3 && iq < 3 && (iq + 1) % 3 == ip && U->n[j] == t;
            int c1 = (T->flags & CDT_CONSTRAINED(i)) != 0, f1 = (T->flags & CDT_FORWARD(i)) != 0;
            if (ok) {
                int c2 = (U->flags & CDT_CONSTRAINED(j)) != 0;
                int f2 = (U->flags & CDT_FORWARD(j)) != 0;
                ok = c1 == c2 && (!c1 || f1 != f2);
            }
            if (!ok)
                return sl_error_set(w->err, SL_E_INTERNAL, 0, NULL,
                                    "triangulation: triangles %u and %u disagree on edge %u-%u",
                                    t, u, p, q);
        }
#ifndef NDEBUG
        if (sl_orient2d(cdt_xy(w, T->v[0]), cdt_xy(w, T->v[1]), cdt_xy(w, T->v[2])) <= 0)
            return sl_error_set(w->err, SL_E_INTERNAL, 0, NULL,
                                "triangulation: triangle %u is not counter-clockwise", t);
#endif
    }
    return SL_OK;
}

/* Winding number of every triangle by a breadth-first fill from the bounding triangle:
 * crossing a loop edge from its left to its right subtracts 1. OUT: wind[tri_count]. */
static int wind_triangles(cdt_work *w, int32_t *wind)
{
    for (uint32_t t = 0; t < w->tri_count; t++)
        wind[t] = INT32_MIN;
    uint32_t start = w->vt[w->n], head = 0, tail = 0;
    wind[start] = 0;
    w->stack[tail++] = start;
    while (head < tail) {
        uint32_t t = w->stack[head++];
        const cdt_tri *T = &w->tri[t];
        for (int i = 0; i < 3; i++) {
            uint32_t u = T->n[i];
            if (u == CDT_NONE)
                continue;
            int32_t wu = wind[t];
            if (T->flags & CDT_CONSTRAINED(i))
                wu += (T->flags & CDT_FORWARD(i)) ? -1 : 1;
            if (wind[u] == INT32_MIN) {
                wind[u] = wu;
                w->stack[tail++] = u;
            } else if (wind[u] != wu) {
                return sl_error_set(w->err, SL_E_INTERNAL, 0, NULL,
                                    "triangulation: inconsistent winding at triangle %u", u);
            }
        }
    }
    if (tail != w->tri_count)
        return sl_error_set(w->err, SL_E_INTERNAL, 0, NULL, "triangulation: %u of %u reached",
                            tail, w->tri_count);
    return SL_OK;
}

/* Inside per triangle (1/0) from the windings; refuses folds in oriented mode. */
static int classify(cdt_work *w, uint32_t flags, uint8_t *inside)
{
    int32_t *wind = malloc(((uint64_t)w->tri_count + 1) * sizeof *wind);
    if (!wind)
        return sl_error_set(w->err, SL_E_NOMEM, 0, NULL, "triangulation of %u points", w->n);
    int rc = wind_triangles(w, wind);
    for (uint32_t t = 0; t < w->tri_count && rc == SL_OK; t++) {
        const uint32_t *v = w->tri[t].v;
        if (flags & SL_CDT_EVEN_ODD) {
            inside[t] = wind[t] % 2 != 0;
        } else if (wind[t] == 0 || wind[t] == 1) {
            inside[t] = (uint8_t)wind[t];
        } else {
            w->report->winding = wind[t];
            rc = cdt_refuse(w, SL_CDT_FOLD, v[0], v[1], v[2], CDT_NONE,
                            "triangle %u %u %u is wound %d times: the loops overlap (a folded "
                            "projection, or a hole running the same way as its outer loop)%s",
                            v[0], v[1], v[2], wind[t],
                            wind[t] < 0 ? ", or an outer loop runs clockwise" : "");
        }
    }
    free(wind);
    return rc;
}

static int cmp_triangle(const void *p, const void *q)
{
    const uint32_t *a = p, *b = q;
    for (int i = 0; i < 3; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

static int emit(cdt_work *w, const uint8_t *inside, uint64_t merged, sl_cdt_result **out)
{
    uint64_t count = 0;
    for (uint32_t t = 0; t < w->tri_count; t++)
        count += inside[t];
    sl_cdt_result *r = calloc(1, sizeof *r);
    uint8_t *used = calloc((uint64_t)w->n + 1, 1);
    if (r)
        r->triangles = malloc((3 * count + 1) * sizeof *r->triangles);
    if (!r || !r->triangles || !used) {
        sl_cdt_free(r);
        free(used);
        return sl_error_set(w->err, SL_E_NOMEM, 0, NULL, "%llu triangles",
                            (unsigned long long)count);
    }
    uint64_t k = 0;
    for (uint32_t t = 0; t < w->tri_count; t++) {
        if (!inside[t])
            continue;
        const uint32_t *v = w->tri[t].v;
        int m = v[0] < v[1] ? (v[0] < v[2] ? 0 : 2) : (v[1] < v[2] ? 1 : 2);
        for (int c = 0; c < 3; c++) { /* rotated to start at the lowest index, still CCW */
            r->triangles[3 * k + c] = v[(m + c) % 3];
            used[v[c]] = 1;
        }
        k++;
    }
    qsort(r->triangles, count, 3 * sizeof *r->triangles, cmp_triangle);
    r->triangle_count = count;
    r->merged_points = merged;
    r->split_edges = w->split_edges;
    for (uint32_t i = 0; i < w->n; i++)
        r->unused_points += !used[i];
    free(used);
    *out = r;
    return SL_OK;
}

int sl_cdt_triangulate(const sl_cdt_input *in, uint32_t flags, sl_cdt_result **out,
                       sl_cdt_report *report, sl_error *err)
{
    sl_cdt_report scratch;
    cdt_work w;
    memset(&w, 0, sizeof w);
    w.report = report ? report : &scratch;
    memset(w.report, 0, sizeof *w.report);
    memset(w.report->v, 0xff, sizeof w.report->v);
    w.err = err;
    *out = NULL;
    uint64_t merged = 0;
    uint8_t *inside = NULL;
    int rc = check_input(&w, in);
    if (rc == SL_OK)
        rc = allocate(&w, in->point_count);
    if (rc == SL_OK)
        rc = place_super_triangle(&w, in->points);
    if (rc == SL_OK)
        rc = insert_points(&w, flags, &merged);
    if (rc == SL_OK)
        rc = cdt_insert_loops(&w, in);
    if (rc == SL_OK)
        rc = check_links(&w);
    if (rc == SL_OK && !(inside = malloc((uint64_t)w.tri_count + 1)))
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangulation of %u points", w.n);
    if (rc == SL_OK)
        rc = classify(&w, flags, inside);
    if (rc == SL_OK)
        rc = emit(&w, inside, merged, out);
    free(inside);
    free(w.xy);
    free(w.tri);
    free(w.vt);
    free(w.rep);
    free(w.stack);
    free(w.crossed);
    return rc;
}

void sl_cdt_free(sl_cdt_result *result)
{
    if (!result)
        return;
    free(result->triangles);
    free(result);
}
