/* Dual vertices of the marching-cube octree from quadrics of the input surface ([octree]
 * vertices = qef; merge.h, docs/lod.md "Vertices from quadrics").
 *
 * Method (dual contouring of Hermite data, Ju et al. 2002, with the quadrics of
 * Garland-Heckbert and Lindstrom's truncated solve, geometry/qef.h):
 *   leaves   the input's triangles are cut along the leaf grid (a triangle is split at its
 *            edge midpoints until it spans at most two cubes per axis, then clipped to
 *            each), each piece's plane goes, weighted by its area, into the quadric of
 *            the leaf's loop nearest to it (a point of a cloud: its tangent plane,
 *            weighted by the area a point stands for);
 *   parents  bottom-up, level by level, each child vertex's quadric is added to the
 *            parent's loop nearest to that vertex (all of them when the parent has one
 *            loop): the quadric of a loop is the sum over the input surface it stands for,
 *            accumulated by addition as the octree is;
 *   vertex   per loop the minimiser of its quadric (truncated at tau), clamped to the cell.
 * A node's error is the quadric error of its vertices (area x squared distance to the
 * surface's tangent planes) plus, for the surface its cell holds but draws no loop for,
 * area x (cell edge / 2)^2: what the priority stage orders expansions by.
 *
 * Units: quadrics live in leaf-grid units relative to their node's corner (numbers of
 * order one whatever the scan's coordinates), converted to world units on output.
 * Memory: the levels below the vertex bricks' (SL_VERTEX_BRICK_LEVEL) are built one brick
 * (subtree) at a time per thread, so the leaves' quadrics, 112 bytes a slot and the largest
 * table of the merge, are never held for the whole tree (docs/bricks.md).
 * Determinism: each leaf sums its pieces in item order (a brick's items are ascending),
 * each parent its children in octant order: the same sums whatever the brick level and the
 * thread count.
 */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/alloc.h"
#include "geometry/qef.h"
#include "geometry/triangle_bvh.h"
#include "runtime/lod_dual.h"
#include "runtime/mc_cube.h"
#include "stages/merge/merge.h"
#include "stages/merge/vertices_internal.h"

/* ---- levels -------------------------------------------------------------------------- */

/* Slots for the run of `count` nodes from `node0` (one level's, or a brick's part of it). */
static int slots_init(const sl_octree *t, uint32_t node0, uint32_t count, level_slots *ls)
{
    memset(ls, 0, sizeof *ls);
    ls->node0 = node0;
    ls->nodes = count;
    ls->first = malloc(((size_t)ls->nodes + 1) * sizeof *ls->first);
    if (!ls->first)
        return -1;
    uint32_t k = 0;
    for (uint32_t i = 0; i < ls->nodes; i++) {
        ls->first[i] = k;
        int loops = sl_vertices_node_loops(&t->nodes[ls->node0 + i]);
        k += (uint32_t)(loops ? loops : 1);
    }
    ls->first[ls->nodes] = k;
    ls->qef = sl_alloc_zeroed(k ? k : 1, sizeof *ls->qef);
    ls->x = sl_alloc_zeroed(3 * (size_t)(k ? k : 1), sizeof *ls->x);
    ls->color = t->crossing_color ? sl_alloc_zeroed(4 * (size_t)(k ? k : 1), sizeof *ls->color)
                                  : NULL;
    return ls->qef && ls->x && (ls->color || !t->crossing_color) ? 0 : -1;
}

static void slots_release(level_slots *ls)
{
    free(ls->first);
    free(ls->qef);
    free(ls->color);
    free(ls->x);
    memset(ls, 0, sizeof *ls);
}

