/* Surface distance and edge topology on analytic cases: spheres shifted and scaled
 * (closed-form Hausdorff and RMS), identical meshes, a cube with and without a face, a
 * non-manifold fan, bad meshes, and bit-identical results for 1 and 2 threads; one A
 * against many B (sl_distance_reference) bit-identical to the full measure on a bundled
 * scan. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "tests/check.h"
#include "geometry/mesh_distance.h"
#include "formats/ply.h"
#include "geometry/triangle_bvh.h"

/* Unit sphere from a cube: each face an n x n grid, projected onto the sphere, scaled
 * by `radius` and moved by `shift`. Face edges repeat their vertices (bit-identical
 * positions, so topology welds them). */
static void make_sphere(sl_mesh *m, int n, double radius, const double shift[3])
{
    sl_mesh_init(m);
    uint64_t per_face = (uint64_t)(n + 1) * (n + 1);
    m->vertex_count = 6 * per_face;
    m->triangle_count = 6 * 2 * (uint64_t)n * n;
    m->positions = malloc(3 * m->vertex_count * sizeof *m->positions);
    m->triangles = malloc(3 * m->triangle_count * sizeof *m->triangles);
    uint64_t v = 0, t = 0;
    for (int face = 0; face < 6; face++) {
        int axis = face / 2;
        double side = face % 2 ? 1.0 : -1.0;
        uint64_t base = v;
        for (int i = 0; i <= n; i++)
            for (int j = 0; j <= n; j++) {
                double q[3];
                q[axis] = side;
                q[(axis + 1) % 3] = -1.0 + 2.0 * i / n;
                q[(axis + 2) % 3] = -1.0 + 2.0 * j / n;
                double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
                for (int a = 0; a < 3; a++)
                    m->positions[3 * v + a] = (float)(q[a] / len * radius + shift[a]);
                v++;
            }
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                uint32_t c00 = (uint32_t)(base + i * (n + 1) + j), c01 = c00 + 1;
                uint32_t c10 = c00 + (uint32_t)(n + 1), c11 = c10 + 1;
                uint32_t quad[6] = {c00, c10, c11, c00, c11, c01};
                if (side < 0) { /* keep the outward orientation (not needed, but tidy) */
                    quad[1] = c11; quad[2] = c10; quad[4] = c01; quad[5] = c11;
                }
                memcpy(&m->triangles[3 * t], quad, sizeof quad);
                t += 2;
            }
    }
}

static void make_mesh(sl_mesh *m, const float *pos, uint64_t nv, const uint32_t *tri,
                      uint64_t nt)
{
    sl_mesh_init(m);
    m->vertex_count = nv;
    m->triangle_count = nt;
    m->positions = malloc(3 * nv * sizeof *pos + 1);
    m->triangles = malloc(3 * nt * sizeof *tri + 1);
    memcpy(m->positions, pos, 3 * nv * sizeof *pos);
    memcpy(m->triangles, tri, 3 * nt * sizeof *tri);
}

static const float cube_pos[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,
                                 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
static const uint32_t cube_tri[] = {0, 2, 1, 0, 3, 2, /* z = 0 */ 4, 5, 6, 4, 6, 7, /* z = 1 */
                                    0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5,
                                    2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};

static sl_mesh_distance distance_of(const sl_mesh *a, const sl_mesh *b, uint64_t samples)
{
    sl_mesh_distance_config cfg = sl_mesh_distance_default_config();
    cfg.samples = samples;
    sl_mesh_distance d;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_mesh_distance_compute(a, b, &cfg, &d, NULL, &err);
    CHECK_MSG(rc == SL_OK, "%s", err.message);
    return d;
}

static void test_closest_point(void)
{
    double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0}, q[3];
    double p1[3] = {0.2, 0.2, 0.5};  /* over the face */
    CHECK_NEAR(sl_closest_point_triangle(p1, a, b, c, q), 0.25, 1e-15);
    CHECK_NEAR(q[0], 0.2, 1e-15);
    double p2[3] = {-1, -1, 0};      /* vertex region of a */
    CHECK_NEAR(sl_closest_point_triangle(p2, a, b, c, q), 2.0, 1e-15);
    double p3[3] = {1, 1, 0};        /* edge bc */
    CHECK_NEAR(sl_closest_point_triangle(p3, a, b, c, q), 0.5, 1e-15);
    CHECK_NEAR(q[0], 0.5, 1e-15);
    double p4[3] = {0.5, -2, 1};     /* edge ab */
    CHECK_NEAR(sl_closest_point_triangle(p4, a, b, c, q), 5.0, 1e-15);
    /* Degenerate: collinear corners and a repeated corner behave as segments. */
    double d1[3] = {2, 0, 0}, p5[3] = {1.5, 1, 0};
    CHECK_NEAR(sl_closest_point_triangle(p5, a, b, d1, q), 1.0, 1e-15);
    CHECK_NEAR(sl_closest_point_triangle(p5, b, b, b, q), 1.25, 1e-15);
    CHECK(!isnan(q[0]));
}

