/* Robust predicates: cases where the naive determinant gets the sign wrong and the exact
 * answer is known in closed form (Kettner et al.'s orientation grid near a line, exactly
 * cocircular points, points a few ulps off the unit circle checked in 128-bit integers),
 * the same at huge and tiny scales and with coordinates spanning 1000 binary orders (the
 * big-integer path), the filter against both exact methods on near-degenerate input at
 * every scale, permutation identities, and non-finite input. Prints the cost per call. */
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

#include "geometry/predicates.h"
#include "tests/check.h"

static uint64_t rng_state = 0x2545f4914f6cdd1dull;
static double uniform(void)
{
    rng_state ^= rng_state << 13, rng_state ^= rng_state >> 7, rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

static int sign_of(double x)
{
    return (x > 0) - (x < 0);
}

/* The textbook evaluations, to show that the tests catch what they must. */
static int naive_orient(const double a[2], const double b[2], const double c[2])
{
    return sign_of((a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0]));
}

static int naive_incircle(const double a[2], const double b[2], const double c[2],
                          const double d[2])
{
    double adx = a[0] - d[0], ady = a[1] - d[1], bdx = b[0] - d[0], bdy = b[1] - d[1];
    double cdx = c[0] - d[0], cdy = c[1] - d[1];
    return sign_of((adx * adx + ady * ady) * (bdx * cdy - cdx * bdy) +
                   (bdx * bdx + bdy * bdy) * (cdx * ady - adx * cdy) +
                   (cdx * cdx + cdy * cdy) * (adx * bdy - bdx * ady));
}

/* Kettner, Mehlhorn, Pion, Schirra, Yap, "Classroom examples of robustness problems in
 * geometric computations" (2008): p = (0.5 + i u, 0.5 + j u), q = (12, 12), r = (24, 24).
 * orient(p, q, r) = 12 (py - px) exactly, so the true sign is that of j - i. Run at the
 * given power-of-two scale (which leaves the true sign alone). */
static void kettner_grid(int scale, int *naive_wrong, int *wrong)
{
    const double u = 0x1p-53;
    double q[2] = {ldexp(12, scale), ldexp(12, scale)};
    double r[2] = {ldexp(24, scale), ldexp(24, scale)};
    *naive_wrong = *wrong = 0;
    for (int i = 0; i < 256; i++)
        for (int j = 0; j < 256; j++) {
            double p[2] = {ldexp(0.5 + i * u, scale), ldexp(0.5 + j * u, scale)};
            int truth = (j > i) - (j < i);
            *naive_wrong += naive_orient(p, q, r) != truth;
            *wrong += sl_orient2d(p, q, r) != truth;
            *wrong += sl_orient2d(q, r, p) != truth;
            *wrong += sl_orient2d(r, q, p) != -truth;
        }
}

static void test_orient_near_line(void)
{
    int naive_wrong, wrong;
    kettner_grid(0, &naive_wrong, &wrong);
    CHECK_MSG(naive_wrong > 1000, "the naive sign is wrong on only %d of 65536", naive_wrong);
    CHECK_MSG(wrong == 0, "%d wrong orientation signs near the line y = x", wrong);
    printf("near y = x: naive determinant wrong on %d of 65536 points, sl_orient2d on %d\n",
           naive_wrong, wrong);
    /* Huge: the naive products overflow. Tiny: they underflow to zero. */
    const int scales[] = {900, 1000, -1000, -1021}; /* 0.5 + i u stays exact */
    for (int s = 0; s < 4; s++) {
        kettner_grid(scales[s], &naive_wrong, &wrong);
        CHECK_MSG(wrong == 0, "scale 2^%d: %d wrong signs (naive: %d)", scales[s], wrong,
                  naive_wrong);
        CHECK_MSG(naive_wrong > 0, "scale 2^%d: the naive determinant was right", scales[s]);
    }
}

/* Points exactly on the circle of radius 5 s around c (Pythagorean directions), all
 * coordinates multiples of 2^-50 below 4, so every one is an exact double. */
static void cocircular_points(double c[2], double s, double out[12][2])
{
    static const int dir[12][2] = {{5, 0},  {4, 3},   {3, 4},   {0, 5},  {-3, 4}, {-4, 3},
                                   {-5, 0}, {-4, -3}, {-3, -4}, {0, -5}, {3, -4}, {4, -3}};
    for (int k = 0; k < 12; k++) {
        out[k][0] = c[0] + dir[k][0] * s;
        out[k][1] = c[1] + dir[k][1] * s;
    }
}

static double multiple_of_2m50(double lo, double span)
{
    return ldexp(floor(ldexp(lo + span * uniform(), 50)), -50);
}

