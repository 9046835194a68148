/* export stage internals (export.h). */
#ifndef SCANLOD_STAGES_EXPORT_INTERNAL_H
#define SCANLOD_STAGES_EXPORT_INTERNAL_H

#include <stdint.h>

#include "geometry/mesh.h"
#include "geometry/triangle_bvh.h"
#include "pipeline/stage.h"
#include "shim/oiio_shim.h"
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

/* The input's texture, ready to bake level atlases from (export_texture.c). */
typedef struct sl_export_texture {
    const sl_mesh *input; /* NULL: no texture */
    sl_image image;       /* as stored (sRGB) */
    sl_triangle_bvh bvh;  /* over the input's triangles */
} sl_export_texture;

/* 1 when `input` (read from a PLY in `dir`) has a texture to bake from, else 0 with the
 * reason in `why` (a warning in the report, never a failure). */
int sl_export_texture_open(const sl_mesh *input, const char *dir, sl_export_texture *t,
                           char *why, size_t why_size);
void sl_export_texture_close(sl_export_texture *t);

/* A level with its own atlas: three vertices per triangle (each triangle is a chart). */
typedef struct sl_export_baked {
    uint64_t vertex_count, triangle_count;
    float *positions, *normals, *texcoords; /* texcoords: OpenGL convention (v up) */
    uint32_t *triangles;
    void *image;                            /* the encoded atlas */
    size_t image_size;
    const char *mime_type;
    int size, cell;                         /* atlas edge, chart cell edge (texels) */
    double texel_efficiency;                /* texels on the surface / all texels */
} sl_export_baked;

/* Bakes `level`'s atlas, at most `max_size` texels wide: 0, 1 when the level has too many
 * triangles for that atlas (it keeps its vertex colours), or SL_E_NOMEM/SL_E_INTERNAL. */
int sl_export_bake(const sl_export_texture *src, const sl_lod_mesh *level, int max_size,
                   int png, int quality, sl_export_baked *out, sl_error *err);
void sl_export_baked_release(sl_export_baked *b);

/* The atlas edge for level `name`: [export] texture_sizes, else texture_size. */
int sl_export_texture_size(const sl_export_config *c, const char *name);

/* Generates, writes and measures every level; fills io->report. `input` may be NULL (no
 * fidelity). */
int sl_export_levels(const sl_export_config *c, sl_lod_model *model, const sl_mesh *input,
                     const sl_export_frame *frame, const sl_export_texture *texture,
                     const sl_stage_io *io, sl_error *err);

/* One level's line of the collection summary. */
typedef struct level_row {
    uint32_t k;
    uint64_t triangles, vertices;
    int watertight, measured, thumbnail;
    double rms, hausdorff; /* fractions of the input's diagonal, when measured */
    double diagonal;       /* the input's, world; when measured */
} level_row;

/* One level, its JSON object open in io->report: its atlas baked (with `texture`), its
 * files written as [export] asks, its topology and (with `input`) fidelity measured, its
 * GLB's quantisation reported on top of `max_error`; *row filled (but k). What the LOD
 * model's levels and a level list share. */
int sl_export_write_level(const sl_export_config *c, const sl_export_level *lv,
                          const sl_lod_mesh *mesh, const char *extras, double max_error,
                          const sl_mesh *input, const sl_export_frame *frame,
                          const sl_export_texture *texture, const sl_stage_io *io,
                          level_row *row, sl_error *err);

/* The levels of a level list (levels.sllev in list_dir: the cluster or the segment stage's,
 * stages/cluster/cluster.h, `method` naming it) instead of an LOD model: written, measured
 * and reported like sl_export_levels (export_level_list.c). */
int sl_export_level_list(const sl_export_config *c, const char *method, const char *list_dir,
                         const char *range_dir, const sl_mesh *input,
                         const sl_export_frame *frame, const sl_export_texture *texture,
                         const sl_stage_io *io, sl_error *err);

#endif
