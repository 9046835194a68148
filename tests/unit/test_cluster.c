/* The clustering method (stages/cluster/cluster.h) on analytic meshes: a subdivided cube
 * collapses to 12 triangles with a bound of ~0; on a sphere, a torus and an open grid the
 * measured symmetric Hausdorff distance (geometry/mesh_distance.h, the measure of
 * `scanlod compare`) never exceeds the proven bound, which never exceeds the target;
 * intermediate models are strictly between the two levels, decreasing, each within the
 * level's bound; budgets; passes; threads; bad input. */
#include <omp.h>
#include <string.h>

#include "geometry/mesh.h"
#include "geometry/mesh_distance.h"
#include "stages/cluster/cluster.h"
#include "tests/check.h"
#include "tests/unit/analytic_meshes.h"

static sl_cluster_input input_of(const test_mesh *m)
{
    sl_cluster_input in;
    memset(&in, 0, sizeof in);
    in.vertex_count = m->vertex_count;
    in.positions = m->positions;
    in.triangle_count = m->triangle_count;
    in.triangles = m->triangles;
    return in;
}

/* Symmetric Hausdorff distance (world) between the input and a mesh on its vertices. */
static double measured(const test_mesh *m, uint64_t vertex_count, float *positions,
                       uint64_t triangle_count, uint32_t *triangles)
{
    sl_mesh a = sl_mesh_view(m->vertex_count, m->positions, NULL, NULL, m->triangle_count,
                             m->triangles);
    sl_mesh b = sl_mesh_view(vertex_count, positions, NULL, NULL, triangle_count, triangles);
    sl_mesh_distance_config dc = sl_mesh_distance_default_config();
    dc.samples = 200000;
    sl_mesh_distance d;
    sl_error err;
    sl_error_init(&err);
    if (sl_mesh_distance_compute(&a, &b, &dc, &d, NULL, &err))
        return INFINITY;
    return d.world.hausdorff;
}

static double measured_level(const test_mesh *m, const sl_cluster_level *l)
{
    return measured(m, m->vertex_count, m->positions, l->triangle_count, l->triangles);
}

static int u64_cmp(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Every edge of the level in exactly two triangles. */
static int watertight(uint64_t triangle_count, const uint32_t *t)
{
    uint64_t n = 3 * triangle_count;
    uint64_t *e = malloc((n ? n : 1) * sizeof *e);
    for (uint64_t i = 0; i < n; i++) {
        uint64_t a = t[i], b = t[i % 3 == 2 ? i - 2 : i + 1];
        e[i] = a < b ? a << 32 | b : b << 32 | a;
    }
    qsort(e, n, sizeof *e, u64_cmp);
    int ok = 1;
    for (uint64_t i = 0; i < n;) {
        uint64_t j = i;
        while (j < n && e[j] == e[i])
            j++;
        ok &= j - i == 2;
        i = j;
    }
    free(e);
    return ok && n > 0;
}

static double diagonal_of(const test_mesh *m)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->positions[3 * v + k]);
            hi[k] = fmax(hi[k], m->positions[3 * v + k]);
        }
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

static void test_cube(void)
{
    test_mesh m = tm_cube(4);
    sl_cluster_config cfg = sl_cluster_default_config();
    sl_cluster_input in = input_of(&m);
    sl_cluster_target target = {1e-4, 0, 0};
    sl_cluster_level l;
    sl_error err;
    sl_error_init(&err);
    CHECK_EQ_U64(sl_cluster_simplify(&cfg, &in, &target, &l, NULL, &err), 0);
    CHECK_EQ_U64(l.triangle_count, 12);
    CHECK_MSG(l.bound_fraction < 1e-5, "cube bound %g", l.bound_fraction);
    CHECK(watertight(l.triangle_count, l.triangles));
    CHECK_EQ_U64(l.pass[0].clusters, 6);
    CHECK_EQ_U64(l.pass[0].corners, 8);
    CHECK(measured_level(&m, &l) <= l.bound);
    sl_cluster_level_release(&l);
    tm_free(&m);
}

