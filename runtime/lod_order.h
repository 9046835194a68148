/* Model format 5: the plain body in LOD order (docs/formats.md "model.slod"), so that what
 * a cut of the first k expansions reads is a prefix of every section (lod_prefix.h).
 *
 * LOD order is the cells' layout order (lod_layout.c): the root, then the children of
 * the 1st expanded node, of the 2nd, ..., then the nodes no expansion reaches. Every
 * per-node table (nodes, their crossing ids, dual vertex ranges and vertices, transition
 * bases and records) is stored in that order, the crossings are numbered by first use in
 * it, node links (parent, first child, LOD array) name LOD positions, and the per-node
 * pools are laid out in it. So after k expansions the nodes drawn are among the first
 * F(k) = 1 + (children of the first k expanded nodes) positions, and the crossings,
 * vertices and transition words they name are the first ones of their tables.
 *
 * Reading turns what was read (all of it, or such a prefix) back into a model in the
 * usual level order, checked by the same checks as every format, with the nodes the
 * prefix does not expand made leaves: cutting it at any k up to the prefix's gives the
 * very mesh the whole model gives.
 */
#ifndef SCANLOD_RUNTIME_LOD_ORDER_H
#define SCANLOD_RUNTIME_LOD_ORDER_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "runtime/lod_model.h"
#include "runtime/octree_io.h"

/* Format 5's LOD header: u32 expansion count, u32 node count, u64 neighbour links of the
 * whole table, u64 transition words, f32 bounds min[3], max[3] (of every crossing), i32
 * root x, y, z (the root's cube; the other nodes' follow from it), u32 0. */
#define SL_LOD_ORDER_HEADER 64u
/* A node's bytes in format 5: inside, child mask, flags, 0. */
#define SL_LOD_ORDER_NODE 4u
/* A node crossing code naming the parent's transition record's id j: this bit | j. */
#define SL_LOD_ORDER_FROM_PARENT 0x80000000u
/* Plain bytes per packed piece in format 5: a prefix reader unpacks whole pieces, so
 * smaller ones waste less on a small cut (docs/benchmarks.md). */
#define SL_LOD_ORDER_PIECE ((size_t)1 << 20)

/* The packed body of model m in format 5 (malloc'd), in pieces of piece_size plain bytes
 * (SL_LOD_ORDER_PIECE; the tests take small ones, so that every section spans several).
 * Each section is made in LOD order, packed and freed before the next, so writing needs
 * about one section's bytes beyond the model. Returns -1 when out of memory or for a model
 * opened for cutting only (cuts_only: its nodes are gone). */
int sl_lod_order_pack(const sl_lod_model *m, size_t piece_size, void **out, size_t *out_size);

/* What a reader has of a format 5 body: the octree header's scalars, then the first
 * `nodes` positions' tables and the first `expansions` entries of the LOD tables. */
typedef struct sl_lod_raw {
    sl_octree head; /* scalars only (sl_octree_parse_header) */
    sl_octree_layout layout;
    uint32_t nodes;                     /* positions present: F(expansions), or all */
    const uint8_t *node;                /* [nodes] stored records (SL_LOD_ORDER_NODE) */
    int32_t root[3];                    /* the root's coordinates (LOD header) */
    uint64_t ids;                       /* the positions' own crossing ids, in order, */
    const uint32_t *node_crossings;     /* [ids] as stored (coded: lod_order.c, code_id) */
    uint32_t crossings;
    const float *crossing_position;     /* [3 crossings] */
    const uint8_t *crossing_color;      /* [4 crossings] or NULL */
    const uint32_t *vertex_first;       /* [nodes + 1], dual only */
    const float *vertex_position;       /* [3 vertex_first[nodes]] */
    const uint8_t *vertex_color;
    uint32_t expansions;
    const uint32_t *lod_array;          /* [expansions] */
    const uint64_t *accumulation;       /* [expansions + 1] */
    const float *error_after;           /* [expansions + 1] */
    const uint32_t *surface_before;     /* [expansions + 1] */
    const uint32_t *transition_base;    /* [nodes] */
    uint64_t words;
    const uint32_t *transition_words;   /* [words], their ids as stored */
    int whole;                 /* every node and expansion of the file */
    uint64_t neighbour_links;  /* the header's: checked against the octree when whole */
} sl_lod_raw;

/* Checks that the coded crossing ids of positions 0 .. nodes - 1 (stored records `node`;
 * each one's own codes from `ids` in turn, then its transition record's, words at
 * base[p] + 3 on, base SL_OCTREE_NONE for none) lie within `id_count` and `word_count`,
 * the records in position order without overlap (as the writer lays them out), and counts the new ones (the zero codes) into *crossings: the prefix of the crossing
 * table they use. 1 when they run past. (sl_lod_raw_build decodes them.) */
int sl_lod_order_count_new(const uint8_t *node, uint32_t nodes, const uint32_t *ids,
                           uint64_t id_count, const uint32_t *base, const uint32_t *words,
                           uint64_t word_count, uint64_t *crossings);

/* The model (level order, checked, derived for cutting when cuts_only) from raw; on
 * failure `out` holds nothing. */
int sl_lod_raw_build(const sl_lod_raw *raw, int cuts_only, const char *name, sl_lod_model *out,
                     sl_error *err);

/* The octree section's bytes in format 5 (its nodes SL_LOD_ORDER_NODE bytes each): where
 * the LOD header starts. */
static inline uint64_t sl_lod_order_octree_size(const sl_octree_layout *layout, uint32_t nodes)
{
    return layout->total - layout->nodes + (uint64_t)SL_LOD_ORDER_NODE * nodes;
}

/* Where each section lies in the plain body (byte offsets and sizes), from the octree
 * header and the LOD header. */
enum {
    SL_SEC_OCTREE_HEADER, SL_SEC_NODES, SL_SEC_IDS, SL_SEC_POSITIONS, SL_SEC_COLORS,
    SL_SEC_VERTEX_FIRST, SL_SEC_VERTICES, SL_SEC_VERTEX_COLORS, SL_SEC_LOD_HEADER,
    SL_SEC_LOD_ARRAY, SL_SEC_ACCUMULATION, SL_SEC_ERROR_AFTER, SL_SEC_SURFACE,
    SL_SEC_TRANSITION_BASE, SL_SEC_TRANSITION_WORDS, SL_SEC_COUNT
};
typedef struct sl_lod_sections {
    uint64_t at[SL_SEC_COUNT], size[SL_SEC_COUNT];
    uint32_t expansions, nodes;
    uint64_t links, words;
    float bounds[6]; /* min[3], max[3] */
    int32_t root[3];
} sl_lod_sections;
/* The octree header's layout must be format 5's (LOD order, no node metrics); the LOD
 * header (SL_LOD_ORDER_HEADER bytes at the octree section's end) must agree with it and
 * the sections must fill plain_size exactly. */
int sl_lod_order_sections(const sl_octree *head, const sl_octree_layout *layout,
                          const unsigned char *lod_header, uint64_t plain_size,
                          const char *name, sl_lod_sections *out, sl_error *err);

/* Parses a whole plain body of format 5 into `out` (sl_lod_raw_build). */
int sl_lod_order_parse(const unsigned char *plain, uint64_t size, int cuts_only,
                       const char *name, sl_lod_model *out, sl_error *err);

#endif
