/* The octree's cuts for the refine stage (refine_internal.h): k for a count or a share of
 * the LOD array, within the input's count ([refine] cap_at_input), less the shards
 * (refine_shards.c), a budget cut refilled with the triangles its shards had. */
#include <string.h>

#include "runtime/lod_prefix.h"
#include "stages/refine/refine_internal.h"

void refine_cut_release(refine_cut *c)
{
    sl_lod_mesh_release(&c->mesh);
    memset(c, 0, sizeof *c);
}

/* Whether the finest cut is one body, found once (cut again unless it is this one). */
static int learn_one_body(refine_cutter *x, const sl_lod_mesh *mesh, int finest, sl_error *err)
{
    double share = 1;
    int rc = 0;
    if (finest) {
        rc = refine_largest_part(mesh, &share, err);
    } else {
        sl_lod_mesh whole;
        uint32_t e = x->levels->expansion_count;
        if (x->file && (rc = sl_lod_file_reach(x->file, e, &x->model, err)))
            return rc; /* the whole model, read: a caller that knows sets one_body first */
        int cut = sl_lod_generate(x->model, e, &whole, NULL);
        sl_mesh_scratch_shrink(&x->model->scratch);
        rc = cut ? sl_error_nomem(err, NULL, "the finest cut")
                 : refine_largest_part(&whole, &share, err);
        if (!cut)
            sl_lod_mesh_release(&whole);
    }
    if (rc == 0)
        x->one_body = share >= SL_REFINE_ONE_BODY;
    return rc;
}

int refine_cut_at(refine_cutter *x, uint32_t k, refine_cut *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    out->k = k;
    if (x->file) { /* the prefix k needs (held from before when it reached as far) */
        int rc = sl_lod_file_reach(x->file, k, &x->model, err);
        if (rc)
            return rc;
    }
    int failed = sl_lod_generate(x->model, k, &out->mesh, &out->cracks);
    /* The cut is refined and measured while it is held: the extraction scratch (over 100
     * bytes per triangle of the largest cut) goes. */
    sl_mesh_scratch_shrink(&x->model->scratch);
    if (failed)
        return sl_error_nomem(err, NULL, "a cut of %u expansions", k);
    int finest = k >= x->levels->expansion_count;
    if (!(x->min_part_area > 0) || (finest && x->one_body >= 0))
        return 0;
    int rc = x->one_body < 0 ? learn_one_body(x, &out->mesh, finest, err) : 0;
    if (rc == 0 && !finest && x->one_body)
        rc = refine_drop_parts(&out->mesh, x->min_part_area, x->shard_reach, &out->dropped, err);
    if (rc)
        refine_cut_release(out);
    return rc;
}

/* k within the cap: a model whose every non-empty cut is above the input (a mesh of a few
 * triangles the cells cannot draw with fewer) is left uncapped rather than cut empty. */
static uint32_t capped_k(const refine_cutter *x, uint32_t k, int *capped)
{
    *capped = 0;
    if (!x->cap || x->levels->accumulation[k] <= x->cap)
        return k;
    uint32_t within = sl_lod_expansions_for_triangles(x->levels, x->cap);
    *capped = x->levels->accumulation[within] > 0;
    return *capped ? within : k;
}

int refine_cut_percent(refine_cutter *x, double percent, refine_cut *out, sl_error *err)
{
    int capped;
    uint32_t k = capped_k(x, sl_lod_expansions_for_percent(x->levels, percent), &capped);
    int rc = refine_cut_at(x, k, out, err);
    out->capped = capped;
    return rc;
}

/* A budget cut that lost shards gives their triangles to the body: the k of the budget
 * raised by what was lost is tried, then k is bisected below it (at most REFILL_CUTS more
 * cuts in all) for the largest whose cut without its shards still fits the budget; when
 * they were more than 0.5 % of the budget (a large cut's few specks are not worth it). */
#define REFILL_CUTS 4
#define REFILL_WORTH 200
int refine_cut_within(refine_cutter *x, uint64_t budget, refine_cut *out, sl_error *err)
{
    int capped;
    uint32_t k = capped_k(x, sl_lod_expansions_for_triangles(x->levels, budget), &capped);
    if (capped && x->cap < budget)
        budget = x->cap;
    int rc = refine_cut_at(x, k, out, err);
    out->capped = capped;
    if (rc || out->dropped.triangles * REFILL_WORTH <= budget)
        return rc;
    uint32_t lo = k;
    uint32_t hi = sl_lod_expansions_for_triangles(x->levels, budget + out->dropped.triangles) + 1;
    for (int step = 0; step < REFILL_CUTS && hi - lo > 1; step++) {
        uint32_t at = step == 0 ? hi - 1 : lo + (hi - lo) / 2; /* the raised budget's first */
        refine_cut refill;
        if ((rc = refine_cut_at(x, at, &refill, err))) {
            refine_cut_release(out);
            return rc;
        }
        if (refill.mesh.triangle_count > budget) {
            hi = at;
            refine_cut_release(&refill);
            continue;
        }
        lo = at;
        refill.capped = out->capped;
        refine_cut_release(out);
        *out = refill;
    }
    return 0;
}
