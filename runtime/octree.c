/* Octree basics: lifetime, lookup, Morton codes (see octree.h). */
#include "runtime/octree.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

void sl_octree_init(sl_octree *t)
{
    memset(t, 0, sizeof *t);
}

void sl_octree_release(sl_octree *t)
{
    free(t->nodes);
    free(t->crossing_position);
    free(t->crossing_color);
    free(t->node_crossings);
    free(t->morton);
    free(t->vertex_first);
    free(t->vertex_position);
    free(t->vertex_color);
    free(t->node_error);
    free(t->node_area);
    sl_octree_init(t);
}

void sl_octree_drop_node_metrics(sl_octree *t)
{
    free(t->node_error);
    free(t->node_area);
    t->node_error = t->node_area = NULL;
}

static uint64_t spread_bits(uint32_t v)
{
    uint64_t x = v & 0xfffffu; /* 20 bits */
    x = (x | x << 32) & 0x001f00000000ffffULL;
    x = (x | x << 16) & 0x001f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

uint64_t sl_morton3(uint32_t x, uint32_t y, uint32_t z)
{
    return spread_bits(x) | spread_bits(y) << 1 | spread_bits(z) << 2;
}

void sl_octree_corner_world(const sl_octree *t, const sl_octree_node *n, int c, double out[3])
{
    double size = t->leaf_size * (double)(1u << n->level);
    int32_t p[3] = {n->x + (c & 1), n->y + (c >> 1 & 1), n->z + (c >> 2 & 1)};
    for (int a = 0; a < 3; a++)
        out[a] = t->origin[a] + p[a] * size;
}

int sl_octree_index(sl_octree *t)
{
    free(t->morton);
    t->morton = malloc((t->node_count ? t->node_count : 1) * sizeof *t->morton);
    if (!t->morton)
        return -1;
#pragma omp parallel for schedule(static)
    for (uint32_t i = 0; i < t->node_count; i++)
        t->morton[i] = sl_morton3((uint32_t)t->nodes[i].x, (uint32_t)t->nodes[i].y,
                                  (uint32_t)t->nodes[i].z);
    return 0;
}

uint32_t sl_octree_search(const sl_octree *t, uint32_t lo, uint32_t hi, uint64_t key)
{
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        const sl_octree_node *n = &t->nodes[mid];
        uint64_t k = t->morton ? t->morton[mid]
                               : sl_morton3((uint32_t)n->x, (uint32_t)n->y, (uint32_t)n->z);
        if (k == key)
            return mid;
        if (k < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return SL_OCTREE_NONE;
}

uint32_t sl_octree_find(const sl_octree *t, uint32_t level, int64_t x, int64_t y, int64_t z)
{
    if (level > t->depth || x < 0 || y < 0 || z < 0 || x >= (1 << 20) || y >= (1 << 20) ||
        z >= (1 << 20))
        return SL_OCTREE_NONE;
    uint64_t key = sl_morton3((uint32_t)x, (uint32_t)y, (uint32_t)z);
    return sl_octree_search(t, t->level_first[level], t->level_first[level] + t->level_count[level],
                            key);
}

int sl_octree_permuted_crossings(const sl_octree *t, const uint32_t *new_id, float **position,
                                 uint8_t **color)
{
    uint32_t c = t->crossing_count;
    float *p = malloc((c ? c : 1) * 3 * sizeof *p);
    uint8_t *q = t->crossing_color ? malloc((c ? c : 1) * 4) : NULL;
    if (!p || (t->crossing_color && !q)) {
        free(p);
        free(q);
        return -1;
    }
    /* new_id is a permutation: each slot is written once, by one thread. */
#pragma omp parallel for schedule(static)
    for (uint32_t i = 0; i < c; i++) {
        memcpy(p + 3 * (size_t)new_id[i], t->crossing_position + 3 * (size_t)i, 3 * sizeof *p);
        if (q)
            memcpy(q + 4 * (size_t)new_id[i], t->crossing_color + 4 * (size_t)i, 4);
    }
    *position = p;
    *color = q;
    return 0;
}

void sl_octree_crossing_bounds(const sl_octree *t, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = FLT_MAX;
        hi[a] = -FLT_MAX;
    }
    for (uint32_t i = 0; i < t->crossing_count; i++)
        for (int a = 0; a < 3; a++) {
            float v = t->crossing_position[3 * (size_t)i + a];
            lo[a] = v < lo[a] ? v : lo[a];
            hi[a] = v > hi[a] ? v : hi[a];
        }
}
