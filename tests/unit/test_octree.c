/* Marching-cube octree (merge stage core) on analytic signed distances: the finest level
 * equals plain marching cubes over the same samples, every uniform level is watertight,
 * parent crossings are child crossings, and the build does not depend on thread count. */
#include <math.h>
#include <stddef.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "runtime/lod_mesh.h"
#include "runtime/mc_cube.h"
#include "runtime/octree_io.h"
#include "stages/merge/merge.h"
#include "tests/check.h"
#include "tests/unit/sealed_file.h"
#include "tests/unit/mesh_checks.h"

typedef struct samples {
    uint64_t count;
    int32_t *coords;
    float *distance;
    uint8_t *colors;
} samples;

typedef double (*sdf_fn)(const double p[3]);

static double sphere_sdf(const double p[3])
{
    return sqrt((p[0] - 0.3) * (p[0] - 0.3) + (p[1] + 0.2) * (p[1] + 0.2) + p[2] * p[2]) - 11.3;
}

static double torus_sdf(const double p[3])
{
    double q = sqrt(p[0] * p[0] + p[1] * p[1]) - 9.0;
    return sqrt(q * q + p[2] * p[2]) - 3.4;
}

/* Samples within `band` cells of the surface on an integer grid in [-n, n]^3 (leaf 1). */
static samples make_samples(sdf_fn sdf, int n, double band)
{
    samples s = {0};
    size_t cap = 1024;
    s.coords = malloc(cap * 3 * sizeof *s.coords);
    s.distance = malloc(cap * sizeof *s.distance);
    s.colors = malloc(cap * 4);
    for (int x = -n; x <= n; x++)
        for (int y = -n; y <= n; y++)
            for (int z = -n; z <= n; z++) {
                double p[3] = {x, y, z}, d = sdf(p);
                if (fabs(d) > band)
                    continue;
                if (s.count == cap) {
                    cap *= 2;
                    s.coords = realloc(s.coords, cap * 3 * sizeof *s.coords);
                    s.distance = realloc(s.distance, cap * sizeof *s.distance);
                    s.colors = realloc(s.colors, cap * 4);
                }
                s.coords[3 * s.count] = x;
                s.coords[3 * s.count + 1] = y;
                s.coords[3 * s.count + 2] = z;
                s.distance[s.count] = (float)d;
                memset(s.colors + 4 * s.count, (x + 64) & 0xff, 4);
                s.count++;
            }
    return s;
}

static sl_sample_grid grid_of(const samples *s)
{
    sl_sample_grid g = {s->count, s->coords, s->distance, s->colors, 1.0, {0, 0, 0}};
    return g;
}

/* Plain marching cubes over the same samples, independently of the octree. */
static uint64_t plain_mc(const samples *s, double *sum_positions)
{
    const sl_mc_triangles *table = sl_mc_uniform_table();
    int n = 0;
    for (uint64_t i = 0; i < s->count; i++)
        for (int a = 0; a < 3; a++)
            n = abs(s->coords[3 * i + a]) > n ? abs(s->coords[3 * i + a]) : n;
    int w = 2 * n + 1;
    float *grid = malloc((size_t)w * w * w * sizeof *grid);
    for (int i = 0; i < w * w * w; i++)
        grid[i] = NAN;
    for (uint64_t i = 0; i < s->count; i++)
        grid[((s->coords[3 * i] + n) * w + s->coords[3 * i + 1] + n) * w + s->coords[3 * i + 2] + n] =
            s->distance[i];
    uint64_t triangles = 0;
    *sum_positions = 0;
    for (int x = 0; x + 1 < w; x++)
        for (int y = 0; y + 1 < w; y++)
            for (int z = 0; z + 1 < w; z++) {
                float d[8];
                int ok = 1, config = 0;
                for (int c = 0; c < 8; c++) {
                    d[c] = grid[((x + (c & 1)) * w + y + (c >> 1 & 1)) * w + z + (c >> 2 & 1)];
                    ok &= !isnan(d[c]);
                    config |= (d[c] < 0) << c;
                }
                if (!ok)
                    continue;
                const sl_mc_triangles *tri = &table[config];
                triangles += tri->count;
                for (int t = 0; t < tri->count; t++)
                    for (int k = 0; k < 3; k++) {
                        int e = tri->points[t][k], c0 = sl_mc_edge_c0(e), c1 = sl_mc_edge_c1(e);
                        double tt = d[c0] / ((double)d[c0] - d[c1]);
                        tt = tt < 1e-3 ? 1e-3 : tt > 1 - 1e-3 ? 1 - 1e-3 : tt;
                        for (int a = 0; a < 3; a++) {
                            double p0 = (a == 0 ? x : a == 1 ? y : z) - n + (c0 >> a & 1);
                            double p1 = (a == 0 ? x : a == 1 ? y : z) - n + (c1 >> a & 1);
                            *sum_positions += (float)(p0 + tt * (p1 - p0));
                        }
                    }
            }
    free(grid);
    return triangles;
}

