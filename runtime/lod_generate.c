/* Direct generation of a level of detail from the LOD array (paper 1, section 3).
 *
 * The frontier after k expansions is read off the LOD array: the children of the first k
 * expanded nodes that are not themselves among them. Each frontier cell is drawn from its
 * own signs and crossings, split where a same-level neighbour is expanded (that side is one
 * level finer; the priority order keeps it at most one), with the finer points taken from
 * the cell's precomputed transition record. Cost O(k + m): no search, no sorting.
 */
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_dual.h"
#include "runtime/lod_model.h"
#include "runtime/lod_splits.h"

void sl_lod_model_init(sl_lod_model *m)
{
    memset(m, 0, sizeof *m);
    sl_octree_init(&m->tree);
}

void sl_lod_model_release(sl_lod_model *m)
{
    sl_octree_release(&m->tree);
    free(m->lod_array);
    free(m->accumulation);
    free(m->error_after);
    sl_lod_model_drop_layout(m);
    sl_neighbours_release(&m->neighbours);
    sl_transitions_release(&m->transitions);
    sl_lod_model_init(m);
}

void sl_lod_model_drop_layout(sl_lod_model *m)
{
    free(m->expansion_index);
    sl_mesh_scratch_release(&m->scratch);
    free(m->split_drawings);
    free(m->frontier_end);
    free(m->cells);
    free(m->split_words);
    free(m->surface_before);
    free(m->cell_node);
    free(m->dual_position);
    free(m->dual_color);
    m->expansion_index = m->split_drawings = m->frontier_end = m->split_words = NULL;
    m->surface_before = m->cell_node = NULL;
    m->cells = NULL;
    m->dual_position = NULL;
    m->dual_color = NULL;
    m->split_drawing_words = 0;
    m->dual_count = 0;
}

typedef struct record_view {
    uint32_t mid_known, mid_inside, centre_known, centre_inside, half_mask, spoke_mask;
    const uint32_t *ids;
} record_view;

static void decode(const uint32_t *w, record_view *r)
{
    r->mid_known = w[0] & 0xfff;
    r->mid_inside = w[0] >> 12 & 0xfff;
    r->centre_known = w[0] >> 24 & 0x3f;
    r->half_mask = w[1] & 0xffffff;
    r->centre_inside = w[1] >> 24 & 0x3f;
    r->spoke_mask = w[2] & 0xffffff;
    r->ids = w + 3;
}

/* Set bits of a 24-bit mask (inline: without -mpopcnt __builtin_popcount is a call). */
static inline uint32_t bits24(uint32_t x)
{
    x = x - (x >> 1 & 0x555555u);
    x = (x & 0x333333u) + (x >> 2 & 0x333333u);
    x = (x + (x >> 4)) & 0x0f0f0fu;
    return (x * 0x010101u) >> 16 & 0xff;
}

static uint32_t half_id(const record_view *r, int j)
{
    if (!(r->half_mask >> j & 1))
        return SL_OCTREE_NONE;
    return r->ids[bits24(r->half_mask & ((1u << j) - 1u))];
}

static uint32_t spoke_id(const record_view *r, int j)
{
    if (!(r->spoke_mask >> j & 1))
        return SL_OCTREE_NONE;
    return r->ids[bits24(r->half_mask) + bits24(r->spoke_mask & ((1u << j) - 1u))];
}

/* Splits edge e of the cell (its same-level neighbourhood has an expanded cell). The
 * finer level's midpoint sign and half-edge crossings come from the record. A midpoint no
 * finer cell touches means the finer side draws nothing along this edge: the edge is then
 * split "virtually" (midpoint sign = first corner's), keeping the coarse crossing, which
 * every cell around the edge does alike. Returns 0, or -1 when a finer crossing the
 * signs require is missing from the record (a crack the report counts). */
