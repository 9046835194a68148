/* The in-memory triangle mesh / point set every stage and tool shares.
 *
 * Spaces and units: positions are world coordinates in the input file's units.
 * Ownership: arrays are malloc'd by whoever fills the mesh and released by
 * sl_mesh_release(); optional arrays are NULL when absent.
 */
#ifndef SCANLOD_GEOMETRY_MESH_H
#define SCANLOD_GEOMETRY_MESH_H

#include <stdint.h>

/* What the reader saw and did, reported per item. */
typedef struct sl_mesh_stats {
    uint64_t polygons_triangulated; /* faces with > 3 corners, fan-triangulated */
    uint64_t faces_too_short;       /* faces with < 3 corners, dropped */
    uint64_t texcoord_faces;        /* faces that carried a texcoord list */
} sl_mesh_stats;

typedef struct sl_mesh {
    uint64_t vertex_count;
    float *positions;      /* 3 * vertex_count, world */
    float *normals;        /* 3 * vertex_count, or NULL (not necessarily unit length) */
    uint8_t *colors;       /* 4 * vertex_count RGBA, or NULL */
    float *texcoords;      /* 2 * vertex_count (u, v), or NULL */

    uint64_t triangle_count;
    uint32_t *triangles;   /* 3 * triangle_count vertex indices, all < vertex_count */
    float *face_texcoords; /* 6 * triangle_count (u, v per corner), or NULL */

    /* Scanner pixel grid of a raw range scan (Stanford `element range_grid`):
     * grid_index[row * grid_cols + col] = vertex index or -1. NULL when absent. */
    uint32_t grid_cols, grid_rows;
    int64_t *grid_index;

    char texture_file[256];  /* from `comment TextureFile NAME`, "" if none */
    char units[4];           /* `comment units NAME`: "mm", "cm", "m", "in", "ft"; "" if none */
    char up_axis;            /* `comment up AXIS`: 'y' or 'z'; 0 if none */
    int has_viewpoint;       /* the file states where the scanner was */
    double viewpoint[3];     /* world */

    sl_mesh_stats stats;
} sl_mesh;

void sl_mesh_init(sl_mesh *m);
void sl_mesh_release(sl_mesh *m); /* frees every array and re-inits */

/* A view of arrays someone else owns, as an sl_mesh (normals and colours may be NULL;
 * every other optional array is NULL): the one way to hand generated or borrowed
 * geometry to what reads an sl_mesh (writers, topology, BVH, distances). Nothing is
 * copied; never sl_mesh_release() a view. */
sl_mesh sl_mesh_view(uint64_t vertex_count, float *positions, float *normals, uint8_t *colors,
                     uint64_t triangle_count, uint32_t *triangles);

#endif
