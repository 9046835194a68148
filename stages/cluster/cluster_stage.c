/* cluster stage entry (cluster.h): the range stage's welded mesh -> a level per rung of
 * the ladder ([levels]), each from the next finer one (the paper's hierarchy: a pass takes
 * the previous pass's output), with their bounds, as a level list (levels/level.h) the
 * refine stage takes on.
 *
 * A rung asking for a share P % is a budget of floor(P % of the input's triangles); the
 * levels are built from the largest budget down, each from the last one that needed work,
 * so its bound is that level's plus its own passes'. A budget the finer level already
 * meets is that level, unchanged. Expansions rungs belong to the octree: not made here. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "levels/level.h"
#include "stages/cluster/cluster.h"
#include "stages/range/range.h"

/* 2: the level list of levels/level.h, the ladder of [levels]. */
#define CLUSTER_STAGE_VERSION 2u

static const sl_option cluster_options[] = {
    {"cluster", "passes", SL_OPT_INT, "1", 1, SL_CLUSTER_MAX_PASSES, NULL,
     "Clustering passes per level (paper 2): each clusters, straightens and triangulates "
     "the previous one's output; their bounds add up. Tolerances double from pass to pass."},
    {"cluster", "intermediates", SL_OPT_INT, "0", 0, SL_CLUSTER_MAX_INTERMEDIATES, NULL,
     "Intermediate models (paper 2, section 4) written between each level and the next "
     "finer one: border vertices moved part of the way to their straightened segments, "
     "straightened and triangulated again. 0 = none."},
    {"cluster", "max_angle", SL_OPT_DOUBLE, "60", 1, SL_CLUSTER_MAX_ANGLE, NULL,
     "Degrees: a face joins a cluster only when its normal is within this angle of the "
     "cluster's direction (its seed face's normal, then the mean normal of what grew)."},
    {"cluster", "slab_share", SL_OPT_DOUBLE, "0.7", 0.01, 1, NULL,
     "Share of a pass's tolerance eps that a cluster's thickness (the slab of its vertices "
     "across its direction) may take; its borders are straightened within "
     "sqrt(eps^2 - thickness^2), so that the pass's bound is at most eps."},
    {"cluster", "search_steps", SL_OPT_INT, "16", 1, 64, NULL,
     "Bisection steps of the bound when a level is asked as a triangle budget."},
    SL_OPTION_END,
};

/* The stage's resolved config: the method's section, and the ladder it builds. */
typedef struct stage_config {
    sl_cluster_config method; /* first: sl_cluster_default_config copies just this */
    sl_ladder ladder;
} stage_config;

static int cluster_configure(const sl_config *cfg, void **out, sl_error *err)
{
    stage_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_nomem(err, NULL, "out of memory");
    c->method.passes = (uint32_t)sl_config_int(cfg, "cluster", "passes");
    c->method.intermediates = (uint32_t)sl_config_int(cfg, "cluster", "intermediates");
    c->method.max_angle = sl_config_double(cfg, "cluster", "max_angle");
    c->method.slab_share = sl_config_double(cfg, "cluster", "slab_share");
    c->method.search_steps = (uint32_t)sl_config_int(cfg, "cluster", "search_steps");
    int rc = sl_ladder_read(cfg, &c->ladder, err);
    if (rc == 0)
        *out = c;
    else
        free(c);
    return rc;
}

sl_cluster_config sl_cluster_default_config(void)
{
    sl_cluster_config c; /* the stage config's first member */
    sl_stage_default_config(&sl_cluster_stage, &c, sizeof c);
    return c;
}

