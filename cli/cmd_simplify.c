/* `scanlod simplify IN.ply --method M (--triangles N | --ratio R | --max-error E) -o OUT.ply`:
 * one mesh simplified by one of the papers' methods, without a collection or a work
 * folder (ARCHITECTURE section 1; docs/segmentation.md).
 *
 * The input is cleaned exactly as the range stage cleans it (welded, degenerate and
 * non-finite faces dropped, an inside-out mesh turned), so a level made here equals the
 * one the pipeline makes. A method is an entry of `methods[]`: its option parser, its
 * usage text and a function from the cleaned mesh and the target to triangles in the
 * cleaned mesh's vertices; adding `cluster` (paper 2) is one more entry.
 *
 * stdout: one line per level figure, or one JSON object with --json. Bad input: one line
 * `scanlod: FILE: cause`, exit 65; a bad option: exit 64; out of memory, interrupt: 75.
 */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli/commands.h"
#include "core/json.h"
#include "core/signals.h"
#include "geometry/ply.h"
#include "stages/range/range.h"
#include "stages/segment/segment.h"

static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* What every method gets: the cleaned mesh and the size asked for. */
typedef struct simplify_job {
    const char *input;   /* for messages */
    const sl_pointset *mesh;
    uint64_t triangles;  /* > 0: budget */
    double ratio;        /* > 0: budget as a fraction of the input */
    double max_error;    /* > 0: error bound, fraction of the diagonal */
} simplify_job;

/* What a method gives back: triangles in the cleaned mesh's points, and its figures. */
typedef struct simplify_output {
    uint64_t triangle_count;
    uint32_t *triangles;
    uint32_t *segment_of_input; /* optional: a segment id per input triangle (owned) */
    uint32_t segment_count;
    sl_json figures;            /* the method's own figures (an open object's members) */
} simplify_output;

typedef struct simplify_method {
    const char *name;
    const char *options_help;
    /* Parses argv[*i] (and its value) if it is one of the method's options: 1 taken,
     * 0 not the method's, -1 a bad value (message printed). */
    int (*parse)(void *opts, int argc, char **argv, int *i);
    void *opts;
    int (*run)(void *opts, const simplify_job *job, simplify_output *out, sl_progress *progress,
               sl_error *err);
    const char *problem; /* set by parse: why a value was refused */
} simplify_method;

/* --- the segment method (paper 3) ------------------------------------------------------ */

static sl_segment_config segment_opts;

