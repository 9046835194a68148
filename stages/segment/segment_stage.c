/* The segment stage ([lod] method = segment; segment.h): the range stage's welded mesh
 * (points.slpts) -> the export's ladder of levels (levels.sllev, the level list the
 * cluster method writes too) and the segmentation of equation 1 (segments.slsgm).
 * Formats: docs/formats.md.
 *
 * The ladder is the export's own ([export] lod_percents and budgets), read here so that
 * the export stage gets exactly the levels it asks for: a percent P is at most P % of
 * the input's triangles (100: the input itself), a budget name:N at most N triangles
 * (at or above the input's count: the input, "clamped"). Registered after the range
 * stage, on the segment method's path only (.methods).
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "stages/cluster/cluster.h"
#include "stages/export/export.h"
#include "stages/range/range.h"
#include "stages/segment/segment_internal.h"

#define SEGMENT_STAGE_VERSION 2u /* 2: levels.sllev, the level list, for levels.slseg */
#define MAX_LEVELS SL_EXPORT_MAX_LEVELS
#define MAP_MAGIC "SLSEGMAP"

static const sl_option segment_options[] = {
    {"segment", "delta_seg", SL_OPT_DOUBLE, "20", 0.01, 89, NULL,
     "Equation 1 (paper 3): the largest angle in degrees between two triangles of a "
     "segment."},
    {"segment", "target_segments", SL_OPT_INT, "0", 0, 4294967295.0, NULL,
     "Min-delta instead: the smallest delta_seg giving at most this many segments "
     "(0: Min-# with delta_seg)."},
    {"segment", "delta_b", SL_OPT_DOUBLE, "180", 0, 180, NULL,
     "Equation 2: a boundary vertex on exactly two segments may go when its angle is "
     "within delta_b degrees of straight (180: no angle test, the error bound alone "
     "decides; the paper uses 20 and 60)."},
    {"segment", "rule", SL_OPT_ENUM, "error", 0, 0, "error|near|paper",
     "Which interior vertices go (section 3.3, equation 8): error = greedy insertion, "
     "the vertices far from the rebuilt patch stay (levels of any size); near = those "
     "near the fitted plane go; paper = equation 8 as printed (far ones go). near and "
     "paper take no size: every level is the same single pass."},
    {"segment", "alpha", SL_OPT_DOUBLE, "-1.5", -1e6, 1e6, NULL,
     "Equation 8's control parameter (rules near and paper)."},
    {"segment", "max_normal_deviation", SL_OPT_DOUBLE, "90", 1, 180, NULL,
     "A new triangle whose normal is farther than this many degrees from the input's "
     "normals at its corners gets a vertex back, or its segment is kept as it was."},
    {"segment", "merge_ratio", SL_OPT_DOUBLE, "25", 0, 1e9, NULL,
     "Levels with a budget merge segments down to budget / merge_ratio (so that their "
     "corners fit); 0 = never merge."},
    {"segment", "merge_angle", SL_OPT_DOUBLE, "60", 1, 89, NULL,
     "Merging keeps every triangle of a segment within this many degrees of its mean "
     "normal (so that it still projects onto its plane one-to-one), and merges two parts "
     "only when their mean normals are that close (a crease sharper than this stays)."},
    {"segment", "search_samples", SL_OPT_INT, "50000", 0, 100000000, NULL,
     "Area samples per surface of the RMS distance the budget search minimises; 0 = "
     "estimate it from the removed vertices (faster, less faithful)."},
    SL_OPTION_END,
};

static const char *const segment_sections[] = {"segment", "export", NULL};

/* --- the ladder ------------------------------------------------------------------------- */

typedef struct stage_level {
    char name[32];
    int by_percent;
    double value;        /* percent, or budget */
    uint64_t triangles;  /* asked for */
} stage_level;

/* What a level was asked to be. */
typedef struct stage_level_info {
    char name[32];   /* the file name stem: "lod20", "thumb" */
    int by_percent;  /* 1: value is a percent; 0: a triangle budget */
    double value;
    uint64_t budget; /* the triangles it may have */
    int clamped;     /* the budget was at or above the input's size: the input itself */
    int over_budget; /* the method could not get within the budget (its corners alone
                        exceed it): the smallest level it reaches */
} stage_level_info;

typedef struct stage_config {
    sl_segment_config seg;
    uint32_t level_count;
    stage_level levels[MAX_LEVELS];
} stage_config;

