/* scanlod extract: any level of detail from a built model, in O(m) (paper 1, section 3).
 *
 *   scanlod extract MODEL.slod (--expansions K | --triangles N | --lod-percent P |
 *                               --max-error E) -o OUT.{ply,glb,obj}
 *   scanlod extract MODEL.slod (...) --morph-to M [--morph-weight W] -o OUT.{ply,glb,obj}
 *   scanlod extract OCTREE.slot --level L -o OUT.ply      (a uniform octree level)
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

#include "cli/cli_output.h"
#include "cli/commands.h"
#include "core/error.h"
#include "runtime/lod_io.h"
#include "runtime/lod_prefix.h"
#include "runtime/octree_io.h"
#include "geometry/morph_refine.h"
#include "geometry/morph_target.h"
#include "stages/export/export.h"

/* A level to `path` in the format its extension names, a GLB at the [export] defaults. */
static int write_mesh(const char *path, const sl_lod_mesh *mesh, const char *extras,
                      sl_error *err)
{
    sl_export_glb glb = sl_export_default_glb();
    return sl_export_write_mesh(path, mesh, extras, &glb, NULL, err);
}

static const char usage[] =
    "usage: scanlod extract MODEL.slod (--expansions K | --triangles N | --lod-percent P |\n"
    "                                   --max-error E) -o OUT.{ply,glb,obj} [--repeat R [--hot]]\n"
    "       scanlod extract MODEL.slod (--triangles N | ...) --morph-to M [--morph-weight W]\n"
    "                                   [--morph-tears] -o OUT.{ply,glb,obj}\n"
    "       scanlod extract OCTREE.slot --level L -o OUT.{ply,glb,obj}\n"
    "Cuts one level of detail from a model built by `scanlod run` (published as\n"
    "OUTPUT/ITEM/model.slod): K expansions of the LOD array, the largest level within N\n"
    "triangles (the finest when N is above it), P percent of the LOD array's expansions\n"
    "that have surface (paper Table 1; 100 = the finest level), or the coarsest level\n"
    "whose geometric error is at most E (world units). Prints what it wrote and how long the\n"
    "generation took (in a fresh process: the first extraction). --repeat R then times R\n"
    "more extractions of the same level into buffers allocated once, as a viewer using\n"
    "the runtime API does, each after flushing the CPU caches (a viewer renders between\n"
    "two cuts), and prints their median and minimum (for benchmarks). --hot times them\n"
    "back to back instead, after one untimed extraction: the model as far into the caches\n"
    "as its size lets it (the cost of the work itself, without a cold start).\n"
    "--morph-to M morphs the level towards the largest level within M triangles, which\n"
    "must be coarser (docs/morphing.md): each vertex goes to its closest point on that\n"
    "level, and the level is cut along that level's edges so that its surface, not only\n"
    "its vertices, lies on it at weight 1. A .glb gets the morph target (weight 0: the\n"
    "level's surface, 1: on the coarser level); a .ply or .obj is the mesh at weight W\n"
    "(--morph-weight, in [0, 1], default 1; 0 writes the level itself). --morph-tears\n"
    "tears the triangles the cut cannot bring onto the coarser level, as [export]\n"
    "morph_tears does: weight 1 then lies on it exactly, with cracks in between.\n";

typedef struct request {
    const char *input, *output;
    int kind;       /* 'k' expansions, 't' triangles, 'p' percent, 'e' error, 'l' level */
    uint64_t count; /* k, t, l: the whole number given */
    double value;   /* p, e: the number given */
    long repeat;    /* --repeat: warm extractions timed after the first */
    int hot;        /* --hot: those back to back, caches not flushed */
    int morph;      /* --morph-to given */
    uint64_t morph_to; /* its triangle count */
    int has_weight; /* --morph-weight given */
    double weight;  /* its value (default 1) */
    int morph_tears; /* --morph-tears: tear what the refinement cannot mend */
} request;

