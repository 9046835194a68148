/* Constrained Delaunay triangulation against brute force (tests/unit/cdt_checks.h) on
 * random star-shaped polygons with holes and interior points, grid polygons (collinear
 * boundaries, every grid square cocircular, points on loop edges that must split them),
 * lattice points exactly on two circles, the same with one-ulp perturbations, huge, tiny
 * and offset coordinates, and touching loops; then every refusal (crossing, overlap,
 * duplicates, folds, bad numbers) and determinism across threads. */
#include <omp.h>

#include "tests/unit/cdt_checks.h"

static uint64_t rng = 0x853c49e6748fea9bull;
static double uniform(void)
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static sl_cdt_result *triangulate(const poly *p, uint32_t flags, int *rc, sl_cdt_report *rep)
{
    sl_cdt_input in = poly_input(p);
    sl_cdt_result *r = NULL;
    sl_error err;
    sl_error_init(&err);
    *rc = sl_cdt_triangulate(&in, flags, &r, rep, &err);
    if (*rc && (!rep || rep->problem == SL_CDT_PROBLEM_NONE))
        fprintf(stderr, "triangulation failed: %s\n", err.message);
    return r;
}

/* Triangulates and checks; returns the number of failed checks. */
static int run_and_verify(const char *name, const poly *p, int holes, int brute)
{
    int rc;
    sl_cdt_report rep;
    sl_cdt_result *r = triangulate(p, 0, &rc, &rep);
    CHECK_MSG(rc == SL_OK, "%s: rc %d, problem %d", name, rc, rep.problem);
    int failed = r ? cdt_verify(name, p, r, holes, brute) : 1;
    sl_cdt_free(r);
    return failed;
}

/* A star-shaped loop around c: m vertices at increasing angles, radii in [0.5, 1] * size;
 * counter-clockwise, or clockwise for a hole. */
static void star_loop(poly *p, double cx, double cy, double size, uint32_t m, int clockwise)
{
    uint32_t first = p->n;
    for (uint32_t k = 0; k < m; k++) {
        double a = (k + 0.8 * uniform()) * 2 * M_PI / m, r = size * (0.5 + 0.5 * uniform());
        poly_point(p, cx + r * cos(a), cy + r * sin(a));
    }
    for (uint32_t k = 0; k < m; k++)
        poly_loop_add(p, first + (clockwise ? m - 1 - k : k));
    poly_close(p);
}

/* The last loop touches no earlier one. */
static int last_loop_is_clear(const poly *p)
{
    uint32_t l = p->loops - 1;
    for (uint32_t k = p->start[l]; k < p->start[l + 1]; k++) {
        uint32_t nk = k + 1 == p->start[l + 1] ? p->start[l] : k + 1;
        for (uint32_t e = 0; e < p->start[l]; e++) {
            uint32_t le = 0;
            while (p->start[le + 1] <= e)
                le++;
            uint32_t ne = e + 1 == p->start[le + 1] ? p->start[le] : e + 1;
            if (segments_touch(P(p, p->idx[k]), P(p, p->idx[nk]), P(p, p->idx[e]),
                               P(p, p->idx[ne])))
                return 0;
        }
    }
    /* one vertex inside the outer loop and outside the other holes, and no other hole
     * inside this one */
    poly probe = *p;
    probe.loops = l;
    if (!poly_contains(&probe, P(p, p->idx[p->start[l]])))
        return 0;
    poly alone = *p;
    alone.loops = 1;
    alone.start[0] = 0;
    alone.idx = p->idx + p->start[l];
    alone.start[1] = p->start[l + 1] - p->start[l];
    for (uint32_t h = 1; h < l; h++)
        if (poly_contains(&alone, P(p, p->idx[p->start[h]])))
            return 0;
    return 1;
}

static void random_polygon(poly *p, uint32_t outer, int holes, uint32_t interior)
{
    poly_init(p);
    star_loop(p, 0, 0, 1, outer, 0);
    for (int h = 0; h < holes; h++) {
        for (int tries = 0; tries < 50; tries++) {
            uint32_t n0 = p->n, i0 = p->nidx;
            star_loop(p, uniform() - 0.5, uniform() - 0.5, 0.05 + 0.15 * uniform(),
                      3 + (uint32_t)(uniform() * 12), 1);
            if (last_loop_is_clear(p))
                break;
            p->n = n0, p->nidx = i0, p->loops--; /* undo and retry */
        }
    }
    for (uint32_t i = 0; i < interior;) {
        double q[2] = {2 * uniform() - 1, 2 * uniform() - 1};
        if (poly_contains(p, q))
            poly_point(p, q[0], q[1]), i++;
    }
}

