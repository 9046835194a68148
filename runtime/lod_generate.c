/* Direct generation of a level of detail from the LOD array (paper 1, section 3).
 *
 * The frontier after k expansions is read off the LOD array: the children of the first k
 * expanded nodes that are not themselves among them. Each frontier cell is drawn from its
 * own signs and crossings, split where a same-level neighbour is expanded (that side is one
 * level finer; the priority order keeps it at most one), with the finer points taken from
 * the cell's precomputed transition record. Cost O(k + m): no search, no sorting.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_model.h"

void sl_lod_model_init(sl_lod_model *m)
{
    memset(m, 0, sizeof *m);
    sl_octree_init(&m->tree);
}

void sl_lod_model_release(sl_lod_model *m)
{
    sl_octree_release(&m->tree);
    free(m->lod_array);
    free(m->expansion_index);
    free(m->accumulation);
    free(m->error_after);
    free(m->scratch);
    sl_neighbours_release(&m->neighbours);
    sl_transitions_release(&m->transitions);
    sl_lod_model_init(m);
}

static int face_direction(int f)
{
    int a = f / 2, d = f % 2 ? 1 : -1;
    return sl_direction(a == 0 ? d : 0, a == 1 ? d : 0, a == 2 ? d : 0);
}

/* The 3 same-level neighbours sharing edge e. */
static void edge_directions(int e, int dirs[3])
{
    int a = sl_mc_edge_axis(e), c0 = sl_mc_edge_c0(e), b = (a + 1) % 3, c = (a + 2) % 3;
    int off_b[3] = {0, 0, 0}, off_c[3] = {0, 0, 0};
    off_b[b] = (c0 >> b & 1) ? 1 : -1;
    off_c[c] = (c0 >> c & 1) ? 1 : -1;
    dirs[0] = sl_direction(off_b[0], off_b[1], off_b[2]);
    dirs[1] = sl_direction(off_c[0], off_c[1], off_c[2]);
    dirs[2] = sl_direction(off_b[0] + off_c[0], off_b[1] + off_c[1], off_b[2] + off_c[2]);
}

static int expanded(const uint32_t *expansion_index, uint32_t node, uint32_t k)
{
    return node != SL_OCTREE_NONE && expansion_index[node] < k;
}

typedef struct record_view {
    uint32_t mid_known, mid_inside, centre_known, centre_inside, half_mask, spoke_mask;
    const uint32_t *ids;
} record_view;

static void decode(const sl_transitions *tr, uint32_t n, record_view *r)
{
    const uint32_t *w = tr->words + tr->base[n];
    r->mid_known = w[0] & 0xfff;
    r->mid_inside = w[0] >> 12 & 0xfff;
    r->centre_known = w[0] >> 24 & 0x3f;
    r->half_mask = w[1] & 0xffffff;
    r->centre_inside = w[1] >> 24 & 0x3f;
    r->spoke_mask = w[2] & 0xffffff;
    r->ids = w + 3;
}

static uint32_t half_id(const record_view *r, int j)
{
    if (!(r->half_mask >> j & 1))
        return SL_OCTREE_NONE;
    return r->ids[__builtin_popcount(r->half_mask & ((1u << j) - 1u))];
}

static uint32_t spoke_id(const record_view *r, int j)
{
    if (!(r->spoke_mask >> j & 1))
        return SL_OCTREE_NONE;
    return r->ids[__builtin_popcount(r->half_mask) +
                  __builtin_popcount(r->spoke_mask & ((1u << j) - 1u))];
}

/* Splits edge e of the cell (its same-level neighbourhood has an expanded cell). The
 * finer level's midpoint sign and half-edge crossings come from the record. A midpoint no
 * finer cell touches means the finer side draws nothing along this edge: the edge is then
 * split "virtually" (midpoint sign = first corner's), keeping the coarse crossing, which
 * every cell around the edge does alike. Returns 0, or -1 when a finer crossing the
 * signs require is missing from the record (a crack the report counts). */
static int split_edge(const record_view *r, const sl_octree_node *node, int e, sl_mc_cell *cell,
                      uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    int in0 = node->inside >> sl_mc_edge_c0(e) & 1, in1 = node->inside >> sl_mc_edge_c1(e) & 1;
    int mid = (r->mid_known >> e & 1) ? (int)(r->mid_inside >> e & 1) : in0;
    uint32_t coarse = point_crossing[SL_MC_EDGE_POINT(e)];
    uint32_t half[2] = {SL_OCTREE_NONE, SL_OCTREE_NONE};
    int flips[2] = {in0 != mid, mid != in1}, rc = 0;
    for (int h = 0; h < 2; h++) {
        if (!flips[h])
            continue;
        half[h] = (r->mid_known >> e & 1) ? half_id(r, 2 * e + h) : SL_OCTREE_NONE;
        /* The coarse crossing is the finer crossing of the half where the sign flips. */
        if (half[h] == SL_OCTREE_NONE && in0 != in1)
            half[h] = coarse;
        if (half[h] == SL_OCTREE_NONE)
            rc = -1;
    }
    if (rc)
        return rc; /* drawn whole: the finer side disagrees here */
    cell->split_edges |= (uint16_t)(1u << e);
    if (mid)
        cell->mid_inside |= (uint16_t)(1u << e);
    point_crossing[SL_MC_HALF_POINT(e, 0)] = half[0];
    point_crossing[SL_MC_HALF_POINT(e, 1)] = half[1];
    return 0;
}

