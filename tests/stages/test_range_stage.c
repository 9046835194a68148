/* The range stage through its registry entry: options of [range], the run function on
 * files (report, points.slpts, nothing written on failure or interrupt), byte-identical
 * output on 1 and 2 threads, range images, and a textured PLY + PNG written here.
 * Prints the stage's wall time on bun_zipper and igea at 1 and 2 threads. */
#include <dirent.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "pipeline/config.h"
#include "shim/oiio_shim.h"
#include "stages/range/range.h"
#include "stages/registry.h"
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

/* Runs the stage on `source` into a fresh `out` dir; the report text goes to *report. */
static int run_stage(const sl_range_config *cfg, const char *source, const char *out,
                     int threads, volatile sig_atomic_t *interrupt, char **report, double *secs)
{
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_progress progress = {NULL, NULL, interrupt};
    sl_stage_io io = {.item = "item", .source_path = source, .out_dir = out, .report = &j,
                      .progress = &progress, .threads = threads};
    sl_error err;
    sl_error_init(&err);
    omp_set_num_threads(threads);
    double t0 = omp_get_wtime();
    int rc = sl_range_stage.run(cfg, &io, &err);
    if (secs)
        *secs = omp_get_wtime() - t0;
    sl_json_object_end(&j);
    if (rc != SL_OK && rc != SL_E_INTERRUPTED)
        fprintf(stderr, "  (stage: %s: %s: %s)\n", sl_error_name(rc), err.file, err.message);
    if (report)
        *report = strdup(j.buf ? j.buf : "");
    sl_json_release(&j);
    return rc;
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

static void test_options(void)
{
    const sl_option *tables[] = {sl_range_stage.options, NULL};
    const char *overrides[] = {"range.normals=file", "range.knn=20", "range.colors=none",
                               "range.max_vertices=1000"};
    sl_config *cfg = NULL;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, tables, NULL, overrides, 4, &err) == SL_OK);
    void *sc = NULL;
    CHECK(cfg && sl_range_stage.configure(cfg, &sc, &err) == SL_OK);
    const sl_range_config *rc = sc;
    CHECK(rc && rc->normals_from_file == 1 && rc->knn == 20 && rc->colors == 0);
    CHECK(rc && rc->limits.max_vertices == 1000 && rc->grid_max_edge_factor == 4.0);
    CHECK(rc && rc->range_image_size == 512 && rc->max_nonfinite_fraction == 0.5);
    sl_range_stage.release_config(sc);
    sl_config_free(cfg);
    const char *bad[] = {"range.knn=1"};
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, tables, NULL, bad, 1, &err) == SL_E_CONFIG);
    CHECK(strcmp(sl_range_stage.name, "range") == 0 && sl_stage_find("range") == &sl_range_stage);
}

/* Same bytes on 1 and 2 threads; report counts; prints timings. */
static void test_deterministic(const char *rel, const char *expect_in_report)
{
    char buf[1024], out1[600], out2[600], p1[700], p2[700];
    const char *source = check_shared_path(rel, buf, sizeof buf);
    if (!source)
        return;
    sl_range_config cfg = sl_range_default_config();
    make_dir(out1, sizeof out1, "det1");
    make_dir(out2, sizeof out2, "det2");
    char *report = NULL;
    double t1 = 0, t2 = 0;
    CHECK(run_stage(&cfg, source, out1, 1, NULL, &report, &t1) == SL_OK);
    CHECK(run_stage(&cfg, source, out2, 2, NULL, NULL, &t2) == SL_OK);
    snprintf(p1, sizeof p1, "%s/%s", out1, SL_POINTSET_FILE);
    snprintf(p2, sizeof p2, "%s/%s", out2, SL_POINTSET_FILE);
    long s1 = 0, s2 = 0;
    char *a = slurp(p1, &s1), *b = slurp(p2, &s2);
    CHECK_MSG(a && b && s1 == s2 && s1 > 0 && memcmp(a, b, s1) == 0,
              "%s: points.slpts differs between 1 and 2 threads", rel);
    CHECK_MSG(report && strstr(report, expect_in_report), "%s: report lacks %s: %s", rel,
              expect_in_report, report ? report : "");
    printf("  %s: range stage %.3f s (1 thread), %.3f s (2 threads), %ld bytes\n", rel, t1, t2, s1);
    free(a), free(b), free(report);
    remove_tree(out1);
    remove_tree(out2);
}

