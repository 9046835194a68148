/* Where things live: the run's folders and their rules, and the layout of the work folder
 * (docs/engine.md, "Work directory" and "The trees of a run").
 *
 * The four trees a run touches ([run] input, work, output, logs) must each be a folder
 * of its own, none inside another. An output inside the input would be scanned as new
 * items by the next run (and the next, each adding one more level: in/out/out/out/...);
 * a work folder inside the input likewise; an input inside the output would be swapped
 * away by a publication. The check runs before any work and names the option and where it
 * was set (FILE:LINE), so a mistake costs one line and exit 78, not a night.
 */
#include "pipeline/engine_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/dirs.h"
#include "core/io.h"

int sl_engine_path(char *buf, size_t size, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf, size, fmt, ap);
    va_end(ap);
    return n < 0 || (size_t)n >= size ? -1 : 0;
}

int sl_artifact_dir(const sl_engine *e, int stage, const char *ticket, char *buf, size_t size)
{
    return sl_engine_path(buf, size, "%s/artifacts/%s/%s", e->work, e->stages[stage]->name,
                          ticket);
}

int sl_engine_item_published(const sl_engine *e, const char *item)
{
    char ticket[SL_TICKET_NAME_MAX + 1], record[PATH_MAX];
    sl_error err;
    sl_error_init(&err);
    return sl_ticket_name(item, ticket, sizeof ticket, &err) == 0 &&
           sl_engine_path(record, sizeof record, "%s/artifacts/_publish/%s/%s", e->work, ticket,
                          SL_RECORD_FILE) == 0 &&
           access(record, F_OK) == 0;
}

int sl_engine_swap_in(const char *staged, const char *final_dir, const char *parent, sl_error *err)
{
    if (sl_io_rename(staged, final_dir) == 0)
        return sl_fsync_dir(parent, err);
    if (errno != EEXIST && errno != ENOTEMPTY)
        return sl_error_errno(err, errno, final_dir, "rename");
    if (renameat2(AT_FDCWD, staged, AT_FDCWD, final_dir, RENAME_EXCHANGE) != 0)
        return sl_error_errno(err, errno, final_dir, "rename (exchange)");
    int rc = sl_fsync_dir(parent, err);
    sl_error ignored;
    sl_error_init(&ignored);
    sl_remove_tree(staged, 0, &ignored); /* now the previous publication */
    return rc;
}

int sl_remove_dir_contents(const char *dir, sl_error *err)
{
    /* The record goes first: without it nothing left here is trusted. */
    char path[PATH_MAX];
    if (sl_engine_path(path, sizeof path, "%s/%s", dir, SL_RECORD_FILE) == 0 &&
        sl_io_unlink(path) != 0 && errno != ENOENT)
        return sl_error_errno(err, errno, path, "unlink");
    int rc = sl_remove_tree(dir, 1, err);
    return rc ? rc : sl_fsync_dir(dir, err);
}

int sl_engine_make_work_layout(sl_engine *e, sl_error *err)
{
    char path[PATH_MAX];
    int rc = sl_mkdirs(e->work, err);
    for (int s = 0; rc == 0 && s < e->stage_count; s++) {
        rc = sl_queue_create(e->work, e->stages[s]->name, err);
        if (rc == 0 && sl_engine_path(path, sizeof path, "%s/artifacts/%s", e->work,
                                      e->stages[s]->name) == 0)
            rc = sl_mkdirs(path, err);
    }
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/artifacts/_publish", e->work) == 0)
        rc = sl_mkdirs(path, err);
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/cache/input", e->work) == 0)
        rc = sl_mkdirs(path, err);
    if (rc == 0)
        rc = sl_mkdirs(e->output, err);
    return rc;
}

/* `path` with every existing leading part resolved through symlinks (realpath), the
 * rest appended as it is: a folder that does not exist yet is compared where it will be. */
static void resolve_existing(const char *path, char *out, size_t size)
{
    char head[PATH_MAX];
    snprintf(head, sizeof head, "%s", path);
    size_t n = strlen(head);
    while (n > 1) {
        char real[PATH_MAX];
        if (realpath(head, real)) {
            snprintf(out, size, "%s%s", strcmp(real, "/") ? real : "", path + n);
            return;
        }
        char *slash = strrchr(head, '/');
        if (!slash || slash == head)
            break;
        *slash = '\0';
        n = (size_t)(slash - head);
    }
    snprintf(out, size, "%s", path);
}

