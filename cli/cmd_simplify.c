/* `scanlod simplify IN --method M (--triangles N | --ratio R | --max-error E)
 * [method options] -o OUT.ply`: one mesh (any scan format sl_scan_read reads) simplified by one
 * of the papers' methods (segment:
 * paper 3, docs/segmentation.md; cluster: paper 2, docs/clustering.md), without a
 * collection or a work folder (README.md, "Using it").
 *
 * The input is cleaned exactly as the range stage cleans it (welded, degenerate and
 * non-finite faces dropped, an inside-out mesh turned), so a level made here equals the
 * one the pipeline makes. A method is an entry of `methods[]` (cli/simplify.h, one file
 * each): its option parser, its usage text and a function from the cleaned mesh and the
 * target to triangles in the cleaned mesh's vertices (plus, optionally, meshes of its
 * own, e.g. intermediate models, and a segment per input triangle).
 *
 * stdout: one summary line, or one JSON object with --json. Bad input: one line
 * `scanlod: FILE: cause`, exit 65; a bad option: exit 64; out of memory, interrupt: 75.
 */
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#include "cli/cli_output.h"
#include "cli/commands.h"
#include "cli/simplify.h"
#include "core/json.h"
#include "core/signals.h"
#include "formats/scan_read.h"
#include "stages/range/range.h"

