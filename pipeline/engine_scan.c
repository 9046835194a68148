/* The collection scan: walk [run] input (docs/engine.md, "The input tree") and reconcile
 * every item it finds (engine_reconcile.c).
 */
#include "pipeline/engine_internal.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/log.h"
#include "core/progress.h"

#define MAX_TREE_DEPTH 64

/* ---- input tree walk ------------------------------------------------------------- */

/* Whether `name` ends in one of the scan suffixes the program reads (and is more than it). */
static int is_scan_name(const sl_engine *e, const char *name)
{
    size_t n = strlen(name);
    for (const char *const *s = e->input_suffixes; *s; s++) {
        size_t k = strlen(*s);
        if (n > k && strcasecmp(name + n - k, *s) == 0)
            return 1;
    }
    return 0;
}

static int compare_strings(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* An entry the scan does not take: said in the log and counted, never silent. */
static void skip(sl_engine *e, const char *rel, const char *why)
{
    e->counts.skipped++;
    SL_LOG(SL_LOG_WARN, "scan", NULL, "%s: %s; skipped", rel, why);
    sl_log_event("scan_skip", "scan", rel, 0, NULL, NULL);
}

/* A scan's name that cannot be read as a scan (a dangling link, a FIFO, a device): the
 * item is quarantined at once with the reason, under a key made of that reason, so it
 * stays there until the entry changes and is listed by `status` and the summary. */
static int quarantine_unreadable(sl_engine *e, const char *item, const char *why,
                                 sl_error *err)
{
    char name[SL_TICKET_NAME_MAX + 1];
    int rc = sl_ticket_name(item, name, sizeof name, err);
    if (rc)
        return rc;
    const char *stage = e->stages[0]->name;
    sl_hash key = sl_hash_bytes(why, strlen(why));
    char key_hex[SL_HASH_HEX_SIZE], path[PATH_MAX];
    sl_hash_hex(key, key_hex);
    int state = sl_queue_find(e->work, stage, name);
    sl_ticket t;
    if (state == SL_STATE_CLAIMED ||
        (state == SL_STATE_QUARANTINE &&
         sl_queue_get(e->work, stage, state, name, &t) == 0 && strcmp(t.key, key_hex) == 0))
        return 0;
    sl_ticket_for(&t, item, item, key);
    snprintf(t.cls, sizeof t.cls, "badinput");
    snprintf(t.reason, sizeof t.reason, "%.500s: %s", item, why);
    rc = sl_queue_put(e->work, stage, SL_STATE_QUARANTINE, name, &t, err);
    if (rc == 0 && state != SL_STATE_NONE && state != SL_STATE_QUARANTINE &&
        sl_queue_path(path, sizeof path, e->work, stage, state, name) == 0)
        unlink(path);
    if (rc == 0) {
        e->counts.quarantined++;
        SL_LOG(SL_LOG_WARN, "scan", item, "quarantined: %s", why);
    }
    return rc;
}

static int scan_item(sl_engine *e, const char *rel, const char *unreadable, sl_error *err)
{
    if (e->item_fn) {
        char full[PATH_MAX];
        if (sl_engine_path(full, sizeof full, "%s/%s", e->input, rel) == 0)
            e->item_fn(e->item_ctx, rel, full, unreadable);
        return 0;
    }
    e->counts.items++;
    sl_engine_scan_mark(e, 1); /* renews the announcement on a long scan */
    if (e->item_count == e->item_capacity) {
        uint64_t cap = e->item_capacity ? 2 * e->item_capacity : 64;
        char **grown = realloc(e->items, cap * sizeof *grown);
        if (grown) {
            e->items = grown;
            e->item_capacity = cap;
        }
    }
    if (e->item_count < e->item_capacity)
        e->items[e->item_count++] = strdup(rel);
    sl_error item_err;
    sl_error_init(&item_err);
    int settled = 0;
    int rc = unreadable ? quarantine_unreadable(e, rel, unreadable, &item_err)
                        : sl_engine_reconcile(e, rel, rel, 0, &settled, &item_err);
    if (rc == 0) {
        e->items_settled += unreadable || settled; /* nothing left to do for it */
        return 0;
    }
    sl_error_context(&item_err, NULL, rel);
    char line[1400];
    SL_LOG(SL_LOG_ERROR, "scan", rel, "%s", sl_error_format(&item_err, line, sizeof line));
    sl_log_event("scan_error", "scan", rel, 0, &item_err, NULL);
    enum sl_error_class cls = sl_error_class_of(rc);
    /* An unreadable input is that item's problem; an unwritable work dir is everyone's. */
    if (cls == SL_CLASS_STORAGE && strncmp(item_err.file, e->work, strlen(e->work)) == 0) {
        sl_error_merge(err, &item_err);
        return rc;
    }
    e->counts.transient++; /* retried by the next run; the exit code says so */
    e->counts.untracked++;
    return 0; /* one bad item never stops the scan */
}

/* Why a scan-named entry that is not a directory cannot be a scan, or NULL if it can:
 * `st` is its lstat, `target` the stat of what a link points to (errno if dangling). */
static const char *unreadable_reason(const struct stat *st, const struct stat *target,
                                     int target_errno, char *buf, size_t size)
{
    if (S_ISLNK(st->st_mode) && target_errno) {
        snprintf(buf, size, "symbolic link to nothing (%s)", strerror(target_errno));
        return buf;
    }
    const struct stat *what = S_ISLNK(st->st_mode) ? target : st;
    if (S_ISREG(what->st_mode))
        return NULL;
    snprintf(buf, size, "%s, not a regular file",
             S_ISFIFO(what->st_mode) ? "a FIFO" : S_ISSOCK(what->st_mode) ? "a socket"
             : S_ISCHR(what->st_mode) || S_ISBLK(what->st_mode) ? "a device" : "not a file");
    return buf;
}

static int walk(sl_engine *e, const char *rel_dir, int depth, sl_error *err);

/* One entry of a directory: a folder is walked (never through a link: a link to a
 * folder could lead out of the tree or back into it), a file with a scan suffix
 * (sl_engine_options.input_suffixes) is an item, and anything else that looks like a scan
 * is skipped or quarantined with its reason. */
static int scan_entry(sl_engine *e, const char *rel, const char *base, int depth, sl_error *err)
{
    char full[PATH_MAX];
    if (sl_engine_path(full, sizeof full, "%s/%s", e->input, rel)) {
        skip(e, rel, "path too long");
        return 0;
    }
    struct stat st, target;
    if (lstat(full, &st) != 0)
        return 0; /* gone since the directory was read */
    if (base[0] == '.') {
        /* Hidden: never an item. Said for what could hold scans; a .DS_Store or an
         * editor's backup is noise, like any file that is not a scan. */
        if (S_ISDIR(st.st_mode) || is_scan_name(e, base))
            skip(e, rel, "hidden name");
        return 0;
    }
    int target_errno = 0;
    if (S_ISLNK(st.st_mode) && stat(full, &target) != 0)
        target_errno = errno;
    if (S_ISDIR(st.st_mode))
        return walk(e, rel, depth + 1, err);
    if (S_ISLNK(st.st_mode) && !target_errno && S_ISDIR(target.st_mode)) {
        skip(e, rel, "symbolic link to a folder (not followed)");
        return 0;
    }
    if (!is_scan_name(e, base))
        return 0; /* textures, MTL files, glTF buffers, notes: not items */
    char why[160];
    return scan_item(e, rel, unreadable_reason(&st, &target, target_errno, why, sizeof why),
                     err);
}

static int walk(sl_engine *e, const char *rel_dir, int depth, sl_error *err)
{
    char dir_path[PATH_MAX];
    sl_engine_path(dir_path, sizeof dir_path, "%s%s%s", e->input, rel_dir[0] ? "/" : "", rel_dir);
    if (depth > MAX_TREE_DEPTH) {
        skip(e, rel_dir, "folder nested deeper than 64 levels");
        return 0;
    }
    DIR *d = opendir(dir_path);
    if (!d) {
        if (depth == 0)
            return sl_error_errno(err, errno, dir_path, "opendir");
        char why[160];
        snprintf(why, sizeof why, "folder cannot be read (%s)", strerror(errno));
        skip(e, rel_dir, why);
        return 0;
    }
    char **names = NULL;
    size_t count = 0, cap = 0;
    struct dirent *de;
    while ((de = readdir(d))) {
        if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, ".."))
            continue;
        if (count == cap) {
            cap = cap ? cap * 2 : 64;
            char **grown = realloc(names, cap * sizeof *names);
            if (!grown)
                break;
            names = grown;
        }
        names[count++] = strdup(de->d_name);
    }
    closedir(d);
    if (count > 1)
        qsort(names, count, sizeof *names, compare_strings);
    int rc = 0;
    for (size_t i = 0; i < count; i++) {
        char rel[PATH_MAX];
        if (rc == 0 && !*sl_interrupt_flag()) {
            if (sl_engine_path(rel, sizeof rel, "%s%s%s", rel_dir, rel_dir[0] ? "/" : "",
                               names[i]) == 0)
                rc = scan_entry(e, rel, names[i], depth, err);
            else
                skip(e, names[i], "path too long");
        }
        free(names[i]);
    }
    free(names);
    return rc;
}

