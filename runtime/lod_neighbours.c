/* Same-level neighbours of every octree node, for the priority stage's level-difference
 * rule and for generation (lod_model.h): the priority stage builds the table, and reading
 * a model of format 3 rebuilds it (the file does not store it: lod_io.h). */
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_model.h"

int sl_neighbours_build(const sl_octree *t, sl_neighbours *out)
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
