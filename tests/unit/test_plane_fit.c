/* Plane fit: exact planes in every direction (vertical ones included), noisy planes where
 * the mean squared distance must match the noise, the paper's z-form refusing a vertical
 * plane and leaning on a steep noisy one, weights, a flat elongated cloud whose normal is
 * the smallest eigenvector (not the largest), the frame and the projection, degenerate and
 * bad input, and a folding strip caught both by the orientation test and by the
 * triangulation of its projected boundary. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/cdt.h"
#include "geometry/plane_fit.h"
#include "geometry/predicates.h"
#include "tests/check.h"

static uint64_t rng = 0xd1b54a32d192ed03ull;
static double uniform(void)
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static double gauss(void)
{
    double u = uniform() + 1e-300, v = uniform();
    return sqrt(-2 * log(u)) * cos(2 * M_PI * v);
}

static double dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* count points on the plane through c with unit normal n, spread over `size`, moved
 * `noise` (standard deviation) along n. */
static float *plane_points(const double c[3], const double n[3], double size, double noise,
                           int count)
{
    double e[3] = {fabs(n[0]) < 0.9 ? 1 : 0, fabs(n[0]) < 0.9 ? 0 : 1, 0}, s[3], t[3];
    s[0] = n[1] * e[2] - n[2] * e[1], s[1] = n[2] * e[0] - n[0] * e[2],
    s[2] = n[0] * e[1] - n[1] * e[0];
    double len = sqrt(dot(s, s));
    for (int a = 0; a < 3; a++)
        s[a] /= len;
    t[0] = n[1] * s[2] - n[2] * s[1], t[1] = n[2] * s[0] - n[0] * s[2],
    t[2] = n[0] * s[1] - n[1] * s[0];
    float *p = malloc(3 * (size_t)count * sizeof *p);
    for (int i = 0; i < count; i++) {
        double x = size * (uniform() - 0.5), y = size * (uniform() - 0.5), z = noise * gauss();
        for (int a = 0; a < 3; a++)
            p[3 * i + a] = (float)(c[a] + x * s[a] + y * t[a] + z * n[a]);
    }
    return p;
}

static void unit(double v[3])
{
    double len = sqrt(dot(v, v));
    for (int a = 0; a < 3; a++)
        v[a] /= len;
}

static void test_exact_planes(void)
{
    const double dirs[6][3] = {{0, 0, 1}, {0.3, -0.2, 1}, {1, 0, 0}, {0, 1, 0},
                               {1, 1, 0}, {0.1, 1, 0.001}};
    for (int d = 0; d < 6; d++) {
        double n[3] = {dirs[d][0], dirs[d][1], dirs[d][2]}, c[3] = {3, -2, 7};
        unit(n);
        float *p = plane_points(c, n, 10, 0, 500);
        sl_plane pl;
        sl_error err;
        sl_error_init(&err);
        CHECK(sl_plane_fit(p, NULL, 500, NULL, SL_PLANE_TLS, &pl, &err) == SL_OK);
        CHECK_MSG(fabs(fabs(dot(pl.normal, n)) - 1) < 1e-9, "direction %d: normal . n = %.12f",
                  d, dot(pl.normal, n));
        CHECK_MSG(pl.max_dist2 < 1e-10, "direction %d: max distance^2 %g", d, pl.max_dist2);
        CHECK_NEAR(pl.offset, dot(pl.normal, c), 1e-5);
        CHECK(!pl.degenerate);
        /* the frame: orthonormal, u x v = n */
        double cr[3] = {pl.u[1] * pl.v[2] - pl.u[2] * pl.v[1], pl.u[2] * pl.v[0] - pl.u[0] * pl.v[2],
                        pl.u[0] * pl.v[1] - pl.u[1] * pl.v[0]};
        CHECK(fabs(dot(pl.u, pl.u) - 1) < 1e-12 && fabs(dot(pl.v, pl.v) - 1) < 1e-12);
        CHECK(fabs(dot(pl.u, pl.v)) < 1e-12 && fabs(dot(cr, pl.normal) - 1) < 1e-12);
        /* vertical planes (d = 2..4): the z-form has no answer */
        int z_rc = sl_plane_fit(p, NULL, 500, NULL, SL_PLANE_Z_FORM, &pl, &err);
        if (fabs(n[2]) < 1e-12)
            CHECK_MSG(z_rc == SL_E_BADINPUT, "direction %d: the z-form fit a vertical plane", d);
        else if (fabs(n[2]) > 0.5)
            CHECK_MSG(z_rc == SL_OK && fabs(fabs(dot(pl.normal, n)) - 1) < 1e-9,
                      "direction %d: z-form", d);
        free(p);
    }
}