/* The BVH answer equals brute force over all triangles for random points. */
static void test_bvh_matches_brute_force(void)
{
    sl_mesh m;
    double zero[3] = {0, 0, 0};
    make_sphere(&m, 12, 1.0, zero);
    sl_triangle_bvh bvh;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_triangle_bvh_build(&bvh, &m, &err) == SL_OK);
    srand(7);
    int mismatches = 0;
    for (int i = 0; i < 2000; i++) {
        double p[3], q[3], best = INFINITY;
        for (int a = 0; a < 3; a++)
            p[a] = 3.0 * rand() / RAND_MAX - 1.5;
        for (uint64_t t = 0; t < bvh.triangle_count; t++) {
            const float *f = &bvh.corners[9 * t];
            double x[3] = {f[0], f[1], f[2]}, y[3] = {f[3], f[4], f[5]}, z[3] = {f[6], f[7], f[8]};
            double d = sl_closest_point_triangle(p, x, y, z, q);
            best = d < best ? d : best;
        }
        sl_closest c;
        sl_triangle_bvh_closest(&bvh, p, (uint32_t)(i % 7), &c);
        mismatches += c.distance_sq != best;
    }
    CHECK_EQ_U64(mismatches, 0);
    sl_triangle_bvh_release(&bvh);
    sl_mesh_release(&m);
}

static void test_spheres(void)
{
    double zero[3] = {0, 0, 0}, shift[3] = {0.03, 0.04, 0.0}; /* |shift| = 0.05 */
    sl_mesh a, b, c;
    make_sphere(&a, 48, 1.0, zero);
    make_sphere(&b, 48, 1.0, shift);
    make_sphere(&c, 48, 1.2, zero);

    /* Tessellation: chords of ~0.03 sag ~5e-4 below the sphere. */
    sl_mesh_distance d = distance_of(&a, &b, 200000);
    CHECK_NEAR(d.world.hausdorff, 0.05, 2e-3);
    CHECK_NEAR(d.a_to_b.world.rms, 0.05 / sqrt(3.0), 1e-3); /* RMS = d / sqrt(3) */
    CHECK_NEAR(d.b_to_a.world.rms, 0.05 / sqrt(3.0), 1e-3);
    CHECK_NEAR(d.diagonal, 2.0 * sqrt(3.0), 1e-5);
    CHECK_NEAR(d.fraction.hausdorff, d.world.hausdorff / d.diagonal, 1e-15);
    CHECK(d.a_to_b.area_samples == 200000 && d.a_to_b.vertex_samples == a.vertex_count);

    d = distance_of(&a, &c, 200000); /* every point is 0.2 off */
    CHECK_NEAR(d.world.hausdorff, 0.2, 2e-3);
    CHECK_NEAR(d.a_to_b.world.rms, 0.2, 2e-3);
    CHECK_NEAR(d.b_to_a.world.mean, 0.2, 2e-3);

    d = distance_of(&a, &a, 100000);
    CHECK(d.world.hausdorff < 1e-9);

    /* Determinism: bit-identical for 1 and 2 threads. */
    int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    sl_mesh_distance d1 = distance_of(&a, &b, 100000);
    omp_set_num_threads(2);
    sl_mesh_distance d2 = distance_of(&a, &b, 100000);
    omp_set_num_threads(threads);
    CHECK(memcmp(&d1, &d2, sizeof d1) == 0);

    sl_mesh_topology topo;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_mesh_topology_compute(&a, &topo, &err) == SL_OK);
    CHECK(topo.watertight);
    CHECK_EQ_U64(topo.welded_vertices, 6 * 48 * 48 + 2); /* Euler: V = F/2 + 2 */
    sl_mesh_release(&a);
    sl_mesh_release(&b);
    sl_mesh_release(&c);
}

