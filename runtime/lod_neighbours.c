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

static unsigned pop8(unsigned v) /* no popcount instruction is assumed */
{
    v = v - ((v >> 1) & 0x55u);
    v = (v & 0x33u) + ((v >> 2) & 0x33u);
    return (v + (v >> 4)) & 0x0fu;
}

/* For a child in octant o, direction d: the direction of its neighbour's parent from its
 * own parent (13: the same), and the neighbour's octant there. */
typedef struct octant_map {
    uint8_t up[8][27], octant[8][27];
} octant_map;

static void octant_map_init(octant_map *m)
{
    for (int o = 0; o < 8; o++)
        for (int d = 0; d < 27; d++) {
            int c[3] = {(o & 1) + d % 3 - 1, (o >> 1 & 1) + d / 3 % 3 - 1, (o >> 2) + d / 9 - 1};
            int up = 0, oc = 0, scale[3] = {1, 3, 9};
            for (int a = 0; a < 3; a++) { /* c in -1..2: parent offset floor(c / 2) */
                up += ((c[a] + 2) / 2 - 1 + 1) * scale[a];
                oc |= (c[a] & 1) << a;
            }
            m->up[o][d] = (uint8_t)up;
            m->octant[o][d] = (uint8_t)oc;
        }
}

/* Node i's same-level neighbours in the 27 directions (13: none), through its parent's:
 * a cell's parent is the parent itself or one of its neighbours, and the cell is that
 * node's child in its octant (the octree's children sit in their octants, in octant
 * order). The same nodes the search finds, in O(1) each. */
static void around(const sl_octree *t, const sl_neighbours *nb, const octant_map *map,
                   uint32_t i, uint32_t out[27])
{
    for (int d = 0; d < 27; d++)
        out[d] = SL_OCTREE_NONE;
    const sl_octree_node *n = &t->nodes[i];
    if (n->parent == SL_OCTREE_NONE || n->parent >= i)
        return;
    uint32_t up[27], mask = nb->mask[n->parent], k = nb->base[n->parent];
    for (int d = 0; d < 27; d++)
        up[d] = mask >> d & 1 ? nb->index[k++] : SL_OCTREE_NONE;
    up[13] = n->parent;
    unsigned o = (unsigned)((n->x & 1) | (n->y & 1) << 1 | (n->z & 1) << 2);
    for (int d = 0; d < 27; d++) {
        uint32_t q = up[map->up[o][d]];
        if (d == 13 || q == SL_OCTREE_NONE)
            continue;
        unsigned oc = map->octant[o][d], children = t->nodes[q].child_mask;
        if (children >> oc & 1)
            out[d] = t->nodes[q].first_child + pop8(children & ((1u << oc) - 1u));
    }
}

/* Level by level from the root: each level's masks, bases and indices from its parents'.
 * Below level `lowest` the links are only counted (*all_links) and the masks left 0. */
static int build_by_parents(const sl_octree *t, int lowest, sl_neighbours *out,
                            uint64_t *all_links)
{
    *all_links = 0;
    memset(out, 0, sizeof *out);
    uint32_t n = t->node_count;
    out->mask = calloc(n ? n : 1, sizeof *out->mask);
    out->base = calloc(n ? n : 1, sizeof *out->base);
    uint64_t capacity = (uint64_t)n + 1;
    out->index = malloc(capacity * sizeof *out->index);
    if (!out->mask || !out->base || !out->index)
        goto nomem;
    octant_map map;
    octant_map_init(&map);
    for (int l = (int)t->depth; l >= 0; l--) {
        uint32_t first = t->level_first[l], end = first + t->level_count[l];
#pragma omp parallel for schedule(static)
        for (uint32_t i = first; i < end; i++) {
            uint32_t cells[27], mask = 0;
            around(t, out, &map, i, cells);
            for (int d = 0; d < 27; d++)
                mask |= (uint32_t)(cells[d] != SL_OCTREE_NONE) << d;
            out->mask[i] = mask;
        }
        if (l < lowest) { /* counted, not kept */
            uint64_t links = 0;
            for (uint32_t i = first; i < end; i++) {
                links += (uint64_t)__builtin_popcount(out->mask[i]);
                out->base[i] = (uint32_t)out->count;
            }
            *all_links += links;
            memset(out->mask + first, 0, (size_t)(end - first) * sizeof *out->mask);
            continue;
        }
        uint64_t count = out->count;
        for (uint32_t i = first; i < end; i++) {
            out->base[i] = (uint32_t)count;
            count += (uint64_t)__builtin_popcount(out->mask[i]);
        }
        if (count > capacity) { /* exactly: the leaves' level is most of the table */
            capacity = count;
            uint32_t *grown = realloc(out->index, capacity * sizeof *out->index);
            if (!grown)
                goto nomem;
            out->index = grown;
        }
#pragma omp parallel for schedule(static)
        for (uint32_t i = first; i < end; i++) {
            uint32_t cells[27], k = out->base[i];
            around(t, out, &map, i, cells);
            for (int d = 0; d < 27; d++)
                if (cells[d] != SL_OCTREE_NONE)
                    out->index[k++] = cells[d];
        }
        *all_links += count - out->count;
        out->count = count;
    }
    return 0;
nomem:
    sl_neighbours_release(out);
    return -1;
}

int sl_neighbours_build(const sl_octree *t, sl_neighbours *out)
{
    uint64_t all;
    return levels_descending(t) ? build_by_parents(t, 0, out, &all) : build_by_search(t, out);
}

int sl_neighbours_build_internal(const sl_octree *t, sl_neighbours *out, uint64_t *all_links)
{
    if (!levels_descending(t)) {
        int rc = build_by_search(t, out);
        *all_links = out->count;
        return rc;
    }
    return build_by_parents(t, 1, out, all_links);
}
