/* export stage entry: levels, files, fidelity and the summary row (export.h). */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "geometry/mesh_distance.h"
#include "formats/scan_read.h"
#include "formats/scan_texture.h"
#include "levels/level.h"
#include "runtime/lod_io.h"
#include "stages/export/export_internal.h"

/* 5: [export] morph (morph targets in the GLBs). 6: report.json gives each level's
 * connected parts and the largest one's share of the area. 7: the pages name the segment
 * method's levels as such (they said "Clustering levels"). 8: a morphing GLB carries the
 * level cut along the coarser level's edges, so its weight-1 surface lies on it. 9: [export]
 * min_part_area (coarser octree levels leave out shards). 10: [export] cap_at_input (no
 * octree level above the input's triangle count). 11: the levels are the refine stage's
 * level list for every method; normals from each level's own faces. 12: the item's manifest
 * row (titles, credit, frame), an estimated frame when nobody gives it, pages for curators,
 * the Voyager scene's meta. 13: [export] texture = keep (default): a level with the input's
 * texture coordinates embeds the input's image instead of a baked atlas. 14: the morph
 * refinement bounds how far a vertex travels and tears only with [export] morph_tears;
 * texture coordinates projected from the input's; texture_format = webp. */
#define EXPORT_STAGE_VERSION 14u

