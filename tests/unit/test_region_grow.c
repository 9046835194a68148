/* Normal-angle region growing (geometry/region_grow.h): paper 3 equation 1 as an
 * invariant (every pair of a segment within delta_seg, checked by brute force) and
 * maximality (no neighbour of a finished segment would pass it), on a cube (6 segments),
 * a cylinder (caps alone, sides in strips), a sphere; Min-delta; bad input; threads. */
#include <omp.h>
#include <string.h>

#include "geometry/normal_hull.h"
#include "geometry/region_grow.h"
#include "tests/check.h"
#include "tests/unit/analytic_meshes.h"

typedef struct grown {
    sl_mesh_adjacency adj;
    sl_segmentation seg;
    double *normals;
} grown;

static int grow_mesh(const test_mesh *m, sl_region_grow_config cfg, grown *g, sl_error *err)
{
    sl_error_init(err);
    memset(g, 0, sizeof *g);
    int rc = sl_mesh_adjacency_build(m->triangles, m->triangle_count, m->vertex_count,
                                     m->positions, 0, &g->adj, err);
    if (rc)
        return rc;
    g->normals = malloc(3 * (size_t)m->triangle_count * sizeof *g->normals);
    sl_face_normals(&g->adj, m->positions, g->normals);
    return sl_region_grow(&g->adj, m->positions, &cfg, &g->seg, err);
}

static void grown_free(grown *g)
{
    sl_mesh_adjacency_release(&g->adj);
    sl_segmentation_release(&g->seg);
    free(g->normals);
}

static double angle(const double *a, const double *b)
{
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    return acos(d > 1 ? 1 : d < -1 ? -1 : d) * 180.0 / M_PI;
}

/* Largest angle between t's normal and the members of segment k. */
static double worst_angle(const grown *g, uint32_t t, uint32_t k)
{
    double worst = 0;
    for (uint32_t o = 0; o < g->seg.triangle_count; o++)
        if (g->seg.segment[o] == k) {
            double a = angle(g->normals + 3 * t, g->normals + 3 * o);
            worst = a > worst ? a : worst;
        }
    return worst;
}

/* Equation 1 holds inside every segment, and every triangle next to segment k that a
 * later segment took fails it against k. Returns the number of violations. */
static uint64_t check_equation_1(const grown *g, double delta)
{
    uint64_t bad = 0;
    const uint32_t *s = g->seg.segment;
    uint32_t n = g->seg.triangle_count;
    for (uint32_t t = 0; t < n; t++)
        for (uint32_t o = t + 1; o < n; o++)
            if (s[t] == s[o] && angle(g->normals + 3 * t, g->normals + 3 * o) > delta + 1e-9)
                bad++;
    for (uint32_t h = 0; h < 3 * n; h++) {
        uint32_t tw = g->adj.twin[h];
        if (tw == SL_HALFEDGE_NONE)
            continue;
        uint32_t t = h / 3, o = tw / 3;
        if (s[o] > s[t] && worst_angle(g, o, s[t]) <= delta - 1e-9)
            bad++;
    }
    return bad;
}

static void test_cube(void)
{
    test_mesh cube = tm_cube(3);
    sl_region_grow_config cfg = sl_region_grow_default_config();
    grown g;
    sl_error err;
    CHECK(grow_mesh(&cube, cfg, &g, &err) == 0);
    CHECK_EQ_U64(g.seg.segment_count, 6);
    /* each segment is one face: 18 triangles with one normal */
    uint32_t size[6] = {0};
    for (uint32_t t = 0; t < cube.triangle_count; t++) {
        size[g.seg.segment[t]]++;
        uint32_t seed = g.seg.seed[g.seg.segment[t]];
        CHECK(angle(g.normals + 3 * t, g.normals + 3 * seed) < 1e-9);
    }
    for (int k = 0; k < 6; k++)
        CHECK_EQ_U64(size[k], 18);
    CHECK_EQ_U64(check_equation_1(&g, cfg.delta_seg), 0);
    grown_free(&g);
    /* Min-delta: at most 6 segments needs a delta below 90 and gives the six faces */
    cfg.target_segments = 6;
    CHECK(grow_mesh(&cube, cfg, &g, &err) == 0);
    CHECK_EQ_U64(g.seg.segment_count, 6);
    CHECK(g.seg.delta_seg < 1.0);
    grown_free(&g);
    tm_free(&cube);
}