double sl_simplify_seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int sl_simplify_parse_double(const char *text, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (errno || end == text || *end || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

int sl_simplify_parse_count(int argc, char **argv, int *i, double lo, double hi, double *out)
{
    const char *arg = argv[*i];
    double v;
    if (*i + 1 >= argc || sl_simplify_parse_double(argv[++*i], &v) || v < lo || v > hi ||
        v != floor(v)) {
        fprintf(stderr, "scanlod simplify: %s needs a whole number in [%g, %g]\n", arg, lo, hi);
        return -1;
    }
    *out = v;
    return 0;
}

static const simplify_method *const methods[] = {&sl_simplify_segment, &sl_simplify_cluster};
#define METHOD_COUNT (sizeof methods / sizeof methods[0])

/* --- the command -------------------------------------------------------------------- */

static const char simplify_usage[] =
    "usage: scanlod simplify IN --method M (--triangles N | --ratio R | --max-error E)\n"
    "                        [method options] [-o OUT.ply] [--segment-map MAP.ply]\n"
    "                        [--strict] [--json]\n"
    "  One mesh (PLY, OBJ, STL, OFF, glTF/GLB) simplified by one method, cleaned first as\n"
    "  the pipeline's range stage does.\n"
    "  --method M       segment (paper 3) or cluster (paper 2)\n"
    "  --triangles N    at most N triangles, as close as the method's search gets\n"
    "  --ratio R        at most R x the input's triangles (0 < R <= 1)\n"
    "  --max-error E    no budget: the method's error bound, a fraction of the bounding-box\n"
    "                   diagonal in (0, 1] (none of the three: the method's default bound)\n"
    "  -o OUT.ply       write the level (positions, and colours when the input has them)\n"
    "  --segment-map F  write the input coloured by segment (methods that segment)\n"
    "  --strict         refuse open boundaries, non-manifold edges and degenerate faces\n"
    "                   (by default they are kept: see the method's doc)\n"
    "  --json           the figures as one JSON object on stdout\n";

typedef struct simplify_args {
    const char *input, *output, *segment_map;
    const simplify_method *method;
    simplify_job job;
    int json;
} simplify_args;

/* A bad option: one line naming it (the usage is --help's). */
static int usage_error(const char *fmt, const char *what)
{
    fputs("scanlod simplify: ", stderr);
    fprintf(stderr, fmt, what);
    fputs(" (scanlod simplify --help)\n", stderr);
    return SL_EXIT_USAGE;
}

static int parse_common(int argc, char **argv, int *i, simplify_args *a)
{
    const char *arg = argv[*i];
    if (!strcmp(arg, "--triangles")) {
        double v;
        if (*i + 1 >= argc || sl_simplify_parse_double(argv[++*i], &v) || v < 1 || v != floor(v) || v > 1e15)
            return usage_error("%s needs a whole number >= 1", arg);
        a->job.triangles = (uint64_t)v;
    } else if (!strcmp(arg, "--ratio")) {
        if (*i + 1 >= argc || sl_simplify_parse_double(argv[++*i], &a->job.ratio) ||
            !(a->job.ratio > 0) || a->job.ratio > 1)
            return usage_error("%s needs a number in (0, 1]", arg);
    } else if (!strcmp(arg, "--max-error")) {
        if (*i + 1 >= argc || sl_simplify_parse_double(argv[++*i], &a->job.max_error) ||
            !(a->job.max_error > 0) || a->job.max_error > 1)
            return usage_error("%s needs a fraction of the diagonal in (0, 1] (0.01 = 1 %%)", arg);
    } else if (!strcmp(arg, "-o") || !strcmp(arg, "--segment-map")) {
        if (*i + 1 >= argc)
            return usage_error("%s needs a file name", arg);
        *(!strcmp(arg, "-o") ? &a->output : &a->segment_map) = argv[++*i];
    } else if (!strcmp(arg, "--json")) {
        a->json = 1;
    } else if (!strcmp(arg, "--strict")) {
        a->job.strict = 1;
    } else {
        return -1;
    }
    return 0;
}

static int parse_args(int argc, char **argv, simplify_args *a)
{
    memset(a, 0, sizeof *a);
    for (size_t m = 0; m < METHOD_COUNT; m++)
        methods[m]->reset();
    for (int i = 1; i < argc; i++) /* the method first: its options depend on it */
        if (!strcmp(argv[i], "--method") && i + 1 < argc) {
            a->method = NULL;
            for (size_t m = 0; m < METHOD_COUNT; m++)
                if (!strcmp(argv[i + 1], methods[m]->name))
                    a->method = methods[m];
            if (!a->method)
                return usage_error("unknown method '%s'", argv[i + 1]);
        }
    int counted = 0;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
            fputs(simplify_usage, stdout);
            for (size_t m = 0; m < METHOD_COUNT; m++)
                fputs(methods[m]->options_help, stdout);
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
        rc = a->method ? a->method->parse(argc, argv, &i) : 0;
        if (rc < 0) /* the method said what, in one line */
            return SL_EXIT_USAGE;
        if (rc > 0)
            continue;
        if (arg[0] == '-' && arg[1])
            return usage_error("unknown option %s", arg);
        if (a->input)
            return usage_error("unexpected argument %s", arg);
        a->input = arg;
    }
    if (!a->method)
        return usage_error("%s", "needs --method (segment or cluster)");
    if (!a->input)
        return usage_error("%s", "needs an input PLY file");
    if (counted > 1)
        return usage_error("%s", "give one of --triangles, --ratio and --max-error");
    /* it writes PLY only: a .glb name would get PLY bytes a viewer cannot read */
    const char *dot = a->output ? strrchr(a->output, '.') : NULL;
    if (a->output && (!dot || strcasecmp(dot, ".ply")))
        return usage_error("-o %s: simplify writes PLY (OUT.ply); GLB levels come from a "
                           "run with [lod] method = segment or cluster", a->output);
    if ((a->output && sl_cli_check_output("simplify", "-o", a->output)) ||
        (a->segment_map && sl_cli_check_output("simplify", "--segment-map", a->segment_map)))
        return SL_EXIT_USAGE;
    a->job.has_output = a->output != NULL;
    if (a->method->check(&a->job)) /* the method said what, in one line */
        return SL_EXIT_USAGE;
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

/* A mesh whose vertex k is positions[k] (the cleaned mesh's vertex source[k], or k when
 * source is NULL), coloured from the cleaned mesh when it has colours. */
static int write_mesh(const char *path, const sl_pointset *ps, uint64_t vertex_count,
                      const float *positions, const uint32_t *source, uint64_t triangle_count,
                      const uint32_t *triangles, sl_error *err)
{
    sl_mesh m;
    sl_mesh_init(&m);
    m.vertex_count = vertex_count;
    m.triangle_count = triangle_count;
    m.positions = malloc((vertex_count ? vertex_count : 1) * 12);
    m.colors = ps->colors ? malloc((vertex_count ? vertex_count : 1) * 4) : NULL;
    m.triangles = malloc((triangle_count ? triangle_count : 1) * 12);
    int rc;
    if (!m.positions || (ps->colors && !m.colors) || !m.triangles) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, path, "writing the mesh");
    } else {
        memcpy(m.positions, positions, vertex_count * 12);
        memcpy(m.triangles, triangles, triangle_count * 12);
        for (uint64_t v = 0; m.colors && v < vertex_count; v++)
            memcpy(m.colors + 4 * v, ps->colors + 4 * (uint64_t)(source ? source[v] : v), 4);
        rc = sl_ply_write(path, &m, err);
    }
    sl_mesh_release(&m);
    return rc;
}

