/* range stage on the shared real scans (checks that need them are skipped when
 * ../shared/data is absent):
 *   - counts: points = input vertices - unreferenced - welded, with the unreferenced
 *     counts of the data README's topology table;
 *   - normals: unit length; on closed meshes the divergence theorem computed from the
 *     point normals gives the mesh's own volume with a positive sign, so they point
 *     outwards (inside-out horse.ply included);
 *   - raw scans: grid normals face the scanner (they agree with the outward normals of
 *     the zippered reconstruction in the same frame), PCA normals agree with grid or
 *     face normals of the same surface;
 * The stage entry itself (options, report, files, threads): test_range_stage.c.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/kdtree.h"
#include "formats/ply.h"
#include "stages/range/range.h"
#include "tests/check.h"

typedef struct result {
    sl_pointset ps;
    sl_range_counts c;
} result;

static int load(const char *rel, sl_mesh *m)
{
    char buf[1024];
    const char *path = check_shared_path(rel, buf, sizeof buf);
    if (!path)
        return 0;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_read(path, NULL, m, NULL, NULL, &err);
    CHECK_MSG(rc == SL_OK, "%s: %s", rel, err.message);
    return rc == SL_OK;
}

/* Reads `rel` and runs the stage's work on it; 0 when the data is absent or it failed. */
static int process(const char *rel, const sl_range_config *cfg, int as_cloud, result *r)
{
    sl_mesh m;
    memset(r, 0, sizeof *r);
    if (!load(rel, &m))
        return 0;
    if (as_cloud) { /* the bare vertices: PCA normals */
        free(m.grid_index);
        free(m.triangles);
        m.grid_index = NULL;
        m.triangles = NULL;
        m.triangle_count = 0;
    }
    sl_error err;
    sl_error_init(&err);
    int rc = sl_range_points_from_mesh(cfg, &m, NULL, &r->ps, &r->c, NULL, &err);
    sl_mesh_release(&m);
    CHECK_MSG(rc == SL_OK, "%s: %s", rel, err.message);
    return rc == SL_OK;
}

static void release(result *r)
{
    sl_pointset_release(&r->ps);
}

static double dot3(const float *a, const float *b)
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

static void check_unit_normals(const result *r, const char *rel)
{
    uint64_t bad = 0;
    for (uint64_t i = 0; i < r->ps.count; i++)
        bad += fabs(sqrt(dot3(r->ps.normals + 3 * i, r->ps.normals + 3 * i)) - 1.0) > 1e-5;
    CHECK_MSG(bad == 0, "%s: %llu normals not unit length", rel, (unsigned long long)bad);
}

/* Counts against the data README (vertex/face counts and unreferenced vertices). */
static void test_counts(void)
{
    static const struct {
        const char *file;
        uint64_t vertices, faces, unreferenced, welded;
    } files[] = {
        {"bun_zipper.ply", 35947, 69451, 1113, 0},
        {"bun_zipper_res2.ply", 8171, 16301, 25, 0},
        {"bun_zipper_res3.ply", 1889, 3851, 2, 0},
        {"bun_zipper_res4.ply", 453, 948, 0, 0},
        {"dragon_vrip_res3.ply", 22998, 47794, 16, 0},
        /* CGAL's cow has two distinct vertices at one position: welded by design. */
        {"cow.ply", 2904, 5804, 0, 1},
        {"fandisk.ply", 6475, 12946, 0, 0},
        {"rocker_arm.ply", 10044, 20088, 0, 0},
        {"lee_perry_smith_head.ply", 8844, 17684, 0, 0},
    };
    sl_range_config cfg = sl_range_default_config();
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        result r;
        if (!process(files[i].file, &cfg, 0, &r))
            continue;
        CHECK_EQ_U64(r.c.input_vertices, files[i].vertices);
        CHECK_EQ_U64(r.c.input_faces, files[i].faces);
        CHECK_EQ_U64(r.c.unreferenced, files[i].unreferenced);
        CHECK_EQ_U64(r.c.welded, files[i].welded);
        CHECK_EQ_U64(r.c.nonfinite_vertices, 0);
        CHECK_EQ_U64(r.c.points, files[i].vertices - files[i].unreferenced - files[i].welded);
        check_unit_normals(&r, files[i].file);
        release(&r);
    }
}

