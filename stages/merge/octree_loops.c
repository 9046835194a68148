/* A node's dual loops as the quadric vertices see them (vertices_internal.h): how many it
 * draws, its corner and a crossing in leaf-grid units, and the loop nearest a point, which
 * both the leaves' pieces (octree_pieces.c) and the parents' gathering (octree_vertices.c)
 * send their quadrics to. */
#include <float.h>
#include <string.h>

#include "geometry/triangle_bvh.h"
#include "runtime/lod_dual.h"
#include "runtime/mc_cube.h"
#include "stages/merge/vertices_internal.h"

int sl_vertices_node_loops(const sl_octree_node *n)
{
    return sl_dual_uniform_table()[n->inside].loops;
}

/* Node corner in leaf-grid units. */
void sl_vertices_node_corner(const sl_octree_node *n, double c[3])
{
    double s = (double)(1u << n->level);
    c[0] = n->x * s;
    c[1] = n->y * s;
    c[2] = n->z * s;
}

/* A crossing's position in grid units relative to `corner`. */
void sl_vertices_crossing_local(const sl_octree *t, uint32_t id, const double corner[3],
                                double p[3])
{
    for (int a = 0; a < 3; a++)
        p[a] = (t->crossing_position[3 * (size_t)id + a] - t->origin[a]) / t->leaf_size - corner[a];
}

/* The loop of node n nearest to point p (grid units relative to the node's corner): the
 * loop whose fan (from its first crossing) comes closest. */
int sl_vertices_nearest_loop(const sl_octree *t, const sl_octree_node *n, const double p[3])
{
    const sl_mc_triangles *u = &sl_dual_uniform_table()[n->inside];
    if (u->loops < 2)
        return 0;
    double corner[3];
    sl_vertices_node_corner(n, corner);
    int best = 0;
    double best_d = DBL_MAX;
    for (int l = 0; l < u->loops; l++) {
        double v0[3], v1[3], v2[3], q[3];
        sl_vertices_crossing_local(t, sl_octree_crossing(t, n, u->loop_points[l][0]), corner, v0);
        sl_vertices_crossing_local(t, sl_octree_crossing(t, n, u->loop_points[l][1]), corner, v2);
        for (int k = 2; k < u->loop_sizes[l]; k++) {
            memcpy(v1, v2, sizeof v1);
            sl_vertices_crossing_local(t, sl_octree_crossing(t, n, u->loop_points[l][k]), corner, v2);
            double d = sl_closest_point_triangle(p, v0, v1, v2, q);
            if (d < best_d) {
                best_d = d;
                best = l;
            }
        }
    }
    return best;
}
