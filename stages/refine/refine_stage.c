/* refine stage entry: options, the item's inputs, the ladder's levels (refine.h). */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "geometry/mesh_distance.h"
#include "geometry/surface_fit.h"
#include "runtime/lod_io.h"
#include "runtime/lod_prefix.h"
#include "stages/refine/refine_internal.h"

/* 1: the first refine stage (levels from every method, the scan at the top). 2: a level
 * the collapse keeping the topology leaves above its count is collapsed again with the
 * topology rules relaxed ([refine] relax_topology); the report says which. 3: levels made
 * from the scan's vertices (the scan, its collapses) keep its texture coordinates. 4: a
 * level already within [refine] fit_floor of the input is not fitted. 5: a collapse from
 * more than [refine] collapse_brick_triangles runs by bricks (default off). 6: beside the
 * scan simplified, no octree candidate for a level above [refine] octree_max_share of the
 * input's count. 7: a candidate farther uncollapsed than a lead within [refine] fit_floor
 * is not collapsed (outranked; the levels as before, the report says outranked). */
#define REFINE_STAGE_VERSION 7u

static const sl_option refine_options[] = {
    {"refine", "collapse", SL_OPT_BOOL, "true", 0, 0, NULL,
     "Bring every level a method leaves above its count to exactly that count (within 1 %) "
     "by quadric edge collapse with optimal vertex placement, keeping the topology (no part "
     "breaks off, closed stays closed, borders stay) and the colours (docs/levels.md). false: "
     "each method's own level, as its paper makes it."},
    {"refine", "relax_topology", SL_OPT_BOOL, "true", 0, 0, NULL,
     "When the collapse keeping the topology stops above a level's count (an open or "
     "non-manifold level: segment and cluster on usnm_1145291 at 1-5 %), collapse the "
     "method's level again to the count with the topology rules lifted: non-manifold points "
     "move, holes, handles and specks may close, borders may join; still no triangle turns "
     "over (docs/simplify.md; 'topology_relaxed' in the report). false: such a level stays "
     "above its count."},
    {"refine", "collapse_brick_triangles", SL_OPT_INT, "-1", -1, 2000000000, NULL,
     "A collapse from more triangles than this runs by bricks of at most this many "
     "(docs/simplify.md \"By bricks\"): each brick alone and in parallel with its borders "
     "and the rings around them locked, all stopping at one collapse error, then strips "
     "around the borders, the last pass on the whole once it fits one brick. Memory about "
     "180 bytes per brick triangle per thread instead of per input triangle (20 M -> 16 M "
     "triangles, bricks of 1 M: 1.3 GB against 3.9, about the same time); RMS as close or "
     "closer on closed scans, up to 19 % farther on an open, non-manifold one. 0: every "
     "collapse on the whole mesh at once. -1 (default): by the memory budget ([run] "
     "memory_limit_mb, else the node's): whole unless the input's triangles times 300 "
     "bytes are over it (a 20 M-triangle scan against 5.6 GB), then bricks of 1 M "
     "(docs/bricks.md)."},
    {"refine", "octree_max_share", SL_OPT_DOUBLE, "0.3", 0, 1, NULL,
     "When the scan simplified is a candidate ([lod] method = best on a mesh, collapse on), "
     "the octree's "
     "cut is one too only for a level of at most this share of the input's triangles. Above "
     "it the cut, a remesh with about as many triangles as the level, was at least 1.76 times "
     "farther from the input than the scan collapsed on every input measured (20 scans and "
     "tori of 1 and 20 M triangles, levels of 29-80 %; at 20 % it won once, 0.53 times), and making "
     "and measuring it was a fifth of a 20 M scan's run (docs/levels.md). 1: every level "
     "gets one, as before."},
    {"refine", "fit", SL_OPT_BOOL, "true", 0, 0, NULL,
     "Move every refined level's vertices to fit the input surface (the squared distance of "
     "dense samples both ways, connectivity fixed, no fold; Hoppe et al. 1993): what the "
     "RMS distance measures. false: the vertices where the method or the collapse put "
     "them."},
    {"refine", "fit_rounds", SL_OPT_INT, "4", 1, 100, NULL,
     "Rounds of the fit (each projects dense samples both ways and solves for the vertices; "
     "docs/surface-fit.md): more fit closer, each costs about as much as the first. 4 keep "
     "about 90 % of 8 rounds' gain at half their cost (docs/levels.md)."},
    {"refine", "fit_floor", SL_OPT_DOUBLE, "1e-5", 0, 1, NULL,
     "A level whose RMS distance to the input, measured before the fit, is at most this "
     "fraction of the input's diagonal is not fitted: "
     "the fit gains 5-10 % of the RMS there, below what the published GLB shows (its default "
     "14-bit positions alone are at least 1.8e-5 of the diagonal RMS), and on a large scan "
     "the top levels' fits were 70 % of the stage's time (docs/levels.md). 0 fits every "
     "level."},
    {"refine", "select_samples", SL_OPT_INT, "100000", 1000, 100000000, NULL,
     "Area samples per surface when candidates of one level are measured against the input "
     "to choose the most faithful ([lod] method = best)."},
    {"refine", "min_part_area", SL_OPT_DOUBLE, "0.01", 0, 0.5, NULL,
     "Shards (docs/lod.md): when the octree's finest cut is one body (its largest part "
     "holds 99 % of its area; for a mesh under [lod] method = best: when the input is), "
     "each coarser cut leaves out the connected parts holding less "
     "than this share of its area (never its largest): pieces of thin parts that the coarse "
     "cells cut loose, and specks. 0 keeps every part as the octree draws it (paper 1). A "
     "scan of several pieces keeps all its parts."},
    {"refine", "shard_reach", SL_OPT_DOUBLE, "2", 0, 1e9, NULL,
     "A small part (min_part_area) is left out only when each of its vertices lies within "
     "this many of the cut's mean triangle edges of the rest of it: a speck the body covers "
     "goes, a part farther out (the only surface there) stays."},
    {"refine", "cap_at_input", SL_OPT_BOOL, "true", 0, 0, NULL,
     "No octree cut has more triangles than the input mesh (the largest cut within it "
     "instead; 'capped' in the report). false: the octree's finest level whatever its "
     "count (paper 1)."},
    SL_OPTION_END,
};

