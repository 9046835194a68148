/* Closest point on a triangle soup: a bounding-volume hierarchy over triangles and the
 * exact point-triangle distance of Ericson, "Real-Time Collision Detection", 5.1.5.
 *
 * The tree is a median split on triangle centroids along the widest centroid axis, at
 * most SL_BVH_LEAF_SIZE triangles per leaf, nodes in depth-first order (the left child
 * follows its parent). Triangles are copied in leaf order so a query reads memory
 * sequentially. Because every split is at the median, a subtree's node count depends
 * only on its triangle count: the build places every subtree at a precomputed offset
 * and may run its halves as parallel tasks, yet the layout is the same for any thread
 * count.
 *
 * Arithmetic is in double (positions are float), so a query's distance is exact to
 * double rounding and independent of traversal order up to ties.
 *
 * Thread safety: a built tree is read-only; queries from many threads are fine.
 * Memory: 36 bytes per triangle + 4 (original index) + about 16 bytes per triangle of
 * nodes.
 */
#ifndef SCANLOD_GEOMETRY_TRIANGLE_BVH_H
#define SCANLOD_GEOMETRY_TRIANGLE_BVH_H

#include <stdint.h>

#include "core/error.h"
#include "geometry/mesh.h"

#define SL_BVH_LEAF_SIZE 4

typedef struct sl_bvh_node {
    float lo[3], hi[3]; /* bounds of every triangle below, world */
    uint32_t first;     /* leaf: first triangle (leaf order); inner: right child index */
    uint32_t count;     /* leaf: triangle count (>= 1); inner: 0 (left child = this + 1) */
} sl_bvh_node;

typedef struct sl_triangle_bvh {
    uint64_t node_count;
    sl_bvh_node *nodes;
    uint64_t triangle_count;
    float *corners;       /* 9 * triangle_count: a, b, c of each triangle in leaf order */
    uint32_t *source;     /* triangle_count: index in the mesh of each leaf-order triangle */
} sl_triangle_bvh;

/* Where on triangle (a, b, c) a closest point lies: its Voronoi region. Signed distance
 * needs it: the sign of (p - q) . N is exact for a closed, consistently wound mesh when N
 * is the pseudonormal of that region (Baerentzen and Aanaes, IEEE TVCG 11(3), 2005): the
 * face normal inside the face, the sum of the adjacent face normals on an edge, the
 * angle-weighted sum at a vertex. */
enum sl_triangle_feature {
    SL_FEATURE_FACE = 0,
    SL_FEATURE_VERTEX_A = 1, SL_FEATURE_VERTEX_B = 2, SL_FEATURE_VERTEX_C = 3,
    SL_FEATURE_EDGE_AB = 4, SL_FEATURE_EDGE_BC = 5, SL_FEATURE_EDGE_CA = 6
};

/* Result of one query. */
typedef struct sl_closest {
    double distance_sq;   /* squared distance to the closest point, world^2 */
    double point[3];      /* the closest point, world */
    uint32_t triangle;    /* its triangle, leaf order (bvh->source maps it to the mesh) */
    int feature;          /* enum sl_triangle_feature, in that triangle's corner order */
} sl_closest;

/* Builds the tree over every triangle of `mesh` (positions must be finite; the caller
 * checks). Fails with SL_E_NOMEM, or SL_E_LIMIT above 2^32 - 1 triangles. */
int sl_triangle_bvh_build(sl_triangle_bvh *bvh, const sl_mesh *mesh, sl_error *err);
void sl_triangle_bvh_release(sl_triangle_bvh *bvh);

/* The closest point of the triangles to `p`. `hint` is a leaf-order triangle to try
 * first (the previous query's answer for a nearby point prunes most of the tree), or
 * UINT32_MAX for none. The tree must hold at least one triangle. */
void sl_triangle_bvh_closest(const sl_triangle_bvh *bvh, const double p[3], uint32_t hint,
                             sl_closest *out);

/* Closest point on triangle (a, b, c) to p (Ericson 5.1.5, with degenerate triangles
 * handled as their longest edge); returns the squared distance. */
double sl_closest_point_triangle(const double p[3], const double a[3], const double b[3],
                                 const double c[3], double out[3]);
/* The same, also naming the region the point lies in (*feature: enum sl_triangle_feature).
 * A sliver's closest point is on an edge or a vertex. */
double sl_closest_point_triangle_feature(const double p[3], const double a[3], const double b[3],
                                         const double c[3], double out[3], int *feature);

#endif
