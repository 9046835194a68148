/* The samples stage on meshes ([samples] closest = triangles, the default):
 *   - a cube of 12 large triangles: every sample is the analytic signed distance of the
 *     box, and the marching-cubes surface is closed; from its 8 corner points alone
 *     (closest = points, the paper) it is not -- the case that made triangles the default;
 *   - the same cube wound inside out: every sign turns;
 *   - closed real scans (bundled: cow, rocker_arm, fandisk; shared data when present:
 *     dragon_100kf, armadillo_86kf, happy_buddha_100kf, horse): plain marching cubes over
 *     the samples (= the octree's finest level) has no boundary or non-manifold edge; the
 *     cow needs the sign repair (its ear tips fold back on themselves) and gets it;
 *   - an open scan (bun_zipper): no sign repair, the surface stays within 1.5 leaves of
 *     the input;
 *   - identical samples on 1 and 2 threads.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_distance.h"
#include "formats/ply.h"
#include "stages/samples/samples.h"
#include "tests/check.h"

/* The cube [0, 1]^3 as 12 triangles wound outwards (or inwards). */
static sl_pointset cube_mesh(int inside_out)
{
    static const int faces[12][3] = {
        {0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
        {2, 3, 7}, {2, 7, 6}, {1, 2, 6}, {1, 6, 5}, {0, 4, 7}, {0, 7, 3}};
    sl_pointset ps;
    memset(&ps, 0, sizeof ps);
    ps.count = 8;
    ps.positions = malloc(8 * 12);
    ps.normals = malloc(8 * 12);
    for (int i = 0; i < 8; i++) {
        float p[3] = {(float)((i == 1 || i == 2 || i == 5 || i == 6)),
                      (float)((i == 2 || i == 3 || i == 6 || i == 7)), (float)(i >= 4)};
        for (int k = 0; k < 3; k++) {
            ps.positions[3 * i + k] = p[k];
            ps.normals[3 * i + k] = (p[k] - 0.5f) * 1.1547f; /* corner direction, unit */
        }
    }
    ps.triangle_count = 12;
    ps.triangles = malloc(12 * 12);
    for (int t = 0; t < 12; t++)
        for (int k = 0; k < 3; k++)
            ps.triangles[3 * t + k] = (uint32_t)faces[t][inside_out ? 2 - k : k];
    for (int k = 0; k < 3; k++)
        ps.bbox_min[k] = 0, ps.bbox_max[k] = 1;
    ps.mean_spacing = 1;
    return ps;
}

/* Signed distance of the box [0, 1]^3 (> 0 outside). */
static double box_distance(const double p[3])
{
    double outside = 0, inside = -1e30;
    for (int k = 0; k < 3; k++) {
        double d = fabs(p[k] - 0.5) - 0.5;
        outside += d > 0 ? d * d : 0;
        inside = d > inside ? d : inside;
    }
    return inside > 0 ? sqrt(outside) : inside;
}

/* Boundary and non-manifold edges of plain marching cubes over `s`. */
static uint64_t open_edges(const sl_vdb_samples *s, uint64_t *triangles)
{
    sl_mesh mc;
    sl_mesh_topology topo;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_samples_marching_cubes(s, &mc, &err) == SL_OK);
    CHECK(sl_mesh_topology_compute(&mc, &topo, &err) == SL_OK);
    *triangles = mc.triangle_count;
    sl_mesh_release(&mc);
    return topo.boundary_edges + topo.nonmanifold_edges;
}

static void test_cube(void)
{
    sl_pointset ps = cube_mesh(0), inverted = cube_mesh(1);
    sl_samples_config cfg = sl_samples_default_config();
    cfg.leaf_size = 0.1;
    sl_vdb_samples s, t;
    sl_samples_counts c, ct;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_samples_compute(&cfg, &ps, &s, &c, NULL, &err) == SL_OK);
    CHECK(sl_samples_compute(&cfg, &inverted, &t, &ct, NULL, &err) == SL_OK);
    CHECK_EQ_U64(c.triangles, 12);
    CHECK_EQ_U64(c.sign_repairs, 0);
    CHECK(c.closed_surface);
    CHECK_EQ_U64(s.count, t.count);
    double worst = 0;
    uint64_t flipped = 0;
    for (uint64_t i = 0; i < s.count; i++) {
        double v[3];
        for (int k = 0; k < 3; k++)
            v[k] = s.origin[k] + s.leaf_size * s.coords[3 * i + k];
        double e = fabs(s.distance[i] - box_distance(v));
        worst = e > worst ? e : worst;
        flipped += (s.distance[i] < 0) != (t.distance[i] < 0) &&
                   fabs(s.distance[i] + t.distance[i]) < 1e-6;
    }
    printf("  cube: %llu samples, worst error %.3g leaf\n", (unsigned long long)s.count,
           worst / cfg.leaf_size);
    CHECK_MSG(worst < 1e-5, "cube samples off the box distance by %g", worst);
    /* every sign turns, except on the surface itself (0 counts as outside) */
    uint64_t zero = 0;
    for (uint64_t i = 0; i < s.count; i++)
        zero += fabs(s.distance[i]) < 1e-6;
    CHECK_MSG(flipped + zero >= s.count, "inverted cube: %llu of %llu signs turned",
              (unsigned long long)flipped, (unsigned long long)s.count);
    uint64_t tris;
    CHECK_EQ_U64(open_edges(&s, &tris), 0);
    CHECK(tris > 0);
    sl_vdb_samples_release(&s);
    sl_vdb_samples_release(&t);

    /* The paper's closest point: only the 8 corners are points, the faces' middles get
     * no samples, and the surface is open. */
    cfg.closest = SL_SAMPLES_CLOSEST_POINTS;
    CHECK(sl_samples_compute(&cfg, &ps, &s, &c, NULL, &err) == SL_OK);
    uint64_t open = open_edges(&s, &tris);
    printf("  cube from its corner points: %llu open edges\n", (unsigned long long)open);
    CHECK(open > 0);
    sl_vdb_samples_release(&s);
    sl_pointset_release(&ps);
    sl_pointset_release(&inverted);
}

