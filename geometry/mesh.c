/* sl_mesh lifecycle (see mesh.h). */
#include "geometry/mesh.h"

#include <stdlib.h>
#include <string.h>

void sl_mesh_init(sl_mesh *m)
{
    memset(m, 0, sizeof *m);
}

void sl_mesh_release(sl_mesh *m)
{
    free(m->positions);
    free(m->normals);
    free(m->colors);
    free(m->texcoords);
    free(m->triangles);
    free(m->face_texcoords);
    free(m->grid_index);
    sl_mesh_init(m);
}

sl_mesh sl_mesh_view(uint64_t vertex_count, float *positions, float *normals, uint8_t *colors,
                     uint64_t triangle_count, uint32_t *triangles)
{
    sl_mesh v;
    sl_mesh_init(&v);
    v.vertex_count = vertex_count;
    v.positions = positions;
    v.normals = normals;
    v.colors = colors;
    v.triangle_count = triangle_count;
    v.triangles = triangles;
    return v;
}
