/* crack stage (paper 1, section 2.4): octree + LOD array -> the LOD model `model.slod`.
 *
 * Cracks open where a cell meets a neighbour one level finer. For every internal node the
 * stage precomputes its transition record: the finer level's signs and crossings on the
 * node's boundary (crack_transitions.c), so that generation draws such a cell with the
 * finer neighbour's points on their shared faces and edges and the surface stays closed,
 * with no geometric search at generation time. With the records in place it computes the
 * accumulation table (triangles after each expansion, counting exactly the cells that
 * generation draws; crack_accumulation.c) and the error table, and writes the complete
 * model. The records' format and their reading at generation belong to the runtime
 * (runtime/lod_model.h); only building them is here.
 */
#ifndef SCANLOD_STAGES_CRACK_H
#define SCANLOD_STAGES_CRACK_H

#include <stdint.h>

#include "core/error.h"
#include "pipeline/stage.h"
#include "runtime/lod_io.h"
#include "runtime/lod_model.h"

extern const sl_stage sl_crack_stage;

/* The crack stage reads no options: its model follows from its inputs alone. The struct
 * keeps the stage face uniform (and C has no empty struct). */
typedef struct sl_crack_config {
    int unused; /* always 0 */
} sl_crack_config;

/* The (empty) section at its defaults (sl_stage_default_config). */
sl_crack_config sl_crack_default_config(void);

/* Gathers every internal node's transition record from the finer level (OpenMP over
 * nodes, deterministic): the 64 finer cells around a node are its own and its neighbours'
 * children, found through `nb` (the priority stage's links of internal nodes; O(1) each)
 * or, with nb NULL and for a node without links, by a search (O(log n)); the records are
 * the same either way. *unresolved = how many edge midpoints and face centres of internal
 * nodes no finer cell has (the report's finer_samples_missing). Returns -1 on OOM. */
int sl_transitions_build(const sl_octree *t, const sl_neighbours *nb, sl_transitions *out,
                         uint64_t *unresolved);

/* Completes a model whose tree, lod_array, neighbours and transitions are set: derives
 * expansion_index, the accumulation table (by drawing the cells each expansion changes)
 * and error_after from the expanded nodes' errors, one per expansion in order (may be
 * NULL: then all zero). It does not lay the cells out for generating meshes: call
 * sl_lod_model_prepare (runtime/lod_model.h) before sl_lod_generate. */
int sl_lod_model_finish(sl_lod_model *m, const float *expansion_error, sl_error *err);

#endif
