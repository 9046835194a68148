/* Packed parts: how a model of format 3 or 4 stores its plain body (docs/formats.md,
 * "model.slod").
 * The plain body is cut into pieces of at most SL_PACK_PIECE bytes, each stored as one zstd
 * frame of its bytes after an optional reversible filter (byte planes of fixed-size
 * records, or per-column differences of u32 words then byte planes), whichever is smallest.
 *
 *   u32 magic "SLPK", u32 piece count P
 *   P x 24 bytes: u64 plain size, u64 stored size, u8 codec (0 copy, 1 zstd),
 *                 u8 filter (0 none, 1 planes, 2 differences + planes), u16 record bytes,
 *                 u32 0
 *   the stored pieces, in order, filling the rest exactly
 *
 * Unpacking checks the table against the bytes present, every piece's frame against its
 * declared sizes (one frame, exactly the stored size, declaring exactly the plain size) and
 * the plain total against a limit before it allocates, so a hostile or damaged file gives
 * one error, never an allocation the file's size does not justify. Packing is
 * deterministic on any thread count (fixed level, single-threaded frames; OpenMP runs
 * pieces side by side). */
#ifndef SCANLOD_RUNTIME_LOD_PACK_H
#define SCANLOD_RUNTIME_LOD_PACK_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

#define SL_PACK_MAGIC 0x4b504c53u /* "SLPK" little-endian */
#define SL_PACK_PIECE ((size_t)8 << 20)
/* zstd's level for the stored pieces: 6 rather than 9 since level 9 cost the crack stage
 * 18 % of its time and 40-260 MB of its peak (1 and 5 M triangles) for a model 1.1-1.4 %
 * smaller (docs/benchmarks.md section 7). */
#define SL_PACK_LEVEL 6
#define SL_PACK_TABLE_ENTRY 24
/* The largest plain/stored ratio a zstd frame reaches (an RLE block: 3 + 1 bytes for 128
 * KiB), plus a frame's fixed bytes: a piece declaring more is refused unread. */
#define SL_PACK_MAX_RATIO 32768u

/* One part of the plain body and the size of its records (the filters' unit: 4 for u32
 * and f32 arrays, 12 for xyz positions, 32 for octree nodes; 0 for none). */
typedef struct sl_pack_part {
    const void *data;
    size_t size;
    uint16_t record;
} sl_pack_part;

/* Packs the concatenation of `parts` into one malloc'd buffer (*out, *out_size).
 * Returns 0, or -1 when out of memory or a compression fails. */
int sl_pack(const sl_pack_part *parts, int part_count, void **out, size_t *out_size);

/* Whether a body starts with the packed magic. */
int sl_pack_is_packed(const void *body, uint64_t size);

/* Unpacks into a malloc'd plain body of at most `limit` bytes. SL_E_CORRUPT naming `name`
 * on any inconsistency, SL_E_NOMEM when out of memory. */
int sl_unpack(const void *body, uint64_t size, uint64_t limit, const char *name, void **plain,
              uint64_t *plain_size, sl_error *err);

#endif