int sl_engine_each_item(sl_engine *e, sl_engine_item_fn fn, void *ctx, sl_error *err)
{
    e->item_fn = fn;
    e->item_ctx = ctx;
    int rc = walk(e, "", 0, err);
    e->item_fn = NULL;
    e->item_ctx = NULL;
    return rc;
}

void sl_engine_facts_of(const sl_engine *e, sl_engine_facts *out)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    *out = (sl_engine_facts){e->cfg, e->threads > 0 ? e->threads : cores > 0 ? (int)cores : 1,
                             e->memory_limit_mb, sl_config_string(e->cfg, "lod", "method"),
                             e->stages, e->stage_count};
}

int sl_engine_scan(sl_engine *e, sl_error *err)
{
    double start = sl_now_seconds();
    sl_engine_scan_mark(e, 1);
    sl_engine_gc(e);
    e->items_settled = 0;
    int rc = walk(e, "", 0, err);
    e->items_total = e->counts.items;
    sl_engine_manifest_check(e);
    e->work_start = sl_now_seconds();
    e->settled_at_start = e->items_settled;
    if (rc == 0 && !*sl_interrupt_flag())
        sl_engine_scan_stamp(e); /* before the mark goes: a waiting worker sees one of them */
    sl_engine_scan_mark(e, 0);
    char extra[128];
    snprintf(extra, sizeof extra, "\"items\":%llu", (unsigned long long)e->counts.items);
    sl_log_event("scan_end", "scan", NULL, sl_now_seconds() - start, rc ? err : NULL, extra);
    SL_LOG(SL_LOG_INFO, "scan", NULL, "%llu items in %s", (unsigned long long)e->counts.items,
           e->input);
    if (rc && sl_error_class_of(rc) == SL_CLASS_STORAGE) {
        e->stop = 1;
        sl_error_merge(&e->storage_error, err);
    }
    return rc;
}
