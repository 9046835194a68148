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
#include "geometry/ply.h"
#include "runtime/lod_io.h"
#include "stages/crack/crack.h"
#include "stages/export/export_internal.h"

/* 5: [export] morph (morph targets in the GLBs). 6: report.json gives each level's
 * connected parts and the largest one's share of the area. 7: the pages name the segment
 * method's levels as such (they said "Clustering levels"). 8: a morphing GLB carries the
 * level cut along the coarser level's edges, so its weight-1 surface lies on it. 9: [export]
 * min_part_area (coarser octree levels leave out shards). 10: [export] cap_at_input (no
 * octree level above the input's triangle count). */
#define EXPORT_STAGE_VERSION 10u

static const sl_option export_options[] = {
    {"export", "lod_percents", SL_OPT_LIST, "20,40,60,80,100", 0, 100, NULL,
     "Levels by LOD percent, as in the paper's Table 1: P% of the LOD array's expansions "
     "of nodes with surface below them are done (empty band cells change nothing and are "
     "not counted; 100 = the finest level). Empty for none."},
    {"export", "budgets", SL_OPT_LIST, "thumb:2000,low:20000,medium:100000,high:500000", 0, 0,
     NULL,
     "Named triangle budgets (name:triangles), as museum web viewers use: the largest level "
     "within each budget. A budget above the finest level gives the finest (\"clamped\" in "
     "the report). A name becomes the level's file names: letters, digits, '.', '_' and '-', "
     "starting with a letter or digit, and no two levels (budgets or lodP percents) alike. "
     "Empty for none."},
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
     "Length unit of the input coordinates. GLBs are written in metres, as glTF requires. "
     "auto = a 'comment units NAME' line in the PLY header if there is one, else the "
     "coordinates are taken as metres (written as given). A value given here wins over "
     "the header."},
    {"export", "up", SL_OPT_ENUM, "auto", 0, 0, "auto|y|z",
     "The input's up axis. GLBs are written +Y up, as glTF requires (z: (x, y, z) -> "
     "(x, z, -y)), and thumbnails look at the model upright. auto = a 'comment up AXIS' "
     "line in the PLY header if there is one, else y (as given). A value given here wins "
     "over the header."},
    {"export", "texture", SL_OPT_ENUM, "auto", 0, 0, "auto|none",
     "auto: a textured input (PLY 'comment TextureFile' with texture coordinates) gives "
     "every level a baked texture atlas, embedded in its GLB as baseColorTexture with "
     "TEXCOORD_0 (PLY files keep vertex colours). none: vertex colours only."},
    {"export", "texture_format", SL_OPT_ENUM, "jpeg", 0, 0, "jpeg|png",
     "Image format of the atlases (glTF core: JPEG or PNG)."},
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
     "distance). At weight 0 the GLB is the level, at weight 1 it lies on the coarser level. "
     "The coarsest level has none. Works with every compression (Draco: the target is "
     "stored uncompressed beside the Draco stream)."},
    {"export", "min_part_area", SL_OPT_DOUBLE, "0.01", 0, 0.5, NULL,
     "Shards (docs/lod.md): when the octree's finest level is one body (its largest part "
     "holds 99 % of its area), each coarser published level leaves out the connected parts "
     "holding less than this share of its area (never its largest): pieces of thin parts "
     "that the coarse cells cut loose, and specks. 0 publishes every part as the octree "
     "draws it (paper 1). The finest level, and every level of a scan of several pieces, "
     "keep all their parts; the levels of the cluster and segment methods are never "
     "changed."},
    {"export", "shard_reach", SL_OPT_DOUBLE, "2", 0, 1e9, NULL,
     "A small part (min_part_area) is left out only when each of its vertices lies within "
     "this many of the level's mean triangle edges of the rest of the level: a speck the "
     "body covers goes, a part farther out (the only surface there) stays."},
    {"export", "cap_at_input", SL_OPT_BOOL, "true", 0, 0, NULL,
     "No octree level has more triangles than the input mesh: a level whose cut would "
     "(lod100 when the finest level outgrows the input, a budget above the input's count) is "
     "the largest cut within the input's count instead ('capped' in the report). false: "
     "lod100 is the octree's finest level whatever its count (paper 1). Point clouds have no "
     "count to keep to, nor a mesh so small that no non-empty cut fits its count; the "
     "cluster and segment methods never exceed it."},
    SL_OPTION_END,
};

static int export_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_export_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    int rc = sl_export_parse_levels(sl_config_string(cfg, "export", "lod_percents"),
                                    sl_config_string(cfg, "export", "budgets"), c, err);
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
    c->texture = !strcmp(sl_config_string(cfg, "export", "texture"), "auto");
    c->texture_png = !strcmp(sl_config_string(cfg, "export", "texture_format"), "png");
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
    c->min_part_area = sl_config_double(cfg, "export", "min_part_area");
    c->shard_reach = sl_config_double(cfg, "export", "shard_reach");
    c->cap_at_input = sl_config_bool(cfg, "export", "cap_at_input");
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

