/* `scanlod compare A B [--samples N] [--seed S] [--json]`: how far B's surface is from A's
 * (docs/fidelity.md); A and B are scans in any format sl_scan_read reads. Results go to stdout, as a table or as one JSON
 * object for the benchmark scripts; a bad file is one line `scanlod: FILE: cause` on
 * stderr and exit 65; a usage error exits 64.
 */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli/commands.h"
#include "core/json.h"
#include "geometry/mesh_distance.h"
#include "formats/scan_read.h"

static const char compare_usage[] =
    "usage: scanlod compare A B [--samples N] [--seed S] [--json]\n"
    "  A and B: scans (PLY, OBJ, STL, OFF, XYZ/PTS, glTF/GLB).\n"
    "  Surface distance from B to A and back: symmetric and one-sided Hausdorff, RMS and\n"
    "  mean, as fractions of A's bounding-box diagonal; B's boundary and non-manifold\n"
    "  edges and whether B is watertight. A may be a point cloud (a scan without faces):\n"
    "  then the distances are from its points to B only.\n"
    "  --samples N  area samples on each mesh, vertices come on top (default 1000000)\n"
    "  --seed S     sample positions (default 1)\n"
    "  --json       one JSON object instead of the table\n";

typedef struct compare_args {
    const char *path_a, *path_b;
    sl_mesh_distance_config cfg;
    int json;
} compare_args;

static int usage_error(const char *fmt, const char *what)
{
    fputs("scanlod compare: ", stderr);
    fprintf(stderr, fmt, what);
    fputs("\n", stderr);
    fputs(compare_usage, stderr);
    return SL_EXIT_USAGE;
}

static int parse_u64(const char *text, uint64_t min, uint64_t *out)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(text, &end, 10);
    if (errno || end == text || *end || text[0] == '-' || v < min)
        return -1;
    *out = v;
    return 0;
}

static int parse_args(int argc, char **argv, compare_args *args)
{
    memset(args, 0, sizeof *args);
    args->cfg = sl_mesh_distance_default_config();
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (!strcmp(arg, "--json")) {
            args->json = 1;
        } else if (!strcmp(arg, "--samples")) {
            if (i + 1 >= argc || parse_u64(argv[++i], 1, &args->cfg.samples))
                return usage_error("%s needs a positive integer", arg);
        } else if (!strcmp(arg, "--seed")) {
            if (i + 1 >= argc || parse_u64(argv[++i], 0, &args->cfg.seed))
                return usage_error("%s needs a non-negative integer", arg);
        } else if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
            fputs(compare_usage, stdout);
            return -1;
        } else if (arg[0] == '-' && arg[1]) {
            return usage_error("unknown option %s", arg);
        } else if (!args->path_a) {
            args->path_a = arg;
        } else if (!args->path_b) {
            args->path_b = arg;
        } else {
            return usage_error("unexpected argument %s", arg);
        }
    }
    if (!args->path_b)
        return usage_error("%s", "needs two PLY files");
    return 0;
}

/* One line `scanlod: FILE: cause`. A file that cannot be read at all (missing,
 * unreadable, not a regular file) is bad input for this one-shot command, like a
 * malformed one: exit 65; other failures (out of memory) keep their class's exit code. */
static int report_error(const sl_error *err, int reading)
{
    char line[1600];
    fprintf(stderr, "scanlod: %s\n", sl_error_format(err, line, sizeof line));
    return reading ? sl_error_input_exit_code(err->code) : sl_error_exit_code(err->code);
}

static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void json_figures(sl_json *j, const char *key, const sl_distance_side *side)
{
    sl_json_object_begin(j, key);
    sl_json_double(j, "hausdorff", side->fraction.hausdorff);
    sl_json_double(j, "rms", side->fraction.rms);
    sl_json_double(j, "mean", side->fraction.mean);
    sl_json_double(j, "hausdorff_world", side->world.hausdorff);
    sl_json_double(j, "rms_world", side->world.rms);
    sl_json_double(j, "mean_world", side->world.mean);
    sl_json_u64(j, "area_samples", side->area_samples);
    sl_json_u64(j, "vertex_samples", side->vertex_samples);
    sl_json_object_end(j);
}

static int print_json(const compare_args *args, const sl_mesh *a, const sl_mesh *b,
                      const sl_mesh_distance *d, const sl_mesh_topology *topo, const double seconds[2])
{
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "a", args->path_a);
    sl_json_string(&j, "b", args->path_b);
    sl_json_u64(&j, "a_triangles", a->triangle_count);
    sl_json_u64(&j, "b_triangles", b->triangle_count);
    sl_json_double(&j, "diagonal", d->diagonal);
    sl_json_double(&j, "hausdorff", d->fraction.hausdorff);
    sl_json_double(&j, "rms", d->fraction.rms);
    sl_json_double(&j, "mean", d->fraction.mean);
    sl_json_double(&j, "hausdorff_world", d->world.hausdorff);
    sl_json_double(&j, "rms_world", d->world.rms);
    sl_json_double(&j, "mean_world", d->world.mean);
    sl_json_bool(&j, "a_is_points", d->a_is_points);
    json_figures(&j, "a_to_b", &d->a_to_b);
    if (!d->a_is_points)
        json_figures(&j, "b_to_a", &d->b_to_a);
    sl_json_object_begin(&j, "b_topology");
    sl_json_u64(&j, "welded_vertices", topo->welded_vertices);
    sl_json_u64(&j, "edges", topo->edges);
    sl_json_u64(&j, "boundary_edges", topo->boundary_edges);
    sl_json_u64(&j, "nonmanifold_edges", topo->nonmanifold_edges);
    sl_json_u64(&j, "degenerate_triangles", topo->degenerate_triangles);
    sl_json_bool(&j, "watertight", topo->watertight);
    sl_json_u64(&j, "components", topo->components);
    sl_json_double(&j, "largest_component_area_fraction",
                   topo->area > 0 ? topo->largest_component_area / topo->area : 0);
    sl_json_object_end(&j);
    sl_json_u64(&j, "samples", args->cfg.samples);
    sl_json_u64(&j, "seed", args->cfg.seed);
    sl_json_double(&j, "read_seconds", seconds[0]);
    sl_json_double(&j, "compare_seconds", seconds[1]);
    sl_json_object_end(&j);
    int failed = j.failed;
    if (!failed)
        printf("%.*s\n", (int)j.len, j.buf);
    sl_json_release(&j);
    if (failed) {
        fputs("scanlod: compare: out of memory writing JSON\n", stderr);
        return SL_EXIT_TEMPFAIL;
    }
    return SL_EXIT_OK;
}

