/* What every level of the octree build does, the leaves (octree_leaves.c) and the parents
 * (octree_build.c) alike (merge_internal.h): room for crossings, nodes in Morton order, a
 * node's corner signs from its level's vertex table, the level's sign-changing edges and
 * each node's crossings on them. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/key_table.h"
#include "runtime/mc_cube.h"
#include "stages/merge/merge_internal.h"

int sl_merge_crossings_reserve(build_state *b, uint32_t extra)
{
    crossing_table *c = &b->crossings;
    if ((uint64_t)c->count + extra >= UINT32_MAX)
        return sl_error_set(b->err, SL_E_LIMIT, 0, NULL, "more than 2^32 crossings");
    if (c->count + extra <= c->capacity)
        return 0;
    uint32_t cap = c->capacity ? c->capacity : 1024;
    while (cap < c->count + extra)
        cap = cap > UINT32_MAX / 2 ? UINT32_MAX - 1 : cap * 2;
    float *p = realloc(c->position, (size_t)cap * 3 * sizeof *p);
    if (!p)
        return nomem(b);
    c->position = p;
    if (b->coloured) {
        uint8_t *col = realloc(c->color, (size_t)cap * 4);
        if (!col)
            return nomem(b);
        c->color = col;
    }
    c->capacity = cap;
    return 0;
}

/* Sorts `count` nodes (x, y, z filled) into Morton order. */
int sl_merge_sort_nodes_morton(build_state *b, sl_octree_node *nodes, size_t count)
{
    sl_key_pair *pairs = malloc(count * sizeof *pairs);
    sl_octree_node *copy = malloc(count * sizeof *copy);
    if (!pairs || !copy) {
        free(pairs);
        free(copy);
        return nomem(b);
    }
    for (size_t i = 0; i < count; i++) {
        pairs[i].key = sl_morton3((uint32_t)nodes[i].x, (uint32_t)nodes[i].y, (uint32_t)nodes[i].z);
        pairs[i].value = i;
    }
    int rc = sl_sort_pairs(pairs, count, 3 * SL_COORD_BITS);
    if (rc == 0) {
        memcpy(copy, nodes, count * sizeof *copy);
        for (size_t i = 0; i < count; i++)
            nodes[i] = copy[pairs[i].value];
    }
    free(pairs);
    free(copy);
    return rc ? nomem(b) : 0;
}

/* Corner signs of every node from the level's vertex table. */
void sl_merge_node_signs(level_tables *l)
{
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < l->ncount; i++) {
        sl_octree_node *n = &l->nodes[i];
        uint8_t inside = 0;
        for (int c = 0; c < 8; c++) {
            int64_t v = vertex_index(l, (uint32_t)(n->x + corner_offset(c, 0)),
                                     (uint32_t)(n->y + corner_offset(c, 1)),
                                     (uint32_t)(n->z + corner_offset(c, 2)));
            if (v >= 0 && l->vinside[v])
                inside |= (uint8_t)(1u << c);
        }
        n->inside = inside;
        uint16_t mask = 0;
        for (int e = 0; e < 12; e++)
            if (((inside >> sl_mc_edge_c0(e)) ^ (inside >> sl_mc_edge_c1(e))) & 1)
                mask |= (uint16_t)(1u << e);
        n->edge_mask = mask;
    }
}

/* Keys of every edge with a crossing, over all nodes of the level, sorted and unique. */
int sl_merge_collect_edges(build_state *b, level_tables *l)
{
    size_t total = 0;
    for (size_t i = 0; i < l->ncount; i++)
        total += (size_t)__builtin_popcount(l->nodes[i].edge_mask);
    uint64_t *keys = malloc((total ? total : 1) * sizeof *keys);
    if (!keys)
        return nomem(b);
    size_t k = 0;
    for (size_t i = 0; i < l->ncount; i++) {
        const sl_octree_node *n = &l->nodes[i];
        for (int e = 0; e < 12; e++) {
            if (!(n->edge_mask >> e & 1))
                continue;
            int c0 = sl_mc_edge_c0(e);
            keys[k++] = sl_edge_key(sl_vertex_key((uint32_t)(n->x + corner_offset(c0, 0)),
                                                  (uint32_t)(n->y + corner_offset(c0, 1)),
                                                  (uint32_t)(n->z + corner_offset(c0, 2))),
                                    sl_mc_edge_axis(e));
        }
    }
    if (sl_sort_keys(keys, total, 3 * SL_COORD_BITS + 2) != 0) {
        free(keys);
        return nomem(b);
    }
    l->ecount = sl_unique_keys(keys, total);
    l->ekeys = keys;
    l->ecrossing = malloc((l->ecount ? l->ecount : 1) * sizeof *l->ecrossing);
    return l->ecrossing ? 0 : nomem(b);
}

/* Per node, the crossing id of each edge (from the level's edge table). */
int sl_merge_node_crossings(build_state *b, level_tables *l)
{
    l->ncross = malloc((l->ncount ? l->ncount : 1) * 12 * sizeof *l->ncross);
    if (!l->ncross)
        return nomem(b);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < l->ncount; i++) {
        const sl_octree_node *n = &l->nodes[i];
        for (int e = 0; e < 12; e++) {
            uint32_t id = SL_OCTREE_NONE;
            if (n->edge_mask >> e & 1) {
                int c0 = sl_mc_edge_c0(e);
                uint64_t key = sl_edge_key(
                    sl_vertex_key((uint32_t)(n->x + corner_offset(c0, 0)),
                                  (uint32_t)(n->y + corner_offset(c0, 1)),
                                  (uint32_t)(n->z + corner_offset(c0, 2))),
                    sl_mc_edge_axis(e));
                int64_t at = sl_find_key(l->ekeys, l->ecount, key);
                if (at >= 0)
                    id = l->ecrossing[at];
            }
            l->ncross[12 * i + (size_t)e] = id;
        }
    }
    return 0;
}

/* ---- level l + 1 from level l ----------------------------------------------------- */