void sl_export_resolve_frame(const sl_export_config *c, const sl_mesh *input,
                             sl_export_frame *f)
{
    const char *hint = input && input->units[0] ? input->units : NULL;
    snprintf(f->units, sizeof f->units, "%.3s", c->units_to_metres > 0 ? c->units : hint ? hint : "m");
    f->to_metres = sl_export_unit_metres(f->units);
    f->units_from = c->units_to_metres > 0 ? "config" : hint ? "header" : "default";
    char up_hint = input ? input->up_axis : 0;
    f->up = c->up ? c->up : up_hint ? up_hint : 'y';
    f->up_from = c->up ? "config" : up_hint ? "header" : "default";
}

static int export_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const sl_export_config *c = config;
    /* [lod] method = cluster or segment: that stage's level list instead of an LOD model. */
    const char *list_method = sl_stage_dir(io, "cluster")   ? "cluster"
                              : sl_stage_dir(io, "segment") ? "segment"
                                                            : NULL;
    const char *list_dir = list_method ? sl_stage_dir(io, list_method) : NULL;
    char model_path[PATH_MAX], published[PATH_MAX];
    sl_lod_model model;
    sl_lod_model_init(&model);
    int rc = list_dir ? 0 : sl_stage_path(model_path, io->in_dir, SL_MODEL_FILE, err);
    if (rc == 0 && !list_dir)
        rc = sl_stage_path(published, io->out_dir, SL_MODEL_FILE, err);
    if (rc == 0 && !list_dir)
        rc = sl_lod_model_open(model_path, &model, err);
    if (rc)
        return rc;
    /* The input: the surface the fidelity is measured against, and its header's unit
     * and up-axis hints. The range stage already validated it. */
    sl_mesh input;
    sl_mesh_init(&input);
    int have_input = 0, measure = 0;
    if (c->fidelity || !c->units_to_metres || !c->up || c->texture || c->cap_at_input) {
        sl_error ierr;
        sl_error_init(&ierr);
        have_input = sl_ply_read(io->source_path, NULL, &input, NULL, NULL, &ierr) == 0;
        /* A point cloud has nothing to compare surfaces with. */
        measure = c->fidelity && have_input && input.triangle_count > 0 &&
                  sl_mesh_check_surface(&input, NULL, &ierr) == 0;
    }
    sl_export_frame frame;
    sl_export_resolve_frame(c, have_input ? &input : NULL, &frame);
    sl_json_object_begin(io->report, "frame");
    sl_json_string(io->report, "units", frame.units);
    sl_json_string(io->report, "units_from", frame.units_from);
    sl_json_double(io->report, "to_metres", frame.to_metres);
    sl_json_string(io->report, "up", frame.up == 'z' ? "z" : "y");
    sl_json_string(io->report, "up_from", frame.up_from);
    sl_json_object_end(io->report);
    sl_export_texture texture;
    memset(&texture, 0, sizeof texture);
    if (c->texture && have_input && input.texture_file[0]) {
        char dir[PATH_MAX], why[1024];
        snprintf(dir, sizeof dir, "%s", io->source_path);
        char *slash = strrchr(dir, '/'); /* the PLY's directory */
        if (!slash)
            snprintf(dir, sizeof dir, ".");
        else
            slash[slash == dir] = '\0';
        sl_json_object_begin(io->report, "texture");
        sl_json_string(io->report, "file", input.texture_file);
        if (sl_export_texture_open(&input, dir, &texture, why, sizeof why)) {
            sl_json_u64(io->report, "width", (uint64_t)texture.image.width);
            sl_json_u64(io->report, "height", (uint64_t)texture.image.height);
        } else {
            sl_json_string(io->report, "warning", why);
        }
        sl_json_object_end(io->report);
    }
    /* Past here the input's surface is read only to measure the levels or to bake its
     * texture: otherwise it goes now, not after the levels (at 20 M triangles a mesh of
     * 360 MB was held beside the model and the two levels in flight for nothing). */
    uint64_t input_triangles = input.triangle_count;
    if (!measure && !texture.input)
        sl_mesh_release(&input);
    if (list_dir) {
        rc = sl_export_level_list(c, list_method, list_dir, sl_stage_dir(io, "range"),
                                  measure ? &input : NULL, &frame,
                                  texture.input ? &texture : NULL, io, err);
    } else {
        rc = sl_link_or_copy(model_path, published, err);
        if (rc == 0)
            rc = sl_export_levels(c, &model, measure ? &input : NULL,
                                  c->cap_at_input && have_input ? input_triangles : 0, &frame,
                                  texture.input ? &texture : NULL, io, err);
    }
    sl_export_texture_close(&texture);
    sl_mesh_release(&input);
    sl_lod_model_release(&model);
    return rc;
}

const sl_stage sl_export_stage = {
    .name = "export",
    .methods = SL_METHODS_ALL,
    .description = "LOD model -> meshes (PLY, GLB), thumbnails, fidelity report (paper 1 3)",
    .version = EXPORT_STAGE_VERSION,
    .options = export_options,
    .configure = export_configure,
    .release_config = free,
    .run = export_run,
    .publish = 1,
};