static void test_finest_equals_plain_mc(const samples *s)
{
    sl_sample_grid g = grid_of(s);
    sl_octree t;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_octree_build(&g, &t, NULL, &err) == 0);
    sl_lod_mesh m;
    CHECK(sl_octree_level_mesh(&t, 0, &m) == 0);
    double plain_sum, octree_sum = 0;
    uint64_t plain = plain_mc(s, &plain_sum);
    for (uint64_t i = 0; i < m.triangle_count; i++)
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++)
                octree_sum += m.positions[3 * (size_t)m.indices[3 * i + k] + a];
    CHECK_EQ_U64(m.triangle_count, plain);
    CHECK_NEAR(octree_sum, plain_sum, 1e-6 * (double)plain * 30);
    sl_lod_mesh_release(&m);
    sl_octree_release(&t);
}

static void test_levels(const samples *s, const char *name, double surface_tolerance, sdf_fn sdf)
{
    sl_sample_grid g = grid_of(s);
    sl_octree t;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_octree_build(&g, &t, NULL, &err) == 0);
    CHECK(t.depth >= 4);
    for (uint32_t level = 0; level <= t.depth; level++) {
        sl_lod_mesh m;
        CHECK(sl_octree_level_mesh(&t, level, &m) == 0);
        uint64_t bad = bad_edges(&m);
        CHECK_MSG(bad == 0, "%s level %u: %llu of %llu triangles' edges not shared by two", name,
                  level, (unsigned long long)bad, (unsigned long long)m.triangle_count);
        if (level == 0) {
            double worst = 0;
            for (uint64_t v = 0; v < m.vertex_count; v++) {
                double p[3] = {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
                worst = fmax(worst, fabs(sdf(p)));
            }
            CHECK_MSG(worst < surface_tolerance, "%s finest vertex %.4f off the surface", name, worst);
            CHECK(m.triangle_count > 1000);
        }
        sl_lod_mesh_release(&m);
    }
    /* Parent crossings are child crossings: the same id on the half-edge of a child. */
    uint64_t checked = 0, coincide = 0;
    for (uint32_t i = 0; i < t.node_count; i++) {
        const sl_octree_node *p = &t.nodes[i];
        if (p->level == 0)
            continue;
        for (int e = 0; e < 12; e++) {
            if (!(p->edge_mask >> e & 1))
                continue;
            uint32_t id = sl_octree_crossing(&t, p, e);
            checked++;
            int found = 0;
            for (int k = 0; k < __builtin_popcount(p->child_mask) && !found; k++) {
                const sl_octree_node *c = &t.nodes[p->first_child + (uint32_t)k];
                for (int ce = 0; ce < 12 && !found; ce++)
                    found = (c->edge_mask >> ce & 1) && sl_mc_edge_axis(ce) == sl_mc_edge_axis(e) &&
                            sl_octree_crossing(&t, c, ce) == id;
            }
            coincide += found;
        }
    }
    CHECK_MSG(coincide + t.stats.fallback_crossings >= checked,
              "%s: %llu of %llu parent crossings are neither a child's nor a fallback", name,
              (unsigned long long)(checked - coincide), (unsigned long long)checked);
    CHECK_MSG(coincide >= 0.95 * (double)checked, "%s: only %llu of %llu parent crossings inherited",
              name, (unsigned long long)coincide, (unsigned long long)checked);
    printf("%s: depth %u, %u nodes, %u crossings, %llu inherited, %llu fallback, cases A-D "
           "%llu %llu %llu %llu\n",
           name, t.depth, t.node_count, t.crossing_count,
           (unsigned long long)t.stats.inherited_crossings,
           (unsigned long long)t.stats.fallback_crossings,
           (unsigned long long)t.stats.sign_case[0], (unsigned long long)t.stats.sign_case[1],
           (unsigned long long)t.stats.sign_case[2], (unsigned long long)t.stats.sign_case[3]);
    sl_octree_release(&t);
}

