/* The accumulation table (paper 1, section 2.3: the triangle count after each expansion)
 * and the error table, the last part of the LOD model the crack stage builds (crack.h).
 *
 * Expansion i changes only the cells of the node itself, its children and the same-level
 * neighbours whose cells it splits; each is drawn before and after by sl_lod_cell
 * (runtime/lod_model.h: its signs, split by its transition record where a neighbour is
 * finer), so the table counts the triangles a cut at k holds. The deltas are independent: one parallel pass, then a
 * serial prefix sum.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "stages/crack/crack.h"

static int cell_triangles(const sl_lod_model *m, uint32_t n, uint32_t k)
{
    sl_mc_cell cell;
    uint32_t point_crossing[SL_MC_MAX_POINTS];
    sl_lod_cell(&m->tree, &m->neighbours, &m->transitions, m->expansion_index, k, n, &cell,
                point_crossing);
    sl_mc_triangles tri;
    sl_mc_triangulate(&cell, &tri);
    return tri.count;
}

static int frontier_at(const sl_lod_model *m, uint32_t n, uint32_t k)
{
    uint32_t parent = m->tree.nodes[n].parent;
    return m->expansion_index[n] >= k &&
           (parent == SL_OCTREE_NONE || m->expansion_index[parent] < k);
}

/* Triangle count change of expansion i: the node, its children, and the same-level
 * neighbours whose cells it splits. */
static int64_t expansion_delta(const sl_lod_model *m, uint32_t i)
{
    uint32_t n = m->lod_array[i];
    const sl_octree_node *node = &m->tree.nodes[n];
    int64_t before = cell_triangles(m, n, i), after = 0;
    for (int c = 0; c < __builtin_popcount(node->child_mask); c++)
        after += cell_triangles(m, node->first_child + (uint32_t)c, i + 1);
    for (int d = 0; d < 27; d++) {
        uint32_t nb = d == 13 ? SL_OCTREE_NONE : sl_neighbour(&m->neighbours, n, d);
        if (nb == SL_OCTREE_NONE || !frontier_at(m, nb, i))
            continue;
        before += cell_triangles(m, nb, i);
        after += cell_triangles(m, nb, i + 1);
    }
    return after - before;
}

int sl_lod_model_finish(sl_lod_model *m, const float *node_error, sl_error *err)
{
    uint32_t e = m->expansion_count;
    free(m->accumulation);
    free(m->error_after);
    m->accumulation = malloc(((size_t)e + 1) * sizeof *m->accumulation);
    m->error_after = malloc(((size_t)e + 1) * sizeof *m->error_after);
    int64_t *delta = malloc(((size_t)e + 1) * sizeof *delta);
    if (!m->accumulation || !m->error_after || !delta || sl_lod_model_prepare(m)) {
        free(delta);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    }
#pragma omp parallel for schedule(dynamic, 256)
    for (uint32_t i = 0; i < e; i++)
        delta[i] = expansion_delta(m, i);
    int64_t count = cell_triangles(m, 0, 0);
    for (uint32_t i = 0; i <= e; i++) {
        m->accumulation[i] = (uint64_t)(count < 0 ? 0 : count);
        if (i < e)
            count += delta[i];
    }
    free(delta);
    float worst = 0;
    m->error_after[e] = 0;
    for (uint32_t i = e; i-- > 0;) {
        if (node_error)
            worst = fmaxf(worst, node_error[m->lod_array[i]]);
        m->error_after[i] = worst;
    }
    return 0;
}
