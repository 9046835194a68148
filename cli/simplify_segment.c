/* `scanlod simplify --method segment` (paper 3; docs/segmentation.md): the segment
 * method's options and its run (cli/simplify.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/simplify.h"
#include "stages/segment/segment.h"

static sl_segment_config segment_opts;

static void segment_reset(void)
{
    segment_opts = sl_segment_default_config();
}

static int segment_parse(int argc, char **argv, int *i)
{
    sl_segment_config *c = &segment_opts;
    const char *arg = argv[*i];
    double *dst = !strcmp(arg, "--delta-seg") ? &c->delta_seg
                  : !strcmp(arg, "--delta-b") ? &c->delta_b
                  : !strcmp(arg, "--alpha") ? &c->alpha
                  : !strcmp(arg, "--max-deviation") ? &c->max_normal_deviation
                  : !strcmp(arg, "--merge-ratio") ? &c->merge_ratio
                  : !strcmp(arg, "--merge-angle") ? &c->merge_angle
                                                    : NULL;
    if (dst) {
        if (*i + 1 >= argc || sl_simplify_parse_double(argv[++*i], dst)) {
            fprintf(stderr, "scanlod simplify: %s needs a number\n", arg);
            return -1;
        }
        return 1;
    }
    if (!strcmp(arg, "--search-samples")) {
        double v;
        if (*i + 1 >= argc || sl_simplify_parse_double(argv[++*i], &v) || v < 0 || v > 1e9 || v != floor(v)) {
            fprintf(stderr, "scanlod simplify: --search-samples needs a whole number >= 0\n");
            return -1;
        }
        c->search_samples = (uint64_t)v;
        return 1;
    }
    if (!strcmp(arg, "--segments")) {
        double v;
        if (*i + 1 >= argc || sl_simplify_parse_double(argv[++*i], &v) || v < 1 || v > 4e9 || v != floor(v)) {
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

static int segment_check(const simplify_job *job)
{
    (void)job;
    sl_error err;
    sl_error_init(&err);
    if (sl_segment_check_config(&segment_opts, &err)) {
        fprintf(stderr, "scanlod simplify: %s\n", err.message);
        return -1;
    }
    return 0;
}

/* What the segment method keeps: the level's triangles and the segment map. */
typedef struct segment_state {
    uint32_t *triangles;
    uint32_t *segment_of_input;
} segment_state;

static int segment_run(const simplify_job *job, simplify_output *out,
                       sl_progress *progress, sl_error *err)
{
    const sl_segment_config *cfg = &segment_opts;
    segment_state *st = calloc(1, sizeof *st);
    if (!st)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory");
    out->state = st;
    sl_segment_input in = {job->mesh->count, job->mesh->positions, job->mesh->triangle_count,
                           job->mesh->triangles};
    sl_segment_target target = {job->triangles, job->ratio, job->max_error};
    sl_segment_model *model = NULL;
    double t0 = sl_simplify_seconds_now();
    int rc = sl_segment_model_build(cfg, &in, &model, progress, err);
    double t1 = sl_simplify_seconds_now();
    sl_segment_level level;
    memset(&level, 0, sizeof level);
    if (!rc)
        rc = sl_segment_model_level(model, cfg, &target, &level, progress, err);
    double t2 = sl_simplify_seconds_now();
    if (!rc && job->strict && level.stats.nonmanifold_edges_kept)
        rc = sl_error_set(err, SL_E_BADINPUT, 0, job->input,
                          "%llu non-manifold edges (in three or more triangles); --strict "
                          "refuses them", (unsigned long long)level.stats.nonmanifold_edges_kept);
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
        st->segment_of_input = malloc((in.triangle_count ? in.triangle_count : 1) * sizeof *map);
        if (st->segment_of_input) {
            memcpy(st->segment_of_input, map, in.triangle_count * sizeof *map);
            out->segment_of_input = st->segment_of_input;
            out->segment_count = count;
        }
        out->triangle_count = level.triangle_count;
        out->triangles = st->triangles = level.triangles;
        level.triangles = NULL;
        segment_figures(&out->figures, &level.stats);
        sl_json_double(&out->figures, "segmentation_seconds", t1 - t0);
        sl_json_double(&out->figures, "level_seconds", t2 - t1);
    }
    sl_segment_level_release(&level);
    sl_segment_model_free(model);
    return rc;
}

static void segment_release(simplify_output *out)
{
    segment_state *s = out->state;
    if (s) {
        free(s->triangles);
        free(s->segment_of_input);
    }
    free(s);
}

const simplify_method sl_simplify_segment = {
    "segment",
    "  segment (paper 3; docs/segmentation.md): --max-error bounds how far a removed vertex\n"
    "  lies from the new surface (no search; default 0.001); --strict refuses non-manifold edges\n"
    "    --delta-seg D      largest angle between two triangles of a segment, degrees (20)\n"
     "    --segments K       instead: the smallest delta-seg giving at most K segments\n"
     "    --delta-b D        boundary vertices within D degrees of straight may go (180: any)\n"
     "    --rule R           interior vertices: error (far from the new patch stay; the\n"
     "                       default), near (near the plane go), paper (equation 8 as printed)\n"
     "    --alpha A          equation 8's control parameter, rules near and paper (-1.5)\n"
     "    --max-deviation D  a new triangle's normal within D degrees of the input's (90)\n"
     "    --merge-ratio R    budgets: merge segments down to budget / R (25; 0: never)\n"
     "    --merge-angle A    merged segments keep their triangles within A degrees of\n"
     "                       their mean normal, parts only merge that close (60)\n"
     "    --search-samples N budgets: samples of the RMS the search minimises (50000; 0:\n"
     "                       estimate it from the removed vertices, faster)\n",
    segment_reset, segment_parse, segment_check, segment_run, segment_release,
};
