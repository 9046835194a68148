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
#include "stages/segment/segment.h"

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
    seg_frame *frame;         /* per segment */
    uint8_t *unfit;           /* per segment: enum seg_unfit */
    uint8_t *fixed;           /* per vertex: never removed (corner, anchor, unused) */
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
 * degrees of its mean. OUT: *labels (malloc'd, per triangle), *count. Returns 0 or
 * SL_E_NOMEM. */
int seg_merge(const sl_segment_model *m, uint32_t target, double max_angle, uint32_t **labels,
              uint32_t *count, sl_error *err);

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

/* segment_patch.c */
typedef struct seg_patch_params {
    int rule;                 /* enum sl_segment_rule */
    double alpha;
    double max_error;         /* world units */
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
} seg_patch_result;

/* Per-thread scratch for seg_patch_run. */
typedef struct seg_scratch seg_scratch;
seg_scratch *seg_scratch_new(uint32_t vertex_count);
void seg_scratch_free(seg_scratch *s);

/* Retriangulates segment k with the loops given by `kept` (two-segment vertices) and the
 * fixed vertices. Fills *out (its triangles malloc'd; freed by the caller). */
void seg_patch_run(const sl_segment_model *m, uint32_t k, const uint8_t *kept,
                   const seg_patch_params *p, seg_scratch *s, seg_patch_result *out);

/* segment_flip.c: data-dependent edge flips of one patch's triangulation. */
typedef struct seg_flip_input {
    const double *uv;           /* per point: 2, the projection */
    const double *pos;          /* per point: 3, world (any common origin) */
    const double *h;            /* per point: height along the projection direction */
    const double *point_normal; /* per point: 3, input normal; NULL: no check */
    double cos_max_deviation;
    double max_error;           /* a flip keeps every vertex within max(this, its distance before) */
    uint32_t loop_count;        /* the constrained edges: loops over point ids */
    const uint32_t *loop_start, *loop_points;
    uint32_t cand_count;        /* removed vertices under the triangles */
    const double *cand_uv, *cand_pos;
    const uint32_t *cand_tri;   /* the triangle each lies in, or SEG_NONE */
} seg_flip_input;
/* Flips `triangles` (point ids, counter-clockwise) in place. Returns 0, -1 out of memory. */
int seg_flip_optimize(const seg_flip_input *in, uint32_t *triangles, uint32_t triangle_count,
                      uint64_t *flips);

/* segment_pass.c: one pass over the whole mesh with these parameters, checked and
 * repaired (see there). OUT: *level (stats filled but for search_passes, max_error). */
int seg_run_pass(sl_segment_model *m, const seg_trim_params *trim, const seg_patch_params *patch,
                 sl_segment_level *level, sl_progress *progress, sl_error *err);

#endif
