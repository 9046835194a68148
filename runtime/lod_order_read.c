/* Model format 5's LOD-ordered body: turning what was read of it (all of it, or a prefix)
 * back into a model in level order (lod_order.h; writing: lod_order.c). */
#include "runtime/lod_order.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "runtime/lod_io.h"

static void *copy_of(const void *src, size_t bytes)
{
    void *p = malloc(bytes ? bytes : 1);
    if (p && bytes)
        memcpy(p, src, bytes);
    return p;
}

/* Children of position p at the next free positions (*next on), their records made from
 * p's; 1 when they do not fit or p is a leaf. */
static int place_children(const sl_lod_raw *raw, sl_octree_node *out, uint32_t p, uint32_t *next)
{
    sl_octree_node *parent = &out[p];
    uint32_t kids = (uint32_t)__builtin_popcount(parent->child_mask);
    if (parent->level == 0 || (uint64_t)*next + kids > raw->nodes)
        return 1;
    parent->first_child = *next;
    for (uint32_t mask = parent->child_mask; mask; mask &= mask - 1u) {
        uint32_t o = (uint32_t)__builtin_ctz(mask), c = (*next)++;
        const uint8_t *r = raw->node + (size_t)SL_LOD_ORDER_NODE * c;
        if (parent->level == 1 && r[1])
            return 1; /* a leaf with children */
        out[c] = (sl_octree_node){2 * parent->x + (int32_t)(o & 1),
                                  2 * parent->y + (int32_t)(o >> 1 & 1),
                                  2 * parent->z + (int32_t)(o >> 2),
                                  (uint8_t)(parent->level - 1), r[0], r[1], r[2], p,
                                  SL_OCTREE_NONE, 0, sl_octree_edge_mask(r[0]), 0};
    }
    return 0;
}

/* The positions' full records from the stored ones: the root from the header, then each
 * expansion's children, in LOD array order, at the next free positions; when whole, then
 * the never expanded nodes' children, breadth first (sl_lod_order). 1 when the positions
 * do not come out as one tree. */
static int lod_nodes(const sl_lod_raw *raw, const uint8_t *expanded, sl_octree_node *out)
{
    const uint8_t *r = raw->node;
    if (r[3] || raw->head.depth >= SL_OCTREE_MAX_LEVELS)
        return 1;
    for (int a = 0; a < 3; a++) /* the cubes below it are then in range as they are made */
        if (raw->root[a] < 0 || raw->root[a] >= (1 << 20))
            return 1;
    out[0] = (sl_octree_node){raw->root[0], raw->root[1], raw->root[2],
                              (uint8_t)raw->head.depth, r[0], r[1], r[2], SL_OCTREE_NONE,
                              SL_OCTREE_NONE, 0, sl_octree_edge_mask(r[0]), 0};
    uint32_t next = 1;
    for (uint32_t i = 0; i < raw->expansions; i++)
        if (raw->lod_array[i] >= next || place_children(raw, out, raw->lod_array[i], &next))
            return 1;
    for (uint32_t p = 0; raw->whole && p < next; p++)
        if (out[p].child_mask && !expanded[p] && place_children(raw, out, p, &next))
            return 1;
    if (next != raw->nodes)
        return 1;
    uint32_t base = 0;
    for (uint32_t p = 0; p < raw->nodes; p++) {
        if (raw->node[(size_t)SL_LOD_ORDER_NODE * p + 3])
            return 1;
        out[p].crossing_base = base;
        base += (uint32_t)__builtin_popcount(out[p].edge_mask);
    }
    return 0;
}

/* Level order from LOD order: a breadth-first walk from the root, children in octant
 * order, gives root, then each level in Morton order (a child's code is its parent's
 * times 8 plus its octant). Only the children of expanded positions are followed unless
 * the raw body is whole. level[i] = LOD position of the i-th node in level order;
 * index_of[pos] = its index. Returns 0, 1 when the positions are not one tree, -1 on OOM. */
