/* k-d tree (Bentley 1975; Friedman, Bentley & Finkel 1977: median split on the widest
 * axis, branch-and-bound search visiting the near child first).
 *
 * Method: the points are copied into one array of {x, y, z, index} records and reordered
 * in place while building, so every leaf is a contiguous run of at most LEAF_SIZE records
 * (cache friendly queries, no per-point pointers). Each split is at the median of the
 * node's widest axis, found by quickselect on the key (coordinate, index;
 * geometry/axis_select.h): all keys are distinct, so the tree shape is a pure function of
 * the input. Queries keep the k best candidates sorted by (squared distance, index), which
 * makes equal distances resolve to the lower index, and prune a far child only when its
 * splitting plane is strictly farther than the current k-th candidate.
 *
 * A uniform grid hash was the other candidate; on scans whose density varies by orders
 * of magnitude (range scans: dense near the scanner, sparse at grazing angles) a grid
 * needs a per-cell size choice that the tree does not (timings: docs/range-stage.md).
 */
#include "geometry/kdtree.h"

#include <stdlib.h>
#include <string.h>

#include "geometry/axis_select.h"

enum { LEAF_SIZE = 8, AXIS_LEAF = 3, STACK_RESULTS = 256 };
#define PARALLEL_RECORDS 65536u /* subtrees at least this big are built as tasks */

/* The records: {x, y, z, the caller's point index}. */
typedef sl_axis_record kd_point;

typedef struct kd_node {
    float split;        /* inner: left has key <= split, right >= split on `axis` */
    uint32_t axis;      /* 0..2, or AXIS_LEAF */
    uint32_t begin, end; /* range of records (leaf) */
    uint32_t child;     /* inner: left child; right child = child + 1 */
} kd_node;

struct sl_kdtree {
    kd_point *points;
    uint32_t count;
    kd_node *nodes;
    uint32_t node_capacity; /* slots; unused ones are never reached */
};

/* Node slots reserved below the root of a subtree of n records: B(n) = n/2 - 2. It
 * covers the subtree because B(n) >= 2 + B(n/2) + B(n - n/2) (the two children and their
 * reservations), and a leaf needs B >= 0, true for every leaf that comes from a split
 * (> LEAF_SIZE records halve into >= LEAF_SIZE / 2 = 4). About n/2 nodes in all. */
static uint64_t descendants_bound(uint64_t n)
{
    return n < 4 ? 0 : n / 2 - 2;
}

/* Builds the subtree of records [begin, end) into node `at`; its descendants take node
 * slots from `region` on. Each child's subtree gets its own slot range sized by
 * descendants_bound, so the layout does not depend on which task runs first and large
 * subtrees are built as parallel OpenMP tasks (unused slots are left as empty leaves). */
static void build_node(sl_kdtree *t, uint32_t at, uint32_t begin, uint32_t end, uint64_t region)
{
    kd_node *nd = &t->nodes[at];
    nd->begin = begin;
    nd->end = end;
    if (end - begin <= LEAF_SIZE) {
        nd->axis = AXIS_LEAF;
        nd->split = 0.0f;
        nd->child = 0;
        return;
    }
    uint32_t n = end - begin, half = n / 2;
    int axis = sl_axis_widest(t->points + begin, n);
    sl_axis_select(t->points + begin, n, half, axis);
    uint32_t child = (uint32_t)region;
    uint64_t left_region = region + 2, right_region = left_region + descendants_bound(half);
    nd->axis = (uint32_t)axis;
    nd->split = t->points[begin + half].p[axis];
    nd->child = child;
#pragma omp task if (n > PARALLEL_RECORDS) default(shared) firstprivate(child, begin, half, left_region)
    build_node(t, child, begin, begin + half, left_region);
    build_node(t, child + 1, begin + half, end, right_region);
#pragma omp taskwait
}

