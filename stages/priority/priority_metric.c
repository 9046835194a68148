/* The priority metric (paper 1, section 2.3; priority.h; docs/lod.md "The priority
 * metric"): area difference, node errors and the expansion keys. The order they drive,
 * under the level-difference rule: priority_order.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/triangle_bvh.h"
#include "runtime/lod_dual.h"
#include "stages/priority/priority.h"

/* The node's uniform marching-cube triangles as world positions; returns the count. */
static int node_triangles(const sl_octree *t, const sl_octree_node *n, double tri[][3][3])
{
    const sl_mc_triangles *cell = &sl_mc_uniform_table()[n->inside];
    for (int i = 0; i < cell->count; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t c = sl_octree_crossing(t, n, cell->points[i][k]);
            for (int a = 0; a < 3; a++)
                tri[i][k][a] = t->crossing_position[3 * (size_t)c + a];
        }
    return cell->count;
}

static double triangle_area(const double p[3][3])
{
    double u[3], v[3];
    for (int a = 0; a < 3; a++) {
        u[a] = p[1][a] - p[0][a];
        v[a] = p[2][a] - p[0][a];
    }
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

static double node_area(const sl_octree *t, const sl_octree_node *n)
{
    double tri[SL_MC_MAX_TRIANGLES][3][3], area = 0;
    int count = node_triangles(t, n, tri);
    for (int i = 0; i < count; i++)
        area += triangle_area(tri[i]);
    return area;
}

/* Squared distance from p to the nearest of `count` triangles. */
static double point_to_triangles(const double p[3], double tri[][3][3], int count)
{
    double best = INFINITY, q[3];
    for (int i = 0; i < count; i++) {
        double d2 = sl_closest_point_triangle(p, tri[i][0], tri[i][1], tri[i][2], q);
        best = d2 < best ? d2 : best;
    }
    return best;
}

/* Largest distance from the children's crossing points to the node's own triangles. */
static double node_error(const sl_octree *t, const sl_octree_node *n)
{
    double tri[SL_MC_MAX_TRIANGLES][3][3];
    int count = node_triangles(t, n, tri), kids = __builtin_popcount(n->child_mask);
    double worst = 0;
    int child_points = 0;
    for (int c = 0; c < kids; c++) {
        const sl_octree_node *child = &t->nodes[n->first_child + (uint32_t)c];
        for (int e = 0; e < 12; e++) {
            if (!(child->edge_mask >> e & 1))
                continue;
            child_points++;
            if (count == 0)
                continue;
            uint32_t id = sl_octree_crossing(t, child, e);
            double p[3] = {t->crossing_position[3 * (size_t)id], t->crossing_position[3 * (size_t)id + 1],
                           t->crossing_position[3 * (size_t)id + 2]};
            worst = fmax(worst, sqrt(point_to_triangles(p, tri, count)));
        }
    }
    if (count == 0 && child_points > 0) /* the node draws nothing its children draw */
        return t->leaf_size * (double)(1u << n->level) * sqrt(3.0);
    return worst;
}

static const char *const metric_names[] = {"error", "hausdorff", "area", "qef", "auto"};

int sl_priority_metric_parse(const char *name)
{
    for (int i = 0; i < 5; i++)
        if (!strcmp(name, metric_names[i]))
            return i;
    return -1;
}

const char *sl_priority_metric_name(sl_priority_metric metric)
{
    return metric_names[metric];
}

int sl_priority_metrics(const sl_octree *t, float *area_difference, float *error)
{
    float *area = malloc((t->node_count ? t->node_count : 1) * sizeof *area);
    if (!area)
        return -1;
#pragma omp parallel for schedule(dynamic, 1024)
    for (uint32_t i = 0; i < t->node_count; i++)
        area[i] = (float)node_area(t, &t->nodes[i]);
#pragma omp parallel for schedule(dynamic, 256)
    for (uint32_t i = 0; i < t->node_count; i++) {
        const sl_octree_node *n = &t->nodes[i];
        int kids = __builtin_popcount(n->child_mask);
        double sum = 0;
        for (int c = 0; c < kids; c++)
            sum += area[n->first_child + (uint32_t)c];
        area_difference[i] = kids ? (float)(sum - area[i]) : 0.0f;
        if (sl_octree_dual(t))
            error[i] = kids && t->node_area[i] > 0
                           ? (float)sqrt((double)t->node_error[i] / t->node_area[i])
                           : 0.0f;
        else
            error[i] = kids ? (float)node_error(t, n) : 0.0f;
    }
    free(area);
    return 0;
}

/* ---- error-driven keys ------------------------------------------------------------- */

/* The leaves under node i: the contiguous range [*lo, *hi) of level 0 (each level is in
 * Morton order, so a subtree's nodes on any level are contiguous). */
static void leaf_range(const sl_octree *t, uint32_t i, uint32_t *lo, uint32_t *hi)
{
    uint32_t a = i, b = i;
    while (t->nodes[a].level > 0 && t->nodes[a].child_mask)
        a = t->nodes[a].first_child;
    while (t->nodes[b].level > 0 && t->nodes[b].child_mask)
        b = t->nodes[b].first_child + (uint32_t)__builtin_popcount(t->nodes[b].child_mask) - 1u;
    *lo = a;
    *hi = t->nodes[a].level == 0 && t->nodes[b].level == 0 ? b + 1 : a;
}

/* How far node i's own triangles are from the finest surface under it (its leaves'
 * triangles), both ways: leaf triangle centroids and corners against the node's triangles,
 * and the node's triangle centroids and corners against the leaf triangles. *worst = the
 * largest of these distances (a Hausdorff estimate), *squares = the area-weighted sum of
 * squared centroid distances of both sides (the node's share of the squared error behind
 * an RMS figure). A node that draws nothing where its leaves draw, or draws where they
 * draw nothing, is charged its cell edge per point. */
static void deep_error(const sl_octree *t, uint32_t i, double *worst, double *squares)
{
    double own[SL_MC_MAX_TRIANGLES][3][3], leaf[SL_MC_MAX_TRIANGLES][3][3];
    int count = node_triangles(t, &t->nodes[i], own);
    double missing = t->leaf_size * (double)(1u << t->nodes[i].level);
    /* Own samples (centroids, then corners) and their nearest leaf triangle so far. */
    double own_point[4 * SL_MC_MAX_TRIANGLES][3], own_best[4 * SL_MC_MAX_TRIANGLES];
    for (int k = 0; k < count; k++)
        for (int a = 0; a < 3; a++) {
            own_point[k][a] = (own[k][0][a] + own[k][1][a] + own[k][2][a]) / 3.0;
            for (int v = 0; v < 3; v++)
                own_point[count + 3 * k + v][a] = own[k][v][a];
        }
    for (int k = 0; k < 4 * count; k++)
        own_best[k] = missing * missing;
    uint32_t lo, hi;
    leaf_range(t, i, &lo, &hi);
    double w = 0, s = 0;
    for (uint32_t l = lo; l < hi; l++) {
        int lc = node_triangles(t, &t->nodes[l], leaf);
        for (int k = 0; k < lc; k++) {
            double c[3];
            for (int a = 0; a < 3; a++)
                c[a] = (leaf[k][0][a] + leaf[k][1][a] + leaf[k][2][a]) / 3.0;
            double d2 = count ? point_to_triangles(c, own, count) : missing * missing;
            s += triangle_area(leaf[k]) * d2;
            for (int v = 0; v < 3 && count; v++)
                d2 = fmax(d2, point_to_triangles(leaf[k][v], own, count));
            w = fmax(w, d2);
        }
        for (int p = 0; p < 4 * count; p++)
            own_best[p] = fmin(own_best[p], point_to_triangles(own_point[p], leaf, lc));
    }
    for (int k = 0; k < count; k++) {
        s += triangle_area(own[k]) * own_best[k];
        for (int v = 0; v < 3; v++)
            w = fmax(w, own_best[count + 3 * k + v]);
    }
    *worst = sqrt(w);
    *squares = s;
}

/* key[r] = max(key[r], its children's keys), finest level first: a node with a costly
 * region anywhere below it comes before nodes whose whole subtree is cheaper. */
static void saturate(const sl_octree *t, float *key)
{
    for (uint32_t l = 1; l <= t->depth; l++) {
        uint32_t first = t->level_first[l], count = t->level_count[l];
#pragma omp parallel for schedule(static)
        for (uint32_t i = first; i < first + count; i++) {
            const sl_octree_node *r = &t->nodes[i];
            for (int c = 0; c < __builtin_popcount(r->child_mask); c++)
                key[i] = fmaxf(key[i], key[r->first_child + (uint32_t)c]);
        }
    }
}

/* Loops a node draws in a uniform cut: its own, unless it has no vertex. */
static int drawn_loops(const sl_octree *t, uint32_t i)
{
    if (t->vertex_first[i + 1] == t->vertex_first[i])
        return 0;
    return sl_dual_uniform_table()[t->nodes[i].inside].loops;
}

/* qef: the quadric error expanding r removes, per triangle it adds (a dual mesh has about
 * two triangles per vertex, one vertex per drawn loop). */
static void qef_keys(const sl_octree *t, float *key)
{
#pragma omp parallel for schedule(static)
    for (uint32_t i = 0; i < t->node_count; i++) {
        const sl_octree_node *r = &t->nodes[i];
        int kids = __builtin_popcount(r->child_mask), loops = -drawn_loops(t, i);
        double removed = t->node_error[i];
        for (int c = 0; c < kids; c++) {
            removed -= t->node_error[r->first_child + (uint32_t)c];
            loops += drawn_loops(t, r->first_child + (uint32_t)c);
        }
        key[i] = kids ? (float)(removed / fmax(2.0 * loops, 1.0)) : 0.0f;
    }
}

int sl_priority_keys(const sl_octree *t, sl_priority_metric metric, const float *area_difference,
                     float *key)
{
    uint32_t n = t->node_count;
    if (metric == SL_PRIORITY_AREA) {
        memcpy(key, area_difference, (size_t)n * sizeof *key);
        return 0;
    }
    if (metric == SL_PRIORITY_QEF) {
        if (!sl_octree_dual(t))
            return -1;
        qef_keys(t, key);
        return 0;
    }
    double *worst = malloc((n ? n : 1) * sizeof *worst), *squares = malloc((n ? n : 1) * sizeof *squares);
    if (!worst || !squares) {
        free(worst);
        free(squares);
        return -1;
    }
#pragma omp parallel for schedule(dynamic, 16)
    for (uint32_t i = 0; i < n; i++) {
        worst[i] = squares[i] = 0;
        if (t->nodes[i].child_mask)
            deep_error(t, i, &worst[i], &squares[i]);
    }
    const sl_mc_triangles *table = sl_mc_uniform_table();
#pragma omp parallel for schedule(static)
    for (uint32_t i = 0; i < n; i++) {
        const sl_octree_node *r = &t->nodes[i];
        int kids = __builtin_popcount(r->child_mask);
        double removed = squares[i], added = -(double)table[r->inside].count;
        for (int c = 0; c < kids; c++) {
            removed -= squares[r->first_child + (uint32_t)c];
            added += table[t->nodes[r->first_child + (uint32_t)c].inside].count;
        }
        /* error: squared error removed per triangle added (an expansion that adds none is
         * charged one: it comes early, without a division by zero or a negative) */
        double k = metric == SL_PRIORITY_HAUSDORFF ? worst[i] : removed / fmax(added, 1.0);
        key[i] = kids ? (float)k : 0.0f;
    }
    free(worst);
    free(squares);
    if (metric == SL_PRIORITY_HAUSDORFF)
        saturate(t, key);
    return 0;
}
