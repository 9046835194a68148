/* meshopt_lod: the meshoptimizer peer of the benchmark (issue 3).
 *
 *   meshopt_lod IN.ply (--targets N,N,.. | --fractions F,F,..) [-o PREFIX]
 *               [--target-error E] [--lock-border]
 *
 * Reads IN.ply with the project's reader, welds equal positions
 * (meshopt_generateVertexRemap: meshopt_simplify only collapses along shared vertices),
 * then runs meshopt_simplify from the full welded mesh to each target triangle count,
 * timing each level on its own. target_error is relative to the mesh extent
 * (meshopt_simplifyScale); the default 1.0 lets the simplifier go as far as the target
 * asks, so a level that stays above its target is a topological limit of the method,
 * reported as "reached": false. With -o, level k is written to PREFIX_<target>.ply
 * (positions only, unused vertices dropped).
 *
 * stdout: one JSON object {"peer","version","input","input_triangles",
 * "welded_vertices","read_seconds","weld_seconds","levels":[{"target","triangles",
 * "reached","result_error","seconds","output"}],"peak_rss_kb"}.
 * Exit 64 on usage errors, 65 when the input cannot be read, 74 when a write fails.
 */
#include <errno.h>
#include <math.h>
#include <meshoptimizer.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "core/json.h"
#include "formats/ply.h"

#define MAX_LEVELS 64

typedef struct options {
    const char *input, *prefix;
    double targets[MAX_LEVELS]; /* triangle counts, or fractions when `fractions` */
    int level_count, fractions, lock_border;
    float target_error;
} options;

typedef struct welded {
    size_t vertex_count, index_count;
    float *positions;       /* 3 * vertex_count */
    unsigned int *indices;  /* index_count */
} welded;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int usage(const char *why)
{
    if (why)
        fprintf(stderr, "meshopt_lod: %s\n", why);
    fputs("usage: meshopt_lod IN.ply (--targets N,N,.. | --fractions F,F,..) [-o PREFIX]\n"
          "                   [--target-error E] [--lock-border]\n",
          stderr);
    return 64;
}

static int parse_list(const char *text, options *o)
{
    char *end;
    for (const char *p = text; *p; p = *end ? end + 1 : end) {
        if (o->level_count == MAX_LEVELS)
            return -1;
        double v = strtod(p, &end);
        if (end == p || (*end && *end != ',') || !(v > 0.0))
            return -1;
        if (o->fractions ? v > 1.0 : v != floor(v))
            return -1;
        o->targets[o->level_count++] = v;
    }
    return o->level_count ? 0 : -1;
}

static int parse_options(int argc, char **argv, options *o)
{
    memset(o, 0, sizeof *o);
    o->target_error = 1.0f;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has_value = i + 1 < argc;
        if ((!strcmp(a, "--targets") || !strcmp(a, "--fractions")) && has_value) {
            if (o->level_count)
                return usage("give --targets or --fractions once");
            o->fractions = a[2] == 'f';
            if (parse_list(argv[++i], o))
                return usage("bad list: whole counts for --targets, (0, 1] for --fractions");
        } else if (!strcmp(a, "-o") && has_value) {
            o->prefix = argv[++i];
        } else if (!strcmp(a, "--target-error") && has_value) {
            o->target_error = strtof(argv[++i], NULL);
            if (!(o->target_error > 0.0f))
                return usage("--target-error must be positive");
        } else if (!strcmp(a, "--lock-border")) {
            o->lock_border = 1;
        } else if (a[0] != '-' && !o->input) {
            o->input = a;
        } else {
            return usage(NULL);
        }
    }
    if (!o->input || !o->level_count)
        return usage("needs an input and targets");
    return 0;
}

/* Positions-only, welded copy of the mesh. Returns 0 or -1 (out of memory). */
static int weld(const sl_mesh *m, welded *w)
{
    size_t index_count = 3 * (size_t)m->triangle_count;
    unsigned int *remap = malloc((m->vertex_count ? m->vertex_count : 1) * sizeof *remap);
    w->indices = malloc((index_count ? index_count : 1) * sizeof *w->indices);
    w->positions = NULL;
    if (remap && w->indices) {
        w->vertex_count = meshopt_generateVertexRemap(remap, m->triangles, index_count,
                                                      m->positions, m->vertex_count,
                                                      3 * sizeof(float));
        w->positions = malloc((w->vertex_count ? w->vertex_count : 1) * 3 * sizeof(float));
    }
    if (!w->positions) {
        free(remap);
        free(w->indices);
        return -1;
    }
    w->index_count = index_count;
    meshopt_remapIndexBuffer(w->indices, m->triangles, index_count, remap);
    meshopt_remapVertexBuffer(w->positions, m->positions, m->vertex_count, 3 * sizeof(float),
                              remap);
    free(remap);
    return 0;
}