static int add_level(stage_config *c, const char *word, int by_percent, sl_error *err)
{
    if (c->level_count == MAX_LEVELS)
        return sl_error_set(err, SL_E_CONFIG, 0, "[export]", "more than %d levels", MAX_LEVELS);
    stage_level *lv = &c->levels[c->level_count];
    memset(lv, 0, sizeof *lv);
    char *end;
    lv->by_percent = by_percent;
    if (by_percent) {
        lv->value = strtod(word, &end);
        if (*end || !(lv->value >= 0 && lv->value <= 100))
            return sl_error_set(err, SL_E_CONFIG, 0, "[export] lod_percents",
                                "'%s' is not a percent in [0, 100]", word);
        snprintf(lv->name, sizeof lv->name, "lod%g", lv->value);
    } else {
        const char *colon = strchr(word, ':');
        if (!colon || colon == word || (size_t)(colon - word) >= sizeof lv->name)
            return sl_error_set(err, SL_E_CONFIG, 0, "[export] budgets",
                                "'%s' is not name:triangles", word);
        snprintf(lv->name, sizeof lv->name, "%.*s", (int)(colon - word), word);
        errno = 0;
        double v = strtod(colon + 1, &end);
        if (errno || *end || !(v >= 1) || v != floor(v) || v > 1e15)
            return sl_error_set(err, SL_E_CONFIG, 0, "[export] budgets",
                                "'%s': the budget must be a whole number >= 1", word);
        lv->value = v;
    }
    c->level_count++;
    return SL_OK;
}

static int parse_list(stage_config *c, const char *text, int by_percent, sl_error *err)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", text);
    for (char *save = NULL, *w = strtok_r(buf, ",", &save); w; w = strtok_r(NULL, ",", &save)) {
        int rc = add_level(c, w, by_percent, err);
        if (rc)
            return rc;
    }
    return SL_OK;
}

static int segment_configure(const sl_config *cfg, void **out, sl_error *err)
{
    stage_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    c->seg = sl_segment_default_config();
    c->seg.delta_seg = sl_config_double(cfg, "segment", "delta_seg");
    c->seg.target_segments = (uint32_t)sl_config_int(cfg, "segment", "target_segments");
    c->seg.delta_b = sl_config_double(cfg, "segment", "delta_b");
    const char *rule = sl_config_string(cfg, "segment", "rule");
    c->seg.rule = !strcmp(rule, "near") ? SL_SEGMENT_RULE_NEAR
                  : !strcmp(rule, "paper") ? SL_SEGMENT_RULE_PAPER : SL_SEGMENT_RULE_ERROR;
    c->seg.alpha = sl_config_double(cfg, "segment", "alpha");
    c->seg.max_normal_deviation = sl_config_double(cfg, "segment", "max_normal_deviation");
    c->seg.merge_ratio = sl_config_double(cfg, "segment", "merge_ratio");
    c->seg.merge_angle = sl_config_double(cfg, "segment", "merge_angle");
    c->seg.search_samples = (uint64_t)sl_config_int(cfg, "segment", "search_samples");
    int rc = parse_list(c, sl_config_string(cfg, "export", "lod_percents"), 1, err);
    if (!rc)
        rc = parse_list(c, sl_config_string(cfg, "export", "budgets"), 0, err);
    if (!rc && sl_segment_check_config(&c->seg, err))
        rc = sl_error_set(err, SL_E_CONFIG, 0, "[segment]", "%s", err->message);
    if (rc) {
        free(c);
        return rc;
    }
    *out = c;
    return SL_OK;
}

static void segment_release_config(void *c)
{
    free(c);
}

/* --- files ------------------------------------------------------------------------------ */

/* levels.sllev, the level list the export reads (stages/cluster/cluster.h, the same file
 * as the cluster method's): per level the points of points.slpts it uses, in their order
 * (positions copied, `source` naming each point for the export's normals and colours),
 * and its triangles remapped to them. The segment method proves no Hausdorff bound: its
 * levels carry bound 0 and the export reports their measured distances only. */
