/* The samples stage: options; a generated sphere against the analytic signed distance;
 * the sampled vertices against a brute-force count of band-cube corners; the stage on a
 * real scan (range stage first) giving byte-identical .vdb files on 1 and 2 threads and on
 * two runs, its samples read back exactly; degenerate clouds; a corrupted .vdb; an
 * interrupt leaving nothing behind.
 * With SCANLOD_SAMPLES_MEASURE=1 it also prints the distance-variant comparison of
 * docs/samples-stage.md: plain marching cubes over the samples against the input surface
 * (geometry/mesh_distance.h, what `scanlod compare` prints) on fandisk, armadillo_86kf and
 * bun_zipper from the shared data. */
#include <dirent.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/hash.h"
#include "geometry/mesh_distance.h"
#include "formats/ply.h"
#include "pipeline/config.h"
#include "geometry/key_table.h"
#include "stages/registry.h"
#include "stages/samples/samples.h"
#include "tests/check.h"
#include "tests/stages/stage_fixtures.h"

static char tmp_root[256];

static int count_files(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int n = 0;
    while (d && (e = readdir(d)))
        n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    if (d)
        closedir(d);
    return n;
}

static void test_options(void)
{
    const sl_option *tables[] = {sl_samples_stage.options, NULL};
    const char *ov[] = {"octree.depth=9", "samples.distance=euclidean", "samples.band=2",
                        "octree.spacing_factor=2.5", "samples.sign_neighbours=8"};
    sl_config *cfg = NULL;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, tables, NULL, ov, 5, &err) == SL_OK);
    void *sc = NULL;
    CHECK(cfg && sl_samples_stage.configure(cfg, &sc, &err) == SL_OK);
    const sl_samples_config *c = sc;
    CHECK(c && c->depth == 9 && c->distance == SL_SAMPLES_EUCLIDEAN && c->band == 2);
    CHECK(c && c->spacing_factor == 2.5 && c->sign_neighbours == 8 && c->max_depth == 16);
    CHECK(c && c->max_samples == (uint64_t)1 << 31 && c->leaf_size == 0);
    sl_samples_stage.release_config(sc);
    sl_config_free(cfg);
    /* depth above max_depth: a config error, not an item failure. */
    const char *bad[] = {"octree.depth=12", "octree.max_depth=10"};
    CHECK(sl_config_load(&cfg, tables, NULL, bad, 2, &err) == SL_OK);
    sl_error_init(&err);
    CHECK(cfg && sl_samples_stage.configure(cfg, &sc, &err) == SL_E_CONFIG);
    sl_config_free(cfg);
    CHECK(sl_stage_find("samples") == &sl_samples_stage);
    CHECK(sl_samples_stage.sections && !strcmp(sl_samples_stage.sections[1], "octree"));
    sl_samples_config d = sl_samples_default_config();
    CHECK(d.distance == SL_SAMPLES_TANGENT && d.band == 1 && d.sign_neighbours == 1);
}