static sl_mesh_topology topology_of(const sl_mesh *m)
{
    sl_mesh_topology topo;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_mesh_topology_compute(m, &topo, &err) == SL_OK);
    return topo;
}

static void test_topology(void)
{
    sl_mesh m;
    make_mesh(&m, cube_pos, 8, cube_tri, 12);
    sl_mesh_topology t = topology_of(&m);
    CHECK(t.watertight && t.edges == 18 && t.boundary_edges == 0);
    sl_mesh_release(&m);

    make_mesh(&m, cube_pos, 8, cube_tri + 6, 10); /* z = 0 face removed */
    t = topology_of(&m);
    CHECK(!t.watertight);
    CHECK_EQ_U64(t.edges, 17);
    CHECK_EQ_U64(t.boundary_edges, 4);
    CHECK_EQ_U64(t.nonmanifold_edges, 0);
    sl_mesh_release(&m);

    /* Unwelded cube: every triangle with its own corners; welding restores it. */
    float soup[12 * 9];
    uint32_t soup_tri[36];
    for (int i = 0; i < 36; i++) {
        memcpy(&soup[3 * i], &cube_pos[3 * cube_tri[i]], 3 * sizeof(float));
        soup_tri[i] = (uint32_t)i;
    }
    soup[0] = -0.0f; /* -0 welds with +0 */
    make_mesh(&m, soup, 36, soup_tri, 12);
    t = topology_of(&m);
    CHECK(t.watertight && t.welded_vertices == 8 && t.edges == 18);
    sl_mesh_release(&m);

    /* Fan: three triangles on edge 0-1. */
    static const float fan_pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1};
    static const uint32_t fan_tri[] = {0, 1, 2, 0, 1, 3, 0, 1, 4, 2, 2, 1};
    make_mesh(&m, fan_pos, 5, fan_tri, 4);
    t = topology_of(&m);
    CHECK_EQ_U64(t.nonmanifold_edges, 1);
    CHECK_EQ_U64(t.boundary_edges, 6);
    CHECK_EQ_U64(t.edges, 7);
    CHECK_EQ_U64(t.degenerate_triangles, 1);
    CHECK(!t.watertight);
    sl_mesh_release(&m);
}

static void test_bad_meshes(void)
{
    sl_mesh good, bad;
    make_mesh(&good, cube_pos, 8, cube_tri, 12);
    sl_mesh_distance d;
    sl_error err;

    make_mesh(&bad, cube_pos, 8, cube_tri, 0);
    sl_error_init(&err);
    CHECK(sl_mesh_distance_compute(&good, &bad, NULL, &d, NULL, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.message, "mesh B: no triangles") != NULL);
    sl_mesh_release(&bad);

    make_mesh(&bad, cube_pos, 8, cube_tri, 12);
    bad.positions[7] = NAN;
    sl_error_init(&err);
    CHECK(sl_mesh_distance_compute(&bad, &good, NULL, &d, NULL, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.message, "mesh A: vertex 2 has a non-finite coordinate") != NULL);
    sl_mesh_release(&bad);

    static const uint32_t flat[] = {0, 1, 1, 2, 2, 2};
    make_mesh(&bad, cube_pos, 8, flat, 2);
    sl_error_init(&err);
    CHECK(sl_mesh_distance_compute(&good, &bad, NULL, &d, NULL, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.message, "zero area") != NULL);
    sl_error_init(&err);
    CHECK(sl_mesh_check_surface(&bad, "flat.ply", &err) == SL_E_BADINPUT);
    CHECK(!strcmp(err.file, "flat.ply") && !strcmp(err.message, "every triangle has zero area"));
    sl_mesh_release(&bad);
    sl_mesh_release(&good);
}