static const char *const refine_sections[] = {"refine", SL_LADDER_SECTION, "lod", NULL};
static const sl_option *const refine_shared[] = {sl_ladder_options, NULL};

static int refine_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_refine_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_nomem(err, NULL, "out of memory");
    int rc = sl_ladder_read(cfg, &c->ladder, err);
    c->best = !strcmp(sl_config_string(cfg, "lod", "method"), "best");
    c->collapse = sl_config_bool(cfg, "refine", "collapse");
    c->relax_topology = sl_config_bool(cfg, "refine", "relax_topology");
    c->collapse_brick_triangles =
        sl_config_int(cfg, "refine", "collapse_brick_triangles");
    c->octree_max_share = sl_config_double(cfg, "refine", "octree_max_share");
    c->fit = sl_config_bool(cfg, "refine", "fit");
    c->fit_rounds = (int)sl_config_int(cfg, "refine", "fit_rounds");
    c->fit_floor = sl_config_double(cfg, "refine", "fit_floor");
    c->select_samples = (uint64_t)sl_config_int(cfg, "refine", "select_samples");
    c->min_part_area = sl_config_double(cfg, "refine", "min_part_area");
    c->shard_reach = sl_config_double(cfg, "refine", "shard_reach");
    c->cap_at_input = sl_config_bool(cfg, "refine", "cap_at_input");
    if (rc == 0 && !c->collapse && c->ladder.oversample != 1) {
        char where[1024];
        sl_config_where(cfg, "refine", "collapse", where, sizeof where);
        rc = sl_error_set(err, SL_E_CONFIG, 0, where,
                          "[refine] collapse = false needs [levels] oversample = 1: nothing would "
                          "bring the methods' levels, made at %g times their counts, down to them",
                          c->ladder.oversample);
    }
    if (rc) {
        free(c);
        return rc;
    }
    *out = c;
    return 0;
}