int sl_kdtree_build(sl_kdtree **out, const float *points, uint64_t count, sl_error *err)
{
    *out = NULL;
    if (count > SL_KDTREE_MAX_POINTS)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "k-d tree: %llu points exceed the limit",
                            (unsigned long long)count);
    sl_kdtree *t = calloc(1, sizeof *t);
    if (!t)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "k-d tree: out of memory");
    t->count = (uint32_t)count;
    uint64_t capacity = 1 + descendants_bound(count);
    if (capacity > UINT32_MAX) {
        sl_kdtree_free(t);
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "k-d tree: %llu points need too many nodes",
                            (unsigned long long)count);
    }
    t->node_capacity = (uint32_t)capacity;
    t->points = malloc((count ? count : 1) * sizeof *t->points);
    t->nodes = malloc((size_t)t->node_capacity * sizeof *t->nodes);
    if (!t->points || !t->nodes) {
        sl_kdtree_free(t);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "k-d tree: out of memory (%llu points)",
                            (unsigned long long)count);
    }
    for (uint32_t i = 0; i < t->count; i++) {
        memcpy(t->points[i].p, points + 3 * (uint64_t)i, 3 * sizeof(float));
        t->points[i].index = i;
    }
#pragma omp parallel if (count > PARALLEL_RECORDS)
#pragma omp single
    build_node(t, 0, 0, t->count, 1);
    *out = t;
    return SL_OK;
}

typedef struct knn_state {
    const float *q;
    uint32_t k, found;
    uint32_t *idx;
    float *dist2;
} knn_state;

static void knn_offer(knn_state *s, float d2, uint32_t index)
{
    uint32_t pos = s->found;
    if (s->found == s->k) {
        uint32_t last = s->k - 1;
        if (d2 > s->dist2[last] || (d2 == s->dist2[last] && index > s->idx[last]))
            return;
        pos = last;
    } else {
        s->found++;
    }
    while (pos > 0 && (d2 < s->dist2[pos - 1] ||
                       (d2 == s->dist2[pos - 1] && index < s->idx[pos - 1]))) {
        s->dist2[pos] = s->dist2[pos - 1];
        s->idx[pos] = s->idx[pos - 1];
        pos--;
    }
    s->dist2[pos] = d2;
    s->idx[pos] = index;
}

static void knn_visit(const sl_kdtree *t, uint32_t at, knn_state *s)
{
    const kd_node *nd = &t->nodes[at];
    if (nd->axis == AXIS_LEAF) {
        for (uint32_t i = nd->begin; i < nd->end; i++) {
            const kd_point *p = &t->points[i];
            float dx = p->p[0] - s->q[0], dy = p->p[1] - s->q[1], dz = p->p[2] - s->q[2];
            knn_offer(s, dx * dx + dy * dy + dz * dz, p->index);
        }
        return;
    }
    float diff = s->q[nd->axis] - nd->split;
    uint32_t near = diff <= 0.0f ? nd->child : nd->child + 1;
    knn_visit(t, near, s);
    /* The plane bound only (not the cell's): rounding keeps it a true lower bound, so
     * ties at exactly the k-th distance, which may hide a lower index on the far side,
     * are never pruned. */
    if (s->found < s->k || diff * diff <= s->dist2[s->k - 1])
        knn_visit(t, near == nd->child ? nd->child + 1 : nd->child, s);
}

uint32_t sl_kdtree_knn(const sl_kdtree *tree, const float query[3], uint32_t k,
                       uint32_t *out_idx, float *out_dist2)
{
    if (!tree || tree->count == 0 || k == 0)
        return 0;
    if (k > tree->count)
        k = tree->count;
    float stack_dist2[STACK_RESULTS];
    float *dist2 = out_dist2;
    if (!dist2) {
        dist2 = k <= STACK_RESULTS ? stack_dist2 : malloc((size_t)k * sizeof *dist2);
        if (!dist2)
            return 0;
    }
    knn_state s = {query, k, 0, out_idx, dist2};
    knn_visit(tree, 0, &s);
    if (!out_dist2 && dist2 != stack_dist2)
        free(dist2);
    return s.found;
}

uint32_t sl_kdtree_nearest(const sl_kdtree *tree, const float query[3], float *dist2)
{
    uint32_t idx = UINT32_MAX;
    float d2 = 0.0f;
    if (sl_kdtree_knn(tree, query, 1, &idx, &d2) == 0)
        return UINT32_MAX;
    if (dist2)
        *dist2 = d2;
    return idx;
}

uint64_t sl_kdtree_count(const sl_kdtree *tree)
{
    return tree ? tree->count : 0;
}

void sl_kdtree_free(sl_kdtree *tree)
{
    if (!tree)
        return;
    free(tree->points);
    free(tree->nodes);
    free(tree);
}