/* Is `inner` the folder `outer` or inside it? Whole path components only. */
static int inside(const char *inner, const char *outer)
{
    size_t n = strlen(outer);
    return strncmp(inner, outer, n) == 0 && (inner[n] == '\0' || inner[n] == '/');
}

int sl_engine_check_trees(sl_engine *e, sl_error *err)
{
    static const char *const keys[] = {"input", "work", "output", "logs"};
    const char *paths[] = {e->input, e->work, e->output, e->logs};
    char real[4][PATH_MAX];
    for (int i = 0; i < 4; i++)
        resolve_existing(paths[i], real[i], sizeof real[i]);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            if (i == j || !inside(real[i], real[j]) || (strcmp(real[i], real[j]) == 0 && i > j))
                continue;
            char where[PATH_MAX];
            sl_config_where(e->cfg, "run", keys[i], where, sizeof where);
            return sl_error_set(err, SL_E_CONFIG, 0, where,
                                "[run] %s (%s) %s [run] %s (%s): the four folders of a run "
                                "(input, work, output, logs) must not contain one another",
                                keys[i], real[i], strcmp(real[i], real[j]) ? "is inside" : "is",
                                keys[j], real[j]);
        }
    return 0;
}

int sl_engine_check_input(sl_engine *e, sl_error *err)
{
    struct stat st;
    if (stat(e->input, &st) == 0 && S_ISDIR(st.st_mode))
        return 0;
    int saved = errno;
    char where[PATH_MAX];
    sl_config_where(e->cfg, "run", "input", where, sizeof where);
    return sl_error_set(err, SL_E_CONFIG, saved, where, "[run] input %s: %s", e->input,
                        stat(e->input, &st) == 0 ? "not a folder" : strerror(saved));
}

/* Creates and removes one empty file in `dir`: a read-only or foreign folder is found
 * before the first item runs, not after all its stages. Its name has the atomic writer's
 * form (.NAME.HOST.PID.N.tmp), so a crash between the two leaves a temp that the next
 * run's gc removes (engine_gc.c). */
static int probe_writable(const sl_engine *e, const char *key, const char *dir, sl_error *err)
{
    char path[PATH_MAX];
    if (sl_engine_path(path, sizeof path, "%s/.scanlod-probe.%s.%ld.0.tmp", dir, e->self.host,
                       e->self.pid))
        return sl_error_set(err, SL_E_STORAGE, ENAMETOOLONG, dir, "path too long");
    int fd = sl_io_open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) {
        char what[64];
        snprintf(what, sizeof what, "[run] %s: creating a file", key);
        sl_error probe;
        sl_error_init(&probe);
        int rc = sl_error_errno(&probe, errno, dir, what);
        if (sl_error_class_of(rc) != SL_CLASS_STORAGE)
            return 0; /* a full disk may clear up; the items will say so */
        sl_error_merge(err, &probe);
        return rc;
    }
    close(fd);
    sl_io_unlink(path);
    return 0;
}

int sl_engine_check_writable(sl_engine *e, sl_error *err)
{
    int rc = probe_writable(e, "work", e->work, err);
    if (rc == 0)
        rc = probe_writable(e, "output", e->output, err);
    return rc;
}

/* The private folder a claim's stage process writes into: a hidden sibling of the
 * artifact folder named after its writer (`.TICKET.stage.HOST.PID`, which gc removes once
 * that pid is gone), swapped in by commit_success. */
int sl_engine_staged_path(const sl_engine *e, const char *out_dir, char *buf, sl_error *err)
{
    const char *slash = strrchr(out_dir, '/');
    int dir_len = slash ? (int)(slash - out_dir) : 0;
    const char *base = slash ? slash + 1 : out_dir;
    if (sl_engine_path(buf, PATH_MAX, "%.*s/.%.100s.stage.%s.%ld", dir_len, out_dir, base,
                       e->self.host, e->self.pid))
        return sl_error_set(err, SL_E_LIMIT, 0, out_dir, "path too long");
    return 0;
}
