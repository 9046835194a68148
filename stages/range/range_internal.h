/* Internal interfaces between the range stage's files (not used outside stages/range/).
 *
 * Data flow (range_points.c drives it):
 *   range_grid.c   scanner grid -> triangles (raw range scans only)
 *   weld.c         input vertices -> points: non-finite dropped, exact duplicates welded,
 *                  unreferenced dropped; triangles remapped to points, degenerate dropped
 *   normals.c      area-weighted face normals per point, or the file's normals
 *   pca_normals.c  point clouds: PCA normals, viewpoint or MST orientation
 *   texture.c      colours from vertex colours or the texture image
 * Indices: input vertices and points are uint32_t (the reader caps vertex counts below
 * 2^32); UINT32_MAX marks "none".
 */
#ifndef SCANLOD_STAGES_RANGE_INTERNAL_H
#define SCANLOD_STAGES_RANGE_INTERNAL_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/kdtree.h"
#include "geometry/mesh.h"
#include "stages/range/range.h"

#define RANGE_NONE UINT32_MAX

/* Input vertices -> points, and the kept triangles (weld.c). */
typedef struct range_clean {
    uint64_t point_count;
    uint32_t *vertex_point;  /* per input vertex: its point (welded twins share one), or
                                RANGE_NONE (non-finite or unreferenced) */
    uint32_t *point_vertex;  /* per point: its representative (lowest) input vertex */
    uint64_t triangle_count;
    uint32_t *triangles;     /* 3 * triangle_count point indices */
    uint64_t *triangle_source; /* per kept triangle: its input triangle (face texcoords) */
} range_clean;

/* Fills `out` from `mesh`; counts welded, unreferenced, nonfinite_*, degenerate_faces.
 * A mesh without triangles is a point cloud: every finite, welded vertex is a point. */
int range_clean_mesh(const sl_mesh *mesh, range_clean *out, sl_range_counts *counts,
                     sl_progress *progress, sl_error *err);
void range_clean_release(range_clean *c);

/* Triangulates mesh->grid_index into mesh->triangles (range_grid.c). */
int range_grid_triangulate(sl_mesh *mesh, double max_edge_factor, sl_range_counts *counts,
                           sl_progress *progress, sl_error *err);

/* Area-weighted mean of adjacent face normals (normals.c). OUT: normals[3 * points]. */
int range_face_normals(const float *positions, uint64_t point_count, const uint32_t *triangles,
                       uint64_t triangle_count, float *normals, sl_range_counts *counts,
                       sl_progress *progress, sl_error *err);

/* The mean of the file normals of each point's welded vertices; OUT: valid[p] = 1 where
 * that mean is a usable direction (normals[p] then unit length), else 0. */
int range_file_normals(const sl_mesh *mesh, const range_clean *clean, float *normals,
                       uint8_t *valid, sl_error *err);

/* PCA normals over the k nearest neighbours (pca_normals.c), oriented towards the
 * viewpoint when `viewpoint` is not NULL, else by MST propagation. OUT: normals, *source,
 * counts->pca_components. */
int range_pca_normals(const sl_kdtree *tree, const float *positions, uint64_t point_count,
                      uint32_t k, const double *viewpoint, float *normals, uint32_t *source,
                      sl_range_counts *counts, sl_progress *progress, sl_error *err);

/* Colours per point (texture.c): vertex colours, else texture samples. OUT: *colors
 * (malloc'd 4 * point_count, or NULL when there is no colour), counts->color_source,
 * texture_warnings, colors_unsampled. */
/* One texture coordinate per point (u, v as the input's, v up) when the input has a
 * texture and every point's vertices or triangle corners agree on it (texture.c); else
 * NULL, with counts->texcoord_seams the corners that disagree. 0 or SL_E_NOMEM. */
int range_texcoords(const sl_mesh *mesh, const range_clean *clean, float **texcoords,
                    sl_range_counts *counts, sl_error *err);

int range_colors(const sl_mesh *mesh, const range_clean *clean, const char *texture_dir,
                 int enabled, uint8_t **colors, sl_range_counts *counts, sl_error *err);

/* Mean distance from each point to its nearest other point (0 for a single point).
 * OUT: *spacing. Returns 0 or SL_E_NOMEM. */
int range_mean_spacing(const sl_kdtree *tree, const float *positions, uint64_t point_count,
                       double *spacing, sl_error *err);

#endif
