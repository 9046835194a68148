/* segment stage and method (paper 3: Kim, Yun, Lee, "Multi-resolution modeling technique
 * using mesh segmentation"; docs/segmentation.md): a welded triangle mesh -> levels of
 * detail that keep planar parts exact.
 *
 *   segmentation (3.1, eq. 1) -> boundary trimming (3.2, eq. 2) -> plane fit and vertex
 *   selection (3.3, eq. 3-8) -> vertex removal -> retriangulation in each segment's
 *   plane (3.4, constrained Delaunay)
 *
 * Every level uses a subset of the input's vertices (indices into the input, so colours
 * and normals carry over) and is manifold, watertight when the input is, of the same
 * Euler characteristic, with no triangle turned against the input: each is checked, and a
 * segment that would break one is kept as it is. Non-manifold edges and vertices of the
 * input are kept as they are (their vertices never move).
 *
 * Parallel over segments with OpenMP; the result does not depend on the thread count.
 */
#ifndef SCANLOD_STAGES_SEGMENT_H
#define SCANLOD_STAGES_SEGMENT_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "pipeline/stage.h"

/* Which vertices of a segment's interior are removed (paper section 3.3, equation 8). */
enum sl_segment_rule {
    /* Default: keep the vertices far from the retriangulated patch. Greedy insertion: the
     * patch starts as the trimmed boundary, and the interior vertex farthest from it (along
     * the segment's normal) in each triangle is put back while it is farther than
     * max_error; what is never put back is removed. */
    SL_SEGMENT_RULE_ERROR = 0,
    /* Remove the vertices near the fitted plane: q_i <= m_k + alpha s_k, s_k the standard
     * deviation of the squared distances q (the paper's text, its equation read as it says). */
    SL_SEGMENT_RULE_NEAR = 1,
    /* The paper's equation 8 as printed: remove q_i >= m_k + alpha sigma_k, with sigma_k
     * the variance of q as equation 7 prints it (alpha = -1.5 in its experiments). */
    SL_SEGMENT_RULE_PAPER = 2
};

typedef struct sl_segment_config {
    double delta_seg;          /* eq. 1: the largest angle between two triangles of a
                                  segment, degrees, (0, 89]; default 20 */
    uint32_t target_segments;  /* > 0: Min-delta, the smallest delta_seg giving at most this
                                  many segments (delta_seg is then ignored); default 0 */
    double delta_b;            /* eq. 2: a two-segment boundary vertex may go when its
                                  angle is within delta_b of 180 degrees; [0, 180];
                                  default 180: no angle test, the error bound alone
                                  decides (the paper's 20 and 60 stay reachable) */
    int rule;                  /* enum sl_segment_rule; default SL_SEGMENT_RULE_ERROR */
    double alpha;              /* eq. 8 control parameter (rules near and paper); default -1.5 */
    double max_error;          /* rule error: the largest distance of a removed vertex from
                                  the new surface, as a fraction of the bounding-box
                                  diagonal (also bounds boundary trimming); default 0.001 */
    double max_normal_deviation; /* degrees: a new triangle whose normal is farther than this
                                  from the mean input normal at its corners is refused (a
                                  vertex is put back, or the segment kept); default 90 */
    double merge_ratio;        /* budgets: segments are merged down to budget / merge_ratio
                                  (segment_merge.c; 0: never); default 25 */
    double merge_angle;        /* merging keeps every triangle of a segment within this many
                                  degrees of its mean normal, and two parts merge only
                                  when their means are that close, (0, 89]; default 60 */
    uint64_t search_samples;   /* budgets: area samples per surface of the RMS the search of
                                  the trimming bound minimises (0: an estimate from the removed
                                  vertices' distances, faster, less faithful); default 50000 */
} sl_segment_config;

sl_segment_config sl_segment_default_config(void);

/* Checks the ranges above; SL_E_USAGE with a message naming the field. */
int sl_segment_check_config(const sl_segment_config *cfg, sl_error *err);

/* The mesh to simplify: welded (vertices shared by index), triangles counter-clockwise. */
typedef struct sl_segment_input {
    uint64_t vertex_count;
    const float *positions;    /* 3 * vertex_count, world */
    uint64_t triangle_count;
    const uint32_t *triangles; /* 3 * triangle_count, < vertex_count */
} sl_segment_input;

/* What a level is asked to be. Exactly one of the three is used, in this order. */
typedef struct sl_segment_target {
    uint64_t triangles;        /* > 0: at most this many triangles, as close as the search gets */
    double ratio;              /* > 0: at most ratio x input triangles */
    double max_error;          /* > 0: rule error with this max_error (fraction of the
                                  diagonal), no search; 0 with the others 0: cfg->max_error */
} sl_segment_target;

