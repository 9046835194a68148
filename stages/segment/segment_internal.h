/* The segment method's parts (segment.h; docs/segmentation.md):
 *   segment_model.c  adjacency, segmentation, loops, per-segment frames, chains
 *   segment_trim.c   boundary trimming of the chains (paper 3.2, eq. 2)
 *   segment_patch.c  one segment: vertex selection (3.3, eq. 3-8) and retriangulation (3.4)
 *   segment_pass.c   one pass over all segments, the whole-mesh checks, the level search
 *   segment_stage.c  the stage entry and its files
 */
#ifndef SCANLOD_STAGES_SEGMENT_INTERNAL_H
#define SCANLOD_STAGES_SEGMENT_INTERNAL_H

#include <stdint.h>

#include "geometry/mesh_adjacency.h"
#include "geometry/region_grow.h"
#include "geometry/segment_loops.h"
#include "levels/ladder.h"
#include "pipeline/config.h"
#include "stages/segment/segment.h"

/* The stage's resolved config (segment_config.c): the method's section first (what
 * sl_segment_default_config copies), then the ladder it builds. */
typedef struct sl_segment_stage_config {
    sl_segment_config seg;
    sl_ladder ladder;
} sl_segment_stage_config;

extern const sl_option sl_segment_options[];
int sl_segment_configure(const sl_config *cfg, void **out, sl_error *err);

#define SEG_NONE UINT32_MAX

/* Why a segment is left as it is from the start. */
enum seg_unfit {
    SEG_FIT = 0,
    SEG_UNFIT_NO_NORMAL,   /* zero area, or a degenerate triangle */
    SEG_UNFIT_NO_OUTER,    /* no loop of positive area (closed or strongly curved patch) */
    SEG_UNFIT_TOPOLOGY,    /* not a disc with holes (Euler characteristic != 2 - loops) */
    SEG_UNFIT_FOLD,        /* a triangle turns over in the segment's plane */
    SEG_UNFIT_OVERLAP,     /* its loops overlap in that plane (the patch winds over itself) */
    SEG_UNFIT_TRIVIAL      /* nothing to remove: every vertex fixed, no interior vertex */
};

typedef struct seg_frame {
    double normal[3];   /* unit, area-weighted normal of the segment's triangles */
    double u[3], v[3];  /* u x v = normal */
    double origin[3];   /* centroid of the segment's vertices */
} seg_frame;

struct sl_segment_model {
    uint32_t vertex_count, triangle_count;
    const float *positions;
    const uint32_t *triangles;
    double diagonal;
    sl_mesh_adjacency adj;
    int borrowed_adjacency;   /* a relabelled model shares its base's adjacency */
    sl_segmentation seg;
    sl_segment_loops loops;
    uint32_t *seg_tri_start;  /* segment_count + 1, into seg_tris */
    uint32_t *seg_tris;       /* triangles by segment, ascending */
    uint32_t *by_size;        /* segments, the most triangles first (ties: lower id): the
                                 order parallel loops over segments hand them out in, so the
                                 largest do not come last */
    seg_frame *frame;         /* per segment */
    uint8_t *unfit;           /* per segment: enum seg_unfit */
    uint8_t *fixed;           /* per vertex: never removed (corner, anchor, unused) */
    double *vertex_normal;    /* per vertex: 3, the input's unit area-weighted normal */
    uint32_t *chain_start;    /* chain_count + 1, into chain_vertices */
    uint32_t *chain_vertices; /* each chain: fixed vertex, two-segment vertices, fixed vertex */
    uint32_t (*chain_segments)[2]; /* the two segments (lower id first) */
    uint32_t chain_count;
    uint32_t *seg_chain_start;  /* segment_count + 1, into seg_chains */
    uint32_t *seg_chains;       /* the chains of each segment (each chain under both) */
    uint64_t used_vertices;
    uint64_t input_boundary_edges, input_nonmanifold_edges, input_inconsistent_edges;
    uint64_t input_nonmanifold_vertices;
    int64_t input_euler;
};

/* segment_model.c */
void seg_sub(const float *a, const float *b, double out[3]); /* a - b in double */
/* A model of the same mesh with other labels (taken: freed with the model), sharing the
 * base's adjacency: the base must outlive it. */
int seg_model_relabel(const sl_segment_model *base, uint32_t *labels, uint32_t count,
                      sl_segment_model **out, sl_error *err);

/* segment_merge.c: merges adjacent segments of `m`, the cheapest first (see there), until
 * at most `target` remain or no merge keeps every normal of a segment within max_angle
 * degrees of its mean; only segments with allowed[k] (NULL: all) take part. OUT: *labels
 * (malloc'd, per triangle, renumbered by first triangle), *count. Returns 0 or
 * SL_E_NOMEM. */
int seg_merge(const sl_segment_model *m, uint32_t target, double max_angle,
              const uint8_t *allowed, uint32_t **labels, uint32_t *count, sl_error *err);

/* segment_trim.c: kept[v] = 1 for every two-segment vertex a pass keeps, given which
 * segments may be trimmed (trimmable[k]) and each chain's level (0: max_error, 1 and 2:
 * a quarter and a sixteenth of it, SEG_CHAIN_KEEP: untrimmed); fixed vertices are not
 * touched. */