static int parse_double(const char *text, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (errno || end == text || *end || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

static int segment_parse(void *opts, int argc, char **argv, int *i)
{
    sl_segment_config *c = opts;
    const char *arg = argv[*i];
    double *dst = !strcmp(arg, "--delta-seg") ? &c->delta_seg
                  : !strcmp(arg, "--delta-b") ? &c->delta_b
                  : !strcmp(arg, "--alpha") ? &c->alpha
                  : !strcmp(arg, "--max-deviation") ? &c->max_normal_deviation
                  : !strcmp(arg, "--merge-ratio") ? &c->merge_ratio
                  : !strcmp(arg, "--merge-angle") ? &c->merge_angle
                                                    : NULL;
    if (dst) {
        if (*i + 1 >= argc || parse_double(argv[++*i], dst)) {
            fprintf(stderr, "scanlod simplify: %s needs a number\n", arg);
            return -1;
        }
        return 1;
    }
    if (!strcmp(arg, "--search-samples")) {
        double v;
        if (*i + 1 >= argc || parse_double(argv[++*i], &v) || v < 0 || v > 1e9 || v != floor(v)) {
            fprintf(stderr, "scanlod simplify: --search-samples needs a whole number >= 0\n");
            return -1;
        }
        c->search_samples = (uint64_t)v;
        return 1;
    }
    if (!strcmp(arg, "--segments")) {
        double v;
        if (*i + 1 >= argc || parse_double(argv[++*i], &v) || v < 1 || v > 4e9 || v != floor(v)) {
            fprintf(stderr, "scanlod simplify: --segments needs a whole number >= 1\n");
            return -1;
        }
        c->target_segments = (uint32_t)v;
        return 1;
    }
    if (!strcmp(arg, "--rule")) {
        const char *v = *i + 1 < argc ? argv[++*i] : "";
        c->rule = !strcmp(v, "error") ? SL_SEGMENT_RULE_ERROR
                  : !strcmp(v, "near") ? SL_SEGMENT_RULE_NEAR
                  : !strcmp(v, "paper") ? SL_SEGMENT_RULE_PAPER : -1;
        if (c->rule < 0) {
            fprintf(stderr, "scanlod simplify: --rule is one of error, near, paper\n");
            return -1;
        }
        return 1;
    }
    return 0;
}

static void segment_figures(sl_json *j, const sl_segment_stats *s)
{
    sl_json_u64(j, "segments", s->segments);
    sl_json_double(j, "delta_seg", s->delta_seg);
    sl_json_u64(j, "input_vertices", s->input_vertices);
    sl_json_u64(j, "removed_vertices", s->removed_vertices);
    sl_json_double(j, "removed_percent",
                   s->input_vertices ? 100.0 * (double)s->removed_vertices / (double)s->input_vertices : 0);
    sl_json_u64(j, "removed_boundary", s->removed_boundary);
    sl_json_u64(j, "removed_interior", s->removed_interior);
    sl_json_u64(j, "corners", s->corners);
    sl_json_u64(j, "boundary_vertices", s->boundary_vertices);
    sl_json_u64(j, "interior_vertices", s->interior_vertices);
    sl_json_u64(j, "patches_retriangulated", s->patches_retriangulated);
    sl_json_u64(j, "patches_boundary_kept", s->patches_boundary_kept);
    sl_json_u64(j, "patches_kept", s->patches_kept);
    sl_json_u64(j, "patches_folded", s->patches_folded);
    sl_json_u64(j, "repairs", s->repairs);
    sl_json_u64(j, "search_passes", s->search_passes);
    sl_json_double(j, "max_error", s->max_error);
    sl_json_double(j, "estimated_rms", s->estimate);
    sl_json_bool(j, "over_budget", s->over_budget);
    sl_json_u64(j, "nonmanifold_edges_kept", s->nonmanifold_edges_kept);
    sl_json_i64(j, "euler_characteristic", s->euler_characteristic);
    sl_json_bool(j, "watertight", s->watertight);
}

static int segment_run(void *opts, const simplify_job *job, simplify_output *out,
                       sl_progress *progress, sl_error *err)
{
    const sl_segment_config *cfg = opts;
    sl_segment_input in = {job->mesh->count, job->mesh->positions, job->mesh->triangle_count,
                           job->mesh->triangles};
    sl_segment_target target = {job->triangles, job->ratio, job->max_error};
    sl_segment_model *model = NULL;
    double t0 = seconds_now();
    int rc = sl_segment_model_build(cfg, &in, &model, progress, err);
    double t1 = seconds_now();
    sl_segment_level level;
    memset(&level, 0, sizeof level);
    if (!rc)
        rc = sl_segment_model_level(model, cfg, &target, &level, progress, err);
    double t2 = seconds_now();
    if (!rc && level.stats.nonmanifold_edges_kept)
        fprintf(stderr,
                "scanlod simplify: %s: %llu non-manifold edges (in three or more triangles) "
                "kept as they are, with the segments around them\n",
                job->input, (unsigned long long)level.stats.nonmanifold_edges_kept);
    if (!rc && level.stats.over_budget)
        fprintf(stderr,
                "scanlod simplify: %s: the budget is below what the segments' corners need: "
                "%llu triangles, the fewest the method reaches here\n",
                job->input, (unsigned long long)level.triangle_count);
    if (!rc) {
        uint32_t count;
        const uint32_t *map = sl_segment_model_map(model, &count);
        out->segment_of_input = malloc((in.triangle_count ? in.triangle_count : 1) * sizeof *map);
        if (out->segment_of_input) {
            memcpy(out->segment_of_input, map, in.triangle_count * sizeof *map);
            out->segment_count = count;
        }
        out->triangle_count = level.triangle_count;
        out->triangles = level.triangles;
        level.triangles = NULL;
        segment_figures(&out->figures, &level.stats);
        sl_json_double(&out->figures, "segmentation_seconds", t1 - t0);
        sl_json_double(&out->figures, "level_seconds", t2 - t1);
    }
    sl_segment_level_release(&level);
    sl_segment_model_free(model);
    return rc;
}

static simplify_method methods[] = {
    {"segment",
     "  segment (paper 3; docs/segmentation.md):\n"
     "    --delta-seg D      largest angle between two triangles of a segment, degrees (20)\n"
     "    --segments K       instead: the smallest delta-seg giving at most K segments\n"
     "    --delta-b D        boundary vertices within D degrees of straight may go (60)\n"
     "    --rule R           interior vertices: error (far from the new patch stay; the\n"
     "                       default), near (near the plane go), paper (equation 8 as printed)\n"
     "    --alpha A          equation 8's control parameter, rules near and paper (-1.5)\n"
     "    --max-deviation D  a new triangle's normal within D degrees of the input's (90)\n"
     "    --merge-ratio R    budgets: merge segments down to budget / R (25; 0: never)\n"
     "    --merge-angle A    merged segments keep their triangles within A degrees of\n"
     "                       their mean normal, parts only merge that close (60)\n"
     "    --search-samples N budgets: samples of the RMS the search minimises (50000; 0:\n"
     "                       estimate it from the removed vertices, faster)\n",
     segment_parse, &segment_opts, segment_run, NULL},
};

/* --- the command -------------------------------------------------------------------- */

static const char simplify_usage[] =
    "usage: scanlod simplify IN.ply [--method M] (--triangles N | --ratio R | --max-error E)\n"
    "                        [method options] [-o OUT.ply] [--segment-map MAP.ply] [--json]\n"
    "  One mesh simplified by one method, cleaned first as the pipeline's range stage does.\n"
    "  --method M       segment (default)\n"
    "  --triangles N    at most N triangles, as close as the method's search gets\n"
    "  --ratio R        at most R x the input's triangles (0 < R <= 1)\n"
    "  --max-error E    no search: the method's error bound, a fraction of the bounding-box\n"
    "                   diagonal (neither given: the method's default bound)\n"
    "  -o OUT.ply       write the level (positions, and colours when the input has them)\n"
    "  --segment-map F  write the input coloured by segment (methods that segment)\n"
    "  --json           the figures as one JSON object on stdout\n";

typedef struct simplify_args {
    const char *input, *output, *segment_map;
    const simplify_method *method;
    simplify_job job;
    int json;
} simplify_args;

static int usage_error(const char *fmt, const char *what)
{
    fputs("scanlod simplify: ", stderr);
    fprintf(stderr, fmt, what);
    fputs("\n", stderr);
    fputs(simplify_usage, stderr);
    return SL_EXIT_USAGE;
}

static void print_help(void)
{
    fputs(simplify_usage, stdout);
    for (size_t i = 0; i < sizeof methods / sizeof methods[0]; i++)
        fputs(methods[i].options_help, stdout);
}

static int parse_common(int argc, char **argv, int *i, simplify_args *a)
{
    const char *arg = argv[*i];
    if (!strcmp(arg, "--triangles")) {
        double v;
        if (*i + 1 >= argc || parse_double(argv[++*i], &v) || v < 1 || v != floor(v) || v > 1e15)
            return usage_error("%s needs a whole number >= 1", arg);
        a->job.triangles = (uint64_t)v;
    } else if (!strcmp(arg, "--ratio")) {
        if (*i + 1 >= argc || parse_double(argv[++*i], &a->job.ratio) || !(a->job.ratio > 0) ||
            a->job.ratio > 1)
            return usage_error("%s needs a number in (0, 1]", arg);
    } else if (!strcmp(arg, "--max-error")) {
        if (*i + 1 >= argc || parse_double(argv[++*i], &a->job.max_error) ||
            !(a->job.max_error > 0) || a->job.max_error > 1)
            return usage_error("%s needs a number in (0, 1]", arg);
    } else if (!strcmp(arg, "-o") || !strcmp(arg, "--segment-map")) {
        if (*i + 1 >= argc)
            return usage_error("%s needs a file name", arg);
        *(!strcmp(arg, "-o") ? &a->output : &a->segment_map) = argv[++*i];
    } else if (!strcmp(arg, "--json")) {
        a->json = 1;
    } else {
        return -1;
    }
    return 0;
}

static int parse_args(int argc, char **argv, simplify_args *a)
{
    memset(a, 0, sizeof *a);
    segment_opts = sl_segment_default_config();
    a->method = &methods[0];
    for (int i = 1; i < argc; i++) /* the method first: its options depend on it */
        if (!strcmp(argv[i], "--method") && i + 1 < argc) {
            a->method = NULL;
            for (size_t m = 0; m < sizeof methods / sizeof methods[0]; m++)
                if (!strcmp(argv[i + 1], methods[m].name))
                    a->method = &methods[m];
            if (!a->method)
                return usage_error("unknown method '%s'", argv[i + 1]);
        }
    int counted = 0;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
            print_help();
            return -2;
        }
        if (!strcmp(arg, "--method")) {
            if (++i >= argc)
                return usage_error("%s needs a name", arg);
            continue;
        }
        int rc = parse_common(argc, argv, &i, a);
        if (rc > 0)
            return rc;
        if (rc == 0) {
            counted += !strcmp(arg, "--triangles") || !strcmp(arg, "--ratio") ||
                       !strcmp(arg, "--max-error");
            continue;
        }
        rc = a->method->parse(a->method->opts, argc, argv, &i);
        if (rc < 0) {
            fputs(simplify_usage, stderr);
            return SL_EXIT_USAGE;
        }
        if (rc > 0)
            continue;
        if (arg[0] == '-' && arg[1])
            return usage_error("unknown option %s (see --help)", arg);
        if (a->input)
            return usage_error("unexpected argument %s", arg);
        a->input = arg;
    }
    if (!a->input)
        return usage_error("%s", "needs an input PLY file");
    if (counted > 1)
        return usage_error("%s", "give one of --triangles, --ratio, --max-error");
    return 0;
}