static const sl_option export_options[] = {
    {"export", "formats", SL_OPT_LIST, "ply,glb", 0, 0, "ply|glb|obj",
     "Mesh files written per level: any of ply, glb, obj (empty: none, only thumbnails and "
     "the report)."},
    {"export", "thumbnail_size", SL_OPT_INT, "256", 0, 4096, NULL,
     "Edge of the square PNG thumbnail rendered per level, in pixels; 0 = none."},
    {"export", "fidelity", SL_OPT_BOOL, "true", 0, 0, NULL,
     "Measure every level against the input surface (symmetric Hausdorff and RMS distance, "
     "fractions of the input's bounding-box diagonal). Inputs without faces are not "
     "measured."},
    {"export", "fidelity_samples", SL_OPT_INT, "200000", 1000, 100000000, NULL,
     "Area samples per surface for the fidelity measurement."},
    {"export", "compression", SL_OPT_ENUM, "meshopt", 0, 0, "meshopt|draco|none",
     "GLB compression (docs/glb.md): meshopt = EXT_meshopt_compression (meshoptimizer's "
     "vertex and index codecs, octahedral normals; fast to decode, small after HTTP gzip), "
     "draco = KHR_draco_mesh_compression (smallest raw files, slower to decode), none."},
    {"export", "quantize", SL_OPT_BOOL, "true", 0, 0, NULL,
     "KHR_mesh_quantization in meshopt and uncompressed GLBs: integer positions, normals "
     "and texture coordinates at the bits below (Draco always quantises, to the same "
     "bits). false = float attributes."},
    {"export", "position_bits", SL_OPT_INT, "14", 8, 16, NULL,
     "Bits per position coordinate (gltfpack's default 14). The grid step s is the largest "
     "bounding-box extent / (2^bits - 1); no vertex moves more than sqrt(3)/2 s, and that "
     "bound is added to the level's error in the report."},
    {"export", "normal_bits", SL_OPT_INT, "8", 4, 16, NULL,
     "Bits per normal component (gltfpack's default 8)."},
    {"export", "color_bits", SL_OPT_INT, "12", 8, 16, NULL,
     "Bits of the linear vertex colours (glTF's COLOR_0 is linear; 8 bits of linear light "
     "change dark sRGB bytes by up to 3 steps, 12 keep every byte within half a step)."},
    {"export", "texcoord_bits", SL_OPT_INT, "12", 8, 16, NULL,
     "Bits per texture coordinate (gltfpack's default 12)."},
    {"export", "units", SL_OPT_ENUM, "auto", 0, 0, "auto|mm|cm|m|in|ft",
     "Length unit of the input coordinates, for every item (docs/metadata.md, \"Frames\"). "
     "GLBs are written in metres, as glTF requires, and the pages give errors in mm. An "
     "item's row in the collection manifest wins over this; auto = the file's own hint (a "
     "PLY 'comment units NAME', glTF's metres), else estimated from the bounding box "
     "(flagged as such in the report, the page and the log)."},
    {"export", "up", SL_OPT_ENUM, "auto", 0, 0, "auto|y|z",
     "The input's up axis, for every item. GLBs are written +Y up, as glTF requires (z: "
     "(x, y, z) -> (x, z, -y)), and thumbnails look at the model upright. An item's row in "
     "the collection manifest wins over this; auto = the file's own hint (a PLY 'comment "
     "up AXIS', glTF's +Y), else estimated from the scan's base (flagged as such in the "
     "report, the page and the log)."},
    {"export", "texture", SL_OPT_ENUM, "keep", 0, 0, "keep|bake|none|auto",
     "A textured input (PLY 'comment TextureFile', OBJ's map_Kd, a glTF baseColor texture, "
     "with texture coordinates) gives each level's GLB a baseColorTexture with TEXCOORD_0 "
     "(PLY files keep vertex colours). keep: a level made of the scan's own vertices (the "
     "scan at the top, the scan simplified by the refine stage) keeps their texture "
     "coordinates and embeds the input's JPEG/PNG unchanged; the others take coordinates "
     "projected from the input's (docs/glb.md) and embed its image, scaled down to the "
     "level's texture_sizes / texture_size when larger. "
     "bake: every level gets a baked atlas. none: vertex colours only. auto: keep (the "
     "old name)."},
    {"export", "texture_format", SL_OPT_ENUM, "jpeg", 0, 0, "jpeg|png|webp",
     "Image format of the images scanlod encodes: baked atlases and images scaled down to a "
     "level's size (an image embedded as the input has it stays as it is). jpeg and png are "
     "glTF core; webp (EXT_texture_webp; the food vessel's 512 and 1024 px images 11-12 % "
     "smaller than JPEG at the same texture_quality) comes with a JPEG fallback for viewers "
     "without WebP (texture_webp_fallback)."},
    {"export", "texture_webp_fallback", SL_OPT_BOOL, "true", 0, 0, NULL,
     "With texture_format = webp: each GLB also carries the image as a JPEG, which viewers "
     "without WebP draw (EXT_texture_webp used, not required). false: the WebP alone "
     "(EXT_texture_webp required): the smallest files, for viewers that read WebP (three.js, "
     "Voyager, current browsers)."},
    {"export", "texture_quality", SL_OPT_INT, "90", 1, 100, NULL, "JPEG quality of the atlases."},
    {"export", "texture_sizes", SL_OPT_LIST, "thumb:512,low:1024,medium:2048,high:4096", 0, 0,
     NULL,
     "Atlas edge in pixels per level name (name:pixels), like Voyager's derivative ladder. "
     "A level with few triangles gets a smaller atlas (chart cells of at most 64 texels)."},
    {"export", "texture_size", SL_OPT_INT, "2048", 64, 8192, NULL,
     "Atlas edge of the levels texture_sizes does not name (the lodP levels)."},
    {"export", "viewer", SL_OPT_BOOL, "true", 0, 0, NULL,
     "With glb in formats: the item's index.html (and the collection's summary.html) show "
     "each level in an interactive 3D view that needs no network and works from a local "
     "file. This adds the viewer script (about 1 MB) and each GLB again as a script "
     "(NAME.glb.js, a third larger than the GLB) to every item."},
    {"export", "morph", SL_OPT_BOOL, "false", 0, 0, NULL,
     "Each published level's GLB carries one glTF morph target (docs/morphing.md) that "
     "moves every vertex to its closest point on the next coarser published level, so a "
     "viewer can blend between levels instead of popping (the 3D views do, by camera "
     "distance). At weight 0 the GLB is the level, at weight 1 it lies on the coarser level "
     "(see morph_tears for the few triangles the cut cannot bring onto it). "
     "The coarsest level has none. Works with every compression (Draco: the target is "
     "stored uncompressed beside the Draco stream)."},
    {"export", "morph_tears", SL_OPT_BOOL, "false", 0, 0, NULL,
     "With morph: where the morph refinement cannot cut a level's triangle along the "
     "coarser level (a fold of the closest-point map, a thin part), tear it so that weight "
     "1 lies exactly on the coarser level, at the price of cracks and of vertices that "
     "travel farther mid-blend. false: leave it whole, its corners on their closest "
     "points; the blend then comes closer to the coarser level at every weight, and at "
     "weight 1 those few triangles stand off it by morph_unresolved_world in report.json "
     "(docs/morphing.md)."},
    SL_OPTION_END,
};

