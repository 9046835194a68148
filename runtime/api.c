/* The public runtime API (include/scanlod/scanlod.h) over the LOD model. */
#include "scanlod/scanlod.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_io.h"

struct scanlod_model {
    sl_lod_model lod;
};

int scanlod_model_open(const char *path, scanlod_model **out, char *error, size_t error_size)
{
    *out = NULL;
    scanlod_model *m = calloc(1, sizeof *m);
    sl_error err;
    sl_error_init(&err);
    int rc = m ? sl_lod_model_open(path, &m->lod, &err)
               : sl_error_set(&err, SL_E_NOMEM, 0, path, "out of memory");
    if (rc) {
        if (error && error_size)
            sl_error_format(&err, error, error_size);
        free(m);
        return rc;
    }
    *out = m;
    return 0;
}

void scanlod_model_free(scanlod_model *model)
{
    if (!model)
        return;
    sl_lod_model_release(&model->lod);
    free(model);
}

uint32_t scanlod_model_expansions(const scanlod_model *model)
{
    return model->lod.expansion_count;
}

uint64_t scanlod_model_triangles(const scanlod_model *model, uint32_t k)
{
    if (k > model->lod.expansion_count)
        k = model->lod.expansion_count;
    return model->lod.accumulation[k];
}

void scanlod_model_bounds(const scanlod_model *model, float min[3], float max[3])
{
    const sl_octree *t = &model->lod.tree;
    for (int a = 0; a < 3; a++) {
        min[a] = FLT_MAX;
        max[a] = -FLT_MAX;
    }
    for (uint32_t i = 0; i < t->crossing_count; i++)
        for (int a = 0; a < 3; a++) {
            float v = t->crossing_position[3 * (size_t)i + a];
            min[a] = v < min[a] ? v : min[a];
            max[a] = v > max[a] ? v : max[a];
        }
}

uint32_t scanlod_expansions_for_triangles(const scanlod_model *model, uint64_t budget)
{
    return sl_lod_expansions_for_triangles(&model->lod, budget);
}

uint32_t scanlod_expansions_for_percent(const scanlod_model *model, double percent)
{
    return sl_lod_expansions_for_percent(&model->lod, percent);
}

uint32_t scanlod_expansions_for_error(const scanlod_model *model, double max_error)
{
    return sl_lod_expansions_for_error(&model->lod, max_error);
}

scanlod_mesh_bound scanlod_extract_bound(const scanlod_model *model, uint32_t k)
{
    uint64_t triangles = scanlod_model_triangles(model, k);
    /* Every vertex is a corner of some triangle. */
    scanlod_mesh_bound b = {3 * triangles, triangles};
    return b;
}

int scanlod_extract(scanlod_model *model, uint32_t k, float *positions, float *normals,
                    uint8_t *colors, uint32_t *indices, scanlod_mesh_bound *written)
{
    /* Straight into the caller's arrays: the bound is the accumulation table's count, so a
     * mesh past it (a model whose table is wrong) fails instead of writing past them. */
    scanlod_mesh_bound bound = scanlod_extract_bound(model, k);
    sl_lod_mesh mesh = {0, 0, positions, normals, colors, indices};
    written->vertices = written->triangles = 0;
    if (sl_lod_generate_into(&model->lod, k, &mesh, bound.vertices, bound.triangles, NULL) != 0)
        return -1;
    if (colors && !model->lod.tree.crossing_color)
        memset(colors, 255, mesh.vertex_count * 4);
    written->vertices = mesh.vertex_count;
    written->triangles = mesh.triangle_count;
    return 0;
}