/* One line `scanlod: FILE: cause`; reading failures of the input are the user's data. */
static int report_error(sl_error *err, const char *file, int reading)
{
    if (!err->file[0] && file)
        snprintf(err->file, sizeof err->file, "%s", file);
    char line[1600];
    fprintf(stderr, "scanlod: %s\n", sl_error_format(err, line, sizeof line));
    return reading ? sl_error_input_exit_code(err->code) : sl_error_exit_code(err->code);
}

/* The level as a mesh of the points it uses (in their order), with colours if any. */
static int write_level(const char *path, const sl_pointset *ps, const simplify_output *o,
                       sl_error *err)
{
    uint32_t *map = malloc((ps->count ? ps->count : 1) * sizeof *map);
    if (!map)
        return sl_error_set(err, SL_E_NOMEM, 0, path, "writing the level");
    memset(map, 0xff, (ps->count ? ps->count : 1) * sizeof *map);
    uint64_t used = 0;
    for (uint64_t i = 0; i < 3 * o->triangle_count; i++)
        if (map[o->triangles[i]] == UINT32_MAX)
            map[o->triangles[i]] = 0;
    for (uint64_t p = 0; p < ps->count; p++)
        if (map[p] != UINT32_MAX)
            map[p] = (uint32_t)used++;
    sl_mesh m;
    sl_mesh_init(&m);
    m.vertex_count = used;
    m.triangle_count = o->triangle_count;
    m.positions = malloc((used ? used : 1) * 12);
    m.colors = ps->colors ? malloc((used ? used : 1) * 4) : NULL;
    m.triangles = malloc((o->triangle_count ? o->triangle_count : 1) * 12);
    int rc = SL_OK;
    if (!m.positions || (ps->colors && !m.colors) || !m.triangles) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, path, "writing the level");
    } else {
        for (uint64_t p = 0; p < ps->count; p++)
            if (map[p] != UINT32_MAX) {
                memcpy(m.positions + 3 * (uint64_t)map[p], ps->positions + 3 * p, 12);
                if (m.colors)
                    memcpy(m.colors + 4 * (uint64_t)map[p], ps->colors + 4 * p, 4);
            }
        for (uint64_t i = 0; i < 3 * o->triangle_count; i++)
            m.triangles[i] = map[o->triangles[i]];
        rc = sl_ply_write(path, &m, err);
    }
    free(map);
    sl_mesh_release(&m);
    return rc;
}