/* Volume by the divergence theorem from point normals, (1/3) sum A_p n_p . p with A_p a
 * third of the adjacent triangle areas, against the mesh's signed volume: they agree
 * (and are positive) only if the normals point outwards nearly everywhere. */
static void check_outward_volume(const result *r, const char *rel)
{
    const float *P = r->ps.positions;
    double *area = calloc(r->ps.count, sizeof *area), mesh_volume = 0, point_volume = 0;
    for (uint64_t t = 0; t < r->ps.triangle_count; t++) {
        const float *a = P + 3 * (uint64_t)r->ps.triangles[3 * t], *b = P + 3 * (uint64_t)r->ps.triangles[3 * t + 1];
        const float *c = P + 3 * (uint64_t)r->ps.triangles[3 * t + 2];
        double u[3], w[3], n[3];
        for (int k = 0; k < 3; k++)
            u[k] = (double)b[k] - a[k], w[k] = (double)c[k] - a[k];
        n[0] = u[1] * w[2] - u[2] * w[1], n[1] = u[2] * w[0] - u[0] * w[2], n[2] = u[0] * w[1] - u[1] * w[0];
        mesh_volume += (a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) -
                        a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
                        a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) / 6.0;
        double third = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 6.0;
        for (int k = 0; k < 3; k++)
            area[r->ps.triangles[3 * t + k]] += third;
    }
    for (uint64_t i = 0; i < r->ps.count; i++)
        point_volume += area[i] * dot3(r->ps.normals + 3 * i, P + 3 * i) / 3.0;
    free(area);
    /* horse.ply is wound inside out: the stage flips its normals and its triangles as a
     * whole, so the triangles it writes always enclose a positive volume. */
    CHECK_MSG(r->c.normals_flipped == (strstr(rel, "horse") != NULL), "%s: flipped %d", rel,
              r->c.normals_flipped);
    CHECK_MSG(mesh_volume > 0, "%s: written triangles enclose volume %g", rel, mesh_volume);
    double rel_err = fabs(point_volume - mesh_volume) / fabs(mesh_volume);
    printf("  %s: volume from point normals %.6g, mesh %.6g (%.2f%%)\n", rel, point_volume,
           mesh_volume, 100 * rel_err);
    CHECK_MSG(mesh_volume > 0 && point_volume > 0 && rel_err < 0.05,
              "%s: volume from normals %g vs mesh %g", rel, point_volume, mesh_volume);
}

static void test_closed_meshes(void)
{
    const char *files[] = {"cow.ply", "fandisk.ply", "rocker_arm.ply", "armadillo_86kf.ply",
                           "igea.ply", "horse.ply", "lucy_100kf.ply"};
    sl_range_config cfg = sl_range_default_config();
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        result r;
        if (!process(files[i], &cfg, 0, &r))
            continue;
        CHECK(r.c.normal_source == SL_NORMALS_FACES);
        check_unit_normals(&r, files[i]);
        check_outward_volume(&r, files[i]);
        release(&r);
    }
}

/* Fraction of `a`'s points whose normal is within `max_deg` of the normal of the nearest
 * point of `b` (only points with a neighbour within `radius`). */
static double agreement(const sl_pointset *a, const sl_pointset *b, double radius,
                        double max_deg, uint64_t *compared)
{
    sl_kdtree *tree = NULL;
    sl_error err;
    sl_error_init(&err);
    if (sl_kdtree_build(&tree, b->positions, b->count, &err) != SL_OK)
        return 0;
    uint64_t agree = 0, n = 0;
    double cos_max = cos(max_deg * 3.14159265358979 / 180.0);
    for (uint64_t i = 0; i < a->count; i++) {
        float d2;
        uint32_t j = sl_kdtree_nearest(tree, a->positions + 3 * i, &d2);
        if (j == UINT32_MAX || d2 > radius * radius)
            continue;
        n++;
        agree += dot3(a->normals + 3 * i, b->normals + 3 * (uint64_t)j) >= cos_max;
    }
    sl_kdtree_free(tree);
    *compared = n;
    return n ? (double)agree / n : 0;
}

