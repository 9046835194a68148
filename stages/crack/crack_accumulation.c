/* The accumulation table (paper 1, section 2.3: the triangle count after each expansion)
 * and the error table, the last part of the LOD model the crack stage builds (crack.h).
 *
 * Expansion i changes only the cells of the node itself, its children and the same-level
 * neighbours whose cells it splits; each is drawn before and after by sl_lod_cell
 * (runtime/lod_model.h: its signs, split by its transition record where a neighbour is
 * finer), so the table counts the triangles a cut at k holds. The deltas are independent: one parallel pass, then a
 * serial prefix sum.
 *
 * A dual model (runtime/lod_dual.h) has max(0, degree - 2) triangles per crossing, the
 * degree being how many drawn loops hold it: not a sum over cells. Its table comes from
 * one pass over the expansions in order that keeps every crossing's degree; the loops
 * each expansion removes and adds are drawn in parallel, a chunk of expansions at a time.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_dual.h"
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

/* ---- dual models ---------------------------------------------------------------------- */

typedef struct incidences {
    uint32_t *ids;          /* crossing id | REMOVED for a loop that goes */
    uint64_t count, capacity;
} incidences;

#define REMOVED 0x80000000u

/* Appends the crossings of the drawn loops of node n's cell after k expansions. */
static int cell_incidences(const sl_lod_model *m, uint32_t n, uint32_t k, uint32_t sign,
                           incidences *out)
{
    if (m->tree.vertex_first[n + 1] == m->tree.vertex_first[n])
        return 0; /* no vertex: its loops are not drawn */
    sl_mc_cell cell;
    uint32_t point_crossing[SL_MC_MAX_POINTS];
    sl_lod_cell(&m->tree, &m->neighbours, &m->transitions, m->expansion_index, k, n, &cell,
                point_crossing);
    sl_mc_triangles tri;
    sl_dual_loops(&cell, &tri);
    for (int l = 0; l < tri.loops; l++) {
        if (tri.loop_sizes[l] < 3)
            continue;
        if (out->count + tri.loop_sizes[l] > out->capacity) {
            uint64_t cap = out->capacity ? 2 * out->capacity : 4096;
            uint32_t *ids = realloc(out->ids, (size_t)cap * sizeof *ids);
            if (!ids)
                return -1;
            out->ids = ids;
            out->capacity = cap;
        }
        for (int i = 0; i < tri.loop_sizes[l]; i++)
            out->ids[out->count++] = point_crossing[tri.loop_points[l][i]] | sign;
    }
    return 0;
}

/* The loops expansion i removes and adds: the node's, its children's, and those of the
 * same-level neighbours whose cells it splits, before and after. */
static int expansion_incidences(const sl_lod_model *m, uint32_t i, incidences *out)
{
    uint32_t n = m->lod_array[i];
    const sl_octree_node *node = &m->tree.nodes[n];
    int rc = cell_incidences(m, n, i, REMOVED, out);
    for (int c = 0; c < __builtin_popcount(node->child_mask) && !rc; c++)
        rc = cell_incidences(m, node->first_child + (uint32_t)c, i + 1, 0, out);
    for (int d = 0; d < 27 && !rc; d++) {
        uint32_t nb = d == 13 ? SL_OCTREE_NONE : sl_neighbour(&m->neighbours, n, d);
        if (nb == SL_OCTREE_NONE || !frontier_at(m, nb, i))
            continue;
        rc = cell_incidences(m, nb, i, REMOVED, out);
        if (!rc)
            rc = cell_incidences(m, nb, i + 1, 0, out);
    }
    return rc;
}

/* Applies incidences to the degrees; returns the change in triangles. */
static int64_t apply(uint16_t *degree, const uint32_t *ids, uint64_t count)
{
    int64_t change = 0;
    for (uint64_t j = 0; j < count; j++) {
        uint32_t c = ids[j] & ~REMOVED;
        change -= sl_dual_polygon_triangles(degree[c]);
        degree[c] = (uint16_t)(ids[j] & REMOVED ? degree[c] - 1 : degree[c] + 1);
        change += sl_dual_polygon_triangles(degree[c]);
    }
    return change;
}

#define DUAL_CHUNK 2048 /* expansions drawn in parallel, then applied in order */

static int dual_accumulation(sl_lod_model *m)
{
    uint32_t e = m->expansion_count;
    uint16_t *degree = calloc(m->tree.crossing_count ? m->tree.crossing_count : 1, sizeof *degree);
    incidences *lists = calloc(DUAL_CHUNK, sizeof *lists), root = {NULL, 0, 0};
    int failed = !degree || !lists || cell_incidences(m, 0, 0, 0, &root);
    int64_t count = failed ? 0 : apply(degree, root.ids, root.count);
    free(root.ids);
    m->accumulation[0] = (uint64_t)count;
    for (uint32_t i0 = 0; i0 < e && !failed; i0 += DUAL_CHUNK) {
        uint32_t i1 = e - i0 < DUAL_CHUNK ? e : i0 + DUAL_CHUNK;
#pragma omp parallel for schedule(dynamic, 16)
        for (uint32_t i = i0; i < i1; i++) {
            lists[i - i0].count = 0;
            if (expansion_incidences(m, i, &lists[i - i0])) {
#pragma omp atomic write
                failed = 1;
            }
        }
        for (uint32_t i = i0; i < i1 && !failed; i++) {
            count += apply(degree, lists[i - i0].ids, lists[i - i0].count);
            m->accumulation[i + 1] = (uint64_t)(count < 0 ? 0 : count);
        }
    }
    for (uint32_t j = 0; lists && j < DUAL_CHUNK; j++)
        free(lists[j].ids);
    free(lists);
    free(degree);
    return failed ? -1 : 0;
}

/* Each node's expansion: what drawing a cell after k expansions reads (sl_lod_cell). The
 * rest of sl_lod_model_prepare (the cells laid out in LOD order, their split lists and
 * drawing states: 2.2-2.6 GB of the 20 M-triangle torus's model) is for generating
 * meshes, which the tables do not: the crack stage held it for nothing at its peak. */
static int index_expansions(sl_lod_model *m)
{
    uint32_t n = m->tree.node_count;
    free(m->expansion_index);
    m->expansion_index = malloc((n ? n : 1) * sizeof *m->expansion_index);
    if (!m->expansion_index)
        return -1;
    memset(m->expansion_index, 0xff, (size_t)n * sizeof *m->expansion_index);
    for (uint32_t i = 0; i < m->expansion_count; i++)
        m->expansion_index[m->lod_array[i]] = i;
    return 0;
}

int sl_lod_model_finish(sl_lod_model *m, const float *expansion_error, sl_error *err)
{
    uint32_t e = m->expansion_count;
    free(m->accumulation);
    free(m->error_after);
    m->accumulation = malloc(((size_t)e + 1) * sizeof *m->accumulation);
    m->error_after = malloc(((size_t)e + 1) * sizeof *m->error_after);
    int64_t *delta = malloc(((size_t)e + 1) * sizeof *delta);
    if (!m->accumulation || !m->error_after || !delta || index_expansions(m)) {
        free(delta);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    }
    if (sl_octree_dual(&m->tree)) {
        free(delta);
        if (dual_accumulation(m))
            return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    } else {
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
    }
    float worst = 0;
    m->error_after[e] = 0;
    for (uint32_t i = e; i-- > 0;) {
        if (expansion_error)
            worst = fmaxf(worst, expansion_error[i]);
        m->error_after[i] = worst;
    }
    return 0;
}