static void test_square(void)
{
    poly p;
    poly_init(&p);
    for (int k = 0; k < 4; k++)
        poly_loop_add(&p, poly_point(&p, k == 1 || k == 2, k >= 2));
    poly_close(&p);
    int rc;
    sl_cdt_result *r = triangulate(&p, 0, &rc, NULL);
    CHECK(rc == SL_OK && r && r->triangle_count == 2);
    if (r && r->triangle_count == 2) { /* canonical: lowest index first, sorted */
        const uint32_t *t = r->triangles;
        CHECK(t[0] < t[1] && t[0] < t[2] && t[3] < t[4] && t[3] < t[5]);
        CHECK(t[0] < t[3] || (t[0] == t[3] && t[1] < t[4]));
    }
    sl_cdt_free(r);
    poly_release(&p);
}

static void test_random_polygons(void)
{
    int failed = 0;
    for (int trial = 0; trial < 60; trial++) {
        poly p;
        uint32_t outer = 3 + (uint32_t)(uniform() * 200);
        int holes = trial % 7;
        random_polygon(&p, outer, holes, (uint32_t)(uniform() * 400));
        char name[64];
        snprintf(name, sizeof name, "random polygon %d (%u points, %u loops)", trial, p.n,
                 p.loops);
        failed += run_and_verify(name, &p, (int)p.loops - 1, 1) != 0;
        poly_release(&p);
    }
    CHECK_MSG(failed == 0, "%d random polygons failed", failed);
}

/* An n x n grid square with rectangular holes; `dense` puts every grid point of the
 * boundaries into the loops, else loops have only their corners and the other grid
 * points lie on the loop edges (they must split them). `ulps` perturbs every coordinate
 * by up to that many ulps. */
static void grid_polygon(poly *p, int n, int dense, int ulps)
{
    static const int holes[3][4] = {{2, 2, 5, 4}, {7, 3, 9, 9}, {3, 7, 5, 8}}; /* x0 y0 x1 y1 */
    poly_init(p);
    int32_t *id = malloc((size_t)(n + 1) * (n + 1) * sizeof *id);
    for (int i = 0; i <= n; i++)
        for (int j = 0; j <= n; j++) {
            int in_hole = 0;
            for (int h = 0; h < 3; h++)
                in_hole |= i > holes[h][0] * n / 10 && i < holes[h][2] * n / 10 &&
                           j > holes[h][1] * n / 10 && j < holes[h][3] * n / 10;
            double x = i, y = j;
            for (int k = 0; k < ulps; k++) {
                x = nextafter(x, uniform() < 0.5 ? -1e9 : 1e9);
                y = nextafter(y, uniform() < 0.5 ? -1e9 : 1e9);
            }
            id[i * (n + 1) + j] = in_hole ? -1 : (int32_t)poly_point(p, x, y);
        }
    /* A rectangle loop x0..x1, y0..y1 in grid units, counter-clockwise or clockwise. */
    for (int h = -1; h < 3; h++) {
        int x0 = h < 0 ? 0 : holes[h][0] * n / 10, y0 = h < 0 ? 0 : holes[h][1] * n / 10;
        int x1 = h < 0 ? n : holes[h][2] * n / 10, y1 = h < 0 ? n : holes[h][3] * n / 10;
        int corners[4][2] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
        for (int c = 0; c < 4; c++) {
            int cc = h < 0 ? c : 3 - c, nc = h < 0 ? (c + 1) % 4 : (3 - c + 3) % 4;
            int ax = corners[cc][0], ay = corners[cc][1], bx = corners[nc][0], by = corners[nc][1];
            int steps = dense ? abs(bx - ax) + abs(by - ay) : 1;
            for (int s = 0; s < steps; s++) {
                int gx = ax + (bx - ax) * s / steps, gy = ay + (by - ay) * s / steps;
                poly_loop_add(p, (uint32_t)id[gx * (n + 1) + gy]);
            }
        }
        poly_close(p);
    }
    free(id);
}