static void test_incircle_cocircular(void)
{
    int naive_wrong = 0, wrong = 0, strict_wrong = 0;
    for (int trial = 0; trial < 2000; trial++) {
        double c[2] = {multiple_of_2m50(1, 1), multiple_of_2m50(1, 1)};
        double s = multiple_of_2m50(0.01, 0.18), p[12][2];
        cocircular_points(c, s, p);
        /* Four distinct points; i < j < k are counter-clockwise (directions go round). */
        int pick[4], n = 0;
        while (n < 4) {
            int v = (int)(uniform() * 12), seen = 0;
            for (int q = 0; q < n; q++)
                seen |= pick[q] == v;
            if (!seen)
                pick[n++] = v;
        }
        for (int x = 0; x < 3; x++)
            for (int y = x + 1; y < 3; y++)
                if (pick[y] < pick[x]) {
                    int tmp = pick[x];
                    pick[x] = pick[y], pick[y] = tmp;
                }
        int i = pick[0], j = pick[1], k = pick[2], m = pick[3];
        naive_wrong += naive_incircle(p[i], p[j], p[k], p[m]) != 0;
        wrong += sl_incircle(p[i], p[j], p[k], p[m]) != 0;
        /* The centre is strictly inside, a point just beyond the radius strictly outside. */
        double out[2] = {c[0] + 5 * s + 0x1p-50, c[1]};
        strict_wrong += sl_incircle(p[i], p[j], p[k], c) != 1;
        strict_wrong += sl_incircle(p[i], p[j], p[k], out) != -1;
    }
    CHECK_MSG(naive_wrong > 100, "the naive incircle was nonzero on only %d of 2000",
              naive_wrong);
    CHECK_MSG(wrong == 0, "%d cocircular quadruples not reported as cocircular", wrong);
    CHECK_MSG(strict_wrong == 0, "%d wrong signs for the centre / a point just outside",
              strict_wrong);
    printf("exactly cocircular: naive incircle nonzero on %d of 2000, sl_incircle on %d\n",
           naive_wrong, wrong);
}

/* Integer points exactly on the circle of radius 32045 = 5 13 17 29 (it has thousands):
 * 15-bit differences, too wide for plain doubles to be exact (products of four of them
 * need 64 bits), so this is the expansions' job. */
static void test_incircle_lattice_circle(void)
{
    enum { R = 32045 };
    static double pts[8192][2];
    int n = 0;
    for (long x = -R; x <= R && n < 8190; x++) {
        long y = (long)llround(sqrt((double)R * R - (double)x * x));
        if (x * x + y * y == (long)R * R) {
            pts[n][0] = (double)x, pts[n++][1] = (double)y;
            if (y)
                pts[n][0] = (double)x, pts[n++][1] = (double)-y;
        }
    }
    int naive_wrong = 0, wrong = 0;
    for (int t = 0; t < 20000; t++) {
        const double *q[4];
        for (int k = 0; k < 4; k++)
            q[k] = pts[(int)(uniform() * n)];
        naive_wrong += naive_incircle(q[0], q[1], q[2], q[3]) != 0;
        wrong += sl_incircle(q[0], q[1], q[2], q[3]) != 0;
    }
    CHECK_MSG(n > 300 && naive_wrong > 100, "%d lattice points, naive wrong %d", n, naive_wrong);
    CHECK_MSG(wrong == 0, "%d of 20000 lattice quadruples on one circle not cocircular", wrong);
    printf("integer circle (%d points): naive incircle nonzero on %d of 20000, sl_incircle on %d\n",
           n, naive_wrong, wrong);
}

/* d a few ulps off the unit circle, a b c = (1,0) (0,1) (-1,0): the truth is the sign of
 * 1 - x^2 - y^2, exact in 128-bit integers as x = X 2^-60 (|x|, |y| >= 2^-7). */
static void test_incircle_unit_circle(void)
{
    const double a[2] = {1, 0}, b[2] = {0, 1}, c[2] = {-1, 0};
    int naive_wrong = 0, wrong = 0, total = 0;
    for (int t = 0; t < 400; t++) {
        double theta = 0.02 + 1.53 * uniform() + (t % 4) * (M_PI / 2);
        for (int dx = -3; dx <= 3; dx++)
            for (int dy = -3; dy <= 3; dy++) {
                double d[2] = {cos(theta), sin(theta)};
                for (int k = 0; k < abs(dx); k++)
                    d[0] = nextafter(d[0], dx > 0 ? 2.0 : -2.0);
                for (int k = 0; k < abs(dy); k++)
                    d[1] = nextafter(d[1], dy > 0 ? 2.0 : -2.0);
                if (fabs(d[0]) < 0x1p-7 || fabs(d[1]) < 0x1p-7)
                    continue;
                unsigned __int128 X = (unsigned __int128)(int64_t)fabs(ldexp(d[0], 60));
                unsigned __int128 Y = (unsigned __int128)(int64_t)fabs(ldexp(d[1], 60));
                unsigned __int128 one = (unsigned __int128)1 << 120, r2 = X * X + Y * Y;
                int truth = (one > r2) - (one < r2);
                naive_wrong += naive_incircle(a, b, c, d) != truth;
                wrong += sl_incircle(a, b, c, d) != truth;
                wrong += sl_incircle(b, c, a, d) != truth;
                wrong += sl_incircle(b, a, c, d) != -truth;
                total++;
            }
    }
    CHECK_MSG(naive_wrong > 50, "the naive incircle was wrong on only %d", naive_wrong);
    CHECK_MSG(wrong == 0, "%d wrong incircle signs near the unit circle", wrong);
    printf("near the unit circle: naive incircle wrong on %d of %d points, sl_incircle on %d\n",
           naive_wrong, total, wrong);
}