/* Splits face f when a finer cell touches it (its centre is known); 0, or -1 when a
 * spoke crossing the signs require is missing. */
static int split_face(const record_view *r, int f, sl_mc_cell *cell,
                      uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    if (!(r->centre_known >> f & 1))
        return 0; /* no finer cell on this face: it is drawn whole on both sides */
    int edges[4], centre = r->centre_inside >> f & 1;
    uint32_t spokes[4];
    sl_mc_face_edges(f, edges);
    for (int k = 0; k < 4; k++) {
        if (!(cell->split_edges >> edges[k] & 1))
            return -1;
        spokes[k] = SL_OCTREE_NONE;
        if ((int)(cell->mid_inside >> edges[k] & 1) != centre) {
            spokes[k] = spoke_id(r, 4 * f + k);
            if (spokes[k] == SL_OCTREE_NONE)
                return -1;
        }
    }
    cell->split_faces |= (uint8_t)(1u << f);
    if (centre)
        cell->centre_inside |= (uint8_t)(1u << f);
    for (int k = 0; k < 4; k++)
        point_crossing[SL_MC_SPOKE_POINT(f, k)] = spokes[k];
    return 0;
}

int sl_lod_cell(const sl_octree *t, const sl_neighbours *nb, const sl_transitions *tr,
                const uint32_t *expansion_index, uint32_t k, uint32_t n, sl_mc_cell *cell,
                uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    const sl_octree_node *node = &t->nodes[n];
    memset(cell, 0, sizeof *cell);
    cell->inside = node->inside;
    for (int e = 0; e < 12; e++)
        point_crossing[SL_MC_EDGE_POINT(e)] =
            (node->edge_mask >> e & 1) ? sl_octree_crossing(t, node, e) : SL_OCTREE_NONE;
    if (node->level == 0 || tr->base[n] == SL_OCTREE_NONE)
        return 0; /* a leaf never meets a finer cell */
    unsigned want_faces = 0, want_edges = 0;
    for (int f = 0; f < 6; f++)
        if (expanded(expansion_index, sl_neighbour(nb, n, face_direction(f)), k)) {
            int edges[4];
            sl_mc_face_edges(f, edges);
            want_faces |= 1u << f;
            for (int i = 0; i < 4; i++)
                want_edges |= 1u << edges[i];
        }
    for (int e = 0; e < 12; e++) {
        int dirs[3];
        edge_directions(e, dirs);
        for (int i = 0; i < 3; i++)
            if (expanded(expansion_index, sl_neighbour(nb, n, dirs[i]), k))
                want_edges |= 1u << e;
    }
    if (!want_edges)
        return 0;
    record_view r;
    decode(tr, n, &r);
    int rc = 0;
    for (int e = 0; e < 12; e++)
        if (want_edges >> e & 1)
            rc |= split_edge(&r, node, e, cell, point_crossing);
    for (int f = 0; f < 6; f++)
        if (want_faces >> f & 1)
            rc |= split_face(&r, f, cell, point_crossing);
    return rc ? -1 : 0;
}

uint64_t sl_lod_frontier_bound(const sl_lod_model *m, uint32_t k)
{
    return k == 0 ? 1 : 8 * (uint64_t)k;
}

uint64_t sl_lod_frontier(const sl_lod_model *m, uint32_t k, uint32_t *cells)
{
    if (k > m->expansion_count)
        k = m->expansion_count;
    if (k == 0) {
        cells[0] = 0; /* the root */
        return 1;
    }
    uint64_t count = 0;
    for (uint32_t i = 0; i < k; i++) {
        const sl_octree_node *p = &m->tree.nodes[m->lod_array[i]];
        int kids = __builtin_popcount(p->child_mask);
        for (int c = 0; c < kids; c++) {
            uint32_t child = p->first_child + (uint32_t)c;
            if (m->expansion_index[child] >= k)
                cells[count++] = child;
        }
    }
    return count;
}

int sl_lod_generate(sl_lod_model *m, uint32_t k, sl_lod_mesh *out, uint64_t *cracks)
{
    memset(out, 0, sizeof *out);
    if (k > m->expansion_count)
        k = m->expansion_count;
    uint32_t *cells = malloc(sl_lod_frontier_bound(m, k) * sizeof *cells);
    sl_mesh_builder b;
    if (!cells || sl_mesh_builder_init(&b, &m->tree, m->scratch)) {
        free(cells);
        return -1;
    }
    uint64_t count = sl_lod_frontier(m, k, cells), incomplete = 0;
    for (uint64_t i = 0; i < count; i++) {
        sl_mc_cell cell;
        uint32_t point_crossing[SL_MC_MAX_POINTS];
        if (sl_lod_cell(&m->tree, &m->neighbours, &m->transitions, m->expansion_index, k,
                        cells[i], &cell, point_crossing))
            incomplete++;
        sl_mc_triangles tri;
        sl_mc_triangulate(&cell, &tri);
        sl_mesh_builder_add_cell(&b, &tri, point_crossing);
    }
    free(cells);
    if (cracks)
        *cracks = incomplete;
    return sl_mesh_builder_finish(&b, out);
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
    if (percent >= 100)
        return m->expansion_count;
    return (uint32_t)llround(percent / 100.0 * m->expansion_count);
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