/* Writes the level (indices into w's positions) with unused vertices dropped. */
static int write_level(const char *path, const welded *w, unsigned int *indices,
                       size_t index_count, sl_error *err)
{
    float *positions = malloc((w->vertex_count ? w->vertex_count : 1) * 3 * sizeof(float));
    if (!positions)
        return sl_error_set(err, SL_E_NOMEM, 0, path, "level vertices");
    size_t used = meshopt_optimizeVertexFetch(positions, indices, index_count, w->positions,
                                              w->vertex_count, 3 * sizeof(float));
    sl_mesh out = sl_mesh_view(used, positions, NULL, NULL, index_count / 3, indices);
    int rc = sl_ply_write(path, &out, err);
    free(positions);
    return rc;
}

static int run_level(const options *o, const welded *w, double target_value, sl_json *j,
                     unsigned int *indices, sl_error *err)
{
    size_t input_triangles = w->index_count / 3;
    size_t target = o->fractions ? (size_t)llround(target_value * (double)input_triangles)
                                 : (size_t)target_value;
    float result_error = 0.0f;
    double t0 = now();
    size_t count = meshopt_simplify(indices, w->indices, w->index_count, w->positions,
                                    w->vertex_count, 3 * sizeof(float), 3 * target,
                                    o->target_error,
                                    o->lock_border ? meshopt_SimplifyLockBorder : 0,
                                    &result_error);
    double seconds = now() - t0;

    char path[4096] = "";
    if (o->prefix) {
        snprintf(path, sizeof path, "%s_%zu.ply", o->prefix, target);
        if (write_level(path, w, indices, count, err) != SL_OK)
            return -1;
    }
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "target", target);
    sl_json_u64(j, "triangles", count / 3);
    sl_json_bool(j, "reached", count / 3 <= target);
    sl_json_double(j, "result_error", result_error); /* relative to the mesh extent */
    sl_json_double(j, "seconds", seconds);
    sl_json_string(j, "output", o->prefix ? path : NULL);
    sl_json_object_end(j);
    return 0;
}

int main(int argc, char **argv)
{
    options o;
    int rc = parse_options(argc, argv, &o);
    if (rc)
        return rc;

    sl_mesh mesh;
    sl_error err;
    sl_error_init(&err);
    double t0 = now();
    if (sl_ply_read(o.input, NULL, &mesh, NULL, NULL, &err) != SL_OK) {
        char line[1600];
        fprintf(stderr, "meshopt_lod: %s\n", sl_error_format(&err, line, sizeof line));
        return 65;
    }
    double read_seconds = now() - t0;
    welded w;
    t0 = now();
    unsigned int *indices = NULL;
    if (weld(&mesh, &w) != 0 || !(indices = malloc((w.index_count + 1) * sizeof *indices))) {
        fputs("meshopt_lod: out of memory\n", stderr);
        return 75;
    }
    double weld_seconds = now() - t0;

    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "peer", "meshoptimizer");
    sl_json_u64(&j, "version", MESHOPTIMIZER_VERSION);
    sl_json_string(&j, "input", o.input);
    sl_json_u64(&j, "input_triangles", mesh.triangle_count);
    sl_json_u64(&j, "welded_vertices", w.vertex_count);
    sl_json_double(&j, "read_seconds", read_seconds);
    sl_json_double(&j, "weld_seconds", weld_seconds);
    sl_json_double(&j, "target_error", o.target_error);
    sl_json_array_begin(&j, "levels");
    for (int k = 0; k < o.level_count && rc == 0; k++)
        rc = run_level(&o, &w, o.targets[k], &j, indices, &err);
    sl_json_array_end(&j);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    sl_json_u64(&j, "peak_rss_kb", (uint64_t)ru.ru_maxrss);
    sl_json_object_end(&j);

    if (rc == 0 && !j.failed)
        printf("%s\n", sl_json_text(&j));
    else if (rc != 0) {
        char line[1600];
        fprintf(stderr, "meshopt_lod: %s\n", sl_error_format(&err, line, sizeof line));
    }
    int code = rc == 0 && !j.failed ? 0 : 74;
    sl_json_release(&j);
    free(indices);
    free(w.indices);
    free(w.positions);
    sl_mesh_release(&mesh);
    return code;
}
