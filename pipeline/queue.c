/* Directory-per-state queues (see queue.h). */
#include "pipeline/queue.h"

#include <assert.h>
#include <dirent.h>
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/atomicfile.h"
#include "core/dirs.h"
#include "core/escape.h"
#include "core/hash.h"
#include "core/io.h"

static const char *const state_names[SL_STATE_COUNT] = {"ready", "claimed", "done", "failed",
                                                        "quarantine"};

const char *sl_queue_state_name(int state)
{
    return state >= 0 && state < SL_STATE_COUNT ? state_names[state] : "none";
}

void sl_ticket_init(sl_ticket *t)
{
    memset(t, 0, sizeof *t);
    t->memory_limit_mb = -1;
}

int sl_ticket_name(const char *item, char *name, size_t size, sl_error *err)
{
    if (!item[0])
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "empty item id");
    char escaped[4 * sizeof ((sl_ticket *)0)->item];
    long n = sl_escape(item, '/', '.', escaped, sizeof escaped);
    if (n < 0)
        return sl_error_set(err, SL_E_LIMIT, 0, item, "item id too long");
    if (n > SL_TICKET_NAME_MAX) {
        /* Too long for one file name: a prefix to read, then the hash of the whole id,
         * so every item still gets its own ticket. */
        char hex[SL_HASH_HEX_SIZE];
        sl_hash_hex(sl_hash_bytes(item, strlen(item)), hex);
        snprintf(escaped + SL_TICKET_NAME_MAX - 33, 34, "~%s", hex);
    }
    if (strlen(escaped) >= size)
        return sl_error_set(err, SL_E_INTERNAL, 0, item, "ticket name buffer too small");
    memcpy(name, escaped, strlen(escaped) + 1);
    return 0;
}

int sl_queue_path(char *buf, size_t size, const char *work, const char *stage, int state,
                  const char *name)
{
    if (state < 0 || state >= SL_STATE_COUNT)
        return -1; /* SL_STATE_NONE has no folder */
    int n = name ? snprintf(buf, size, "%s/queue/%s/%s/%s", work, stage, state_names[state], name)
                 : snprintf(buf, size, "%s/queue/%s/%s", work, stage, state_names[state]);
    return n < 0 || (size_t)n >= size ? -1 : 0;
}

int sl_queue_create(const char *work, const char *stage, sl_error *err)
{
    char path[PATH_MAX];
    for (int s = 0; s < SL_STATE_COUNT; s++) {
        sl_queue_path(path, sizeof path, work, stage, s, NULL);
        int rc = sl_mkdirs(path, err);
        if (rc)
            return rc;
    }
    return 0;
}

int sl_queue_find(const char *work, const char *stage, const char *name)
{
    char path[PATH_MAX];
    struct stat st;
    for (int s = 0; s < SL_STATE_COUNT; s++) {
        if (sl_queue_path(path, sizeof path, work, stage, s, name) == 0 && stat(path, &st) == 0)
            return s;
    }
    return SL_STATE_NONE;
}

#ifndef NDEBUG
/* The life of a ticket (docs/engine.md, "Queues and the life of an item"): ready is
 * claimed; a claim ends done, failed, quarantined or back in ready (interrupted, lost,
 * stale); reconciliation returns any ended state to ready. Nothing else moves a ticket. */
static int legal_move(int from, int to)
{
    switch (from) {
    case SL_STATE_READY: return to == SL_STATE_CLAIMED;
    case SL_STATE_CLAIMED:
        return to == SL_STATE_READY || to == SL_STATE_DONE || to == SL_STATE_FAILED ||
               to == SL_STATE_QUARANTINE;
    case SL_STATE_DONE:
    case SL_STATE_FAILED:
    case SL_STATE_QUARANTINE: return to == SL_STATE_READY;
    default: return 0;
    }
}
#endif

int sl_queue_move(const char *work, const char *stage, const char *name, int from, int to,
                  sl_error *err)
{
    assert(legal_move(from, to));
    char src[PATH_MAX], dst[PATH_MAX];
    if (sl_queue_path(src, sizeof src, work, stage, from, name) ||
        sl_queue_path(dst, sizeof dst, work, stage, to, name))
        return sl_error_set(err, SL_E_STORAGE, ENAMETOOLONG, name, "queue path too long");
    if (sl_io_rename(src, dst) != 0) {
        if (errno == ENOENT)
            return SL_E_BUSY;
        return sl_error_errno(err, errno, src, "rename");
    }
    char dir[PATH_MAX];
    sl_queue_path(dir, sizeof dir, work, stage, to, NULL);
    int rc = sl_fsync_dir(dir, err);
    if (rc == 0) {
        sl_queue_path(dir, sizeof dir, work, stage, from, NULL);
        rc = sl_fsync_dir(dir, err);
    }
    return rc;
}

int sl_queue_get(const char *work, const char *stage, int state, const char *name,
                 sl_ticket *t)
{
    char path[PATH_MAX];
    sl_error err;
    sl_error_init(&err);
    return sl_queue_path(path, sizeof path, work, stage, state, name) ||
           sl_ticket_read(path, t, &err) != 0;
}

