/* Folders: the one way scanlod lists a folder and the one way it removes a tree (the
 * queues, the input scan, garbage collection, verification and publication all use
 * these, so "which entries count" and "what removal may touch" are decided once).
 */
#ifndef SCANLOD_CORE_DIRS_H
#define SCANLOD_CORE_DIRS_H

#include <stddef.h>

#include "core/error.h"

enum sl_dir_flags {
    SL_DIR_ALL = 0,         /* every entry but "." and ".." */
    SL_DIR_NO_HIDDEN = 1,   /* also leave out names starting with '.' (temps, silly-renames) */
};

/* The names in folder `path`, sorted by strcmp (the same order on every host and run), in
 * one malloc'd block: free(*names) once. A folder that cannot be read is an error
 * (sl_error_errno: ENOENT included; callers that allow a missing folder test for it). */
int sl_dir_list(const char *path, int flags, char ***names, size_t *count, sl_error *err);

/* Removes `path` and everything below it without following links (a link is removed,
 * not its target); `keep_root` empties the folder but keeps it. A missing path is not an
 * error. Returns 0 or the first failure (the rest is still attempted). */
int sl_remove_tree(const char *path, int keep_root, sl_error *err);

#endif
