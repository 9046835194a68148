/* The LOD model file, `.slod` (docs/formats.md): artifact envelope "SLODMODL" whose body is
 * the octree section (octree_io.h) followed by the LOD section:
 *
 *   u32 expansion_count, u32 node_count, u64 neighbour_count, u64 transition_words
 *   lod_array      expansion_count x u32
 *   accumulation   (expansion_count + 1) x u64
 *   error_after    (expansion_count + 1) x f32
 *   neighbours     node_count x u32 mask, node_count x u32 base, neighbour_count x u32
 *   transitions    node_count x u32 base, transition_words x u32
 *
 * Reading validates every index (the LOD array is a valid expansion order: each entry an
 * internal node whose parent was expanded before it, each node at most once).
 */
#ifndef SCANLOD_RUNTIME_LOD_IO_H
#define SCANLOD_RUNTIME_LOD_IO_H

#include "core/error.h"
#include "runtime/lod_model.h"

#define SL_LOD_MAGIC "SLODMODL"
/* 2: the octree section of format 2 (optional dual vertices). */
#define SL_LOD_FORMAT_VERSION 2u

int sl_lod_model_write(const char *path, const sl_lod_model *m, uint32_t stage_version,
                       sl_error *err);
/* Loads and validates; derives what generation needs (sl_lod_model_prepare). */
int sl_lod_model_read(const char *path, sl_lod_model *out, sl_error *err);
/* The same from a body already out of its envelope (what sl_artifact_read returns; the
 * fuzz target feeds bodies here, past the checksum). `name` is used in messages. On
 * failure `out` holds nothing. */
int sl_lod_model_parse(const void *body, uint64_t size, const char *name, sl_lod_model *out,
                       sl_error *err);

#endif
