/* extern "C" shim around OpenVDB (C++): the signed samples of the samples stage as sparse
 * OpenVDB grids in a `.vdb` file, read back by the merge stage.
 *
 * File (docs/samples-stage.md, docs/formats.md): a standard OpenVDB file (format 224,
 * readable by any OpenVDB tool) holding
 *   - FloatGrid "distance": one active voxel per sample, value = signed distance in world
 *     units (> 0 outside, < 0 inside); background 0, inactive voxels carry no meaning;
 *   - Int32Grid "color" (only when the samples have colours): the same active voxels,
 *     value = RGBA packed little-endian (R in bits 0-7 ... A in bits 24-31);
 *   - both with the transform index -> world: world = origin + leaf_size * index (the
 *     grid's voxel size is the leaf size), so a sample's index coordinate is its grid
 *     vertex and index (0,0,0) sits at `origin`;
 *   - file metadata "scanlod_samples_version" (int32) = SL_VDB_SAMPLES_VERSION.
 * No grid statistics metadata and no timestamps are written. OpenVDB's header carries a
 * random 36-character UUID; the writer replaces it by the XXH3-128 of the whole file
 * (with those 36 bytes set to '0') spelled as a UUID, so the same samples give the same
 * bytes and the reader can verify the content before OpenVDB parses it (a corrupt file
 * is refused with SL_E_CORRUPT instead of reaching OpenVDB's unchecked decoders).
 *
 * Threads: OpenVDB runs on TBB. sl_vdb_set_threads() caps TBB's parallelism for the
 * whole process (docs/threads.md): call it with the OpenMP thread count so the two pools
 * do not oversubscribe the cores. Every entry point may be called from any thread, but
 * not from inside an OpenMP parallel region.
 *
 * Errors: every entry point catches every C++ exception and returns it as an sl_error
 * naming the file (SL_E_NOMEM for std::bad_alloc).
 */
#ifndef SCANLOD_SHIM_VDB_SHIM_H
#define SCANLOD_SHIM_VDB_SHIM_H

#include <stdint.h>

#include "core/error.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SL_VDB_SAMPLES_VERSION 1

/* Signed samples at grid vertices (index space), one per vertex. */
typedef struct sl_vdb_samples {
    uint64_t count;
    int32_t *coords;   /* 3 * count grid-vertex coordinates (index space), sorted by
                          (x, y, z) lexicographically, no duplicates */
    float *distance;   /* count signed distances in world units: > 0 outside, < 0 inside */
    uint8_t *colors;   /* 4 * count RGBA, or NULL */
    double leaf_size; /* the leaf cubes' edge, world units; > 0 */
    double origin[3];  /* world position of index (0,0,0) */
} sl_vdb_samples;

/* Caps TBB (OpenVDB's thread pool) at `n` threads for the whole process; n <= 0 removes
 * the cap. Holds one tbb::global_control; thread-safe. */
void sl_vdb_set_threads(int n);

/* Writes `s` to `path` atomically (temp name in the same directory, fsync, rename, fsync
 * of the directory; through core/atomicfile.h). Same samples give identical bytes.
 * Refuses (SL_E_INTERNAL) coordinates that are not strictly increasing, a voxel size that
 * is not finite and positive, or non-finite distances/origin. */
int sl_vdb_samples_write(const char *path, const sl_vdb_samples *s, sl_error *err);

/* Reads samples written by sl_vdb_samples_write. Verifies the content hash in the header
 * (SL_E_CORRUPT on a mismatch or on anything that is not such a file), the grid names and
 * types, the version metadata, a uniform linear transform and that both grids have the
 * same active voxels; refuses files with more than `max_count` samples (SL_E_LIMIT).
 * OUT: *out with malloc'd arrays sorted by (x, y, z); release with
 * sl_vdb_samples_release. On failure *out is empty. */
int sl_vdb_samples_read(const char *path, uint64_t max_count, sl_vdb_samples *out,
                        sl_error *err);

/* Frees the arrays (also those a C caller malloc'd) and zeroes *s; NULL is fine. */
void sl_vdb_samples_release(sl_vdb_samples *s);

#ifdef __cplusplus
}
#endif
#endif