static void test_grids(void)
{
    for (int dense = 0; dense <= 1; dense++)
        for (int ulps = 0; ulps <= 1; ulps++) {
            poly p;
            grid_polygon(&p, 20, dense, ulps);
            char name[64];
            snprintf(name, sizeof name, "grid 20, %s loops, %d ulp", dense ? "dense" : "corner",
                     ulps);
            int rc;
            sl_cdt_result *r = triangulate(&p, 0, &rc, NULL);
            CHECK_MSG(rc == SL_OK, "%s: rc %d", name, rc);
            if (r) {
                /* With corner-only loops every grid point on a boundary splits it (ulp
                 * perturbed points lie off the edges, and are simply interior or outside). */
                if (!dense && ulps == 0)
                    CHECK_MSG(r->split_edges > 50, "%s: %llu splits", name,
                              (unsigned long long)r->split_edges);
                cdt_verify(name, &p, r, 3, 1);
            }
            sl_cdt_free(r);
            poly_release(&p);
        }
}

/* Lattice points on x^2 + y^2 = R^2 in angular order (R = 1105 and 65 have many). */
static void circle_loop(poly *p, int R, int clockwise, int as_loop)
{
    uint32_t first = p->n, m = 0;
    double ang[512];
    int pts[512][2];
    for (int x = -R; x <= R; x++) {
        int y = (int)llround(sqrt((double)R * R - (double)x * x));
        for (int s = -1; s <= 1; s += 2)
            if ((long)x * x + (long)y * y == (long)R * R && (s > 0 || y != 0) && m < 512) {
                pts[m][0] = x, pts[m][1] = s * y;
                ang[m] = atan2(s * y, x);
                m++;
            }
    }
    for (uint32_t i = 1; i < m; i++) /* sort by angle */
        for (uint32_t j = i; j > 0 && ang[j] < ang[j - 1]; j--) {
            double ta = ang[j];
            int tx = pts[j][0], ty = pts[j][1];
            ang[j] = ang[j - 1], pts[j][0] = pts[j - 1][0], pts[j][1] = pts[j - 1][1];
            ang[j - 1] = ta, pts[j - 1][0] = tx, pts[j - 1][1] = ty;
        }
    for (uint32_t i = 0; i < m; i++)
        poly_point(p, pts[i][0], pts[i][1]);
    if (!as_loop)
        return;
    for (uint32_t i = 0; i < m; i++)
        poly_loop_add(p, first + (clockwise ? m - 1 - i : i));
    poly_close(p);
}

static void test_cocircular(void)
{
    poly p;
    poly_init(&p); /* a convex polygon of 36 cocircular points, with its centre and 12
                      cocircular points inside */
    circle_loop(&p, 1105, 0, 1);
    CHECK_MSG(p.n > 30, "only %u lattice points on the circle", p.n);
    poly_point(&p, 0, 0);
    circle_loop(&p, 65, 0, 0);
    run_and_verify("cocircular, centre and inner circle", &p, 0, 1);
    poly_release(&p);
    poly_init(&p); /* the inner circle as a hole */
    circle_loop(&p, 1105, 0, 1);
    circle_loop(&p, 65, 1, 1);
    run_and_verify("cocircular ring", &p, 1, 1);
    poly_release(&p);
}

/* Huge, tiny and offset coordinates: the same polygons scaled by powers of ten (not exact:
 * the rounding makes nearly collinear boundaries) or moved far from the origin. */
static void test_scales(void)
{
    const double scales[] = {1e-150, 1e-30, 1e30, 1e150};
    for (int s = 0; s < 5; s++) {
        poly p;
        random_polygon(&p, 60, 3, 150);
        for (uint32_t i = 0; i < 2 * p.n; i++)
            p.xy[i] = s < 4 ? p.xy[i] * scales[s] : p.xy[i] + 1e7; /* 1e7: 24 bits lost */
        char name[64] = "moved by 1e7";
        if (s < 4)
            snprintf(name, sizeof name, "scaled by %g", scales[s]);
        run_and_verify(name, &p, -1, 1);
        poly_release(&p);
    }
}

/* Two edges of the loops, not neighbours on one loop, share a point. */
static int loops_touch(const poly *p)
{
    for (uint32_t e = 0; e < p->nidx; e++)
        for (uint32_t f = e + 1; f < p->nidx; f++) {
            uint32_t le = 0, lf = 0;
            while (p->start[le + 1] <= e)
                le++;
            while (p->start[lf + 1] <= f)
                lf++;
            uint32_t ne = e + 1 == p->start[le + 1] ? p->start[le] : e + 1;
            uint32_t nf = f + 1 == p->start[lf + 1] ? p->start[lf] : f + 1;
            if (le == lf && (ne == f || nf == e))
                continue;
            if (segments_touch(P(p, p->idx[e]), P(p, p->idx[ne]), P(p, p->idx[f]),
                               P(p, p->idx[nf])))
                return 1;
        }
    return 0;
}