/* Points on a sphere (Fibonacci lattice) with exact outward normals. */
static sl_pointset sphere_points(uint64_t n, const double c[3], double r, int with_colors)
{
    sl_pointset ps;
    memset(&ps, 0, sizeof ps);
    ps.count = n;
    ps.positions = malloc(12 * n);
    ps.normals = malloc(12 * n);
    ps.colors = with_colors ? malloc(4 * n) : NULL;
    double golden = M_PI * (3.0 - sqrt(5.0));
    for (uint64_t i = 0; i < n; i++) {
        double z = 1.0 - 2.0 * (i + 0.5) / n, s = sqrt(1.0 - z * z), t = golden * i;
        double u[3] = {s * cos(t), s * sin(t), z};
        for (int k = 0; k < 3; k++) {
            ps.normals[3 * i + k] = (float)u[k];
            ps.positions[3 * i + k] = (float)(c[k] + r * u[k]);
        }
        if (with_colors)
            for (int k = 0; k < 4; k++)
                ps.colors[4 * i + k] = (uint8_t)(i * (k + 1));
    }
    ps.mean_spacing = sqrt(4 * M_PI * r * r / n);
    return ps;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Distinct corners of the band cubes, brute force: every point's cube, every cube of its
 * (2b+1)^3 neighbourhood, every corner of those, all in one array, sorted, unique. */
static uint64_t brute_force_vertices(const sl_pointset *ps, const sl_samples_plan *p,
                                     uint64_t **out)
{
    int b = p->band, w = 2 * b + 1;
    uint64_t cap = ps->count * (uint64_t)(w * w * w) * 8, n = 0;
    uint64_t *keys = malloc(cap * sizeof *keys);
    for (uint64_t i = 0; i < ps->count; i++) {
        int64_t cube[3];
        for (int k = 0; k < 3; k++) {
            double c = floor((ps->positions[3 * i + k] - p->origin[k]) / p->leaf_size);
            cube[k] = c < b ? b : c > b + p->cells[k] - 1.0 ? b + p->cells[k] - 1 : (int64_t)c;
        }
        for (int dx = -b; dx <= b + 1; dx++)
            for (int dy = -b; dy <= b + 1; dy++)
                for (int dz = -b; dz <= b + 1; dz++)
                    keys[n++] = sl_vertex_key((uint32_t)(cube[0] + dx), (uint32_t)(cube[1] + dy),
                                               (uint32_t)(cube[2] + dz));
    }
    qsort(keys, n, sizeof *keys, cmp_u64);
    uint64_t m = 0;
    for (uint64_t i = 0; i < n; i++)
        if (m == 0 || keys[i] != keys[m - 1])
            keys[m++] = keys[i];
    *out = keys;
    return m;
}

static int coords_less(const int32_t *a, const int32_t *b)
{
    return a[0] != b[0] ? a[0] < b[0] : a[1] != b[1] ? a[1] < b[1] : a[2] < b[2];
}

static void test_sphere(int distance, int sign_neighbours)
{
    const double c[3] = {0.3, -0.2, 0.1}, r = 1.0;
    sl_pointset ps = sphere_points(20000, c, r, 1);
    sl_samples_config cfg = sl_samples_default_config();
    cfg.distance = distance;
    cfg.sign_neighbours = sign_neighbours;
    cfg.leaf_size = 0.03; /* ~80000 samples: the parallel merges use several chunks */
    sl_vdb_samples s;
    sl_samples_counts counts;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_samples_compute(&cfg, &ps, &s, &counts, NULL, &err) == SL_OK);
    double leaf = counts.plan.leaf_size, worst = 0;
    uint64_t wrong_sign = 0, far = 0, sorted = 1;
    for (uint64_t i = 0; i < s.count; i++) {
        double v[3], d2 = 0;
        for (int k = 0; k < 3; k++) {
            v[k] = s.origin[k] + s.leaf_size * s.coords[3 * i + k] - c[k];
            d2 += v[k] * v[k];
        }
        double exact = sqrt(d2) - r, got = s.distance[i];
        if (distance == SL_SAMPLES_TANGENT && fabs(got - exact) > worst)
            worst = fabs(got - exact);
        if (fabs(exact) > 0.5 * leaf) {
            far++;
            wrong_sign += (got < 0) != (exact < 0);
        }
        if (i > 0 && !coords_less(&s.coords[3 * i - 3], &s.coords[3 * i]))
            sorted = 0;
    }
    CHECK(sorted && s.colors != NULL && counts.samples == s.count);
    CHECK_MSG(wrong_sign == 0, "%llu of %llu far vertices have the wrong sign",
              (unsigned long long)wrong_sign, (unsigned long long)far);
    if (distance == SL_SAMPLES_TANGENT)
        CHECK_MSG(worst <= 0.25 * leaf, "tangent distance off by %g > 0.25 leaf (%g)", worst, leaf);
    CHECK(counts.inside + counts.outside == s.count && counts.inside > 0 && counts.outside > 0);
    /* All samples inside the root: [0, 2^depth] on every axis. */
    int32_t lo = INT32_MAX, hi = INT32_MIN;
    for (uint64_t i = 0; i < 3 * s.count; i++)
        lo = s.coords[i] < lo ? s.coords[i] : lo, hi = s.coords[i] > hi ? s.coords[i] : hi;
    CHECK(lo == 0 && hi <= (1 << counts.plan.depth) && hi > (1 << (counts.plan.depth - 1)));
    /* Vertex set = brute-force corners of band cubes. */
    uint64_t *keys = NULL, n = brute_force_vertices(&ps, &counts.plan, &keys), same = n == s.count;
    for (uint64_t i = 0; same && i < n; i++)
        same = keys[i] == sl_vertex_key((uint32_t)s.coords[3 * i], (uint32_t)s.coords[3 * i + 1],
                                         (uint32_t)s.coords[3 * i + 2]);
    CHECK_MSG(same, "%llu samples, brute force %llu", (unsigned long long)s.count,
              (unsigned long long)n);
    CHECK(sign_neighbours > 1 || counts.sign_flips == 0);
    printf("  sphere (%s, sign k %d): %llu samples, %llu occupied, %llu band cubes, worst |error| "
           "%.4f leaf\n", distance == SL_SAMPLES_TANGENT ? "tangent" : "euclidean",
           sign_neighbours, (unsigned long long)s.count,
           (unsigned long long)counts.occupied_cubes, (unsigned long long)counts.band_cubes,
           worst / leaf);
    /* Marching cubes over the samples is a closed surface near the sphere. */
    sl_mesh mc;
    sl_mesh_topology topo;
    CHECK(sl_samples_marching_cubes(&s, &mc, &err) == SL_OK && mc.triangle_count > 1000);
    CHECK(sl_mesh_topology_compute(&mc, &topo, &err) == SL_OK && topo.watertight);
    double off = 0;
    for (uint64_t i = 0; i < mc.vertex_count; i++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++)
            d2 += (mc.positions[3 * i + k] - c[k]) * (mc.positions[3 * i + k] - c[k]);
        off = fabs(sqrt(d2) - r) > off ? fabs(sqrt(d2) - r) : off;
    }
    CHECK_MSG(off < (distance == SL_SAMPLES_TANGENT ? 0.05 : 0.5) * leaf,
              "marching cubes vertex %g leaf off the sphere", off / leaf);
    free(keys);
    sl_mesh_release(&mc);
    sl_vdb_samples_release(&s);
    sl_pointset_release(&ps);
}

