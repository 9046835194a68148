/* Area-difference metric, node errors and the expansion order (paper 1, section 2.3;
 * priority.h). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/triangle_bvh.h"
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
            double best = INFINITY, q[3];
            for (int i = 0; i < count; i++) {
                double d2 = sl_closest_point_triangle(p, tri[i][0], tri[i][1], tri[i][2], q);
                best = d2 < best ? d2 : best;
            }
            worst = fmax(worst, sqrt(best));
        }
    }
    if (count == 0 && child_points > 0) /* the node draws nothing its children draw */
        return t->leaf_size * (double)(1u << n->level) * sqrt(3.0);
    return worst;
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
        error[i] = kids ? (float)node_error(t, n) : 0.0f;
    }
    free(area);
    return 0;
}

/* ---- the expansion order ----------------------------------------------------------- */

typedef struct heap_entry {
    float key;
    uint32_t node;
} heap_entry;

/* a before b: larger area difference first, then smaller index (deterministic). */
static int before(heap_entry a, heap_entry b)
{
    return a.key > b.key || (a.key == b.key && a.node < b.node);
}

static void heap_push(heap_entry *h, uint32_t *size, heap_entry e)
{
    uint32_t i = (*size)++;
    while (i > 0 && before(e, h[(i - 1) / 2])) {
        h[i] = h[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h[i] = e;
}

static heap_entry heap_pop(heap_entry *h, uint32_t *size)
{
    heap_entry top = h[0], last = h[--*size];
    uint32_t i = 0;
    for (;;) {
        uint32_t c = 2 * i + 1;
        if (c >= *size)
            break;
        if (c + 1 < *size && before(h[c + 1], h[c]))
            c++;
        if (!before(h[c], last))
            break;
        h[i] = h[c];
        i = c;
    }
    if (*size > 0)
        h[i] = last;
    return top;
}

/* A coarser unexpanded node around n (the level-difference rule), or NONE. The nodes one
 * level up around n are n's parent (expanded) and its neighbours. */
static uint32_t blocker(const sl_octree *t, const sl_neighbours *nb, const uint32_t *expanded_at,
                        uint32_t n)
{
    const sl_octree_node *node = &t->nodes[n];
    if (node->parent == SL_OCTREE_NONE)
        return SL_OCTREE_NONE;
    const sl_octree_node *p = &t->nodes[node->parent];
    for (int d = 0; d < 27; d++) {
        if (d == 13)
            continue;
        int64_t q[3] = {(int64_t)node->x + d % 3 - 1, (int64_t)node->y + d / 3 % 3 - 1,
                        (int64_t)node->z + d / 9 - 1};
        int off[3];
        int64_t pc[3] = {p->x, p->y, p->z};
        for (int a = 0; a < 3; a++)
            off[a] = (int)((q[a] >= 0 ? q[a] / 2 : -1) - pc[a]);
        int pd = sl_direction(off[0], off[1], off[2]);
        if (pd == 13)
            continue;
        uint32_t m = sl_neighbour(nb, node->parent, pd);
        if (m != SL_OCTREE_NONE && expanded_at[m] == SL_OCTREE_NONE)
            return m;
    }
    return SL_OCTREE_NONE;
}

int sl_priority_order(const sl_octree *t, const sl_neighbours *nb, const float *area_difference,
                      uint32_t *lod_array, uint32_t *expansion_count, sl_error *err)
{
    uint32_t n = t->node_count, size = 0, k = 0;
    heap_entry *heap = malloc((n ? n : 1) * sizeof *heap);
    uint32_t *expanded_at = malloc((n ? n : 1) * sizeof *expanded_at);
    uint32_t *wait_head = malloc((n ? n : 1) * sizeof *wait_head);
    uint32_t *wait_next = malloc((n ? n : 1) * sizeof *wait_next);
    if (!heap || !expanded_at || !wait_head || !wait_next) {
        free(heap);
        free(expanded_at);
        free(wait_head);
        free(wait_next);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory ordering the LOD");
    }
    memset(expanded_at, 0xff, (size_t)n * sizeof *expanded_at);
    memset(wait_head, 0xff, (size_t)n * sizeof *wait_head);
    if (t->nodes[0].child_mask)
        heap_push(heap, &size, (heap_entry){area_difference[0], 0});
    while (size > 0) {
        uint32_t node = heap_pop(heap, &size).node;
        uint32_t b = blocker(t, nb, expanded_at, node);
        if (b != SL_OCTREE_NONE) { /* wait until the coarser neighbour expands */
            wait_next[node] = wait_head[b];
            wait_head[b] = node;
            continue;
        }
        expanded_at[node] = k;
        lod_array[k++] = node;
        const sl_octree_node *p = &t->nodes[node];
        for (int c = 0; c < __builtin_popcount(p->child_mask); c++) {
            uint32_t child = p->first_child + (uint32_t)c;
            if (t->nodes[child].child_mask)
                heap_push(heap, &size, (heap_entry){area_difference[child], child});
        }
        for (uint32_t w = wait_head[node]; w != SL_OCTREE_NONE; w = wait_next[w])
            heap_push(heap, &size, (heap_entry){area_difference[w], w});
        wait_head[node] = SL_OCTREE_NONE;
    }
    uint32_t internal = 0;
    for (uint32_t i = 0; i < n; i++)
        internal += t->nodes[i].child_mask != 0;
    free(heap);
    free(expanded_at);
    free(wait_head);
    free(wait_next);
    *expansion_count = k;
    if (k != internal)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL,
                            "expansion order stopped after %u of %u internal nodes", k, internal);
    return 0;
}
