/* Which level: the expansion count k for a triangle budget, a LOD percent or a maximum
 * error (paper 1, section 3: "we convert this input to the priority number by using the
 * accumulation table"), and the per-expansion surface counts LOD percents rest on.
 */
#include <math.h>
#include <stdlib.h>

#include "runtime/lod_model.h"

/* surface_before (see lod_model.h). Nodes are stored coarse to fine, so a reverse sweep
 * sees every child before its parent. */
int sl_lod_surface_counts(const sl_lod_model *m, uint32_t *out)
{
    const sl_octree *t = &m->tree;
    uint8_t *below = calloc(t->node_count ? t->node_count : 1, 1);
    if (!below)
        return -1;
    for (uint32_t i = t->node_count; i-- > 0;) {
        const sl_octree_node *node = &t->nodes[i];
        below[i] |= node->edge_mask != 0;
        if (below[i] && node->parent != SL_OCTREE_NONE)
            below[node->parent] = 1;
    }
    out[0] = 0;
    for (uint32_t k = 0; k < m->expansion_count; k++)
        out[k + 1] = out[k] + below[m->lod_array[k]];
    free(below);
    return 0;
}

uint32_t sl_lod_expansions_for_triangles(const sl_lod_model *m, uint64_t budget)
{
    /* The largest k whose mesh -- and every coarser one -- fits the budget. */
    uint32_t k = 0;
    uint64_t peak = m->accumulation[0];
    while (k < m->expansion_count) {
        uint64_t next = m->accumulation[k + 1];
        if (next > peak)
            peak = next;
        if (peak > budget)
            break;
        k++;
    }
    return k;
}

uint32_t sl_lod_expansions_for_percent(const sl_lod_model *m, double percent)
{
    if (!(percent > 0))
        return 0;
    uint32_t total = m->surface_before[m->expansion_count];
    uint32_t want = percent >= 100 ? total : (uint32_t)llround(percent / 100.0 * total);
    uint32_t lo = 0, hi = m->expansion_count; /* smallest k with surface_before[k] >= want */
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (m->surface_before[mid] < want)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

uint32_t sl_lod_expansions_for_error(const sl_lod_model *m, double max_error)
{
    uint32_t lo = 0, hi = m->expansion_count; /* error_after is non-increasing */
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (m->error_after[mid] <= max_error)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}