/* Noise sigma along the normal: TLS finds the plane, its mean squared distance is sigma^2
 * (and equals the smallest eigenvalue); on a steep plane the z-form leans away. */
static void test_noisy_planes(void)
{
    const double sigma = 0.1;
    double n[3] = {1, 0, 0.03}, c[3] = {100, 200, -50}; /* 88 degrees from horizontal */
    unit(n);
    float *p = plane_points(c, n, 2, sigma, 20000);
    sl_plane tls, zf;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_plane_fit(p, NULL, 20000, NULL, SL_PLANE_TLS, &tls, &err) == SL_OK);
    CHECK(sl_plane_fit(p, NULL, 20000, NULL, SL_PLANE_Z_FORM, &zf, &err) == SL_OK);
    CHECK_MSG(fabs(dot(tls.normal, n)) > 0.9999, "TLS normal . n = %.6f", dot(tls.normal, n));
    CHECK_MSG(fabs(tls.mean_dist2 / (sigma * sigma) - 1) < 0.05, "TLS mean d^2 %.6g, sigma^2 %g",
              tls.mean_dist2, sigma * sigma);
    CHECK_NEAR(tls.mean_dist2, tls.eigenvalues[0], 1e-9);
    CHECK_MSG(zf.mean_dist2 > 1.5 * tls.mean_dist2 && fabs(dot(zf.normal, n)) < 0.999,
              "z-form on a steep plane: mean d^2 %.6g (TLS %.6g), normal . n %.5f",
              zf.mean_dist2, tls.mean_dist2, dot(zf.normal, n));
    printf("steep noisy plane: TLS mean d^2 %.3g, z-form %.3g (normal %.2f degrees off)\n",
           tls.mean_dist2, zf.mean_dist2, acos(fmin(1, fabs(dot(zf.normal, n)))) * 180 / M_PI);
    free(p);
}

/* A flat elongated cloud (10 x 1 x noise): the normal is the smallest eigenvector. */
static void test_smallest_eigenvector(void)
{
    enum { N = 2000 };
    float *p = malloc(3 * N * sizeof *p);
    for (int i = 0; i < N; i++) {
        p[3 * i] = (float)(10 * uniform()), p[3 * i + 1] = (float)uniform();
        p[3 * i + 2] = (float)(0.01 * gauss());
    }
    sl_plane pl;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_plane_fit(p, NULL, N, NULL, SL_PLANE_TLS, &pl, &err) == SL_OK);
    CHECK_MSG(fabs(pl.normal[2]) > 0.999, "normal (%.3f, %.3f, %.3f), want the z axis",
              pl.normal[0], pl.normal[1], pl.normal[2]);
    CHECK(pl.eigenvalues[0] < pl.eigenvalues[1] && pl.eigenvalues[1] < pl.eigenvalues[2]);
    CHECK_NEAR(pl.eigenvalues[2], 100.0 / 12, 0.5); /* variance of uniform(0, 10) */
    free(p);
}