static void reverse_loop(poly *p, uint32_t l)
{
    for (uint32_t i = p->start[l], j = p->start[l + 1] - 1; i < j; i++, j--) {
        uint32_t t = p->idx[i];
        p->idx[i] = p->idx[j], p->idx[j] = t;
    }
}

/* Loops through 4-12 random points, often self-intersecting: refused as crossing exactly
 * when two of their edges cross (brute force), else triangulated correctly. */
static void test_random_loops(void)
{
    int wrong = 0, refused = 0;
    for (int trial = 0; trial < 600; trial++) {
        poly p;
        poly_init(&p);
        uint32_t m = 4 + trial % 9;
        for (uint32_t k = 0; k < m; k++)
            poly_loop_add(&p, poly_point(&p, uniform(), uniform()));
        poly_close(&p);
        int crossing = loops_touch(&p);
        if (!crossing && poly_area(&p) < 0)
            reverse_loop(&p, 0);
        int rc;
        sl_cdt_report rep;
        sl_cdt_result *r = triangulate(&p, 0, &rc, &rep);
        if (crossing) {
            wrong += rc != SL_E_BADINPUT || rep.problem != SL_CDT_CROSSING;
            refused++;
        } else {
            wrong += rc != SL_OK || !r || cdt_verify("random simple loop", &p, r, 0, 1);
        }
        sl_cdt_free(r);
        poly_release(&p);
    }
    CHECK_MSG(wrong == 0, "%d of 600 random loops misjudged (%d self-intersecting)", wrong,
              refused);
    CHECK(refused > 100 && refused < 550);
}

/* Star polygons snapped to multiples of 1/16 with every grid point inside: collinear
 * runs, points on loop edges, cocircular grid squares, all at once. */
static void test_snapped_polygons(void)
{
    int failed = 0, done = 0;
    for (int trial = 0; trial < 200 && done < 25; trial++) {
        poly p;
        poly_init(&p);
        star_loop(&p, 0, 0, 1, 5 + (uint32_t)(uniform() * 30), 0);
        for (uint32_t i = 0; i < 2 * p.n; i++)
            p.xy[i] = round(p.xy[i] * 16) / 16;
        int dup = 0;
        for (uint32_t i = 0; i < p.n; i++)
            for (uint32_t j = i + 1; j < p.n; j++)
                dup |= p.xy[2 * i] == p.xy[2 * j] && p.xy[2 * i + 1] == p.xy[2 * j + 1];
        if (dup || loops_touch(&p) || poly_area(&p) <= 0) {
            poly_release(&p);
            continue;
        }
        uint32_t boundary = p.n;
        for (int x = -16; x <= 16; x++)
            for (int y = -16; y <= 16; y++) {
                double q[2] = {x / 16.0, y / 16.0};
                int on_loop = 0;
                for (uint32_t i = 0; i < boundary; i++)
                    on_loop |= p.xy[2 * i] == q[0] && p.xy[2 * i + 1] == q[1];
                if (!on_loop && (poly_contains(&p, q) || uniform() < 0.1))
                    poly_point(&p, q[0], q[1]); /* inside, on an edge, or (some) outside */
            }
        char name[64];
        snprintf(name, sizeof name, "snapped polygon %d (%u points)", trial, p.n);
        failed += run_and_verify(name, &p, 0, 1) != 0;
        done++;
        poly_release(&p);
    }
    CHECK_MSG(failed == 0 && done == 25, "%d of %d snapped polygons failed", failed, done);
}

static void test_touching(void)
{
    poly p;
    poly_init(&p); /* square 0..4 with a triangular hole touching the outer loop at (2, 0) */
    const double sq[4][2] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
    for (int k = 0; k < 4; k++)
        poly_loop_add(&p, poly_point(&p, sq[k][0], sq[k][1]));
    poly_close(&p);
    uint32_t t0 = poly_point(&p, 2, 0), t1 = poly_point(&p, 3, 2), t2 = poly_point(&p, 1, 2);
    poly_loop_add(&p, t0), poly_loop_add(&p, t2), poly_loop_add(&p, t1);
    poly_close(&p);
    poly_point(&p, 2, 3);
    int rc;
    sl_cdt_result *r = triangulate(&p, 0, &rc, NULL);
    CHECK_MSG(rc == SL_OK, "touching hole: rc %d", rc);
    if (r) {
        CHECK_EQ_U64(r->split_edges, 1); /* (2, 0) splits the bottom edge */
        cdt_verify("hole touching the outer loop", &p, r, -1, 1);
    }
    sl_cdt_free(r);
    poly_release(&p);
}

