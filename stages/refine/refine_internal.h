/* refine stage internals (refine.h). */
#ifndef SCANLOD_STAGES_REFINE_INTERNAL_H
#define SCANLOD_STAGES_REFINE_INTERNAL_H

#include <stdint.h>

#include "core/json.h"
#include "geometry/mesh.h"
#include "levels/level.h"
#include "pipeline/stage.h"
#include "runtime/lod_mesh.h"
#include "runtime/lod_model.h"
#include "stages/range/range.h"
#include "stages/refine/refine.h"

/* --- the octree's cuts (refine_octree.c, refine_shards.c) ----------------------------- */

/* Shards (refine_shards.c; docs/lod.md "Shards"): the finest cut is one body when its
 * largest part holds at least this share of its area. */
#define SL_REFINE_ONE_BODY 0.99

/* What sl_refine_drop_parts removed from a cut. */
typedef struct refine_parts {
    uint64_t parts, triangles; /* parts and triangles dropped */
    double area_fraction;      /* their share of the cut's area before */
} refine_parts;

/* The largest connected part's share of the mesh's area (1 without triangles). */
int refine_largest_part(const sl_lod_mesh *mesh, double *fraction /* OUT */, sl_error *err);

/* Drops the parts holding less than `min_fraction` of the mesh's area that lie within
 * `reach` mean edges of the rest, never its largest; the kept triangles and vertices stay
 * in their order. 0, or SL_E_NOMEM. */
int refine_drop_parts(sl_lod_mesh *mesh, double min_fraction, double reach,
                      refine_parts *out /* OUT */, sl_error *err);

/* What cuts the model's levels: the model (held whole, or read by prefixes from `file`:
 * then `model` is the prefix last reached, lod_prefix.h), its level tables (the whole
 * model's either way), whether its finest cut is one body (-1 not known yet, 0 several
 * pieces, 1 one body), the most triangles a cut may have (cap, 0 = none), and the shard
 * rule. */
typedef struct refine_cutter {
    sl_lod_model *model;
    struct sl_lod_file *file;
    const sl_lod_model *levels;
    int one_body;
    uint64_t cap;
    double min_part_area, shard_reach;
} refine_cutter;

/* One octree cut as published before any refinement. */
typedef struct refine_cut {
    uint32_t k;          /* expansions */
    int capped;          /* held within the input's count (cap) */
    uint64_t cracks;     /* cells the crack patching could not close */
    refine_parts dropped;
    sl_lod_mesh mesh;
} refine_cut;

/* The cut after k expansions, less its shards when the rule applies. 0 or SL_E_NOMEM. */
int refine_cut_at(refine_cutter *x, uint32_t k, refine_cut *out, sl_error *err);
/* The largest cut within `budget` triangles (within the cap), with the triangles its
 * shards had given back to the body. 0 or SL_E_NOMEM. */
int refine_cut_within(refine_cutter *x, uint64_t budget, refine_cut *out, sl_error *err);
/* The cut after `percent` % of the LOD array (paper 1, Table 1), within the cap. */
int refine_cut_percent(refine_cutter *x, double percent, refine_cut *out, sl_error *err);
void refine_cut_release(refine_cut *c);

/* --- what the levels are made from (refine_stage.c) ------------------------------------ */