/* The bound holds and the target is met, for a few bounds and pass counts. */
static void test_bound(const char *name, const test_mesh *m, uint32_t passes)
{
    sl_cluster_config cfg = sl_cluster_default_config();
    cfg.passes = passes;
    sl_cluster_input in = input_of(m);
    double diag = diagonal_of(m);
    static const double bounds[] = {0.001, 0.005, 0.01, 0.02, 0.05};
    uint64_t previous = m->triangle_count;
    for (size_t i = 0; i < sizeof bounds / sizeof bounds[0]; i++) {
        sl_cluster_target target = {bounds[i], 0, 0};
        sl_cluster_level l;
        sl_error err;
        sl_error_init(&err);
        int rc = sl_cluster_simplify(&cfg, &in, &target, &l, NULL, &err);
        CHECK_MSG(rc == 0, "%s: %s", name, err.message);
        if (rc)
            continue;
        double h = measured_level(m, &l);
        printf("%s passes %u bound %.3f%%: %llu -> %llu triangles, bound %.4f%%, measured "
               "%.4f%%\n", name, passes, 100 * bounds[i], (unsigned long long)m->triangle_count,
               (unsigned long long)l.triangle_count, 100 * l.bound / diag, 100 * h / diag);
        CHECK_MSG(h <= l.bound, "%s %g: measured %g > bound %g", name, bounds[i], h, l.bound);
        CHECK_MSG(l.bound <= bounds[i] * diag, "%s: bound %g > target %g", name, l.bound,
                  bounds[i] * diag);
        CHECK_MSG(l.triangle_count <= previous, "%s: %llu triangles after %llu", name,
                  (unsigned long long)l.triangle_count, (unsigned long long)previous);
        CHECK(l.reached);
        previous = l.triangle_count;
        sl_cluster_level_release(&l);
    }
    CHECK_MSG(previous < m->triangle_count / 4, "%s: only down to %llu of %u", name,
              (unsigned long long)previous, m->triangle_count);
}

/* Intermediate models: counts strictly between, decreasing; bounds within the level's,
 * and measured within their own. */
static void test_intermediates(const char *name, const test_mesh *m, double bound, uint32_t count)
{
    sl_cluster_config cfg = sl_cluster_default_config();
    sl_cluster_input in = input_of(m);
    sl_cluster_target target = {bound, 0, count};
    sl_cluster_level l;
    sl_error err;
    sl_error_init(&err);
    CHECK_EQ_U64(sl_cluster_simplify(&cfg, &in, &target, &l, NULL, &err), 0);
    CHECK_EQ_U64(l.intermediate_count, count);
    uint64_t previous = m->triangle_count;
    printf("%s intermediates:", name);
    for (uint32_t j = 0; j < l.intermediate_count; j++) {
        const sl_cluster_intermediate *im = &l.intermediates[j];
        printf(" %llu", (unsigned long long)im->triangle_count);
        CHECK_MSG(im->triangle_count < previous, "%s: intermediate %u has %llu, after %llu",
                  name, j + 1, (unsigned long long)im->triangle_count,
                  (unsigned long long)previous);
        CHECK_MSG(im->triangle_count > l.triangle_count, "%s: intermediate %u has %llu <= %llu",
                  name, j + 1, (unsigned long long)im->triangle_count,
                  (unsigned long long)l.triangle_count);
        CHECK_MSG(im->bound <= l.bound, "%s: intermediate %u bound %g > %g", name, j + 1,
                  im->bound, l.bound);
        double h = measured(m, im->vertex_count, im->positions, im->triangle_count, im->triangles);
        CHECK_MSG(h <= im->bound, "%s: intermediate %u measured %g > its bound %g", name, j + 1,
                  h, im->bound);
        CHECK(watertight(im->triangle_count, im->triangles));
        previous = im->triangle_count;
    }
    printf(" -> %llu\n", (unsigned long long)l.triangle_count);
    sl_cluster_level_release(&l);
}