/* An intermediate model as a level (its positions moved in; colours from the points). */
static int take_intermediate(sl_cluster_intermediate *im, const sl_pointset *ps, const char *level,
                             const char *from, uint32_t j, double diagonal, sl_level *m,
                             sl_error *err)
{
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%.22s.morph%u", level, j % 1000u);
    memcpy(m->from, from, sizeof m->from);
    snprintf(m->method, sizeof m->method, "cluster");
    m->flags = SL_LEVEL_INTERMEDIATE | SL_LEVEL_REACHED | SL_LEVEL_PROVEN;
    m->bound = im->bound;
    m->bound_fraction = im->bound / diagonal;
    m->vertex_count = im->vertex_count;
    m->triangle_count = im->triangle_count;
    m->positions = im->positions;
    m->source = im->source;
    m->triangles = im->triangles;
    memset(im, 0, sizeof *im);
    if (ps->colors) {
        m->colors = malloc(4 * (m->vertex_count ? m->vertex_count : 1));
        if (!m->colors)
            return sl_error_nomem(err, NULL, "intermediate %s", m->name);
        for (uint64_t v = 0; v < m->vertex_count; v++)
            memcpy(m->colors + 4 * v, ps->colors + 4 * (uint64_t)m->source[v], 4);
    }
    return 0;
}

typedef struct ladder_step {
    uint32_t level;   /* index into the ladder */
    uint64_t budget;  /* the triangles the level is built with: its count times the
                         ladder's oversample (the refine stage collapses the rest) */
    uint64_t count;   /* the rung's own count */
} ladder_step;

static int step_cmp(const void *a, const void *b)
{
    const ladder_step *x = a, *y = b;
    if (x->budget != y->budget)
        return x->budget > y->budget ? -1 : 1;
    return x->level < y->level ? -1 : x->level > y->level;
}

/* The records the stage writes: a level per rung (ladder order; `made` marks those it
 * made) and each level's intermediate models. */
typedef struct stage_records {
    sl_level levels[SL_LADDER_MAX];
    int made[SL_LADDER_MAX];
    sl_level *morphs;          /* SL_LADDER_MAX * SL_CLUSTER_MAX_INTERMEDIATES */
    uint32_t morph_count[SL_LADDER_MAX];
} stage_records;

/* One level's record and mesh file (the points its triangles use), and its intermediate
 * models' (moved out of `level`). */
static int write_level(const stage_config *c, const sl_pointset *ps, const ladder_step *step,
                       const char *from, uint64_t triangle_count, const uint32_t *triangles,
                       double bound, int reached, sl_cluster_level *level, double diagonal,
                       stage_records *out, const sl_stage_io *io, sl_error *err)
{
    const sl_rung *r = &c->ladder.rungs[step->level];
    sl_level *m = &out->levels[step->level];
    memset(m, 0, sizeof *m);
    memcpy(m->name, r->name, sizeof m->name);
    memcpy(m->from, from, sizeof m->from); /* (a level equal to it: its copy) */
    snprintf(m->method, sizeof m->method, "cluster");
    m->rung = *r;
    m->budget = step->count;
    m->flags = SL_LEVEL_PROVEN | (reached ? SL_LEVEL_REACHED : 0) |
               (step->count >= ps->triangle_count ? SL_LEVEL_CLAMPED : 0);
    m->bound = bound;
    m->bound_fraction = bound / diagonal;
    int rc = sl_level_from_points(m, ps->count, ps->positions, ps->colors, NULL, triangle_count,
                                  triangles, err);
    if (rc == 0)
        rc = sl_level_write_mesh(io->out_dir, m, err);
    sl_level_release_mesh(m);
    out->made[step->level] = rc == 0;
    for (uint32_t j = 0; rc == 0 && level && j < level->intermediate_count; j++) {
        sl_level *im = &out->morphs[(size_t)step->level * SL_CLUSTER_MAX_INTERMEDIATES + j];
        rc = take_intermediate(&level->intermediates[j], ps, r->name, from, j + 1, diagonal,
                               im, err);
        if (rc == 0)
            rc = sl_level_write_mesh(io->out_dir, im, err);
        sl_level_release_mesh(im);
        out->morph_count[step->level] = j + 1;
    }
    return rc;
}

