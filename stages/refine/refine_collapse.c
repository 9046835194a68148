/* A candidate brought to its count and fitted to the input (refine_internal.h).
 *
 * Collapse: quadric edge collapse (geometry/qem_simplify.h) from the method's level to the
 * rung's count (by bricks from a level above [refine] collapse_brick_triangles), keeping
 * its topology, borders, colours and texture seams; where that alone stops above the
 * count, its relaxed phase gives up the topology for the rest of the way. Fit: its
 * vertices moved, connectivity fixed, to the least squared distance between it and the
 * input, both ways (geometry/surface_fit.h), against one reference per item built on the
 * first fit. A level that changed no longer has the method's proven bound (paper 2) nor
 * the octree's error table behind it: it carries none; the export measures it. */
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_distance.h"
#include "geometry/qem_simplify.h"
#include "geometry/surface_fit.h"
#include "stages/refine/refine_internal.h"

/* best: the scan candidate as it is before its fit, for the next, smaller one. */
static int keep_chain(refine_item *it, const sl_level *lv, sl_error *err)
{
    sl_level_release_mesh(&it->scan_chain);
    sl_level_copy_record(&it->scan_chain, lv);
    int rc = sl_level_from_points(&it->scan_chain, lv->vertex_count, lv->positions, lv->colors,
                                  lv->texcoords, lv->triangle_count, lv->triangles, err);
    if (rc == 0 && lv->source) /* the chain's vertices name the input's points */
        for (uint64_t v = 0; v < it->scan_chain.vertex_count; v++)
            it->scan_chain.source[v] = lv->source[it->scan_chain.source[v]];
    return rc;
}

uint64_t sl_refine_collapse_bricks(int64_t configured, uint64_t input_triangles,
                                   uint64_t memory_budget_mb)
{
    if (configured != SL_REFINE_BRICKS_BY_BUDGET)
        return configured > 0 ? (uint64_t)configured : 0;
    double whole_mb = SL_REFINE_WHOLE_BYTES * (double)input_triangles / (1024.0 * 1024.0);
    return memory_budget_mb && whole_mb > (double)memory_budget_mb ? SL_REFINE_BUDGET_BRICK : 0;
}

/* The level's arrays replaced by the collapse's; `source` kept naming the input's points
 * when the level's did. */
static void take_collapsed(sl_level *lv, sl_qem_mesh *out)
{
    if (lv->source && out->source)
        for (uint64_t v = 0; v < out->vertex_count; v++)
            out->source[v] = lv->source[out->source[v]];
    int had_source = lv->source != NULL;
    sl_level_release_mesh(lv);
    lv->vertex_count = out->vertex_count;
    lv->positions = out->positions;
    lv->colors = out->colors;
    lv->texcoords = out->texcoords;
    lv->triangle_count = out->triangle_count;
    lv->triangles = out->triangles;
    lv->source = had_source ? out->source : NULL;
    if (!had_source) /* an octree cut: its vertices are no input point */
        free(out->source);
    memset(out, 0, sizeof *out);
}

/* The collapse keeping the topology; where it stops above the target ([refine]
 * relax_topology), the collapse from the method's level again with the relaxed rules from
 * the first collapse. Why again and not on from where it stopped: by then the strict rules
 * have spent the budget on every small handle and hole and coarsened the body around them
 * (usnm_1145291, segment at 5 %: RMS 0.73 % of the diagonal going on, 0.17 % again;
 * docs/simplify.md). A level the strict collapse reaches is made as before. */
static int collapse(refine_item *it, uint64_t target, refine_candidate *cand, sl_error *err)
{
    sl_level *lv = &cand->level;
    sl_qem_mesh in = {lv->vertex_count, lv->positions, lv->colors, lv->texcoords,
                      lv->triangle_count, lv->triangles, NULL};
    sl_qem_config cfg = sl_qem_default_config();
    cfg.target_triangles = target;
    sl_qem_mesh out;
    sl_qem_stats stats;
    uint64_t brick = it->collapse_bricks;
    int rc = sl_qem_simplify_bricked(&in, &cfg, brick, &out, &stats, it->io->progress, err);
    if (rc == 0 && it->c->relax_topology && stats.stop == SL_QEM_STOP_TOPOLOGY &&
        out.triangle_count > target) {
        cand->strict_triangles = out.triangle_count;
        sl_qem_mesh_release(&out);
        cfg.allow_topology_change = SL_QEM_TOPOLOGY_RELAX;
        rc = sl_qem_simplify_bricked(&in, &cfg, brick, &out, &stats, it->io->progress, err);
        cand->relaxed_collapses = rc == 0 ? stats.relaxed_collapses : 0;
    }
    if (rc)
        return rc;
    take_collapsed(lv, &out);
    return 0;
}

/* A level changed by the collapse or the fit no longer has its method's bound. */
static void mark_refined(sl_level *lv)
{
    lv->flags = (lv->flags | SL_LEVEL_REFINED) & ~(uint32_t)SL_LEVEL_PROVEN;
    lv->bound = lv->bound_fraction = 0;
}

static int fit(refine_item *it, refine_candidate *cand, sl_error *err)
{
    sl_level *lv = &cand->level;
    sl_fit_config cfg = sl_fit_default_config();
    cfg.iterations = it->c->fit_rounds;
    if (it->distance_reference) /* one tree over the input for the measures and the fits */
        cfg.surface_tree = sl_distance_reference_tree(it->distance_reference);
    int rc = it->fit_reference ? 0
                               : sl_fit_reference_build(&it->surface, &cfg, &it->fit_reference,
                                                        err);
    sl_fit_stats stats;
    if (rc == 0)
        rc = sl_surface_fit(it->fit_reference, lv->positions, lv->vertex_count, lv->triangles,
                            lv->triangle_count, &cfg, &stats, it->io->progress, err);
    if (rc == 0) {
        cand->fit_rms_before = stats.rms_before;
        cand->fit_rms_after = stats.rms_after;
    }
    return rc;
}

int refine_collapse(refine_item *it, uint64_t target, refine_candidate *cand, sl_error *err)
{
    sl_level *lv = &cand->level;
    int rc = 0;
    if (it->c->collapse && target && lv->triangle_count > target) {
        rc = collapse(it, target, cand, err);
        if (rc == 0)
            mark_refined(lv);
    }
    if (rc == 0 && it->c->best && !strcmp(lv->method, "scan"))
        rc = keep_chain(it, lv, err);
    return rc;
}

int refine_fit(refine_item *it, refine_candidate *cand, sl_error *err)
{
    if (!it->c->fit || cand->level.triangle_count == 0)
        return 0;
    int rc = fit(it, cand, err);
    if (rc == 0)
        mark_refined(&cand->level);
    return rc;
}