static void print_side(const char *label, const sl_distance_side *s)
{
    printf("  %-10s %12.6g %12.6g %12.6g   (%" PRIu64 " area + %" PRIu64 " vertex samples)\n",
           label, s->fraction.hausdorff, s->fraction.rms, s->fraction.mean, s->area_samples,
           s->vertex_samples);
}

static void print_table(const compare_args *args, const sl_mesh *a, const sl_mesh *b,
                        const sl_mesh_distance *d, const sl_mesh_topology *topo,
                        const double seconds[2])
{
    if (d->a_is_points)
        printf("A %s: %" PRIu64 " points (no triangles: distances from its points), "
               "bounding-box diagonal %.9g\n", args->path_a, a->vertex_count, d->diagonal);
    else
        printf("A %s: %" PRIu64 " triangles, bounding-box diagonal %.9g\n", args->path_a,
               a->triangle_count, d->diagonal);
    printf("B %s: %" PRIu64 " triangles\n", args->path_b, b->triangle_count);
    printf("distance as a fraction of A's diagonal:\n");
    printf("  %-10s %12s %12s %12s\n", "", "hausdorff", "rms", "mean");
    printf("  %-10s %12.6g %12.6g %12.6g\n", "symmetric", d->fraction.hausdorff,
           d->fraction.rms, d->fraction.mean);
    print_side("A to B", &d->a_to_b);
    if (d->a_is_points)
        printf("  %-10s (not measured: A is a point cloud)\n", "B to A");
    else
        print_side("B to A", &d->b_to_a);
    printf("B edges: %" PRIu64 " boundary, %" PRIu64 " non-manifold, %" PRIu64
           " degenerate triangles (after welding equal positions)\n",
           topo->boundary_edges, topo->nonmanifold_edges, topo->degenerate_triangles);
    printf("B watertight: %s\n", topo->watertight ? "yes" : "no");
    printf("B parts: %" PRIu64 ", the largest with %.2f %% of the area\n", topo->components,
           topo->area > 0 ? 100 * topo->largest_component_area / topo->area : 0.0);
    printf("time: %.3f s reading, %.3f s comparing\n", seconds[0], seconds[1]);
}

/* B must be a surface; A may also be a point cloud (no triangles at all), whose points
 * the distance code checks. */
static int read_surface(const char *path, int points_allowed, sl_mesh *m, sl_error *err)
{
    int rc = sl_scan_read(path, NULL, m, NULL, NULL, err);
    if (rc == SL_OK && !(points_allowed && m->triangle_count == 0))
        rc = sl_mesh_check_surface(m, path, err);
    return rc;
}

int sl_cmd_compare(int argc, char **argv)
{
    compare_args args;
    int rc = parse_args(argc, argv, &args);
    if (rc)
        return rc < 0 ? SL_EXIT_OK : rc;

    sl_mesh a, b;
    sl_mesh_init(&a);
    sl_mesh_init(&b);
    sl_error err;
    sl_error_init(&err);
    sl_mesh_distance d;
    sl_mesh_topology topo;
    double seconds[2], start = seconds_now();
    rc = read_surface(args.path_a, 1, &a, &err);
    if (rc == SL_OK)
        rc = read_surface(args.path_b, 0, &b, &err);
    int reading = rc != SL_OK;
    seconds[0] = seconds_now() - start;
    start = seconds_now();
    if (rc == SL_OK) {
        rc = sl_mesh_distance_compute(&a, &b, &args.cfg, &d, NULL, &err);
        if (rc == SL_E_BADINPUT && !err.file[0]) /* "mesh A: ..." names the file */
            snprintf(err.file, sizeof err.file, "%s",
                     strncmp(err.message, "mesh B", 6) == 0 ? args.path_b : args.path_a);
    }
    if (rc == SL_OK)
        rc = sl_mesh_topology_compute(&b, &topo, &err);
    seconds[1] = seconds_now() - start;

    int exit_code;
    if (rc != SL_OK)
        exit_code = report_error(&err, reading);
    else if (args.json)
        exit_code = print_json(&args, &a, &b, &d, &topo, seconds);
    else {
        print_table(&args, &a, &b, &d, &topo, seconds);
        exit_code = SL_EXIT_OK;
    }
    sl_mesh_release(&a);
    sl_mesh_release(&b);
    return exit_code;
}