sl_refine_config sl_refine_default_config(void)
{
    sl_refine_config c;
    sl_stage_default_config(&sl_refine_stage, &c, sizeof c);
    return c;
}

/* --- the item's inputs -------------------------------------------------------------------- */

/* A mesh under [lod] method = best: its model read by prefixes, opened late (below). */
static int model_by_prefixes(const refine_item *it)
{
    return it->is_mesh && it->c->best;
}

int refine_model(refine_item *it, sl_error *err)
{
    if (it->cutter.levels || !it->have_model) /* open already, or none */
        return 0;
    char path[PATH_MAX];
    int rc = sl_stage_path(path, it->model_dir, SL_MODEL_FILE, err);
    /* A mesh's levels below the top are cut from the model read as far as each cut needs
     * (lod_prefix.h): the largest is [levels] oversample times octree_max_share of the
     * input, so most of a large model is never read (the 20 M torus: 3 GB held whole).
     * Whether its finest cut is one body (the shards' rule, refine_octree.c) is then taken
     * from the input mesh, which the finest cut remeshes, instead of from that cut, which
     * would read all of it. A point set's levels are all cut: its model is opened whole. */
    int prefix = model_by_prefixes(it);
    if (rc == 0 && prefix)
        rc = sl_lod_file_open(path, &it->cutter.file, err);
    else if (rc == 0)
        rc = sl_lod_model_open(path, &it->model, err);
    if (rc)
        return rc;
    it->cutter.model = prefix ? NULL : &it->model;
    it->cutter.levels = prefix ? sl_lod_file_levels(it->cutter.file) : &it->model;
    it->cutter.one_body = prefix ? it->input_one_body : -1;
    it->cutter.min_part_area = it->c->min_part_area;
    it->cutter.shard_reach = it->c->shard_reach;
    return 0;
}

/* The model found in `dir`: its level tables' size read now (the file's header and tables
 * only, lod_prefix.h; closed again, so the tables are not held through a scan's top
 * levels), the model itself when a rung first cuts it (refine_model); a point
 * set's at once, whose every level is cut from it. */
static int find_model(refine_item *it, const char *dir, sl_error *err)
{
    char path[PATH_MAX];
    int rc = sl_stage_path(path, dir, SL_MODEL_FILE, err);
    sl_lod_file *f = NULL;
    if (rc == 0)
        rc = sl_lod_file_open(path, &f, err);
    if (rc)
        return rc;
    const sl_lod_model *levels = sl_lod_file_levels(f);
    it->model_expansions = levels->expansion_count;
    it->model_triangles = levels->accumulation[levels->expansion_count];
    sl_lod_file_close(f);
    it->have_model = 1;
    it->model_dir = dir;
    it->cutter.cap = it->c->cap_at_input && it->is_mesh ? it->points.triangle_count : 0;
    return model_by_prefixes(it) ? 0 : refine_model(it, err);
}

/* The inputs found by the artifacts the earlier stages left: the range stage's points, an
 * LOD model, and level lists (the stage names no method). */