static void expect_refusal(const char *name, const poly *p, uint32_t flags, int problem)
{
    int rc;
    sl_cdt_report rep;
    sl_cdt_result *r = triangulate(p, flags, &rc, &rep);
    CHECK_MSG(rc == SL_E_BADINPUT && rep.problem == problem && r == NULL,
              "%s: rc %d problem %d, want %d", name, rc, rep.problem, problem);
    sl_cdt_free(r);
}

static void square_loop(poly *p, double x0, double y0, double x1, double y1, int clockwise)
{
    uint32_t v[4] = {poly_point(p, x0, y0), poly_point(p, x1, y0), poly_point(p, x1, y1),
                     poly_point(p, x0, y1)};
    for (int k = 0; k < 4; k++)
        poly_loop_add(p, v[clockwise ? 3 - k : k]);
    poly_close(p);
}

static void test_refusals(void)
{
    poly p;
    poly_init(&p); /* bowtie */
    const double bow[4][2] = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
    for (int k = 0; k < 4; k++)
        poly_loop_add(&p, poly_point(&p, bow[k][0], bow[k][1]));
    poly_close(&p);
    expect_refusal("bowtie", &p, 0, SL_CDT_CROSSING);
    poly_release(&p);

    poly_init(&p); /* a hole poking out of the outer loop */
    square_loop(&p, 0, 0, 4, 4, 0);
    square_loop(&p, 3, 1, 5, 2, 1);
    expect_refusal("hole crossing the boundary", &p, 0, SL_CDT_CROSSING);
    poly_release(&p);

    poly_init(&p); /* a random polygon whose hole is then dragged across the outer loop */
    random_polygon(&p, 80, 1, 50);
    if (p.loops == 2) {
        uint32_t v = p.idx[p.start[1]];
        p.xy[2 * v] = 3, p.xy[2 * v + 1] = 0.01;
        expect_refusal("hole vertex dragged outside", &p, 0, SL_CDT_CROSSING);
    }
    poly_release(&p);

    poly_init(&p); /* two squares sharing an edge */
    square_loop(&p, 0, 0, 2, 2, 0);
    uint32_t a = 1, b = 2, c = poly_point(&p, 4, 2), d = poly_point(&p, 4, 0);
    poly_loop_add(&p, d), poly_loop_add(&p, c), poly_loop_add(&p, b), poly_loop_add(&p, a);
    poly_close(&p);
    expect_refusal("shared edge", &p, SL_CDT_EVEN_ODD, SL_CDT_OVERLAP);
    poly_release(&p);

    poly_init(&p); /* a triangle lying along the outer loop's bottom edge */
    square_loop(&p, 0, 0, 4, 4, 0);
    uint32_t e = poly_point(&p, 1, 0), f = poly_point(&p, 3, 0), g = poly_point(&p, 2, 1);
    poly_loop_add(&p, e), poly_loop_add(&p, g), poly_loop_add(&p, f);
    poly_close(&p);
    expect_refusal("collinear overlap", &p, 0, SL_CDT_OVERLAP);
    poly_release(&p);

    poly_init(&p); /* a duplicate interior point: refused, or merged into the lower index */
    square_loop(&p, 0, 0, 4, 4, 0);
    poly_point(&p, 1, 1), poly_point(&p, 3, 2), poly_point(&p, 1, 1);
    expect_refusal("duplicate point", &p, 0, SL_CDT_DUPLICATE_POINT);
    int rc;
    sl_cdt_result *r = triangulate(&p, SL_CDT_MERGE_DUPLICATES, &rc, NULL);
    CHECK(rc == SL_OK && r && r->merged_points == 1 && r->unused_points == 1);
    for (uint64_t i = 0; r && i < 3 * r->triangle_count; i++)
        CHECK(r->triangles[i] != 6);
    CHECK(r && r->triangle_count == 6);
    sl_cdt_free(r);
    poly_release(&p);

    poly_init(&p); /* a duplicate boundary point (an unwelded mesh's loop) */
    square_loop(&p, 0, 0, 4, 4, 0);
    uint32_t dup = poly_point(&p, 4, 0);
    p.idx[1] = dup; /* the loop names the copy */
    r = triangulate(&p, SL_CDT_MERGE_DUPLICATES, &rc, NULL);
    CHECK(rc == SL_OK && r && r->triangle_count == 2 && r->merged_points == 1);
    sl_cdt_free(r);
    poly_release(&p);

    poly_init(&p); /* holes running the same way as the outer loop: a fold (winding 2) */
    square_loop(&p, 0, 0, 4, 4, 0);
    square_loop(&p, 1, 1, 2, 2, 0);
    int rc2;
    sl_cdt_report rep;
    sl_cdt_free(triangulate(&p, 0, &rc2, &rep));
    CHECK(rc2 == SL_E_BADINPUT && rep.problem == SL_CDT_FOLD && rep.winding == 2);
    r = triangulate(&p, SL_CDT_EVEN_ODD, &rc, NULL); /* even-odd: an ordinary hole */
    CHECK(rc == SL_OK && r);
    if (r) {
        p.idx[4] = 7, p.idx[5] = 6, p.idx[6] = 5, p.idx[7] = 4; /* clockwise for the checker */
        cdt_verify("even-odd hole", &p, r, 1, 1);
    }
    sl_cdt_free(r);
    poly_release(&p);

    poly_init(&p); /* a clockwise outer loop: a mirrored projection (winding -1) */
    square_loop(&p, 0, 0, 4, 4, 1);
    sl_cdt_free(triangulate(&p, 0, &rc2, &rep));
    CHECK(rc2 == SL_E_BADINPUT && rep.problem == SL_CDT_FOLD && rep.winding == -1);
    poly_release(&p);

    poly_init(&p); /* NaN, huge, bad index, bad offsets, too many points */
    square_loop(&p, 0, 0, 4, 4, 0);
    p.xy[3] = NAN;
    expect_refusal("NaN", &p, 0, SL_CDT_NONFINITE);
    p.xy[3] = 1e200;
    expect_refusal("1e200", &p, 0, SL_CDT_NONFINITE);
    p.xy[3] = 0;
    p.idx[2] = 9;
    expect_refusal("index 9 of 4", &p, 0, SL_CDT_BAD_INDEX);
    p.idx[2] = 2;
    p.loops = 2, p.start[2] = 2; /* offsets going down */
    expect_refusal("descending loop offsets", &p, 0, SL_CDT_BAD_INDEX);
    p.loops = 1;
    sl_cdt_input in = poly_input(&p);
    in.point_count = SL_CDT_MAX_POINTS + 1;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_cdt_triangulate(&in, 0, &r, NULL, &err) == SL_E_LIMIT && r == NULL);
    poly_release(&p);
}

