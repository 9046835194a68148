/* System-call layer for everything that must be durable, with fault injection; and the
 * one open of files read whole (sl_io_open_regular).
 *
 * Tests set SCANLOD_FAULT="OP:N[:ERRNO]" (OP one of write, fsync, rename, unlink, mkdir,
 * open, any; ERRNO a name like ENOSPC or EIO, or "crash" or "halt") to make the N-th call
 * of that kind fail with ERRNO, or `_exit(99)` for "crash" -- SQLite's test6.c idea:
 * sweep N over every durability point and check that resume recovers. Counting is per
 * process. "halt" is "crash" for the whole run, as on a power cut: in a per-item child
 * it SIGKILLs the engine before exiting (a child's "crash" alone is a stage crash, which
 * the engine retries and then quarantines as a bug). "stop" freezes the process with
 * SIGSTOP right before the call, which goes ahead once it gets SIGCONT: an owner frozen
 * at that exact point (tests/faults/test_frozen_owner.sh).
 *
 * SCANLOD_FAULT_COUNT=FILE (with or without a fault) appends one line per durable call
 * to FILE: "PID parent|child:K OP N ANY[ FAULT]" (the engine, or the K-th per-item child
 * it forked), N counting that OP and ANY every durable call of the process (the index
 * `any:N` addresses); FAULT (the errno's name, "crash" or "halt") marks the one call that
 * was failed. A sweep first counts the points of a clean run,
 * then checks that each injected run failed the call it aimed at
 * (tests/crash/test_fault_points.sh, tests/faults/test_lost_races.sh).
 */
#ifndef SCANLOD_CORE_IO_H
#define SCANLOD_CORE_IO_H

#include <stddef.h>
#include <sys/stat.h>
#include <sys/types.h>

#include "core/error.h"

int sl_io_open(const char *path, int flags, mode_t mode);
ssize_t sl_io_write(int fd, const void *buf, size_t n); /* writes all or fails */
int sl_io_fsync(int fd);
int sl_io_rename(const char *from, const char *to);
int sl_io_unlink(const char *path);
int sl_io_mkdir(const char *path, mode_t mode);

/* Opens a file to read it whole (a scan, an artifact, a model): O_RDONLY | O_NONBLOCK,
 * then fstat, then anything but a regular file is refused before a byte is read, so a
 * FIFO can neither block the open nor the reads, and a directory or device gets its own
 * message: SL_E_BADINPUT "is a directory" / "is a FIFO, not a regular file" / ... .
 * A failed open records the errno's own words ("No such file or directory"), its code
 * from sl_error_code_of_errno (a command reading the user's file maps it with
 * sl_error_input_exit_code). O_NONBLOCK is cleared again before returning.
 * Returns the descriptor (O_CLOEXEC; caller closes), or a negative SL_E_* code. `st`
 * (may be NULL) receives the fstat. Not fault-injected: the fault sweeps count the
 * durable operations, and read-only opens are none. */
int sl_io_open_regular(const char *path, struct stat *st, sl_error *err);

/* Maps the regular file `path` read-only and privately (through sl_io_open_regular, so a
 * FIFO or directory is refused first): *map is NULL for an empty file, *size its size.
 * Files of at most `populate_max` bytes are prefaulted in one call (MAP_POPULATE: cheaper
 * than a fault per 64 KiB); larger ones stream through readahead instead of being pinned
 * whole. The mapping outlives the descriptor; release it with sl_io_unmap. A file that
 * shrinks while mapped raises SIGBUS: inputs are not expected to change under a run. */
int sl_io_map(const char *path, size_t populate_max, void **map, size_t *size, sl_error *err);
void sl_io_unmap(void *map, size_t size);

/* Reads SCANLOD_FAULT once; called by the engine at start, before its first fork (also
 * lazily). SCANLOD_FAULT_SCOPE = all (default) | parent | child | child:K picks the
 * processes that inject: the engine's own process, each per-item stage process, or only
 * the K-th of them in the order the engine forked them (from 1). */
void sl_io_fault_init(void);
/* Nonzero when this process injects a fault or counts the calls: copies then take the
 * write path (no reflink or copy_file_range), so every byte written is a call the fault
 * can hit, and a counting run has the points of the injected runs. */
int sl_io_faults_armed(void);
/* Called first thing in a per-item child: restarts the counts for this process. */
void sl_io_fault_enter_child(void);

#endif