/* The range stage's point set of a PLY (bundled or shared); 0 when absent. */
static int load(const char *path, sl_pointset *ps)
{
    sl_mesh m;
    sl_range_counts rc;
    sl_range_config rcfg = sl_range_default_config();
    sl_error err;
    sl_error_init(&err);
    int read = sl_ply_read(path, NULL, &m, NULL, NULL, &err);
    CHECK_MSG(read == SL_OK, "%s: %s", path, err.message);
    if (read != SL_OK)
        return 0;
    int rc1 = sl_range_points_from_mesh(&rcfg, &m, NULL, ps, &rc, NULL, &err);
    sl_mesh_release(&m);
    CHECK_MSG(rc1 == SL_OK, "%s: %s", path, err.message);
    return rc1 == SL_OK;
}

static void check_closed(const char *path, const char *name, int must_repair)
{
    sl_pointset ps;
    if (!load(path, &ps))
        return;
    sl_samples_config cfg = sl_samples_default_config();
    sl_vdb_samples s;
    sl_samples_counts c;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_samples_compute(&cfg, &ps, &s, &c, NULL, &err) == SL_OK);
    uint64_t tris, open = open_edges(&s, &tris);
    printf("  %s: %llu samples, %llu triangles, %llu sign repairs, %llu open edges\n", name,
           (unsigned long long)s.count, (unsigned long long)tris,
           (unsigned long long)c.sign_repairs, (unsigned long long)open);
    CHECK_MSG(c.closed_surface, "%s: input not seen as closed", name);
    CHECK_MSG(open == 0, "%s: finest level has %llu open edges", name, (unsigned long long)open);
    if (must_repair)
        CHECK_MSG(c.sign_repairs > 0, "%s: expected sign repairs", name);
    sl_vdb_samples_release(&s);
    sl_pointset_release(&ps);
}

static void test_closed_scans(void)
{
    static const char *const bundled[] = {"cow", "rocker_arm", "fandisk"};
    static const char *const shared[] = {"dragon_100kf", "armadillo_86kf",
                                         "happy_buddha_100kf", "horse"};
    char rel[256], buf[600];
    for (int i = 0; i < 3; i++) {
        snprintf(rel, sizeof rel, "tests/data/scans/%s.ply", bundled[i]);
        check_closed(check_source_path(rel, buf, sizeof buf), bundled[i],
                     strcmp(bundled[i], "cow") == 0);
    }
    for (int i = 0; i < 4; i++) {
        snprintf(rel, sizeof rel, "%s.ply", shared[i]);
        if (check_shared_path(rel, buf, sizeof buf))
            check_closed(buf, shared[i], 0);
    }
}

/* An open scan: nothing to repair against, and the surface stays near the input. */
static void test_open_scan(void)
{
    char buf[600];
    sl_pointset ps;
    sl_mesh input;
    sl_error err;
    sl_error_init(&err);
    const char *path = check_source_path("tests/data/scans/bun_zipper_res3.ply", buf, sizeof buf);
    if (!load(path, &ps) || sl_ply_read(path, NULL, &input, NULL, NULL, &err) != SL_OK)
        return;
    sl_samples_config cfg = sl_samples_default_config();
    sl_vdb_samples s;
    sl_samples_counts c;
    CHECK(sl_samples_compute(&cfg, &ps, &s, &c, NULL, &err) == SL_OK);
    CHECK(!c.closed_surface);
    CHECK_EQ_U64(c.sign_repairs, 0);
    sl_mesh mc;
    sl_mesh_distance dist;
    sl_mesh_distance_config dcfg = sl_mesh_distance_default_config();
    CHECK(sl_samples_marching_cubes(&s, &mc, &err) == SL_OK);
    CHECK(sl_mesh_distance_compute(&input, &mc, &dcfg, &dist, NULL, &err) == SL_OK);
    double leaves = dist.a_to_b.world.hausdorff / c.plan.leaf_size;
    printf("  bun_zipper_res3: input to surface within %.2f leaf\n", leaves);
    CHECK_MSG(leaves < 1.5, "open scan: input %.2f leaves from its surface", leaves);
    sl_mesh_release(&mc);
    sl_mesh_release(&input);
    sl_vdb_samples_release(&s);
    sl_pointset_release(&ps);
}

static void test_threads(void)
{
    char buf[600];
    sl_pointset ps;
    if (!load(check_source_path("tests/data/scans/cow.ply", buf, sizeof buf), &ps))
        return;
    sl_samples_config cfg = sl_samples_default_config();
    sl_vdb_samples a, b;
    sl_samples_counts ca, cb;
    sl_error err;
    sl_error_init(&err);
    omp_set_num_threads(1);
    CHECK(sl_samples_compute(&cfg, &ps, &a, &ca, NULL, &err) == SL_OK);
    omp_set_num_threads(2);
    CHECK(sl_samples_compute(&cfg, &ps, &b, &cb, NULL, &err) == SL_OK);
    CHECK_EQ_U64(a.count, b.count);
    CHECK(a.count == b.count && memcmp(a.distance, b.distance, 4 * a.count) == 0 &&
          memcmp(a.coords, b.coords, 12 * a.count) == 0);
    sl_vdb_samples_release(&a);
    sl_vdb_samples_release(&b);
    sl_pointset_release(&ps);
}

int main(void)
{
    test_cube();
    test_closed_scans();
    test_open_scan();
    test_threads();
    return check_report();
}