/* Samples of `ps` under `cfg`, released at once; OUT: counts. */
static int compute(const sl_pointset *ps, const sl_samples_config *cfg, sl_samples_counts *counts,
                   sl_error *err)
{
    sl_vdb_samples s;
    sl_error_init(err);
    int rc = sl_samples_compute(cfg, ps, &s, counts, NULL, err);
    CHECK(rc == SL_OK || (s.count == 0 && s.coords == NULL));
    sl_vdb_samples_release(&s);
    return rc;
}

/* `n` points from f(i, pos, nrm). */
static sl_pointset points_from(uint64_t n, void (*f)(uint64_t, float *, float *), double spacing)
{
    sl_pointset ps;
    memset(&ps, 0, sizeof ps);
    ps.count = n;
    ps.positions = malloc(12 * n + 1);
    ps.normals = malloc(12 * n + 1);
    for (uint64_t i = 0; i < n; i++)
        f(i, ps.positions + 3 * i, ps.normals + 3 * i);
    ps.mean_spacing = spacing;
    return ps;
}

static void one_point(uint64_t i, float *p, float *n)
{
    p[0] = 1, p[1] = 2, p[2] = 3, n[0] = 0, n[1] = 0, n[2] = 1;
    p[0] += (float)i; /* i = 1: the second of two points */
}
static void plane_point(uint64_t i, float *p, float *n)
{
    p[0] = (float)(i % 50) * 0.02f, p[1] = (float)(i / 50) * 0.02f, p[2] = 0.5f;
    n[0] = 0, n[1] = 0, n[2] = 1;
}
static void line_point(uint64_t i, float *p, float *n)
{
    p[0] = (float)i * 0.01f, p[1] = p[2] = 0, n[0] = 0, n[1] = 0.6f, n[2] = 0.8f;
}
static void far_clusters(uint64_t i, float *p, float *n)
{
    p[0] = (float)(i % 10) * 1e-4f + (i < 500 ? 0.0f : 1e6f);
    p[1] = (float)(i / 10 % 10) * 1e-4f, p[2] = (float)(i / 100) * 1e-4f;
    n[0] = 1, n[1] = n[2] = 0;
}

