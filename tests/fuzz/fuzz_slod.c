/* libFuzzer target for the LOD model reader and generation (build: -DSCANLOD_FUZZ=ON with
 * clang; see tests/fuzz/CMakeLists.txt). Inputs are .slod bodies, after the envelope, so
 * mutations reach the structural checks instead of stopping at the checksum: a checksum
 * proves a file intact, not that whoever wrote it meant well (a viewer opens files it is
 * handed). Crashes, sanitizer reports, leaks, hangs and broken promises
 * (slod_promises.h) are findings.
 *
 * Byte mutations alone rarely get past the reader's checks (a flipped parent link or
 * child range is refused at once), so two mutations in three are made in the body's own
 * terms (docs/formats.md): the LOD array reordered, table entries, transition record
 * bits, neighbour masks and indices, crossing ids and positions, corner signs with their
 * edge mask recomputed, the grid's leaf size and origin, the grid collapsed onto one
 * point, and in a model with dual vertices their positions, ranges, errors and areas.
 * They keep the counts the reader checks and change what it trusts. A format 5 body
 * (checked pieces, LOD order: runtime/lod_order.h) is unpacked first, mutated in its own
 * terms (node records' signs and child masks, coded crossing ids, the LOD array, records,
 * ranges, surface counts, the root's cube) and packed again in small pieces, so that the
 * mutations reach past the pieces' checks and the prefix reader's piece boundaries.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "runtime/lod_order.h"
#include "runtime/lod_pack.h"
#include "runtime/mc_cube.h"
#include "tests/fuzz/slod_promises.h"

size_t LLVMFuzzerMutate(uint8_t *data, size_t size, size_t max_size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *why = slod_body_broken(data, size);
    if (why) {
        fprintf(stderr, "broken promise: %s\n", why);
        abort();
    }
    return 0;
}

/* Counts and byte offsets of the body's sections (layout_of fails when the body does not
 * hold them exactly). */
typedef struct body_layout {
    uint64_t n, cc, e, nbc, tc, vc;
    size_t nodes, node_crossings, ncc, positions;
    size_t vertex_first, vertex_positions, node_error; /* dual vertices (vc > 0) */
    size_t lod_array, accumulation, error_after, nb_mask, nb_index, tr_base, tr_words;
} body_layout;

#define OCTREE_HEADER 288
#define LOD_HEADER 24

static int layout_of(const uint8_t *d, size_t size, body_layout *l)
{
    if (size < OCTREE_HEADER)
        return -1;
    l->n = sl_get_u32(d + 4);
    l->cc = sl_get_u32(d + 8);
    uint64_t colour = sl_get_u32(d + 12) ? 4 : 0;
    l->ncc = sl_get_u64(d + 16);
    if (l->ncc > size || l->n > size)
        return -1;
    l->vc = sl_get_u32(d + 272);
    int dual = sl_get_u32(d + 276) & 1;
    if (l->vc > size)
        return -1;
    l->nodes = OCTREE_HEADER;
    l->node_crossings = l->nodes + 32 * l->n;
    l->positions = l->node_crossings + 4 * l->ncc;
    size_t lod = l->positions + (12 + colour) * l->cc;
    if (dual) {
        l->vertex_first = lod;
        l->vertex_positions = l->vertex_first + 4 * (l->n + 1);
        l->node_error = l->vertex_positions + (12 + colour) * l->vc;
        lod = l->node_error + 8 * l->n;
    } else {
        l->vc = 0;
    }
    if (lod + LOD_HEADER > size)
        return -1;
    l->e = sl_get_u32(d + lod);
    l->nbc = sl_get_u64(d + lod + 8);
    l->tc = sl_get_u64(d + lod + 16);
    if (l->e > size || l->nbc > size || l->tc > size)
        return -1;
    l->lod_array = lod + LOD_HEADER;
    l->accumulation = l->lod_array + 4 * l->e;
    l->error_after = l->accumulation + 8 * (l->e + 1);
    l->nb_mask = l->error_after + 4 * (l->e + 1);
    l->nb_index = l->nb_mask + 8 * l->n;
    l->tr_base = l->nb_index + 4 * l->nbc;
    l->tr_words = l->tr_base + 4 * l->n;
    return l->tr_words + 4 * l->tc == size && l->n && l->cc ? 0 : -1;
}