static int export_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_export_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    int rc = 0;
    /* The config checked every element against ply|glb|obj; the canonical list is
     * "a,b,c", so a name is in it when it is a whole element. */
    char formats[64];
    snprintf(formats, sizeof formats, ",%s,", sl_config_string(cfg, "export", "formats"));
    c->write_ply = strstr(formats, ",ply,") != NULL;
    c->write_glb = strstr(formats, ",glb,") != NULL;
    c->write_obj = strstr(formats, ",obj,") != NULL;
    c->thumbnail_size = (int)sl_config_int(cfg, "export", "thumbnail_size");
    c->fidelity = sl_config_bool(cfg, "export", "fidelity");
    c->fidelity_samples = (uint64_t)sl_config_int(cfg, "export", "fidelity_samples");
    const char *compression = sl_config_string(cfg, "export", "compression");
    c->glb = sl_glb_default_options();
    c->glb.compression = !strcmp(compression, "meshopt") ? SL_GLB_MESHOPT
                         : !strcmp(compression, "draco") ? SL_GLB_DRACO : SL_GLB_UNCOMPRESSED;
    c->glb.quantize = sl_config_bool(cfg, "export", "quantize");
    c->glb.position_bits = (int)sl_config_int(cfg, "export", "position_bits");
    c->glb.normal_bits = (int)sl_config_int(cfg, "export", "normal_bits");
    c->glb.color_bits = (int)sl_config_int(cfg, "export", "color_bits");
    c->glb.texcoord_bits = (int)sl_config_int(cfg, "export", "texcoord_bits");
    snprintf(c->units, sizeof c->units, "%s", sl_config_string(cfg, "export", "units"));
    c->units_to_metres = sl_export_unit_metres(c->units); /* 0 for auto */
    const char *up = sl_config_string(cfg, "export", "up");
    c->up = !strcmp(up, "auto") ? 0 : up[0];
    const char *texture = sl_config_string(cfg, "export", "texture");
    c->texture = !strcmp(texture, "none")   ? SL_EXPORT_TEXTURE_NONE
                 : !strcmp(texture, "bake") ? SL_EXPORT_TEXTURE_BAKE
                                            : SL_EXPORT_TEXTURE_KEEP;
    const char *format = sl_config_string(cfg, "export", "texture_format");
    c->texture_format = !strcmp(format, "png")    ? SL_EXPORT_IMAGE_PNG
                        : !strcmp(format, "webp") ? SL_EXPORT_IMAGE_WEBP
                                                  : SL_EXPORT_IMAGE_JPEG;
    c->texture_webp_fallback = sl_config_bool(cfg, "export", "texture_webp_fallback");
    c->texture_quality = (int)sl_config_int(cfg, "export", "texture_quality");
    c->texture_size = (int)sl_config_int(cfg, "export", "texture_size");
    snprintf(c->texture_sizes, sizeof c->texture_sizes, "%s",
             sl_config_string(cfg, "export", "texture_sizes"));
    for (const char *p = c->texture_sizes; *p && rc == 0;) { /* name:pixels, 64..8192 */
        size_t n = strcspn(p, ",");
        const char *colon = memchr(p, ':', n);
        size_t digits = colon ? strspn(colon + 1, "0123456789") : 0;
        long v = colon ? strtol(colon + 1, NULL, 10) : 0;
        if (!colon || colon == p || colon + 1 + digits != p + n || v < 64 || v > 8192)
            rc = sl_error_set(err, SL_E_CONFIG, 0, "[export] texture_sizes",
                              "'%.*s' is not name:pixels with 64 <= pixels <= 8192", (int)n, p);
        p += n + (p[n] == ',');
    }
    c->viewer = sl_config_bool(cfg, "export", "viewer");
    c->morph = sl_config_bool(cfg, "export", "morph");
    c->morph_tears = sl_config_bool(cfg, "export", "morph_tears");
    if (rc) {
        free(c);
        return rc;
    }
    *out = c;
    return 0;
}

sl_export_config sl_export_default_config(void)
{
    sl_export_config c;
    sl_stage_default_config(&sl_export_stage, &c, sizeof c);
    return c;
}

sl_export_glb sl_export_default_glb(void)
{
    sl_export_glb g = {sl_export_default_config().glb, 1.0, 0, NULL, NULL, 0};
    return g;
}

/* The input's texture, when it has one and [export] texture is not none (a warning in the
 * report when it cannot be read). */
