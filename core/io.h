/* System-call layer for everything that must be durable, with fault injection.
 *
 * Tests set SCANLOD_FAULT="OP:N[:ERRNO]" (OP one of write, fsync, rename, unlink, mkdir,
 * open, any; ERRNO a name like ENOSPC or EIO, or "crash") to make the N-th call of that
 * kind fail with ERRNO, or `_exit(99)` for "crash" -- SQLite's test6.c idea: sweep N
 * over every durability point and check that resume recovers. Counting is per process.
 */
#ifndef SCANLOD_CORE_IO_H
#define SCANLOD_CORE_IO_H

#include <stddef.h>
#include <sys/types.h>

int sl_io_open(const char *path, int flags, mode_t mode);
ssize_t sl_io_write(int fd, const void *buf, size_t n); /* writes all or fails */
int sl_io_fsync(int fd);
int sl_io_rename(const char *from, const char *to);
int sl_io_unlink(const char *path);
int sl_io_mkdir(const char *path, mode_t mode);

/* Reads SCANLOD_FAULT once; called by the engine at start (also lazily).
 * SCANLOD_FAULT_SCOPE = all (default) | parent | child picks the processes that inject:
 * the engine's own process, or each per-item stage process. */
void sl_io_fault_init(void);
/* Nonzero when this process injects a fault: copies then take the write path (no reflink
 * or copy_file_range), so every byte written is a call the fault can hit. */
int sl_io_faults_armed(void);
/* Called first thing in a per-item child: restarts the counts for this process. */
void sl_io_fault_enter_child(void);

#endif
