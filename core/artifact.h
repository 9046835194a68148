/* The envelope of every binary artifact (docs/formats.md).
 *
 *   offset size  field
 *   0      8     magic (e.g. "SLPOINTS")
 *   8      4     format version   (u32 LE)
 *   12     4     producing stage version (u32 LE)
 *   16     8     body size in bytes (u64 LE)
 *   24     8     XXH3-64 of the body (u64 LE)
 *   32     ...   body
 *
 * Readers refuse a wrong magic, an unknown format version, a body size that disagrees
 * with the file size, or a checksum mismatch, with an error naming the file (SL_E_CORRUPT
 * for our own artifacts: the engine then reruns the producing stage).
 */
#ifndef SCANLOD_CORE_ARTIFACT_H
#define SCANLOD_CORE_ARTIFACT_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "core/error.h"

#define SL_ARTIFACT_HEADER_SIZE 32u

typedef struct sl_artifact_part {
    const void *data;
    size_t size;
} sl_artifact_part;

/* Writes header + the concatenated parts through the atomic-write helper. */
int sl_artifact_write(const char *path, const char magic[8], uint32_t format_version,
                      uint32_t stage_version, const sl_artifact_part *parts, int part_count,
                      sl_error *err);

/* Reads and validates; *body is malloc'd (caller frees), *body_size its size.
 * `stage_version` may be NULL. Bodies above max_body_size are refused (SL_E_LIMIT). */
int sl_artifact_read(const char *path, const char magic[8], uint32_t format_version,
                     uint64_t max_body_size, void **body, uint64_t *body_size,
                     uint32_t *stage_version, sl_error *err);
/* The same for a reader of several format versions: any of oldest..newest, the file's in
 * *version. */
int sl_artifact_read_versions(const char *path, const char magic[8], uint32_t oldest,
                              uint32_t newest, uint64_t max_body_size, void **body,
                              uint64_t *body_size, uint32_t *stage_version, uint32_t *version,
                              sl_error *err);

/* What the header of an artifact says. */
typedef struct sl_artifact_info {
    uint32_t version, stage_version;
    uint64_t body_size, checksum;
} sl_artifact_info;

/* The header read and checked (magic, version oldest..newest, body size against the file),
 * the file left open in *fd after it (the caller closes it). sl_artifact_read_versions
 * reads the body on; a reader that takes only parts of it (lod_prefix.h) preads them and
 * checks what it reads by other means, since the body's checksum covers all of it. */
int sl_artifact_open(const char *path, const char magic[8], uint32_t oldest, uint32_t newest,
                     int *fd, sl_artifact_info *info, sl_error *err);
/* `size` bytes of the body from offset `at` (SL_E_IO naming `path`, or SL_E_CORRUPT when
 * the file ends first). */
int sl_artifact_pread(int fd, const char *path, void *dest, uint64_t size, uint64_t at,
                      sl_error *err);

/* A body read in order straight into the reader's own arrays, checksummed as it goes:
 * for large artifacts (the octree, the priority file) whose whole body held beside the
 * arrays parsed from it was the stage's peak (at 20 M triangles 1.6 GB twice over).
 * Counts read from the body before the checksum is known must be checked against
 * `info.body_size` before they size an allocation; nothing read is trusted until
 * sl_artifact_reader_finish has compared the checksum. */
typedef struct sl_artifact_reader {
    int fd;
    const char *path;
    sl_artifact_info info;
    uint64_t at;  /* body bytes read so far */
    void *hash;   /* XXH3 state */
} sl_artifact_reader;

/* The header checked (as sl_artifact_open); max_body_size as sl_artifact_read's. */
int sl_artifact_reader_open(sl_artifact_reader *r, const char *path, const char magic[8],
                            uint32_t oldest, uint32_t newest, uint64_t max_body_size,
                            sl_error *err);
/* The next `size` bytes of the body into dest (SL_E_CORRUPT past the body's end). */
int sl_artifact_reader_take(sl_artifact_reader *r, void *dest, uint64_t size, sl_error *err);
/* The same into a fresh malloc'd block (*dest; NULL and SL_E_NOMEM when out of memory). */
int sl_artifact_reader_take_new(sl_artifact_reader *r, void **dest, uint64_t size, sl_error *err);
/* Every byte of the body taken and its checksum right (SL_E_CORRUPT: "trailing bytes" or
 * "checksum mismatch"). */
int sl_artifact_reader_finish(sl_artifact_reader *r, sl_error *err);
/* Closes the file and frees the state (after finish, or to give up). */
void sl_artifact_reader_close(sl_artifact_reader *r);

/* Little-endian helpers for bodies (the format is LE on every host). */
static inline void sl_put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static inline void sl_put_u64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}
static inline uint32_t sl_get_u32(const unsigned char *p)
{
    uint32_t v = 0;
    for (int i = 0; i < 4; i++)
        v |= (uint32_t)p[i] << (8 * i);
    return v;
}
static inline uint64_t sl_get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 0; i < 8; i++)
        v |= (uint64_t)p[i] << (8 * i);
    return v;
}

static inline void sl_put_f64(unsigned char *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    sl_put_u64(p, u);
}
static inline double sl_get_f64(const unsigned char *p)
{
    uint64_t u = sl_get_u64(p);
    double v;
    memcpy(&v, &u, 8);
    return v;
}
static inline void sl_put_f32(unsigned char *p, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    sl_put_u32(p, u);
}
static inline float sl_get_f32(const unsigned char *p)
{
    uint32_t u = sl_get_u32(p);
    float v;
    memcpy(&v, &u, 4);
    return v;
}

#endif