static void open_texture(const sl_export_config *c, const sl_mesh *input, int have_input,
                         const sl_stage_io *io, sl_export_texture *texture)
{
    memset(texture, 0, sizeof *texture);
    if (!c->texture || !have_input || !sl_scan_has_texture(input))
        return;
    char dir[PATH_MAX], why[1600], name[300];
    sl_scan_directory_of(io->source_path, dir, sizeof dir); /* the input's directory */
    sl_json_object_begin(io->report, "texture");
    sl_json_string(io->report, "file", sl_scan_texture_name(input, name, sizeof name));
    if (sl_export_texture_open(input, dir, texture, why, sizeof why)) {
        sl_json_u64(io->report, "width", (uint64_t)texture->image.width);
        sl_json_u64(io->report, "height", (uint64_t)texture->image.height);
        if (texture->original) {
            sl_json_string(io->report, "mime_type", texture->original_mime);
            sl_json_u64(io->report, "image_bytes", (uint64_t)texture->original_size);
        }
    } else {
        sl_json_string(io->report, "warning", why);
    }
    sl_json_object_end(io->report);
}

/* The earlier stages' artifacts the export publishes, found by what they are: the last
 * level list (the refine stage's) and an LOD model, if any. */
static int find_inputs(const sl_stage_io *io, const char **list_dir, const char **model_dir,
                       sl_error *err)
{
    *list_dir = *model_dir = NULL;
    for (const struct sl_stage_dir_entry *u = io->upstream; u && u->stage; u++) {
        char path[PATH_MAX];
        if (sl_level_list_present(u->dir))
            *list_dir = u->dir;
        if (sl_stage_path(path, u->dir, SL_MODEL_FILE, err) == 0 && access(path, F_OK) == 0)
            *model_dir = u->dir;
    }
    if (!*list_dir)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "no earlier stage made a level list");
    return 0;
}

static int export_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const sl_export_config *c = config;
    const char *list_dir, *model_dir;
    int rc = find_inputs(io, &list_dir, &model_dir, err);
    if (rc)
        return rc;
    if (model_dir) { /* viewers cut any level from it in O(m) */
        char model_path[PATH_MAX], published[PATH_MAX];
        rc = sl_stage_path(model_path, model_dir, SL_MODEL_FILE, err);
        if (rc == 0)
            rc = sl_stage_path(published, io->out_dir, SL_MODEL_FILE, err);
        if (rc == 0)
            rc = sl_link_or_copy(model_path, published, err);
        if (rc)
            return rc;
    }
    /* The input: the surface the fidelity is measured against, and its header's unit
     * and up-axis hints. The range stage already validated it. */
    sl_mesh input;
    sl_mesh_init(&input);
    int have_input = 0, measure = 0;
    if (c->fidelity || !c->units_to_metres || !c->up || c->texture) {
        sl_error ierr;
        sl_error_init(&ierr);
        have_input = sl_scan_read(io->source_path, NULL, &input, NULL, NULL, &ierr) == 0;
        /* A point cloud has nothing to compare surfaces with. */
        measure = c->fidelity && have_input && input.triangle_count > 0 &&
                  sl_mesh_check_surface(&input, NULL, &ierr) == 0;
    }
    sl_export_frame frame;
    sl_export_resolve_frame(c, io->metadata, have_input ? &input : NULL, &frame);
    sl_export_report_frame(&frame, io);
    sl_export_texture texture;
    open_texture(c, &input, have_input, io, &texture);
    /* Past here the input's surface is read only to measure the levels or to bake its
     * texture: otherwise it goes now, not after the levels. */
    if (!measure && !texture.input)
        sl_mesh_release(&input);
    /* The input's side of every level's measure (its tree and samples), made once. */
    sl_distance_reference *fidelity = NULL;
    if (measure) {
        sl_mesh_distance_config dc = sl_mesh_distance_default_config();
        dc.samples = c->fidelity_samples;
        rc = sl_distance_reference_build(&input, &dc, &fidelity, err);
    }
    if (rc == 0)
        rc = sl_export_level_list(c, list_dir, model_dir != NULL, measure ? &input : NULL,
                                  fidelity, &frame, texture.input ? &texture : NULL, io, err);
    sl_distance_reference_free(fidelity);
    sl_export_texture_close(&texture);
    sl_mesh_release(&input);
    return rc;
}

const sl_stage sl_export_stage = {
    .name = "export",
    .methods = SL_METHODS_ALL,
    .description = "published levels -> meshes (PLY, GLB), thumbnails, fidelity, pages, "
                   "Voyager scene (paper 1 3)",
    .version = EXPORT_STAGE_VERSION,
    .options = export_options,
    .configure = export_configure,
    .release_config = free,
    .run = export_run,
    .publish = 1,
    .reads_metadata = 1, /* titles and credit on its pages and scene, the frame */
};