/* The level: the cleaned mesh's vertices it uses, in their order. */
static int write_level(const char *path, const sl_pointset *ps, const simplify_output *o,
                       sl_error *err)
{
    uint64_t n = ps->count ? ps->count : 1;
    uint32_t *map = malloc(n * sizeof *map), *source = malloc(n * sizeof *source);
    float *pos = malloc(n * 12);
    uint32_t *tri = malloc((o->triangle_count ? o->triangle_count : 1) * 12);
    int rc;
    if (!map || !source || !pos || !tri) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, path, "writing the level");
    } else {
        memset(map, 0xff, n * sizeof *map);
        for (uint64_t i = 0; i < 3 * o->triangle_count; i++)
            map[o->triangles[i]] = 0;
        uint64_t used = 0;
        for (uint64_t p = 0; p < ps->count; p++)
            if (map[p] != UINT32_MAX) {
                source[used] = (uint32_t)p;
                memcpy(pos + 3 * used, ps->positions + 3 * p, 12);
                map[p] = (uint32_t)used++;
            }
        for (uint64_t i = 0; i < 3 * o->triangle_count; i++)
            tri[i] = map[o->triangles[i]];
        rc = write_mesh(path, ps, used, pos, source, o->triangle_count, tri, err);
    }
    free(map);
    free(source);
    free(pos);
    free(tri);
    return rc;
}

