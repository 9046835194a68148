/* export stage internals (export.h). */
#ifndef SCANLOD_STAGES_EXPORT_INTERNAL_H
#define SCANLOD_STAGES_EXPORT_INTERNAL_H

#include <pthread.h>
#include <stdint.h>

#include "core/hash.h"
#include "core/json.h"
#include "geometry/frame_estimate.h"
#include "geometry/mesh.h"
#include "geometry/mesh_distance.h"
#include "geometry/triangle_bvh.h"
#include "pipeline/stage.h"
#include "shim/oiio_shim.h"
#include "levels/level.h"
#include "runtime/lod_model.h"
#include "stages/export/export.h"

/* A generated level as an sl_mesh view (geometry/mesh.h): what the writers and the
 * measurements read. */
sl_mesh sl_export_mesh_view(const sl_lod_mesh *m);

/* Renders the level's PNG thumbnail (geometry/raster.h), upright for a Z-up input. */
int sl_export_thumbnail(const char *path, const sl_lod_mesh *mesh, int size, int z_up,
                        sl_error *err);

/* An item's frame (export_frame.c; docs/metadata.md, "Frames"): units and up axis, each
 * from the item's manifest row, else [export] units/up, else the file's own hints, else
 * estimated from the input's geometry (geometry/frame_estimate.h). `meta` and `input`
 * may be NULL (no row; the input not read). */
typedef struct sl_export_frame {
    char units[4];
    double to_metres;
    const char *units_from; /* "manifest", "config", "file" or "estimated" */
    char up;                /* 'y' or 'z' */
    const char *up_from;
    char units_why[256], up_why[320]; /* how an estimated part was estimated, else "" */
    int estimated;                    /* `estimate` holds the geometry's estimate */
    sl_frame_estimate estimate;
} sl_export_frame;

void sl_export_resolve_frame(const sl_export_config *c, const sl_item_metadata *meta,
                             const sl_mesh *input, sl_export_frame *f);
/* The report's "frame" section, and a WARN line in the log per estimated part. */
void sl_export_report_frame(const sl_export_frame *f, const sl_stage_io *io);

/* The input's texture, ready to bake level atlases from (export_texture.c), and its
 * encoded bytes as the input has them, for the levels that keep its texture coordinates. */
typedef struct sl_export_texture {
    const sl_mesh *input; /* NULL: no texture */
    sl_image image;       /* as stored (sRGB) */
    sl_triangle_bvh bvh;  /* over the input's triangles */
    const void *original; /* the file's (or the embedded) JPEG or PNG bytes; NULL when it
                             is neither (then every level is baked) */
    size_t original_size;
    const char *original_mime; /* "image/jpeg" or "image/png" */
    void *original_owned;      /* what to free: the bytes read from the file */
    uint32_t *chart;           /* per input triangle: its chart of the input's atlas (the
                                  lowest triangle of the region its texture coordinates
                                  join without a seam); with `original` only, and only
                                  when every coordinate lies in [0, 1] (a wrapping, tiled
                                  texture cannot be projected: its levels are baked) */
} sl_export_texture;

/* export_uv.c: each input triangle's chart (see `chart`), OUT: *chart (free() it); 0, or
 * -1 out of memory. */
int sl_export_texture_charts(const sl_mesh *input, uint32_t **chart);
/* The input's texture coordinate at corner k of input triangle `tri` (per corner or per
 * vertex, as the input has them). */
void sl_export_input_uv(const sl_mesh *in, uint32_t tri, int k, double uv[2]);
/* Barycentric weights of p's projection onto the plane of (a, b, c), least squares (1/3
 * each for a degenerate triangle); negative for p beyond an edge: the affine map
 * continued. */
void sl_export_plane_weights(const double p[3], const double a[3], const double b[3],
                             const double c[3], double w[3]);

/* 1 when `input` (read by sl_scan_read from a file in `dir`) has a texture to bake from (a
 * file or an embedded image), else 0 with the reason in `why` (a warning in the report,
 * never a failure). */
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
    void *fallback_image;                   /* a WebP image's JPEG fallback, or NULL */
    size_t fallback_image_size;
    int size, cell;                         /* atlas edge, chart cell edge (texels) */
    double texel_efficiency;                /* texels on the surface / all texels */
} sl_export_baked;