static int bad_request(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* One line "scanlod extract: ..." on stderr; returns the usage exit code. */
static int bad_request(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("scanlod extract: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    return SL_EXIT_USAGE;
}

static const char digits[] = "0123456789";

/* A count: decimal digits and nothing else -- no sign, space, base prefix (strtoull
 * would read "0x10" as 16 and "-1" as 2^64 - 1) or exponent -- that fits 64 bits. */
static int parse_count(const char *flag, const char *text, uint64_t *out)
{
    size_t n = strspn(text, digits);
    if (n == 0 || text[n])
        return bad_request("%s: '%s' is not a whole number in decimal digits", flag, text);
    uint64_t v = 0;
    for (size_t i = 0; i < n; i++) {
        unsigned d = (unsigned)(text[i] - '0');
        if (v > (UINT64_MAX - d) / 10)
            return bad_request("%s: '%s' is too large", flag, text);
        v = 10 * v + d;
    }
    *out = v;
    return 0;
}

/* [+-]digits[.digits][(e|E)[+-]digits] with a digit before the exponent: what a user
 * writes for a percent or a distance; not strtod's hex, inf, nan or leading spaces. */
static int is_decimal(const char *s)
{
    s += *s == '+' || *s == '-';
    size_t whole = strspn(s, digits), fraction = 0;
    s += whole;
    if (*s == '.') {
        fraction = strspn(++s, digits);
        s += fraction;
    }
    if (whole + fraction == 0)
        return 0;
    if (*s == 'e' || *s == 'E') {
        s += 1 + (s[1] == '+' || s[1] == '-');
        size_t exponent = strspn(s, digits);
        if (exponent == 0)
            return 0;
        s += exponent;
    }
    return *s == 0;
}

static int parse_number(const char *flag, const char *text, double *out)
{
    *out = is_decimal(text) ? strtod(text, NULL) : NAN;
    if (!isfinite(*out))
        return bad_request("%s: '%s' is not a finite number", flag, text);
    return 0;
}

/* The checks that need no model, so that a bad request is refused before the model is
 * read and before any output exists. */
static int check_value(const request *r)
{
    switch (r->kind) {
    case 't':
        if (r->count < 1)
            return bad_request("--triangles must be a whole number >= 1 (got %llu)",
                               (unsigned long long)r->count);
        return 0;
    case 'p':
        if (!(r->value > 0 && r->value <= 100))
            return bad_request("--lod-percent must be in (0, 100] (got %g; the coarsest level "
                               "is --expansions 0)", r->value);
        return 0;
    case 'e':
        if (r->value < 0)
            return bad_request("--max-error must be >= 0 (got %g)", r->value);
        return 0;
    default:
        return 0;
    }
}

/* --morph-to and --morph-weight: with a model, not with --repeat; a weight in [0, 1] and
 * only where the output is one mesh at that weight (not a .glb, which holds the target). */
static int check_morph(request *r)
{
    if (!r->morph && !r->has_weight && !r->morph_tears)
        return 0;
    const char *dot = strrchr(r->output, '.');
    if (!r->morph && r->morph_tears)
        return bad_request("--morph-tears needs --morph-to");
    if (!r->morph)
        return bad_request("--morph-weight needs --morph-to");
    if (r->kind == 'l' || r->repeat)
        return bad_request("--morph-to applies to a model's level, without --repeat");
    if (r->morph_to < 1)
        return bad_request("--morph-to must be a whole number >= 1 (got 0)");
    if (r->has_weight && !(r->weight >= 0 && r->weight <= 1))
        return bad_request("--morph-weight must be in [0, 1] (got %g)", r->weight);
    if (r->has_weight && dot && !strcasecmp(dot, ".glb"))
        return bad_request("--morph-weight applies to .ply and .obj output; a .glb holds the "
                           "morph target itself (its weight is the viewer's)");
    if (!r->has_weight)
        r->weight = 1;
    return 0;
}

/* 0; -1 when the command line is malformed (the caller prints the usage); the usage exit
 * code when a value is bad (said here, in one line naming the flag). */
static int parse(int argc, char **argv, request *r)
{
    memset(r, 0, sizeof *r);
    static const struct { const char *flag; int kind; } flags[] = {
        {"--expansions", 'k'}, {"--triangles", 't'}, {"--lod-percent", 'p'},
        {"--max-error", 'e'},  {"--level", 'l'},
    };
    for (int i = 1; i < argc; i++) {
        int matched = 0;
        for (size_t f = 0; f < sizeof flags / sizeof flags[0]; f++) {
            if (strcmp(argv[i], flags[f].flag) != 0)
                continue;
            if (i + 1 >= argc || r->kind)
                return -1;
            r->kind = flags[f].kind;
            const char *text = argv[++i];
            int rc = r->kind == 'p' || r->kind == 'e'
                         ? parse_number(flags[f].flag, text, &r->value)
                         : parse_count(flags[f].flag, text, &r->count);
            if (rc)
                return rc;
            matched = 1;
        }
        if (matched)
            continue;
        if (!strcmp(argv[i], "-o") && i + 1 < argc) {
            r->output = argv[++i];
        } else if (!strcmp(argv[i], "--repeat") && i + 1 < argc) {
            uint64_t repeat = 0;
            const char *text = argv[++i];
            if (parse_count("--repeat", text, &repeat))
                return SL_EXIT_USAGE;
            if (repeat < 1 || repeat > 100000)
                return bad_request("--repeat: '%s' is not a count in [1, 100000]", text);
            r->repeat = (long)repeat;
        } else if (!strcmp(argv[i], "--hot")) {
            r->hot = 1;
        } else if (!strcmp(argv[i], "--morph-to") && i + 1 < argc) {
            if (parse_count("--morph-to", argv[++i], &r->morph_to))
                return SL_EXIT_USAGE;
            r->morph = 1;
        } else if (!strcmp(argv[i], "--morph-weight") && i + 1 < argc) {
            if (parse_number("--morph-weight", argv[++i], &r->weight))
                return SL_EXIT_USAGE;
            r->has_weight = 1;
        } else if (!strcmp(argv[i], "--morph-tears")) {
            r->morph_tears = 1;
        } else if (argv[i][0] != '-' && !r->input)
            r->input = argv[i];
        else
            return -1;
    }
    if (!(r->input && r->output && r->kind && !(r->repeat && r->kind == 'l') &&
          !(r->hot && !r->repeat)))
        return -1;
    if (check_value(r) || sl_cli_check_output("extract", "-o", r->output))
        return SL_EXIT_USAGE;
    return check_morph(r);
}

/* One line "scanlod: FILE: cause". The model is the user's file: failing to read it is
 * a data error (sl_error_input_exit_code); failing to write the output keeps its class. */
static int fail(const sl_error *err, int reading)
{
    char line[1600];
    fprintf(stderr, "scanlod: %s\n", sl_error_format(err, line, sizeof line));
    return reading ? sl_error_input_exit_code(err->code) : sl_error_exit_code(err->code);
}

static double seconds_since(const struct timespec *t0)
{
    struct timespec t1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return (double)(t1.tv_sec - t0->tv_sec) + (t1.tv_nsec - t0->tv_nsec) * 1e-9;
}

static int extract_level(const request *r)
{
    sl_error err;
    sl_error_init(&err);
    sl_octree tree;
    if (sl_octree_read(r->input, &tree, &err))
        return fail(&err, 1);
    if (r->count > tree.depth) {
        uint32_t depth = tree.depth;
        sl_octree_release(&tree);
        return bad_request("--level %llu exceeds the octree's depth %u (levels 0 to %u)",
                           (unsigned long long)r->count, depth, depth);
    }
    sl_lod_mesh mesh;
    int rc = sl_octree_level_mesh(&tree, (uint32_t)r->count, &mesh);
    if (rc == 0 && write_mesh(r->output, &mesh, NULL, &err) == 0)
        printf("level %llu: %llu triangles, %llu vertices -> %s\n", (unsigned long long)r->count,
               (unsigned long long)mesh.triangle_count, (unsigned long long)mesh.vertex_count,
               r->output);
    else if (rc)
        sl_error_set(&err, SL_E_NOMEM, ENOMEM, r->input, "out of memory");
    sl_lod_mesh_release(&mesh);
    sl_octree_release(&tree);
    return err.code ? fail(&err, 0) : SL_EXIT_OK;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Pushes the model out of the CPU caches: writes one byte per line of a buffer twice
 * the last-level cache (at least 64 MiB). A viewer renders between two cuts, so a cut
 * finds its model in memory, not in cache; timing the same cut back to back instead
 * would serve small cuts from cache and large ones from memory. */
static void evict_caches(volatile unsigned char *buffer, size_t size)
{
    for (size_t i = 0; i < size; i += 64)
        buffer[i]++;
}

static size_t eviction_size(void)
{
    size_t size = (size_t)64 << 20;
#ifdef _SC_LEVEL3_CACHE_SIZE
    long l3 = sysconf(_SC_LEVEL3_CACHE_SIZE);
    if (l3 > 0 && 2 * (size_t)l3 > size)
        size = 2 * (size_t)l3;
#endif
    return size;
}

/* Times `repeat` extractions of level k into buffers sized once by the accumulation
 * table (sl_lod_generate_into: no allocation per extraction), each after the caches
 * were flushed, or (`hot`) back to back after one untimed extraction. */
static int time_warm(sl_lod_model *m, uint32_t k, long repeat, int hot, double *median,
                     double *min)
{
    uint64_t triangles = m->accumulation[k], vertices = 3 * triangles;
    size_t v = (size_t)(vertices ? vertices : 1), t = (size_t)(triangles ? triangles : 1);
    float *positions = malloc(v * 3 * sizeof(float)), *normals = malloc(v * 3 * sizeof(float));
    uint8_t *colors = malloc(v * 4);
    uint32_t *indices = malloc(t * 3 * sizeof(uint32_t));
    double *times = malloc((size_t)repeat * sizeof *times);
    size_t evict_size = hot ? 1 : eviction_size();
    unsigned char *evict = calloc(evict_size, 1);
    int rc = positions && normals && colors && indices && times && evict ? 0 : -1;
    if (rc == 0 && hot) {
        sl_lod_mesh into = {0, 0, positions, normals, colors, indices};
        rc = sl_lod_generate_into(m, k, &into, vertices, triangles, NULL);
    }
    for (long i = 0; rc == 0 && i < repeat; i++) {
        sl_lod_mesh into = {0, 0, positions, normals, colors, indices};
        if (!hot)
            evict_caches(evict, evict_size);
        struct timespec t0;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        rc = sl_lod_generate_into(m, k, &into, vertices, triangles, NULL);
        times[i] = seconds_since(&t0);
    }
    if (rc == 0) {
        qsort(times, (size_t)repeat, sizeof *times, compare_doubles);
        *median = repeat % 2 ? times[repeat / 2]
                             : 0.5 * (times[repeat / 2 - 1] + times[repeat / 2]);
        *min = times[0];
    }
    free(positions);
    free(normals);
    free(colors);
    free(indices);
    free(times);
    free(evict);
    return rc;
}

/* The level cut along `coarser`'s edges (geometry/morph_refine.h) at weight r->weight:
 * its surface lies on `coarser` at weight 1, not only its vertices. */
static int write_weighted(const request *r, const sl_lod_mesh *mesh, const sl_lod_mesh *coarser,
                          const char *extras, double *moved, uint64_t *added, sl_error *err)
{
    sl_mesh to = sl_mesh_view(coarser->vertex_count, coarser->positions, NULL, NULL,
                              coarser->triangle_count, coarser->indices);
    sl_mesh level = sl_mesh_view(mesh->vertex_count, mesh->positions, NULL, NULL,
                                 mesh->triangle_count, mesh->indices);
    sl_morph_refined m;
    int rc = sl_morph_refine(&to, &level, r->morph_tears ? SL_MORPH_REFINE_TEAR : 0, &m, err);
    if (rc)
        return rc;
    size_t n = (size_t)(m.vertex_count ? m.vertex_count : 1);
    float *nrm = mesh->normals ? malloc(n * 12) : NULL;
    uint8_t *col = mesh->colors ? malloc(n * 4) : NULL;
    if ((mesh->normals && !nrm) || (mesh->colors && !col)) {
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, r->input, "out of memory");
    } else {
        if (nrm)
            sl_morph_refined_normals(&m, mesh->normals, nrm);
        if (col)
            sl_morph_refined_interpolate_rgba(&m, mesh->colors, col);
        sl_morph_blend(m.positions, m.targets, m.vertex_count, r->weight, m.positions);
        sl_lod_mesh at = {m.vertex_count, m.triangle_count, m.positions, nrm, col, m.triangles};
        rc = write_mesh(r->output, &at, extras, err);
    }
    *moved = m.max_move, *added = m.triangle_count - m.level_triangles;
    free(nrm), free(col);
    sl_morph_refined_release(&m);
    return rc;
}

/* --morph-to: writes `mesh` morphed towards the largest level within r->morph_to
 * triangles: a .glb with the morph target, another format at weight r->weight. Says what
 * it did in `note`. Returns 0, the usage exit code (printed), or -1 with `err` set. */
static int write_morph(const request *r, sl_lod_model *m, const sl_lod_mesh *mesh,
                       const char *extras, char *note, size_t note_size, sl_error *err)
{
    uint32_t k = sl_lod_expansions_for_triangles(m, r->morph_to);
    if (m->accumulation[k] >= mesh->triangle_count)
        return bad_request("--morph-to %llu: the level within it has %llu triangles, not fewer "
                           "than the level's %llu (morph towards a coarser level)",
                           (unsigned long long)r->morph_to,
                           (unsigned long long)m->accumulation[k],
                           (unsigned long long)mesh->triangle_count);
    sl_lod_mesh coarser;
    if (sl_lod_generate(m, k, &coarser, NULL)) {
        sl_error_set(err, SL_E_NOMEM, ENOMEM, r->input, "out of memory");
        return -1;
    }
    const char *dot = strrchr(r->output, '.');
    int rc = 0;
    double moved = 0;
    uint64_t added = 0;
    if (dot && !strcasecmp(dot, ".glb")) {
        sl_export_glb glb = sl_export_default_glb();
        glb.morph_to = &coarser;
        glb.morph_tears = r->morph_tears;
        rc = sl_export_write_mesh(r->output, mesh, extras, &glb, NULL, err);
        snprintf(note, note_size, ", morph target to expansions %u (%llu triangles)", k,
                 (unsigned long long)coarser.triangle_count);
    } else if (r->weight == 0) { /* the level itself, byte for byte */
        rc = write_mesh(r->output, mesh, extras, err);
        snprintf(note, note_size, ", at weight 0 of the morph to expansions %u: the level", k);
    } else {
        rc = write_weighted(r, mesh, &coarser, extras, &moved, &added, err);
        snprintf(note, note_size,
                 ", morphed to expansions %u (%llu triangles) at weight %g (moves up to %.6g; "
                 "%llu triangles added so the surface lies on it at weight 1)",
                 k, (unsigned long long)coarser.triangle_count, r->weight, moved,
                 (unsigned long long)added);
    }
    sl_lod_mesh_release(&coarser);
    return rc ? -1 : 0;
}

/* Turns the request into an expansion count, or prints why it cannot. */
static int choose_k(const request *r, const sl_lod_model *m, uint32_t *k)
{
    uint64_t finest = m->accumulation[m->expansion_count];
    switch (r->kind) {
    case 'k':
        if (r->count > m->expansion_count)
            return bad_request("--expansions must be an integer in [0, %u] (got %llu)",
                               m->expansion_count, (unsigned long long)r->count);
        *k = (uint32_t)r->count;
        return 0;
    case 't':
        /* A budget is a ceiling: above the finest level it gets the finest, as [export]
         * budgets do ("clamped"). It was refused (exit 64), and so was the README's own
         * `--triangles 50000` on the demo's bunny (issue 34 item 6). */
        if (r->count > finest)
            fprintf(stderr, "scanlod extract: --triangles %llu is above the finest level "
                            "(%llu triangles): extracting the finest\n",
                    (unsigned long long)r->count, (unsigned long long)finest);
        *k = sl_lod_expansions_for_triangles(m, r->count > finest ? finest : r->count);
        return 0;
    case 'p':
        *k = sl_lod_expansions_for_percent(m, r->value);
        return 0;
    case 'e':
        *k = sl_lod_expansions_for_error(m, r->value);
        return 0;
    default:
        return bad_request("--level applies to an octree (.slot), not a model");
    }
}

int sl_cmd_extract(int argc, char **argv)
{
    request r;
    if (argc >= 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        fputs(usage, stdout);
        return SL_EXIT_OK;
    }
    int parsed = parse(argc, argv, &r);
    if (parsed != 0) {
        if (parsed == -1) /* else a bad value, said in one line already */
            fputs(usage, stderr);
        return SL_EXIT_USAGE;
    }
    if (r.kind == 'l')
        return extract_level(&r);
    sl_error err;
    sl_error_init(&err);
    /* A model of format 5 is read only as far as the level needs (lod_prefix.h). */
    sl_lod_file *file = NULL;
    if (sl_lod_file_open(r.input, &file, &err))
        return fail(&err, 1);
    const sl_lod_model *levels = sl_lod_file_levels(file);
    uint32_t k = 0;
    int rc = choose_k(&r, levels, &k);
    sl_lod_model *cut = NULL;
    if (rc == 0 && sl_lod_file_reach(file, k, &cut, &err)) {
        sl_lod_file_close(file);
        return fail(&err, 1);
    }
    if (rc) {
        sl_lod_file_close(file);
        return rc;
    }
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    sl_lod_mesh mesh;
    uint64_t cracks = 0;
    if (sl_lod_generate(cut, k, &mesh, &cracks)) {
        sl_lod_file_close(file);
        sl_error_set(&err, SL_E_NOMEM, ENOMEM, r.input, "out of memory");
        return fail(&err, 0);
    }
    double generate_s = seconds_since(&t0);
    char extras[256];
    snprintf(extras, sizeof extras, "{\"expansions\":%u,\"of\":%u,\"max_error\":%.9g}", k,
             levels->expansion_count, (double)levels->error_after[k]);
    char warm[128] = "";
    double median = 0, min = 0;
    if (r.repeat && time_warm(cut, k, r.repeat, r.hot, &median, &min) != 0)
        sl_error_set(&err, SL_E_NOMEM, ENOMEM, r.input, "out of memory");
    else if (r.repeat)
        snprintf(warm, sizeof warm, ", then %ld more in median %.7f s (min %.7f s, %s)",
                 r.repeat, median, min, r.hot ? "back to back" : "caches flushed");
    char note[160] = "";
    int written = err.code == SL_OK ? 0 : -1;
    if (written == 0)
        written = r.morph ? write_morph(&r, cut, &mesh, extras, note, sizeof note, &err)
                          : write_mesh(r.output, &mesh, extras, &err);
    if (written == 0)
        printf("expansions %u of %u: %llu triangles, %llu vertices, max error %.6g, "
               "generated in %.7f s%s%s -> %s\n",
               k, levels->expansion_count, (unsigned long long)mesh.triangle_count,
               (unsigned long long)mesh.vertex_count, (double)levels->error_after[k], generate_s,
               warm, note, r.output);
    sl_lod_mesh_release(&mesh);
    sl_lod_file_close(file);
    if (written > 0)
        return written;
    return err.code ? fail(&err, 0) : SL_EXIT_OK;
}
