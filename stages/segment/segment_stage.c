/* The segment stage ([lod] method = segment; segment.h): the range stage's welded mesh
 * (points.slpts) -> a level per rung of the ladder (levels/level.h, the level list every
 * method writes) and the segmentation of equation 1 (segments.slsgm). Formats:
 * docs/formats.md.
 *
 * The ladder is every method's ([levels], levels/ladder.h): a share P % is at most P % of
 * the input's triangles, a count N at most N triangles (at or above the input's count:
 * the input, "clamped"); expansions rungs belong to the octree and are not made here.
 * The refine stage takes a level that stopped above its count the rest of the way.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "levels/level.h"
#include "stages/range/range.h"
#include "stages/segment/segment_internal.h"

/* 3: the level list of levels/level.h, the ladder of [levels]. */
#define SEGMENT_STAGE_VERSION 3u
#define MAP_MAGIC "SLSEGMAP"

static const char *const segment_sections[] = {"segment", SL_LADDER_SECTION, NULL};
static const sl_option *const segment_shared[] = {sl_ladder_options, NULL};

/* --- files ------------------------------------------------------------------------------ */

/* The level list: per level the points of points.slpts it uses, in their order (with
 * their colours and, as `source`, their point index), and its triangles renumbered. The
 * segment method proves no Hausdorff bound: its levels carry bound 0. */
static int write_levels(const char *dir, const sl_pointset *ps, sl_level *records,
                        const sl_segment_level *levels, uint32_t count, sl_error *err)
{
    sl_level_list list = {ps->triangle_count, ps->count, 0, 0, 0, count, records};
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += ((double)ps->bbox_max[k] - ps->bbox_min[k]) * ((double)ps->bbox_max[k] - ps->bbox_min[k]);
    list.diagonal = sqrt(d2);
    int rc = SL_OK;
    for (uint32_t i = 0; i < count && !rc; i++) {
        sl_level *lv = &records[i];
        rc = sl_level_from_points(lv, ps->count, ps->positions, ps->colors, NULL,
                                  levels[i].triangle_count, levels[i].triangles, err);
        if (!rc)
            rc = sl_level_write_mesh(dir, lv, err);
        sl_level_release_mesh(lv);
    }
    if (!rc)
        rc = sl_level_list_write(dir, &list, err);
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

static void report_level(sl_json *j, const sl_level *info, const sl_segment_level *lv)
{
    const sl_segment_stats *s = &lv->stats;
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "name", info->name);
    sl_json_u64(j, "budget", info->budget);
    sl_json_bool(j, "clamped", (info->flags & SL_LEVEL_CLAMPED) != 0);
    sl_json_bool(j, "over_budget", !(info->flags & SL_LEVEL_REACHED));
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

/* A level per rung that asks for a count (expansions rungs are the octree's), its record
 * in info[*count]. */
static int make_levels(const sl_segment_stage_config *c, sl_segment_model *model,
                       uint64_t input_triangles, sl_segment_level *levels, sl_level *info,
                       uint32_t *count, sl_progress *progress, sl_error *err)
{
    *count = 0;
    for (int i = 0; i < c->ladder.count; i++) {
        const sl_rung *r = &c->ladder.rungs[i];
        if (r->kind == SL_RUNG_EXPANSIONS)
            continue;
        sl_level *lv = &info[*count];
        memset(lv, 0, sizeof *lv);
        memcpy(lv->name, r->name, sizeof lv->name);
        snprintf(lv->method, sizeof lv->method, "segment");
        lv->rung = *r;
        /* Built at the ladder's oversample times the count: the refine stage collapses it
         * the rest of the way (docs/levels.md). */
        uint64_t budget = sl_rung_build_triangles(&c->ladder, r, input_triangles);
        lv->budget = sl_rung_triangles(r, input_triangles);
        sl_segment_target target = {budget, 0, 0};
        if (c->seg.rule != SL_SEGMENT_RULE_ERROR) /* no size: one pass */
            target.triangles = 0;
        int rc = sl_segment_model_level(model, &c->seg, &target, &levels[*count], progress, err);
        if (rc)
            return rc;
        const sl_segment_level *made = &levels[(*count)++];
        lv->flags = (lv->budget >= input_triangles ? SL_LEVEL_CLAMPED : 0) |
                    (made->stats.over_budget || made->triangle_count > budget ? 0 : SL_LEVEL_REACHED);
        lv->triangle_count = made->triangle_count;
        if (sl_progress_step(progress, "segment", 0.2 + 0.7 * (i + 1) / c->ladder.count))
            return sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "interrupted");
    }
    return SL_OK;
}

static int segment_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const sl_segment_stage_config *c = config;
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
    sl_segment_level levels[SL_LADDER_MAX];
    sl_level info[SL_LADDER_MAX];
    uint32_t count = 0;
    memset(levels, 0, sizeof levels);
    rc = sl_segment_model_build(&c->seg, &in, &model, io->progress, err);
    if (!rc)
        rc = make_levels(c, model, ps.triangle_count, levels, info, &count, io->progress, err);
    if (!rc) {
        snprintf(path, sizeof path, "%s/%s", io->out_dir, SL_SEGMENT_MAP_FILE);
        rc = write_map(path, model, err);
    }
    if (!rc)
        rc = write_levels(io->out_dir, &ps, info, levels, count, err);
    if (!rc) {
        sl_json *j = io->report;
        sl_json_u64(j, "input_triangles", ps.triangle_count);
        sl_json_u64(j, "input_vertices", ps.count);
        sl_json_u64(j, "segments", model->seg.segment_count);
        sl_json_double(j, "delta_seg", model->seg.delta_seg);
        sl_json_u64(j, "nonmanifold_edges_kept", model->input_nonmanifold_edges);
        sl_json_array_begin(j, "levels");
        for (uint32_t i = 0; i < count; i++)
            report_level(j, &info[i], &levels[i]);
        sl_json_array_end(j);
    }
    if (rc && sl_error_class_of(rc) == SL_CLASS_BADINPUT && !err->file[0])
        snprintf(err->file, sizeof err->file, "%s", io->source_path);
    for (uint32_t i = 0; i < count; i++)
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
    .options = sl_segment_options,
    .shared_options = segment_shared,
    .sections = segment_sections,
    .configure = sl_segment_configure,
    .release_config = free,
    .run = segment_run,
};