/* The ladder's levels, finest first, each from the one before. */
static int build_levels(const stage_config *c, const sl_pointset *ps, double diagonal,
                        stage_records *out, const sl_stage_io *io, sl_error *err)
{
    ladder_step steps[SL_LADDER_MAX];
    int count = 0;
    uint64_t n = ps->triangle_count;
    for (int i = 0; i < c->ladder.count; i++)
        if (c->ladder.rungs[i].kind != SL_RUNG_EXPANSIONS) {
            const sl_rung *r = &c->ladder.rungs[i];
            steps[count++] = (ladder_step){(uint32_t)i, sl_rung_build_triangles(&c->ladder, r, n),
                                           sl_rung_triangles(r, n)};
        }
    qsort(steps, (size_t)count, sizeof *steps, step_cmp);
    const uint32_t *prev = ps->triangles;
    char prev_name[SL_LEVEL_NAME_SIZE] = "";
    uint64_t prev_count = n;
    double prev_bound = 0.0;
    sl_cluster_level keep; /* the previous level, whose triangles `prev` points into */
    memset(&keep, 0, sizeof keep);
    int rc = 0;
    for (int s = 0; s < count && rc == 0; s++) {
        if ((rc = sl_stage_step(io, "cluster", (double)s / count, err)))
            break;
        sl_cluster_level level;
        memset(&level, 0, sizeof level);
        if (steps[s].budget < prev_count) {
            sl_cluster_input in = {ps->count, ps->positions, prev_count, prev, prev_bound,
                                   diagonal, 0};
            sl_cluster_target target = {0.0, steps[s].budget, c->method.intermediates};
            rc = sl_cluster_simplify(&c->method, &in, &target, &level, io->progress, err);
            if (rc)
                break;
        }
        int same = level.triangles == NULL; /* the budget holds the finer level already */
        rc = write_level(c, ps, &steps[s], prev_name, same ? prev_count : level.triangle_count,
                         same ? prev : level.triangles, same ? prev_bound : level.bound,
                         same || level.reached, &level, diagonal, out, io, err);
        if (!same && rc == 0) {
            memcpy(prev_name, c->ladder.rungs[steps[s].level].name, sizeof prev_name);
            sl_cluster_level_release(&keep);
            keep = level;
            prev = keep.triangles;
            prev_count = keep.triangle_count;
            prev_bound = keep.bound;
        } else {
            sl_cluster_level_release(&level);
        }
    }
    sl_cluster_level_release(&keep);
    return rc;
}

static void report(const stage_config *c, const sl_level_list *list, sl_json *r)
{
    sl_json_u64(r, "passes", c->method.passes);
    sl_json_u64(r, "intermediates", c->method.intermediates);
    sl_json_double(r, "max_angle", c->method.max_angle);
    sl_json_double(r, "slab_share", c->method.slab_share);
    sl_json_u64(r, "input_triangles", list->input_triangles);
    sl_json_double(r, "diagonal", list->diagonal);
    sl_json_array_begin(r, "levels");
    for (uint32_t i = 0; i < list->count; i++) {
        const sl_level *m = &list->levels[i];
        int intermediate = (m->flags & SL_LEVEL_INTERMEDIATE) != 0;
        sl_json_object_begin(r, NULL);
        sl_json_string(r, "name", m->name);
        sl_json_bool(r, "intermediate", intermediate);
        sl_json_string(r, "from", m->from[0] ? m->from : NULL);
        if (!intermediate) {
            sl_json_u64(r, "budget", m->budget);
            sl_json_bool(r, "reached", (m->flags & SL_LEVEL_REACHED) != 0);
            sl_json_bool(r, "clamped", (m->flags & SL_LEVEL_CLAMPED) != 0);
        }
        sl_json_u64(r, "triangles", m->triangle_count);
        sl_json_u64(r, "vertices", m->vertex_count);
        sl_json_double(r, "bound", m->bound_fraction);
        sl_json_double(r, "bound_world", m->bound);
        sl_json_object_end(r);
    }
    sl_json_array_end(r);
}

/* The list in the ladder's order, each level's intermediates after it; every name must be
 * a file stem of its own. */
