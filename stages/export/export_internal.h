/* export stage internals (export.h). */
#ifndef SCANLOD_STAGES_EXPORT_INTERNAL_H
#define SCANLOD_STAGES_EXPORT_INTERNAL_H

#include <pthread.h>
#include <stdint.h>

#include "core/hash.h"
#include "core/json.h"
#include "geometry/mesh.h"
#include "geometry/mesh_distance.h"
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
 * fidelity). `cap` > 0 ([export] cap_at_input): no level has more triangles than that, a
 * level whose cut would is cut within it instead. */
int sl_export_levels(const sl_export_config *c, sl_lod_model *model, const sl_mesh *input,
                     uint64_t cap, const sl_export_frame *frame, const sl_export_texture *texture,
                     const sl_stage_io *io, sl_error *err);

/* Shards ([export] min_part_area, export_parts.c): the finest level is one body when its
 * largest part holds at least this share of its area. */
#define SL_EXPORT_ONE_BODY 0.99

/* What sl_export_drop_parts removed from a level. */
typedef struct sl_export_parts {
    uint64_t parts, triangles; /* parts and triangles dropped */
    double area_fraction;      /* their share of the level's area before */
} sl_export_parts;

/* The largest connected part's share of the mesh's area (1 without triangles). */
int sl_export_largest_part(const sl_lod_mesh *mesh, double *fraction /* OUT */, sl_error *err);

/* Drops the parts holding less than `min_fraction` of the mesh's area, never its largest;
 * the kept triangles and vertices stay in their order. 0, or SL_E_NOMEM. */
int sl_export_drop_parts(sl_lod_mesh *mesh, double min_fraction, double reach,
                         sl_export_parts *out /* OUT */, sl_error *err);

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
    sl_export_parts dropped;     /* shards left out ([export] min_part_area) */
    int capped;                  /* cut within the input's count ([export] cap_at_input) */
    /* The level's atlas: 1 baked, -1 too many triangles for it, 0 no texture. */
    int texture, texture_size, texture_cell;
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

/* What cuts an LOD model's levels: the model, whether its finest level is one body
 * (one_body: -1 not known yet, 0 several pieces, 1 one body; start at -1), and the most
 * triangles a level may have (cap, 0 = no cap). */
typedef struct sl_export_cutter {
    const sl_export_config *c;
    sl_lod_model *model;
    int one_body;
    uint64_t cap;
} sl_export_cutter;

/* Level lv's k (paper Table 1's percent or its budget) into row->k; when the cutter has a
 * cap and that cut is above it, the largest k within the cap instead (row->capped), unless
 * no non-empty cut fits the cap (then the level stays as it was). */
void sl_export_level_k(const sl_export_cutter *x, const sl_export_level *lv,
                       sl_export_result *row);

/* The published mesh after k expansions: the cut, less its shards when the rule applies
 * (`dropped`, may be NULL, says what went); `cracks` may be NULL. 0 or SL_E_NOMEM (then
 * nothing is held). */
int sl_export_cut_level(sl_export_cutter *x, uint32_t k, sl_lod_mesh *mesh, uint64_t *cracks,
                        sl_export_parts *dropped, sl_error *err);

/* Level lv's published mesh into *mesh, row->k (set by sl_export_level_k before; a budget
 * or capped level may raise it to refill what its shards cost) and row->dropped. 0 or
 * SL_E_NOMEM. */
int sl_export_cut_row(sl_export_cutter *x, const sl_export_level *lv, sl_export_result *row,
                      sl_lod_mesh *mesh, uint64_t *cracks, sl_error *err);

/* With [export] morph and GLBs written: the published level (rows[j].file == j) next
 * coarser than published level i, the one with the most triangles below i's; else -1. */
int sl_export_morph_coarser(const sl_export_config *c, const sl_export_result *rows, int i);

/* What identifies a generated mesh: counts and the XXH3-128 of every array. Two meshes
 * with equal digests (compared whole, with memcmp) have the same vertices, normals,
 * colours and triangles in the same order, so they would write byte-identical files. */
typedef struct sl_export_digest {
    uint64_t vertices, triangles;
    sl_hash positions, normals, colors, indices;
} sl_export_digest;

