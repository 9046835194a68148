/* priority stage (paper 1, section 2.3): octree -> LOD array.
 *
 * Every internal node r gets a key, and the LOD array is the order in which the nodes are
 * expanded. Expansion starts at the root; the expandable set holds the frontier nodes
 * none of whose 26 surrounding frontier nodes is coarser (so neighbouring levels never
 * differ by 2 or more); the one with the largest key is expanded next (max-heap, ties by
 * node index). A node held back by a coarser neighbour waits on it and re-enters the heap
 * when it expands; under the error-driven metrics it also lends that neighbour its key
 * (so a costly region is never stuck behind a cheap coarse cell).
 *
 * The key ([priority] metric, docs/lod.md "The priority metric"): by default the squared
 * distance between the node's triangles and the finest surface under it that expanding
 * it removes, per triangle it adds; "hausdorff": the largest such distance in its
 * subtree; "area": the paper's area difference
 *     M_r = sum over children s of area(F_MC(s)) - area(F_MC(r)).
 * Each node also gets a geometric error (world units): the largest distance from its
 * children's surface points to its own triangles, so generation can cut by a maximum
 * error. Output: `priority.slpri` (docs/formats.md).
 */
#ifndef SCANLOD_STAGES_PRIORITY_H
#define SCANLOD_STAGES_PRIORITY_H

#include <stdint.h>

#include "core/error.h"
#include "pipeline/stage.h"
#include "runtime/lod_model.h"
#include "runtime/octree.h"

#define SL_PRIORITY_FILE "priority.slpri"

extern const sl_stage sl_priority_stage;

typedef struct sl_priority {
    uint32_t node_count;
    uint32_t expansion_count;
    uint32_t *lod_array;
    float *area_difference; /* per node (0 for leaves); the stage's own, not in the file */
    float *node_error;      /* per node, world units (0 for leaves); the stage's own */
    float *expansion_error; /* per expansion: the expanded node's error (the file's;
                               what the crack stage reads for error_after) */
    /* The internal nodes' links alone, the leaves' masks 0 (a leaf's cell never meets a
     * finer one, so nothing asks for its neighbours; sl_neighbours_build_internal); the
     * whole table's count in neighbour_links. */
    sl_neighbours neighbours;
    uint64_t neighbour_links;
} sl_priority;

void sl_priority_release(sl_priority *p);


/* What orders the expansions ([priority] metric; docs/lod.md "The priority metric"). */
typedef enum sl_priority_metric {
    SL_PRIORITY_ERROR,     /* squared distance to the finest surface removed per triangle
                              added (greedy rate-distortion); the default */
    SL_PRIORITY_HAUSDORFF, /* largest distance to the finest surface, saturated over the
                              subtree */
    SL_PRIORITY_AREA,      /* the paper's M_r, with the paper's waiting rule */
    SL_PRIORITY_QEF,       /* dual vertices (octree.h): the quadric error an expansion
                              removes per triangle it adds */
    SL_PRIORITY_AUTO       /* qef for an octree with dual vertices, else error */
} sl_priority_metric;

/* The resolved [priority] section (options: stages/priority/priority_stage.c). */
typedef struct sl_priority_config {
    sl_priority_metric metric; /* what orders the expansions */
} sl_priority_config;

/* The section at its option table's defaults (sl_stage_default_config). */
sl_priority_config sl_priority_default_config(void);

/* "error", "hausdorff", "area", "qef", "auto" -> metric; -1 for another name. And back. */
int sl_priority_metric_parse(const char *name);
const char *sl_priority_metric_name(sl_priority_metric metric);

/* M_r and node errors for every node (OpenMP over nodes). With dual vertices the node
 * error is the RMS distance its quadric stands for, sqrt(node_error / node_area) (the
 * marching-cube error does not describe what is drawn). */
int sl_priority_metrics(const sl_octree *t, float *area_difference, float *node_error);

/* The expansion key of every node under `metric` (OpenMP over nodes; AREA copies
 * area_difference; QEF needs the tree's dual vertices). Deterministic. -1 on OOM. */
int sl_priority_keys(const sl_octree *t, sl_priority_metric metric, const float *area_difference,
                     float *key);

/* The expansion order under the level-difference rule: the largest key first among the
 * expandable nodes; with `inherit`, a node held back by a coarser neighbour lends it its
 * key. lod_array holds one entry per internal node. Deterministic. */
int sl_priority_order(const sl_octree *t, const sl_neighbours *nb, const float *key, int inherit,
                      uint32_t *lod_array, uint32_t *expansion_count, sl_error *err);

int sl_priority_write(const char *path, const sl_priority *p, uint32_t stage_version,
                      sl_error *err);
int sl_priority_read(const char *path, const sl_octree *t, sl_priority *out, sl_error *err);

#endif