/* Parent node p (octree index) sums its children's vertex quadrics into its slots. */
static void gather_children(const sl_octree *t, const level_slots *child, level_slots *ls,
                            uint32_t p)
{
    const sl_octree_node *n = &t->nodes[p];
    double pc[3];
    sl_vertices_node_corner(n, pc);
    uint32_t first = ls->first[p - ls->node0];
    for (int j = 0; j < __builtin_popcount(n->child_mask); j++) {
        uint32_t c = n->first_child + (uint32_t)j, ci = c - child->node0;
        double cc[3], t_shift[3];
        sl_vertices_node_corner(&t->nodes[c], cc);
        for (int a = 0; a < 3; a++)
            t_shift[a] = pc[a] - cc[a];
        for (uint32_t v = child->first[ci]; v < child->first[ci + 1]; v++) {
            if (!(child->qef[v].area > 0))
                continue;
            sl_qef q = child->qef[v];
            sl_qef_shift(&q, t_shift);
            double x[3];
            for (int a = 0; a < 3; a++)
                x[a] = child->x[3 * (size_t)v + (size_t)a] - t_shift[a];
            uint32_t to = first + (uint32_t)sl_vertices_nearest_loop(t, n, x);
            sl_qef_add(&ls->qef[to], &q);
            if (ls->color)
                for (size_t i = 0; i < 4; i++)
                    ls->color[4 * (size_t)to + i] += child->color[4 * (size_t)v + i];
        }
    }
}

/* Solves the run's vertices (in parallel when `parallel`: not inside a brick). */
static void solve_level(const sl_octree *t, level_slots *ls, double tau, int parallel)
{
#pragma omp parallel for schedule(static) if (parallel)
    for (uint32_t i = 0; i < ls->nodes; i++) {
        double size = (double)(1u << t->nodes[ls->node0 + i].level);
        const double lo[3] = {0, 0, 0}, hi[3] = {size, size, size};
        for (uint32_t v = ls->first[i]; v < ls->first[i + 1]; v++)
            sl_qef_solve(&ls->qef[v], tau, lo, hi, &ls->x[3 * (size_t)v]);
    }
}

/* ---- output -------------------------------------------------------------------------- */

/* Every node's slots, solved, in octree order (what the octree keeps is chosen once every
 * level's areas are known). */
typedef struct all_slots {
    uint32_t *first;        /* node_count + 1 */
    float *position;        /* 3 per slot, world */
    float *area;            /* world^2 */
    float *error;           /* world^4 */
    uint8_t *color;         /* 4 per slot, or NULL */
} all_slots;

/* The level's solved slots into `all` (world units). A loop that stands for no surface
 * sits at its crossings' centroid. */
static void store_level(const sl_octree *t, const level_slots *ls, all_slots *all, int parallel)
{
    double leaf = t->leaf_size, leaf2 = leaf * leaf;
#pragma omp parallel for schedule(static) if (parallel)
    for (uint32_t i = 0; i < ls->nodes; i++) {
        uint32_t node = ls->node0 + i;
        const sl_octree_node *n = &t->nodes[node];
        const sl_mc_triangles *u = &sl_dual_uniform_table()[n->inside];
        double corner[3];
        sl_vertices_node_corner(n, corner);
        for (uint32_t k = 0; k < ls->first[i + 1] - ls->first[i]; k++) {
            uint32_t v = ls->first[i] + k, g = all->first[node] + k;
            const sl_qef *q = &ls->qef[v];
            double x[3];
            memcpy(x, &ls->x[3 * (size_t)v], sizeof x);
            if (!(q->area > 0) && u->loops) {
                x[0] = x[1] = x[2] = 0;
                int m = u->loop_sizes[k];
                for (int j = 0; j < m; j++) {
                    double p[3];
                    sl_vertices_crossing_local(t, sl_octree_crossing(t, n, u->loop_points[k][j]), corner, p);
                    for (int a = 0; a < 3; a++)
                        x[a] += p[a] / m;
                }
            }
            for (int a = 0; a < 3; a++)
                all->position[3 * (size_t)g + (size_t)a] =
                    (float)(t->origin[a] + (corner[a] + x[a]) * leaf);
            all->area[g] = (float)(q->area * leaf2);
            all->error[g] = q->area > 0 ? (float)(fmax(0, sl_qef_eval(q, x)) * leaf2 * leaf2) : 0;
            if (all->color) {
                const double *sum = ls->color + 4 * (size_t)v;
                for (int j = 0; j < 4; j++)
                    all->color[4 * (size_t)g + (size_t)j] =
                        q->area > 0 ? (uint8_t)lround(fmin(255, fmax(0, sum[j] / q->area))) : 160;
            }
        }
    }
}

/* Brick k's levels below the bricks' (vertices_internal.h), bottom-up: the leaves'
 * quadrics from the brick's items, each parent's from its children; then the brick's root,
 * a slot run of `top` (the bricks' level), gathers its children. A brick's nodes at each
 * level are a run of that level's order, from its first node's first child to its last
 * node's last. Serial: the bricks run in parallel. */