/* The input with each triangle coloured by its segment (unwelded: one colour per face). */
static int write_segment_map(const char *path, const sl_pointset *ps, const simplify_output *o,
                             sl_error *err)
{
    if (!o->segment_of_input)
        return sl_error_set(err, SL_E_USAGE, 0, path, "this method makes no segments");
    uint64_t n = ps->triangle_count;
    sl_mesh m;
    sl_mesh_init(&m);
    m.vertex_count = 3 * n;
    m.triangle_count = n;
    m.positions = malloc((n ? n : 1) * 36);
    m.colors = malloc((n ? n : 1) * 12);
    m.triangles = malloc((n ? n : 1) * 12);
    int rc;
    if (!m.positions || !m.colors || !m.triangles) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, path, "writing the segment map");
    } else {
        for (uint64_t t = 0; t < n; t++) {
            uint64_t h = (o->segment_of_input[t] + 1) * 0x9e3779b97f4a7c15ull;
            for (int c = 0; c < 3; c++) {
                memcpy(m.positions + 9 * t + 3 * c, ps->positions + 3 * (uint64_t)ps->triangles[3 * t + c], 12);
                m.colors[12 * t + 4 * c + 0] = (uint8_t)(64 + (h >> 40) % 192);
                m.colors[12 * t + 4 * c + 1] = (uint8_t)(64 + (h >> 48) % 192);
                m.colors[12 * t + 4 * c + 2] = (uint8_t)(64 + (h >> 56) % 192);
                m.colors[12 * t + 4 * c + 3] = 255;
                m.triangles[3 * t + c] = (uint32_t)(3 * t + c);
            }
        }
        rc = sl_ply_write(path, &m, err);
    }
    sl_mesh_release(&m);
    return rc;
}

