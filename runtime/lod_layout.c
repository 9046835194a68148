/* Where a loaded LOD model sits in memory, so that cutting a level streams it (docs/lod.md
 * "Memory layout for extraction").
 *
 * LOD order: the root, then the children of lod_array[0], then those of lod_array[1], and
 * so on (then the children of nodes never expanded). The frontier after k expansions is the part
 * of the first frontier_end[k] positions that is not itself expanded before k, in this
 * very order. So generation reads one prefix of the cell records, and, once the pools are
 * laid out in the same order (sl_lod_model_localize), a prefix of the crossing ids and of
 * the transition records: sequential reads the hardware prefetches, at any budget, where
 * the level-sorted node array would be gathered from all over.
 */
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_model.h"
#include "runtime/lod_splits.h"

uint32_t *sl_lod_order(const sl_lod_model *m)
{
    const sl_octree *t = &m->tree;
    uint32_t n = t->node_count, pos = 0;
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    uint8_t *placed = calloc(n ? n : 1, 1);
    if (!order || !placed) {
        free(order);
        free(placed);
        return NULL;
    }
    if (n) {
        order[pos++] = 0;
        placed[0] = 1;
    }
    for (uint32_t i = 0; i < m->expansion_count; i++) {
        const sl_octree_node *p = &t->nodes[m->lod_array[i]];
        for (uint32_t c = 0; c < (uint32_t)__builtin_popcount(p->child_mask); c++) {
            uint32_t child = p->first_child + c;
            if (child >= n || placed[child])
                continue; /* only a model the readers refuse (shared children) gets here */
            order[pos++] = child;
            placed[child] = 1;
        }
    }
    /* Then the children of the nodes never expanded, breadth first in this order (their
     * places follow from the tree alone: model format 5 stores no links, lod_order.h). */
    for (uint32_t at = 0; at < pos; at++) {
        const sl_octree_node *p = &t->nodes[order[at]];
        if (!p->child_mask || p->first_child >= n || placed[p->first_child])
            continue;
        for (uint32_t c = 0; c < (uint32_t)__builtin_popcount(p->child_mask); c++) {
            uint32_t child = p->first_child + c;
            if (child >= n || placed[child])
                continue;
            order[pos++] = child;
            placed[child] = 1;
        }
    }
    for (uint32_t i = 0; i < n; i++) /* only a model the readers refuse leaves any */
        if (!placed[i])
            order[pos++] = i;
    free(placed);
    return order;
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

static uint32_t record_words(const sl_transitions *tr, uint32_t n)
{
    return sl_transition_record_words(tr->words + tr->base[n]);
}

/* Rewrites the pools of per-node crossing ids and of transition records in LOD order
 * (each node's entries keep their content; only their place, and so the bases, move). */
static int order_pools(sl_lod_model *m, const uint32_t *order)
{
    sl_octree *t = &m->tree;
    sl_transitions *tr = &m->transitions;
    uint64_t id_total = 0, word_total = 0;
    for (uint32_t n = 0; n < t->node_count; n++) {
        id_total += (uint64_t)__builtin_popcount(t->nodes[n].edge_mask);
        if (tr->base[n] != SL_OCTREE_NONE)
            word_total += record_words(tr, n);
    }
    /* A well-formed model uses every entry once; a file that shares entries between nodes
     * keeps its pools, which are as valid, only slower to stream. */
    if (id_total > t->node_crossing_count || word_total > tr->count)
        return 0;
    uint32_t *ids = malloc((id_total ? id_total : 1) * sizeof *ids);
    uint32_t *words = malloc((word_total ? word_total : 1) * sizeof *words);
    if (!ids || !words) {
        free(ids);
        free(words);
        return -1;
    }
    uint64_t at_ids = 0, at_words = 0;
    for (uint32_t pos = 0; pos < t->node_count; pos++) {
        uint32_t n = order[pos];
        sl_octree_node *node = &t->nodes[n];
        uint32_t count = (uint32_t)__builtin_popcount(node->edge_mask);
        memcpy(ids + at_ids, t->node_crossings + node->crossing_base, count * sizeof *ids);
        node->crossing_base = (uint32_t)at_ids;
        at_ids += count;
        if (tr->base[n] != SL_OCTREE_NONE) {
            uint32_t size = record_words(tr, n);
            memcpy(words + at_words, tr->words + tr->base[n], size * sizeof *words);
            tr->base[n] = (uint32_t)at_words;
            at_words += size;
        }
    }
    free(t->node_crossings);
    t->node_crossings = ids;
    t->node_crossing_count = id_total;
    free(tr->words);
    tr->words = words;
    tr->count = word_total;
    return 0;
}

uint32_t *sl_lod_crossing_numbers(const sl_lod_model *m, const uint32_t *order)
{
    const sl_octree *t = &m->tree;
    uint32_t c = t->crossing_count, next = 0;
    uint32_t *new_id = malloc((c ? c : 1) * sizeof *new_id);
    if (!new_id)
        return NULL;
    memset(new_id, 0xff, (size_t)c * sizeof *new_id);
    /* The crossings in the order the nodes in LOD order name them, then those no node
     * names. */
    for (uint32_t pos = 0; pos < t->node_count; pos++)
        number_crossings(m, order[pos], new_id, &next);
    for (uint32_t i = 0; i < c; i++)
        if (new_id[i] == SL_OCTREE_NONE)
            new_id[i] = next++;
    return new_id;
}

int sl_lod_model_localize(sl_lod_model *m)
{
    sl_octree *t = &m->tree;
    uint32_t *order = sl_lod_order(m);
    uint32_t *new_id = order ? sl_lod_crossing_numbers(m, order) : NULL;
    float *position = NULL;
    uint8_t *color = NULL;
    if (!order || !new_id || sl_octree_permuted_crossings(t, new_id, &position, &color)) {
        free(order);
        free(new_id);
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < t->node_crossing_count; i++)
        t->node_crossings[i] = new_id[t->node_crossings[i]];
#pragma omp parallel for schedule(dynamic, 4096)
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
    int rc = order_pools(m, order);
    free(order);
    return rc;
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

#define SPLIT_LIST_MAX (3 + 3 * SL_LOD_SPLIT_DIRS)

/* The split list (lod_model.h) of internal node n, on the frontier for k in [first, last];
 * its length in words, 0 when no such k splits it. */
static uint32_t split_list(const sl_lod_model *m, const sl_lod_split_table *st, uint32_t n,
                           uint32_t first, uint32_t last, uint32_t out[SPLIT_LIST_MAX])
{
    const sl_neighbours *nb = &m->neighbours;
    uint32_t initial = 0, events = 0, mask = nb->mask[n];
    const uint32_t *index = nb->index + nb->base[n];
    for (int j = 0; mask; mask &= mask - 1u, j++) {
        int slot = st->slot_of_dir[__builtin_ctz(mask)];
        uint32_t s = m->expansion_index[index[j]];
        if (slot < 0 || s == SL_OCTREE_NONE || s >= last)
            continue; /* never expanded while this cell is drawn */
        uint32_t adds = st->slot_faces[slot] | (uint32_t)st->slot_edges[slot] << 6;
        if (s < first) {
            initial |= adds;
            continue;
        }
        uint32_t at = events++; /* insertion sort by s: at most 18 */
        while (at > 0 && out[3 + 3 * (at - 1)] > s) {
            memcpy(out + 3 + 3 * at, out + 3 * at, 3 * sizeof *out);
            at--;
        }
        out[3 + 3 * at] = s;
        out[4 + 3 * at] = adds;
        out[5 + 3 * at] = SL_OCTREE_NONE; /* sl_lod_draw_states fills these */
    }
    if (!initial && !events)
        return 0;
    out[0] = m->transitions.base[n];
    out[1] = initial | events << 24;
    out[2] = SL_OCTREE_NONE;
    return 3 + 3 * events;
}

/* The split list of the cell at LOD-order position pos (node n); its length in words. */
static uint32_t cell_split_list(const sl_lod_model *m, const sl_lod_split_table *st, uint32_t pos,
                                uint32_t n, uint32_t list[SPLIT_LIST_MAX])
{
    if (m->tree.nodes[n].level == 0 || m->transitions.base[n] == SL_OCTREE_NONE)
        return 0; /* a leaf never meets a finer cell */
    uint32_t e = m->expansion_count;
    uint32_t last = m->expansion_index[n] == SL_OCTREE_NONE ? e : m->expansion_index[n];
    return split_list(m, st, n, sl_lod_first_frontier(m, pos), last, list);
}

/* The cell records and split lists in LOD order, and frontier_end. */
static int lay_out_cells(sl_lod_model *m)
{
    const sl_octree *t = &m->tree;
    const sl_lod_split_table *st = sl_lod_split_table_get();
    uint32_t e = m->expansion_count;
    uint32_t *order = sl_lod_order(m);
    free(m->frontier_end);
    free(m->cells);
    free(m->split_words);
    free(m->cell_node);
    m->cells = NULL;
    m->split_words = NULL;
    m->cell_node = NULL;
    m->frontier_end = malloc(((size_t)e + 1) * sizeof *m->frontier_end);
    if (!order || !m->frontier_end) {
        free(order);
        return -1;
    }
    uint32_t end = t->node_count ? 1 : 0;
    for (uint32_t i = 0; i < e; i++) {
        m->frontier_end[i] = end;
        end += (uint32_t)__builtin_popcount(t->nodes[m->lod_array[i]].child_mask);
    }
    m->frontier_end[e] = end;
    m->cells = malloc((end ? end : 1) * sizeof *m->cells);
    if (sl_octree_dual(t))
        m->cell_node = malloc((end ? end : 1) * sizeof *m->cell_node);
    if (!m->cells || (sl_octree_dual(t) && !m->cell_node)) {
        free(order);
        return -1;
    }
    if (m->cell_node)
        memcpy(m->cell_node, order, (size_t)end * sizeof *order);
    /* The lists' sizes (in the cells' `splits` for now), their offsets, their words. */
#pragma omp parallel for schedule(static)
    for (uint32_t pos = 0; pos < end; pos++) {
        uint32_t list[SPLIT_LIST_MAX];
        m->cells[pos].splits = cell_split_list(m, st, pos, order[pos], list);
    }
    uint64_t words = 0;
    for (uint32_t pos = 0; pos < end; pos++) {
        uint32_t size = m->cells[pos].splits;
        m->cells[pos].splits = size ? (uint32_t)words : SL_OCTREE_NONE;
        words += size;
        if (words >= SL_OCTREE_NONE)
            break;
    }
    if (words < SL_OCTREE_NONE)
        m->split_words = malloc((words ? words : 1) * sizeof *m->split_words);
    if (!m->split_words) {
        free(order);
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (uint32_t pos = 0; pos < end; pos++) {
        uint32_t n = order[pos], list[SPLIT_LIST_MAX];
        const sl_octree_node *node = &t->nodes[n];
        sl_lod_cell_ref *c = &m->cells[pos];
        uint32_t size = cell_split_list(m, st, pos, n, list);
        c->expansion = m->expansion_index[n];
        c->crossing_base = node->crossing_base;
        c->edge_mask = node->edge_mask;
        c->inside = node->inside;
        /* A cell whose corners share one sign draws nothing unless a split brings in a
         * finer sample of the other sign. */
        c->draws = node->edge_mask || (size && !uniform_record(&m->transitions, n, node->inside));
        if (size)
            memcpy(m->split_words + c->splits, list, size * sizeof *list);
    }
    free(order);
    return 0;
}

/* A dual model's vertex table starts as the tree's vertices (sl_lod_draw_states adds the
 * transition loops' own). */
static int dual_vertices(sl_lod_model *m)
{
    const sl_octree *t = &m->tree;
    free(m->dual_position);
    free(m->dual_color);
    m->dual_position = NULL;
    m->dual_color = NULL;
    m->dual_count = 0;
    if (!sl_octree_dual(t))
        return 0;
    size_t count = t->vertex_count ? t->vertex_count : 1;
    m->dual_position = malloc(count * 3 * sizeof *m->dual_position);
    m->dual_color = t->vertex_color ? malloc(count * 4) : NULL;
    if (!m->dual_position || (t->vertex_color && !m->dual_color))
        return -1;
    memcpy(m->dual_position, t->vertex_position, (size_t)t->vertex_count * 3 * sizeof(float));
    if (t->vertex_color)
        memcpy(m->dual_color, t->vertex_color, (size_t)t->vertex_count * 4);
    m->dual_count = t->vertex_count;
    return 0;
}

/* What generation never reads, once a model opened for cutting is laid out: the nodes
 * but the root (the normals' scale is taken from its cube), their Morton keys, the
 * expansion indices and the transition bases (the cells and their split lists carry what
 * cutting needs). 48 bytes a node: 1.3 GB of the 20 M-triangle torus's model, held by the
 * export stage through every cut. */
static void drop_for_cuts(sl_lod_model *m)
{
    sl_octree *t = &m->tree;
    free(t->morton);
    t->morton = NULL;
    free(m->expansion_index);
    m->expansion_index = NULL;
    free(m->transitions.base);
    m->transitions.base = NULL;
    sl_octree_node *root = t->node_count ? realloc(t->nodes, sizeof *root) : NULL;
    if (root)
        t->nodes = root;
}

int sl_lod_model_prepare(sl_lod_model *m)
{
    const sl_octree *t = &m->tree;
    uint32_t n = t->node_count;
    free(m->expansion_index);
    sl_mesh_scratch_release(&m->scratch);
    free(m->surface_before);
    m->surface_before = malloc(((size_t)m->expansion_count + 1) * sizeof *m->surface_before);
    m->expansion_index = malloc((n ? n : 1) * sizeof *m->expansion_index);
    if (!m->neighbours.mask && n) /* an opened model (cuts_only) is laid out once */
        return -1;
    if (!m->expansion_index || !m->surface_before ||
        sl_mesh_scratch_init(&m->scratch, t) != 0)
        return -1;
    if (sl_lod_surface_counts(m, m->surface_before) != 0)
        return -1;
    memset(m->expansion_index, 0xff, (size_t)n * sizeof *m->expansion_index);
    for (uint32_t i = 0; i < m->expansion_count; i++)
        m->expansion_index[m->lod_array[i]] = i;
    /* The triangulator builds its own tables on first use: let that be now, at load,
     * rather than in the first extraction. */
    sl_mc_cell empty;
    sl_mc_triangles none;
    memset(&empty, 0, sizeof empty);
    sl_mc_triangulate(&empty, &none);
    if (lay_out_cells(m))
        return -1;
    if (m->cuts_only) /* generation reads the split lists, never the neighbours */
        sl_neighbours_release(&m->neighbours);
    if (dual_vertices(m) || sl_lod_draw_states(m))
        return -1;
    if (m->cuts_only)
        drop_for_cuts(m);
    return 0;
}
