/* Content hashes (XXH3-128) for inputs, outputs and stage keys, and the input-hash cache
 * keyed by (device, inode, size, mtime, ctime) so `touch` or a copy costs a re-hash but
 * never a recompute (docs/engine.md, "Keys and commit records"). */
#ifndef SCANLOD_CORE_HASH_H
#define SCANLOD_CORE_HASH_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

typedef struct sl_hash {
    uint64_t hi, lo;
} sl_hash;

#define SL_HASH_HEX_SIZE 33 /* 32 hex digits + NUL */

void sl_hash_hex(sl_hash h, char out[SL_HASH_HEX_SIZE]);
int sl_hash_parse(const char *hex, sl_hash *out); /* 0 ok, -1 malformed */
int sl_hash_equal(sl_hash a, sl_hash b);
sl_hash sl_hash_bytes(const void *data, size_t size);

/* Streams the file through XXH3-128; *size gets its byte count (may be NULL). */
int sl_hash_file(const char *path, sl_hash *out, uint64_t *size, sl_error *err);

/* A file's identity as the caches compare it: "dev ino size mtime_ns ctime_ns" (any
 * write through the file system changes the ctime; a rename in changes the inode).
 * `size` >= SL_STAT_IDENTITY_SIZE. */
#define SL_STAT_IDENTITY_SIZE 128
struct stat;
void sl_stat_identity(const struct stat *st, char *buf, size_t size);

/* Same, but trusts `cache_path` when it records the file's current identity
 * (dev, ino, size, mtime_ns, ctime_ns); otherwise hashes and rewrites the cache. */
int sl_hash_file_cached(const char *path, const char *cache_path, sl_hash *out,
                        sl_error *err);

#endif
