/* The samples stage split into parts (docs/engine.md, "Parts"): each part run by the
 * stage's run_part into its own folder, then joined by its run, must give the bytes of
 * the unsplit stage: samples.vdb and report.json. On real scans through the range stage:
 * rocker_arm (triangles; closed, so the join repairs signs), the textured cow (colours
 * from its texture), and rocker_arm with [samples] closest = points and
 * sign_neighbours = 8 (the k-d tree path, with vote flips summed over the parts); split
 * into 2, 3 and 7 parts, and into more parts than there are blocks of vertices (empty
 * parts). A part from another split, a part missing, or a truncated one: the join fails
 * with SL_E_CORRUPT (or the open error) naming the part's file, and writes nothing. */
#include <dirent.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/hash.h"
#include "pipeline/config.h"
#include "stages/range/range.h"
#include "stages/samples/samples.h"
#include "tests/check.h"
#include "tests/stages/stage_fixtures.h"

static char tmp_root[256];

static int count_files(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    if (!d)
        return 0;
    for (struct dirent *e; (e = readdir(d));)
        n += e->d_name[0] != '.';
    closedir(d);
    return n;
}

/* The stage on in_dir into out: the whole of it (part -1, parts 0), part `part` of
 * `parts`, or the join of `parts` parts found in part_dirs. *report (may be NULL): its
 * report text; *err: its error. */
static int run_stage(const char *const *overrides, int n_overrides, const char *in_dir,
                     const char *out, int part, int parts, const char *const *part_dirs,
                     char **report, sl_error *err)
{
    const sl_option *tables[] = {sl_samples_stage.options, NULL};
    sl_config *cfg = NULL;
    void *sc = NULL;
    sl_error_init(err);
    mkdir(out, 0755);
    if (sl_config_load(&cfg, tables, NULL, overrides, n_overrides, err) ||
        sl_samples_stage.configure(cfg, &sc, err))
        return -100;
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_stage_io io = {.item = "item", .source_path = "unused.ply", .in_dir = in_dir,
                      .out_dir = out, .report = &j, .threads = 2, .part = part,
                      .parts = parts, .part_dirs = part_dirs};
    int rc = part >= 0 ? sl_samples_stage.run_part(sc, &io, err) : sl_samples_stage.run(sc, &io, err);
    sl_json_object_end(&j);
    if (report)
        *report = strdup(j.buf ? j.buf : "");
    sl_json_release(&j);
    sl_samples_stage.release_config(sc);
    sl_config_free(cfg);
    return rc;
}

enum { MAX_PARTS = 64 };

/* Runs every part of a `parts`-way split of in_dir under `name`; their folders in dirs. */
static void run_parts(const char *const *ov, int n_ov, const char *in_dir, const char *name,
                      int parts, char dirs[][300])
{
    for (int p = 0; p < parts; p++) {
        sl_error err;
        snprintf(dirs[p], 300, "%s/%s-part%d", tmp_root, name, p);
        int rc = run_stage(ov, n_ov, in_dir, dirs[p], p, parts, NULL, NULL, &err);
        CHECK_MSG(rc == SL_OK, "%s part %d of %d: %s", name, p, parts, err.message);
    }
}

