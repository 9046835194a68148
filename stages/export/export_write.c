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

sl_mesh sl_export_mesh_view(const sl_lod_mesh *m)
{
    return sl_mesh_view(m->vertex_count, m->positions, m->normals, m->colors, m->triangle_count,
                        m->indices);
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
        sl_mesh g = sl_mesh_view(used, pos, nrm, col, m->triangle_count, order);
        rc = sl_glb_write(path, &g, extras, err);
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
    sl_mesh view = sl_export_mesh_view(mesh);
    if (strcasecmp(ext, "ply") == 0)
        return sl_ply_write(path, &view, err);
    if (strcasecmp(ext, "glb") == 0)
        return write_glb(path, mesh, extras_json, err);
    if (strcasecmp(ext, "obj") == 0)
        return sl_obj_write(path, &view, NULL, err);
    return sl_error_set(err, SL_E_USAGE, 0, path,
                        "unknown output format '.%s' (use .ply, .glb or .obj)", ext);
}

int sl_export_thumbnail(const char *path, const sl_lod_mesh *mesh, int size, sl_error *err)
{
    sl_mesh view = sl_export_mesh_view(mesh);
    return sl_write_thumbnail(path, &view, size, err);
}