static void octahedron_point(uint64_t i, float *p, float *n)
{
    p[0] = p[1] = p[2] = 0;
    p[i / 2] = i % 2 ? -1.0f : 1.0f; /* (+-1, 0, 0), (0, +-1, 0), (0, 0, +-1) */
    memcpy(n, p, 3 * sizeof *p);
}

static void test_degenerate(void)
{
    sl_samples_config cfg = sl_samples_default_config();
    sl_samples_counts counts;
    sl_error err;
    sl_pointset ps = points_from(1, one_point, 0.0);
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_E_BADINPUT && strstr(err.message, "leaf_size"));
    cfg.depth = 5;
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_E_BADINPUT && strstr(err.message, "coincide"));
    cfg.depth = 0, cfg.leaf_size = 0.1; /* one cube, dilated: 3^3 cubes, 4^3 vertices */
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_OK && counts.samples == 64 &&
          counts.occupied_cubes == 1 && counts.band_cubes == 27 &&
          (counts.inside == 16 || counts.inside == 32)); /* the point sits on a grid plane */
    printf("  one point: %s\n", err.message[0] ? err.message : "64 samples with leaf_size");
    sl_pointset_release(&ps);

    cfg = sl_samples_default_config();
    ps = points_from(2, one_point, 0.5); /* leaf 0.75 < their distance 1 */
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_OK && counts.occupied_cubes == 2);
    sl_pointset_release(&ps);

    /* Six points sqrt(2) apart: 1.5 x the spacing (2.12) would be wider than the shape
     * (issue 16); the leaf is bounded by the diagonal / SL_SAMPLES_DIAGONAL_LEAVES. */
    ps = points_from(6, octahedron_point, sqrt(2.0));
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_OK);
    CHECK_NEAR(counts.plan.leaf_size, 2 * sqrt(3.0) / SL_SAMPLES_DIAGONAL_LEAVES, 1e-12);
    CHECK(counts.plan.depth >= 4 && counts.inside > 0);
    sl_pointset_release(&ps);

    ps = points_from(2500, plane_point, 0.02); /* coplanar: flat in z */
    sl_vdb_samples s;
    CHECK(sl_samples_compute(&cfg, &ps, &s, &counts, NULL, &err) == SL_OK);
    uint64_t wrong = 0;
    for (uint64_t i = 0; i < s.count; i++) {
        double z = s.origin[2] + s.leaf_size * s.coords[3 * i + 2] - 0.5;
        wrong += z != 0 && (z < 0) != (s.distance[i] < 0);
    }
    CHECK_MSG(wrong == 0 && counts.plan.cells[2] == 1 && s.count > 2500, "plane: %llu wrong",
              (unsigned long long)wrong);
    sl_vdb_samples_release(&s);
    sl_pointset_release(&ps);

    ps = points_from(1000, line_point, 0.01); /* collinear */
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_OK && counts.plan.cells[1] == 1);
    sl_pointset_release(&ps);

    /* A huge extent with tiny features: refused before anything is allocated. */
    ps = points_from(1000, far_clusters, 1e-4);
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_E_LIMIT && strstr(err.message, "max_depth"));
    printf("  far clusters: %s\n", err.message);
    cfg.leaf_size = 1e-3;
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_E_LIMIT);
    cfg.leaf_size = 0;
    ps.positions[7] = NAN;
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_E_BADINPUT && strstr(err.message, "finite"));
    ps.count = 0;
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_E_BADINPUT);
    sl_pointset_release(&ps);

    /* Too many samples for max_samples: refused by the counting pass. */
    const double c[3] = {0, 0, 0};
    ps = sphere_points(5000, c, 1.0, 0);
    cfg.max_samples = 1000;
    CHECK(compute(&ps, &cfg, &counts, &err) == SL_E_LIMIT && strstr(err.message, "max_samples"));
    sl_pointset_release(&ps);
}

