/* The segment stage through its entry: options of [segment] and the ladder ([levels]), the
 * run on the range stage's points.slpts (the level list of levels/level.h, its levels
 * within their budgets and watertight, segments.slsgm), byte-identical files on 1 and 2
 * threads, nothing written when interrupted, a point cloud refused, a damaged level file
 * refused by the reader. */
#include <dirent.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "geometry/mesh_adjacency.h"
#include "formats/ply.h"
#include "pipeline/config.h"
#include "levels/level.h"
#include "stages/range/range.h"
#include "stages/segment/segment.h"
#include "tests/check.h"

static char tmp_root[512];

static void make_dir(char *dir, size_t size, const char *name)
{
    snprintf(dir, size, "%s/%s", tmp_root, name);
    mkdir(dir, 0755);
}

static void remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    char path[1400];
    while (d && (e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (unlink(path) != 0)
            remove_tree(path);
    }
    if (d)
        closedir(d);
    rmdir(dir);
}

static int count_files(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int n = 0;
    while (d && (e = readdir(d)))
        n += e->d_name[0] != '.';
    if (d)
        closedir(d);
    return n;
}

static char *slurp(const char *path, long *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    *size = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *data = malloc(*size + 1);
    if (fread(data, 1, *size, f) != (size_t)*size)
        *size = -1;
    fclose(f);
    return data;
}

/* points.slpts of a bundled scan, as the range stage writes it, into DIR. */
static int write_points(const char *scan, const char *dir, sl_pointset *ps)
{
    char path[1024], out[1100];
    check_source_path(scan, path, sizeof path);
    sl_mesh mesh;
    sl_mesh_init(&mesh);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_read(path, NULL, &mesh, NULL, NULL, &err);
    sl_range_config rc_cfg = sl_range_default_config();
    sl_range_counts counts;
    if (!rc)
        rc = sl_range_points_from_mesh(&rc_cfg, &mesh, NULL, ps, &counts, NULL, &err);
    sl_mesh_release(&mesh);
    snprintf(out, sizeof out, "%s/%s", dir, SL_POINTSET_FILE);
    if (!rc)
        rc = sl_pointset_write(out, ps, &err);
    CHECK_MSG(rc == 0, "%s: %s", scan, err.message);
    return rc;
}

static void *configure(const char **overrides, int n)
{
    const sl_option *tables[] = {sl_segment_stage.options, sl_ladder_options, NULL};
    sl_config *cfg = NULL;
    sl_error err;
    sl_error_init(&err);
    void *sc = NULL;
    int rc = sl_config_load(&cfg, tables, NULL, overrides, n, &err);
    if (!rc)
        rc = sl_segment_stage.configure(cfg, &sc, &err);
    CHECK_MSG(rc == 0, "%s", err.message);
    sl_config_free(cfg);
    return sc;
}

static int run_stage(const void *sc, const char *range_dir, const char *out, int threads,
                     volatile sig_atomic_t *interrupt)
{
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_progress progress = {NULL, NULL, interrupt};
    struct sl_stage_dir_entry up[] = {{"range", range_dir}, {NULL, NULL}};
    sl_stage_io io = {.item = "item", .source_path = "item.ply", .in_dir = range_dir,
                      .out_dir = out, .report = &j, .progress = &progress, .threads = threads,
                      .upstream = up};
    sl_error err;
    sl_error_init(&err);
    omp_set_num_threads(threads);
    int rc = sl_segment_stage.run(sc, &io, &err);
    sl_json_object_end(&j);
    if (rc && rc != SL_E_INTERRUPTED && rc != SL_E_UNSUPPORTED)
        fprintf(stderr, "  (stage: %s: %s)\n", sl_error_name(rc), err.message);
    CHECK(rc || strstr(j.buf, "\"levels\":[") != NULL);
    sl_json_release(&j);
    return rc;
}