static void test_range_images(void)
{
    char buf[1024], out[600], path[700];
    const char *source = check_shared_path("fandisk.ply", buf, sizeof buf);
    if (!source)
        return;
    sl_range_config cfg = sl_range_default_config();
    cfg.range_images = 1;
    cfg.range_image_size = 128;
    make_dir(out, sizeof out, "images");
    CHECK(run_stage(&cfg, source, out, 2, NULL, NULL, NULL) == SL_OK);
    CHECK(count_files(out) == 7);
    const char *views[] = {"xpos", "xneg", "ypos", "yneg", "zpos", "zneg"};
    for (int v = 0; v < 6; v++) {
        sl_image img;
        sl_error err;
        sl_error_init(&err);
        snprintf(path, sizeof path, "%s/range_%s.exr", out, views[v]);
        CHECK(sl_image_read(path, 1 << 20, &img, &err) == SL_OK);
        CHECK(img.width == 128 && img.height == 128 && img.channels == 4);
        uint64_t covered = 0, bad = 0, background_ok = 0;
        for (int i = 0; img.pixels && i < 128 * 128; i++) {
            const float *px = img.pixels + 4 * i;
            if (isnan(px[0])) {
                background_ok += isnan(px[1]) && isnan(px[2]) && isnan(px[3]);
                continue;
            }
            covered++;
            double len = sqrt(px[1] * px[1] + px[2] * px[2] + px[3] * px[3]);
            bad += px[0] < 0 || fabs(len - 1) > 1e-3;
        }
        CHECK_MSG(covered > 128 * 128 / 10 && bad == 0 && background_ok + covered == 128 * 128,
                  "%s: %llu covered, %llu bad", views[v], (unsigned long long)covered,
                  (unsigned long long)bad);
        sl_image_release(&img);
    }
    remove_tree(out);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* A quad with per-vertex u v on a 2 x 2 texture (red, green / blue, white). */
static void test_texture_file(void)
{
    char dir[600], out[600], path[700];
    make_dir(dir, sizeof dir, "textured");
    make_dir(out, sizeof out, "textured_out");
    const float px[] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    sl_error err;
    sl_error_init(&err);
    snprintf(path, sizeof path, "%s/tex.png", dir);
    CHECK(sl_image_write(path, 2, 2, 3, px, &err) == SL_OK);
    snprintf(path, sizeof path, "%s/quad.ply", dir);
    write_text(path, "ply\nformat ascii 1.0\ncomment TextureFile tex.png\n"
                     "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                     "property float u\nproperty float v\nelement face 1\n"
                     "property list uchar int vertex_indices\nend_header\n"
                     "0 0 0 0.25 0.25\n1 0 0 0.75 0.25\n1 1 0 0.75 0.75\n0 1 0 0.25 0.75\n"
                     "4 0 1 2 3\n");
    sl_range_config cfg = sl_range_default_config();
    char *report = NULL;
    CHECK(run_stage(&cfg, path, out, 1, NULL, &report, NULL) == SL_OK);
    CHECK(report && strstr(report, "\"color_source\":\"texture\"") &&
          strstr(report, "\"polygons_triangulated\":1"));
    free(report);
    sl_pointset ps;
    snprintf(path, sizeof path, "%s/%s", out, SL_POINTSET_FILE);
    CHECK(sl_pointset_read(path, &ps, &err) == SL_OK);
    /* Vertex order is kept: (0.25, 0.25) = bottom-left texel = blue, and so on. */
    CHECK(ps.count == 4 && ps.colors && memcmp(ps.colors, "\x00\x00\xff\xff", 4) == 0 &&
          memcmp(ps.colors + 4, "\xff\xff\xff\xff", 4) == 0 &&
          memcmp(ps.colors + 8, "\x00\xff\x00\xff", 4) == 0 &&
          memcmp(ps.colors + 12, "\xff\x00\x00\xff", 4) == 0);
    sl_pointset_release(&ps);
    remove_tree(out);
    /* Per-face texcoords (the MeshLab `texcoord` list): a point averages its corners. */
    snprintf(path, sizeof path, "%s/faces.ply", dir);
    write_text(path, "ply\nformat ascii 1.0\ncomment TextureFile tex.png\n"
                     "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face 1\nproperty list uchar int vertex_indices\n"
                     "property list uchar float texcoord\nend_header\n"
                     "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 6 0.25 0.75 0.75 0.75 0.75 0.25\n");
    make_dir(out, sizeof out, "textured_out");
    CHECK(run_stage(&cfg, path, out, 1, NULL, NULL, NULL) == SL_OK);
    snprintf(path, sizeof path, "%s/%s", out, SL_POINTSET_FILE);
    CHECK(sl_pointset_read(path, &ps, &err) == SL_OK);
    CHECK(ps.count == 3 && ps.colors && memcmp(ps.colors, "\xff\x00\x00\xff", 4) == 0 &&
          memcmp(ps.colors + 4, "\x00\xff\x00\xff", 4) == 0 &&
          memcmp(ps.colors + 8, "\xff\xff\xff\xff", 4) == 0);
    sl_pointset_release(&ps);
    remove_tree(out);
    /* Without the image: a warning in the report, not a failure. */
    snprintf(path, sizeof path, "%s/tex.png", dir);
    unlink(path);
    make_dir(out, sizeof out, "textured_out");
    snprintf(path, sizeof path, "%s/quad.ply", dir);
    CHECK(run_stage(&cfg, path, out, 1, NULL, &report, NULL) == SL_OK);
    CHECK(report && strstr(report, "\"texture_warnings\":1") &&
          strstr(report, "\"color_source\":\"none\""));
    free(report);
    remove_tree(out);
    remove_tree(dir);
}

static void test_failures(void)
{
    char dir[600], out[600], path[700];
    make_dir(dir, sizeof dir, "bad");
    make_dir(out, sizeof out, "bad_out");
    snprintf(path, sizeof path, "%s/nan.ply", dir);
    write_text(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                     "property float y\nproperty float z\nelement face 1\n"
                     "property list uchar int vertex_indices\nend_header\n"
                     "nan 0 0\n0 nan 0\n0 0 1\n3 0 1 2\n");
    sl_range_config cfg = sl_range_default_config();
    CHECK(run_stage(&cfg, path, out, 1, NULL, NULL, NULL) == SL_E_BADINPUT);
    CHECK(count_files(out) == 0);
    /* Interrupted before anything is published. */
    snprintf(path, sizeof path, "%s/ok.ply", dir);
    write_text(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                     "property float y\nproperty float z\nelement face 1\n"
                     "property list uchar int vertex_indices\nend_header\n"
                     "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    volatile sig_atomic_t stop = 1;
    CHECK(run_stage(&cfg, path, out, 1, &stop, NULL, NULL) == SL_E_INTERRUPTED);
    CHECK(count_files(out) == 0);
    CHECK(run_stage(&cfg, path, out, 1, NULL, NULL, NULL) == SL_OK);
    CHECK(count_files(out) == 1);
    remove_tree(out);
    remove_tree(dir);
}

int main(void)
{
    snprintf(tmp_root, sizeof tmp_root, "%s/scanlod-test-range-stage-XXXXXX",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    if (!mkdtemp(tmp_root)) {
        perror("mkdtemp");
        return 1;
    }
    sl_oiio_init();
    test_options();
    test_deterministic("bun_zipper.ply", "\"points\":34834");
    test_deterministic("igea.ply", "\"points\":134345");
    test_deterministic("bunny_range/bun000.ply", "\"normal_source\":\"range-grid\"");
    test_deterministic("dragon_rangescan.ply", "\"normal_source\":\"pca-propagated\"");
    test_range_images();
    test_texture_file();
    test_failures();
    remove_tree(tmp_root);
    return check_report();
}
