/* Mesh files by extension, and thumbnails (export.h). GLB vertices are put in
 * meshoptimizer's vertex-cache order, then its fetch order, as GPUs like them. */
#include <errno.h>
#include <meshoptimizer.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "geometry/glb.h"
#include "geometry/mesh.h"
#include "geometry/ply.h"
#include "geometry/raster.h"
#include "stages/export/export_internal.h"

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot + 1 : "";
}

static sl_glb_mesh glb_view(const sl_lod_mesh *m, const char *extras_json)
{
    sl_glb_mesh g = {m->vertex_count, m->triangle_count, m->positions, m->normals,
                     m->colors,       m->indices,        extras_json};
    return g;
}

static int write_ply(const char *path, const sl_lod_mesh *m, sl_error *err)
{
    /* sl_mesh views the generated arrays; nothing is copied or freed here. */
    sl_mesh view;
    sl_mesh_init(&view);
    view.vertex_count = m->vertex_count;
    view.positions = m->positions;
    view.normals = m->normals;
    view.colors = m->colors;
    view.triangle_count = m->triangle_count;
    view.triangles = m->indices;
    return sl_ply_write(path, &view, err);
}

/* GLB in meshoptimizer's vertex-cache and vertex-fetch order (same surface, same welds). */
static int write_glb(const char *path, const sl_lod_mesh *m, const char *extras, sl_error *err)
{
    size_t indices = (size_t)m->triangle_count * 3, vertices = (size_t)m->vertex_count;
    uint32_t *order = malloc((indices ? indices : 1) * sizeof *order);
    uint32_t *remap = malloc((vertices ? vertices : 1) * sizeof *remap);
    float *pos = malloc((vertices ? vertices : 1) * 3 * sizeof *pos);
    float *nrm = malloc((vertices ? vertices : 1) * 3 * sizeof *nrm);
    uint8_t *col = m->colors ? malloc((vertices ? vertices : 1) * 4) : NULL;
    int rc;
    if (!order || !remap || !pos || !nrm || (m->colors && !col)) {
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    } else {
        meshopt_optimizeVertexCache(order, m->indices, indices, vertices);
        size_t used = meshopt_optimizeVertexFetchRemap(remap, order, indices, vertices);
        meshopt_remapIndexBuffer(order, order, indices, remap);
        meshopt_remapVertexBuffer(pos, m->positions, vertices, 3 * sizeof(float), remap);
        meshopt_remapVertexBuffer(nrm, m->normals, vertices, 3 * sizeof(float), remap);
        if (col)
            meshopt_remapVertexBuffer(col, m->colors, vertices, 4, remap);
        sl_glb_mesh g = {used, m->triangle_count, pos, nrm, col, order, extras};
        rc = sl_glb_write(path, &g, err);
    }
    free(order);
    free(remap);
    free(pos);
    free(nrm);
    free(col);
    return rc;
}

int sl_export_write_mesh(const char *path, const sl_lod_mesh *mesh, const char *extras_json,
                         sl_error *err)
{
    const char *ext = extension(path);
    if (strcasecmp(ext, "ply") == 0)
        return write_ply(path, mesh, err);
    if (strcasecmp(ext, "glb") == 0)
        return write_glb(path, mesh, extras_json, err);
    if (strcasecmp(ext, "obj") == 0) {
        sl_glb_mesh g = glb_view(mesh, NULL);
        return sl_obj_write(path, &g, err);
    }
    return sl_error_set(err, SL_E_USAGE, 0, path,
                        "unknown output format '.%s' (use .ply, .glb or .obj)", ext);
}

int sl_export_thumbnail(const char *path, const sl_lod_mesh *mesh, int size, sl_error *err)
{
    sl_glb_mesh g = glb_view(mesh, NULL);
    return sl_write_thumbnail(path, &g, size, err);
}