static int run_brick(const sl_octree *t, const sl_surface *s, const vertex_bricks *vb,
                     uint32_t k, double tau, level_slots *top, all_slots *all)
{
    uint32_t root = t->level_first[vb->level] + k, lo = root, hi = root + 1;
    uint32_t first[SL_OCTREE_MAX_LEVELS], count[SL_OCTREE_MAX_LEVELS];
    for (uint32_t l = vb->level; l-- > 0;) {
        const sl_octree_node *a = &t->nodes[lo], *z = &t->nodes[hi - 1];
        lo = a->first_child;
        hi = z->first_child + (uint32_t)__builtin_popcount(z->child_mask);
        first[l] = lo;
        count[l] = hi - lo;
    }
    level_slots child, cur;
    memset(&child, 0, sizeof child);
    int rc = 0;
    for (uint32_t l = 0; l < vb->level && rc == 0; l++) {
        if (slots_init(t, first[l], count[l], &cur)) {
            slots_release(&cur);
            rc = -1;
            break;
        }
        if (l == 0)
            sl_vertices_leaf_quadrics(t, s, &cur, vb->item + vb->item_first[k],
                                      vb->item_first[k + 1] - vb->item_first[k]);
        else
            for (uint32_t i = 0; i < cur.nodes; i++)
                gather_children(t, &child, &cur, cur.node0 + i);
        solve_level(t, &cur, tau, 0);
        store_level(t, &cur, all, 0);
        slots_release(&child);
        child = cur;
    }
    if (rc == 0)
        gather_children(t, &child, top, root);
    slots_release(&child);
    return rc;
}

/* Every level's vertices: the levels below the bricks' brick by brick (one brick's slots
 * per thread at a time, not a level's), the rest level by level. */
static int run_levels(const sl_octree *t, const sl_surface *s, double tau, uint32_t brick_level,
                      all_slots *all, sl_error *err)
{
    uint32_t b = sl_vertex_brick_level(t, brick_level);
    level_slots child, cur;
    memset(&child, 0, sizeof child);
    memset(&cur, 0, sizeof cur);
    if (slots_init(t, t->level_first[b], t->level_count[b], &cur)) {
        slots_release(&cur);
        return sl_error_nomem(err, NULL, "out of memory placing vertices");
    }
    int rc = 0;
    if (b == 0) { /* one node: a brick of its own */
        sl_vertices_leaf_quadrics(t, s, &cur, NULL,
                                  s->triangle_count ? s->triangle_count : s->point_count);
    } else {
        vertex_bricks vb;
        rc = sl_vertex_bricks_bin(t, s, b, &vb, err);
        int failed = 0;
        if (rc == 0) {
#pragma omp parallel for schedule(dynamic, 1) reduction(| : failed)
            for (uint32_t k = 0; k < vb.count; k++)
                failed |= run_brick(t, s, &vb, k, tau, &cur, all) != 0;
            if (failed)
                rc = sl_error_nomem(err, NULL, "out of memory placing vertices");
        }
        sl_vertex_bricks_release(&vb);
    }
    for (uint32_t level = b; rc == 0; level++) {
        if (level > b) {
#pragma omp parallel for schedule(dynamic, 256)
            for (uint32_t i = 0; i < cur.nodes; i++)
                gather_children(t, &child, &cur, cur.node0 + i);
        }
        solve_level(t, &cur, tau, 1);
        store_level(t, &cur, all, 1);
        slots_release(&child);
        child = cur;
        memset(&cur, 0, sizeof cur);
        if (level == t->depth)
            break;
        if (slots_init(t, t->level_first[level + 1], t->level_count[level + 1], &cur))
            rc = sl_error_nomem(err, NULL, "out of memory placing vertices");
    }
    slots_release(&child);
    slots_release(&cur);
    return rc;
}

/* Vertices kept per node: its loops (or one cell vertex) when its cell holds surface; its
 * loops at their centroids when it holds none and the input is closed; none otherwise
 * (an open scan's loops beyond its border are trimmed). */
static uint32_t kept_vertices(const sl_octree *t, const all_slots *all, uint32_t node, int open)
{
    int loops = sl_vertices_node_loops(&t->nodes[node]);
    double area = 0;
    for (uint32_t g = all->first[node]; g < all->first[node + 1]; g++)
        area += all->area[g];
    if (area > 0)
        return (uint32_t)(loops ? loops : 1);
    return loops && !open ? (uint32_t)loops : 0;
}

