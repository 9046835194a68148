/* export stage (paper 1, section 3; docs/levels.md): the published levels -> what users
 * take away, per item: each level of the level list the refine stage made (levels/level.h,
 * found by the artifact, not by a stage's name) as a welded mesh (PLY, GLB with
 * meshoptimizer's vertex order), a thumbnail per level (PNG), the LOD model `model.slod`
 * when an earlier stage made one (any cut in O(m) for viewers), and the levels' fidelity
 * against the input surface (RMS and Hausdorff as fractions of the bbox diagonal, from the
 * project's own `compare`) with watertightness, in the report. Levels whose meshes are
 * identical (the scan at the top asked by a percent and a budget) are published once,
 * under one of their names (docs/formats.md).
 *
 * Also per item: `scene.svx.json` (a Smithsonian Voyager scene of the GLBs, mapped to
 * Voyager's qualities by triangle count) and `index.html` (the item's page with a 3D view
 * of each level), and the item's sections of the collection's summaries.
 */
#ifndef SCANLOD_STAGES_EXPORT_H
#define SCANLOD_STAGES_EXPORT_H

#include <stdint.h>

#include "core/error.h"
#include "formats/glb.h"
#include "pipeline/stage.h"
#include "runtime/lod_mesh.h"

extern const sl_stage sl_export_stage;

#define SL_EXPORT_MAX_LEVELS 32

/* One published level as the pages and the manifest name it. */
typedef struct sl_export_level {
    char name[32];  /* its file names: "lod20", the budget's name ("medium") */
    char method[16]; /* what made it: scan, octree, segment, cluster */
    int by_percent; /* asked as a share (lodP) or a share of expansions (kP) */
    double percent; /* by_percent: in [0, 100] */
    uint64_t budget; /* the triangles it was asked for (0: an expansions level) */
    int scan;        /* the scan itself, unchanged (no error to show) */
} sl_export_level;

/* How a level's GLB is written (docs/glb.md): the encoding, and the map from the input's
 * frame to glTF's (metres, +Y up), baked into the positions and normals. */
typedef struct sl_export_glb {
    sl_glb_options options;
    double to_metres; /* metres per input unit (mm: 0.001) */
    int z_up;         /* the input's up is +Z: (x, y, z) -> (x, z, -y), a rotation */
    const float *texcoords; /* per vertex (OpenGL convention) with options.image, or NULL */
    /* The next coarser level, or NULL: the GLB then carries a morph target moving each
     * vertex to its closest point on this level's surface (docs/morphing.md). */
    const sl_lod_mesh *morph_to;
    int morph_tears; /* tear what the refinement cannot mend (SL_MORPH_REFINE_TEAR) */
} sl_export_glb;

/* [export] texture: none; bake every level's atlas; keep (default): a level with the
 * input's texture coordinates keeps them and the input's image, the others are baked. */
enum sl_export_texture_mode {
    SL_EXPORT_TEXTURE_NONE = 0,
    SL_EXPORT_TEXTURE_BAKE = 1,
    SL_EXPORT_TEXTURE_KEEP = 2
};

/* [export] texture_format: how the images scanlod encodes (baked atlases, images scaled
 * to a level's size) are stored; an image embedded as the input has it stays as it is. */
enum sl_export_image_format {
    SL_EXPORT_IMAGE_JPEG = 0,
    SL_EXPORT_IMAGE_PNG = 1,
    SL_EXPORT_IMAGE_WEBP = 2 /* EXT_texture_webp, with a JPEG fallback unless told not */
};

/* The resolved [export] section (options: stages/export/export_stage.c). */
typedef struct sl_export_config {
    int level_count;                            /* the published levels, once read */
    sl_export_level levels[SL_EXPORT_MAX_LEVELS];
    int write_ply, write_glb, write_obj;        /* [export] formats */
    int thumbnail_size;                         /* PNG edge in pixels; 0 = none */
    int fidelity;                               /* measure every level against the input */
    uint64_t fidelity_samples;                  /* area samples per surface for that */
    sl_glb_options glb;                         /* compression, quantize, *_bits */
    double units_to_metres;                     /* [export] units; 0 = auto (the header) */
    char units[8];                              /* its name: "auto", "mm", ... */
    char up;                                    /* [export] up: 'y', 'z', or 0 = auto */
    int texture;                                /* [export] texture: enum sl_export_texture_mode */
    int texture_format;                         /* enum sl_export_image_format */
    int texture_webp_fallback;                  /* webp: a JPEG beside it */
    int texture_quality;                        /* JPEG quality */
    int texture_size;                           /* atlas edge of levels not listed below */
    char texture_sizes[256];                    /* "name:edge,..." */
    int viewer; /* index.html gets a 3D view per level: viewer bundle + NAME.glb.js copies */
    int morph;  /* each published level's GLB morphs to the next coarser published level */
    int morph_tears; /* [export] morph_tears: exact weight 1, cracks in between */
} sl_export_config;

/* The section at its option table's defaults (sl_stage_default_config). */
sl_export_config sl_export_default_config(void);
/* How a GLB is written at the [export] defaults, the input taken as metres, +Y up. */
sl_export_glb sl_export_default_glb(void);

/* Writes `mesh` to `path` in the format its extension names (.ply, .glb, .obj).
 * `extras_json` (may be NULL) goes into the GLB's extras. A GLB is written per `glb` (which
 * a GLB needs: sl_export_default_glb() for the [export] defaults), in meshoptimizer's
 * vertex-cache and fetch order, and `stats` (OUT, may be NULL) says what it holds; PLY and
 * OBJ keep the input's units and axes (`glb` may be NULL for them). */
int sl_export_write_mesh(const char *path, const sl_lod_mesh *mesh, const char *extras_json,
                         const sl_export_glb *glb, sl_glb_stats *stats, sl_error *err);

/* Metres per unit of `name` ("mm", "cm", "m", "in", "ft"), or 0 for another name. */
double sl_export_unit_metres(const char *name);

#endif