static void check_agreement(const char *what, const result *a, const result *b, double radius)
{
    uint64_t n = 0;
    double f = agreement(&a->ps, &b->ps, radius, 30.0, &n);
    printf("  %s: %.2f%% of %llu points within 30 deg\n", what, 100 * f, (unsigned long long)n);
    CHECK_MSG(f > 0.90 && n > a->ps.count / 2, "%s: %.3f agree over %llu", what, f,
              (unsigned long long)n);
}

static void test_scans(void)
{
    sl_range_config cfg = sl_range_default_config();
    result grid, pca, zipper, dragon_scan, dragon_mesh;
    if (process("bunny_range/bun000.ply", &cfg, 0, &grid)) {
        CHECK(grid.c.normal_source == SL_NORMALS_RANGE_GRID);
        CHECK(grid.c.grid_triangles > 70000 && grid.c.grid_long_edges > 0);
        check_unit_normals(&grid, "bun000 (grid)");
        /* bun000's frame is the reconstruction's (identity in bun.conf). */
        if (process("bun_zipper.ply", &cfg, 0, &zipper)) {
            check_agreement("bun000 grid normals vs bun_zipper face normals", &grid, &zipper,
                            3 * zipper.ps.mean_spacing);
            release(&zipper);
        }
        if (process("bunny_range/bun000.ply", &cfg, 1, &pca)) {
            CHECK(pca.c.normal_source == SL_NORMALS_PCA_PROPAGATED);
            CHECK_EQ_U64(pca.c.points, grid.c.input_vertices);
            check_agreement("bun000 PCA normals vs its grid normals", &pca, &grid, 1e-9);
            release(&pca);
        }
        release(&grid);
    }
    /* dragon_rangescan is in dragon_vrip_res3's frame (same bounding box). */
    if (process("dragon_rangescan.ply", &cfg, 0, &dragon_scan)) {
        CHECK(dragon_scan.c.normal_source == SL_NORMALS_PCA_PROPAGATED);
        check_unit_normals(&dragon_scan, "dragon_rangescan");
        if (process("dragon_vrip_res3.ply", &cfg, 0, &dragon_mesh)) {
            check_agreement("dragon_rangescan PCA normals vs dragon_vrip_res3 face normals",
                            &dragon_scan, &dragon_mesh, 2 * dragon_mesh.ps.mean_spacing);
            release(&dragon_mesh);
        }
        release(&dragon_scan);
    }
}

/* Meshes read as bare vertices: the PCA normals' signs against the face normals of the
 * same points (thin parts and sharp edges are what make propagation fail). */
static void test_pca_on_mesh_vertices(void)
{
    static const struct {
        const char *file;
        double min_agreement;
    } files[] = {{"fandisk.ply", 0.99},         {"armadillo_86kf.ply", 0.99},
                 {"rocker_arm.ply", 0.99},      {"lucy_100kf.ply", 0.97},
                 {"happy_buddha_100kf.ply", 0.98}, {"cow.ply", 0.88}};
    sl_range_config cfg = sl_range_default_config();
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        result faces, cloud;
        if (!process(files[i].file, &cfg, 0, &faces))
            continue;
        if (process(files[i].file, &cfg, 1, &cloud)) {
            CHECK(cloud.c.normal_source == SL_NORMALS_PCA_PROPAGATED);
            uint64_t n = 0;
            double f = agreement(&cloud.ps, &faces.ps, 0.0, 90.0, &n);
            printf("  %s vertices: PCA sign agrees with faces for %.2f%% of %llu\n",
                   files[i].file, 100 * f, (unsigned long long)n);
            CHECK_MSG(f >= files[i].min_agreement && n == faces.ps.count, "%s: %.3f",
                      files[i].file, f);
            release(&cloud);
        }
        release(&faces);
    }
}

int main(void)
{
    test_counts();
    test_closed_meshes();
    test_scans();
    test_pca_on_mesh_vertices();
    return check_report();
}
