/* cluster stage entry (cluster.h): the range stage's welded mesh -> the export ladder's
 * levels, each from the next finer one (the paper's hierarchy: a pass takes the previous
 * pass's output), with their bounds; the export stage writes them (export_level_list.c).
 *
 * A level asked as lod_percents P is a budget of floor(P% of the input's triangles); the
 * levels are built from the largest budget down, each from the last one that needed work,
 * so its bound is that level's plus its own passes'. A budget the finer level already
 * meets is that level, unchanged. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <stdio.h>

#include "stages/cluster/cluster.h"
#include "stages/export/export.h"
#include "stages/range/range.h"

#define CLUSTER_STAGE_VERSION 1u

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

/* The stage's resolved config: the method's section, and the export ladder it builds. */
typedef struct stage_config {
    sl_cluster_config method; /* first: sl_cluster_default_config copies just this */
    sl_export_config ladder;  /* [export] lod_percents and budgets */
} stage_config;

static int cluster_configure(const sl_config *cfg, void **out, sl_error *err)
{
    stage_config *c = calloc(1, sizeof *c);
    void *ladder = NULL;
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    c->method.passes = (uint32_t)sl_config_int(cfg, "cluster", "passes");
    c->method.intermediates = (uint32_t)sl_config_int(cfg, "cluster", "intermediates");
    c->method.max_angle = sl_config_double(cfg, "cluster", "max_angle");
    c->method.slab_share = sl_config_double(cfg, "cluster", "slab_share");
    c->method.search_steps = (uint32_t)sl_config_int(cfg, "cluster", "search_steps");
    int rc = sl_export_stage.configure(cfg, &ladder, err);
    if (rc == 0) {
        c->ladder = *(const sl_export_config *)ladder;
        sl_export_stage.release_config(ladder);
        *out = c;
    } else {
        free(c);
    }
    return rc;
}

sl_cluster_config sl_cluster_default_config(void)
{
    /* The stage reads [export] too (its ladder), so its defaults need both tables. */
    const sl_option *tables[3] = {sl_cluster_stage.options, sl_export_stage.options, NULL};
    sl_config *cfg = NULL;
    void *c = NULL;
    sl_error err;
    sl_error_init(&err);
    if (sl_config_load(&cfg, tables, NULL, NULL, 0, &err) || cluster_configure(cfg, &c, &err)) {
        char line[1024];
        fprintf(stderr, "scanlod: the cluster stage's defaults fail: %s\n",
                sl_error_format(&err, line, sizeof line));
        abort();
    }
    sl_cluster_config out = ((stage_config *)c)->method;
    free(c);
    sl_config_free(cfg);
    return out;
}

/* A level's triangles (indices into the point set) as a mesh of the points it uses. */
static int compact(const sl_pointset *ps, uint64_t triangle_count, const uint32_t *triangles,
                   uint32_t *map, sl_cluster_list_mesh *m)
{
    memset(map, 0xff, ps->count * sizeof *map);
    for (uint64_t i = 0; i < 3 * triangle_count; i++)
        map[triangles[i]] = 0;
    uint64_t used = 0;
    for (uint64_t v = 0; v < ps->count; v++)
        if (map[v] != UINT32_MAX)
            map[v] = (uint32_t)used++;
    m->positions = malloc(3 * (used ? used : 1) * sizeof *m->positions);
    m->source = malloc((used ? used : 1) * sizeof *m->source);
    m->triangles = malloc(3 * (triangle_count ? triangle_count : 1) * sizeof *m->triangles);
    if (!m->positions || !m->source || !m->triangles)
        return -1;
    for (uint64_t v = 0; v < ps->count; v++)
        if (map[v] != UINT32_MAX) {
            memcpy(m->positions + 3 * (uint64_t)map[v], ps->positions + 3 * v, 3 * sizeof(float));
            m->source[map[v]] = (uint32_t)v;
        }
    for (uint64_t i = 0; i < 3 * triangle_count; i++)
        m->triangles[i] = map[triangles[i]];
    m->vertex_count = used;
    m->triangle_count = triangle_count;
    return 0;
}

