/* One published level's work in the export stage: its files, atlas, measures and report
 * entry (export.h). */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "core/atomicfile.h"
#include "core/log.h"
#include "core/markdown.h"
#include "geometry/mesh_distance.h"
#include "stages/export/export_internal.h"

/* The level's GLB geometry: the level itself; with a baked atlas its per-triangle charts
 * (three vertices per triangle) with texture coordinates and the image; with coordinates
 * projected from the input's, the level split at its seams and the input's image; with
 * the input's texture kept, the level with its own texture coordinates and the input's
 * image. */
/* The image a level's GLB embeds: the one scanlod encoded for it (baked, or scaled to the
 * level's size; with a WebP's JPEG fallback), else the input's own bytes. */
static void glb_image(const sl_export_baked *baked, const sl_export_texture *texture,
                      sl_export_glb *glb)
{
    int own = baked && baked->image;
    glb->options.image = own ? baked->image : texture->original;
    glb->options.image_size = own ? baked->image_size : texture->original_size;
    glb->options.image_mime_type = own ? baked->mime_type : texture->original_mime;
    glb->options.fallback_image = own ? baked->fallback_image : NULL;
    glb->options.fallback_image_size = own ? baked->fallback_image_size : 0;
}

static sl_lod_mesh glb_geometry(const sl_lod_mesh *mesh, const sl_export_baked *baked,
                                const float *kept_texcoords, const sl_export_texture *texture,
                                sl_export_glb *glb)
{
    if (kept_texcoords) {
        glb->texcoords = kept_texcoords;
        glb_image(baked, texture, glb);
        sl_lod_mesh g = *mesh;
        g.colors = NULL; /* vertex colours would multiply the texture */
        return g;
    }
    if (!baked || !baked->texcoords)
        return *mesh;
    glb->texcoords = baked->texcoords;
    glb_image(baked, texture, glb);
    sl_lod_mesh g = {baked->vertex_count, baked->triangle_count, baked->positions,
                     baked->normals, NULL, baked->triangles};
    return g; /* vertex colours would multiply the texture: left out */
}

static int write_files(const sl_export_config *c, const sl_export_level *lv,
                       const sl_lod_mesh *mesh, const sl_lod_mesh *textured, const char *extras,
                       const sl_export_glb *textured_glb, sl_glb_stats *stats,
                       const sl_stage_io *io, sl_error *err)
{
    sl_export_glb glb = *textured_glb;
    static const char *const exts[4] = {"ply", "glb", "obj", "png"};
    const int wanted[4] = {c->write_ply, c->write_glb, c->write_obj, c->thumbnail_size > 0};
    int rcs[4] = {0};
    sl_error errs[4];
    /* The four files are independent (each its own bytes, the GLB's stats its own), so they
     * are written as tasks: the GLB's vertex-cache order and the thumbnail were the
     * export's serial path (a one-thread main loop while the cut ahead ran beside it).
     * The first failure in file order is reported, whatever finished first. */
#pragma omp parallel num_threads(omp_in_parallel() ? 1 : omp_get_max_threads())
#pragma omp single
    for (int i = 0; i < 4; i++) {
        sl_error_init(&errs[i]);
        if (!wanted[i])
            continue;
#pragma omp task firstprivate(i)
        {
            char file[sizeof lv->name + 8], path[PATH_MAX];
            snprintf(file, sizeof file, "%s.%s", lv->name, exts[i]);
            sl_error *e = &errs[i];
            int r = sl_stage_path(path, io->out_dir, file, e);
            if (r == 0)
                r = i == 1 ? sl_export_write_mesh(path, textured, extras, &glb, stats, e)
                    : i < 3 ? sl_export_write_mesh(path, mesh, extras, &glb, NULL, e)
                            : sl_export_thumbnail(path, mesh, c->thumbnail_size, glb.z_up, e);
            rcs[i] = r;
        }
    }
    for (int i = 0; i < 4; i++)
        if (rcs[i]) {
            *err = errs[i];
            return rcs[i];
        }
    return 0;
}

/* The GLB's encoding and what quantisation did to it, in the input's units and as
 * fractions of the input's diagonal (0 when not measured): the bound is added to the
 * level's errors, since no point of the published surface is further than it from the
 * point of the unquantised level it came from. */
