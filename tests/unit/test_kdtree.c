/* k-d tree: exact kNN against brute force (with many equal distances, where the index
 * tie-break matters), k beyond the point count, empty trees, and identical answers from
 * parallel queries. Prints build/query timings on 1M points of a sphere. */
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/kdtree.h"
#include "tests/check.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double uniform(void)
{
    rng_state ^= rng_state << 13, rng_state ^= rng_state >> 7, rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* Brute force: the k smallest (dist2, index) pairs. */
static void brute_knn(const float *pts, uint32_t n, const float *q, uint32_t k, uint32_t *idx,
                      float *d2)
{
    uint32_t found = 0;
    for (uint32_t i = 0; i < n; i++) {
        float dx = pts[3 * i] - q[0], dy = pts[3 * i + 1] - q[1], dz = pts[3 * i + 2] - q[2];
        float d = dx * dx + dy * dy + dz * dz;
        uint32_t pos = found < k ? found++ : k;
        if (pos == k) {
            if (d > d2[k - 1] || (d == d2[k - 1] && i > idx[k - 1]))
                continue;
            pos = k - 1;
        }
        while (pos > 0 && (d < d2[pos - 1] || (d == d2[pos - 1] && i < idx[pos - 1]))) {
            d2[pos] = d2[pos - 1], idx[pos] = idx[pos - 1];
            pos--;
        }
        d2[pos] = d, idx[pos] = i;
    }
}

static void check_against_brute(const float *pts, uint32_t n, const char *what)
{
    sl_kdtree *t = NULL;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_kdtree_build(&t, pts, n, &err) == SL_OK);
    int mismatches = 0;
    const uint32_t ks[] = {1, 5, 12, 40};
    for (int qi = 0; qi < 300; qi++) {
        float q[3];
        if (qi % 2) /* on a point (self first, then ties) */
            memcpy(q, pts + 3 * (uint32_t)(uniform() * n), sizeof q);
        else
            for (int c = 0; c < 3; c++)
                q[c] = (float)(uniform() * 12 - 1);
        for (int ki = 0; ki < 4; ki++) {
            uint32_t k = ks[ki], a[40], b[40];
            float da[40], db[40];
            uint32_t got = sl_kdtree_knn(t, q, k, a, da);
            uint32_t want = k < n ? k : n;
            brute_knn(pts, n, q, want, b, db);
            if (got != want || memcmp(a, b, want * sizeof *a) || memcmp(da, db, want * sizeof *da))
                mismatches++;
        }
    }
    CHECK_MSG(mismatches == 0, "%s: %d kNN answers differ from brute force", what, mismatches);
    sl_kdtree_free(t);
}

static void test_exact(void)
{
    enum { N = 3000 };
    float *pts = malloc(3 * N * sizeof *pts);
    for (int i = 0; i < 3 * N; i++)
        pts[i] = (float)(uniform() * 10);
    check_against_brute(pts, N, "random");
    /* An integer lattice with duplicates: many exactly equal distances. */
    for (int i = 0; i < N; i++)
        for (int c = 0; c < 3; c++)
            pts[3 * i + c] = (float)((i / (c == 0 ? 1 : c == 1 ? 10 : 100)) % 10);
    check_against_brute(pts, N, "lattice with duplicates");
    check_against_brute(pts, 7, "fewer points than k");
    free(pts);
}

static void test_edges(void)
{
    sl_kdtree *t = NULL;
    sl_error err;
    sl_error_init(&err);
    float one[3] = {1, 2, 3}, q[3] = {0, 0, 0}, d2 = -1;
    uint32_t idx[4];
    CHECK(sl_kdtree_build(&t, one, 0, &err) == SL_OK);
    CHECK(sl_kdtree_knn(t, q, 4, idx, NULL) == 0);
    CHECK(sl_kdtree_nearest(t, q, NULL) == UINT32_MAX);
    sl_kdtree_free(t);
    CHECK(sl_kdtree_build(&t, one, 1, &err) == SL_OK);
    CHECK(sl_kdtree_nearest(t, q, &d2) == 0);
    CHECK_NEAR(d2, 14.0, 1e-6);
    CHECK(sl_kdtree_count(t) == 1);
    sl_kdtree_free(t);
    sl_kdtree_free(NULL);
}

static void test_parallel_and_timing(void)
{
    const uint32_t n = 1000000, k = 12;
    float *pts = malloc(3ull * n * sizeof *pts);
    uint32_t *serial = malloc((size_t)n * k * sizeof *serial);
    uint32_t *parallel = malloc((size_t)n * k * sizeof *parallel);
    /* A jittered sphere in scanline order, like a scan's vertex order. */
    for (uint32_t i = 0; i < n; i++) {
        double theta = 3.14159265358979 * ((i / 1000) + uniform()) / 1000.0;
        double phi = 6.28318530717959 * ((i % 1000) + uniform()) / 1000.0;
        pts[3 * i] = (float)(sin(theta) * cos(phi));
        pts[3 * i + 1] = (float)(sin(theta) * sin(phi));
        pts[3 * i + 2] = (float)cos(theta);
    }
    sl_kdtree *t = NULL;
    sl_error err;
    sl_error_init(&err);
    double t0 = omp_get_wtime();
    CHECK(sl_kdtree_build(&t, pts, n, &err) == SL_OK);
    double t1 = omp_get_wtime();
    for (int64_t i = 0; i < (int64_t)n; i++)
        sl_kdtree_knn(t, pts + 3 * i, k, serial + i * k, NULL);
    double t2 = omp_get_wtime();
#pragma omp parallel for schedule(dynamic, 1024) num_threads(2)
    for (int64_t i = 0; i < (int64_t)n; i++)
        sl_kdtree_knn(t, pts + 3 * i, k, parallel + i * k, NULL);
    double t3 = omp_get_wtime();
    CHECK(memcmp(serial, parallel, (size_t)n * k * sizeof *serial) == 0);
    printf("kdtree 1M points on a sphere: build %.3f s, 12-NN of every point %.3f s (1 thread), "
           "%.3f s (2 threads)\n", t1 - t0, t2 - t1, t3 - t2);
    sl_kdtree_free(t);
    free(pts), free(serial), free(parallel);
}

int main(void)
{
    test_exact();
    test_edges();
    test_parallel_and_timing();
    return check_report();
}
