/* Listing a folder and removing a tree (dirs.h). */
#include "core/dirs.h"

#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/io.h"

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int sl_dir_list(const char *path, int flags, char ***names, size_t *count, sl_error *err)
{
    *names = NULL;
    *count = 0;
    DIR *dir = opendir(path);
    if (!dir)
        return sl_error_errno(err, errno, path, "opendir");
    /* First the names into one growing text, then the pointer array over it: one block
     * the caller frees once. */
    size_t n = 0, text = 0, text_cap = 0;
    char *buf = NULL;
    struct dirent *de;
    int rc = 0;
    errno = 0;
    while ((de = readdir(dir))) {
        const char *name = de->d_name;
        if (!strcmp(name, ".") || !strcmp(name, "..") ||
            ((flags & SL_DIR_NO_HIDDEN) && name[0] == '.'))
            continue;
        size_t len = strlen(name) + 1;
        if (text + len > text_cap) {
            size_t cap = text_cap ? 2 * text_cap : 4096;
            while (cap < text + len)
                cap *= 2;
            char *grown = realloc(buf, cap);
            if (!grown) {
                rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
                break;
            }
            buf = grown;
            text_cap = cap;
        }
        memcpy(buf + text, name, len);
        text += len;
        n++;
    }
    closedir(dir);
    char **block = rc ? NULL : malloc(n * sizeof *block + text + 1);
    if (!block) {
        free(buf);
        return rc ? rc : sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    }
    char *p = (char *)(block + n);
    if (text)
        memcpy(p, buf, text);
    free(buf);
    for (size_t i = 0; i < n; i++) {
        block[i] = p;
        p += strlen(p) + 1;
    }
    if (n > 1)
        qsort(block, n, sizeof *block, compare_names);
    *names = block;
    *count = n;
    return 0;
}

int sl_remove_tree(const char *path, int keep_root, sl_error *err)
{
    struct stat st;
    if (lstat(path, &st) != 0)
        return errno == ENOENT ? 0 : sl_error_errno(err, errno, path, "lstat");
    if (!S_ISDIR(st.st_mode)) {
        if (sl_io_unlink(path) != 0 && errno != ENOENT)
            return sl_error_errno(err, errno, path, "unlink");
        return 0;
    }
    char **names;
    size_t count;
    int rc = sl_dir_list(path, SL_DIR_ALL, &names, &count, err);
    if (rc)
        return rc;
    for (size_t i = 0; i < count; i++) {
        char child[PATH_MAX];
        int n = snprintf(child, sizeof child, "%s/%s", path, names[i]);
        sl_error cerr;
        sl_error_init(&cerr);
        int crc = n < 0 || (size_t)n >= sizeof child
                      ? sl_error_set(&cerr, SL_E_STORAGE, ENAMETOOLONG, path, "path too long")
                      : sl_remove_tree(child, 0, &cerr);
        if (crc && rc == 0) {
            rc = crc;
            sl_error_merge(err, &cerr);
        }
    }
    free(names);
    if (rc == 0 && !keep_root && rmdir(path) != 0 && errno != ENOENT)
        rc = sl_error_errno(err, errno, path, "rmdir");
    return rc;
}