static int write_list(const char *path, const sl_pointset *ps, const stage_level_info *info,
                      const sl_segment_level *levels, uint32_t level_count, sl_error *err)
{
    sl_cluster_list list;
    memset(&list, 0, sizeof list);
    list.input_triangles = ps->triangle_count;
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += ((double)ps->bbox_max[k] - ps->bbox_min[k]) * ((double)ps->bbox_max[k] - ps->bbox_min[k]);
    list.diagonal = sqrt(d2);
    list.count = level_count;
    list.meshes = calloc(level_count ? level_count : 1, sizeof *list.meshes);
    uint32_t *map = malloc((ps->count ? ps->count : 1) * sizeof *map);
    int rc = list.meshes && map ? SL_OK : sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    for (uint32_t i = 0; i < level_count && !rc; i++) {
        sl_cluster_list_mesh *m = &list.meshes[i];
        const sl_segment_level *lv = &levels[i];
        memcpy(m->name, info[i].name, sizeof m->name);
        m->by_percent = info[i].by_percent;
        m->percent = info[i].by_percent ? info[i].value : 0;
        m->budget = info[i].budget;
        m->reached = !info[i].over_budget;
        m->clamped = info[i].clamped;
        memset(map, 0xff, (ps->count ? ps->count : 1) * sizeof *map);
        for (uint64_t k = 0; k < 3 * lv->triangle_count; k++)
            map[lv->triangles[k]] = 0;
        for (uint64_t p = 0; p < ps->count; p++)
            if (map[p] != UINT32_MAX)
                map[p] = (uint32_t)m->vertex_count++;
        size_t nv = m->vertex_count ? (size_t)m->vertex_count : 1;
        m->positions = malloc(12 * nv);
        m->source = malloc(4 * nv);
        m->triangle_count = lv->triangle_count;
        m->triangles = malloc(12 * (lv->triangle_count ? lv->triangle_count : 1));
        if (!m->positions || !m->source || !m->triangles) {
            rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "level %s", m->name);
            break;
        }
        for (uint64_t p = 0; p < ps->count; p++)
            if (map[p] != UINT32_MAX) {
                memcpy(m->positions + 3 * (uint64_t)map[p], ps->positions + 3 * p, 12);
                m->source[map[p]] = (uint32_t)p;
            }
        for (uint64_t k = 0; k < 3 * lv->triangle_count; k++)
            m->triangles[k] = map[lv->triangles[k]];
    }
    if (!rc)
        rc = sl_cluster_list_write(path, &list, err);
    free(map);
    sl_cluster_list_release(&list);
    return rc;
}

/* segments.slsgm: the segment of each triangle, then per segment its unit area-weighted
 * normal and area. */
static int write_map(const char *path, const sl_segment_model *m, sl_error *err)
{
    uint32_t ns = m->seg.segment_count;
    unsigned char header[16];
    sl_put_u64(header, m->triangle_count);
    sl_put_u32(header + 8, ns);
    sl_put_u32(header + 12, 0);
    float *planes = calloc(4 * (size_t)(ns ? ns : 1), sizeof *planes);
    if (!planes)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *c = m->triangles + 3 * (uint64_t)t;
        double u[3], w[3];
        seg_sub(m->positions + 3 * (uint64_t)c[1], m->positions + 3 * (uint64_t)c[0], u);
        seg_sub(m->positions + 3 * (uint64_t)c[2], m->positions + 3 * (uint64_t)c[0], w);
        double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        planes[4 * (size_t)m->seg.segment[t] + 3] +=
            (float)(0.5 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]));
    }
    for (uint32_t k = 0; k < ns; k++)
        for (int j = 0; j < 3; j++)
            planes[4 * (size_t)k + j] = (float)m->frame[k].normal[j];
    sl_artifact_part parts[] = {
        {header, sizeof header},
        {m->seg.segment, 4 * (size_t)m->triangle_count},
        {planes, 16 * (size_t)ns},
    };
    int rc = sl_artifact_write(path, MAP_MAGIC, SL_SEGMENT_MAP_FORMAT_VERSION,
                               SEGMENT_STAGE_VERSION, parts, 3, err);
    free(planes);
    return rc;
}

/* --- run -------------------------------------------------------------------------------- */

static void report_level(sl_json *j, const stage_level_info *info, const sl_segment_level *lv)
{
    const sl_segment_stats *s = &lv->stats;
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "name", info->name);
    if (info->by_percent)
        sl_json_double(j, "lod_percent", info->value);
    else
        sl_json_u64(j, "budget", (uint64_t)info->value);
    sl_json_bool(j, "clamped", info->clamped);
    sl_json_bool(j, "over_budget", info->over_budget);
    sl_json_u64(j, "triangles", lv->triangle_count);
    sl_json_u64(j, "segments", s->segments);
    sl_json_u64(j, "removed_vertices", s->removed_vertices);
    sl_json_u64(j, "removed_boundary", s->removed_boundary);
    sl_json_u64(j, "removed_interior", s->removed_interior);
    sl_json_u64(j, "patches_kept", s->patches_kept);
    sl_json_double(j, "max_error", s->max_error);
    sl_json_double(j, "estimated_rms", s->estimate);
    sl_json_i64(j, "euler_characteristic", s->euler_characteristic);
    sl_json_bool(j, "watertight", s->watertight);
    sl_json_object_end(j);
}