/* Coordinates spanning more orders of magnitude than expansions hold exactly. */
static void test_wide_exponent_span(void)
{
    const double a[2] = {0, 0}, b[2] = {1, 0}, c[2] = {0.5, 0x1p-1074};
    CHECK(naive_orient(a, b, c) == 0); /* 0.5 * 2^-1074 rounds to zero */
    CHECK(sl_orient2d(a, b, c) == 1);
    CHECK(sl_orient2d(b, a, c) == -1);
    const double c2[2] = {0x1p-1074, 1}, d2[2] = {1, 0x1p-1074}; /* b, d2: span 1075 */
    CHECK(sl_orient2d(a, b, d2) == 1);
    CHECK(sl_orient2d(a, c2, b) == -1);
    const double p[2] = {1, 0}, q[2] = {0, 1}, r[2] = {-1, 0};
    const double out[2] = {0x1p-300, -1};            /* x^2 + y^2 = 1 + 2^-600 */
    const double in[2] = {0x1p-300, -1 + 0x1p-53};   /* 1 - 2^-52 + 2^-106 + 2^-600 */
    const double on[2] = {0, -1};
    CHECK(naive_incircle(p, q, r, out) == 0);
    CHECK(sl_incircle(p, q, r, out) == -1);
    CHECK(sl_incircle(p, q, r, in) == 1);
    CHECK(sl_incircle(p, q, r, on) == 0);
    CHECK(sl_incircle(q, p, r, out) == 1);
    /* Huge and tiny cocircular sets: exact zero, and strict signs either side. */
    static const int dir[4][2] = {{5, 0}, {4, 3}, {3, 4}, {-5, 0}};
    for (int scale = -1070; scale <= 1000; scale += 415) {
        double pts[4][2], centre[2] = {ldexp(1.25, scale), ldexp(-1.75, scale)};
        /* one ulp below the circle's lowest point (1.25, -2.375) */
        double beyond[2] = {ldexp(1.25, scale), nextafter(ldexp(-2.375, scale), -INFINITY)};
        for (int k = 0; k < 4; k++) {
            pts[k][0] = ldexp(1.25 + 0.125 * dir[k][0], scale);
            pts[k][1] = ldexp(-1.75 + 0.125 * dir[k][1], scale);
        }
        CHECK_MSG(sl_incircle(pts[0], pts[1], pts[2], pts[3]) == 0, "scale 2^%d", scale);
        CHECK_MSG(sl_incircle(pts[0], pts[1], pts[2], centre) == 1, "scale 2^%d", scale);
        CHECK_MSG(sl_incircle(pts[0], pts[1], pts[2], beyond) == -1, "scale 2^%d", scale);
    }
}

/* Near-degenerate input at every scale: the filtered predicate, the expansion path and the
 * big-integer reference must agree, and permutations must flip the sign consistently. */
static double perturb(double x, int ulps)
{
    for (int k = 0; k < abs(ulps); k++)
        x = nextafter(x, ulps > 0 ? INFINITY : -INFINITY);
    return x;
}