static int open_item(refine_item *it, sl_error *err)
{
    const char *range_dir = sl_stage_dir(it->io, "range");
    char path[PATH_MAX];
    int rc = range_dir ? sl_stage_path(path, range_dir, SL_POINTSET_FILE, err)
                       : sl_error_set(err, SL_E_INTERNAL, 0, NULL, "refine needs the range stage");
    if (rc == 0)
        rc = sl_pointset_read(path, &it->points, err);
    if (rc)
        return rc;
    const sl_pointset *ps = &it->points;
    it->is_mesh = ps->triangle_count > 0;
    it->surface = sl_mesh_view(ps->count, ps->positions, NULL, NULL, ps->triangle_count,
                               ps->triangles);
    if (it->is_mesh) { /* what the levels should keep of it */
        sl_mesh_topology topo;
        rc = sl_mesh_topology_compute(&it->surface, &topo, err);
        if (rc)
            return rc;
        it->input_watertight = topo.watertight;
        it->input_one_body = topo.area > 0 &&
                             topo.largest_component_area >= SL_REFINE_ONE_BODY * topo.area;
    }
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += ((double)ps->bbox_max[k] - ps->bbox_min[k]) * ((double)ps->bbox_max[k] - ps->bbox_min[k]);
    it->diagonal = sqrt(d2);
    for (const struct sl_stage_dir_entry *u = it->io->upstream; rc == 0 && u && u->stage; u++) {
        if (sl_stage_path(path, u->dir, SL_MODEL_FILE, err) == 0 && !it->have_model &&
            access(path, F_OK) == 0)
            rc = find_model(it, u->dir, err);
        if (rc == 0 && sl_level_list_present(u->dir) && it->method_count < 2) {
            struct refine_method_list *m = &it->methods[it->method_count++];
            m->method = u->stage;
            m->dir = u->dir;
            rc = sl_level_list_read(u->dir, &m->list, err);
        }
    }
    it->input_triangles = it->is_mesh ? ps->triangle_count
                          : it->have_model ? it->model_triangles
                                           : 0;
    it->collapse_bricks = sl_refine_collapse_bricks(it->c->collapse_brick_triangles,
                                                    it->input_triangles, it->io->memory_budget_mb);
    if (rc == 0 && !it->have_model && it->method_count == 0 && !it->is_mesh)
        rc = sl_error_set(err, SL_E_UNSUPPORTED, 0, it->io->source_path,
                          "a point set (no faces) needs the octree method for its levels");
    return rc;
}

static void close_item(refine_item *it)
{
    for (int m = 0; m < it->method_count; m++)
        sl_level_list_release(&it->methods[m].list);
    if (it->cutter.file)
        sl_lod_file_close(it->cutter.file);
    else if (it->cutter.levels)
        sl_lod_model_release(&it->model);
    sl_level_release_mesh(&it->scan_chain);
    sl_fit_reference_free(it->fit_reference);
    sl_distance_reference_free(it->distance_reference);
    sl_pointset_release(&it->points);
}

/* --- the levels ----------------------------------------------------------------------------- */

/* The rungs in the order they are made: most triangles first (a scan candidate is
 * simplified from the one before), expansions rungs last; ties in the ladder's order. */
static void making_order(const refine_item *it, int *order, uint64_t *target)
{
    const sl_ladder *l = &it->c->ladder;
    for (int i = 0; i < l->count; i++) {
        target[i] = sl_rung_triangles(&l->rungs[i], it->input_triangles);
        int at = i;
        while (at > 0 && target[order[at - 1]] < target[i])
            order[at] = order[at - 1], at--;
        order[at] = i;
    }
}

/* The cluster method's intermediate models after its level `name`, into the list: only
 * when that level is published as the method made it (they lead to it). */
static int pass_intermediates(refine_item *it, const sl_level *chosen, sl_level_list *out,
                              sl_error *err)
{
    for (int m = 0; m < it->method_count; m++) {
        struct refine_method_list *ml = &it->methods[m];
        if (strcmp(chosen->method, ml->method) || (chosen->flags & SL_LEVEL_REFINED))
            continue;
        for (uint32_t i = 0; i < ml->list.count; i++) {
            const sl_level *rec = &ml->list.levels[i];
            size_t n = strlen(chosen->name);
            if (!(rec->flags & SL_LEVEL_INTERMEDIATE) || strncmp(rec->name, chosen->name, n) ||
                rec->name[n] != '.')
                continue;
            sl_level *lv = &out->levels[out->count];
            sl_level_copy_record(lv, rec);
            int rc = sl_level_read_mesh(ml->dir, lv, it->points.count, err);
            if (rc == 0)
                rc = sl_level_write_mesh(it->io->out_dir, lv, err);
            sl_level_release_mesh(lv);
            if (rc)
                return rc;
            out->count++;
        }
    }
    return 0;
}

static void report_level(sl_json *r, const sl_level *lv, const refine_candidate *cands, int count,
                         int chosen)
{
    sl_json_object_begin(r, NULL);
    sl_json_string(r, "name", lv->name);
    sl_json_string(r, "method", lv->method);
    sl_json_u64(r, "budget", lv->budget);
    sl_json_u64(r, "triangles", lv->triangle_count);
    sl_json_bool(r, "reached", (lv->flags & SL_LEVEL_REACHED) != 0);
    sl_json_bool(r, "scan", (lv->flags & SL_LEVEL_SCAN) != 0);
    if (count > 0) /* the chosen one's collapse gave up the topology to reach the count */
        sl_json_bool(r, "topology_relaxed", cands[chosen].strict_triangles > 0);
    if (count > 0)
        refine_report_candidates(r, cands, count, chosen);
    sl_json_object_end(r);
}