/* An intermediate model as a list mesh (its arrays moved in). */
static void take_intermediate(sl_cluster_intermediate *im, const char *level, const char *from,
                              uint32_t j, double diagonal, sl_cluster_list_mesh *m)
{
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%.22s.morph%u", level, j % 1000u);
    memcpy(m->from, from, sizeof m->from);
    m->intermediate = 1;
    m->reached = 1;
    m->bound = im->bound;
    m->bound_fraction = im->bound / diagonal;
    m->vertex_count = im->vertex_count;
    m->triangle_count = im->triangle_count;
    m->positions = im->positions;
    m->source = im->source;
    m->triangles = im->triangles;
    memset(im, 0, sizeof *im);
}

typedef struct ladder_step {
    uint32_t level;   /* index into the export ladder */
    uint64_t budget;
} ladder_step;

static int step_cmp(const void *a, const void *b)
{
    const ladder_step *x = a, *y = b;
    if (x->budget != y->budget)
        return x->budget > y->budget ? -1 : 1;
    return x->level < y->level ? -1 : x->level > y->level;
}

/* The ladder's levels, finest first, each from the one before; OUT: meshes (ladder order)
 * and morphs[level] (its intermediates, count cfg->intermediates each). */
static int build_levels(const stage_config *c, const sl_pointset *ps, double diagonal,
                        sl_cluster_list_mesh *meshes, sl_cluster_list_mesh *morphs,
                        uint32_t *morph_count, const sl_stage_io *io, sl_error *err)
{
    const sl_export_config *ld = &c->ladder;
    ladder_step steps[SL_EXPORT_MAX_LEVELS];
    uint64_t n = ps->triangle_count;
    for (int i = 0; i < ld->level_count; i++) {
        const sl_export_level *lv = &ld->levels[i];
        uint64_t b = lv->by_percent ? (uint64_t)floor(lv->percent / 100.0 * (double)n) : lv->budget;
        steps[i] = (ladder_step){(uint32_t)i, b ? b : 1};
    }
    qsort(steps, (size_t)ld->level_count, sizeof *steps, step_cmp);
    uint32_t *map = malloc((ps->count ? ps->count : 1) * sizeof *map);
    if (!map)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    const uint32_t *prev = ps->triangles;
    char prev_name[32] = "";
    uint64_t prev_count = n;
    double prev_bound = 0.0;
    sl_cluster_level keep; /* the previous level, whose triangles `prev` points into */
    memset(&keep, 0, sizeof keep);
    int rc = 0;
    for (int s = 0; s < ld->level_count && rc == 0; s++) {
        const sl_export_level *lv = &ld->levels[steps[s].level];
        sl_cluster_list_mesh *m = &meshes[steps[s].level];
        if ((rc = sl_stage_step(io, "cluster", (double)s / ld->level_count, err)))
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
        memcpy(m->name, lv->name, sizeof m->name);
        memcpy(m->from, prev_name, sizeof m->from); /* (a level equal to it: its copy) */
        m->by_percent = lv->by_percent;
        m->percent = lv->percent;
        m->budget = steps[s].budget;
        m->clamped = steps[s].budget >= n;
        m->reached = same || level.reached;
        m->bound = same ? prev_bound : level.bound;
        m->bound_fraction = m->bound / diagonal;
        if (compact(ps, same ? prev_count : level.triangle_count, same ? prev : level.triangles,
                    map, m)) {
            rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "level %s", lv->name);
            sl_cluster_level_release(&level);
            break;
        }
        morph_count[steps[s].level] = level.intermediate_count;
        for (uint32_t j = 0; j < level.intermediate_count; j++)
            take_intermediate(&level.intermediates[j], lv->name, prev_name, j + 1, diagonal,
                              &morphs[(size_t)steps[s].level * SL_CLUSTER_MAX_INTERMEDIATES + j]);
        if (!same) {
            memcpy(prev_name, lv->name, sizeof prev_name);
            sl_cluster_level_release(&keep);
            keep = level;
            prev = keep.triangles;
            prev_count = keep.triangle_count;
            prev_bound = keep.bound;
        }
    }
    sl_cluster_level_release(&keep);
    free(map);
    return rc;
}

