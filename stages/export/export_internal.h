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

/* One level's line of the collection summary. */
typedef struct level_row {
    uint32_t k;
    uint64_t triangles, vertices;
    int watertight, measured, thumbnail;
    double rms, hausdorff; /* fractions of the input's diagonal, when measured */
} level_row;

/* Writes lv->name.{ply,glb,obj,png} of `mesh`, as [export] formats and thumbnail_size ask. */
int sl_export_write_files(const sl_export_config *c, const sl_export_level *lv,
                          const sl_lod_mesh *mesh, const char *extras, const sl_stage_io *io,
                          sl_error *err);

/* Edge topology and (with `input`) fidelity of `mesh` into the open object r and *row. */
int sl_export_measure_level(const sl_export_config *c, const sl_mesh *input,
                            const sl_lod_mesh *mesh, const sl_stage_io *io, sl_json *r,
                            level_row *row, sl_error *err);

/* The levels of a level list (the cluster stage's, stages/cluster/cluster.h) instead of an
 * LOD model: written, measured and reported like sl_export_levels (export_level_list.c). */
int sl_export_level_list(const sl_export_config *c, const char *cluster_dir,
                         const char *range_dir, const sl_mesh *input, const sl_stage_io *io,
                         sl_error *err);

#endif