static uint64_t next(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static uint32_t get32(const uint8_t *d, size_t at) { return sl_get_u32(d + at); }
static void put32(uint8_t *d, size_t at, uint32_t v) { sl_put_u32(d + at, v); }

/* A node with a transition record, or SL_OCTREE_NONE after a few misses. */
static uint32_t node_with_record(const uint8_t *d, const body_layout *l, uint64_t *s)
{
    for (int tries = 0; tries < 32; tries++) {
        uint32_t node = (uint32_t)(next(s) % l->n), base = get32(d, l->tr_base + 4 * node);
        if (base != SL_OCTREE_NONE && (uint64_t)base + 3 <= l->tc)
            return base;
    }
    return SL_OCTREE_NONE;
}

static void mutate_in_terms(uint8_t *d, const body_layout *l, uint64_t *s)
{
    uint64_t r = next(s);
    switch (r % 13) {
    case 0: /* two nearby LOD array entries swapped */
        if (l->e >= 2) {
            uint64_t i = next(s) % (l->e - 1), j = i + 1 + next(s) % 8;
            j = j < l->e ? j : l->e - 1;
            uint32_t a = get32(d, l->lod_array + 4 * i);
            put32(d, l->lod_array + 4 * i, get32(d, l->lod_array + 4 * j));
            put32(d, l->lod_array + 4 * j, a);
        }
        break;
    case 1: { /* an accumulation entry anywhere within the reader's bound */
        uint64_t i = next(s) % (l->e + 1);
        sl_put_u64(d + l->accumulation + 8 * i, next(s) % (64 * (1 + 7 * i) + 1));
        break;
    }
    case 2: { /* midpoint / centre sign and known bits of a transition record */
        uint32_t w = node_with_record(d, l, s);
        if (w != SL_OCTREE_NONE) {
            size_t at = l->tr_words + 4 * (size_t)w;
            put32(d, at, get32(d, at) ^ (uint32_t)(1u << (next(s) % 30)));
            put32(d, at + 4, get32(d, at + 4) ^ (uint32_t)(next(s) % 64) << 24);
        }
        break;
    }
    case 3: { /* one half-edge (or spoke) crossing moved to another slot: same count */
        uint32_t w = node_with_record(d, l, s);
        if (w != SL_OCTREE_NONE) {
            size_t at = l->tr_words + 4 * ((size_t)w + 1 + next(s) % 2);
            uint32_t v = get32(d, at), mask = v & 0xffffff;
            uint32_t on = (uint32_t)(next(s) % 24), off = (uint32_t)(next(s) % 24);
            if ((mask >> on & 1) && !(mask >> off & 1))
                put32(d, at, v ^ (1u << on) ^ (1u << off));
        }
        break;
    }
    case 4: /* a node's or a record's crossing id: another valid crossing */
        if (l->ncc && next(s) % 2)
            put32(d, l->node_crossings + 4 * (next(s) % l->ncc), (uint32_t)(next(s) % l->cc));
        else if (l->tc)
            put32(d, l->tr_words + 4 * (next(s) % l->tc), (uint32_t)(next(s) % l->cc));
        break;
    case 5: { /* a neighbour direction added or dropped (the reader checks only ranges) */
        size_t at = l->nb_mask + 4 * (next(s) % l->n);
        uint32_t bit = (uint32_t)(next(s) % 27);
        if (bit != 13)
            put32(d, at, get32(d, at) ^ (1u << bit));
        break;
    }
    case 6: /* a neighbour: another node */
        if (l->nbc)
            put32(d, l->nb_index + 4 * (next(s) % l->nbc), (uint32_t)(next(s) % l->n));
        break;
    case 7: { /* a corner sign flipped, the edge mask kept consistent */
        uint8_t *node = d + l->nodes + 32 * (next(s) % l->n);
        node[13] ^= (uint8_t)(1u << (next(s) % 8));
        unsigned inside = node[13], mask = 0;
        for (int e = 0; e < 12; e++)
            mask |= (((inside >> sl_mc_edge_c0(e)) ^ (inside >> sl_mc_edge_c1(e))) & 1u) << e;
        node[28] = (uint8_t)mask;
        node[29] = (uint8_t)(mask >> 8);
        break;
    }
    case 8: { /* a crossing coordinate: extreme, tiny or another crossing's */
        static const float values[] = {0.0f, 1e30f, -1e30f, 3.4e38f, 1e-40f, -1e-7f};
        size_t at = l->positions + 4 * (next(s) % (3 * l->cc));
        float v = values[next(s) % 6];
        memcpy(d + at, &v, 4);
        break;
    }
    case 9: { /* the grid: leaf size or an origin coordinate, extreme or tiny */
        static const double values[] = {1e-300, 1e-9, 1e14, 1e16, -1e16, 0.0};
        double v = values[next(s) % 6];
        memcpy(d + 24 + 8 * (next(s) % 4), &v, 8); /* leaf size, then origin x, y, z */
        break;
    }
    case 10: { /* the grid collapsed: a tiny leaf at an origin away from zero, every
                  crossing on the origin or the next float up, which the reader's rounding
                  slack accepts (case 9 alone leaves the crossings outside the cube) */
        static const double leaves[] = {1e-30, 1e-300, 1e-12};
        static const double origins[] = {1.0, -3.0, 1e6};
        double leaf = leaves[next(s) % 3], origin = origins[next(s) % 3];
        memcpy(d + 24, &leaf, 8);
        for (int a = 0; a < 3; a++)
            memcpy(d + 32 + 8 * a, &origin, 8);
        for (uint64_t i = 0; i < 3 * l->cc; i++) {
            float v = (float)origin;
            if (next(s) & 1)
                v = nextafterf(v, INFINITY);
            memcpy(d + l->positions + 4 * i, &v, 4);
        }
        break;
    }
    case 11: { /* a dual vertex: a coordinate extreme or another's; a range end moved; a
                  node error or area negative, huge or not a number */
        if (!l->vc)
            break;
        static const float values[] = {0.0f, 1e30f, -3.4e38f, 1e-40f, -1.0f, NAN};
        uint64_t what = next(s) % 3;
        float v = values[next(s) % 6];
        if (what == 0) {
            memcpy(d + l->vertex_positions + 4 * (next(s) % (3 * l->vc)), &v, 4);
        } else if (what == 1) {
            size_t at = l->vertex_first + 4 * (1 + next(s) % l->n);
            put32(d, at, get32(d, at) + (next(s) & 1 ? 1u : UINT32_MAX));
        } else {
            memcpy(d + l->node_error + 4 * (next(s) % (2 * l->n)), &v, 4);
        }
        break;
    }
    default: { /* an error_after entry, negative or huge */
        static const float values[] = {-1.0f, 0.0f, 1e30f, 3.4e38f};
        float v = values[next(s) % 4];
        memcpy(d + l->error_after + 4 * (next(s) % (l->e + 1)), &v, 4);
        break;
    }
    }
}

/* One mutation of a format 5 plain body in its own terms (sections in `sec`). */
static void mutate_ordered_terms(uint8_t *d, const sl_lod_sections *sec, uint64_t *s)
{
    uint64_t n = sec->nodes, e = sec->expansions, words = sec->words;
    uint64_t ids = sec->size[SL_SEC_IDS] / 4, cc = sec->size[SL_SEC_POSITIONS] / 12;
    switch (next(s) % 11) {
    case 0: /* two nearby LOD array entries swapped */
        if (e >= 2) {
            uint64_t i = next(s) % (e - 1), j = i + 1 + next(s) % 8;
            j = j < e ? j : e - 1;
            size_t at = sec->at[SL_SEC_LOD_ARRAY];
            uint32_t a = get32(d, at + 4 * i);
            put32(d, at + 4 * i, get32(d, at + 4 * j));
            put32(d, at + 4 * j, a);
        }
        break;
    case 1: /* a corner sign (the edge mask follows from it) */
        d[sec->at[SL_SEC_NODES] + 4 * (next(s) % n)] ^= (uint8_t)(1u << (next(s) % 8));
        break;
    case 2: /* a child mask bit: children appear or go, shifting every later position */
        d[sec->at[SL_SEC_NODES] + 4 * (next(s) % n) + 1] ^= (uint8_t)(1u << (next(s) % 8));
        break;
    case 3: /* a coded crossing id: new, a step back, far back, a parent's record entry
               (one it may have, one past any record) */
        if (ids) {
            static const uint32_t codes[] = {0, 1, 2, 7, 100, 0x7fffffff,
                                             SL_LOD_ORDER_FROM_PARENT, SL_LOD_ORDER_FROM_PARENT | 5,
                                             SL_LOD_ORDER_FROM_PARENT | 47, 0xffffffff};
            put32(d, sec->at[SL_SEC_IDS] + 4 * (next(s) % ids), codes[next(s) % 10]);
        }
        break;
    case 4: /* a transition word: sign bits, a half-edge bit, or a coded id */
        if (words) {
            size_t at = sec->at[SL_SEC_TRANSITION_WORDS] + 4 * (next(s) % words);
            put32(d, at, get32(d, at) ^ (uint32_t)(1u << (next(s) % 30)));
        }
        break;
    case 5: /* a transition base: another record's, none, past the end */
        if (n) {
            size_t at = sec->at[SL_SEC_TRANSITION_BASE] + 4 * (next(s) % n);
            uint32_t v = next(s) % 3 == 0 ? SL_OCTREE_NONE
                         : next(s) % 2 ? (uint32_t)(next(s) % (words + 1))
                                       : (uint32_t)words + 1;
            put32(d, at, v);
        }
        break;
    case 6: { /* a crossing coordinate: extreme, tiny or another crossing's */
        static const float values[] = {0.0f, 1e30f, -1e30f, 3.4e38f, 1e-40f, -1e-7f};
        if (cc) {
            float v = values[next(s) % 6];
            memcpy(d + sec->at[SL_SEC_POSITIONS] + 4 * (next(s) % (3 * cc)), &v, 4);
        }
        break;
    }
    case 7: /* a vertex range end moved by one */
        if (sec->size[SL_SEC_VERTEX_FIRST]) {
            size_t at = sec->at[SL_SEC_VERTEX_FIRST] + 4 * (1 + next(s) % n);
            put32(d, at, get32(d, at) + (next(s) & 1 ? 1u : UINT32_MAX));
        }
        break;
    case 8: { /* a surface count one off */
        size_t at = sec->at[SL_SEC_SURFACE] + 4 * (next(s) % (e + 1));
        put32(d, at, get32(d, at) + (next(s) & 1 ? 1u : UINT32_MAX));
        break;
    }
    case 9: { /* the root's cube moved, the bounds changed */
        size_t at = sec->at[SL_SEC_LOD_HEADER] + 24 + 4 * (next(s) % 9);
        put32(d, at, next(s) % 2 ? get32(d, at) + 1u : (uint32_t)next(s));
        break;
    }
    default: { /* an accumulation entry anywhere within the reader's bound */
        uint64_t i = next(s) % (e + 1);
        sl_put_u64(d + sec->at[SL_SEC_ACCUMULATION] + 8 * i, next(s) % (64 * (1 + 7 * i) + 1));
        break;
    }
    }
}

/* A format 5 body unpacked, mutated, packed again section by section in 512-byte pieces;
 * 0 when it is not one or does not fit (the caller mutates bytes then). */
static size_t mutate_ordered(uint8_t *data, size_t size, size_t max_size, uint64_t *s)
{
    void *plain = NULL, *packed = NULL;
    uint64_t plain_size = 0;
    size_t packed_size = 0, out = 0;
    sl_error err;
    sl_error_init(&err);
    sl_octree head;
    sl_octree_layout lay;
    sl_lod_sections sec;
    if (sl_unpack(data, size, (uint64_t)1 << 26, "fuzz", &plain, &plain_size, &err) ||
        sl_octree_parse_header(plain, plain_size, "fuzz", &head, &lay, &err) ||
        plain_size < sl_lod_order_octree_size(&lay, head.node_count) + SL_LOD_ORDER_HEADER ||
        sl_lod_order_sections(&head, &lay,
                              (uint8_t *)plain + sl_lod_order_octree_size(&lay, head.node_count),
                              plain_size, "fuzz", &sec, &err) ||
        !sec.nodes) {
        free(plain);
        return 0;
    }
    for (uint64_t i = 0, count = 1 + next(s) % 3; i < count; i++)
        mutate_ordered_terms(plain, &sec, s);
    sl_packer *pk = sl_packer_new(1, 512);
    int ok = pk != NULL;
    for (int k = 0; ok && k < SL_SEC_COUNT; k++)
        ok = sl_packer_add(pk, (uint8_t *)plain + sec.at[k], sec.size[k],
                           k == SL_SEC_OCTREE_HEADER || k == SL_SEC_LOD_HEADER ? 0 : 4) == 0;
    if (ok && sl_packer_finish(pk, &packed, &packed_size) == 0 && packed_size <= max_size) {
        memcpy(data, packed, packed_size);
        out = packed_size;
    } else if (!ok) {
        sl_packer_free(pk);
    }
    free(packed);
    free(plain);
    return out;
}

size_t LLVMFuzzerCustomMutator(uint8_t *data, size_t size, size_t max_size, unsigned int seed)
{
    uint64_t s = (uint64_t)seed * 0x9e3779b97f4a7c15ull + 1;
    body_layout l;
    if (size >= 4 && sl_get_u32(data) == SL_PACK_MAGIC_CHECKED && next(&s) % 3 != 0) {
        size_t mutated = mutate_ordered(data, size, max_size, &s);
        if (mutated)
            return mutated;
    }
    if (next(&s) % 3 == 0 || layout_of(data, size, &l) != 0)
        return LLVMFuzzerMutate(data, size, max_size);
    for (uint64_t i = 0, count = 1 + next(&s) % 3; i < count; i++)
        mutate_in_terms(data, &l, &s);
    return size;
}
