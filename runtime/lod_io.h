/* The LOD model file, `.slod` (docs/formats.md): artifact envelope "SLODMODL" whose plain
 * body is the octree section (octree_io.h) followed by the LOD section:
 *
 *   u32 expansion_count, u32 node_count, u64 neighbour_count, u64 transition_words
 *   lod_array      expansion_count x u32
 *   accumulation   (expansion_count + 1) x u64
 *   error_after    (expansion_count + 1) x f32
 *   neighbours     node_count x u32 mask, node_count x u32 base, neighbour_count x u32
 *                  (format 2 only: formats 3 and 4 rebuild the table from the octree on reading
 *                  and check its count against the header's)
 *   transitions    node_count x u32 base, transition_words x u32
 *
 * Format 3 stores the plain body in packed parts (lod_pack.h: zstd frames of filtered
 * pieces); format 2 stored it as it is, and is still read.
 *
 * Reading validates every index (the LOD array is a valid expansion order: each entry an
 * internal node whose parent was expanded before it, each node at most once).
 */
#ifndef SCANLOD_RUNTIME_LOD_IO_H
#define SCANLOD_RUNTIME_LOD_IO_H

#include "core/error.h"
#include "runtime/lod_model.h"

#define SL_LOD_MAGIC "SLODMODL"
/* 2: the octree section of format 2 (optional dual vertices). 3: the body in packed parts
 * (lod_pack.h), without the neighbour table. 4: the octree without the per-node errors
 * and areas (a flag in its header; read from 3 and 4 alike). 5: every section in LOD
 * order, in checked pieces of 1 MiB, with the bounds and surface counts stored
 * (lod_order.h), so a cut reads a prefix (lod_prefix.h). */
/* The LOD model's file name in a stage's artifacts and an item's publication. */
#define SL_MODEL_FILE "model.slod"

#define SL_LOD_FORMAT_VERSION 5u
#define SL_LOD_OLDEST_VERSION 2u

int sl_lod_model_write(const char *path, const sl_lod_model *m, uint32_t stage_version,
                       sl_error *err);
/* Loads and validates; derives what generation needs (sl_lod_model_prepare). */
int sl_lod_model_read(const char *path, sl_lod_model *out, sl_error *err);
/* The same for a reader that only cuts levels (the export stage, `scanlod extract`, the
 * C API): the neighbour table goes once the cells are laid out (its count stays), and
 * the file's bytes and the unpacked body are freed as soon as they are parsed, so the
 * model takes about half the memory (docs/benchmarks.md). Every check is the same, and
 * so is every cut. */
int sl_lod_model_open(const char *path, sl_lod_model *out, sl_error *err);
/* The same from a body already out of its envelope (what sl_artifact_read returns; the
 * fuzz target feeds bodies here, past the checksum): packed (formats 3 and 4) or plain (format 2).
 * `name` is used in messages. On failure `out` holds nothing. */
int sl_lod_model_parse(const void *body, uint64_t size, const char *name, sl_lod_model *out,
                       sl_error *err);

/* SL_E_CORRUPT "invalid LOD model: WHAT" naming `path`: every model reader's refusal. */
int sl_lod_corrupt(sl_error *err, const char *path, const char *what);

#endif
