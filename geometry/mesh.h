/* The in-memory triangle mesh / point set every stage and tool shares.
 *
 * Spaces and units: positions are world coordinates in the input file's units.
 * Ownership: arrays are malloc'd by whoever fills the mesh and released by
 * sl_mesh_release(); optional arrays are NULL when absent.
 */
#ifndef SCANLOD_GEOMETRY_MESH_H
#define SCANLOD_GEOMETRY_MESH_H

#include <stdint.h>

#include "core/error.h"

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

    /* The base colour texture: an image file named relative to the input's directory
     * (PLY `comment TextureFile NAME`, OBJ's MTL `map_Kd`, a glTF image `uri`), or the
     * encoded image held in the file itself (glTF/GLB: a bufferView or data: URI) as its
     * bytes and MIME type; neither when the input has no texture. */
    char texture_file[256];  /* "" if none */
    uint8_t *texture_data;   /* malloc'd encoded image (JPEG, PNG, ...), or NULL */
    uint64_t texture_size;   /* its bytes */
    char texture_mime[32];   /* "image/jpeg", "image/png", ...; "" with no texture_data */

    char format[8];          /* the reader that filled the mesh: "ply", "obj", "stl", "off",
                                "xyz", "pts", "gltf", "glb"; "" when not read from a file */
    /* Frame hints: what the file says (PLY comments; glTF's convention: metres, +Y up);
     * left unset by formats that say nothing (OBJ, STL, OFF, XYZ). */
    char units[4];           /* "mm", "cm", "m", "in", "ft"; "" if none */
    char up_axis;            /* 'y' or 'z'; 0 if none */
    int has_viewpoint;       /* the file states where the scanner was */
    double viewpoint[3];     /* world */

    sl_mesh_stats stats;
    /* What the reader could not use but read on without (a missing MTL or texture image,
     * an extension ignored): "mask.mtl: missing; ...", for the item's report. */
    uint32_t warning_count;
    char warnings[768];      /* the first ones, "; "-separated ("..." when cut); "" if none */
} sl_mesh;

void sl_mesh_init(sl_mesh *m);
void sl_mesh_release(sl_mesh *m); /* frees every array and re-inits */

/* Records one reader warning in m->warnings (counted always, the text while it fits). */
void sl_mesh_warn(sl_mesh *m, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* A view of arrays someone else owns, as an sl_mesh (normals and colours may be NULL;
 * every other optional array is NULL): the one way to hand generated or borrowed
 * geometry to what reads an sl_mesh (writers, topology, BVH, distances). Nothing is
 * copied; never sl_mesh_release() a view. */
sl_mesh sl_mesh_view(uint64_t vertex_count, float *positions, float *normals, uint8_t *colors,
                     uint64_t triangle_count, uint32_t *triangles);

/* Area-weighted vertex normals of a triangle mesh into `normals` (3 per vertex, unit;
 * zero for a vertex no triangle with area uses). Summed in triangle order, in double:
 * the same bytes on every run. */
void sl_mesh_vertex_normals(const float *positions, uint64_t vertex_count,
                            const uint32_t *triangles, uint64_t triangle_count,
                            float *normals /* OUT */);

/* What the writers read of `m`: positions (world), triangles (counter-clockwise seen from
 * outside), normals (any length; written unit) and colours (RGBA, sRGB) when not NULL.
 * The checks every writer of a mesh for viewers needs (GLB, OBJ, thumbnails): at least
 * one triangle, finite positions, indices in range. `path` names the file in messages
 * (may be NULL). */
int sl_mesh_check_writable(const sl_mesh *m, const char *path, sl_error *err);

#endif