static int write_list(const stage_config *c, const sl_pointset *ps, double diagonal,
                      stage_records *rec, const sl_stage_io *io, sl_error *err)
{
    sl_level_list list = {ps->triangle_count, ps->count, diagonal, 0, 0, 0, NULL};
    list.levels = calloc((size_t)SL_LADDER_MAX * (SL_CLUSTER_MAX_INTERMEDIATES + 1), sizeof *list.levels);
    if (!list.levels)
        return sl_error_nomem(err, NULL, "level records");
    for (int i = 0; i < c->ladder.count; i++) {
        if (!rec->made[i])
            continue;
        list.levels[list.count++] = rec->levels[i];
        for (uint32_t j = 0; j < rec->morph_count[i]; j++)
            list.levels[list.count++] = rec->morphs[(size_t)i * SL_CLUSTER_MAX_INTERMEDIATES + j];
    }
    int rc = 0;
    for (uint32_t i = 0; rc == 0 && i < list.count; i++)
        for (uint32_t j = 0; j < i; j++)
            if (!strcmp(list.levels[i].name, list.levels[j].name)) {
                rc = sl_error_set(err, SL_E_CONFIG, 0, "[levels]",
                                  "two levels or intermediate models are named '%s' (level "
                                  "names are cut to 22 characters before '.morphJ')",
                                  list.levels[i].name);
                break;
            }
    if (rc == 0)
        rc = sl_level_list_write(io->out_dir, &list, err);
    if (rc == 0)
        report(c, &list, io->report);
    free(list.levels);
    return rc;
}

static int cluster_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const stage_config *c = config;
    const char *range_dir = sl_stage_dir(io, "range");
    char in_path[PATH_MAX];
    if (!range_dir)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "the cluster stage needs the range stage");
    int rc = sl_stage_path(in_path, range_dir, SL_POINTSET_FILE, err);
    sl_pointset ps;
    memset(&ps, 0, sizeof ps);
    if (rc == 0)
        rc = sl_pointset_read(in_path, &ps, err);
    if (rc)
        return rc;
    if (ps.triangle_count == 0) {
        sl_pointset_release(&ps);
        return sl_error_set(err, SL_E_UNSUPPORTED, 0, io->source_path,
                            "a point cloud (no faces): the cluster method needs a triangle mesh");
    }
    double diagonal = 0.0;
    for (int k = 0; k < 3; k++)
        diagonal += (double)(ps.bbox_max[k] - ps.bbox_min[k]) * (ps.bbox_max[k] - ps.bbox_min[k]);
    diagonal = sqrt(diagonal);
    stage_records *rec = calloc(1, sizeof *rec);
    if (rec)
        rec->morphs = calloc((size_t)SL_LADDER_MAX * SL_CLUSTER_MAX_INTERMEDIATES, sizeof *rec->morphs);
    rc = rec && rec->morphs ? 0 : sl_error_nomem(err, NULL, "out of memory");
    if (rc == 0)
        rc = build_levels(c, &ps, diagonal, rec, io, err);
    if (rc == 0)
        rc = write_list(c, &ps, diagonal, rec, io, err);
    if (rec)
        free(rec->morphs);
    free(rec);
    sl_pointset_release(&ps);
    return rc;
}

static const char *const cluster_sections[] = {"cluster", SL_LADDER_SECTION, NULL};
static const sl_option *const cluster_shared[] = {sl_ladder_options, NULL};

const sl_stage sl_cluster_stage = {
    .name = "cluster",
    .methods = SL_METHOD_CLUSTER,
    .description = "welded mesh -> a level per rung of the ladder by clustering with a proven "
                   "Hausdorff bound (paper 2)",
    .version = CLUSTER_STAGE_VERSION,
    .options = cluster_options,
    .shared_options = cluster_shared,
    .sections = cluster_sections,
    .configure = cluster_configure,
    .release_config = free,
    .run = cluster_run,
    .publish = 0,
};