static void test_deterministic(const samples *s)
{
    sl_sample_grid g = grid_of(s);
    sl_octree a, b;
    sl_error err;
    sl_error_init(&err);
    omp_set_num_threads(1);
    CHECK(sl_octree_build(&g, &a, NULL, &err) == 0);
    omp_set_num_threads(2);
    CHECK(sl_octree_build(&g, &b, NULL, &err) == 0);
    CHECK(a.node_count == b.node_count && a.crossing_count == b.crossing_count);
    CHECK(memcmp(a.nodes, b.nodes, a.node_count * sizeof *a.nodes) == 0);
    CHECK(memcmp(a.crossing_position, b.crossing_position, 3 * sizeof(float) * a.crossing_count) == 0);
    CHECK(memcmp(a.node_crossings, b.node_crossings, a.node_crossing_count * sizeof(uint32_t)) == 0);
    sl_octree_release(&a);
    sl_octree_release(&b);
}

static void test_bad_samples(void)
{
    sl_octree t;
    sl_error err;
    sl_error_init(&err);
    sl_sample_grid empty = {0, NULL, NULL, NULL, 1.0, {0, 0, 0}};
    CHECK(sl_octree_build(&empty, &t, NULL, &err) == SL_E_BADINPUT);
    int32_t coords[6] = {0, 0, 0, 1, 0, 0};
    float dist[2] = {-1, 1};
    sl_sample_grid two = {2, coords, dist, NULL, 1.0, {0, 0, 0}};
    sl_error_init(&err);
    CHECK(sl_octree_build(&two, &t, NULL, &err) == SL_E_BADINPUT);
    /* One whole cube, every corner outside: a leaf but no triangle (issue 16: such
     * items were published with empty levels). */
    int32_t cube[24];
    float outside[8];
    for (int c = 0; c < 8; c++) {
        cube[3 * c] = c & 1, cube[3 * c + 1] = c >> 1 & 1, cube[3 * c + 2] = c >> 2 & 1;
        outside[c] = 0.5f;
    }
    sl_sample_grid blank = {8, cube, outside, NULL, 2.0, {0, 0, 0}};
    sl_error_init(&err);
    CHECK(sl_octree_build(&blank, &t, NULL, &err) == SL_E_BADINPUT &&
          strstr(err.message, "no triangles at leaf size 2") &&
          strstr(err.message, "0 of 8 samples inside"));
    int32_t far[6] = {0, 0, 0, 1 << 21, 0, 0};
    sl_sample_grid wide = {2, far, dist, NULL, 1.0, {0, 0, 0}};
    sl_error_init(&err);
    CHECK(sl_octree_build(&wide, &t, NULL, &err) == SL_E_LIMIT);
}

/* One mutant of octree.slot written (sealed_file.h) and read. */
static int read_mutant(const char *path, const unsigned char *bytes, size_t size, int seal,
                       sl_error *err)
{
    sl_octree t;
    sl_error_init(err);
    int rc = sealed_file_write(path, bytes, size, seal) == 0 ? sl_octree_read(path, &t, err) : -1;
    if (rc == 0)
        sl_octree_release(&t);
    return rc;
}

/* octree.slot read in order into the tree's arrays (no whole body beside them): the same
 * tree back, and every kind of bad file refused with the file named, before a count read
 * from it sizes an allocation (a 2^31-node header would ask for 64 GB: ASan stops that). */