static void print_result(const simplify_args *a, const sl_pointset *ps, const simplify_output *o,
                         const sl_range_counts *counts, const double seconds[4])
{
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "input", a->input);
    sl_json_string(&j, "method", a->method->name);
    sl_json_string(&j, "output", a->output);
    sl_json_u64(&j, "input_triangles", ps->triangle_count);
    sl_json_u64(&j, "input_vertices", ps->count);
    sl_json_u64(&j, "triangles", o->triangle_count);
    sl_json_u64(&j, "dropped_degenerate_faces", counts->degenerate_faces);
    sl_json_u64(&j, "welded_vertices", counts->welded);
    sl_json_double(&j, "read_seconds", seconds[0]);
    sl_json_double(&j, "clean_seconds", seconds[1]);
    sl_json_double(&j, "simplify_seconds", seconds[2]);
    sl_json_double(&j, "write_seconds", seconds[3]);
    if (o->figures.len > 2) /* "{" ... : the method's members */
        sl_json_raw(&j, a->method->name, o->figures.buf);
    sl_json_object_end(&j);
    if (a->json) {
        printf("%.*s\n", (int)j.len, j.buf);
    } else {
        printf("%s: %" PRIu64 " -> %" PRIu64 " triangles (%s), %.3f s\n", a->input,
               ps->triangle_count, o->triangle_count, a->method->name, seconds[2]);
        if (o->figures.len > 2)
            printf("  %s\n", o->figures.buf);
    }
    sl_json_release(&j);
}

int sl_cmd_simplify(int argc, char **argv)
{
    simplify_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc)
        return rc == -2 ? SL_EXIT_OK : rc;
    sl_error err;
    sl_error_init(&err);
    if (a.method->run == segment_run && sl_segment_check_config(&segment_opts, &err)) {
        fprintf(stderr, "scanlod simplify: %s\n", err.message);
        return SL_EXIT_USAGE;
    }
    sl_signals_install();
    sl_progress progress = {NULL, NULL, sl_interrupt_flag()};
    double seconds[4] = {0, 0, 0, 0}, t = seconds_now();
    sl_mesh mesh;
    sl_mesh_init(&mesh);
    rc = sl_ply_read(a.input, NULL, &mesh, NULL, &progress, &err);
    if (rc) {
        sl_mesh_release(&mesh);
        return report_error(&err, a.input, 1);
    }
    seconds[0] = seconds_now() - t;
    t = seconds_now();
    sl_range_config rcfg = sl_range_default_config();
    sl_pointset ps;
    sl_range_counts counts;
    rc = sl_range_points_from_mesh(&rcfg, &mesh, NULL, &ps, &counts, &progress, &err);
    sl_mesh_release(&mesh);
    if (rc)
        return report_error(&err, a.input, 1);
    seconds[1] = seconds_now() - t;
    simplify_output out;
    memset(&out, 0, sizeof out);
    sl_json_init(&out.figures, 0);
    sl_json_object_begin(&out.figures, NULL);
    a.job.mesh = &ps;
    a.job.input = a.input;
    t = seconds_now();
    if (ps.triangle_count == 0)
        rc = sl_error_set(&err, SL_E_BADINPUT, 0, a.input,
                          "a point cloud (no faces): simplify needs a triangle mesh");
    else
        rc = a.method->run(a.method->opts, &a.job, &out, &progress, &err);
    seconds[2] = seconds_now() - t;
    sl_json_object_end(&out.figures);
    int exit_code = SL_EXIT_OK;
    if (rc) {
        exit_code = report_error(&err, a.input, sl_error_class_of(rc) == SL_CLASS_BADINPUT);
    } else {
        t = seconds_now();
        if (a.output)
            rc = write_level(a.output, &ps, &out, &err);
        if (!rc && a.segment_map)
            rc = write_segment_map(a.segment_map, &ps, &out, &err);
        seconds[3] = seconds_now() - t;
        if (rc)
            exit_code = report_error(&err, NULL, 0);
        else
            print_result(&a, &ps, &out, &counts, seconds);
    }
    if (!rc && ps.triangle_count == 1)
        fprintf(stderr, "scanlod simplify: %s: a single triangle: nothing to simplify\n", a.input);
    free(out.triangles);
    free(out.segment_of_input);
    sl_json_release(&out.figures);
    sl_pointset_release(&ps);
    return exit_code;
}