void refine_report_candidates(sl_json *r, const refine_candidate *cands, int count, int chosen)
{
    sl_json_array_begin(r, "candidates");
    for (int i = 0; i < count; i++) {
        const refine_candidate *c = &cands[i];
        sl_json_object_begin(r, NULL);
        sl_json_string(r, "method", c->level.method);
        sl_json_bool(r, "chosen", i == chosen);
        sl_json_u64(r, "base_triangles", c->base_triangles);
        sl_json_u64(r, "triangles", c->level.triangle_count);
        sl_json_bool(r, "refined", (c->level.flags & SL_LEVEL_REFINED) != 0);
        sl_json_bool(r, "topology_relaxed", c->strict_triangles > 0);
        if (c->strict_triangles > 0) { /* docs/levels.md, step 3 */
            sl_json_u64(r, "strict_triangles", c->strict_triangles);
            sl_json_u64(r, "relaxed_collapses", c->relaxed_collapses);
        }
        if (!strcmp(c->level.method, "octree")) {
            sl_json_u64(r, "expansions", c->level.expansions);
            sl_json_bool(r, "capped", c->capped);
            sl_json_object_begin(r, "shards_dropped");
            sl_json_u64(r, "parts", c->dropped.parts);
            sl_json_u64(r, "triangles", c->dropped.triangles);
            sl_json_double(r, "area_fraction", c->dropped.area_fraction);
            sl_json_object_end(r);
        }
        if (c->outranked) /* measured as the method gave it, not collapsed (docs/levels.md) */
            sl_json_bool(r, "outranked", 1);
        sl_json_bool(r, "fitted", c->fitted);
        if (c->measured) { /* after the collapse; after the fit too when it was compared
                              after it (docs/levels.md) */
            if (c->rms_uncollapsed > 0 && !c->outranked) /* collapsed after it */
                sl_json_double(r, "rms_before_collapse", c->rms_uncollapsed);
            if (c->rms_collapsed > 0)
                sl_json_double(r, "rms_before_fit", c->rms_collapsed);
            sl_json_double(r, "rms", c->rms);
            sl_json_double(r, "hausdorff", c->hausdorff);
            sl_json_bool(r, "watertight", c->watertight);
            sl_json_double(r, "largest_part", c->largest_part);
        }
        sl_json_object_end(r);
    }
    sl_json_array_end(r);
}

/* Rung i's level: made, written to its file, its record kept in out->levels[i]. */
static int make_level(refine_item *it, int i, uint64_t target, sl_level_list *out, sl_error *err)
{
    const sl_rung *r = &it->c->ladder.rungs[i];
    sl_level *lv = &out->levels[i];
    refine_candidate cands[SL_REFINE_MAX_CANDIDATES];
    int count = 0, chosen = 0, rc;
    memset(cands, 0, sizeof cands);
    if (it->is_mesh && it->c->ladder.top_is_scan && r->kind != SL_RUNG_EXPANSIONS &&
        target >= it->points.triangle_count) {
        rc = refine_scan_level(it, r, target, &cands[0].level, err);
    } else {
        rc = refine_make_candidates(it, r, target, cands, &count, &chosen, err);
    }
    if (rc == 0) {
        sl_level_copy_record(lv, &cands[chosen].level);
        lv->vertex_count = cands[chosen].level.vertex_count;
        lv->triangle_count = cands[chosen].level.triangle_count;
        rc = sl_level_write_mesh(it->io->out_dir, &cands[chosen].level, err);
    }
    if (rc == 0)
        report_level(it->io->report, lv, cands, count, chosen);
    if (rc == 0 && it->io->timings && count > 0) { /* seconds per candidate: timings.json */
        sl_json_array_begin(it->io->timings, lv->name);
        for (int c = 0; c < count; c++)
            sl_json_double(it->io->timings, NULL, cands[c].seconds);
        sl_json_array_end(it->io->timings);
    }
    for (int c = 0; c < SL_REFINE_MAX_CANDIDATES; c++)
        refine_candidate_release(&cands[c]);
    return rc;
}

