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
    free(m->expansion_index);
    free(m->accumulation);
    free(m->error_after);
    sl_mesh_scratch_release(&m->scratch);
    sl_mc_cache_free(m->mc_cache);
    free(m->split_expansion);
    free(m->surface_before);
    sl_neighbours_release(&m->neighbours);
    sl_transitions_release(&m->transitions);
    sl_lod_model_init(m);
}

int sl_lod_model_prepare(sl_lod_model *m)
{
    const sl_octree *t = &m->tree;
    uint32_t n = t->node_count, internal = 0;
    for (uint32_t i = 0; i < n; i++)
        if (t->nodes[i].level > 0)
            internal = i + 1; /* internal nodes come first (sorted by level) */
    free(m->expansion_index);
    sl_mesh_scratch_release(&m->scratch);
    sl_mc_cache_free(m->mc_cache);
    m->mc_cache = sl_mc_cache_new(); /* without it extraction is only slower */
    free(m->split_expansion);
    free(m->surface_before);
    m->split_nodes = internal;
    m->surface_before = malloc(((size_t)m->expansion_count + 1) * sizeof *m->surface_before);
    m->expansion_index = malloc((n ? n : 1) * sizeof *m->expansion_index);
    m->split_expansion = malloc(((size_t)internal * SL_LOD_SPLIT_DIRS + 1) *
                                sizeof *m->split_expansion);
    if (!m->expansion_index || !m->split_expansion || !m->surface_before ||
        sl_mesh_scratch_init(&m->scratch, t) != 0)
        return -1;
    if (sl_lod_surface_counts(m) != 0)
        return -1;
    memset(m->expansion_index, 0xff, (size_t)n * sizeof *m->expansion_index);
    for (uint32_t i = 0; i < m->expansion_count; i++)
        m->expansion_index[m->lod_array[i]] = i;
    const sl_lod_split_table *st = sl_lod_split_table_get();
    /* The triangulator builds its own tables on first use: let that be now, at load,
     * rather than in the first extraction. */
    sl_mc_cell empty;
    sl_mc_triangles none;
    memset(&empty, 0, sizeof empty);
    sl_mc_triangulate(&empty, &none);
    const sl_neighbours *nb = &m->neighbours;
#pragma omp parallel for schedule(static)
    for (uint32_t i = 0; i < internal; i++) {
        uint32_t *slots = m->split_expansion + (size_t)i * SL_LOD_SPLIT_DIRS;
        for (int j = 0; j < SL_LOD_SPLIT_DIRS; j++)
            slots[j] = SL_OCTREE_NONE;
        uint32_t mask = nb->mask[i];
        const uint32_t *index = nb->index + nb->base[i];
        for (int j = 0; mask; mask &= mask - 1u, j++) {
            int slot = st->slot_of_dir[__builtin_ctz(mask)];
            if (slot >= 0)
                slots[slot] = m->expansion_index[index[j]];
        }
    }
    return 0;
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
static int split_edge(const sl_lod_split_table *st, const record_view *r,
                      const sl_octree_node *node, int e, sl_mc_cell *cell,
                      uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    int in0 = node->inside >> st->edge_c0[e] & 1, in1 = node->inside >> st->edge_c1[e] & 1;
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

/* Gives node n's crossings (its own and its transition record's) the next new ids. */
static void number_crossings(const sl_lod_model *m, uint32_t n, uint32_t *new_id, uint32_t *next)
{
    const sl_octree *t = &m->tree;
    const sl_octree_node *node = &t->nodes[n];
    const uint32_t *ids = t->node_crossings + node->crossing_base;
    for (int i = 0, count = __builtin_popcount(node->edge_mask); i < count; i++)
        if (new_id[ids[i]] == SL_OCTREE_NONE)
            new_id[ids[i]] = (*next)++;
    if (node->level == 0 || m->transitions.base[n] == SL_OCTREE_NONE)
        return;
    const uint32_t *w = m->transitions.words + m->transitions.base[n];
    int count = __builtin_popcount(w[1] & 0xffffff) + __builtin_popcount(w[2] & 0xffffff);
    for (int i = 0; i < count; i++)
        if (new_id[w[3 + i]] == SL_OCTREE_NONE)
            new_id[w[3 + i]] = (*next)++;
}

int sl_lod_model_localize(sl_lod_model *m)
{
    sl_octree *t = &m->tree;
    uint32_t c = t->crossing_count, next = 0;
    uint32_t *new_id = malloc((c ? c : 1) * sizeof *new_id);
    float *position = malloc((c ? c : 1) * 3 * sizeof *position);
    uint8_t *color = t->crossing_color ? malloc((c ? c : 1) * 4) : NULL;
    if (!new_id || !position || (t->crossing_color && !color)) {
        free(new_id);
        free(position);
        free(color);
        return -1;
    }
    memset(new_id, 0xff, (size_t)c * sizeof *new_id);
    /* First the frontier nodes' crossings in the order the LOD array reaches them, then
     * any other node's, then the crossings no node names. */
    if (t->node_count)
        number_crossings(m, 0, new_id, &next);
    for (uint32_t i = 0; i < m->expansion_count; i++) {
        const sl_octree_node *p = &t->nodes[m->lod_array[i]];
        for (int k = 0; k < __builtin_popcount(p->child_mask); k++)
            number_crossings(m, p->first_child + (uint32_t)k, new_id, &next);
    }
    for (uint32_t n = 0; n < t->node_count; n++)
        number_crossings(m, n, new_id, &next);
    for (uint32_t i = 0; i < c; i++)
        if (new_id[i] == SL_OCTREE_NONE)
            new_id[i] = next++;
    for (uint32_t i = 0; i < c; i++) {
        memcpy(position + 3 * (size_t)new_id[i], t->crossing_position + 3 * (size_t)i,
               3 * sizeof *position);
        if (color)
            memcpy(color + 4 * (size_t)new_id[i], t->crossing_color + 4 * (size_t)i, 4);
    }
    for (uint64_t i = 0; i < t->node_crossing_count; i++)
        t->node_crossings[i] = new_id[t->node_crossings[i]];
    for (uint32_t n = 0; n < t->node_count; n++) {
        if (t->nodes[n].level == 0 || m->transitions.base[n] == SL_OCTREE_NONE)
            continue;
        uint32_t *w = m->transitions.words + m->transitions.base[n];
        int count = __builtin_popcount(w[1] & 0xffffff) + __builtin_popcount(w[2] & 0xffffff);
        for (int i = 0; i < count; i++)
            w[3 + i] = new_id[w[3 + i]];
    }
    free(t->crossing_position);
    t->crossing_position = position;
    if (color) {
        free(t->crossing_color);
        t->crossing_color = color;
    }
    free(new_id);
    return 0;
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

/* Applies the wanted splits of internal node n; 0, or -1 on a missing finer crossing. */
static int apply_splits(const sl_lod_split_table *st, const sl_transitions *tr,
                        const sl_octree_node *node, uint32_t n,
                        unsigned want_faces, unsigned want_edges, sl_mc_cell *cell,
                        uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    record_view r;
    decode(tr, n, &r);
    int rc = 0;
    for (int e = 0; e < 12; e++)
        if (want_edges >> e & 1)
            rc |= split_edge(st, &r, node, e, cell, point_crossing);
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
    return apply_splits(sl_lod_split_table_get(), tr, node, n, want_faces, want_edges, cell,
                        point_crossing);
}

/* Whether internal node n, all of whose corners have one sign, has that sign at every
 * finer sample its record knows too: then no split can give it a crossing, and it draws
 * nothing (and lacks nothing) whatever its neighbours. */
static int uniform_record(const sl_transitions *tr, uint32_t n, int inside)
{
    const uint32_t *w = tr->words + tr->base[n];
    uint32_t mid_known = w[0] & 0xfff, mid_inside = w[0] >> 12 & 0xfff;
    uint32_t centre_known = w[0] >> 24 & 0x3f, centre_inside = w[1] >> 24 & 0x3f;
    if (inside)
        return (mid_inside & mid_known) == mid_known &&
               (centre_inside & centre_known) == centre_known;
    return !(mid_inside & mid_known) && !(centre_inside & centre_known);
}

uint64_t sl_lod_frontier_bound(const sl_lod_model *m, uint32_t k)
{
    return k == 0 ? 1 : 8 * (uint64_t)k;
}

/* The frontier after k expansions, one node at a time: the children of lod_array[0..k)
 * that are not themselves expanded before k (the root when k = 0). Reads the LOD array in
 * order and asks the memory for the parents and children a few expansions ahead, so the
 * walk does not wait on each. */
typedef struct frontier_walk {
    const sl_lod_model *m;
    uint32_t k, next;   /* next LOD-array position to open */
    uint32_t child, end; /* children of the last opened position still to look at */
} frontier_walk;

#define PARENTS_AHEAD 16 /* LOD-array positions whose parent node is fetched early */
#define CHILDREN_AHEAD 8 /* ... whose children (nodes, expansion indices) are */

static void frontier_start(frontier_walk *w, const sl_lod_model *m, uint32_t k)
{
    w->m = m;
    w->k = k > m->expansion_count ? m->expansion_count : k;
    w->next = 0;
    w->child = 0;
    w->end = w->k == 0 ? 1 : 0; /* the root alone */
}

static uint32_t frontier_next(frontier_walk *w)
{
    const sl_lod_model *m = w->m;
    const sl_octree_node *nodes = m->tree.nodes;
    for (;;) {
        while (w->child < w->end) {
            uint32_t c = w->child++;
            if (m->expansion_index[c] >= w->k)
                return c;
        }
        if (w->next >= w->k)
            return SL_OCTREE_NONE;
        uint32_t i = w->next++;
        if (i + PARENTS_AHEAD < w->k)
            __builtin_prefetch(&nodes[m->lod_array[i + PARENTS_AHEAD]]);
        if (i + CHILDREN_AHEAD < w->k) {
            const sl_octree_node *q = &nodes[m->lod_array[i + CHILDREN_AHEAD]];
            uint32_t last = q->first_child + (uint32_t)__builtin_popcount(q->child_mask) - 1u;
            __builtin_prefetch(&nodes[q->first_child]);
            __builtin_prefetch(&nodes[last]);
            __builtin_prefetch(&m->expansion_index[q->first_child]);
        }
        const sl_octree_node *p = &nodes[m->lod_array[i]];
        w->child = p->first_child;
        w->end = p->first_child + (uint32_t)__builtin_popcount(p->child_mask);
    }
}

uint64_t sl_lod_frontier(const sl_lod_model *m, uint32_t k, uint32_t *cells)
{
    frontier_walk w;
    frontier_start(&w, m, k);
    uint64_t count = 0;
    for (uint32_t n; (n = frontier_next(&w)) != SL_OCTREE_NONE;)
        cells[count++] = n;
    return count;
}

/* Draws frontier node n into the builder; returns 1 when a split lacked data (a crack). */
static int draw_cell(sl_lod_model *m, uint32_t k, uint32_t n, const sl_lod_split_table *st,
                     sl_mesh_builder *b)
{
    const sl_octree *t = &m->tree;
    const sl_octree_node *node = &t->nodes[n];
    /* (A model read from a file has a transition record for every internal node, and
     * sl_transitions_build makes one for each: the level says whether there is one.) */
    int leaf = node->level == 0;
    /* A cell whose corners share one sign draws nothing unless a split brings in a finer
     * sample of the other sign: skip it without looking at its neighbours. */
    if (!node->edge_mask && (leaf || uniform_record(&m->transitions, n, node->inside)))
        return 0;
    sl_mc_cell cell;
    uint32_t point_crossing[SL_MC_MAX_POINTS];
    cell_own(t, node, &cell, point_crossing);
    unsigned want_faces = 0, want_edges = 0;
    if (!leaf) { /* the faces and edges next to an expanded neighbour */
        const uint32_t *slots = m->split_expansion + (size_t)n * SL_LOD_SPLIT_DIRS;
        for (int j = 0; j < SL_LOD_SPLIT_DIRS; j++)
            if (slots[j] < k) {
                want_faces |= st->slot_faces[j];
                want_edges |= st->slot_edges[j];
            }
    }
    if (!want_edges) { /* no finer neighbour: the 256-case table is this cell's drawing */
        const uint8_t *row = sl_lod_uniform_cells[cell.inside];
        sl_mesh_builder_add_triangles(b, row[0], row + 1, point_crossing);
        return 0;
    }
    int rc = apply_splits(st, &m->transitions, node, n, want_faces, want_edges, &cell,
                          point_crossing);
    sl_mc_triangles tri;
    sl_mc_triangulate_cached(m->mc_cache, &cell, &tri);
    sl_mesh_builder_add_cell(b, &tri, point_crossing);
    return rc ? 1 : 0;
}

/* Asks the memory for what drawing frontier node n reads first: its crossing ids and, for
 * an internal node, its neighbours' expansion indices and its transition record's place. */
static void fetch_cell(const sl_lod_model *m, uint32_t n)
{
    const sl_octree_node *node = &m->tree.nodes[n];
    __builtin_prefetch(&m->tree.node_crossings[node->crossing_base]);
    if (node->level > 0) {
        const uint32_t *slots = m->split_expansion + (size_t)n * SL_LOD_SPLIT_DIRS;
        __builtin_prefetch(slots);
        __builtin_prefetch(slots + SL_LOD_SPLIT_DIRS - 1);
        __builtin_prefetch(&m->transitions.base[n]);
    }
}

/* ... and, once those have come, what it reads next: the crossings' vertex map entries and
 * positions, and the transition record. */
static void fetch_cell_data(const sl_lod_model *m, uint32_t n)
{
    const sl_octree *t = &m->tree;
    const sl_octree_node *node = &t->nodes[n];
    const uint32_t *ids = t->node_crossings + node->crossing_base;
    for (int i = 0, count = __builtin_popcount(node->edge_mask); i < count; i++) {
        __builtin_prefetch(&m->scratch.vertex_of_crossing[ids[i]]);
        __builtin_prefetch(&t->crossing_position[3 * (size_t)ids[i]]);
    }
    if (node->level > 0)
        __builtin_prefetch(&m->transitions.words[m->transitions.base[n]]);
}

#define CELLS_AHEAD 8 /* frontier cells fetched before they are drawn (a power of 2) */

/* Draws the frontier after k expansions into the builder; returns the crack count. */
static uint64_t draw_frontier(sl_lod_model *m, uint32_t k, sl_mesh_builder *b)
{
    const sl_lod_split_table *st = sl_lod_split_table_get();
    uint64_t incomplete = 0;
    /* The frontier in the order of sl_lod_frontier, each cell drawn CELLS_AHEAD cells after
     * it is found: in between, its data is fetched in two steps. */
    frontier_walk w;
    frontier_start(&w, m, k);
    uint32_t ring[2 * CELLS_AHEAD], mask = 2 * CELLS_AHEAD - 1;
    for (uint32_t j = 0; j < CELLS_AHEAD; j++) {
        ring[j] = frontier_next(&w);
        if (ring[j] != SL_OCTREE_NONE)
            fetch_cell(m, ring[j]);
    }
    for (uint32_t pos = 0; ring[pos & mask] != SL_OCTREE_NONE; pos++) {
        uint32_t ahead = frontier_next(&w), half = ring[(pos + CELLS_AHEAD / 2) & mask];
        ring[(pos + CELLS_AHEAD) & mask] = ahead;
        if (ahead != SL_OCTREE_NONE)
            fetch_cell(m, ahead);
        if (half != SL_OCTREE_NONE)
            fetch_cell_data(m, half);
        incomplete += (uint64_t)draw_cell(m, k, ring[pos & mask], st, b);
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
