/* Model format 5's LOD-ordered body: writing it (lod_order.h; reading: lod_order_read.c). */
#include "runtime/lod_order.h"

#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "runtime/lod_io.h"
#include "runtime/lod_pack.h"

static int has_record(const sl_lod_model *m, uint32_t n)
{
    return m->tree.nodes[n].level > 0 && m->transitions.base[n] != SL_OCTREE_NONE;
}

/* Adds a part the writer made and frees it; -1 when it could not be made or packed. */
static int add_owned(sl_packer *pk, void *data, size_t size, uint16_t record)
{
    int rc = data || !size ? sl_packer_add(pk, data, size, record) : -1;
    free(data);
    return rc;
}

/* A node in format 5: inside, child mask, flags, 0. Everything else follows from its
 * place (lod_order.h): its parent, its level and coordinates (its octant in its parent),
 * its first child (the next free position when its parent's expansion comes), its edge
 * mask (sl_octree_edge_mask) and its first crossing id (the running count). */
static int pack_nodes(sl_packer *pk, const sl_lod_model *m, const uint32_t *order)
{
    const sl_octree *t = &m->tree;
    uint32_t n = t->node_count;
    uint8_t *nodes = malloc((n ? n : 1) * (size_t)SL_LOD_ORDER_NODE);
    if (!nodes)
        return -1;
    for (uint32_t pos = 0; pos < n; pos++) {
        const sl_octree_node *node = &t->nodes[order[pos]];
        uint8_t *r = nodes + (size_t)SL_LOD_ORDER_NODE * pos;
        r[0] = node->inside;
        r[1] = node->child_mask;
        r[2] = node->flags;
        r[3] = 0;
    }
    return add_owned(pk, nodes, (size_t)n * SL_LOD_ORDER_NODE, SL_LOD_ORDER_NODE);
}

/* A crossing id as format 5 stores it: 0 for the next id not yet named (ids are numbered
 * by first use in LOD order), d > 0 for the id d below it, or SL_LOD_ORDER_FROM_PARENT | j
 * for the j-th id of the parent's transition record (node ids only). A cell's crossings on
 * its parent's boundary (48 of the 54 edges of a parent's children) are the ones its
 * parent's record names, numbered when the parent was placed, far back: as distances they
 * were most of the codes and most of their bytes (docs/benchmarks.md section 7). */
static uint32_t code_id(uint32_t id, uint32_t *next)
{
    if (id == *next) {
        (*next)++;
        return 0;
    }
    return *next - id;
}

/* The pools in LOD order: each node's crossing ids, coded, into the packer; its
 * transition record (ids coded) into *words at the base *bases gets, for pack_lod. */
