/* refine stage: every method's levels -> the published levels (docs/levels.md).
 *
 * For each rung of the ladder ([levels], levels/ladder.h) the stage makes the level the
 * export publishes:
 *   - a mesh input's rung asking for its whole count or more is the scan itself
 *     ([levels] top = scan): welded, its own vertices and colours;
 *   - else each candidate the item has: the octree's cut (from model.slod, at
 *     [levels] oversample times the count, less the shards coarse cells cut loose), the
 *     segment or cluster method's level of that name, and under [lod] method = best the
 *     scan simplified; each brought to the rung's exact count by quadric edge collapse
 *     ([refine] collapse; geometry/qem_simplify.h) and its vertices fitted to the input
 *     surface ([refine] fit; geometry/surface_fit.h);
 *   - with several candidates, each is measured against the input and the most faithful
 *     (the least RMS distance) is published; every candidate's count, RMS, Hausdorff
 *     distance and time are in the report.
 * An expansions rung (paper 1, Table 1) is the octree's cut as the paper makes it. With
 * collapse and fit off, every level is the method's own (the papers' behaviour).
 * Output: a level list (levels/level.h) in the stage's folder, the ladder's order.
 */
#ifndef SCANLOD_STAGES_REFINE_H
#define SCANLOD_STAGES_REFINE_H

#include <stdint.h>

#include "levels/ladder.h"
#include "pipeline/stage.h"

extern const sl_stage sl_refine_stage;

/* The resolved [refine] section, with the ladder and the method it serves. */
typedef struct sl_refine_config {
    sl_ladder ladder;        /* [levels] */
    int best;                /* [lod] method = best: the scan simplified is a candidate */
    int collapse;            /* quadric edge collapse to the rung's count */
    int relax_topology;      /* ... giving up the topology when it alone stops above it */
    int64_t collapse_brick_triangles; /* ... by bricks of this many from a larger level
                                         (0: whole; SL_REFINE_BRICKS_BY_BUDGET: by the
                                         stage's memory budget, refine_internal.h) */
    double octree_max_share; /* beside the scan simplified, an octree candidate only for a
                                level of at most this share of the input's count */
    int fit;                 /* vertices fitted to the input surface */
    int fit_rounds;          /* the fit's projection and solve rounds */
    double fit_floor;        /* no fit for a level measured within this of the input
                                (fraction of the diagonal) */
    uint64_t select_samples; /* area samples per surface when candidates are compared */
    double min_part_area;    /* octree cuts: parts below this share of the area go */
    double shard_reach;      /* ... when within this many mean edges of the rest */
    int cap_at_input;        /* octree cuts: never above the input mesh's count */
} sl_refine_config;

/* The section at its option tables' defaults (sl_stage_default_config). */
sl_refine_config sl_refine_default_config(void);

/* [refine] collapse_brick_triangles = -1 (the default): by the stage's memory budget. A
 * collapse of the whole level holds about 180 bytes per triangle of the level collapsed
 * from (geometry/qem_simplify.h) beside the input and its measures' reference: with the
 * scan's top rungs collapsed from the scan, the stage peaked at 255-275 bytes per input
 * triangle (the 20 M torus: 5,140-5,490 MB, docs/bricks.md). An item whose input times
 * SL_REFINE_WHOLE_BYTES is over the budget has its collapses made by bricks of
 * SL_REFINE_BUDGET_BRICK triangles (docs/simplify.md "By bricks"); every other item's are
 * whole, as before: bricks cost up to 19 % of the RMS on an open scan. */
#define SL_REFINE_BRICKS_BY_BUDGET (-1)
#define SL_REFINE_WHOLE_BYTES 300.0
#define SL_REFINE_BUDGET_BRICK 1000000u

/* The brick size an item's collapses use: `configured` ([refine]
 * collapse_brick_triangles) when not SL_REFINE_BRICKS_BY_BUDGET (0: whole), else by the
 * budget (above; 0 MB: unknown, whole). `scanlod plan` asks it too. */
uint64_t sl_refine_collapse_bricks(int64_t configured, uint64_t input_triangles,
                                   uint64_t memory_budget_mb);

#endif