static int split_edge(const sl_lod_split_table *st, const record_view *r, int e,
                      sl_mc_cell *cell, uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    int in0 = cell->inside >> st->edge_c0[e] & 1, in1 = cell->inside >> st->edge_c1[e] & 1;
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
static int split_face(const sl_lod_split_table *st, const record_view *r, int f, sl_mc_cell *cell,
                      uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    if (!(r->centre_known >> f & 1))
        return 0; /* no finer cell on this face: it is drawn whole on both sides */
    int centre = r->centre_inside >> f & 1;
    const uint8_t *edges = st->face_edges[f];
    uint32_t spokes[4];
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

/* The node's own signs and edge crossings (its node_crossings run in edge order). */
static void cell_own(const sl_octree *t, const sl_octree_node *node, sl_mc_cell *cell,
                     uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    memset(cell, 0, sizeof *cell);
    cell->inside = node->inside;
    const uint32_t *ids = t->node_crossings + node->crossing_base;
    for (int e = 0; e < 12; e++)
        point_crossing[SL_MC_EDGE_POINT(e)] =
            (node->edge_mask >> e & 1) ? *ids++ : SL_OCTREE_NONE;
}

/* Faces and edges of internal node n to split after k expansions: those next to an
 * expanded same-level neighbour. Reads only the neighbours in directions that split. */
static void wanted_splits(const sl_neighbours *nb, const uint32_t *expansion_index, uint32_t k,
                          uint32_t n, unsigned *want_faces, unsigned *want_edges)
{
    const sl_lod_split_table *st = sl_lod_split_table_get();
    uint32_t mask = nb->mask[n];
    const uint32_t *index = nb->index + nb->base[n];
    unsigned faces = 0, edges = 0;
    for (int j = 0; mask; mask &= mask - 1u, j++) {
        int d = __builtin_ctz(mask);
        if ((st->split_dirs >> d & 1) && expansion_index[index[j]] < k) {
            faces |= st->faces[d];
            edges |= st->edges[d];
        }
    }
    *want_faces = faces;
    *want_edges = edges;
}

/* Applies the wanted splits to a cell with its own signs and crossings, from its transition
 * record `words`; 0, or -1 on a missing finer crossing. */
static int apply_splits(const sl_lod_split_table *st, const uint32_t *words,
                        unsigned want_faces, unsigned want_edges, sl_mc_cell *cell,
                        uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    record_view r;
    decode(words, &r);
    int rc = 0;
    for (int e = 0; e < 12; e++)
        if (want_edges >> e & 1)
            rc |= split_edge(st, &r, e, cell, point_crossing);
    for (int f = 0; f < 6; f++)
        if (want_faces >> f & 1)
            rc |= split_face(st, &r, f, cell, point_crossing);
    return rc ? -1 : 0;
}

int sl_lod_cell(const sl_octree *t, const sl_neighbours *nb, const sl_transitions *tr,
                const uint32_t *expansion_index, uint32_t k, uint32_t n, sl_mc_cell *cell,
                uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    const sl_octree_node *node = &t->nodes[n];
    cell_own(t, node, cell, point_crossing);
    if (node->level == 0 || tr->base[n] == SL_OCTREE_NONE)
        return 0; /* a leaf never meets a finer cell */
    unsigned want_faces, want_edges;
    wanted_splits(nb, expansion_index, k, n, &want_faces, &want_edges);
    if (!want_edges)
        return 0;
    return apply_splits(sl_lod_split_table_get(), tr->words + tr->base[n], want_faces,
                        want_edges, cell, point_crossing);
}

uint64_t sl_lod_frontier_bound(const sl_lod_model *m, uint32_t k)
{
    return k == 0 ? 1 : 8 * (uint64_t)k;
}

/* The frontier after k expansions: the children of lod_array[0..k) that are not themselves
 * expanded before k (the root when k = 0), in the order generation draws them. */
uint64_t sl_lod_frontier(const sl_lod_model *m, uint32_t k, uint32_t *cells)
{
    const sl_octree_node *nodes = m->tree.nodes;
    if (k > m->expansion_count)
        k = m->expansion_count;
    if (k == 0) {
        cells[0] = 0;
        return m->tree.node_count ? 1 : 0;
    }
    uint64_t count = 0;
    for (uint32_t i = 0; i < k; i++) {
        const sl_octree_node *p = &nodes[m->lod_array[i]];
        for (uint32_t c = p->first_child;
             c < p->first_child + (uint32_t)__builtin_popcount(p->child_mask); c++)
            if (m->expansion_index[c] >= k)
                cells[count++] = c;
    }
    return count;
}

/* The word of cell c's split list naming its state after k expansions, or NULL when no
 * face or edge of it meets a finer cell then; *want gets the splits. */
static uint32_t *split_state(const sl_lod_model *m, uint32_t k, const sl_lod_cell_ref *c,
                             uint32_t *want)
{
    if (c->splits == SL_OCTREE_NONE)
        return NULL; /* a leaf, or a cell no cut splits */
    uint32_t *w = m->split_words + c->splits;
    uint32_t splits = w[1] & 0xffffffu, events = w[1] >> 24, *state = w + 2;
    for (uint32_t i = 0; i < events && w[3 + 3 * i] < k; i++) {
        splits |= w[4 + 3 * i];
        state = w + 5 + 3 * i;
    }
    *want = splits;
    return SL_LOD_SPLIT_EDGES(splits) ? state : NULL;
}

int sl_lod_frontier_cell(const sl_lod_model *m, uint32_t k, const sl_lod_cell_ref *c,
                         const sl_lod_split_table *st, sl_mc_cell *cell,
                         uint32_t point_crossing[SL_MC_MAX_POINTS], uint32_t **entry)
{
    memset(cell, 0, sizeof *cell);
    cell->inside = c->inside;
    const uint32_t *ids = m->tree.node_crossings + c->crossing_base;
    for (int e = 0; e < 12; e++)
        point_crossing[SL_MC_EDGE_POINT(e)] = (c->edge_mask >> e & 1) ? *ids++ : SL_OCTREE_NONE;
    uint32_t want = 0;
    *entry = split_state(m, k, c, &want);
    if (!*entry)
        return 0;
    return apply_splits(st, m->transitions.words + m->split_words[c->splits],
                        SL_LOD_SPLIT_FACES(want), SL_LOD_SPLIT_EDGES(want), cell, point_crossing);
}

/* Draws frontier cell c into the builder; returns 1 when a split lacked data (a crack). */
static int draw_cell(const sl_lod_model *m, uint32_t k, const sl_lod_cell_ref *c,
                     const sl_lod_split_table *st, sl_mesh_builder *b)
{
    uint32_t want, *state = split_state(m, k, c, &want);
    if (state && *state != SL_OCTREE_NONE) { /* a transition cell, drawn at load */
        const uint32_t *drawing = m->split_drawings + *state;
        sl_mesh_builder_add_crossing_triangles(b, (int)(drawing[0] & 0xff), drawing + 1);
        return (int)(drawing[0] >> 8 & 1);
    }
    uint32_t point_crossing[SL_MC_MAX_POINTS];
    if (!state) { /* no finer neighbour: the 256-case table is this cell's drawing, and its
                     points are the cell's own edge crossings */
        const uint32_t *ids = m->tree.node_crossings + c->crossing_base;
        for (int e = 0; e < 12; e++)
            point_crossing[SL_MC_EDGE_POINT(e)] = (c->edge_mask >> e & 1) ? *ids++ : 0;
        const uint8_t *row = sl_lod_uniform_cells[c->inside];
        sl_mesh_builder_add_triangles(b, row[0], row + 1, point_crossing);
        return 0;
    }
    sl_mc_cell cell;
    uint32_t *entry;
    int rc = sl_lod_frontier_cell(m, k, c, st, &cell, point_crossing, &entry);
    sl_mc_triangles tri; /* centroid vertices or many triangles: not kept at load */
    sl_mc_triangulate(&cell, &tri);
    sl_mesh_builder_add_cell(b, &tri, point_crossing);
    return rc ? 1 : 0;
}

/* A viewer cuts between frames, and rendering pushes the generation tables out of the
 * caches: the walk would then wait for each table row the first time a cell needs it, one
 * at a time, which a small cut pays for more than its triangles (fandisk at 1 %, 62
 * triangles: 12 % of its time). Asked for together at the start, they arrive at once. */
static void fetch_tables(const sl_lod_split_table *st)
{
    const char *uniform = (const char *)sl_lod_uniform_cells;
    for (size_t i = 0; i < sizeof sl_lod_uniform_cells; i += 64)
        __builtin_prefetch(uniform + i, 0, 2);
    for (size_t i = 0; i < sizeof *st; i += 64)
        __builtin_prefetch((const char *)st + i, 0, 2);
}

/* The records, ids, split lists and drawings stream in LOD order, but as several streams
 * with gaps (the expanded cells' entries lie between), and crossings are shared with
 * other cells and only roughly in that order: the walk asks for a cell's data a few cells
 * before drawing it, each step once the previous one's data has come. */
#define LIST_AHEAD 16    /* cells whose split list and crossing ids are fetched */
#define CROSSING_AHEAD 8 /* ... whose own crossings' vertex map entries and positions, and
                            uniform table row, are */
#define DRAWING_AHEAD 4  /* ... whose drawing is (its offset is in the list) */

static inline int drawn_at(const sl_lod_cell_ref *c, uint32_t k)
{
    return c->draws && c->expansion >= k;
}

static void fetch_crossings(const sl_lod_model *m, const uint32_t *ids, int count)
{
    for (int i = 0; i < count; i++) {
        __builtin_prefetch(&m->scratch.vertex_of_crossing[ids[i]]);
        __builtin_prefetch(&m->tree.crossing_position[3 * (size_t)ids[i]]);
    }
}

/* The drawing of cell c after k expansions, or NULL (not a transition cell then). */
static const uint32_t *drawing_of(const sl_lod_model *m, uint32_t k, const sl_lod_cell_ref *c)
{
    uint32_t want, *state = split_state(m, k, c, &want);
    return state && *state != SL_OCTREE_NONE ? m->split_drawings + *state : NULL;
}

static void fetch_ahead(const sl_lod_model *m, uint32_t k, uint32_t pos, uint32_t end)
{
    const sl_lod_cell_ref *c;
    const uint32_t *drawing;
    if (pos + LIST_AHEAD < end && drawn_at(c = &m->cells[pos + LIST_AHEAD], k)) {
        __builtin_prefetch(m->tree.node_crossings + c->crossing_base);
        if (c->splits != SL_OCTREE_NONE)
            __builtin_prefetch(m->split_words + c->splits);
    }
    if (pos + CROSSING_AHEAD < end && drawn_at(c = &m->cells[pos + CROSSING_AHEAD], k)) {
        fetch_crossings(m, m->tree.node_crossings + c->crossing_base,
                        __builtin_popcount(c->edge_mask));
        __builtin_prefetch(sl_lod_uniform_cells[c->inside]);
    }
    if (pos + DRAWING_AHEAD < end && drawn_at(c = &m->cells[pos + DRAWING_AHEAD], k) &&
        (drawing = drawing_of(m, k, c)))
        __builtin_prefetch(drawing);
}

/* Dual models (lod_dual.h): the drawn loops of frontier cell c (at LOD-order position
 * pos) into the builder; returns 1 when a split lacked data (a crack). */
static int draw_cell_loops(const sl_lod_model *m, uint32_t k, uint32_t pos,
                           const sl_lod_cell_ref *c, sl_mesh_builder *b)
{
    uint32_t want, *state = split_state(m, k, c, &want);
    if (state && *state != SL_OCTREE_NONE) { /* a transition cell, drawn at load */
        const uint32_t *d = m->split_drawings + *state;
        for (uint32_t i = 0, at = 1; i < (d[0] & 0xff); i++, at += 2 + d[at])
            sl_mesh_builder_add_loop(b, d[at + 1], d + at + 2, (int)d[at]);
        return (int)(d[0] >> 8 & 1);
    }
    uint32_t node = m->cell_node[pos], first = m->tree.vertex_first[node];
    if (m->tree.vertex_first[node + 1] == first)
        return 0; /* no vertex: trimmed (an open scan's cell beyond its border) */
    uint32_t point_crossing[12], ids[12];
    const uint32_t *own = m->tree.node_crossings + c->crossing_base;
    for (int e = 0; e < 12; e++)
        point_crossing[e] = (c->edge_mask >> e & 1) ? *own++ : SL_OCTREE_NONE;
    const uint8_t *row = sl_dual_uniform_loops()[c->inside];
    for (int l = 0, at = 5; l < row[0]; l++) {
        int n = row[1 + l];
        for (int j = 0; j < n; j++)
            ids[j] = point_crossing[row[at++]];
        sl_mesh_builder_add_loop(b, first + (uint32_t)l, ids, n);
    }
    return 0;
}

static uint64_t draw_frontier_dual(sl_lod_model *m, uint32_t k, sl_mesh_builder *b)
{
    uint32_t end = m->frontier_end[k];
    uint64_t incomplete = 0;
    for (uint32_t pos = 0; pos < end; pos++) {
        const sl_lod_cell_ref *c = &m->cells[pos];
        if (drawn_at(c, k))
            incomplete += (uint64_t)draw_cell_loops(m, k, pos, c, b);
    }
    return incomplete;
}

/* Draws the frontier after k expansions into the builder; returns the crack count. */
static uint64_t draw_frontier(sl_lod_model *m, uint32_t k, sl_mesh_builder *b)
{
    if (k > m->expansion_count)
        k = m->expansion_count;
    if (m->dual_position) {
        if (sl_mesh_builder_dual(b, m->dual_position, m->dual_color, m->dual_count))
            return 0;
        return draw_frontier_dual(m, k, b);
    }
    const sl_lod_split_table *st = sl_lod_split_table_get();
    fetch_tables(st);
    if (k > m->expansion_count)
        k = m->expansion_count;
    uint32_t end = m->frontier_end[k];
    uint64_t incomplete = 0;
    for (uint32_t pos = 0; pos < end; pos++) {
        fetch_ahead(m, k, pos, end);
        const sl_lod_cell_ref *c = &m->cells[pos];
        if (drawn_at(c, k))
            incomplete += (uint64_t)draw_cell(m, k, c, st, b);
    }
    return incomplete;
}

int sl_lod_generate(sl_lod_model *m, uint32_t k, sl_lod_mesh *out, uint64_t *cracks)
{
    memset(out, 0, sizeof *out);
    if (k > m->expansion_count)
        k = m->expansion_count;
    sl_mesh_builder b;
    if (sl_mesh_builder_init(&b, &m->tree, &m->scratch))
        return -1;
    /* The accumulation table says how many triangles this mesh has: size the output once
     * (it is only a hint; the builder still grows if a model's table were off). */
    sl_mesh_builder_reserve(&b, m->accumulation[k]);
    uint64_t incomplete = draw_frontier(m, k, &b);
    if (cracks)
        *cracks = incomplete;
    return sl_mesh_builder_finish(&b, out);
}

int sl_lod_generate_into(sl_lod_model *m, uint32_t k, sl_lod_mesh *buffers,
                         uint64_t vertex_capacity, uint64_t triangle_capacity, uint64_t *cracks)
{
    if (k > m->expansion_count)
        k = m->expansion_count;
    sl_mesh_builder b;
    if (sl_mesh_builder_init(&b, &m->tree, &m->scratch))
        return -1;
    sl_mesh_builder_use_buffers(&b, buffers, vertex_capacity, triangle_capacity);
    sl_mesh_builder_reserve(&b, m->accumulation[k]);
    uint64_t incomplete = draw_frontier(m, k, &b);
    if (cracks)
        *cracks = incomplete;
    return sl_mesh_builder_finish(&b, buffers);
}
