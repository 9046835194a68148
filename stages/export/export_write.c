/* Mesh files by extension, and thumbnails (export.h). GLB vertices are put in
 * meshoptimizer's vertex-cache order, then its fetch order, as GPUs like them and as its
 * codecs need them to compress well; GLB and thumbnail geometry is in glTF's frame
 * (metres, +Y up). */
#include <errno.h>
#include <meshoptimizer.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "formats/glb.h"
#include "geometry/mesh.h"
#include "geometry/morph_refine.h"
#include "geometry/morph_target.h"
#include "formats/ply.h"
#include "geometry/raster.h"
#include "stages/export/export_internal.h"

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot + 1 : "";
}

sl_mesh sl_export_mesh_view(const sl_lod_mesh *m)
{
    return sl_mesh_view(m->vertex_count, m->positions, m->normals, m->colors, m->triangle_count,
                        m->indices);
}

double sl_export_unit_metres(const char *name)
{
    static const struct { const char *name; double metres; } units[] = {
        {"mm", 0.001}, {"cm", 0.01}, {"m", 1}, {"in", 0.0254}, {"ft", 0.3048}};
    for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
        if (!strcmp(name, units[i].name))
            return units[i].metres;
    return 0;
}

/* Input frame -> glTF's: scale to metres, and for Z-up inputs the rotation by -90 degrees
 * about X, (x, y, z) -> (x, z, -y) (determinant +1: windings and outsides stay). Normals
 * rotate alike; a uniform scale does not change their direction. */
static void to_gltf_frame(float *pos, float *nrm, uint64_t n, double to_metres, int z_up)
{
    for (uint64_t i = 0; i < n; i++) {
        float *p = pos + 3 * i;
        double x = p[0] * to_metres, y = p[1] * to_metres, z = p[2] * to_metres;
        p[0] = (float)x, p[1] = (float)(z_up ? z : y), p[2] = (float)(z_up ? -y : z);
        if (nrm && z_up) {
            float *q = nrm + 3 * i, y0 = q[1];
            q[1] = q[2], q[2] = -y0;
        }
    }
}

/* GLB in meshoptimizer's vertex-cache and vertex-fetch order (same surface, same welds);
 * `uv` per vertex or NULL, `morph` (the morph target, input frame) per vertex or NULL. */
static int write_glb_mesh(const char *path, const sl_lod_mesh *m, const float *uv_in,
                          const float *morph, const char *extras, const sl_export_glb *glb,
                          sl_glb_stats *stats, sl_error *err)
{
    size_t indices = (size_t)m->triangle_count * 3, vertices = (size_t)m->vertex_count;
    uint32_t *order = malloc((indices ? indices : 1) * sizeof *order);
    uint32_t *remap = malloc((vertices ? vertices : 1) * sizeof *remap);
    float *pos = malloc((vertices ? vertices : 1) * 3 * sizeof *pos);
    float *nrm = malloc((vertices ? vertices : 1) * 3 * sizeof *nrm);
    uint8_t *col = m->colors ? malloc((vertices ? vertices : 1) * 4) : NULL;
    float *uv = uv_in ? malloc((vertices ? vertices : 1) * 2 * sizeof *uv) : NULL;
    float *target = morph ? malloc((vertices ? vertices : 1) * 12) : NULL;
    int rc = 0;
    if (!order || !remap || !pos || !nrm || (m->colors && !col) || (uv_in && !uv) ||
        (morph && !target)) {
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    } else {
        meshopt_optimizeVertexCache(order, m->indices, indices, vertices);
        size_t used = meshopt_optimizeVertexFetchRemap(remap, order, indices, vertices);
        meshopt_remapIndexBuffer(order, order, indices, remap);
        meshopt_remapVertexBuffer(pos, m->positions, vertices, 3 * sizeof(float), remap);
        meshopt_remapVertexBuffer(nrm, m->normals, vertices, 3 * sizeof(float), remap);
        if (col)
            meshopt_remapVertexBuffer(col, m->colors, vertices, 4, remap);
        if (uv)
            meshopt_remapVertexBuffer(uv, uv_in, vertices, 2 * sizeof *uv, remap);
        to_gltf_frame(pos, nrm, used, glb->to_metres, glb->z_up);
        sl_glb_options options = glb->options;
        if (target) {
            meshopt_remapVertexBuffer(target, morph, vertices, 3 * sizeof(float), remap);
            to_gltf_frame(target, NULL, used, glb->to_metres, glb->z_up);
            options.morph_positions = target;
        }
        sl_mesh g = sl_mesh_view(used, pos, nrm, col, m->triangle_count, order);
        g.texcoords = uv;
        rc = sl_glb_write(path, &g, extras, &options, stats, err);
    }
    free(target);
    free(order);
    free(remap);
    free(pos);
    free(nrm);
    free(col);
    free(uv);
    return rc;
}