static int level_order(const sl_lod_raw *raw, const sl_octree_node *nodes,
                       const uint8_t *expanded, uint32_t *level, uint32_t *index_of)
{
    uint32_t f = raw->nodes, count = 1;
    memset(index_of, 0xff, (size_t)f * sizeof *index_of);
    level[0] = 0;
    index_of[0] = 0;
    for (uint32_t i = 0; i < count; i++) {
        const sl_octree_node *node = &nodes[level[i]];
        uint32_t kids = (uint32_t)__builtin_popcount(node->child_mask);
        if (!kids || (!raw->whole && !expanded[level[i]]))
            continue;
        if (node->first_child == SL_OCTREE_NONE || node->first_child == 0 ||
            (uint64_t)node->first_child + kids > f)
            return 1;
        for (uint32_t j = 0; j < kids; j++) {
            uint32_t c = node->first_child + j;
            if (index_of[c] != SL_OCTREE_NONE || nodes[c].parent != level[i])
                return 1;
            index_of[c] = count;
            level[count++] = c;
        }
    }
    return count == f ? 0 : 1;
}

/* The tree part of the model, in level order; 1 when raw is not one tree. */
static int build_tree(const sl_lod_raw *raw, const sl_octree_node *nodes,
                      const uint8_t *expanded, const uint32_t *level, const uint32_t *index_of,
                      sl_octree *t)
{
    uint32_t f = raw->nodes;
    *t = raw->head;
    t->nodes = malloc((size_t)f * sizeof *t->nodes);
    t->node_count = f;
    memset(t->level_first, 0, sizeof t->level_first);
    memset(t->level_count, 0, sizeof t->level_count);
    if (!t->nodes)
        return -1;
    for (uint32_t i = 0; i < f; i++) {
        sl_octree_node node = nodes[level[i]];
        node.parent = i ? index_of[node.parent] : SL_OCTREE_NONE;
        if (node.child_mask && (raw->whole || expanded[level[i]])) {
            node.first_child = index_of[node.first_child];
        } else {
            node.child_mask = 0; /* its children are past the prefix */
            node.first_child = SL_OCTREE_NONE;
        }
        if (node.level >= SL_OCTREE_MAX_LEVELS)
            return 1;
        if (!t->level_count[node.level]++)
            t->level_first[node.level] = i;
        t->nodes[i] = node;
    }
    t->node_crossing_count = raw->ids;
    t->node_crossings = copy_of(raw->node_crossings, raw->ids * 4);
    t->crossing_count = raw->crossings;
    t->crossing_position = copy_of(raw->crossing_position, (size_t)raw->crossings * 12);
    t->crossing_color = raw->crossing_color ? copy_of(raw->crossing_color, (size_t)raw->crossings * 4)
                                            : NULL;
    if (!t->node_crossings || !t->crossing_position || (raw->crossing_color && !t->crossing_color))
        return -1;
    if (!raw->vertex_first)
        return 0;
    uint32_t v = raw->vertex_first[f];
    t->vertex_first = malloc(((size_t)f + 1) * sizeof *t->vertex_first);
    t->vertex_position = malloc((v ? v : 1) * 12);
    t->vertex_color = raw->vertex_color ? malloc((v ? v : 1) * 4) : NULL;
    if (!t->vertex_first || !t->vertex_position || (raw->vertex_color && !t->vertex_color))
        return -1;
    /* Every range in order before any is copied: in level order, a range read before a
     * wrong one was met could run past the table (fuzz corpus ordered-vertex-overrun). */
    for (uint32_t p = 0; p < f; p++)
        if (raw->vertex_first[p + 1] < raw->vertex_first[p] ||
            raw->vertex_first[p + 1] - raw->vertex_first[p] > SL_OCTREE_MAX_NODE_VERTICES)
            return 1;
    if (raw->vertex_first[0] != 0)
        return 1;
    uint32_t at = 0;
    for (uint32_t i = 0; i < f; i++) {
        uint32_t pos = level[i], from = raw->vertex_first[pos], to = raw->vertex_first[pos + 1];
        t->vertex_first[i] = at;
        memcpy(t->vertex_position + 3 * (size_t)at, raw->vertex_position + 3 * (size_t)from,
               12 * (size_t)(to - from));
        if (t->vertex_color)
            memcpy(t->vertex_color + 4 * (size_t)at, raw->vertex_color + 4 * (size_t)from,
                   4 * (size_t)(to - from));
        at += to - from;
    }
    t->vertex_first[f] = at;
    t->vertex_count = at;
    return 0;
}