static void test_file(const samples *s)
{
    char dir[256], path[300], mutant[300];
    snprintf(dir, sizeof dir, "%s/scanlod-octree.XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    CHECK(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/octree.slot", dir);
    snprintf(mutant, sizeof mutant, "%s/mutant.slot", dir);
    sl_sample_grid g = grid_of(s);
    sl_octree a, b;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_octree_build(&g, &a, NULL, &err) == 0);
    CHECK(sl_octree_write(path, &a, 1, &err) == 0);
    CHECK(sl_octree_read(path, &b, &err) == 0);
    CHECK(a.node_count == b.node_count && a.crossing_count == b.crossing_count &&
          a.node_crossing_count == b.node_crossing_count);
    CHECK(memcmp(a.nodes, b.nodes, a.node_count * sizeof *a.nodes) == 0);
    CHECK(memcmp(a.crossing_position, b.crossing_position, 3 * sizeof(float) * a.crossing_count) == 0);
    CHECK(memcmp(a.node_crossings, b.node_crossings, a.node_crossing_count * sizeof(uint32_t)) == 0);
    CHECK(memcmp(a.morton, b.morton, a.node_count * sizeof *a.morton) == 0);
    sl_octree_release(&b);
    sl_octree_release(&a);

    size_t size;
    unsigned char *bytes = sealed_file_bytes(path, 4, &size);
    CHECK(bytes && size > 200);
    if (!bytes)
        return;
    /* a crossing's coordinate changed: caught by the checksum after the read */
    bytes[size - 3] ^= 0x40;
    CHECK(read_mutant(mutant, bytes, size, 0, &err) == SL_E_CORRUPT &&
          strstr(err.message, "checksum mismatch") && strstr(err.file, "mutant.slot"));
    bytes[size - 3] ^= 0x40;
    /* 2^31 nodes declared, the file sealed again: refused on the counts, not allocated */
    uint32_t nodes = sl_get_u32(bytes + SL_ARTIFACT_HEADER_SIZE + 4);
    sl_put_u32(bytes + SL_ARTIFACT_HEADER_SIZE + 4, 1u << 31);
    CHECK(read_mutant(mutant, bytes, size, 1, &err) == SL_E_CORRUPT &&
          strstr(err.message, "counts exceed the bytes present"));
    sl_put_u32(bytes + SL_ARTIFACT_HEADER_SIZE + 4, nodes);
    /* four bytes more than the counts say, sealed */
    memset(bytes + size, 0, 4);
    CHECK(read_mutant(mutant, bytes, size + 4, 1, &err) == SL_E_CORRUPT &&
          strstr(err.message, "trailing bytes"));
    /* cut short (the header's size no longer the file's) and cut inside the octree header */
    CHECK(read_mutant(mutant, bytes, size - 100, 0, &err) == SL_E_CORRUPT);
    CHECK(read_mutant(mutant, bytes, SL_ARTIFACT_HEADER_SIZE + 40, 1, &err) == SL_E_CORRUPT &&
          strstr(err.message, "truncated header"));
    /* a node's parent out of range, sealed: the checksum is right, the tree's check is not */
    size_t first_node = SL_ARTIFACT_HEADER_SIZE + (size_t)(4 * 4 + 8 + 8 * 4 + 4 * 2 * SL_OCTREE_MAX_LEVELS + 8 * 6 + 16);
    sl_put_u32(bytes + first_node + offsetof(sl_octree_node, parent), 7);
    CHECK(read_mutant(mutant, bytes, size, 1, &err) == SL_E_CORRUPT &&
          strstr(err.message, "invalid octree"));
    /* and the file as written reads again */
    sl_put_u32(bytes + first_node + offsetof(sl_octree_node, parent), SL_OCTREE_NONE);
    CHECK(read_mutant(mutant, bytes, size, 0, &err) == 0);
    free(bytes);
    unlink(path);
    unlink(mutant);
    rmdir(dir);
}

int main(void)
{
    samples sphere = make_samples(sphere_sdf, 16, 2.5);
    samples torus = make_samples(torus_sdf, 16, 2.5);
    test_finest_equals_plain_mc(&sphere);
    test_finest_equals_plain_mc(&torus);
    test_levels(&sphere, "sphere", 0.05, sphere_sdf);
    test_levels(&torus, "torus", 0.08, torus_sdf);
    test_deterministic(&torus);
    test_bad_samples();
    test_file(&torus);
    free(sphere.coords);
    free(sphere.distance);
    free(sphere.colors);
    free(torus.coords);
    free(torus.distance);
    free(torus.colors);
    return check_report();
}