/* A point cloud as A: distances from its points only, mean and rms over them. */
static void test_points_as_a(void)
{
    static const float pts[] = {0.5f, 0.5f, 1.2f, 0.5f, 0.5f, 0.5f, 2, 0, 0};
    sl_mesh cube, cloud;
    make_mesh(&cube, cube_pos, 8, cube_tri, 12);
    make_mesh(&cloud, pts, 3, cube_tri, 0);
    sl_mesh_distance d;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_mesh_distance_compute(&cloud, &cube, NULL, &d, NULL, &err) == SL_OK);
    CHECK(d.a_is_points);
    CHECK_EQ_U64(d.a_to_b.vertex_samples, 3);
    CHECK_EQ_U64(d.a_to_b.area_samples, 0);
    CHECK_NEAR(d.a_to_b.world.hausdorff, 1.0, 1e-6);
    CHECK_NEAR(d.a_to_b.world.mean, (0.2 + 0.5 + 1.0) / 3, 1e-6);
    CHECK_NEAR(d.a_to_b.world.rms, sqrt((0.04 + 0.25 + 1.0) / 3), 1e-6);
    CHECK_NEAR(d.world.hausdorff, 1.0, 1e-6); /* symmetric = the one side measured */
    CHECK_NEAR(d.diagonal, sqrt(1.5 * 1.5 + 0.5 * 0.5 + 1.2 * 1.2), 1e-6);
    cloud.positions[4] = NAN;
    CHECK(sl_mesh_distance_compute(&cloud, &cube, NULL, &d, NULL, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.message, "mesh A: point 1 has a non-finite coordinate") != NULL);
    sl_mesh_release(&cloud);
    sl_mesh_release(&cube);
}

/* The Voronoi region of a closest point (what signed distance needs). */
static void test_closest_feature(void)
{
    const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
    static const struct { double p[3]; int feature; } cases[] = {
        {{0.2, 0.2, 1}, SL_FEATURE_FACE},     {{-1, -1, 0.5}, SL_FEATURE_VERTEX_A},
        {{2, -0.1, 0}, SL_FEATURE_VERTEX_B},  {{-0.1, 3, 1}, SL_FEATURE_VERTEX_C},
        {{0.5, -1, 0.2}, SL_FEATURE_EDGE_AB}, {{1, 1, -0.5}, SL_FEATURE_EDGE_BC},
        {{-1, 0.5, 0.3}, SL_FEATURE_EDGE_CA}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double q[3];
        int feature = -1;
        sl_closest_point_triangle_feature(cases[i].p, a, b, c, q, &feature);
        CHECK_MSG(feature == cases[i].feature, "case %zu: feature %d, want %d", i, feature,
                  cases[i].feature);
    }
    /* a sliver (collinear corners): the closest point is on an edge or a corner */
    const double s[3] = {2, 0, 0}, p[3] = {3, 1, 0};
    double q[3];
    int feature = -1;
    sl_closest_point_triangle_feature(p, a, b, s, q, &feature);
    CHECK(feature == SL_FEATURE_VERTEX_C && q[0] == 2 && q[1] == 0);
}

/* sl_distance_reference: the RMS of many B against one A, bit-identical to
 * sl_mesh_distance_compute's fraction.rms with the same samples and seed, and every figure
 * (sl_distance_reference_compute) bit-identical to its whole result, on 1 and 2
 * threads: a bundled scan against a coarser copy (every other row of triangles dropped
 * and the gaps' vertices kept), a shifted copy and itself. */