/* Bakes `level`'s atlas, at most `max_size` texels wide: 0, 1 when the level has too many
 * triangles for that atlas (it keeps its vertex colours), or SL_E_NOMEM/SL_E_INTERNAL. */
int sl_export_bake(const sl_export_config *c, const sl_export_texture *src,
                   const sl_lod_mesh *level, int max_size, sl_export_baked *out, sl_error *err);
void sl_export_baked_release(sl_export_baked *b);

/* The level with texture coordinates taken from the input's (export_uv.c): per corner,
 * the input's coordinate where it lies on the input surface, in the chart of the input
 * triangle nearest to its triangle's centre; level vertices whose corners differ are
 * split. OUT: *out without an image (the GLB embeds the input's), *continued the corners
 * that lay across a seam of that chart (their coordinate is the chart's continued). 0 or
 * SL_E_NOMEM. */
int sl_export_project_uvs(const sl_export_texture *src, const sl_lod_mesh *level,
                          sl_export_baked *out, uint64_t *continued, sl_error *err);

/* The input's image scaled down to at most max_edge texels on its longer side (a box
 * filter) and encoded as [export] texture_format says into out->image, out->mime_type
 * (and out->fallback_image), out->size; nothing when the image is no larger (the level
 * embeds the input's bytes). 0, SL_E_NOMEM or the encoder's error. */
int sl_export_texture_scaled(const sl_export_config *c, const sl_export_texture *src,
                             int max_edge, sl_export_baked *out, sl_error *err);

/* 1 when a level with these texture coordinates (the input's, carried by the refine
 * stage) keeps them and the original image in its GLB ([export] texture = keep): the
 * texture has its original JPEG/PNG bytes and every coordinate lies in [0, 1] (the GLB
 * stores them normalised, and samples with CLAMP_TO_EDGE). */
int sl_export_texture_keeps(const sl_export_config *c, const sl_export_texture *t,
                            const float *texcoords, uint64_t vertex_count);

/* The atlas edge for level `name`: [export] texture_sizes, else texture_size. */
int sl_export_texture_size(const sl_export_config *c, const char *name);

/* What became of one level: the facts the summaries, the manifest and the pages show. */
typedef struct sl_export_result {
    uint32_t k;
    uint64_t triangles, vertices;
    uint64_t boundary_edges, nonmanifold_edges;
    uint64_t components;          /* connected parts */
    double largest_area_fraction; /* the largest part's share of the area (0 without area) */
    int watertight, measured;
    double rms, hausdorff, mean; /* fractions of the input's diagonal, when measured */
    double diagonal;             /* the input's bounding-box diagonal (world), when measured */
    sl_glb_stats glb;            /* what the GLB writer did (compression, quantisation) */
    /* The level's texture: 1 a baked atlas, 2 the input's image and texture coordinates
     * kept, 3 the input's image with coordinates projected from the input's
     * (texture_continued corners across a seam), -1 too many triangles for an atlas, 0 no
     * texture. */
    int texture, texture_size, texture_cell;
    uint64_t texture_continued;
    const char *texture_mime;
    uint64_t texture_bytes;
    double texel_efficiency;
    /* The level whose files hold this mesh: this level's own index, or that of another
     * level with the identical mesh (lod100 for a budget clamped at the finest level, say),
     * so the mesh is published once; -1 when the level has no triangles, so no files. */
    int file;
    /* The published level this level's GLB morphs to ([export] morph), or -1. */
    int morph_to;
} sl_export_result;

/* What identifies a generated mesh: counts and the XXH3-128 of every array. Two meshes
 * with equal digests (compared whole, with memcmp) have the same vertices, normals,
 * colours and triangles in the same order, so they would write byte-identical files. */
typedef struct sl_export_digest {
    uint64_t vertices, triangles;
    sl_hash positions, normals, colors, indices;
} sl_export_digest;

sl_export_digest sl_export_digest_mesh(const sl_lod_mesh *m);

