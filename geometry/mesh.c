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