static void report_glb(sl_json *r, const sl_export_config *c, const sl_glb_stats *g,
                       double to_metres, double max_error, double diagonal,
                       double hausdorff, int measured)
{
    static const char *const names[] = {"none", "meshopt", "draco"};
    double bound = g->position_bound / to_metres, worst = g->position_error_max / to_metres;
    sl_json_object_begin(r, "glb");
    sl_json_string(r, "compression", names[c->glb.compression]);
    sl_json_bool(r, "quantized", c->glb.quantize || c->glb.compression == SL_GLB_DRACO);
    sl_json_u64(r, "vertices", g->vertices);
    sl_json_u64(r, "triangles", g->triangles);
    sl_json_double(r, "position_step_world", g->position_step / to_metres);
    sl_json_double(r, "quantization_bound_world", bound);
    sl_json_double(r, "quantization_error_world", worst);
    sl_json_double(r, "quantization_rms_world", g->position_error_rms / to_metres);
    if (diagonal > 0) {
        sl_json_double(r, "quantization_bound", bound / diagonal);
        sl_json_double(r, "quantization_error", worst / diagonal);
    }
    sl_json_double(r, "normal_error_deg", g->normal_error_max_deg);
    sl_json_double(r, "color_error_srgb_steps", g->color_error_max);
    sl_json_double(r, "max_error", max_error + bound);
    if (g->morph) { /* how far weight 1 lands from the coarser level's surface point */
        sl_json_double(r, "morph_error_world", g->morph_error_max / to_metres);
        sl_json_u64(r, "morph_added_triangles", g->morph_added_triangles);
        sl_json_u64(r, "morph_unresolved_triangles", g->morph_unresolved);
        sl_json_u64(r, "morph_torn_triangles", g->morph_torn_triangles);
        sl_json_double(r, "morph_tear_world", g->morph_tear_max / to_metres);
        sl_json_double(r, "morph_unresolved_world", g->morph_unresolved_max / to_metres);
    }
    if (measured)
        sl_json_double(r, "hausdorff", hausdorff + bound / diagonal);
    sl_json_object_end(r);
}

static int measure_level(const sl_distance_reference *fidelity, const sl_lod_mesh *mesh,
                         const sl_stage_io *io, sl_export_result *row, sl_error *err)
{
    sl_mesh view = sl_export_mesh_view(mesh);
    sl_mesh_topology topo;
    int rc = sl_mesh_topology_compute(&view, &topo, err);
    if (rc)
        return rc;
    row->boundary_edges = topo.boundary_edges;
    row->nonmanifold_edges = topo.nonmanifold_edges;
    row->components = topo.components;
    row->largest_area_fraction = topo.area > 0 ? topo.largest_component_area / topo.area : 0;
    row->watertight = topo.watertight;
    if (!fidelity || mesh->triangle_count == 0)
        return 0;
    sl_mesh_distance d;
    sl_error derr;
    sl_error_init(&derr);
    rc = sl_distance_reference_compute(fidelity, &view, 1, &d, io->progress, &derr);
    if (rc == SL_E_INTERRUPTED || rc == SL_E_NOMEM) {
        sl_error_merge(err, &derr);
        return rc;
    }
    if (rc == 0) {
        row->measured = 1;
        row->rms = d.fraction.rms;
        row->hausdorff = d.fraction.hausdorff;
        row->mean = d.fraction.mean;
        row->diagonal = d.diagonal;
    }
    return 0;
}

void sl_export_md_thumbnail(FILE *md, const char *item, const char *name, int first)
{
    fputs(first ? "![" : " ![", md);
    sl_md_text(md, item);
    fputc(' ', md);
    sl_md_text(md, name);
    fputs("](<", md);
    sl_md_link(md, item);
    fputc('/', md);
    sl_md_link(md, name);
    fputs(".png>)", md);
}

int sl_export_write_summary_item(const sl_stage_io *io, char *text, size_t size, sl_error *err)
{
    char path[PATH_MAX];
    int rc = text ? sl_stage_path(path, io->out_dir, "summary-item.md", err)
                  : sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = sl_write_file_atomic(path, text, size, err);
    free(text);
    return rc;
}

/* Bakes the level's atlas when the input has a texture (and GLBs are written); reports
 * what it made in the row. 0, or SL_E_NOMEM/SL_E_INTERNAL. */
static int bake_level(const sl_export_config *c, const sl_export_texture *texture,
                      const sl_export_level *lv, const sl_lod_mesh *mesh, sl_export_result *row,
                      sl_export_baked *baked, sl_error *err)
{
    memset(baked, 0, sizeof *baked);
    if (!texture || !c->write_glb || mesh->triangle_count == 0)
        return 0;
    int wanted = sl_export_texture_size(c, lv->name);
    int rc = sl_export_bake(c, texture, mesh, wanted, baked, err);
    if (rc < 0)
        return rc;
    row->texture = rc == 1 ? -1 : 1;
    if (rc == 0) {
        row->texture_size = baked->size;
        row->texture_mime = baked->mime_type;
        row->texture_bytes = baked->image_size;
        row->texture_cell = baked->cell;
        row->texel_efficiency = baked->texel_efficiency;
    }
    return 0;
}