typedef struct refine_item {
    const sl_refine_config *c;
    const sl_stage_io *io;
    sl_pointset points;          /* the range stage's welded mesh or point set */
    sl_mesh surface;             /* a view of it: what every level is fitted and measured to */
    int is_mesh;                 /* it has triangles */
    int input_watertight;        /* the mesh input is closed (every edge in two triangles) */
    int input_one_body;          /* its largest part holds SL_REFINE_ONE_BODY of its area */
    double diagonal;             /* its bounding-box diagonal, world */
    uint64_t input_triangles;    /* what a share of the input is of: the mesh's triangles, or
                                    for a point set the octree's finest cut */
    uint64_t collapse_bricks;    /* the collapses' brick size (0: whole) */
    sl_lod_model model;          /* the octree's, when an upstream stage made one: opened
                                    when the first rung wants a cut of it (refine_model),
                                    whole for a point set, else read by prefixes
                                    (cutter.file) */
    int have_model;              /* an upstream stage made one (open once cutter.levels is
                                    set) */
    const char *model_dir;       /* ... in this stage folder */
    uint32_t model_expansions;   /* its level tables' size, read at the item's opening */
    uint64_t model_triangles;    /* its finest cut's triangles */
    refine_cutter cutter;
    struct refine_method_list {  /* the segment and cluster methods' level lists */
        const char *method, *dir;
        sl_level_list list;
    } methods[2];
    int method_count;
    sl_level scan_chain;         /* best: the last scan candidate before its fit */
    struct refine_raw_cut {      /* the last octree cut measured before its collapse: the
                                    next rung's is often the same cut (capped at the
                                    input's count), measured once */
        int valid;
        uint32_t k;
        uint64_t triangles;
        double rms, hausdorff, largest_part;
        int watertight;
    } raw_cut;
    struct sl_fit_reference *fit_reference; /* the input prepared for fits, on the first */
    struct sl_distance_reference *distance_reference; /* ... for measures, on the first */
} refine_item;

/* The item's model opened (once; no-op when open): a scan's top levels, which get no
 * octree candidate, are made without it held (refine_stage.c). */
int refine_model(refine_item *it, sl_error *err);

/* Whether rung r (of `target` triangles) gets an octree candidate: always but beside the
 * scan simplified to the count ([lod] method = best on a mesh, [refine] collapse on) above
 * [refine] octree_max_share of the input's count (docs/levels.md). */
int refine_octree_wanted(const refine_item *it, const sl_rung *r, uint64_t target);

/* The scan itself as rung r's level (its record and mesh). */
int refine_scan_level(refine_item *it, const sl_rung *r, uint64_t target, sl_level *lv,
                      sl_error *err);

/* --- candidates (refine_candidates.c) --------------------------------------------------- */

typedef struct refine_candidate {
    sl_level level;            /* record and mesh */
    uint64_t base_triangles;   /* what the method gave before the collapse */
    double seconds;            /* wall time to make it (method's cut + collapse + fit) */
    int measured;
    double rms, hausdorff;     /* fractions of the diagonal, when measured (after the
                                  collapse, before the fit: only the chosen is fitted) */
    int fitted;                /* the fit ran on it (the chosen one, and a close rival) */
    int outranked;             /* measured before its collapse, already farther from the
                                  input than the scan collapsed allows: left uncollapsed,
                                  above its count (its figures are those before) */
    double rms_collapsed;      /* when it was fitted to be compared: its RMS before the fit */
    double rms_uncollapsed;    /* when it was measured before its collapse: that RMS */
    int watertight;            /* its topology, when measured */
    double largest_part;       /* the largest connected part's share of its area */
    double fit_rms_before, fit_rms_after; /* the fit's own estimate, world (0: no fit) */
    int capped;                /* octree: the cut was held within the input's count */
    uint64_t strict_triangles;  /* where the collapse keeping the topology stopped, when that
                                   was above the count and it was made again relaxed */
    uint64_t relaxed_collapses; /* ... its collapses the strict rules refuse (0: topology kept) */
    refine_parts dropped;      /* octree: the shards its cut left out */
} refine_candidate;

void refine_candidate_release(refine_candidate *c);

/* The candidates for rung r (target = its count, 0 for an expansions rung) into cands
 * (room for SL_REFINE_MAX_CANDIDATES), *count set; the chosen one's index in *chosen. */
#define SL_REFINE_MAX_CANDIDATES 4
int refine_make_candidates(refine_item *it, const sl_rung *r, uint64_t target,
                           refine_candidate *cands, int *count, int *chosen, sl_error *err);

/* Brings a candidate's level to `target` triangles by quadric edge collapse, as [refine]
 * collapse asks (refine_collapse.c); under best, a scan candidate is kept as the chain's. */
int refine_collapse(refine_item *it, uint64_t target, refine_candidate *cand, sl_error *err);
/* Fits the (chosen) candidate's vertices to the input, as [refine] fit asks. */
int refine_fit(refine_item *it, refine_candidate *cand, sl_error *err);

/* The report's entry of one rung's candidates (refine_stage.c). */
void refine_report_candidates(sl_json *r, const refine_candidate *cands, int count, int chosen);

#endif