/* Runs the stage on in_dir into a fresh out_dir; *report gets its report text. */
static int run_stage(const char *in_dir, const char *out, int threads,
                     volatile sig_atomic_t *interrupt, char **report)
{
    const sl_option *tables[] = {sl_samples_stage.options, NULL};
    sl_config *cfg = NULL;
    void *sc = NULL;
    sl_error err;
    sl_error_init(&err);
    mkdir(out, 0755);
    if (sl_config_load(&cfg, tables, NULL, NULL, 0, &err) || sl_samples_stage.configure(cfg, &sc, &err))
        return -100;
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_progress progress = {NULL, NULL, interrupt};
    sl_stage_io io = {.item = "item", .source_path = "unused.ply", .in_dir = in_dir,
                      .out_dir = out, .report = &j, .progress = &progress, .threads = threads};
    omp_set_num_threads(threads);
    int rc = sl_samples_stage.run(sc, &io, &err);
    sl_json_object_end(&j);
    if (rc != SL_OK && rc != SL_E_INTERRUPTED)
        fprintf(stderr, "  (stage: %s: %s: %s)\n", sl_error_name(rc), err.file, err.message);
    if (report)
        *report = strdup(j.buf ? j.buf : "");
    sl_json_release(&j);
    sl_samples_stage.release_config(sc);
    sl_config_free(cfg);
    return rc;
}

static void test_stage_on(const char *ply, const char *name)
{
    char in[300], out[3][300], vdb[3][1000], pts[400];
    snprintf(in, sizeof in, "%s/%s-points", tmp_root, name);
    CHECK(fixture_range_points(ply, in) == SL_OK);
    char *report[3] = {NULL, NULL, NULL};
    const int threads[3] = {1, 2, 2};
    double secs[3];
    for (int r = 0; r < 3; r++) {
        snprintf(out[r], sizeof out[r], "%s/%s-out%d", tmp_root, name, r);
        snprintf(vdb[r], sizeof vdb[r], "%s/%s", out[r], SL_SAMPLES_FILE);
        double t0 = omp_get_wtime();
        CHECK(run_stage(in, out[r], threads[r], NULL, &report[r]) == SL_OK);
        secs[r] = omp_get_wtime() - t0;
    }
    CHECK_MSG(fixture_same_file(vdb[0], vdb[1]), "%s: samples.vdb differs between 1 and 2 threads", name);
    CHECK_MSG(fixture_same_file(vdb[1], vdb[2]), "%s: samples.vdb differs between two runs", name);
    CHECK(report[0] && report[1] && !strcmp(report[0], report[1]) && strstr(report[0], "\"samples\":"));
    printf("  %s: samples stage %.3f s (1 thread), %.3f s (2 threads)\n    %s\n", name, secs[0],
           secs[1], report[0] ? report[0] : "");

    /* The file holds exactly what sl_samples_compute gives. */
    sl_pointset ps;
    sl_vdb_samples a, b;
    sl_samples_counts counts;
    sl_error err;
    sl_error_init(&err);
    snprintf(pts, sizeof pts, "%s/%s", in, SL_POINTSET_FILE);
    sl_samples_config cfg = sl_samples_default_config();
    CHECK(sl_pointset_read(pts, &ps, &err) == SL_OK);
    CHECK(sl_samples_compute(&cfg, &ps, &a, &counts, NULL, &err) == SL_OK);
    CHECK(sl_vdb_samples_read(vdb[0], UINT64_MAX, &b, &err) == SL_OK);
    CHECK(a.count == b.count && a.leaf_size == b.leaf_size && !a.colors == !b.colors &&
          !memcmp(a.origin, b.origin, sizeof a.origin) &&
          !memcmp(a.coords, b.coords, 12 * a.count) && !memcmp(a.distance, b.distance, 4 * a.count) &&
          (!a.colors || !memcmp(a.colors, b.colors, 4 * a.count)));
    sl_vdb_samples_release(&a);
    sl_vdb_samples_release(&b);
    sl_pointset_release(&ps);
    for (int r = 0; r < 3; r++)
        free(report[r]);
}

