/* export stage (paper 1, section 3; ARCHITECTURE section 1): the LOD model -> what users
 * take away, per item: the chosen levels as welded meshes (PLY, GLB with meshoptimizer's
 * vertex order), a thumbnail per level (PNG), the model itself (`model.slod`), and the
 * levels' fidelity against the input surface (RMS and Hausdorff as fractions of the bbox
 * diagonal, from the project's own `compare`) with watertightness, in the report.
 *
 * Levels: every `[export] lod_percents` (paper Table 1: k = P% of the LOD array) and every
 * named triangle budget `[export] budgets` (name:triangles; a budget above the finest level
 * gives the finest, marked "clamped").
 */
#ifndef SCANLOD_STAGES_EXPORT_H
#define SCANLOD_STAGES_EXPORT_H

#include "core/error.h"
#include "pipeline/stage.h"
#include "runtime/lod_mesh.h"

extern const sl_stage sl_export_stage;

/* Writes `mesh` to `path` in the format its extension names (.ply, .glb, .obj).
 * `extras_json` (may be NULL) goes into the GLB's extras. */
int sl_export_write_mesh(const char *path, const sl_lod_mesh *mesh, const char *extras_json,
                         sl_error *err);

#endif