static void report(const stage_config *c, const sl_cluster_list *list, sl_json *r)
{
    sl_json_u64(r, "passes", c->method.passes);
    sl_json_u64(r, "intermediates", c->method.intermediates);
    sl_json_double(r, "max_angle", c->method.max_angle);
    sl_json_double(r, "slab_share", c->method.slab_share);
    sl_json_u64(r, "input_triangles", list->input_triangles);
    sl_json_double(r, "diagonal", list->diagonal);
    sl_json_array_begin(r, "levels");
    for (uint32_t i = 0; i < list->count; i++) {
        const sl_cluster_list_mesh *m = &list->meshes[i];
        sl_json_object_begin(r, NULL);
        sl_json_string(r, "name", m->name);
        sl_json_bool(r, "intermediate", m->intermediate);
        sl_json_string(r, "from", m->from[0] ? m->from : NULL);
        if (!m->intermediate) {
            sl_json_u64(r, "budget", m->budget);
            sl_json_bool(r, "reached", m->reached);
            sl_json_bool(r, "clamped", m->clamped);
        }
        sl_json_u64(r, "triangles", m->triangle_count);
        sl_json_u64(r, "vertices", m->vertex_count);
        sl_json_double(r, "bound", m->bound_fraction);
        sl_json_double(r, "bound_world", m->bound);
        sl_json_object_end(r);
    }
    sl_json_array_end(r);
}

static int cluster_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const stage_config *c = config;
    const char *range_dir = sl_stage_dir(io, "range");
    char in_path[PATH_MAX], out_path[PATH_MAX];
    if (!range_dir)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "the cluster stage needs the range stage");
    int rc = sl_stage_path(in_path, range_dir, SL_POINTSET_FILE, err);
    if (rc == 0)
        rc = sl_stage_path(out_path, io->out_dir, SL_CLUSTER_LEVELS_FILE, err);
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
    int levels = c->ladder.level_count;
    size_t slots = (size_t)(levels ? levels : 1);
    sl_cluster_list_mesh *meshes = calloc(slots, sizeof *meshes);
    sl_cluster_list_mesh *morphs = calloc(slots * SL_CLUSTER_MAX_INTERMEDIATES, sizeof *morphs);
    uint32_t *morph_count = calloc(slots, sizeof *morph_count);
    sl_cluster_list list = {ps.triangle_count, diagonal, 0, NULL};
    if (!meshes || !morphs || !morph_count)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = build_levels(c, &ps, diagonal, meshes, morphs, morph_count, io, err);
    uint64_t total = 0;
    for (int i = 0; i < levels && rc == 0; i++)
        total += 1 + morph_count[i];
    if (rc == 0 && !(list.meshes = calloc(total ? total : 1, sizeof *list.meshes)))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    for (int i = 0; i < levels && rc == 0; i++) { /* the ladder's order, morphs after their level */
        list.meshes[list.count++] = meshes[i];
        memset(&meshes[i], 0, sizeof meshes[i]);
        for (uint32_t j = 0; j < morph_count[i]; j++) {
            sl_cluster_list_mesh *x = &morphs[(size_t)i * SL_CLUSTER_MAX_INTERMEDIATES + j];
            list.meshes[list.count++] = *x;
            memset(x, 0, sizeof *x);
        }
    }
    for (uint32_t i = 0; rc == 0 && i < list.count; i++) /* each name is its files' stem */
        for (uint32_t j = 0; j < i; j++)
            if (!strcmp(list.meshes[i].name, list.meshes[j].name)) {
                rc = sl_error_set(err, SL_E_CONFIG, 0, "[export]",
                                  "two levels or intermediate models are named '%s' (level "
                                  "names are cut to 22 characters before '.morphJ')",
                                  list.meshes[i].name);
                break;
            }
    if (rc == 0)
        rc = sl_cluster_list_write(out_path, &list, err);
    if (rc == 0)
        report(c, &list, io->report);
    sl_cluster_list_release(&list);
    for (size_t i = 0; meshes && i < slots; i++) { /* what a failure left */
        free(meshes[i].positions);
        free(meshes[i].source);
        free(meshes[i].triangles);
    }
    for (size_t i = 0; morphs && i < slots * SL_CLUSTER_MAX_INTERMEDIATES; i++) {
        free(morphs[i].positions);
        free(morphs[i].source);
        free(morphs[i].triangles);
    }
    free(meshes);
    free(morphs);
    free(morph_count);
    sl_pointset_release(&ps);
    return rc;
}

static const char *const cluster_sections[] = {"cluster", "export", NULL};

const sl_stage sl_cluster_stage = {
    .name = "cluster",
    .methods = SL_METHOD_CLUSTER,
    .description = "welded mesh -> the export ladder's levels by clustering with a proven "
                   "Hausdorff bound (paper 2)",
    .version = CLUSTER_STAGE_VERSION,
    .options = cluster_options,
    .sections = cluster_sections,
    .configure = cluster_configure,
    .release_config = free,
    .run = cluster_run,
    .publish = 0,
};