static void test_cylinder(void)
{
    test_mesh cyl = tm_cylinder(24, 4, 3, 2.0); /* 15 degrees between side columns */
    sl_region_grow_config cfg = sl_region_grow_default_config();
    cfg.delta_seg = 20.0;
    grown g;
    sl_error err;
    CHECK(grow_mesh(&cyl, cfg, &g, &err) == 0);
    /* the caps are one segment each, holding only cap triangles */
    uint32_t side_triangles = 2 * 24 * 4, cap_segment[2] = {UINT32_MAX, UINT32_MAX};
    uint64_t mixed = 0;
    for (uint32_t t = side_triangles; t < cyl.triangle_count; t++) {
        int top = g.normals[3 * t + 2] > 0;
        if (cap_segment[top] == UINT32_MAX)
            cap_segment[top] = g.seg.segment[t];
        mixed += g.seg.segment[t] != cap_segment[top];
    }
    for (uint32_t t = 0; t < side_triangles; t++)
        mixed += g.seg.segment[t] == cap_segment[0] || g.seg.segment[t] == cap_segment[1];
    CHECK_EQ_U64(mixed, 0);
    CHECK(cap_segment[0] != cap_segment[1]);
    /* 24 columns, at most 2 columns (15 degrees apart) per strip: at least 12 strips */
    CHECK_MSG(g.seg.segment_count >= 14 && g.seg.segment_count <= 26, "%u segments",
              g.seg.segment_count);
    CHECK_EQ_U64(check_equation_1(&g, cfg.delta_seg), 0);
    grown_free(&g);
    tm_free(&cyl);
}

static void test_sphere_and_min_delta(void)
{
    test_mesh sphere = tm_sphere(24, 13);
    sl_region_grow_config cfg = sl_region_grow_default_config();
    grown g;
    sl_error err;
    for (double delta = 10; delta <= 85; delta += 25) {
        cfg.delta_seg = delta;
        CHECK(grow_mesh(&sphere, cfg, &g, &err) == 0);
        CHECK_MSG(check_equation_1(&g, delta) == 0, "delta %g", delta);
        grown_free(&g);
    }
    cfg.target_segments = 20;
    CHECK(grow_mesh(&sphere, cfg, &g, &err) == 0);
    CHECK_MSG(g.seg.segment_count <= 20, "%u segments", g.seg.segment_count);
    CHECK_EQ_U64(check_equation_1(&g, g.seg.delta_seg), 0);
    double found = g.seg.delta_seg;
    grown_free(&g);
    cfg.target_segments = 0;
    cfg.delta_seg = found - 2.0; /* clearly smaller: more segments */
    CHECK(grow_mesh(&sphere, cfg, &g, &err) == 0);
    CHECK_MSG(g.seg.segment_count > 20, "%u segments at %g", g.seg.segment_count, found - 2);
    grown_free(&g);
    tm_free(&sphere);
}

static double bumps(double x, double y)
{
    return 0.002 * sin(37 * x) * cos(23 * y);
}

