/* export stage internals (export.h). */
#ifndef SCANLOD_STAGES_EXPORT_INTERNAL_H
#define SCANLOD_STAGES_EXPORT_INTERNAL_H

#include <stdint.h>

#include "geometry/mesh.h"
#include "pipeline/stage.h"
#include "runtime/lod_model.h"
#include "stages/export/export.h"

/* A generated level as an sl_mesh view (geometry/mesh.h): what the writers and the
 * measurements read. */
sl_mesh sl_export_mesh_view(const sl_lod_mesh *m);

/* Renders the level's PNG thumbnail (geometry/raster.h). */
int sl_export_thumbnail(const char *path, const sl_lod_mesh *mesh, int size, sl_error *err);

/* "20,40" and "low:20000,high:500000" -> levels; SL_E_CONFIG on a malformed entry. */
int sl_export_parse_levels(const char *percents, const char *budgets, sl_export_config *c,
                           sl_error *err);

/* Generates, writes and measures every level; fills io->report. `input` may be NULL (no
 * fidelity). */
int sl_export_levels(const sl_export_config *c, sl_lod_model *model, const sl_mesh *input,
                     const sl_stage_io *io, sl_error *err);

#endif