static void test_stage(void)
{
    char buf[600], path[600];
    test_stage_on(check_source_path("tests/data/scans/bun_zipper_res3.ply", buf, sizeof buf), "res3");
    if (check_shared_path("bun_zipper.ply", buf, sizeof buf))
        test_stage_on(buf, "bun_zipper");

    /* A corrupted samples.vdb: a clear error naming it. */
    snprintf(path, sizeof path, "%s/res3-out0/%s", tmp_root, SL_SAMPLES_FILE);
    size_t n = 0;
    char *data = NULL;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_read_file(path, UINT64_C(1) << 30, &data, &n, &err) == SL_OK && n > 1000);
    if (data) {
        data[n / 2] ^= 1;
        FILE *f = fopen(path, "wb");
        fwrite(data, 1, n, f);
        fclose(f);
    }
    sl_vdb_samples s;
    sl_error_init(&err);
    CHECK(sl_vdb_samples_read(path, UINT64_MAX, &s, &err) == SL_E_CORRUPT &&
          strstr(err.file, SL_SAMPLES_FILE) && strstr(err.message, "hash"));
    printf("  corrupted: %s: %s\n", err.file, err.message);
    free(data);

    /* Interrupted: SL_E_INTERRUPTED and nothing written. Missing input: an error naming it. */
    volatile sig_atomic_t stop = 1;
    char in[400], out[400];
    snprintf(in, sizeof in, "%s/res3-points", tmp_root);
    snprintf(out, sizeof out, "%s/interrupted", tmp_root);
    CHECK(run_stage(in, out, 2, &stop, NULL) == SL_E_INTERRUPTED && count_files(out) == 0);
    snprintf(out, sizeof out, "%s/no-input", tmp_root);
    CHECK(run_stage(out, out, 2, NULL, NULL) != SL_OK && count_files(out) == 0);
}

/* One row of the distance-variant table: marching cubes over the samples vs the input. */
static void measure_one(const char *name, const sl_mesh *input, const sl_pointset *ps,
                        const sl_samples_config *cfg)
{
    sl_vdb_samples s;
    sl_samples_counts counts;
    sl_mesh mc;
    sl_mesh_distance dist;
    sl_mesh_topology topo;
    sl_mesh_distance_config dcfg = sl_mesh_distance_default_config();
    sl_error err;
    sl_error_init(&err);
    dcfg.samples = 300000;
    if (sl_samples_compute(cfg, ps, &s, &counts, NULL, &err) != SL_OK ||
        sl_samples_marching_cubes(&s, &mc, &err) != SL_OK ||
        sl_mesh_distance_compute(input, &mc, &dcfg, &dist, NULL, &err) != SL_OK ||
        sl_mesh_topology_compute(&mc, &topo, &err) != SL_OK) {
        printf("| %s | failed: %s |\n", name, err.message);
        return;
    }
    printf("| %s | %s | %d | %d | %.2f | %.4g | %llu | %llu | %.5f | %.5f | %.5f | %.2f | %llu |\n", name,
           counts.triangles ? "triangles"
           : cfg->distance == SL_SAMPLES_TANGENT ? "points, tangent" : "points, euclidean",
           cfg->sign_neighbours,
           cfg->band, cfg->spacing_factor, counts.plan.leaf_size, (unsigned long long)s.count,
           (unsigned long long)mc.triangle_count, dist.a_to_b.fraction.rms, dist.fraction.rms,
           dist.fraction.hausdorff, dist.a_to_b.world.hausdorff / counts.plan.leaf_size,
           (unsigned long long)topo.boundary_edges);
    fflush(stdout);
    sl_mesh_release(&mc);
    sl_vdb_samples_release(&s);
}

/* Reads `rel` (shared data) as the reference surface and its range-stage point set; a
 * point cloud's reference is the range stage's scanner-grid triangulation. */
