/* Plane fitting for planar patches (paper 3, section 3.3: the plane a segment's vertices
 * are measured against) and the plane's 2D frame, in which the constrained Delaunay
 * triangulation (geometry/cdt.h) retriangulates the patch.
 *
 * Default: total least squares (SL_PLANE_TLS): the plane through the weighted centroid
 * whose normal is the eigenvector of the smallest eigenvalue of the weighted covariance
 * matrix (Jacobi rotations in double). It minimises the sum of squared perpendicular
 * distances, whatever the plane's direction. The paper's form z = a x + b y + d (its
 * equations 4-6, SL_PLANE_Z_FORM) minimises vertical offsets instead: it leans towards
 * horizontal on steep patches, and on a vertical one (a wall, the side of a statue) its
 * 2x2 system is singular and there is no answer at all. It is kept for comparison.
 *
 * Points: float xyz (as in sl_mesh), optionally through an index array, in double inside.
 * Thread safety: pure functions; any number of threads.
 */
#ifndef SCANLOD_GEOMETRY_PLANE_FIT_H
#define SCANLOD_GEOMETRY_PLANE_FIT_H

#include <stdint.h>

#include "core/error.h"

enum sl_plane_method {
    SL_PLANE_TLS = 0,    /* perpendicular least squares (PCA) */
    SL_PLANE_Z_FORM = 1  /* the paper's z = a x + b y + d, vertical least squares */
};

typedef struct sl_plane {
    double normal[3];      /* unit; sign: largest component positive (see sl_plane_orient) */
    double offset;         /* the plane is { x : normal . x = offset }, world */
    double centroid[3];    /* weighted centroid of the points, world (on the plane) */
    double u[3], v[3];     /* orthonormal frame of the plane, u x v = normal */
    double eigenvalues[3]; /* weighted covariance eigenvalues, ascending, world^2 (TLS:
                              eigenvalues[0] is the weighted mean squared distance) */
    double mean_dist2;     /* weighted mean squared distance of the points to the plane */
    double max_dist2;      /* largest squared distance of a point (of weight > 0) */
    int degenerate;        /* TLS: the points are (nearly) collinear or coincident,
                              eigenvalues[1] <= 2^-40 eigenvalues[2]: the normal is not
                              determined by them (it is still a unit vector) */
} sl_plane;

/* Fits a plane to `count` points: positions[3 * i ..] for i = index[k] (index NULL: the
 * first `count` points), with weights[k] >= 0 (NULL: all 1; e.g. triangle areas).
 * OUT: *out. Returns 0, or SL_E_BADINPUT: no point or zero total weight, a non-finite
 * coordinate or weight, a negative weight, or (SL_PLANE_Z_FORM) points whose xy projection
 * is (nearly) a line, i.e. a vertical plane. */
int sl_plane_fit(const float *positions, const uint32_t *index, uint64_t count,
                 const double *weights, int method, sl_plane *out, sl_error *err);

/* Turns the plane to face `reference` (e.g. the patch's area-weighted face normal), so
 * that loops running counter-clockwise seen from that side stay counter-clockwise in the
 * plane's frame: flips normal, offset and v if normal . reference < 0. */
void sl_plane_orient(sl_plane *plane, const double reference[3]);

/* 2D coordinates in the plane's frame: uv[2k] = (p - centroid) . u, uv[2k + 1] =
 * (p - centroid) . v for p = positions of index[k] (index NULL: point k). World units. */
void sl_plane_project(const sl_plane *plane, const float *positions, const uint32_t *index,
                      uint64_t count, double *uv);

/* The first of `triangle_count` triangles (3 indices each into uv) whose projection is not
 * strictly counter-clockwise (exact test), or UINT64_MAX. A consistently oriented patch
 * folds in projection exactly when one of its triangles turns over (or its loops overlap,
 * which the triangulation refuses): when none does and the triangulation accepts its
 * loops, every point of the plane is covered at most once, since the number of times is
 * the loops' winding number around it. Callers leave a folding patch as it is. */
uint64_t sl_plane_projection_fold(const double *uv, const uint32_t *triangles,
                                  uint64_t triangle_count);

#endif
