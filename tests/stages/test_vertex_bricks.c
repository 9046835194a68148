/* The merge's quadric vertices built brick by brick (stages/merge/octree_bricks.c,
 * docs/bricks.md): on real scans, through the range and samples stages and the octree
 * build, every output of sl_octree_vertices (vertex ranges, positions, colours, node
 * errors and areas) is byte-identical whether the whole tree is one brick on one thread
 * or the subtrees under level 1, 2, 3 or SL_VERTEX_BRICK_LEVEL are bricks on 2 threads:
 * a triangle across a brick's face is cut in each brick it meets and each leaf sums its
 * pieces in the input's order. Scans: rocker_arm (triangles), the textured cow (colours
 * from its texture), rocker_arm's points without their triangles (a cloud), and
 * armadillo_86kf from the shared data when it is there. */
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/json.h"
#include "shim/vdb_shim.h"
#include "stages/merge/merge.h"
#include "stages/range/range.h"
#include "stages/samples/samples.h"
#include "tests/check.h"

static char tmp_root[256];

/* What sl_octree_vertices fills, copied. */
typedef struct vertices {
    uint32_t nodes, count;
    uint32_t *first;
    float *position, *error, *area;
    uint8_t *color;
} vertices;

static void vertices_copy(const sl_octree *t, vertices *v)
{
    v->nodes = t->node_count;
    v->count = t->vertex_count;
    v->first = malloc(((size_t)t->node_count + 1) * 4);
    v->position = malloc((size_t)t->vertex_count * 12 + 1);
    v->error = malloc((size_t)t->node_count * 4);
    v->area = malloc((size_t)t->node_count * 4);
    v->color = t->vertex_color ? malloc((size_t)t->vertex_count * 4 + 1) : NULL;
    memcpy(v->first, t->vertex_first, ((size_t)t->node_count + 1) * 4);
    memcpy(v->position, t->vertex_position, (size_t)t->vertex_count * 12);
    memcpy(v->error, t->node_error, (size_t)t->node_count * 4);
    memcpy(v->area, t->node_area, (size_t)t->node_count * 4);
    if (v->color)
        memcpy(v->color, t->vertex_color, (size_t)t->vertex_count * 4);
}

static int vertices_same(const vertices *a, const sl_octree *t)
{
    return a->nodes == t->node_count && a->count == t->vertex_count &&
           !memcmp(a->first, t->vertex_first, ((size_t)a->nodes + 1) * 4) &&
           !memcmp(a->position, t->vertex_position, (size_t)a->count * 12) &&
           !memcmp(a->error, t->node_error, (size_t)a->nodes * 4) &&
           !memcmp(a->area, t->node_area, (size_t)a->nodes * 4) && !a->color == !t->vertex_color &&
           (!a->color || !memcmp(a->color, t->vertex_color, (size_t)a->count * 4));
}

static void vertices_release(vertices *v)
{
    free(v->first);
    free(v->position);
    free(v->error);
    free(v->area);
    free(v->color);
}

/* The range stage's point set of `ply` (in tmp_root/name). */
static int pointset_of(const char *ply, const char *name, sl_pointset *ps)
{
    char dir[400], path[600];
    snprintf(dir, sizeof dir, "%s/%s", tmp_root, name);
    mkdir(dir, 0755);
    sl_range_config rcfg = sl_range_default_config();
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_stage_io io = {.item = name, .source_path = ply, .out_dir = dir, .report = &j, .threads = 2};
    sl_error err;
    sl_error_init(&err);
    int rc = sl_range_stage.run(&rcfg, &io, &err);
    sl_json_release(&j);
    snprintf(path, sizeof path, "%s/%s", dir, SL_POINTSET_FILE);
    if (rc == 0)
        rc = sl_pointset_read(path, ps, &err);
    if (rc)
        fprintf(stderr, "%s: %s\n", name, err.message);
    return rc;
}