static int load_input(const char *rel, sl_mesh *input, sl_pointset *ps, sl_error *err)
{
    char buf[600];
    sl_mesh work;
    sl_range_counts rc;
    sl_range_config rcfg = sl_range_default_config();
    if (!check_shared_path(rel, buf, sizeof buf))
        return sl_error_set(err, SL_E_IO, 0, rel, "no shared data");
    int rc1 = sl_ply_read(buf, NULL, input, NULL, NULL, err);
    if (rc1 || (rc1 = sl_ply_read(buf, NULL, &work, NULL, NULL, err)))
        return rc1;
    rc1 = sl_range_points_from_mesh(&rcfg, &work, NULL, ps, &rc, NULL, err);
    sl_mesh_release(&work);
    if (rc1 == SL_OK && input->triangle_count == 0 && ps->triangle_count > 0) {
        sl_mesh_release(input);
        input->vertex_count = ps->count;
        input->positions = malloc(12 * ps->count);
        memcpy(input->positions, ps->positions, 12 * ps->count);
        input->triangle_count = ps->triangle_count;
        input->triangles = malloc(12 * ps->triangle_count);
        memcpy(input->triangles, ps->triangles, 12 * ps->triangle_count);
    }
    return rc1;
}

/* Variants (distance, sign vote, spacing factor) on inputs with a full study; the default
 * alone on the others (closed inputs: is the finest level watertight?). */
void run_measurements(void)
{
    enum { FULL = 5 }; /* the first FULL inputs get every variant */
    static const char *const inputs[] = {"fandisk.ply", "armadillo_86kf.ply", "bun_zipper.ply",
                                         "igea.ply", "bunny_range/bun000.ply", "dragon_100kf.ply",
                                         "rocker_arm.ply", "cow.ply", "happy_buddha_100kf.ply", "horse.ply",
                                         NULL};
    /* closest, distance, sign_neighbours, band, spacing_factor; the first row is the
     * default, the second the paper */
    enum { T = SL_SAMPLES_CLOSEST_TRIANGLES, P = SL_SAMPLES_CLOSEST_POINTS };
    static const struct { int closest, distance, k, band; double factor; } variants[] = {
        {T, SL_SAMPLES_TANGENT, 1, 1, 1.5}, {P, SL_SAMPLES_TANGENT, 1, 1, 1.5},
        {P, SL_SAMPLES_EUCLIDEAN, 1, 1, 1.5}, {P, SL_SAMPLES_TANGENT, 8, 1, 1.5},
        {P, SL_SAMPLES_TANGENT, 1, 2, 1.5}, {P, SL_SAMPLES_TANGENT, 8, 2, 1.5},
        {T, SL_SAMPLES_TANGENT, 1, 1, 1.0}, {T, SL_SAMPLES_TANGENT, 1, 1, 2.0}};
    printf("| input | closest, distance | sign k | band | spacing factor | leaf | samples | triangles | RMS "
           "in->mc | RMS sym | Hausdorff sym | Hausdorff in->mc / leaf | boundary edges |\n");
    for (int i = 0; inputs[i]; i++) {
        const char *rel = inputs[i];
        sl_mesh input;
        sl_pointset ps;
        sl_error err;
        sl_error_init(&err);
        if (load_input(rel, &input, &ps, &err) != SL_OK) {
            printf("| %s | failed: %s |\n", rel, err.message);
            return;
        }
        int count = i < FULL ? (int)(sizeof variants / sizeof variants[0]) : 2;
        for (int v = 0; v < count; v++) {
            sl_samples_config cfg = sl_samples_default_config();
            cfg.closest = variants[v].closest;
            cfg.distance = variants[v].distance;
            cfg.sign_neighbours = variants[v].k;
            cfg.band = variants[v].band;
            cfg.spacing_factor = variants[v].factor;
            measure_one(rel, &input, &ps, &cfg);
        }
        sl_pointset_release(&ps);
        sl_mesh_release(&input);
    }
}

int main(void)
{
    snprintf(tmp_root, sizeof tmp_root, "/tmp/test_samples.XXXXXX");
    if (!mkdtemp(tmp_root))
        return 1;
    const char *measure = getenv("SCANLOD_SAMPLES_MEASURE");
    if (measure && measure[0] == '1') {
        run_measurements();
    } else {
        test_options();
        test_sphere(SL_SAMPLES_TANGENT, 1);
        test_sphere(SL_SAMPLES_EUCLIDEAN, 1);
        test_sphere(SL_SAMPLES_TANGENT, 8);
        test_degenerate();
        test_stage();
    }
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_root);
    if (system(cmd) != 0)
        fprintf(stderr, "cannot remove %s\n", tmp_root);
    return check_report();
}