static int build_lod(const sl_lod_raw *raw, const uint32_t *level, const uint32_t *index_of,
                     sl_lod_model *m)
{
    uint32_t f = raw->nodes, e = raw->expansions;
    m->expansion_count = e;
    m->lod_array = malloc(((size_t)e + 1) * sizeof *m->lod_array);
    m->accumulation = copy_of(raw->accumulation, ((size_t)e + 1) * 8);
    m->error_after = copy_of(raw->error_after, ((size_t)e + 1) * 4);
    m->transitions.base = malloc((size_t)f * sizeof *m->transitions.base);
    m->transitions.count = raw->words;
    m->transitions.words = copy_of(raw->transition_words, raw->words * 4);
    if (!m->lod_array || !m->accumulation || !m->error_after || !m->transitions.base ||
        !m->transitions.words)
        return -1;
    for (uint32_t i = 0; i < e; i++)
        m->lod_array[i] = index_of[raw->lod_array[i]];
    for (uint32_t i = 0; i < f; i++)
        m->transitions.base[i] = raw->transition_base[level[i]];
    return 0;
}

static int decode_pools(const sl_lod_raw *raw, const sl_octree_node *nodes, uint32_t *ids,
                        uint32_t *words);

int sl_lod_raw_build(const sl_lod_raw *raw, int cuts_only, const char *name, sl_lod_model *out,
                     sl_error *err)
{
    sl_lod_model_init(out);
    out->cuts_only = cuts_only;
    uint32_t f = raw->nodes, e = raw->expansions;
    if (f == 0 || e >= f)
        return sl_lod_corrupt(err, name, "LOD section sizes do not match the file");
    uint8_t *expanded = calloc(f, 1);
    uint32_t *level = malloc((size_t)f * sizeof *level);
    uint32_t *index_of = malloc((size_t)f * sizeof *index_of);
    sl_octree_node *nodes = malloc((size_t)f * sizeof *nodes);
    int rc = expanded && level && index_of && nodes ? 0 : -1;
    /* Each expansion a position present, once; the tree then follows their children. */
    for (uint32_t i = 0; !rc && i < e; i++) {
        uint32_t pos = raw->lod_array[i];
        if (pos >= f || expanded[pos])
            rc = 1;
        else
            expanded[pos] = 1;
    }
    if (!rc)
        rc = lod_nodes(raw, expanded, nodes);
    if (!rc)
        rc = level_order(raw, nodes, expanded, level, index_of);
    if (!rc)
        rc = build_tree(raw, nodes, expanded, level, index_of, &out->tree);
    if (!rc)
        rc = build_lod(raw, level, index_of, out);
    const char *why = "nodes in LOD order are not one tree";
    if (!rc && decode_pools(raw, nodes, out->tree.node_crossings, out->transitions.words)) {
        rc = 1;
        why = "crossing ids out of range";
    }
    free(nodes);
    free(expanded);
    free(level);
    free(index_of);
    if (rc) {
        sl_lod_model_release(out);
        return rc < 0 ? sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory")
                      : sl_lod_corrupt(err, name, why);
    }
    rc = sl_octree_check(&out->tree, name, err);
    if (rc == 0)
        rc = sl_lod_model_derive(out, 0, raw->whole ? raw->neighbour_links : UINT64_MAX, name, err);
    /* The stored counts of expansions with surface below: the whole tree's must be what
     * it says; a prefix cannot see the surface below its last level, so it takes them. */
    for (uint32_t i = 0; rc == 0 && i <= e; i++) {
        if (raw->whole && out->surface_before[i] != raw->surface_before[i])
            rc = sl_lod_corrupt(err, name, "surface counts differ from the octree's");
        out->surface_before[i] = raw->surface_before[i];
    }
    if (rc)
        sl_lod_model_release(out);
    return rc;
}