int sl_queue_put(const char *work, const char *stage, int state, const char *name,
                 const sl_ticket *t, sl_error *err)
{
    char path[PATH_MAX];
    if (sl_queue_path(path, sizeof path, work, stage, state, name))
        return sl_error_set(err, SL_E_STORAGE, ENAMETOOLONG, name, "queue path too long");
    return sl_ticket_write(path, t, err);
}

int sl_queue_list(const char *work, const char *stage, int state, char ***names, int *count,
                  sl_error *err)
{
    *names = NULL;
    *count = 0;
    char path[PATH_MAX];
    sl_queue_path(path, sizeof path, work, stage, state, NULL);
    size_t n = 0;
    sl_error lerr;
    sl_error_init(&lerr);
    /* Hidden names are temps being written and NFS silly-renames, never tickets. */
    int rc = sl_dir_list(path, SL_DIR_NO_HIDDEN, names, &n, &lerr);
    if (rc && lerr.sys_errno == ENOENT)
        return 0;
    if (rc) {
        sl_error_merge(err, &lerr);
        return rc;
    }
    *count = (int)n;
    return 0;
}

/* ---- ticket text: "key=value" lines, closed by "end" (a torn ticket is not trusted) */

static void field(char *dst, size_t size, const char *value)
{
    snprintf(dst, size, "%s", value);
}

int sl_ticket_read(const char *path, sl_ticket *t, sl_error *err)
{
    sl_ticket_init(t);
    char *text = NULL;
    size_t size = 0;
    int rc = sl_read_file(path, 64 * 1024, &text, &size, err);
    if (rc)
        return rc;
    int complete = 0;
    for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
        if (strcmp(line, "end") == 0) {
            complete = 1;
            break;
        }
        char *eq = strchr(line, '=');
        if (!eq)
            continue;
        *eq = '\0';
        const char *k = line, *v = eq + 1;
        if (!strcmp(k, "item")) field(t->item, sizeof t->item, v), sl_unescape(t->item);
        else if (!strcmp(k, "source")) field(t->source, sizeof t->source, v), sl_unescape(t->source);
        else if (!strcmp(k, "key")) field(t->key, sizeof t->key, v);
        else if (!strcmp(k, "attempt")) t->attempt = atoi(v);
        else if (!strcmp(k, "crashes")) t->crashes = atoi(v);
        else if (!strcmp(k, "epoch")) t->epoch = strtoull(v, NULL, 10);
        else if (!strcmp(k, "host")) field(t->host, sizeof t->host, v);
        else if (!strcmp(k, "boot")) field(t->boot, sizeof t->boot, v);
        else if (!strcmp(k, "pid")) t->pid = atol(v);
        else if (!strcmp(k, "pid_start")) t->pid_start = strtoull(v, NULL, 10);
        else if (!strcmp(k, "job")) field(t->job, sizeof t->job, v);
        else if (!strcmp(k, "nonce")) field(t->nonce, sizeof t->nonce, v);
        else if (!strcmp(k, "expires")) t->expires = strtoll(v, NULL, 10);
        else if (!strcmp(k, "class")) field(t->cls, sizeof t->cls, v);
        else if (!strcmp(k, "reason")) field(t->reason, sizeof t->reason, v);
        else if (!strcmp(k, "limit_mb")) t->memory_limit_mb = strtoll(v, NULL, 10);
        else if (!strcmp(k, "run")) field(t->run, sizeof t->run, v);
        else if (!strcmp(k, "parts")) t->parts = atoi(v);
    }
    free(text);
    if (!complete || !t->item[0])
        return sl_error_set(err, SL_E_CORRUPT, 0, path, "torn or malformed ticket");
    return 0;
}

static void one_line(const char *src, char *dst, size_t size)
{
    size_t n = 0;
    for (; *src && n + 1 < size; src++)
        dst[n++] = (*src == '\n' || *src == '\r') ? ' ' : *src;
    dst[n] = '\0';
}

int sl_ticket_write(const char *path, const sl_ticket *t, sl_error *err)
{
    char reason[sizeof t->reason];
    one_line(t->reason, reason, sizeof reason);
    char item[3 * sizeof t->item], source[3 * sizeof t->source];
    if (sl_escape(t->item, 0, 0, item, sizeof item) < 0 ||
        sl_escape(t->source, 0, 0, source, sizeof source) < 0)
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "ticket too large");
    char text[4096 + sizeof item + sizeof source];
    int n = snprintf(text, sizeof text,
                     "item=%s\nsource=%s\nkey=%s\nattempt=%d\ncrashes=%d\nepoch=%" PRIu64
                     "\nhost=%s\nboot=%s\npid=%ld\npid_start=%llu\njob=%s\nnonce=%s\n"
                     "expires=%" PRId64 "\nclass=%s\nreason=%s\nlimit_mb=%" PRId64
                     "\nrun=%s\nparts=%d\nend\n",
                     item, source, t->key, t->attempt, t->crashes, t->epoch, t->host,
                     t->boot, t->pid, t->pid_start, t->job, t->nonce, t->expires, t->cls,
                     reason, t->memory_limit_mb, t->run, t->parts);
    if (n < 0 || (size_t)n >= sizeof text)
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "ticket too large");
    return sl_write_file_atomic(path, text, (size_t)n, err);
}