static int write_output(sl_octree *t, const all_slots *all, int open)
{
    uint64_t total = 0;
    t->vertex_first = malloc(((size_t)t->node_count + 1) * sizeof *t->vertex_first);
    if (!t->vertex_first)
        return -1;
    for (uint32_t i = 0; i < t->node_count; i++) {
        t->vertex_first[i] = (uint32_t)total;
        total += kept_vertices(t, all, i, open);
    }
    if (total >= UINT32_MAX)
        return -1;
    t->vertex_first[t->node_count] = (uint32_t)total;
    t->vertex_count = (uint32_t)total;
    t->vertex_position = malloc((total ? total : 1) * 3 * sizeof(float));
    t->vertex_color = t->crossing_color ? malloc((total ? total : 1) * 4) : NULL;
    t->node_error = malloc((size_t)t->node_count * sizeof(float));
    t->node_area = malloc((size_t)t->node_count * sizeof(float));
    if (!t->vertex_position || (t->crossing_color && !t->vertex_color) || !t->node_error ||
        !t->node_area)
        return -1;
    for (uint32_t i = 0; i < t->node_count; i++) {
        const sl_octree_node *n = &t->nodes[i];
        uint32_t g = all->first[i], slots = all->first[i + 1] - g;
        uint32_t out = t->vertex_first[i], count = t->vertex_first[i + 1] - out;
        memcpy(t->vertex_position + 3 * (size_t)out, all->position + 3 * (size_t)g,
               3 * (size_t)count * sizeof(float));
        if (t->vertex_color)
            memcpy(t->vertex_color + 4 * (size_t)out, all->color + 4 * (size_t)g, 4 * (size_t)count);
        double area = 0, error = 0, edge = t->leaf_size * (double)(1u << n->level);
        for (uint32_t k = 0; k < slots; k++) {
            area += all->area[g + k];
            error += all->error[g + k];
        }
        if (!sl_vertices_node_loops(n)) /* surface that no loop of the cell draws */
            error = area * 0.25 * edge * edge;
        t->node_error[i] = (float)error;
        t->node_area[i] = (float)area;
    }
    return 0;
}

static void drop_output(sl_octree *t)
{
    free(t->vertex_first);
    free(t->vertex_position);
    free(t->vertex_color);
    free(t->node_error);
    free(t->node_area);
    t->vertex_first = NULL;
    t->vertex_position = NULL;
    t->vertex_color = NULL;
    t->node_error = t->node_area = NULL;
    t->vertex_count = 0;
}

int sl_octree_vertices(sl_octree *t, const sl_surface *s, double tau, uint32_t brick_level,
                       sl_error *err)
{
    drop_output(t);
    if (s->triangle_count == 0 && !s->normals)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "vertices need triangles or normals");
    all_slots all = {malloc(((size_t)t->node_count + 1) * sizeof(uint32_t)), NULL, NULL, NULL,
                     NULL};
    int rc = all.first ? 0 : sl_error_nomem(err, NULL, "out of memory placing vertices");
    if (rc == 0) {
        uint64_t k = 0;
        for (uint32_t i = 0; i < t->node_count; i++) {
            all.first[i] = (uint32_t)k;
            int loops = sl_vertices_node_loops(&t->nodes[i]);
            k += (uint64_t)(loops ? loops : 1);
        }
        all.first[t->node_count] = (uint32_t)k;
        all.position = malloc((k ? k : 1) * 3 * sizeof(float));
        all.area = malloc((k ? k : 1) * sizeof(float));
        all.error = malloc((k ? k : 1) * sizeof(float));
        all.color = t->crossing_color ? malloc((k ? k : 1) * 4) : NULL;
        if (k >= UINT32_MAX || !all.position || !all.area || !all.error ||
            (t->crossing_color && !all.color))
            rc = sl_error_nomem(err, NULL, "out of memory placing vertices");
    }
    if (rc == 0)
        rc = run_levels(t, s, tau, brick_level, &all, err);
    if (rc == 0 && write_output(t, &all, s->open))
        rc = sl_error_nomem(err, NULL, "out of memory placing vertices");
    free(all.first);
    free(all.position);
    free(all.area);
    free(all.error);
    free(all.color);
    if (rc)
        drop_output(t);
    return rc;
}
