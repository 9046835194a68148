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

/* What became of one level: the facts the summaries, the manifest and the pages show. */
typedef struct sl_export_result {
    uint32_t k;
    uint64_t triangles, vertices;
    uint64_t boundary_edges, nonmanifold_edges;
    int watertight, measured;
    double rms, hausdorff, mean; /* fractions of the input's diagonal, when measured */
    /* The level whose files hold this mesh: this level's own index, or that of another
     * level with the identical mesh (lod100 for a budget clamped at the finest level, say),
     * so the mesh is published once; -1 when the level has no triangles, so no files. */
    int file;
} sl_export_result;

/* The size of the level file NAME.EXT this stage wrote, 0 when there is none. */
uint64_t sl_export_file_bytes(const sl_stage_io *io, const char *name, const char *ext);

/* Voyager's derivative qualities used, coarsest first (docs/formats.md, "scene.svx.json"). */
#define SL_EXPORT_QUALITIES 5
extern const char *const sl_export_quality_names[SL_EXPORT_QUALITIES];

/* For each quality, the level whose GLB serves it, or -1 when no level has a GLB. */
void sl_export_map_qualities(const sl_export_config *c, const sl_export_result *results,
                             int level_of_quality[SL_EXPORT_QUALITIES]);

/* scene.svx.json (when GLBs are written) and the report's "files" and "manifest"
 * sections, after every level is written. */
int sl_export_manifest(const sl_export_config *c, const sl_export_result *results,
                       const int level_of_quality[SL_EXPORT_QUALITIES], const sl_stage_io *io,
                       sl_error *err);

/* index.html and summary-item.html (the item's section of OUTPUT/summary.html), and with
 * [export] viewer the viewer bundle and NAME.glb.js per GLB (export_html.c). */
int sl_export_html(const sl_export_config *c, const sl_lod_model *model, const sl_mesh *input,
                   const sl_export_result *results,
                   const int level_of_quality[SL_EXPORT_QUALITIES], const sl_stage_io *io,
                   sl_error *err);

#endif