int sl_lod_order_count_new(const uint8_t *node, uint32_t nodes, const uint32_t *ids,
                           uint64_t id_count, const uint32_t *base, const uint32_t *words,
                           uint64_t word_count, uint64_t *crossings)
{
    uint64_t at = 0, fresh = 0, end = 0;
    for (uint32_t p = 0; p < nodes; p++) {
        uint32_t own = (uint32_t)__builtin_popcount(sl_octree_edge_mask(node[SL_LOD_ORDER_NODE * (size_t)p]));
        if (at + own > id_count)
            return 1;
        for (uint32_t i = 0; i < own; i++)
            fresh += ids[at++] == 0;
        if (base[p] == SL_OCTREE_NONE)
            continue;
        /* Records in position order, none over another: decoding one record's ids must
         * not change the heads (and so the lengths) of the next. */
        if (base[p] < end || (uint64_t)base[p] + 3 > word_count)
            return 1;
        const uint32_t *w = words + base[p];
        uint32_t size = sl_transition_record_words(w);
        if ((uint64_t)base[p] + size > word_count)
            return 1;
        end = (uint64_t)base[p] + size;
        for (uint32_t i = 3; i < size; i++)
            fresh += w[i] == 0;
    }
    *crossings = fresh;
    return 0;
}

/* One code into its id (lod_order.c, code_id): 1 when it names an id not yet numbered or
 * a parent's record entry it has not. `from` is the parent's record ids (count of them). */
static int decode_id(uint32_t *id, uint32_t *next, const uint32_t *from, uint32_t from_count)
{
    uint32_t code = *id;
    if (code == 0) {
        *id = (*next)++;
    } else if (code & SL_LOD_ORDER_FROM_PARENT) {
        uint32_t j = code & ~SL_LOD_ORDER_FROM_PARENT;
        if (j >= from_count)
            return 1;
        *id = from[j];
    } else if (code > *next) {
        return 1;
    } else {
        *id = *next - code;
    }
    return 0;
}

/* The ids of the model's pools (still in LOD order: each position's own from its crossing
 * base, its record at its transition base) decoded in place, positions in order, so a
 * parent's record is decoded before its children name it. Ranges were checked by
 * sl_lod_order_count_new. 1 on a code that names nothing. */
static int decode_pools(const sl_lod_raw *raw, const sl_octree_node *nodes, uint32_t *ids,
                        uint32_t *words)
{
    uint32_t next = 0;
    for (uint32_t p = 0; p < raw->nodes; p++) {
        const uint32_t *from = NULL;
        uint32_t from_count = 0, parent = nodes[p].parent;
        if (p && raw->transition_base[parent] != SL_OCTREE_NONE) {
            from = words + raw->transition_base[parent] + 3;
            from_count = sl_transition_record_words(from - 3) - 3;
        }
        uint32_t *own = ids + nodes[p].crossing_base;
        for (int i = 0, k = __builtin_popcount(nodes[p].edge_mask); i < k; i++)
            if (decode_id(&own[i], &next, from, from_count))
                return 1;
        if (raw->transition_base[p] == SL_OCTREE_NONE)
            continue;
        uint32_t *w = words + raw->transition_base[p], size = sl_transition_record_words(w);
        for (uint32_t i = 3; i < size; i++)
            if (decode_id(&w[i], &next, NULL, 0))
                return 1;
    }
    return next > raw->crossings;
}

static float get_f32(const unsigned char *p)
{
    uint32_t bits = sl_get_u32(p);
    float v;
    memcpy(&v, &bits, 4);
    return v;
}

int sl_lod_order_sections(const sl_octree *head, const sl_octree_layout *layout,
                          const unsigned char *lod_header, uint64_t plain_size,
                          const char *name, sl_lod_sections *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    if (!(layout->flags & SL_OCTREE_FLAG_LOD_ORDER) || layout->metrics)
        return sl_lod_corrupt(err, name, "format 5 octree not in LOD order or with node metrics");
    uint64_t e = sl_get_u32(lod_header), n = sl_get_u32(lod_header + 4);
    out->expansions = (uint32_t)e;
    out->nodes = (uint32_t)n;
    out->links = sl_get_u64(lod_header + 8);
    out->words = sl_get_u64(lod_header + 16);
    for (int i = 0; i < 6; i++)
        out->bounds[i] = get_f32(lod_header + 24 + 4 * i);
    for (int a = 0; a < 3; a++)
        out->root[a] = (int32_t)sl_get_u32(lod_header + 48 + 4 * a);
    if (n != head->node_count || e >= n || out->links > 26 * n || out->words > 51 * n ||
        sl_get_u32(lod_header + 60) != 0)
        return sl_lod_corrupt(err, name, "LOD section sizes do not match the file");
    const uint64_t size[SL_SEC_COUNT] = {
        SL_OCTREE_HEADER_SIZE, SL_LOD_ORDER_NODE * n, layout->ids, layout->positions, layout->colors,
        layout->vertex_first, layout->vertices, layout->vertex_colors, SL_LOD_ORDER_HEADER,
        4 * e, 8 * (e + 1), 4 * (e + 1), 4 * (e + 1), 4 * n, 4 * out->words};
    uint64_t at = 0;
    for (int s = 0; s < SL_SEC_COUNT; s++) {
        out->at[s] = at;
        out->size[s] = size[s];
        at += size[s];
    }
    if (at != plain_size)
        return sl_lod_corrupt(err, name, "LOD section sizes do not match the file");
    return 0;
}