#define SEG_CHAIN_KEEP 3
typedef struct seg_trim_params {
    int paper;          /* paper mode: eq. 2 at the original neighbours, every candidate goes */
    double delta_b;     /* degrees */
    double max_error;   /* world units (error mode) */
} seg_trim_params;
void seg_trim_chains(const sl_segment_model *m, const seg_trim_params *p,
                     const uint8_t *trimmable, const uint8_t *chain_level, uint8_t *kept);

/* The sum of squared distances of the chain vertices `kept` leaves out to the chords
 * that replace them (world^2). */
double seg_chain_residual(const sl_segment_model *m, const uint8_t *kept);

/* segment_patch.c */
typedef struct seg_patch_params {
    int rule;                 /* enum sl_segment_rule */
    double alpha;
    double max_error;         /* world units: the flips' bound (rule error) */
    double tau;               /* rule error: insert while a triangle's score exceeds it (world^2) */
    int record;               /* rule error: record the insertions' scores */
    int probe;                /* a budget pass asked only whether it fits: when the bases
                                 alone exceed the budget it stops there, with an empty level
                                 and stats.over_budget (the full pass would be over too) */
    double cos_max_deviation; /* cos of max_normal_deviation */
} seg_patch_params;

enum seg_patch_status {
    SEG_PATCH_OK = 0,
    SEG_PATCH_REFUSED,  /* the triangulation refused the polygon (crossing, fold, duplicate) */
    SEG_PATCH_TURNED,   /* a new triangle deviates from the input's normals beyond the bound */
    SEG_PATCH_NOMEM
};

typedef struct seg_patch_result {
    int status;                /* enum seg_patch_status */
    uint32_t triangle_count;
    uint32_t *triangles;       /* global vertex ids */
    uint32_t kept_interior;    /* interior vertices kept */
    uint32_t interior;         /* interior vertices of the segment */
    uint32_t problem[4];       /* SEG_PATCH_REFUSED: the global vertices the triangulation
                                  named (crossing edges, a folded triangle), or SEG_NONE */
    uint32_t base_triangles;   /* rule error: triangles before any insertion */
    double residual;           /* rule error: sum of squared distances of the removed
                                  interior vertices to their triangles (world^2) */
    double *record;            /* rule error with record: each insertion's score (owned) */
    uint32_t record_count;
} seg_patch_result;

/* Per-thread scratch for seg_patch_run. */
typedef struct seg_scratch seg_scratch;
seg_scratch *seg_scratch_new(uint32_t vertex_count);
void seg_scratch_free(seg_scratch *s);

/* Retriangulates segment k with the loops given by `kept` (two-segment vertices) and the
 * fixed vertices. Fills *out (its triangles malloc'd; freed by the caller). */
void seg_patch_run(const sl_segment_model *m, uint32_t k, const uint8_t *kept,
                   const seg_patch_params *p, seg_scratch *s, seg_patch_result *out);

/* segment_refine.c: greedy insertion with data-dependent flips (see there). Slots are
 * the patch's vertex indices; positions relative to the segment's frame origin. */
typedef struct seg_refine seg_refine;
typedef struct seg_refine_input {
    const double *uv, *pos, *h, *normal; /* per slot: 2, 3, 1, 3 (input normal) */
    double cos_max_deviation;
    double flip_height;        /* a flip moves the surface by at most this (world) */
    uint32_t slot_count;
    uint32_t triangle_count;   /* the initial triangulation, in slots, counter-clockwise */
    const uint32_t *triangles;
    uint32_t candidate_count;  /* the removed vertices (slots) and the triangle each is in */
    const uint32_t *candidates, *candidate_tri;
} seg_refine_input;
seg_refine *seg_refine_new(void);
void seg_refine_free(seg_refine *r);
int seg_refine_start(seg_refine *r, const seg_refine_input *in); /* 0, -1 out of memory */
/* Inserts until the worst score is at most tau. record (may be NULL, room for every
 * candidate): the score of each insertion's triangle, in order. inserted (may be NULL):
 * the slots put back. Returns 0 or -1. */
int seg_refine_run(seg_refine *r, double tau, double *record, uint32_t *record_count,
                   uint32_t *inserted, uint32_t *inserted_count);
uint32_t seg_refine_triangles(const seg_refine *r, const uint32_t **triangles);
double seg_refine_residual(const seg_refine *r); /* sum of the triangles' scores */
/* Consistency (for the tests): triangles not counter-clockwise, twins that do not match,
 * vertices outside the triangle that holds them. 0 when all is well. */
uint64_t seg_refine_check(const seg_refine *r);
/* A triangle failing the normal check (no vertex was left to fix it): its corners. */
int seg_refine_turned(const seg_refine *r, uint32_t corners[3]);

/* segment_pass.c: one pass over the whole mesh with these parameters, checked and
 * repaired (see there). With a budget (rule error), patch->tau is where the insertions
 * are first recorded down to, and the pass picks the tau that fits the budget.
 * OUT: *level (stats filled but for search_passes, max_error). */
int seg_run_pass(sl_segment_model *m, const seg_trim_params *trim, const seg_patch_params *patch,
                 uint64_t budget, sl_segment_level *level, sl_progress *progress, sl_error *err);

#endif