/* With glb->morph_to: the level cut along the coarser level's edges (morph_refine.h), so
 * that at weight 1 its surface, not only its vertices, lies on the coarser level; the
 * level's own vertices keep their bytes, the added ones lie on its triangles. */
static int write_glb(const char *path, const sl_lod_mesh *m, const char *extras,
                     const sl_export_glb *glb, sl_glb_stats *stats, sl_error *err)
{
    if (!glb->morph_to)
        return write_glb_mesh(path, m, glb->texcoords, NULL, extras, glb, stats, err);
    sl_mesh coarser = sl_export_mesh_view(glb->morph_to), level = sl_export_mesh_view(m);
    sl_morph_refined r;
    int rc = sl_morph_refine(&coarser, &level, glb->morph_tears ? SL_MORPH_REFINE_TEAR : 0, &r,
                             err);
    if (rc) {
        if (!err->file[0])
            snprintf(err->file, sizeof err->file, "%s", path);
        return rc;
    }
    size_t n = (size_t)(r.vertex_count ? r.vertex_count : 1);
    float *nrm = malloc(n * 12), *uv = glb->texcoords ? malloc(n * 8) : NULL;
    uint8_t *col = m->colors ? malloc(n * 4) : NULL;
    if (!nrm || (glb->texcoords && !uv) || (m->colors && !col)) {
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    } else {
        sl_morph_refined_normals(&r, m->normals, nrm);
        if (uv)
            sl_morph_refined_interpolate(&r, glb->texcoords, 2, uv);
        if (col)
            sl_morph_refined_interpolate_rgba(&r, m->colors, col);
        sl_lod_mesh rm = {r.vertex_count, r.triangle_count, r.positions, nrm, col, r.triangles};
        rc = write_glb_mesh(path, &rm, uv, r.targets, extras, glb, stats, err);
        if (rc == 0 && stats)
            stats->morph_added_triangles = r.triangle_count - r.level_triangles,
            stats->morph_unresolved = r.unresolved, stats->morph_torn_triangles = r.torn_triangles,
            stats->morph_tear_max = r.tear_max * glb->to_metres, /* metres, as the rest */
            stats->morph_unresolved_max = r.unresolved_max * glb->to_metres;
    }
    free(nrm), free(uv), free(col);
    sl_morph_refined_release(&r);
    return rc;
}

int sl_export_write_mesh(const char *path, const sl_lod_mesh *mesh, const char *extras_json,
                         const sl_export_glb *glb, sl_glb_stats *stats, sl_error *err)
{
    const char *ext = extension(path);
    sl_mesh view = sl_export_mesh_view(mesh);
    if (strcasecmp(ext, "ply") == 0)
        return sl_ply_write(path, &view, err);
    if (strcasecmp(ext, "glb") == 0)
        return glb ? write_glb(path, mesh, extras_json, glb, stats, err)
                   : sl_error_set(err, SL_E_INTERNAL, 0, path, "a GLB written without options");
    if (strcasecmp(ext, "obj") == 0)
        return sl_obj_write(path, &view, NULL, err);
    return sl_error_set(err, SL_E_USAGE, 0, path,
                        "unknown output format '.%s' (use .ply, .glb or .obj)", ext);
}

/* Rendered upright: the renderer's camera looks about +Y, glTF's up. */
int sl_export_thumbnail(const char *path, const sl_lod_mesh *mesh, int size, int z_up,
                        sl_error *err)
{
    sl_mesh view = sl_export_mesh_view(mesh);
    if (!z_up)
        return sl_write_thumbnail(path, &view, size, err);
    size_t n = (size_t)mesh->vertex_count;
    float *pos = malloc((n ? n : 1) * 3 * sizeof *pos);
    float *nrm = mesh->normals ? malloc((n ? n : 1) * 3 * sizeof *nrm) : NULL;
    if (!pos || (mesh->normals && !nrm)) {
        free(pos), free(nrm);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    }
    memcpy(pos, mesh->positions, n * 3 * sizeof *pos);
    if (nrm)
        memcpy(nrm, mesh->normals, n * 3 * sizeof *nrm);
    to_gltf_frame(pos, nrm, n, 1.0, 1);
    view.positions = pos, view.normals = nrm;
    int rc = sl_write_thumbnail(path, &view, size, err);
    free(pos), free(nrm);
    return rc;
}
