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

/* Renders the level's PNG thumbnail (geometry/raster.h), upright for a Z-up input. */
int sl_export_thumbnail(const char *path, const sl_lod_mesh *mesh, int size, int z_up,
                        sl_error *err);

/* An item's frame: what [export] units/up say, else the input header's hints, else the
 * coordinates as given (metres, +Y up). `input` may be NULL (no header read). */
typedef struct sl_export_frame {
    char units[4];
    double to_metres;
    const char *units_from; /* "config", "header" or "default" */
    char up;                /* 'y' or 'z' */
    const char *up_from;
} sl_export_frame;

void sl_export_resolve_frame(const sl_export_config *c, const sl_mesh *input,
                             sl_export_frame *f);

/* "20,40" and "low:20000,high:500000" -> levels; SL_E_CONFIG on a malformed entry. */
int sl_export_parse_levels(const char *percents, const char *budgets, sl_export_config *c,
                           sl_error *err);

/* Generates, writes and measures every level; fills io->report. `input` may be NULL (no
 * fidelity). */
int sl_export_levels(const sl_export_config *c, sl_lod_model *model, const sl_mesh *input,
                     const sl_export_frame *frame, const sl_stage_io *io, sl_error *err);

#endif