static int pack_ids(sl_packer *pk, const sl_lod_model *m, const uint32_t *order,
                    const uint32_t *new_id, uint32_t **words_out, uint32_t **bases_out,
                    uint64_t *word_count)
{
    const sl_octree *t = &m->tree;
    uint32_t n = t->node_count;
    uint64_t total = 0, word_total = 0;
    for (uint32_t i = 0; i < n; i++) {
        total += (uint64_t)__builtin_popcount(t->nodes[i].edge_mask);
        if (has_record(m, i))
            word_total += sl_transition_record_words(m->transitions.words + m->transitions.base[i]);
    }
    uint32_t *ids = malloc((total ? total : 1) * sizeof *ids);
    uint32_t *words = malloc((word_total ? word_total : 1) * sizeof *words);
    uint32_t *bases = malloc((n ? n : 1) * sizeof *bases);
    *words_out = words;
    *bases_out = bases;
    if (!ids || !words || !bases) {
        free(ids);
        return -1;
    }
    uint64_t at = 0, at_words = 0;
    uint32_t next = 0;
    for (uint32_t pos = 0; pos < n; pos++) {
        uint32_t node_index = order[pos];
        const sl_octree_node *node = &t->nodes[node_index];
        const uint32_t *own = t->node_crossings + node->crossing_base;
        const uint32_t *from = NULL; /* the parent's record's ids */
        uint32_t from_count = 0;
        if (node->parent != SL_OCTREE_NONE && has_record(m, node->parent)) {
            const uint32_t *w = m->transitions.words + m->transitions.base[node->parent];
            from = w + 3;
            from_count = sl_transition_record_words(w) - 3;
        }
        for (int i = 0, k = __builtin_popcount(node->edge_mask); i < k; i++) {
            uint32_t j = 0;
            while (j < from_count && from[j] != own[i])
                j++;
            ids[at++] = j < from_count ? SL_LOD_ORDER_FROM_PARENT | j : code_id(new_id[own[i]], &next);
        }
        bases[pos] = SL_OCTREE_NONE;
        if (!has_record(m, node_index))
            continue;
        const uint32_t *w = m->transitions.words + m->transitions.base[node_index];
        uint32_t size = sl_transition_record_words(w);
        bases[pos] = (uint32_t)at_words;
        memcpy(words + at_words, w, 3 * sizeof *w);
        for (uint32_t i = 3; i < size; i++)
            words[at_words + i] = code_id(new_id[w[i]], &next);
        at_words += size;
    }
    *word_count = at_words;
    return add_owned(pk, ids, at * sizeof *ids, 4);
}

static int pack_crossings(sl_packer *pk, const sl_octree *t, const uint32_t *new_id)
{
    float *position;
    uint8_t *color;
    if (sl_octree_permuted_crossings(t, new_id, &position, &color))
        return -1;
    int rc = add_owned(pk, position, (size_t)t->crossing_count * 12, 12);
    if (color)
        rc |= add_owned(pk, color, (size_t)t->crossing_count * 4, 4);
    return rc ? -1 : 0;
}

static int pack_vertices(sl_packer *pk, const sl_octree *t, const uint32_t *order)
{
    uint32_t n = t->node_count, v = t->vertex_count;
    uint32_t *first = malloc(((size_t)n + 1) * sizeof *first);
    float *position = malloc((v ? v : 1) * 12);
    uint8_t *color = t->vertex_color ? malloc((v ? v : 1) * 4) : NULL;
    if (!first || !position || (t->vertex_color && !color)) {
        free(first);
        free(position);
        free(color);
        return -1;
    }
    uint32_t at = 0;
    for (uint32_t pos = 0; pos < n; pos++) {
        uint32_t node = order[pos], from = t->vertex_first[node];
        uint32_t count = t->vertex_first[node + 1] - from;
        first[pos] = at;
        memcpy(position + 3 * (size_t)at, t->vertex_position + 3 * (size_t)from, 12 * (size_t)count);
        if (color)
            memcpy(color + 4 * (size_t)at, t->vertex_color + 4 * (size_t)from, 4 * (size_t)count);
        at += count;
    }
    first[n] = at;
    int rc = add_owned(pk, first, ((size_t)n + 1) * 4, 4);
    rc |= add_owned(pk, position, (size_t)v * 12, 12);
    if (t->vertex_color)
        rc |= add_owned(pk, color, (size_t)v * 4, 4);
    else
        free(color);
    return rc ? -1 : 0;
}

static void put_f32(unsigned char *p, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, 4);
    sl_put_u32(p, bits);
}