/* Weights: outliers of weight 0 change nothing; an index array picks a subset. */
static void test_weights_and_index(void)
{
    enum { N = 300 };
    double n[3] = {0, 0.6, 0.8}, c[3] = {1, 2, 3};
    float *p = plane_points(c, n, 5, 0, N);
    double w[N];
    uint32_t idx[N];
    for (int i = 0; i < N; i++) {
        w[i] = i % 10 == 0 ? 0 : 1 + uniform();
        if (i % 10 == 0)
            p[3 * i + 2] += 50; /* outliers, weightless */
        idx[i] = (uint32_t)(N - 1 - i);
    }
    double wi[N];
    for (int i = 0; i < N; i++)
        wi[i] = w[idx[i]];
    sl_plane a, b;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_plane_fit(p, NULL, N, w, SL_PLANE_TLS, &a, &err) == SL_OK);
    CHECK(sl_plane_fit(p, idx, N, wi, SL_PLANE_TLS, &b, &err) == SL_OK);
    CHECK_MSG(fabs(fabs(dot(a.normal, n)) - 1) < 1e-9 && a.max_dist2 < 1e-10,
              "weighted fit: normal . n %.9f, max d^2 %g", dot(a.normal, n), a.max_dist2);
    CHECK(fabs(dot(a.normal, b.normal) - 1) < 1e-12 && fabs(a.offset - b.offset) < 1e-9);
    free(p);
}

static void test_frame_and_orientation(void)
{
    /* A counter-clockwise square seen from +n stays counter-clockwise in (u, v) once the
     * plane faces n; distances within the plane are kept. */
    double n[3] = {0.2, -0.5, 0.7};
    unit(n);
    float *p = plane_points((double[3]){5, 5, 5}, n, 2, 0, 64);
    sl_plane pl;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_plane_fit(p, NULL, 64, NULL, SL_PLANE_TLS, &pl, &err) == SL_OK);
    double neg[3] = {-n[0], -n[1], -n[2]};
    sl_plane_orient(&pl, neg);
    CHECK(dot(pl.normal, neg) > 0.999);
    sl_plane_orient(&pl, n);
    CHECK(dot(pl.normal, n) > 0.999);
    double uv[2 * 64];
    sl_plane_project(&pl, p, NULL, 64, uv);
    double worst = 0;
    for (int i = 0; i < 64; i++)
        for (int j = 0; j < 64; j++) {
            double d3 = 0, d2;
            for (int a = 0; a < 3; a++)
                d3 += ((double)p[3 * i + a] - p[3 * j + a]) * ((double)p[3 * i + a] - p[3 * j + a]);
            d2 = (uv[2 * i] - uv[2 * j]) * (uv[2 * i] - uv[2 * j]) +
                 (uv[2 * i + 1] - uv[2 * j + 1]) * (uv[2 * i + 1] - uv[2 * j + 1]);
            worst = fmax(worst, fabs(sqrt(d3) - sqrt(d2)));
        }
    CHECK_MSG(worst < 1e-5, "projection changes in-plane distances by %g", worst);
    /* a, a + s, a + s + t, a + t with s x t along n: counter-clockwise */
    double s[3] = {pl.u[0], pl.u[1], pl.u[2]}, t[3] = {pl.v[0], pl.v[1], pl.v[2]};
    float sq[12];
    for (int k = 0; k < 4; k++)
        for (int a = 0; a < 3; a++)
            sq[3 * k + a] = (float)(5 + (k == 1 || k == 2) * s[a] + (k >= 2) * t[a]);
    double quv[8];
    sl_plane_project(&pl, sq, NULL, 4, quv);
    CHECK(sl_orient2d(quv, quv + 2, quv + 4) > 0 && sl_orient2d(quv, quv + 4, quv + 6) > 0);
    free(p);
}