static void test_budget(const test_mesh *m)
{
    sl_cluster_config cfg = sl_cluster_default_config();
    sl_cluster_input in = input_of(m);
    sl_cluster_target target = {0, 300, 0};
    sl_cluster_level l;
    sl_error err;
    sl_error_init(&err);
    CHECK_EQ_U64(sl_cluster_simplify(&cfg, &in, &target, &l, NULL, &err), 0);
    CHECK(l.triangle_count <= 300 && l.triangle_count > 150);
    CHECK(l.reached);
    CHECK(measured_level(m, &l) <= l.bound);
    printf("budget 300: %llu triangles, bound %.4f%%\n", (unsigned long long)l.triangle_count,
           100 * l.bound_fraction);
    sl_cluster_level_release(&l);
    target.triangles = 4; /* below what 60 degree clusters can make of a sphere */
    CHECK_EQ_U64(sl_cluster_simplify(&cfg, &in, &target, &l, NULL, &err), 0);
    CHECK(!l.reached && l.triangle_count > 4);
    sl_cluster_level_release(&l);
    target.triangles = m->triangle_count; /* met already: unchanged, bound 0 */
    CHECK_EQ_U64(sl_cluster_simplify(&cfg, &in, &target, &l, NULL, &err), 0);
    CHECK(l.reached && l.triangle_count == m->triangle_count && l.bound == 0.0);
    sl_cluster_level_release(&l);
}

/* 1 and 2 threads give the same bytes (the mesh is above the size a call runs serially). */
static void test_threads(const test_mesh *m)
{
    sl_cluster_config cfg = sl_cluster_default_config();
    sl_cluster_input in = input_of(m);
    sl_cluster_target target = {0.01, 0, 3};
    sl_cluster_level l[2];
    for (int t = 0; t < 2; t++) {
        omp_set_num_threads(t + 1);
        sl_error err;
        sl_error_init(&err);
        CHECK_EQ_U64(sl_cluster_simplify(&cfg, &in, &target, &l[t], NULL, &err), 0);
    }
    CHECK(l[0].triangle_count == l[1].triangle_count &&
          !memcmp(l[0].triangles, l[1].triangles, 12 * l[0].triangle_count));
    CHECK(l[0].bound == l[1].bound);
    for (uint32_t j = 0; j < 3; j++)
        CHECK(l[0].intermediates[j].triangle_count == l[1].intermediates[j].triangle_count &&
              !memcmp(l[0].intermediates[j].positions, l[1].intermediates[j].positions,
                      12 * l[0].intermediates[j].vertex_count));
    sl_cluster_level_release(&l[0]);
    sl_cluster_level_release(&l[1]);
    omp_set_num_threads(2);
}

static int refuses(const sl_cluster_input *in, double bound, uint64_t triangles, uint32_t m,
                   int code, const char *words)
{
    sl_cluster_config cfg = sl_cluster_default_config();
    sl_cluster_target target = {bound, triangles, m};
    sl_cluster_level l;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_cluster_simplify(&cfg, in, &target, &l, NULL, &err);
    int ok = rc == code && strstr(err.message, words) != NULL && l.triangles == NULL;
    if (!ok)
        fprintf(stderr, "refusal: rc %d (wanted %d), '%s' (wanted '%s')\n", rc, code,
                err.message, words);
    if (!rc)
        sl_cluster_level_release(&l);
    return ok;
}

