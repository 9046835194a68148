/* The public runtime API (include/scanlod/scanlod.h) over the LOD model. */
#include "scanlod/scanlod.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_io.h"
#include "runtime/lod_prefix.h"

/* The file, read by prefixes (format 5) or whole (older formats): lod_prefix.h. */
struct scanlod_model {
    sl_lod_file *file;
};

int scanlod_model_open(const char *path, scanlod_model **out, char *error, size_t error_size)
{
    *out = NULL;
    scanlod_model *m = calloc(1, sizeof *m);
    sl_error err;
    sl_error_init(&err);
    int rc = m ? sl_lod_file_open(path, &m->file, &err)
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
    sl_lod_file_close(model->file);
    free(model);
}

static const sl_lod_model *levels(const scanlod_model *model)
{
    return sl_lod_file_levels(model->file);
}

uint32_t scanlod_model_expansions(const scanlod_model *model)
{
    return levels(model)->expansion_count;
}

uint64_t scanlod_model_triangles(const scanlod_model *model, uint32_t k)
{
    const sl_lod_model *l = levels(model);
    return l->accumulation[k > l->expansion_count ? l->expansion_count : k];
}

void scanlod_model_bounds(const scanlod_model *model, float min[3], float max[3])
{
    sl_lod_file_bounds(model->file, min, max);
}

uint32_t scanlod_expansions_for_triangles(const scanlod_model *model, uint64_t budget)
{
    return sl_lod_expansions_for_triangles(levels(model), budget);
}

uint32_t scanlod_expansions_for_percent(const scanlod_model *model, double percent)
{
    return sl_lod_expansions_for_percent(levels(model), percent);
}

uint32_t scanlod_expansions_for_error(const scanlod_model *model, double max_error)
{
    return sl_lod_expansions_for_error(levels(model), max_error);
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
     * mesh past it (a model whose table is wrong) fails instead of writing past them. A
     * format 5 file is read as far as k needs first (lod_prefix.h). */
    scanlod_mesh_bound bound = scanlod_extract_bound(model, k);
    sl_lod_mesh mesh = {0, 0, positions, normals, colors, indices};
    written->vertices = written->triangles = 0;
    sl_lod_model *cut = NULL;
    sl_error err;
    sl_error_init(&err);
    if (sl_lod_file_reach(model->file, k, &cut, &err) != 0 ||
        sl_lod_generate_into(cut, k, &mesh, bound.vertices, bound.triangles, NULL) != 0)
        return -1;
    if (colors && !cut->tree.crossing_color)
        memset(colors, 255, mesh.vertex_count * 4);
    written->vertices = mesh.vertex_count;
    written->triangles = mesh.triangle_count;
    return 0;
}