static void test_split(const char *ply, const char *name, const char *const *ov, int n_ov)
{
    char in[300], whole[300], whole_vdb[400];
    snprintf(in, sizeof in, "%s/%s-points", tmp_root, name);
    CHECK(fixture_range_points(ply, in) == SL_OK);
    snprintf(whole, sizeof whole, "%s/%s-whole", tmp_root, name);
    snprintf(whole_vdb, sizeof whole_vdb, "%s/%s", whole, SL_SAMPLES_FILE);
    char *whole_report = NULL;
    sl_error err;
    CHECK(run_stage(ov, n_ov, in, whole, -1, 0, NULL, &whole_report, &err) == SL_OK);
    const int splits[] = {2, 3, 7, MAX_PARTS};
    for (size_t k = 0; k < sizeof splits / sizeof splits[0]; k++) {
        int parts = splits[k];
        char dirs[MAX_PARTS][300], split_name[100], join[400], join_vdb[500];
        const char *dir_ptrs[MAX_PARTS];
        snprintf(split_name, sizeof split_name, "%s-%d", name, parts);
        run_parts(ov, n_ov, in, split_name, parts, dirs);
        for (int p = 0; p < parts; p++)
            dir_ptrs[p] = dirs[p];
        snprintf(join, sizeof join, "%s/%s-join", tmp_root, split_name);
        snprintf(join_vdb, sizeof join_vdb, "%s/%s", join, SL_SAMPLES_FILE);
        char *report = NULL;
        CHECK(run_stage(ov, n_ov, in, join, -1, parts, dir_ptrs, &report, &err) == SL_OK);
        CHECK_MSG(fixture_same_file(whole_vdb, join_vdb), "%s: samples.vdb of %d parts differs", name,
                  parts);
        CHECK_MSG(report && whole_report && !strcmp(report, whole_report),
                  "%s: the report of %d parts differs:\n  %s\n  %s", name, parts,
                  report ? report : "", whole_report ? whole_report : "");
        free(report);
    }
    printf("  %s: 2, 3, 7 and %d parts joined: the unsplit bytes\n    %s\n", name, MAX_PARTS,
           whole_report ? whole_report : "");
    free(whole_report);
}

/* A join given the wrong parts fails naming the part's file, and writes nothing. */
static void test_bad_parts(const char *ply)
{
    char in[300], a[3][300], b[2][300], out[300], path[400];
    snprintf(in, sizeof in, "%s/bad-points", tmp_root);
    CHECK(fixture_range_points(ply, in) == SL_OK);
    run_parts(NULL, 0, in, "bad3", 3, a);
    run_parts(NULL, 0, in, "bad2", 2, b);
    sl_error err;

    const char *swapped[3] = {a[0], b[1], a[2]}; /* part 2 of 2 where part 2 of 3 goes */
    snprintf(out, sizeof out, "%s/bad-swapped", tmp_root);
    int rc = run_stage(NULL, 0, in, out, -1, 3, swapped, NULL, &err);
    CHECK_MSG(rc == SL_E_CORRUPT && strstr(err.file, b[1]) && strstr(err.message, "another split"),
              "a part of another split: %s %s: %s", sl_error_name(rc), err.file, err.message);
    CHECK(count_files(out) == 0);
    printf("  a part of another split: %s: %s\n", err.file, err.message);

    const char *in_order[3] = {a[0], a[1], a[2]};
    snprintf(path, sizeof path, "%s/samples.part", a[1]);
    CHECK(truncate(path, 100) == 0);
    snprintf(out, sizeof out, "%s/bad-truncated", tmp_root);
    rc = run_stage(NULL, 0, in, out, -1, 3, in_order, NULL, &err);
    CHECK_MSG(rc == SL_E_CORRUPT && strstr(err.file, a[1]) && strstr(err.message, "truncated"),
              "a truncated part: %s %s: %s", sl_error_name(rc), err.file, err.message);
    CHECK(count_files(out) == 0);
    printf("  a truncated part: %s: %s\n", err.file, err.message);

    CHECK(unlink(path) == 0);
    snprintf(out, sizeof out, "%s/bad-missing", tmp_root);
    rc = run_stage(NULL, 0, in, out, -1, 3, in_order, NULL, &err);
    CHECK_MSG(rc != SL_OK && strstr(err.file, a[1]), "a missing part: %s %s: %s",
              sl_error_name(rc), err.file, err.message);
    CHECK(count_files(out) == 0);
    printf("  a missing part: %s: %s\n", err.file, err.message);
}

int main(void)
{
    snprintf(tmp_root, sizeof tmp_root, "/tmp/test_samples_parts.XXXXXX");
    if (!mkdtemp(tmp_root))
        return 1;
    char rocker[600], cow[600];
    check_source_path("tests/data/scans/rocker_arm.ply", rocker, sizeof rocker);
    check_source_path("tests/data/textured/cow_textured.ply", cow, sizeof cow);
    test_split(rocker, "rocker_arm", NULL, 0);
    test_split(cow, "cow_textured", NULL, 0);
    const char *points[] = {"samples.closest=points", "samples.sign_neighbours=8"};
    test_split(rocker, "rocker_arm-points", points, 2);
    test_bad_parts(rocker);
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_root);
    if (system(cmd) != 0)
        fprintf(stderr, "cannot remove %s\n", tmp_root);
    return check_report();
}