/* OUT_K.ply beside OUT.ply (the suffix kept when OUT has one). */
static int extra_path(char *buf, size_t size, const char *out, uint32_t k)
{
    const char *dot = strrchr(out, '.'), *slash = strrchr(out, '/');
    if (!dot || (slash && dot < slash))
        dot = out + strlen(out);
    int n = snprintf(buf, size, "%.*s_%u%s", (int)(dot - out), out, k, dot);
    return n > 0 && (size_t)n < size ? 0 : -1;
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

static int write_outputs(const simplify_args *a, const sl_pointset *ps, const simplify_output *o,
                         sl_error *err)
{
    int rc = a->output ? write_level(a->output, ps, o, err) : 0;
    for (uint32_t k = 0; k < o->extra_count && rc == 0; k++) {
        char path[PATH_MAX];
        const simplify_extra *x = &o->extras[k];
        if (extra_path(path, sizeof path, a->output, k + 1))
            return sl_error_set(err, SL_E_USAGE, 0, a->output, "the file name is too long");
        rc = write_mesh(path, ps, x->vertex_count, x->positions, x->source, x->triangle_count,
                        x->triangles, err);
    }
    if (rc == 0 && a->segment_map)
        rc = write_segment_map(a->segment_map, ps, o, err);
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
    if (a->json)
        printf("%.*s\n", (int)j.len, j.buf);
    else
        printf("%s: %" PRIu64 " -> %" PRIu64 " triangles (%s), %.3f s\n  %s\n", a->input,
               ps->triangle_count, o->triangle_count, a->method->name, seconds[2],
               o->figures.len > 2 ? o->figures.buf : "");
    sl_json_release(&j);
}

/* What the cleaning dropped and the method kept, said once on stderr. */
static void notes(const simplify_args *a, const sl_range_counts *counts)
{
    if (counts->degenerate_faces)
        fprintf(stderr, "scanlod simplify: %s: note: %" PRIu64 " degenerate faces dropped\n",
                a->input, counts->degenerate_faces);
}

int sl_cmd_simplify(int argc, char **argv)
{
    simplify_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc)
        return rc == -2 ? SL_EXIT_OK : rc;
    sl_error err;
    sl_error_init(&err);
    sl_signals_install();
    sl_progress progress = {NULL, NULL, sl_interrupt_flag()};
    double seconds[4] = {0, 0, 0, 0}, t = sl_simplify_seconds_now();
    sl_mesh mesh;
    sl_mesh_init(&mesh);
    rc = sl_scan_read(a.input, NULL, &mesh, NULL, &progress, &err);
    if (rc) {
        sl_mesh_release(&mesh);
        return report_error(&err, a.input, 1);
    }
    seconds[0] = sl_simplify_seconds_now() - t;
    t = sl_simplify_seconds_now();
    sl_range_config rcfg = sl_range_default_config();
    sl_pointset ps;
    sl_range_counts counts;
    uint64_t faces = mesh.triangle_count;
    rc = sl_range_points_from_mesh(&rcfg, &mesh, NULL, &ps, &counts, &progress, &err);
    sl_mesh_release(&mesh);
    if (rc)
        return report_error(&err, a.input, 1);
    seconds[1] = sl_simplify_seconds_now() - t;
    if (a.job.strict && counts.degenerate_faces) {
        sl_error_set(&err, SL_E_BADINPUT, 0, a.input,
                     "%" PRIu64 " of %" PRIu64 " faces are degenerate (a repeated corner after "
                     "welding, or zero area)", counts.degenerate_faces, faces);
        sl_pointset_release(&ps);
        return report_error(&err, a.input, 1);
    }
    simplify_output out;
    memset(&out, 0, sizeof out);
    sl_json_init(&out.figures, 0);
    sl_json_object_begin(&out.figures, NULL);
    a.job.mesh = &ps;
    a.job.input = a.input;
    t = sl_simplify_seconds_now();
    if (ps.triangle_count == 0)
        rc = sl_error_set(&err, SL_E_BADINPUT, 0, a.input,
                          "a point cloud (no faces): simplify needs a triangle mesh");
    else
        rc = a.method->run(&a.job, &out, &progress, &err);
    seconds[2] = sl_simplify_seconds_now() - t;
    sl_json_object_end(&out.figures);
    int exit_code = SL_EXIT_OK;
    if (rc) {
        exit_code = report_error(&err, a.input, sl_error_class_of(rc) == SL_CLASS_BADINPUT);
    } else {
        notes(&a, &counts);
        t = sl_simplify_seconds_now();
        rc = write_outputs(&a, &ps, &out, &err);
        seconds[3] = sl_simplify_seconds_now() - t;
        if (rc)
            exit_code = report_error(&err, NULL, 0);
        else
            print_result(&a, &ps, &out, &counts, seconds);
    }
    if (!rc && ps.triangle_count == 1)
        fprintf(stderr, "scanlod simplify: %s: a single triangle: nothing to simplify\n", a.input);
    a.method->release(&out);
    sl_json_release(&out.figures);
    sl_pointset_release(&ps);
    return exit_code;
}