int sl_lod_order_parse(const unsigned char *plain, uint64_t size, int cuts_only,
                       const char *name, sl_lod_model *out, sl_error *err)
{
    sl_lod_model_init(out);
    sl_lod_raw raw;
    memset(&raw, 0, sizeof raw);
    sl_lod_sections sec;
    int rc = sl_octree_parse_header(plain, size, name, &raw.head, &raw.layout, err);
    uint64_t lod_at = rc ? 0 : sl_lod_order_octree_size(&raw.layout, raw.head.node_count);
    if (rc == 0 && size < lod_at + SL_LOD_ORDER_HEADER)
        rc = sl_lod_corrupt(err, name, "truncated LOD header");
    if (rc == 0)
        rc = sl_lod_order_sections(&raw.head, &raw.layout, plain + lod_at, size, name, &sec, err);
    if (rc)
        return rc;
#define AT(s) (plain + sec.at[s])
    raw.nodes = sec.nodes;
    raw.node = AT(SL_SEC_NODES);
    memcpy(raw.root, sec.root, sizeof raw.root);
    raw.ids = raw.head.node_crossing_count;
    raw.node_crossings = (const uint32_t *)AT(SL_SEC_IDS);
    uint64_t named = 0;
    if (sl_lod_order_count_new(raw.node, sec.nodes, (const uint32_t *)AT(SL_SEC_IDS), raw.ids,
                               (const uint32_t *)AT(SL_SEC_TRANSITION_BASE),
                               (const uint32_t *)AT(SL_SEC_TRANSITION_WORDS), sec.words, &named) ||
        named > raw.head.crossing_count)
        return sl_lod_corrupt(err, name, "crossing ids out of range");
    raw.crossings = raw.head.crossing_count;
    raw.crossing_position = (const float *)AT(SL_SEC_POSITIONS);
    raw.crossing_color = raw.layout.has_color ? AT(SL_SEC_COLORS) : NULL;
    if (raw.layout.vertex_first) {
        raw.vertex_first = (const uint32_t *)AT(SL_SEC_VERTEX_FIRST);
        if (raw.vertex_first[0] != 0 || raw.vertex_first[sec.nodes] != raw.layout.vertex_count)
            return sl_lod_corrupt(err, name, "vertex ranges do not cover the vertex table");
        raw.vertex_position = (const float *)AT(SL_SEC_VERTICES);
        raw.vertex_color = raw.layout.has_color ? AT(SL_SEC_VERTEX_COLORS) : NULL;
    }
    raw.expansions = sec.expansions;
    raw.lod_array = (const uint32_t *)AT(SL_SEC_LOD_ARRAY);
    raw.accumulation = (const uint64_t *)AT(SL_SEC_ACCUMULATION);
    raw.error_after = (const float *)AT(SL_SEC_ERROR_AFTER);
    raw.surface_before = (const uint32_t *)AT(SL_SEC_SURFACE);
    raw.transition_base = (const uint32_t *)AT(SL_SEC_TRANSITION_BASE);
    raw.words = sec.words;
    raw.transition_words = (const uint32_t *)AT(SL_SEC_TRANSITION_WORDS);
#undef AT
    raw.whole = 1;
    raw.neighbour_links = sec.links;
    return sl_lod_raw_build(&raw, cuts_only, name, out, err);
}