static void test_cross_check(void)
{
    const int scales[] = {-1074, -900, -300, -60, 0, 60, 300, 900, 960};
    int disagree = 0, identity = 0, nonzero = 0, zero = 0;
    for (int s = 0; s < 9; s++)
        for (int t = 0; t < 3000; t++) {
            double a[2], b[2], c[2], d[2];
            int sc = scales[s];
            for (int k = 0; k < 2; k++) {
                /* a sometimes far larger than b: spans that need big integers */
                int wide = 1000 - sc < 600 ? 1000 - sc : 600;
                a[k] = ldexp(uniform() * 2 - 1, sc + (t % 3 == 0 ? 40 : t % 3 == 1 ? wide : 0));
                b[k] = ldexp(uniform() * 2 - 1, sc);
            }
            double tt = uniform() * 3 - 1;
            c[0] = perturb(a[0] + tt * (b[0] - a[0]), (int)(t % 5) - 2);
            c[1] = perturb(a[1] + tt * (b[1] - a[1]), (int)(t % 7) - 3);
            int o = sl_orient2d(a, b, c);
            disagree += o != sl_orient2d_exact(a, b, c) || o != sl_orient2d_bigint(a, b, c);
            identity += o != sl_orient2d(b, c, a) || o != -sl_orient2d(b, a, c) ||
                        o != -sl_orient2d(a, c, b);
            /* d near the circle through a, b and a point opposite: a's reflection through
             * the centre of a, b's midpoint perpendicular. */
            double mx = (a[0] + b[0]) / 2, my = (a[1] + b[1]) / 2;
            double cc[2] = {mx + (a[1] - b[1]) * 0.5, my + (b[0] - a[0]) * 0.5};
            d[0] = perturb(a[0] + b[0] - cc[0], (int)(t % 3) - 1);
            d[1] = perturb(a[1] + b[1] - cc[1], (int)(t % 5) - 2);
            int ic = sl_incircle(a, b, cc, d);
            disagree += ic != sl_incircle_exact(a, b, cc, d) ||
                        ic != sl_incircle_bigint(a, b, cc, d);
            identity += ic != sl_incircle(b, cc, a, d) || ic != -sl_incircle(b, a, cc, d);
            nonzero += ic != 0;
            zero += ic == 0;
        }
    /* Small integers (and scaled copies): exact differences, often exactly degenerate; the
     * exact stage evaluates them in plain doubles when that is provably exact. */
    const int int_scales[] = {-1000, -270, 0, 30, 245, 900};
    for (int s = 0; s < 6; s++)
        for (int t = 0; t < 20000; t++) {
            double p[4][2];
            int range = t % 2 ? 8 : 4096;
            for (int k = 0; k < 4; k++)
                for (int a = 0; a < 2; a++)
                    p[k][a] = ldexp((double)(int)(uniform() * range) - range / 2, int_scales[s]);
            int o = sl_orient2d_exact(p[0], p[1], p[2]);
            int ic = sl_incircle_exact(p[0], p[1], p[2], p[3]);
            disagree += o != sl_orient2d_bigint(p[0], p[1], p[2]) || o != sl_orient2d(p[0], p[1], p[2]);
            disagree += ic != sl_incircle_bigint(p[0], p[1], p[2], p[3]) ||
                        ic != sl_incircle(p[0], p[1], p[2], p[3]);
            zero += ic == 0;
        }
    CHECK_MSG(disagree == 0, "%d calls where the filter, expansions and big integers differ",
              disagree);
    CHECK_MSG(identity == 0, "%d permutation identities broken", identity);
    printf("cross-check: %d incircle calls nonzero, %d exactly zero, 0 disagreements wanted: "
           "%d\n", nonzero, zero, disagree);
}

static void test_nonfinite(void)
{
    const double a[2] = {0, 0}, b[2] = {1, 0}, n[2] = {NAN, 1}, i[2] = {INFINITY, 1};
    CHECK(sl_orient2d(a, b, n) == 0);
    CHECK(sl_orient2d(a, b, i) == 0);
    CHECK(sl_incircle(a, b, i, n) == 0);
    CHECK(sl_orient2d(a, a, a) == 0);
    CHECK(sl_incircle(a, a, b, b) == 0);
}

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void print_costs(void)
{
    enum { N = 200000 };
    static double pts[N + 3][2];
    for (int i = 0; i < N + 3; i++)
        pts[i][0] = uniform(), pts[i][1] = uniform();
    int acc = 0;
    double t0 = seconds();
    for (int i = 0; i < N; i++)
        acc += sl_incircle(pts[i], pts[i + 1], pts[i + 2], pts[i + 3]);
    double t1 = seconds();
    for (int i = 0; i < N; i++)
        acc += sl_incircle_exact(pts[i], pts[i + 1], pts[i + 2], pts[i + 3]);
    double t2 = seconds();
    for (int i = 0; i < N / 10; i++)
        acc += sl_incircle_bigint(pts[i], pts[i + 1], pts[i + 2], pts[i + 3]);
    double t3 = seconds();
    printf("incircle per call: filtered %.1f ns, expansions %.1f ns, big integers %.1f ns "
           "(checksum %d)\n", (t1 - t0) / N * 1e9, (t2 - t1) / N * 1e9,
           (t3 - t2) / (N / 10) * 1e9, acc);
}

int main(void)
{
    test_orient_near_line();
    test_incircle_cocircular();
    test_incircle_unit_circle();
    test_incircle_lattice_circle();
    test_wide_exponent_span();
    test_cross_check();
    test_nonfinite();
    print_costs();
    return check_report();
}
