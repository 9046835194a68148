/* The one durable-write helper (after git's tempfile.c/lockfile.c).
 *
 * A file becomes visible under its final name only complete and durable:
 *   temp `.<name>.<host>.<pid>.<n>.tmp` in the destination directory (O_CREAT|O_EXCL)
 *   -> write -> fsync(file) -> close -> rename -> fsync(directory).
 * A failed fsync fails the write (the temp is removed; never retried and trusted).
 * Live temps are registered so sl_atomic_cleanup_all() (called at exit and from the
 * signal path) removes them; a kill -9 leaves at most a `.tmp` that resume ignores and
 * the engine's garbage collection removes.
 *
 * Every system call goes through core/io.h so tests can inject faults.
 * Thread safety: one sl_atomic_file per thread; the registry is locked.
 */
#ifndef SCANLOD_CORE_ATOMICFILE_H
#define SCANLOD_CORE_ATOMICFILE_H

#include <limits.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

typedef struct sl_atomic_file {
    int fd;                 /* -1 when closed */
    char final_path[PATH_MAX];
    char tmp_path[PATH_MAX + 320];
    uint64_t bytes_written;
    /* buffered writes: */
    unsigned char *buf;
    size_t buf_len, buf_cap;
    int failed;             /* a write failed; commit will refuse */
} sl_atomic_file;

int sl_atomic_open(sl_atomic_file *f, const char *final_path, sl_error *err);
int sl_atomic_write(sl_atomic_file *f, const void *data, size_t size, sl_error *err);
int sl_atomic_printf(sl_atomic_file *f, sl_error *err, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* fsync, close, rename over final_path, fsync the directory. On failure the temp is gone
 * and final_path is untouched. */
int sl_atomic_commit(sl_atomic_file *f, sl_error *err);
/* Drops the temp (safe to call after commit or on a never-opened object). */
void sl_atomic_abort(sl_atomic_file *f);

/* Whole file in one call. */
int sl_write_file_atomic(const char *path, const void *data, size_t size, sl_error *err);

/* Removes every registered temp file; async-signal-safe enough for the exit path
 * (unlink only). */
void sl_atomic_cleanup_all(void);

/* fsync a directory (after mkdir/rename/unlink in it). */
int sl_fsync_dir(const char *dir, sl_error *err);
/* mkdir -p with an fsync of each parent that gained an entry. */
int sl_mkdirs(const char *path, sl_error *err);

/* Copies `from` to `to` durably (as sl_write_file_atomic does), as a reflink where the
 * filesystem can share extents, else byte by byte in bounded memory. `to` is a file of
 * its own: changing one never changes the other (publication uses this). */
int sl_copy_file(const char *from, const char *to, sl_error *err);
/* Hard-links `from` as `to` (replacing it), or copies it (sl_copy_file) when linking fails
 * (another filesystem). For immutable artifacts inside the work folder only. */
int sl_link_or_copy(const char *from, const char *to, sl_error *err);

/* Reads a whole file (capped at max_size bytes; SL_E_LIMIT beyond). *data is malloc'd,
 * NUL-terminated for convenience; *size excludes the NUL. */
int sl_read_file(const char *path, uint64_t max_size, char **data, size_t *size, sl_error *err);

#endif