/* Counts of what a level's pass saw and did (the paper's section 4 figures and more). */
typedef struct sl_segment_stats {
    uint32_t segments;            /* after eq. 1 */
    double delta_seg;             /* degrees (Min-delta: the value found) */
    uint64_t input_vertices;      /* vertices the input's triangles use */
    uint64_t removed_vertices;    /* input vertices no output triangle uses */
    uint64_t removed_boundary;    /* of those, two-segment boundary vertices (trimming) */
    uint64_t removed_interior;    /* of those, segment interior vertices */
    uint64_t corners;             /* vertices trimming never removes */
    uint64_t boundary_vertices;   /* two-segment boundary vertices (trimming's candidates) */
    uint64_t interior_vertices;   /* segment interior vertices (equation 8's candidates) */
    uint32_t patches_retriangulated; /* segments given new triangles */
    uint32_t patches_boundary_kept;  /* ... with their boundary untrimmed (a trimmed one failed) */
    uint32_t patches_kept;        /* segments left as they were (fold, refusal, a check) */
    uint32_t patches_folded;      /* of the kept: not one-to-one in projection */
    uint32_t repairs;             /* rounds of the whole-mesh check that kept segments */
    uint32_t search_passes;       /* passes run to reach the target */
    double max_error;             /* the bound used, fraction of the diagonal */
    double tau;                   /* rule error: the score threshold used, world^2 */
    double estimate;              /* RMS distance of the removed vertices to the level,
                                     over all input vertices, fraction of the diagonal */
    int over_budget;              /* the segments' boundaries alone exceed the budget */
    double diagonal;              /* of the input's bounding box, world */
    uint64_t nonmanifold_edges_kept; /* input edges in 3+ triangles, kept as they were */
    int64_t euler_characteristic; /* of the level (equal to the input's) */
    int watertight;               /* every edge in two triangles */
} sl_segment_stats;

typedef struct sl_segment_level {
    uint64_t triangle_count;
    uint32_t *triangles;          /* 3 * triangle_count indices into the input's vertices */
    sl_segment_stats stats;
} sl_segment_level;

void sl_segment_level_release(sl_segment_level *level);

/* The prepared mesh (adjacency, segmentation, loops) many levels are cut from. Opaque. */
typedef struct sl_segment_model sl_segment_model;

/* Builds the model of `in` (borrowed until sl_segment_model_free) for `cfg`'s delta_seg /
 * target_segments. Returns 0, SL_E_BADINPUT (no triangle, an index out of range, a
 * non-finite coordinate, a zero-size bounding box: the message says which), SL_E_USAGE
 * (bad config), SL_E_NOMEM, SL_E_INTERRUPTED. */
int sl_segment_model_build(const sl_segment_config *cfg, const sl_segment_input *in,
                           sl_segment_model **out, sl_progress *progress, sl_error *err);
void sl_segment_model_free(sl_segment_model *model);

/* The segment of each input triangle (triangle_count ids < *segment_count): the segment
 * map. Owned by the model. */
const uint32_t *sl_segment_model_map(const sl_segment_model *model, uint32_t *segment_count);

/* One level (OUT: *level, release with sl_segment_level_release) for `target`, with
 * `cfg`'s delta_b, rule, alpha and max_error (delta_seg is the model's). A triangle
 * budget is met by searching max_error (rule error) or alpha (near and paper rules).
 * Returns 0, SL_E_NOMEM, SL_E_INTERRUPTED, SL_E_INTERNAL (a check found a level the
 * repair could not fix: a bug). */
int sl_segment_model_level(sl_segment_model *model, const sl_segment_config *cfg,
                           const sl_segment_target *target, sl_segment_level *level,
                           sl_progress *progress, sl_error *err);

/* Both in one call: the library entry the standalone command and the stage use. */
int sl_segment_simplify(const sl_segment_config *cfg, const sl_segment_input *in,
                        const sl_segment_target *target, sl_segment_level *level,
                        sl_progress *progress, sl_error *err);

/* --- the stage ([lod] method = segment) ---------------------------------------------- */

/* Reads the range stage's points.slpts, writes into its artifact directory:
 *   a level list (levels/level.h)  a level per rung of the ladder ([levels], a share
 *                   P % = at most P % of the input's triangles), with bound 0 (the segment
 *                   method proves none), which the refine stage takes on;
 *   segments.slsgm  the segment of every input triangle (equation 1) and per segment
 *                   its unit area-weighted normal and area.
 * Options: [segment] (segment_config.c); it also reads [levels]. */
extern const sl_stage sl_segment_stage;

#define SL_SEGMENT_MAP_FILE "segments.slsgm"
#define SL_SEGMENT_MAP_FORMAT_VERSION 1u

#endif
