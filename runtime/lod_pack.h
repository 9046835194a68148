/* Packed parts: how a model of format 3 to 5 stores its plain body (docs/formats.md,
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

#define SL_PACK_MAGIC 0x4b504c53u /* "SLPK" little-endian: model formats 3 and 4 */
/* "SLPC": model format 5, whose table holds each piece's check (the low 32 bits of the
 * XXH3-64 of its stored bytes), so a reader that takes only some pieces (lod_prefix.h)
 * checks what it reads without the envelope's checksum over the whole body. */
#define SL_PACK_MAGIC_CHECKED 0x43504c53u
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

/* The same part by part, for a writer that makes each part only when it is packed (and
 * frees it before making the next): sl_packer_add compresses the part's pieces at once
 * (OpenMP over them), so the part's bytes may go when it returns. piece_size (at most
 * SL_PACK_PIECE; 0 for that) is the plain bytes per piece; `checked` writes the pieces'
 * checks (SL_PACK_MAGIC_CHECKED). sl_packer_finish frees the packer in any case. */
typedef struct sl_packer sl_packer;
sl_packer *sl_packer_new(int checked, size_t piece_size);
int sl_packer_add(sl_packer *pk, const void *data, size_t size, uint16_t record);
int sl_packer_finish(sl_packer *pk, void **out, size_t *out_size);
void sl_packer_free(sl_packer *pk);

/* Whether a body starts with a packed magic (either). */
int sl_pack_is_packed(const void *body, uint64_t size);

/* Unpacks into a malloc'd plain body of at most `limit` bytes. SL_E_CORRUPT naming `name`
 * on any inconsistency, SL_E_NOMEM when out of memory. */
int sl_unpack(const void *body, uint64_t size, uint64_t limit, const char *name, void **plain,
              uint64_t *plain_size, sl_error *err);

/* Reading some pieces only. A packed body's table, checked against the body's size (the
 * frames themselves are checked as each piece is read): */
typedef struct sl_pack_piece_info {
    uint64_t plain_at, plain_size;   /* where its bytes go in the plain body */
    uint64_t stored_at, stored_size; /* where its stored bytes are in the packed body */
    uint32_t check;
    uint16_t record;
    uint8_t codec, filter;
} sl_pack_piece_info;

typedef struct sl_pack_index {
    uint64_t count;
    sl_pack_piece_info *pieces;
    uint64_t plain_total;
    int checked; /* SL_PACK_MAGIC_CHECKED: every piece read is checked first */
} sl_pack_index;

/* Bytes of the head and table, from the body's first 8 bytes. */
uint64_t sl_pack_table_size(const unsigned char head[8]);
/* Parses the head and table (`available` bytes of them at `table`) of a packed body of
 * body_size bytes; the same refusals as sl_unpack's, but for the frames. */
int sl_pack_index_parse(const unsigned char *table, uint64_t available, uint64_t body_size,
                        uint64_t limit, const char *name, sl_pack_index *ix, sl_error *err);
void sl_pack_index_release(sl_pack_index *ix);
/* Pieces first .. first + count - 1, whose stored bytes are stored[0 .. count), into
 * dest (the plain bytes from the first piece's plain_at on), OpenMP over pieces:
 * SL_E_CORRUPT naming the piece on a check or frame that is wrong. */
int sl_pack_pieces_read(const sl_pack_index *ix, uint64_t first, uint64_t count,
                        const unsigned char *const *stored, unsigned char *dest,
                        const char *name, sl_error *err);

#endif