static int pack_lod(sl_packer *pk, const sl_lod_model *m, const uint32_t *pos_of,
                    const uint32_t *words, const uint32_t *bases, uint64_t word_count)
{
    const sl_octree *t = &m->tree;
    uint32_t n = t->node_count, e = m->expansion_count;
    unsigned char header[SL_LOD_ORDER_HEADER] = {0};
    float lo[3], hi[3];
    sl_octree_crossing_bounds(t, lo, hi);
    sl_put_u32(header, e);
    sl_put_u32(header + 4, n);
    sl_put_u64(header + 8, m->neighbours.index ? m->neighbours.count : m->neighbour_links);
    sl_put_u64(header + 16, word_count);
    for (int a = 0; a < 3; a++) {
        put_f32(header + 24 + 4 * a, lo[a]);
        put_f32(header + 36 + 4 * a, hi[a]);
    }
    sl_put_u32(header + 48, (uint32_t)t->nodes[0].x);
    sl_put_u32(header + 52, (uint32_t)t->nodes[0].y);
    sl_put_u32(header + 56, (uint32_t)t->nodes[0].z);
    uint32_t *lod = malloc(((size_t)e + 1) * sizeof *lod);
    if (lod)
        for (uint32_t i = 0; i < e; i++)
            lod[i] = pos_of[m->lod_array[i]];
    /* surface_before: a model being written need not have been prepared. */
    uint32_t *surface = malloc(((size_t)e + 1) * sizeof *surface);
    if (surface && sl_lod_surface_counts(m, surface)) {
        free(surface);
        surface = NULL;
    }
    int rc = !lod || !surface || sl_packer_add(pk, header, sizeof header, 0) ||
             sl_packer_add(pk, lod, (size_t)e * 4, 4) ||
             sl_packer_add(pk, m->accumulation, ((size_t)e + 1) * 8, 8) ||
             sl_packer_add(pk, m->error_after, ((size_t)e + 1) * 4, 4) ||
             sl_packer_add(pk, surface, ((size_t)e + 1) * 4, 4) ||
             sl_packer_add(pk, bases, (size_t)n * 4, 4) ||
             sl_packer_add(pk, words, word_count * 4, 4);
    free(lod);
    free(surface);
    return rc ? -1 : 0;
}

int sl_lod_order_pack(const sl_lod_model *m, size_t piece_size, void **out, size_t *out_size)
{
    const sl_octree *t = &m->tree;
    uint32_t n = t->node_count;
    *out = NULL;
    *out_size = 0;
    if (m->cuts_only)
        return -1; /* its nodes are gone (sl_lod_model_prepare) */
    uint32_t *order = sl_lod_order(m);
    uint32_t *pos_of = malloc((n ? n : 1) * sizeof *pos_of);
    uint32_t *new_id = order ? sl_lod_crossing_numbers(m, order) : NULL;
    sl_packer *pk = sl_packer_new(1, piece_size);
    int rc = order && pos_of && new_id && pk ? 0 : -1;
    for (uint32_t pos = 0; !rc && pos < n; pos++)
        pos_of[order[pos]] = pos;
    /* The octree header as the tree's, without node metrics (format 4 on), in LOD order. */
    sl_octree head = *t;
    head.node_error = head.node_area = NULL;
    head.node_crossing_count = 0; /* what pack_ids writes: each node's own, once */
    for (uint32_t i = 0; i < n; i++)
        head.node_crossing_count += (uint64_t)__builtin_popcount(t->nodes[i].edge_mask);
    unsigned char header[512];
    sl_artifact_part parts[SL_OCTREE_PARTS];
    sl_octree_parts(&head, header, parts, SL_OCTREE_FLAG_LOD_ORDER);
    if (!rc)
        rc = sl_packer_add(pk, header, parts[0].size, 0);
    uint32_t *words = NULL, *bases = NULL;
    uint64_t word_count = 0;
    if (!rc)
        rc = pack_nodes(pk, m, order);
    if (!rc)
        rc = pack_ids(pk, m, order, new_id, &words, &bases, &word_count);
    if (!rc)
        rc = pack_crossings(pk, t, new_id);
    if (!rc && sl_octree_dual(t))
        rc = pack_vertices(pk, t, order);
    if (!rc)
        rc = pack_lod(pk, m, pos_of, words, bases, word_count);
    free(words);
    free(bases);
    free(order);
    free(pos_of);
    free(new_id);
    if (rc) {
        sl_packer_free(pk);
        return -1;
    }
    return sl_packer_finish(pk, out, out_size);
}