static void test_reference(void)
{
    char path[1024];
    check_source_path("tests/data/scans/fandisk.ply", path, sizeof path);
    sl_mesh a;
    sl_mesh_init(&a);
    sl_error err;
    sl_error_init(&err);
    if (sl_ply_read(path, NULL, &a, NULL, NULL, &err)) {
        CHECK_MSG(0, "%s: %s", path, err.message);
        return;
    }
    sl_mesh half, shifted;
    make_mesh(&half, a.positions, a.vertex_count, a.triangles, (a.triangle_count + 1) / 2);
    for (uint64_t t = 0; t < half.triangle_count; t++) /* every other triangle */
        memcpy(half.triangles + 3 * t, a.triangles + 6 * t, 3 * sizeof *a.triangles);
    make_mesh(&shifted, a.positions, a.vertex_count, a.triangles, a.triangle_count);
    for (uint64_t v = 0; v < shifted.vertex_count; v++)
        shifted.positions[3 * v + 1] += 0.01f;
    const sl_mesh *bs[3] = {&half, &shifted, &a};
    sl_mesh_distance_config cfg = {20000, 7};
    int threads = omp_get_max_threads();
    for (int nt = 1; nt <= 2; nt++) {
        omp_set_num_threads(nt);
        sl_distance_reference *ref = NULL;
        CHECK(sl_distance_reference_build(&a, &cfg, &ref, &err) == SL_OK);
        for (int i = 0; ref && i < 3; i++) {
            sl_mesh_distance d;
            CHECK(sl_mesh_distance_compute(&a, bs[i], &cfg, &d, NULL, &err) == SL_OK);
            double rms = -1;
            CHECK(sl_distance_reference_rms(ref, bs[i], &rms, NULL, &err) == SL_OK);
            CHECK_MSG(rms == d.fraction.rms, "B %d, %d threads: reference RMS %.17g, full %.17g",
                      i, nt, rms, d.fraction.rms);
            CHECK_MSG(i == 2 ? rms < 1e-12 : rms > 1e-4, "B %d: RMS %g", i, rms);
            sl_mesh_distance e; /* every figure, the vertex samples included */
            CHECK(sl_distance_reference_compute(ref, bs[i], 1, &e, NULL, &err) == SL_OK);
            sl_mesh_distance f; /* the area samples alone: the same RMS, no vertex samples */
            CHECK(sl_distance_reference_compute(ref, bs[i], 0, &f, NULL, &err) == SL_OK);
            CHECK(f.fraction.rms == d.fraction.rms && f.a_to_b.vertex_samples == 0 &&
                  f.fraction.hausdorff <= d.fraction.hausdorff &&
                  f.fraction.hausdorff >= 0.5 * d.fraction.hausdorff);
            CHECK_MSG(!memcmp(&e, &d, sizeof d),
                      "B %d, %d threads: reference Hausdorff %.17g / %.17g, mean %.17g / %.17g, "
                      "vertex samples %llu / %llu", i, nt, e.fraction.hausdorff,
                      d.fraction.hausdorff, e.fraction.mean, d.fraction.mean,
                      (unsigned long long)e.a_to_b.vertex_samples,
                      (unsigned long long)d.a_to_b.vertex_samples);
        }
        sl_distance_reference_free(ref);
    }
    omp_set_num_threads(threads);
    sl_mesh empty;
    sl_mesh_init(&empty);
    sl_distance_reference *ref = NULL;
    CHECK(sl_distance_reference_build(&empty, &cfg, &ref, &err) == SL_E_BADINPUT && !ref);
    sl_mesh_release(&half);
    sl_mesh_release(&shifted);
    sl_mesh_release(&a);
}

/* Parts: a unit cube (area 6), an unwelded copy of it moved by 2 along x (welding joins
 * its corners), a small triangle apart (area 0.005), and a degenerate triangle touching
 * the first cube (it joins that part, adding no area). */
static void test_parts(void)
{
    float pos[8 * 3 + 36 * 3 + 3 * 3];
    uint32_t tri[12 * 3 + 36 + 3 + 3];
    memcpy(pos, cube_pos, sizeof cube_pos);
    memcpy(tri, cube_tri, sizeof cube_tri);
    for (int i = 0; i < 36; i++) {
        memcpy(&pos[24 + 3 * i], &cube_pos[3 * cube_tri[i]], 3 * sizeof(float));
        pos[24 + 3 * i] += 2;
        tri[36 + i] = 8 + (uint32_t)i;
    }
    const float speck[9] = {5, 5, 5, 5.1f, 5, 5, 5, 5.1f, 5};
    memcpy(&pos[24 + 108], speck, sizeof speck);
    for (int c = 0; c < 3; c++)
        tri[72 + c] = 44 + (uint32_t)c;
    tri[75] = 0, tri[76] = 0, tri[77] = 6; /* degenerate, on the first cube */
    sl_mesh m;
    make_mesh(&m, pos, 47, tri, 26);
    uint32_t part[26];
    double *area = NULL;
    uint64_t parts = 0;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_mesh_parts(&m, part, &area, &parts, &err) == SL_OK);
    CHECK_EQ_U64(parts, 3);
    for (int t = 0; t < 26; t++)
        CHECK_EQ_U64(part[t], t < 12 ? 0 : t < 24 ? 1 : t == 24 ? 2 : 0);
    CHECK(fabs(area[0] - 6) < 1e-5 && fabs(area[1] - 6) < 1e-5 && fabs(area[2] - 0.005) < 1e-6);
    free(area);
    sl_mesh_topology t = topology_of(&m);
    CHECK_EQ_U64(t.components, 3);
    sl_mesh_release(&m);
}

int main(void)
{
    test_parts();
    test_reference();
    test_points_as_a();
    test_closest_feature();
    test_closest_point();
    test_bvh_matches_brute_force();
    test_spheres();
    test_topology();
    test_bad_meshes();
    return check_report();
}
