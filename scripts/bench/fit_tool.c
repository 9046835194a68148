/* fit_tool: the surface fit (geometry/surface_fit.h) on one level, for the benchmark of
 * docs/surface-fit.md.
 *
 *   fit_tool INPUT.ply LEVEL.ply [-o OUT.ply] [--iterations N] [--spring S]
 *            [--border-weight W] [--samples N] [--input-per-triangle N]
 *            [--level-per-triangle N]
 *
 * Fits LEVEL to INPUT (a mesh or a point cloud) and writes the result to OUT (positions
 * and triangles only). stdout: one JSON object with the fit's statistics, the seconds
 * of the reference build and of the fit, and the peak RSS. Exit 64 on usage errors, else
 * the project's exit code of the failure.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "core/json.h"
#include "formats/ply.h"
#include "geometry/surface_fit.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int usage(void)
{
    fputs("usage: fit_tool INPUT.ply LEVEL.ply [-o OUT.ply] [--iterations N] [--spring S]\n"
          "                [--border-weight W] [--samples N] [--input-per-triangle N]\n"
          "                [--level-per-triangle N]\n", stderr);
    return 64;
}

static int parse(int argc, char **argv, const char **paths, sl_fit_config *cfg)
{
    int n = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-o") && v)
            paths[2] = argv[++i];
        else if (!strcmp(a, "--iterations") && v)
            cfg->iterations = atoi(argv[++i]);
        else if (!strcmp(a, "--spring") && v)
            cfg->spring = strtod(argv[++i], NULL);
        else if (!strcmp(a, "--border-weight") && v)
            cfg->border_weight = strtod(argv[++i], NULL);
        else if (!strcmp(a, "--samples") && v)
            cfg->samples = strtoull(argv[++i], NULL, 10);
        else if (!strcmp(a, "--input-per-triangle") && v)
            cfg->input_per_triangle = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--level-per-triangle") && v)
            cfg->level_per_triangle = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (a[0] != '-' && n < 2)
            paths[n++] = a;
        else
            return -1;
    }
    return n == 2 ? 0 : -1;
}

static void report(const sl_fit_stats *st, double build_s, double fit_s)
{
    sl_json j;
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_json_double(&j, "rms_before", st->rms_before / st->diagonal);
    sl_json_double(&j, "rms_after", st->rms_after / st->diagonal);
    sl_json_double(&j, "rms_input_to_level", st->rms_input_to_level / st->diagonal);
    sl_json_double(&j, "rms_level_to_input", st->rms_level_to_input / st->diagonal);
    sl_json_i64(&j, "iterations", st->iterations);
    sl_json_i64(&j, "best_iteration", st->best_iteration);
    sl_json_u64(&j, "vertices_moved", st->vertices_moved);
    sl_json_u64(&j, "vertices_backtracked", st->vertices_backtracked);
    sl_json_u64(&j, "cg_iterations", st->cg_iterations);
    sl_json_u64(&j, "input_samples", st->input_samples);
    sl_json_u64(&j, "level_samples", st->level_samples);
    sl_json_u64(&j, "border_samples", st->border_samples);
    sl_json_u64(&j, "border_vertices", st->border_vertices);
    sl_json_u64(&j, "fixed_vertices", st->fixed_vertices);
    sl_json_double(&j, "reference_seconds", build_s);
    sl_json_double(&j, "fit_seconds", fit_s);
    sl_json_u64(&j, "peak_rss_kb", (uint64_t)ru.ru_maxrss);
    sl_json_object_end(&j);
    printf("%s\n", sl_json_text(&j));
    sl_json_release(&j);
}

int main(int argc, char **argv)
{
    const char *paths[3] = {NULL, NULL, NULL};
    sl_fit_config cfg = sl_fit_default_config();
    if (parse(argc, argv, paths, &cfg))
        return usage();
    sl_mesh input, level;
    sl_mesh_init(&input);
    sl_mesh_init(&level);
    sl_error err;
    sl_error_init(&err);
    sl_fit_reference *ref = NULL;
    sl_fit_stats st;
    double t0 = 0.0, t1 = 0.0, t2 = 0.0;
    int rc = sl_ply_read(paths[0], NULL, &input, NULL, NULL, &err);
    if (rc == SL_OK)
        rc = sl_ply_read(paths[1], NULL, &level, NULL, NULL, &err);
    if (rc == SL_OK) {
        t0 = now();
        rc = sl_fit_reference_build(&input, &cfg, &ref, &err);
        t1 = now();
    }
    if (rc == SL_OK)
        rc = sl_surface_fit(ref, level.positions, level.vertex_count, level.triangles,
                            level.triangle_count, &cfg, &st, NULL, &err);
    t2 = now();
    if (rc == SL_OK && paths[2]) {
        sl_mesh out = sl_mesh_view(level.vertex_count, level.positions, NULL, NULL,
                                   level.triangle_count, level.triangles);
        rc = sl_ply_write(paths[2], &out, &err);
    }
    if (rc == SL_OK)
        report(&st, t1 - t0, t2 - t1);
    else {
        char line[1600];
        fprintf(stderr, "fit_tool: %s\n", sl_error_format(&err, line, sizeof line));
    }
    sl_fit_reference_free(ref);
    sl_mesh_release(&input);
    sl_mesh_release(&level);
    return rc == SL_OK ? 0 : sl_error_exit_code(rc);
}
