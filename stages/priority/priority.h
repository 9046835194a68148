/* priority stage (paper 1, section 2.3): octree -> LOD array.
 *
 * Every internal node r gets the paper's area difference
 *     M_r = sum over children s of area(F_MC(s)) - area(F_MC(r)),
 * the triangles' area its expansion adds. Expansion starts at the root; the expandable
 * set holds the frontier nodes none of whose 26 surrounding frontier nodes is coarser
 * (so neighbouring levels never differ by 2 or more); the one with the largest M_r is
 * expanded next (max-heap, ties by node index), and nodes held back by a coarser
 * neighbour wait on it and re-enter the heap when it expands. The LOD array is the
 * expansion order. Each node also gets a geometric error (world units): the largest
 * distance from its children's surface points to its own triangles, so generation can
 * cut by a maximum error. Output: `priority.slpri` (docs/formats.md).
 */
#ifndef SCANLOD_STAGES_PRIORITY_H
#define SCANLOD_STAGES_PRIORITY_H

#include <stdint.h>

#include "pipeline/error.h"
#include "pipeline/stage.h"
#include "runtime/lod_model.h"
#include "runtime/octree.h"

#define SL_PRIORITY_FILE "priority.slpri"

extern const sl_stage sl_priority_stage;

typedef struct sl_priority {
    uint32_t node_count;
    uint32_t expansion_count;
    uint32_t *lod_array;
    float *area_difference; /* per node (0 for leaves) */
    float *node_error;      /* per node, world units (0 for leaves) */
    sl_neighbours neighbours;
} sl_priority;

void sl_priority_release(sl_priority *p);

/* M_r and node errors for every node (OpenMP over nodes). */
int sl_priority_metrics(const sl_octree *t, float *area_difference, float *node_error);

/* The expansion order under the level-difference rule; lod_array holds one entry per
 * internal node. Deterministic. */
int sl_priority_order(const sl_octree *t, const sl_neighbours *nb, const float *area_difference,
                      uint32_t *lod_array, uint32_t *expansion_count, sl_error *err);

int sl_priority_write(const char *path, const sl_priority *p, uint32_t stage_version,
                      sl_error *err);
int sl_priority_read(const char *path, const sl_octree *t, sl_priority *out, sl_error *err);

#endif