static int make_levels(refine_item *it, sl_level_list *out, sl_error *err)
{
    const sl_ladder *l = &it->c->ladder;
    int order[SL_LADDER_MAX];
    uint64_t target[SL_LADDER_MAX];
    making_order(it, order, target);
    unsigned char made[SL_LADDER_MAX] = {0};
    sl_json_array_begin(it->io->report, "levels");
    int rc = 0;
    for (int at = 0; at < l->count && rc == 0; at++) {
        int i = order[at];
        if (l->rungs[i].kind == SL_RUNG_EXPANSIONS && !it->have_model)
            continue; /* paper 1's Table 1 needs the octree: reported as skipped below */
        rc = sl_stage_step(it->io, "refine", (double)at / (l->count ? l->count : 1), err);
        if (rc == 0)
            rc = make_level(it, i, target[i], out, err);
        made[i] = rc == 0;
    }
    sl_json_array_end(it->io->report);
    /* The list in the ladder's order, intermediates after the level they lead to. */
    sl_level_list final = *out;
    sl_level *records = calloc((size_t)l->count * 101 + 1, sizeof *records);
    if (rc == 0 && !records)
        rc = sl_error_nomem(err, NULL, "level records");
    final.levels = records;
    final.count = 0;
    for (int i = 0; i < l->count && rc == 0; i++) {
        if (!made[i])
            continue;
        final.levels[final.count++] = out->levels[i];
        rc = pass_intermediates(it, &out->levels[i], &final, err);
    }
    if (rc == 0)
        rc = sl_level_list_write(it->io->out_dir, &final, err);
    free(records);
    return rc;
}

static int refine_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    refine_item it;
    memset(&it, 0, sizeof it);
    it.c = config;
    it.io = io;
    sl_lod_model_init(&it.model);
    int rc = open_item(&it, err);
    sl_level_list out;
    memset(&out, 0, sizeof out);
    out.levels = calloc(SL_LADDER_MAX, sizeof *out.levels);
    if (rc == 0 && !out.levels)
        rc = sl_error_nomem(err, NULL, "level records");
    if (rc == 0) {
        out.input_triangles = it.points.triangle_count;
        out.input_points = it.points.count;
        out.diagonal = it.diagonal;
        out.model_expansions = it.have_model ? it.model_expansions : 0;
        out.model_triangles = it.have_model ? it.model_triangles : 0;
        sl_json *r = io->report;
        sl_json_string(r, "method", it.c->best ? "best" : it.have_model ? "octree"
                                    : it.method_count ? it.methods[0].method : "scan");
        sl_json_u64(r, "input_triangles", it.input_triangles);
        if (it.have_model)
            sl_json_u64(r, "triangles_finest", out.model_triangles);
        if (it.cutter.cap)
            sl_json_u64(r, "triangles_cap", it.cutter.cap);
        sl_json_bool(r, "collapse", it.c->collapse);
        sl_json_u64(r, "collapse_brick_triangles", it.collapse_bricks);
        sl_json_bool(r, "relax_topology", it.c->relax_topology);
        sl_json_bool(r, "fit", it.c->fit);
        if (it.have_model && it.c->best && it.is_mesh && it.c->collapse)
            sl_json_double(r, "octree_max_share", it.c->octree_max_share);
        rc = make_levels(&it, &out, err);
    }
    free(out.levels);
    close_item(&it);
    return rc;
}

const sl_stage sl_refine_stage = {
    .name = "refine",
    .methods = SL_METHODS_ALL,
    .description = "every method's levels -> the published levels: the scan at the top, the "
                   "rest collapsed to their exact counts and fitted to the input",
    .version = REFINE_STAGE_VERSION,
    .options = refine_options,
    .shared_options = refine_shared,
    .sections = refine_sections,
    .configure = refine_configure,
    .release_config = free,
    .run = refine_run,
};
