/* Commit records: an artifact is trusted only through its record, written last
 * (docs/engine.md, "Keys and commit records"). The record names the stage, its version, the item, the stage
 * key (hash of stage name + version + config-section hash + upstream digest) and every
 * output file with its size and XXH3-128 hash; `outputs_digest` (hash of those lines) is
 * what the next stage's key chains on, so identical outputs never trigger downstream work.
 *
 * Nothing run-specific (epoch, host, time) is in a record: a retried or duplicated run
 * writes the same bytes. Text format (docs/formats.md): "k=v" lines, "output=NAME SIZE HASH" per file, "end".
 */
#ifndef SCANLOD_PIPELINE_RECORD_H
#define SCANLOD_PIPELINE_RECORD_H

#include <limits.h>
#include <stdint.h>

#include "core/error.h"
#include "core/hash.h"

#define SL_RECORD_FILE "record"
#define SL_RECORD_MAX_OUTPUTS 64

typedef struct sl_record_output {
    char name[128];
    uint64_t size;
    sl_hash hash;
} sl_record_output;

typedef struct sl_record {
    char stage[32];
    uint32_t stage_version;
    char item[PATH_MAX]; /* escaped in the file (core/escape.h) */
    sl_hash key;
    sl_hash outputs_digest;
    int output_count;
    sl_record_output outputs[SL_RECORD_MAX_OUTPUTS];
} sl_record;

/* The stage key (docs/engine.md, "Keys and commit records"). */
sl_hash sl_stage_key(const char *stage, uint32_t stage_version, uint64_t config_hash,
                     sl_hash upstream);

/* Hashes `names` (NULL: every file in `dir` not starting with '.' or '_' and not the
 * record) in `dir` and writes the record at `record_path` durably. `out` may be NULL. */
int sl_record_commit(const char *record_path, const char *dir, const char *const *names,
                     const char *stage, uint32_t stage_version, const char *item, sl_hash key,
                     sl_record *out, sl_error *err);

/* Parses a record without checking its outputs (cheap; for keys already verified). */
int sl_record_read(const char *record_path, sl_record *out, sl_error *err);

/* 0 when the record parses, has `key` (unless key == NULL) and every listed output exists
 * in `dir` with the recorded size and hash; otherwise SL_E_CORRUPT with the reason. Reads
 * every byte of every output: `scanlod verify`. */
int sl_record_verify(const char *record_path, const char *dir, const sl_hash *key,
                     sl_record *out, sl_error *err);

/* The same answer without reading the outputs again when nothing changed since the last
 * full verification: a `_verified` file beside the record holds the identity (dev, inode,
 * size, mtime, ctime: sl_stat_identity) of the record and of each output as they were
 * when their hashes last matched; while every identity is still the same, the hashes are
 * trusted (docs/engine.md, "Keys and commit records": content hashes cached against the stat identity).
 * Anything else is verified in full, and the cache rewritten. For the scan and the stage
 * runner, which ask every night of every artifact; a corruption that keeps a file's
 * identity (bit rot under the file system) is `scanlod verify`'s to find. */
int sl_record_check(const char *record_path, const char *dir, const sl_hash *key,
                    sl_record *out, sl_error *err);

#endif