static void test_bad_input(void)
{
    test_mesh cube = tm_cube(2);
    sl_cluster_input in = input_of(&cube);
    CHECK(refuses(&in, 0.0, 0, 0, SL_E_USAGE, "either a bound"));
    CHECK(refuses(&in, -0.01, 0, 0, SL_E_USAGE, "not a fraction"));
    CHECK(refuses(&in, NAN, 0, 0, SL_E_USAGE, "not a fraction"));
    CHECK(refuses(&in, 2.0, 0, 0, SL_E_USAGE, "not a fraction"));
    CHECK(refuses(&in, 0.01, 100, 0, SL_E_USAGE, "either a bound"));
    CHECK(refuses(&in, 0.01, 0, 1000000, SL_E_USAGE, "intermediate models: at most"));
    /* An open grid, a non-manifold edge and a degenerate triangle: refused in strict mode,
     * kept otherwise (and the bound holds). */
    test_mesh grid = tm_grid(16, NULL);
    sl_cluster_input open = input_of(&grid);
    open.flags = SL_CLUSTER_STRICT;
    CHECK(refuses(&open, 0.01, 0, 0, SL_E_BADINPUT, "the surface is open"));
    test_mesh book = tm_cube(2);
    uint32_t extra = tm_vertex(&book, 1, 1, 1);
    tm_triangle(&book, book.triangles[0], book.triangles[1], extra); /* a third page */
    sl_cluster_input nm = input_of(&book);
    nm.flags = SL_CLUSTER_STRICT;
    CHECK(refuses(&nm, 0.01, 0, 0, SL_E_BADINPUT, "non-manifold"));
    test_mesh degen = tm_cube(2);
    tm_triangle(&degen, 0, 0, 1);
    sl_cluster_input dg = input_of(&degen);
    dg.flags = SL_CLUSTER_STRICT;
    CHECK(refuses(&dg, 0.01, 0, 0, SL_E_BADINPUT, "repeat a corner"));
    nm.flags = dg.flags = 0;
    sl_cluster_config cfg = sl_cluster_default_config();
    sl_cluster_target target = {0.01, 0, 0};
    sl_cluster_level l;
    sl_error err;
    sl_error_init(&err);
    CHECK_EQ_U64(sl_cluster_simplify(&cfg, &nm, &target, &l, NULL, &err), 0);
    CHECK(l.nonmanifold_edges == 1);
    sl_cluster_level_release(&l);
    CHECK_EQ_U64(sl_cluster_simplify(&cfg, &dg, &target, &l, NULL, &err), 0);
    CHECK(l.degenerate_triangles == 1 && l.triangle_count == 12);
    sl_cluster_level_release(&l);
    /* Indices out of range, NaN coordinates, a zero-size box, no triangle. */
    cube.triangles[5] = 99;
    CHECK(refuses(&in, 0.01, 0, 0, SL_E_BADINPUT, "names vertex 99"));
    cube.triangles[5] = 0;
    cube.positions[1] = NAN;
    CHECK(refuses(&in, 0.01, 0, 0, SL_E_BADINPUT, "non-finite"));
    for (uint32_t i = 0; i < 3 * cube.vertex_count; i++)
        cube.positions[i] = 1.0f;
    CHECK(refuses(&in, 0.01, 0, 0, SL_E_BADINPUT, "zero-size"));
    in.triangle_count = 0;
    CHECK(refuses(&in, 0.01, 0, 0, SL_E_BADINPUT, "no triangle"));
    tm_free(&cube);
    tm_free(&grid);
    tm_free(&book);
    tm_free(&degen);
}

static double wavy(double x, double y)
{
    return 0.05 * sin(6 * x) * cos(5 * y);
}

int main(void)
{
    test_cube();
    test_mesh sphere = tm_sphere(96, 48);
    test_mesh torus = tm_torus(96, 48, 1.0, 0.35);
    test_mesh grid = tm_grid(40, wavy);
    test_bound("sphere", &sphere, 1);
    test_bound("sphere", &sphere, 3);
    test_bound("torus", &torus, 1);
    test_bound("open wavy grid", &grid, 1);
    test_intermediates("sphere", &sphere, 0.02, 10);
    test_intermediates("torus", &torus, 0.01, 4);
    test_budget(&sphere);
    test_mesh big = tm_torus(256, 128, 1.0, 0.35);
    test_threads(&big);
    tm_free(&big);
    test_bad_input();
    tm_free(&sphere);
    tm_free(&torus);
    tm_free(&grid);
    return check_report();
}