static void test_options(void)
{
    const char *over[] = {"segment.delta_seg=35", "segment.rule=paper", "segment.alpha=2",
                          "levels.percents=10,100", "levels.budgets=thumb:500"};
    void *sc = configure(over, 5);
    sl_segment_stage.release_config(sc);
    const sl_option *tables[] = {sl_segment_stage.options, sl_ladder_options, NULL};
    const char *bad[] = {"segment.delta_seg=95"};
    sl_config *cfg = NULL;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, tables, NULL, bad, 1, &err) == SL_E_CONFIG);
    CHECK(strcmp(sl_segment_stage.name, "segment") == 0 && sl_segment_stage.version >= 1);
}

static void test_run(void)
{
    char range[600], out1[600], out2[600], out3[600], path[1400];
    make_dir(range, sizeof range, "range");
    make_dir(out1, sizeof out1, "out1");
    make_dir(out2, sizeof out2, "out2");
    make_dir(out3, sizeof out3, "out3");
    sl_pointset ps;
    if (write_points("tests/data/scans/fandisk.ply", range, &ps))
        return;
    /* Each level at its own count (paper 3); by default they are made at twice it, for the
     * refine stage's collapse (checked below). */
    const char *over[] = {"levels.percents=5,20,100", "levels.budgets=thumb:500,big:99999",
                          "segment.search_samples=0", "levels.oversample=1"};
    void *sc = configure(over, 4);
    CHECK(run_stage(sc, range, out1, 1, NULL) == 0);
    CHECK(run_stage(sc, range, out2, 2, NULL) == 0);
    CHECK_EQ_U64(count_files(out1), 7); /* the map, the list, five levels */
    const char *files[] = {SL_LEVEL_LIST_FILE, SL_SEGMENT_MAP_FILE, "lod5.sllvl", "thumb.sllvl"};
    for (int f = 0; f < 4; f++) { /* the same bytes on 1 and 2 threads */
        long s1, s2;
        snprintf(path, sizeof path, "%s/%s", out1, files[f]);
        char *a = slurp(path, &s1);
        snprintf(path, sizeof path, "%s/%s", out2, files[f]);
        char *b = slurp(path, &s2);
        CHECK_MSG(a && b && s1 == s2 && memcmp(a, b, (size_t)s1) == 0, "%s differs", files[f]);
        free(a);
        free(b);
    }
    sl_level_list lv; /* the level list the refine stage reads */
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_level_list_read(out1, &lv, &err) == 0);
    CHECK_EQ_U64(lv.count, 5);
    CHECK_EQ_U64(lv.input_triangles, ps.triangle_count);
    const uint64_t budgets[5] = {ps.triangle_count * 5 / 100, ps.triangle_count * 20 / 100,
                                 ps.triangle_count, 500, 99999};
    const char *names[5] = {"lod5", "lod20", "lod100", "thumb", "big"};
    for (uint32_t i = 0; i < lv.count && i < 5; i++) {
        sl_level *l = &lv.levels[i];
        CHECK_MSG(!strcmp(l->name, names[i]), "%s", l->name);
        CHECK(sl_level_read_mesh(out1, l, ps.count, &err) == 0);
        CHECK_MSG(l->triangle_count <= budgets[i], "%s: %llu", l->name,
                  (unsigned long long)l->triangle_count);
        CHECK(!!(l->flags & SL_LEVEL_CLAMPED) == (budgets[i] >= ps.triangle_count));
        CHECK((l->rung.kind == SL_RUNG_SHARE) == (i < 3) && l->budget == budgets[i] &&
              !(l->flags & SL_LEVEL_INTERMEDIATE) && !strcmp(l->method, "segment"));
        int moved = 0; /* every vertex is the point it names, unmoved */
        for (uint64_t v = 0; v < l->vertex_count; v++)
            moved += l->source[v] >= ps.count ||
                     memcmp(l->positions + 3 * v, ps.positions + 3 * (uint64_t)l->source[v], 12);
        CHECK_MSG(moved == 0, "%s: %d vertices are not their points", l->name, moved);
        sl_mesh_adjacency adj;
        CHECK(sl_mesh_adjacency_build(l->triangles, l->triangle_count, l->vertex_count, NULL,
                                      SL_ADJACENCY_STRICT, &adj, &err) == 0);
        CHECK_MSG(adj.report.boundary_edges == 0 && adj.report.euler_characteristic == 2,
                  "%s: %llu boundary edges", l->name,
                  (unsigned long long)adj.report.boundary_edges);
        sl_mesh_adjacency_release(&adj);
    }
    CHECK(lv.levels[2].triangle_count == ps.triangle_count); /* lod100: the input */
    sl_level_list_release(&lv);

    /* a damaged level file is refused: one byte of its body flipped */
    long size;
    snprintf(path, sizeof path, "%s/lod5.sllvl", out1);
    char *data = slurp(path, &size);
    data[size - 5] ^= 0x40;
    snprintf(path, sizeof path, "%s/lod5.sllvl", out3);
    FILE *f = fopen(path, "wb");
    fwrite(data, 1, (size_t)size, f);
    fclose(f);
    free(data);
    sl_error_init(&err);
    sl_level damaged;
    memset(&damaged, 0, sizeof damaged);
    snprintf(damaged.name, sizeof damaged.name, "lod5");
    CHECK(sl_level_read_mesh(out3, &damaged, ps.count, &err) == SL_E_CORRUPT);
    unlink(path);

    /* The default: each level made at twice its count (at most the input's), for the
     * refine stage to collapse the rest of the way. */
    const char *twice[] = {"levels.percents=5", "levels.budgets=", "segment.search_samples=0"};
    void *sc2 = configure(twice, 3);
    char out4[600];
    make_dir(out4, sizeof out4, "out4");
    CHECK(run_stage(sc2, range, out4, 2, NULL) == 0);
    sl_level_list two;
    CHECK(sl_level_list_read(out4, &two, &err) == 0);
    uint64_t five = ps.triangle_count * 5 / 100;
    CHECK_MSG(two.count == 1 && two.levels[0].budget == five &&
                  two.levels[0].triangle_count > five && two.levels[0].triangle_count <= 2 * five,
              "lod5 made at %llu triangles for %llu", (unsigned long long)two.levels[0].triangle_count,
              (unsigned long long)five);
    sl_level_list_release(&two);
    sl_segment_stage.release_config(sc2);

    /* interrupted: nothing written */
    volatile sig_atomic_t stop = 1;
    CHECK(run_stage(sc, range, out3, 2, &stop) == SL_E_INTERRUPTED);
    CHECK_EQ_U64(count_files(out3), 0);
    sl_segment_stage.release_config(sc);
    sl_pointset_release(&ps);
}

static void test_point_cloud(void)
{
    char range[600], out[600];
    make_dir(range, sizeof range, "cloud");
    make_dir(out, sizeof out, "cloud_out");
    sl_pointset ps;
    memset(&ps, 0, sizeof ps);
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    ps.count = 3;
    ps.positions = pos;
    ps.normals = nrm;
    ps.bbox_max[0] = ps.bbox_max[1] = 1;
    ps.mean_spacing = 1;
    char path[700];
    snprintf(path, sizeof path, "%s/%s", range, SL_POINTSET_FILE);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_pointset_write(path, &ps, &err) == 0);
    const char *over[] = {"segment.search_samples=0"};
    void *sc = configure(over, 1);
    CHECK(run_stage(sc, range, out, 1, NULL) == SL_E_UNSUPPORTED);
    CHECK_EQ_U64(count_files(out), 0);
    sl_segment_stage.release_config(sc);
}

int main(void)
{
    snprintf(tmp_root, sizeof tmp_root, "%s/scanlod-segment-stage.XXXXXX",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    if (!mkdtemp(tmp_root))
        return 1;
    test_options();
    test_run();
    test_point_cloud();
    remove_tree(tmp_root);
    return check_report();
}