static void test_bad_and_degenerate(void)
{
    sl_plane pl;
    sl_error err;
    sl_error_init(&err);
    float p[12] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3};
    CHECK(sl_plane_fit(p, NULL, 0, NULL, SL_PLANE_TLS, &pl, &err) == SL_E_BADINPUT);
    CHECK(sl_plane_fit(p, NULL, 4, NULL, SL_PLANE_TLS, &pl, &err) == SL_OK && pl.degenerate);
    CHECK(sl_plane_fit(p, NULL, 1, NULL, SL_PLANE_TLS, &pl, &err) == SL_OK && pl.degenerate);
    CHECK(fabs(dot(pl.normal, pl.normal) - 1) < 1e-12);
    double w[4] = {1, -1, 1, 1}, zero[4] = {0, 0, 0, 0};
    CHECK(sl_plane_fit(p, NULL, 4, w, SL_PLANE_TLS, &pl, &err) == SL_E_BADINPUT);
    CHECK(sl_plane_fit(p, NULL, 4, zero, SL_PLANE_TLS, &pl, &err) == SL_E_BADINPUT);
    p[4] = NAN;
    CHECK(sl_plane_fit(p, NULL, 4, NULL, SL_PLANE_TLS, &pl, &err) == SL_E_BADINPUT);
}

/* A strip of 2 x K quads in 3D that runs along x, then folds back over itself (a Z fold
 * seen from above). Its projection turns triangles over and its boundary overlaps. */
static void test_fold(void)
{
    enum { K = 12 };
    float p[3 * 2 * (K + 1)];
    uint32_t tri[6 * K], loop[2 * (K + 1)];
    for (int fold = 0; fold <= 1; fold++) {
        for (int i = 0; i <= K; i++) {
            double x = i, z = 0;
            if (fold && i > K / 2) /* back over the first half, half a unit higher */
                x = K - i, z = 0.5;
            for (int r = 0; r < 2; r++)
                p[3 * (2 * i + r)] = (float)x, p[3 * (2 * i + r) + 1] = (float)r,
                p[3 * (2 * i + r) + 2] = (float)z;
        }
        for (int i = 0; i < K; i++) {
            uint32_t a = 2 * i, b = 2 * i + 2, c = 2 * i + 3, d = 2 * i + 1;
            uint32_t q[6] = {a, b, c, a, c, d};
            memcpy(tri + 6 * i, q, sizeof q);
        }
        uint32_t nl = 0;
        for (int i = 0; i <= K; i++)
            loop[nl++] = 2 * i;
        for (int i = K; i >= 0; i--)
            loop[nl++] = 2 * i + 1;
        sl_plane pl;
        sl_error err;
        sl_error_init(&err);
        CHECK(sl_plane_fit(p, NULL, 2 * (K + 1), NULL, SL_PLANE_TLS, &pl, &err) == SL_OK);
        sl_plane_orient(&pl, (double[3]){0, 0, 1});
        double uv[4 * (K + 1)];
        sl_plane_project(&pl, p, NULL, 2 * (K + 1), uv);
        uint64_t first = sl_plane_projection_fold(uv, tri, 2 * K);
        sl_cdt_input in = {2 * (K + 1), uv, 1, (uint32_t[2]){0, nl}, loop};
        sl_cdt_result *r = NULL;
        sl_cdt_report rep;
        int rc = sl_cdt_triangulate(&in, 0, &r, &rep, &err);
        if (fold) {
            CHECK_MSG(first != UINT64_MAX, "the folded strip's projection turns no triangle");
            CHECK_MSG(rc == SL_E_BADINPUT, "the folded strip's boundary was triangulated");
        } else {
            CHECK(first == UINT64_MAX);
            CHECK(rc == SL_OK && r && r->triangle_count == 2 * K);
        }
        sl_cdt_free(r);
    }
}

int main(void)
{
    test_exact_planes();
    test_noisy_planes();
    test_smallest_eigenvector();
    test_weights_and_index();
    test_frame_and_orientation();
    test_bad_and_degenerate();
    test_fold();
    return check_report();
}
