/* Same-level neighbours of every octree node, for the priority stage's level-difference
 * rule and for generation (lod_model.h): the priority stage builds the table, and reading
 * a model of format 3 rebuilds it (the file does not store it: lod_io.h). */
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_model.h"

/* Any layout: a binary search per neighbour (sl_octree_find). */
static int build_by_search(const sl_octree *t, sl_neighbours *out)
{
    memset(out, 0, sizeof *out);
    out->mask = calloc(t->node_count ? t->node_count : 1, sizeof *out->mask);
    out->base = calloc(t->node_count ? t->node_count : 1, sizeof *out->base);
    if (!out->mask || !out->base)
        goto nomem;
#pragma omp parallel for schedule(dynamic, 256)
    for (uint32_t i = 0; i < t->node_count; i++) {
        const sl_octree_node *n = &t->nodes[i];
        uint32_t mask = 0;
        for (int d = 0; d < 27; d++) {
            if (d == 13)
                continue;
            int dx = d % 3 - 1, dy = d / 3 % 3 - 1, dz = d / 9 - 1;
            if (sl_octree_find(t, n->level, (int64_t)n->x + dx, (int64_t)n->y + dy,
                               (int64_t)n->z + dz) != SL_OCTREE_NONE)
                mask |= 1u << d;
        }
        out->mask[i] = mask;
    }
    for (uint32_t i = 0; i < t->node_count; i++) {
        out->base[i] = (uint32_t)out->count;
        out->count += (uint64_t)__builtin_popcount(out->mask[i]);
    }
    out->index = malloc((out->count ? out->count : 1) * sizeof *out->index);
    if (!out->index)
        goto nomem;
#pragma omp parallel for schedule(dynamic, 256)
    for (uint32_t i = 0; i < t->node_count; i++) {
        const sl_octree_node *n = &t->nodes[i];
        uint32_t k = out->base[i];
        for (int d = 0; d < 27; d++)
            if (out->mask[i] >> d & 1)
                out->index[k++] = sl_octree_find(t, n->level, (int64_t)n->x + d % 3 - 1,
                                                 (int64_t)n->y + d / 3 % 3 - 1,
                                                 (int64_t)n->z + d / 9 - 1);
    }
    return 0;
nomem:
    sl_neighbours_release(out);
    return -1;
}

/* Whether the levels lie root first, descending, each contiguous (as the merge stage
 * writes them): then a node's parent level is complete before the node's. */
static int levels_descending(const sl_octree *t)
{
    uint64_t at = 0;
    for (int l = (int)t->depth; l >= 0; l--) {
        if (t->level_first[l] != at)
            return 0;
        at += t->level_count[l];
    }
    return at == t->node_count;
}

/* Node i's neighbour in direction d through its parent's: the cell's parent is the parent
 * itself or one of its neighbours, and the cell is that node's child in its octant (the
 * octree's children sit in their octants, in octant order). The same node the search
 * finds, in O(1). */
static uint32_t via_parent(const sl_octree *t, const sl_neighbours *nb, uint32_t i, int d)
{
    const sl_octree_node *n = &t->nodes[i];
    if (n->parent == SL_OCTREE_NONE || n->parent >= i)
        return SL_OCTREE_NONE;
    int64_t x = (int64_t)n->x + d % 3 - 1, y = (int64_t)n->y + d / 3 % 3 - 1,
            z = (int64_t)n->z + d / 9 - 1;
    if (x < 0 || y < 0 || z < 0)
        return SL_OCTREE_NONE;
    const sl_octree_node *p = &t->nodes[n->parent];
    int64_t ex = (x >> 1) - p->x, ey = (y >> 1) - p->y, ez = (z >> 1) - p->z;
    if (ex < -1 || ex > 1 || ey < -1 || ey > 1 || ez < -1 || ez > 1)
        return SL_OCTREE_NONE;
    int dp = (int)(ex + 1 + 3 * (ey + 1) + 9 * (ez + 1));
    uint32_t q = dp == 13 ? n->parent : sl_neighbour(nb, n->parent, dp);
    if (q == SL_OCTREE_NONE)
        return SL_OCTREE_NONE;
    unsigned o = (unsigned)((x & 1) | (y & 1) << 1 | (z & 1) << 2);
    unsigned mask = t->nodes[q].child_mask;
    if (!(mask >> o & 1))
        return SL_OCTREE_NONE;
    return t->nodes[q].first_child + (uint32_t)__builtin_popcount(mask & ((1u << o) - 1u));
}

/* Level by level from the root: each level's masks, bases and indices from its parents'. */
static int build_by_parents(const sl_octree *t, sl_neighbours *out)
{
    memset(out, 0, sizeof *out);
    uint32_t n = t->node_count;
    out->mask = calloc(n ? n : 1, sizeof *out->mask);
    out->base = calloc(n ? n : 1, sizeof *out->base);
    uint64_t capacity = (uint64_t)n + 1;
    out->index = malloc(capacity * sizeof *out->index);
    if (!out->mask || !out->base || !out->index)
        goto nomem;
    for (int l = (int)t->depth; l >= 0; l--) {
        uint32_t first = t->level_first[l], end = first + t->level_count[l];
#pragma omp parallel for schedule(static)
        for (uint32_t i = first; i < end; i++) {
            uint32_t mask = 0;
            for (int d = 0; d < 27; d++)
                if (d != 13 && via_parent(t, out, i, d) != SL_OCTREE_NONE)
                    mask |= 1u << d;
            out->mask[i] = mask;
        }
        uint64_t count = out->count;
        for (uint32_t i = first; i < end; i++) {
            out->base[i] = (uint32_t)count;
            count += (uint64_t)__builtin_popcount(out->mask[i]);
        }
        if (count > capacity) {
            while (capacity < count)
                capacity *= 2;
            uint32_t *grown = realloc(out->index, capacity * sizeof *out->index);
            if (!grown)
                goto nomem;
            out->index = grown;
        }
#pragma omp parallel for schedule(static)
        for (uint32_t i = first; i < end; i++) {
            uint32_t k = out->base[i];
            for (int d = 0; d < 27; d++)
                if (out->mask[i] >> d & 1)
                    out->index[k++] = via_parent(t, out, i, d);
        }
        out->count = count;
    }
    return 0;
nomem:
    sl_neighbours_release(out);
    return -1;
}

int sl_neighbours_build(const sl_octree *t, sl_neighbours *out)
{
    return levels_descending(t) ? build_by_parents(t, out) : build_by_search(t, out);
}
