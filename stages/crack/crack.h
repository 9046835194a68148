/* crack stage (paper 1, section 2.4): octree + LOD array -> the LOD model `model.slod`.
 *
 * Cracks open where a cell meets a neighbour one level finer. For every internal node the
 * stage precomputes its transition record: the finer level's signs and crossings on the
 * node's boundary (runtime/lod_tables.c), so that generation draws such a cell with the
 * finer neighbour's points on their shared faces and edges and the surface stays closed,
 * with no geometric search at generation time. With the records in place it computes the
 * accumulation table (triangles after each expansion, counting exactly the cells that
 * generation draws) and the error table, and writes the complete model.
 */
#ifndef SCANLOD_STAGES_CRACK_H
#define SCANLOD_STAGES_CRACK_H

#include "pipeline/stage.h"

#define SL_MODEL_FILE "model.slod"

extern const sl_stage sl_crack_stage;

#endif