/* The level's atlas, as bake_level left it in the row, or the input's image kept. */
static void report_texture(const sl_export_result *row, sl_json *r)
{
    sl_json_object_begin(r, "texture");
    if (row->texture == 2 || row->texture == 3) {
        sl_json_string(r, "source", "input");
        sl_json_string(r, "texcoords", row->texture == 2 ? "input" : "projected");
        sl_json_string(r, "mime_type", row->texture_mime);
        sl_json_u64(r, "image_bytes", row->texture_bytes);
        if (row->texture == 3)
            sl_json_u64(r, "corners_across_seams", row->texture_continued);
        if (row->texture_size) /* scaled down to the level's size */
            sl_json_u64(r, "size", (uint64_t)row->texture_size);
    } else if (row->texture < 0) {
        sl_json_string(r, "warning", "too many triangles for the atlas: vertex colours only");
    } else {
        sl_json_string(r, "source", "baked");
        sl_json_u64(r, "size", (uint64_t)row->texture_size);
        sl_json_string(r, "mime_type", row->texture_mime);
        sl_json_u64(r, "image_bytes", row->texture_bytes);
        sl_json_u64(r, "cell_texels", (uint64_t)row->texture_cell);
        sl_json_double(r, "texel_efficiency", row->texel_efficiency);
    }
    sl_json_object_end(r);
}

void sl_export_report_result(const sl_export_config *c, const sl_export_frame *frame,
                             const sl_export_result *row, const char *file_name,
                             double max_error, sl_json *r)
{
    sl_json_u64(r, "boundary_edges", row->boundary_edges);
    sl_json_u64(r, "nonmanifold_edges", row->nonmanifold_edges);
    sl_json_bool(r, "watertight", row->watertight);
    sl_json_u64(r, "components", row->components);
    sl_json_double(r, "largest_component_area_fraction", row->largest_area_fraction);
    if (row->measured) {
        sl_json_double(r, "rms", row->rms);
        sl_json_double(r, "hausdorff", row->hausdorff);
        sl_json_double(r, "mean", row->mean);
        /* What the pages show: the fractions times the diagonal, in the item's frame. */
        double mm = 1000 * row->diagonal * frame->to_metres;
        sl_json_double(r, "rms_mm", row->rms * mm);
        sl_json_double(r, "hausdorff_mm", row->hausdorff * mm);
    }
    /* The level whose files hold this mesh (docs/formats.md); null without triangles. */
    sl_json_string(r, "file", file_name);
    if (row->texture)
        report_texture(row, r);
    if (row->triangles && c->write_glb)
        report_glb(r, c, &row->glb, frame->to_metres, max_error, row->diagonal, row->hausdorff,
                   row->measured);
}

/* The input's image for a level that embeds it (coordinates kept or projected): scaled to
 * the level's size when larger (thumb: 512), else its own bytes; what the row reports. */
static int input_image(const sl_export_config *c, const sl_export_texture *texture,
                       const sl_export_level *lv, sl_export_result *row, sl_export_baked *baked,
                       sl_error *err)
{
    int rc = sl_export_texture_scaled(c, texture, sl_export_texture_size(c, lv->name), baked,
                                      err);
    row->texture_mime = baked->image ? baked->mime_type : texture->original_mime;
    row->texture_bytes = baked->image ? baked->image_size : texture->original_size;
    row->texture_size = baked->image ? baked->size : 0;
    return rc;
}

int sl_export_write_level(const sl_export_config *c, const sl_export_level *lv,
                          const sl_lod_mesh *mesh, const float *texcoords,
                          const sl_lod_mesh *morph_to, const char *extras,
                          const sl_distance_reference *fidelity, const sl_export_frame *frame,
                          const sl_export_texture *texture,
                          const sl_stage_io *io, sl_export_result *row, sl_error *err)
{
    sl_export_glb glb = {c->glb, frame->to_metres, frame->up == 'z', NULL, morph_to,
                         c->morph_tears};
    row->triangles = mesh->triangle_count;
    row->vertices = mesh->vertex_count;
    sl_export_baked baked;
    memset(&baked, 0, sizeof baked);
    int keep = c->write_glb && mesh->triangle_count &&
               sl_export_texture_keeps(c, texture, texcoords, mesh->vertex_count);
    int rc = 0;
    if (keep) {
        rc = input_image(c, texture, lv, row, &baked, err);
        row->texture = 2;
    } else if (c->write_glb && mesh->triangle_count && c->texture == SL_EXPORT_TEXTURE_KEEP &&
               texture && texture->original && texture->chart) {
        rc = sl_export_project_uvs(texture, mesh, &baked, &row->texture_continued, err);
        if (rc == 0)
            rc = input_image(c, texture, lv, row, &baked, err);
        row->texture = 3;
    } else {
        rc = bake_level(c, texture, lv, mesh, row, &baked, err);
        /* A textured scan published untextured is what a curator notices first: said where
         * runs are watched, not only in report.json. */
        if (rc == 0 && row->texture < 0)
            SL_LOG(SL_LOG_WARN, "export", io->item, "%s: %llu triangles do not fit one atlas "
                   "chart each at %d px: vertex colours only, no texture", lv->name,
                   (unsigned long long)mesh->triangle_count, sl_export_texture_size(c, lv->name));
    }
    sl_lod_mesh textured = glb_geometry(mesh, &baked, keep ? texcoords : NULL, texture, &glb);
    if (rc == 0 && mesh->triangle_count)
        rc = write_files(c, lv, mesh, &textured, extras, &glb, &row->glb, io, err);
    sl_export_baked_release(&baked);
    if (rc == 0)
        rc = measure_level(fidelity, mesh, io, row, err);
    return rc;
}