static void test_edge_cases(void)
{
    sl_region_grow_config cfg = sl_region_grow_default_config();
    grown g;
    sl_error err;
    /* a gently noisy plane is one segment */
    test_mesh plane = tm_grid(20, bumps);
    CHECK(grow_mesh(&plane, cfg, &g, &err) == 0);
    CHECK_EQ_U64(g.seg.segment_count, 1);
    grown_free(&g);
    /* a zero-area triangle is a segment of its own */
    uint32_t a = tm_vertex(&plane, 2, 0, 0), b = tm_vertex(&plane, 3, 0, 0),
             c = tm_vertex(&plane, 4, 0, 0);
    tm_triangle(&plane, a, b, c);
    CHECK(grow_mesh(&plane, cfg, &g, &err) == 0);
    CHECK_EQ_U64(g.seg.segment_count, 2);
    CHECK_EQ_U64(g.seg.without_normal, 1);
    grown_free(&g);
    /* delta out of range */
    cfg.delta_seg = 0;
    CHECK(grow_mesh(&plane, cfg, &g, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.message, "outside") != NULL);
    grown_free(&g);
    cfg.delta_seg = 95;
    CHECK(grow_mesh(&plane, cfg, &g, &err) == SL_E_BADINPUT);
    grown_free(&g);
    /* a non-finite coordinate */
    cfg.delta_seg = 30;
    plane.positions[4] = NAN;
    CHECK(grow_mesh(&plane, cfg, &g, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.message, "non-finite") != NULL);
    grown_free(&g);
    tm_free(&plane);
}

static void test_threads(void)
{
    test_mesh torus = tm_torus(80, 50, 2.0, 0.8);
    sl_region_grow_config cfg = sl_region_grow_default_config();
    grown g1, g2;
    sl_error err;
    omp_set_num_threads(1);
    CHECK(grow_mesh(&torus, cfg, &g1, &err) == 0);
    omp_set_num_threads(2);
    CHECK(grow_mesh(&torus, cfg, &g2, &err) == 0);
    CHECK(g1.seg.segment_count == g2.seg.segment_count);
    CHECK(memcmp(g1.seg.segment, g2.seg.segment, torus.triangle_count * sizeof(uint32_t)) == 0);
    grown_free(&g1);
    grown_free(&g2);
    tm_free(&torus);
}

/* The hull's vertices give the same largest angle as all normals added, for random
 * normals in a 60-degree cone and random directions within 20 degrees of its axis. */
static void test_normal_hull(void)
{
    uint64_t state = 99;
#define RND() ((state = state * 6364136223846793005ull + 1442695040888963407ull) >> 11) * 0x1p-53
    double axis[3] = {0.3, -0.2, 0.93}, len = sqrt(0.09 + 0.04 + 0.93 * 0.93);
    for (int k = 0; k < 3; k++)
        axis[k] /= len;
    double (*all)[3] = malloc(500 * sizeof *all);
    sl_normal_hull h;
    sl_normal_hull_init(&h);
    sl_normal_hull_start(&h, axis);
    uint64_t bad = 0;
    for (int i = 0; i < 500; i++) {
        double v[3];
        do {
            for (int k = 0; k < 3; k++)
                v[k] = 2 * RND() - 1;
            double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            for (int k = 0; k < 3; k++)
                v[k] /= l;
        } while (v[0] * axis[0] + v[1] * axis[1] + v[2] * axis[2] < cos(M_PI / 6));
        memcpy(all[i], v, sizeof v);
        CHECK(sl_normal_hull_add(&h, v, (uint32_t)i) == 0);
        for (int q = 0; q < 5; q++) {
            double m[3];
            do {
                for (int k = 0; k < 3; k++)
                    m[k] = axis[k] + 0.3 * (2 * RND() - 1);
                double l = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
                for (int k = 0; k < 3; k++)
                    m[k] /= l;
            } while (m[0] * axis[0] + m[1] * axis[1] + m[2] * axis[2] < cos(M_PI / 9));
            double brute = 1;
            for (int j = 0; j <= i; j++) {
                double d = all[j][0] * m[0] + all[j][1] * m[1] + all[j][2] * m[2];
                brute = d < brute ? d : brute;
            }
            bad += fabs(sl_normal_hull_min_dot(&h, m) - brute) > 1e-12;
        }
    }
    CHECK_EQ_U64(bad, 0);
    CHECK_MSG(h.count < 100, "%u hull vertices", h.count);
    sl_normal_hull_release(&h);
    free(all);
#undef RND
}

int main(void)
{
    test_normal_hull();
    test_cube();
    test_cylinder();
    test_sphere_and_min_delta();
    test_edge_cases();
    test_threads();
    return check_report();
}
