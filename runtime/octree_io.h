/* The octree's on-disk form (docs/formats.md, "octree section"): shared by the merge
 * stage's `octree.slot` and the LOD model `.slod`, inside the artifact envelope.
 *
 *   header  (272 bytes, little-endian: depth, counts, leaf size, origin, level ranges, stats)
 *   nodes   node_count x 32 bytes (sl_octree_node as laid out in octree.h)
 *   node crossings  node_crossing_count x u32
 *   crossing positions  crossing_count x 3 x f32
 *   crossing colours    crossing_count x 4 x u8 (only if has_color)
 *   and with dual vertices (format 2, header flag 1; octree.h):
 *   vertex_first        (node_count + 1) x u32
 *   vertex positions    vertex_count x 3 x f32
 *   vertex colours      vertex_count x 4 x u8 (only if has_color)
 *   node errors, node areas   node_count x f32 each
 *
 * Parsing checks every count against the bytes present and every index against its
 * table (parents, children, crossing ids, level ranges) before anything is trusted, so a
 * corrupt or hostile file gives an error, never an out-of-bounds read.
 */
#ifndef SCANLOD_RUNTIME_OCTREE_IO_H
#define SCANLOD_RUNTIME_OCTREE_IO_H

#include <stddef.h>
#include <stdint.h>

#include "core/artifact.h"
#include "core/error.h"
#include "runtime/octree.h"

#define SL_OCTREE_MAGIC "SLOCTREE"
/* 2: the header has a vertex count and flags; optional dual vertices (octree.h). */
#define SL_OCTREE_FORMAT_VERSION 2u
#define SL_OCTREE_PARTS 10
/* Largest |origin| and root cube edge a file may declare (world units); the root cube
 * itself must lie within twice that of zero. Coordinates any scan has (1e15 units is a
 * light-year in millimetres) keep every product generation forms finite. */
#define SL_OCTREE_MAX_EXTENT 1e15
/* Whether the octree's grid (leaf size, depth, origin, the root node's cube) is within
 * those limits: the readers refuse a file whose grid is not, so the merge stage checks it
 * before writing one. Needs the root node (nodes[0]). */
int sl_octree_grid_ok(const sl_octree *t);

/* Header flag bit 2: the nodes (and every per-node table) are in LOD order rather than
 * by level (model format 5, lod_io.h): sl_octree_parse refuses such a section, and the
 * header's level ranges mean nothing there (the reader derives them). */
#define SL_OCTREE_FLAG_LOD_ORDER 4u
#define SL_OCTREE_HEADER_SIZE 288u

/* Describes the octree as artifact parts (pointing into `t` and `header`, which must
 * outlive the write), with extra_flags (SL_OCTREE_FLAG_LOD_ORDER or 0) in the header.
 * Returns the number of parts used. */
int sl_octree_parts(const sl_octree *t, unsigned char header[512], sl_artifact_part *parts,
                    uint32_t extra_flags);

/* The section's header alone: `out` gets its scalars (no arrays), `lay` the flags and the
 * byte size of every part (`total`: the whole section). */
typedef struct sl_octree_layout {
    uint32_t flags;
    int has_color;
    uint32_t vertex_count;
    uint64_t nodes, ids, positions, colors, vertex_first, vertices, vertex_colors, metrics;
    uint64_t total;
} sl_octree_layout;
int sl_octree_parse_header(const unsigned char *body, uint64_t size, const char *name,
                           sl_octree *out, sl_octree_layout *lay, sl_error *err);
/* The edges of a cube with corner signs `inside` whose two ends differ: a node's edge
 * mask must be this. */
uint16_t sl_octree_edge_mask(uint8_t inside);
/* Every check sl_octree_parse makes on a tree in memory (levels, links, Morton order,
 * crossings, vertices), then the Morton index. */
int sl_octree_check(sl_octree *t, const char *name, sl_error *err);

/* Parses an octree section starting at `body`; *used gets its byte length. The octree
 * gets its own copies of the arrays. `name` is used in messages. */
int sl_octree_parse(const unsigned char *body, uint64_t size, const char *name, sl_octree *out,
                    uint64_t *used, sl_error *err);

int sl_octree_write(const char *path, const sl_octree *t, uint32_t stage_version, sl_error *err);
int sl_octree_read(const char *path, sl_octree *out, sl_error *err);

#endif