static void test_scan(const char *name, sl_pointset *ps, int cloud, int want_colours)
{
    sl_samples_config scfg = sl_samples_default_config();
    sl_samples_counts counts;
    sl_vdb_samples s;
    sl_error err;
    sl_error_init(&err);
    if (cloud) {
        ps->triangle_count = 0; /* the points and their normals alone */
        if (!ps->normals) {
            CHECK_MSG(0, "%s: the point set has no normals to stand for a cloud", name);
            return;
        }
    }
    CHECK(sl_samples_compute(&scfg, ps, &s, &counts, NULL, &err) == SL_OK);
    sl_sample_grid grid = {s.count, s.coords, s.distance, s.colors, s.leaf_size,
                           {s.origin[0], s.origin[1], s.origin[2]}};
    sl_octree tree;
    CHECK(sl_octree_build(&grid, &tree, NULL, &err) == SL_OK);
    sl_vdb_samples_release(&s);
    CHECK_MSG(tree.depth > 3, "%s: depth %u: bricks of level 3 would be the whole tree", name,
              tree.depth);
    CHECK_MSG(!want_colours || tree.crossing_color, "%s: no colours to sum", name);
    sl_surface surface = {ps->count, ps->positions, ps->normals, ps->colors, ps->triangle_count,
                          ps->triangles, ps->mean_spacing * ps->mean_spacing, 0};

    /* The reference: one brick (the whole tree) on one thread. */
    omp_set_num_threads(1);
    CHECK(sl_octree_vertices(&tree, &surface, 0.02, tree.depth, &err) == SL_OK);
    vertices whole;
    vertices_copy(&tree, &whole);
    CHECK_MSG(whole.count > 1000, "%s: %u vertices", name, whole.count);

    const uint32_t levels[] = {1, 2, 3, SL_VERTEX_BRICK_LEVEL};
    for (size_t i = 0; i < sizeof levels / sizeof levels[0]; i++) {
        omp_set_num_threads(2);
        CHECK(sl_octree_vertices(&tree, &surface, 0.02, levels[i], &err) == SL_OK);
        CHECK_MSG(levels[i] >= tree.depth || tree.level_count[levels[i]] > 1,
                  "%s: one brick at level %u", name, levels[i]);
        CHECK_MSG(vertices_same(&whole, &tree),
                  "%s: the vertices under bricks of level %u (%u bricks, 2 threads) differ from "
                  "one brick's", name, levels[i], tree.level_count[levels[i]]);
    }
    printf("  %s: %u nodes, %u vertices, depth %u, %u / %u / %u bricks at levels 1 / 2 / 3%s\n",
           name, tree.node_count, whole.count, tree.depth, tree.level_count[1],
           tree.level_count[2], tree.level_count[3], tree.crossing_color ? ", coloured" : "");
    vertices_release(&whole);
    sl_octree_release(&tree);
}

static int ok(int rc)
{
    CHECK(rc == SL_OK);
    return rc == SL_OK;
}

int main(void)
{
    snprintf(tmp_root, sizeof tmp_root, "/tmp/test_vertex_bricks.XXXXXX");
    if (!mkdtemp(tmp_root))
        return 1;
    char buf[600];
    sl_pointset ps;
    if (ok(pointset_of(check_source_path("tests/data/scans/rocker_arm.ply", buf, sizeof buf),
                             "rocker_arm", &ps))) {
        test_scan("rocker_arm", &ps, 0, 0);
        test_scan("rocker_arm points", &ps, 1, 0);
        sl_pointset_release(&ps);
    }
    if (ok(pointset_of(check_source_path("tests/data/textured/cow_textured.ply", buf,
                                               sizeof buf), "cow_textured", &ps))) {
        test_scan("cow_textured", &ps, 0, 1);
        sl_pointset_release(&ps);
    }
    if (!check_light() && check_shared_path("armadillo_86kf.ply", buf, sizeof buf) &&
        ok(pointset_of(buf, "armadillo", &ps))) {
        test_scan("armadillo_86kf", &ps, 0, 0);
        sl_pointset_release(&ps);
    }
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_root);
    if (system(cmd) != 0)
        fprintf(stderr, "cannot remove %s\n", tmp_root);
    return check_report();
}