static int make_levels(const stage_config *c, sl_segment_model *model, uint64_t input_triangles,
                       sl_segment_level *levels, stage_level_info *info,
                       sl_progress *progress, sl_error *err)
{
    for (uint32_t i = 0; i < c->level_count; i++) {
        const stage_level *want = &c->levels[i];
        memset(&info[i], 0, sizeof info[i]);
        memcpy(info[i].name, want->name, sizeof info[i].name);
        info[i].by_percent = want->by_percent;
        info[i].value = want->value;
        uint64_t budget = want->by_percent
                              ? (uint64_t)floor(want->value / 100.0 * (double)input_triangles)
                              : (uint64_t)want->value;
        info[i].budget = budget;
        info[i].clamped = budget >= input_triangles;
        sl_segment_target target = {budget ? budget : 1, 0, 0};
        if (c->seg.rule != SL_SEGMENT_RULE_ERROR) /* no size: one pass */
            target.triangles = 0;
        int rc = sl_segment_model_level(model, &c->seg, &target, &levels[i], progress, err);
        if (rc)
            return rc;
        info[i].over_budget = levels[i].stats.over_budget || levels[i].triangle_count > budget;
        if (sl_progress_step(progress, "segment", 0.2 + 0.7 * (i + 1) / c->level_count))
            return sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "interrupted");
    }
    return SL_OK;
}

static int segment_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const stage_config *c = config;
    const char *range_dir = sl_stage_dir(io, "range");
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s", range_dir ? range_dir : io->in_dir, SL_POINTSET_FILE);
    sl_pointset ps;
    int rc = sl_pointset_read(path, &ps, err);
    if (rc)
        return rc;
    if (ps.triangle_count == 0) {
        sl_pointset_release(&ps);
        return sl_error_set(err, SL_E_UNSUPPORTED, 0, io->source_path,
                            "a point cloud (no faces): the segment method needs a triangle mesh");
    }
    sl_segment_input in = {ps.count, ps.positions, ps.triangle_count, ps.triangles};
    sl_segment_model *model = NULL;
    sl_segment_level levels[MAX_LEVELS];
    stage_level_info info[MAX_LEVELS];
    memset(levels, 0, sizeof levels);
    rc = sl_segment_model_build(&c->seg, &in, &model, io->progress, err);
    if (!rc)
        rc = make_levels(c, model, ps.triangle_count, levels, info, io->progress, err);
    if (!rc) {
        snprintf(path, sizeof path, "%s/%s", io->out_dir, SL_SEGMENT_MAP_FILE);
        rc = write_map(path, model, err);
    }
    if (!rc) {
        snprintf(path, sizeof path, "%s/%s", io->out_dir, SL_CLUSTER_LEVELS_FILE);
        rc = write_list(path, &ps, info, levels, c->level_count, err);
    }
    if (!rc) {
        sl_json *j = io->report;
        sl_json_u64(j, "input_triangles", ps.triangle_count);
        sl_json_u64(j, "input_vertices", ps.count);
        sl_json_u64(j, "segments", model->seg.segment_count);
        sl_json_double(j, "delta_seg", model->seg.delta_seg);
        sl_json_u64(j, "nonmanifold_edges_kept", model->input_nonmanifold_edges);
        sl_json_array_begin(j, "levels");
        for (uint32_t i = 0; i < c->level_count; i++)
            report_level(j, &info[i], &levels[i]);
        sl_json_array_end(j);
    }
    if (rc && sl_error_class_of(rc) == SL_CLASS_BADINPUT && !err->file[0])
        snprintf(err->file, sizeof err->file, "%s", io->source_path);
    for (uint32_t i = 0; i < c->level_count; i++)
        sl_segment_level_release(&levels[i]);
    sl_segment_model_free(model);
    sl_pointset_release(&ps);
    return rc;
}

const sl_stage sl_segment_stage = {
    .name = "segment",
    .methods = SL_METHOD_SEGMENT,
    .description = "welded mesh -> levels by segmentation, trimming, plane fit and "
                   "retriangulation (paper 3)",
    .version = SEGMENT_STAGE_VERSION,
    .options = segment_options,
    .sections = segment_sections,
    .configure = segment_configure,
    .release_config = segment_release_config,
    .run = segment_run,
};