sl_export_digest sl_export_digest_mesh(const sl_lod_mesh *m);

/* One level's cut for the export loop (export_cuts.c), made one level ahead of the
 * writes: with more than one thread on a thread of its own while the previous level is
 * written, else when it is finished. The caller fills cutter .. threads once; start sets
 * `at` (a position in `order`), finish waits for it. Then `own` is 1 when `mesh` is level
 * order[at]'s own mesh to write (and `coarser` its morph target's when
 * rows[order[at]].morph_to >= 0), 0 when it shares another level's files or has no
 * triangles (nothing held). */
typedef struct sl_export_cut_job {
    sl_export_cutter *cutter;
    const int *order;          /* the levels in preference order */
    sl_export_result *rows;    /* k set; with morph, file, triangles and morph_to too */
    uint64_t *cracks;
    sl_export_digest *digests; /* per level, filled as levels are cut */
    int morph;                 /* the morph plan made every row's file beforehand */
    int threads;               /* omp_get_max_threads() */
    int at, own;
    sl_lod_mesh mesh, coarser;
    sl_error err;
    pthread_t thread;
    int threaded, pending;
} sl_export_cut_job;

void sl_export_cut_job_start(sl_export_cut_job *j, int at);
/* 0, or the cut's error (SL_E_NOMEM) merged into err; nothing is then held. */
int sl_export_cut_job_finish(sl_export_cut_job *j, sl_error *err);
void sl_export_cut_job_release(sl_export_cut_job *j);
/* Waits for a cut under way and drops what it made; a pending one is not made. Nothing
 * is held after it, whatever state the job was in (a finished or released job: nothing
 * to do). */
void sl_export_cut_job_cancel(sl_export_cut_job *j);

/* One distinct mesh's work, what the LOD model's levels and a level list share: its atlas
 * baked (with `texture`), its files written as [export] asks under lv->name, its topology
 * and (with `input`) fidelity measured; all of it kept in *row (not k, not file). With
 * `morph_to` (may be NULL) its GLB morphs to that coarser level ([export] morph). */
int sl_export_write_level(const sl_export_config *c, const sl_export_level *lv,
                          const sl_lod_mesh *mesh, const sl_lod_mesh *morph_to,
                          const char *extras, const sl_mesh *input,
                          const sl_export_frame *frame, const sl_export_texture *texture,
                          const sl_stage_io *io, sl_export_result *row, sl_error *err);

/* A level's facts in its open JSON object in `r`, after its own fields: topology, fidelity,
 * "file" (`file_name`, NULL without triangles), atlas and GLB (with `max_error`, the
 * level's bound before quantisation). */
void sl_export_report_result(const sl_export_config *c, const sl_export_frame *frame,
                             const sl_export_result *row, const char *file_name,
                             double max_error, sl_json *r);

/* The levels of a level list (levels.sllev in list_dir: the cluster or the segment stage's,
 * stages/cluster/cluster.h, `method` naming it) instead of an LOD model: written, measured,
 * deduplicated and reported like sl_export_levels, with the manifest and the pages
 * (export_level_list.c). */
int sl_export_level_list(const sl_export_config *c, const char *method, const char *list_dir,
                         const char *range_dir, const sl_mesh *input,
                         const sl_export_frame *frame, const sl_export_texture *texture,
                         const sl_stage_io *io, sl_error *err);

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
 * [export] viewer the viewer bundle and NAME.glb.js per GLB (export_html.c). `model` is
 * NULL for a level list (the cluster method): no expansions, no model.slod. */
int sl_export_html(const sl_export_config *c, const sl_lod_model *model, const sl_mesh *input,
                   const sl_export_result *results,
                   const int level_of_quality[SL_EXPORT_QUALITIES], const sl_stage_io *io,
                   sl_error *err);

/* export_levels.c, shared with export_level_list.c: one level's thumbnail as a Markdown
 * image linked relative to OUTPUT/ (a space before all but the first), and
 * summary-item.md written from `text` (an open_memstream buffer, freed; NULL: out of
 * memory). */
void sl_export_md_thumbnail(FILE *md, const char *item, const char *name, int first);
int sl_export_write_summary_item(const sl_stage_io *io, char *text, size_t size, sl_error *err);

#endif