/* One distinct mesh's work, what the LOD model's levels and a level list share: its atlas
 * baked (with `texture`; or with `texcoords`, the level's own, the input's image kept when
 * sl_export_texture_keeps says so), its files written as [export] asks under lv->name, its topology
 * and (with `fidelity`, the input's side of the measure made once per item) its distance to
 * the input measured; all of it kept in *row (not k, not file). With
 * `morph_to` (may be NULL) its GLB morphs to that coarser level ([export] morph). */
int sl_export_write_level(const sl_export_config *c, const sl_export_level *lv,
                          const sl_lod_mesh *mesh, const float *texcoords,
                          const sl_lod_mesh *morph_to, const char *extras,
                          const sl_distance_reference *fidelity, const sl_export_frame *frame,
                          const sl_export_texture *texture,
                          const sl_stage_io *io, sl_export_result *row, sl_error *err);

/* A level's facts in its open JSON object in `r`, after its own fields: topology, fidelity,
 * "file" (`file_name`, NULL without triangles), atlas and GLB (with `max_error`, the
 * level's bound before quantisation). */
void sl_export_report_result(const sl_export_config *c, const sl_export_frame *frame,
                             const sl_export_result *row, const char *file_name,
                             double max_error, sl_json *r);

/* Every level of the level list in list_dir (levels/level.h, the refine stage's):
 * written, measured, deduplicated and reported, with the manifest and the pages
 * (export_list.c). `model` says an LOD model is published beside them; `input` (may be
 * NULL) is the scan the pages describe, `fidelity` (may be NULL: not measured) its side of
 * every level's measure. */
int sl_export_level_list(const sl_export_config *c, const char *list_dir, int model,
                         const sl_mesh *input, const sl_distance_reference *fidelity,
                         const sl_export_frame *frame,
                         const sl_export_texture *texture, const sl_stage_io *io,
                         sl_error *err);

/* The size of the level file NAME.EXT this stage wrote, 0 when there is none. */
uint64_t sl_export_file_bytes(const sl_stage_io *io, const char *name, const char *ext);

/* Voyager's derivative qualities used, coarsest first (docs/formats.md, "scene.svx.json"). */
#define SL_EXPORT_QUALITIES 5
extern const char *const sl_export_quality_names[SL_EXPORT_QUALITIES];

/* For each quality, the level whose GLB serves it, or -1 when no level has a GLB. */
void sl_export_map_qualities(const sl_export_config *c, const sl_export_result *results,
                             int level_of_quality[SL_EXPORT_QUALITIES]);

/* What the scene and the pages are made from, once every level is written. */
typedef struct sl_export_item {
    const sl_export_config *c;       /* with the published levels (not intermediates) */
    const sl_level_list *list;       /* their records (the LOD model's size, if any) */
    const sl_mesh *input;            /* NULL when not read or not measured */
    const sl_export_result *results; /* per level of c */
    const int *quality;              /* level of each Voyager quality, or -1 */
    const sl_export_frame *frame;
    const sl_stage_io *io;           /* io->metadata: the item's manifest row, or NULL */
} sl_export_item;

/* The item's title: its manifest row's, else its id. */
const char *sl_export_title(const sl_stage_io *io);

/* scene.svx.json (when GLBs are written) and the report's "files" and "manifest"
 * sections, after every level is written. */
int sl_export_manifest(const sl_export_item *it, sl_error *err);

/* index.html and summary-item.html (the item's section of OUTPUT/summary.html), and with
 * [export] viewer the viewer bundle and NAME.glb.js per GLB (export_html.c). */
int sl_export_html(const sl_export_item *it, sl_error *err);

/* export_levels.c, shared with export_level_list.c: one level's thumbnail as a Markdown
 * image linked relative to OUTPUT/ (a space before all but the first), and
 * summary-item.md written from `text` (an open_memstream buffer, freed; NULL: out of
 * memory). */
void sl_export_md_thumbnail(FILE *md, const char *item, const char *name, int first);
int sl_export_write_summary_item(const sl_stage_io *io, char *text, size_t size, sl_error *err);

#endif