static void test_empty(void)
{
    poly p;
    poly_init(&p);
    int rc;
    sl_cdt_result *r = triangulate(&p, 0, &rc, NULL);
    CHECK(rc == SL_OK && r && r->triangle_count == 0);
    sl_cdt_free(r);
    poly_point(&p, 1, 2), poly_point(&p, 3, 4), poly_point(&p, 5, 6); /* no loops */
    r = triangulate(&p, 0, &rc, NULL);
    CHECK(rc == SL_OK && r && r->triangle_count == 0 && r->unused_points == 3);
    sl_cdt_free(r);
    poly_release(&p);
}

/* The same input from several threads at once gives the same bytes as serially. */
static void test_determinism(void)
{
    poly p;
    grid_polygon(&p, 30, 0, 0);
    int rc;
    sl_cdt_result *ref = triangulate(&p, 0, &rc, NULL);
    CHECK(rc == SL_OK && ref);
    int differ = 0;
#pragma omp parallel for num_threads(2) reduction(+ : differ)
    for (int k = 0; k < 8; k++) {
        int krc;
        sl_cdt_result *r = triangulate(&p, 0, &krc, NULL);
        differ += !r || !ref || r->triangle_count != ref->triangle_count ||
                  memcmp(r->triangles, ref->triangles, 3 * ref->triangle_count * 4) != 0;
        sl_cdt_free(r);
    }
    CHECK_MSG(differ == 0, "%d of 8 parallel runs differ", differ);
    sl_cdt_free(ref);
    poly_release(&p);
}

int main(void)
{
    test_square();
    test_random_polygons();
    test_grids();
    test_random_loops();
    test_snapped_polygons();
    test_cocircular();
    test_scales();
    test_touching();
    test_refusals();
    test_empty();
    test_determinism();
    return check_report();
}
