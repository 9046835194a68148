/* The one durable-write helper (core/atomicfile.h) is all or nothing: whichever of its
 * system calls fails (every open, write, fsync and rename in turn, through core/io.c's
 * fault injection) or crashes the process, the destination holds its old content or the
 * complete new one, never a part; a failure before the rename leaves the old content and
 * no temp file; a failure reports an error naming the file. Also: the buffered writer
 * over several flushes, a destination that did not exist, commit after a failed write,
 * abort, and the exit-time cleanup of live temps. */
#include "core/atomicfile.h"
#include "tests/check.h"
#include "tests/unit/durable_checks.h"

#include <errno.h>

#define CHUNK (700u * 1024u) /* > half the 1 MiB write buffer: every chunk flushes */
#define CHUNKS 5

static char dir[PATH_MAX], dest[PATH_MAX + 16];
static char *old_text, *new_text;
static size_t old_size, new_size;

/* The work each child does; its exit code is the verdict. */
enum { WROTE = 0, FAILED_WITH_MESSAGE = 1, FAILED_SILENTLY = 2, WRONG = 3 };

static int verdict(int rc, const sl_error *err)
{
    if (rc == 0)
        return err->code == SL_OK ? WROTE : WRONG;
    /* The error is the first failure, names a file (the destination, its temp or their
     * directory) and has a cause. */
    if (err->code != rc || !err->message[0] || !strstr(err->file, "test_atomicfile"))
        return FAILED_SILENTLY;
    return FAILED_WITH_MESSAGE;
}

static int write_whole(void *arg)
{
    (void)arg;
    sl_error err;
    sl_error_init(&err);
    return verdict(sl_write_file_atomic(dest, new_text, new_size, &err), &err);
}

/* The same bytes through the buffered API, chunk by chunk (several write calls). */
static int write_chunks(void *arg)
{
    (void)arg;
    sl_error err;
    sl_error_init(&err);
    sl_atomic_file f;
    int rc = sl_atomic_open(&f, dest, &err);
    for (size_t i = 0; rc == 0 && i < CHUNKS; i++)
        rc = sl_atomic_write(&f, new_text + i * CHUNK, CHUNK, &err);
    if (rc == 0)
        rc = sl_atomic_commit(&f, &err);
    else
        sl_atomic_abort(&f);
    return verdict(rc, &err);
}

static void reset_dest(int with_old)
{
    unlink(dest);
    if (with_old)
        CHECK(durable_put(dest, old_text, old_size) == 0);
}

/* Where the destination stands after one faulted run. */
static int holds_old(void) { return durable_holds(dest, old_text, old_size); }
static int holds_new(void) { return durable_holds(dest, new_text, new_size); }

/* Fails the n-th call of `op` for n = 1, 2, ... until a run no longer reaches it (it then
 * succeeds). Every failed run: an error with a message, old content or (only for a
 * failure after the rename: the directory's fsync) the complete new content, no temp.
 * Returns how many calls could fail. */
static int sweep(const char *op, const char *errno_name, int (*work)(void *), int with_old)
{
    int points = 0;
    for (int n = 1; n < 64; n++) {
        reset_dest(with_old);
        char spec[64];
        snprintf(spec, sizeof spec, "%s:%d:%s", op, n, errno_name);
        int v = durable_run(work, NULL, spec);
        if (v == WROTE) {
            CHECK_MSG(holds_new(), "%s: success without the new content", spec);
            break;
        }
        points++;
        CHECK_MSG(v == FAILED_WITH_MESSAGE, "%s: verdict %d", spec, v);
        int after_rename = holds_new();
        CHECK_MSG(after_rename || (with_old ? holds_old() : access(dest, F_OK) != 0),
                  "%s: the destination holds neither its old nor the new content", spec);
        /* Only the last call, the directory's fsync, comes after the rename. */
        CHECK_MSG(!after_rename || !strcmp(op, "fsync") || !strcmp(op, "open") ||
                      !strcmp(op, "any"),
                  "%s: the new content was published although the %s failed", spec, op);
        CHECK_MSG(durable_temps(dir) == 0, "%s: %d temp file(s) left", spec, durable_temps(dir));
    }
    return points;
}

static void test_plain_write(void)
{
    reset_dest(1);
    CHECK(durable_run(write_whole, NULL, NULL) == WROTE);
    CHECK(holds_new());
    CHECK(durable_temps(dir) == 0);
    reset_dest(0); /* no old file */
    CHECK(durable_run(write_chunks, NULL, NULL) == WROTE);
    CHECK(holds_new());
    CHECK(durable_temps(dir) == 0);
}

/* sl_write_file_atomic: one open, one write (a single large block), fsync, rename, then
 * the directory's open and fsync. */
static void test_every_call_fails_in_turn(void)
{
    CHECK_EQ_U64(sweep("write", "EIO", write_whole, 1), 1);
    CHECK_EQ_U64(sweep("fsync", "EIO", write_whole, 1), 2);   /* the file's, the directory's */
    CHECK_EQ_U64(sweep("rename", "EIO", write_whole, 1), 1);
    CHECK_EQ_U64(sweep("open", "EACCES", write_whole, 1), 2); /* the temp, the directory */
    CHECK_EQ_U64(sweep("any", "EIO", write_whole, 1), 6);
    /* ENOSPC on the first write and on a destination that did not exist. */
    CHECK_EQ_U64(sweep("write", "ENOSPC", write_whole, 0), 1);
    CHECK_EQ_U64(sweep("any", "ENOSPC", write_whole, 0), 6);
    /* Buffered: every chunk flushes, so there are as many writes as chunks. */
    CHECK_EQ_U64(sweep("write", "EIO", write_chunks, 1), CHUNKS);
    CHECK_EQ_U64(sweep("any", "EIO", write_chunks, 1), CHUNKS + 5);
}

/* A crash (`_exit` inside the call, as kill -9 would) at every durability point: the
 * destination holds its old or its complete new content; a temp may stay behind, hidden
 * (a dot name ending in .tmp) for the engine's garbage collection. */
static void test_crash_at_every_point(void)
{
    int crashes = 0;
    for (int n = 1; n < 64; n++) {
        reset_dest(1);
        char spec[32];
        snprintf(spec, sizeof spec, "any:%d:crash", n);
        int v = durable_run(write_chunks, NULL, spec);
        if (v == WROTE)
            break;
        crashes++;
        CHECK_MSG(v == 99, "%s: exit %d", spec, v);
        CHECK_MSG(holds_old() || holds_new(), "%s: torn destination", spec);
        DIR *d = opendir(dir);
        struct dirent *de;
        while (d && (de = readdir(d))) {
            if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..") || !strcmp(de->d_name, "dest"))
                continue;
            size_t len = strlen(de->d_name);
            CHECK_MSG(de->d_name[0] == '.' && len > 4 && !strcmp(de->d_name + len - 4, ".tmp"),
                      "%s: unexpected file %s", spec, de->d_name);
            char path[PATH_MAX + 300];
            snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
            unlink(path);
        }
        if (d)
            closedir(d);
    }
    CHECK_EQ_U64(crashes, CHUNKS + 5);
}

/* A write that failed poisons the file: commit refuses and publishes nothing. */
static int commit_after_failed_write(void *arg)
{
    (void)arg;
    sl_error err;
    sl_error_init(&err);
    sl_atomic_file f;
    if (sl_atomic_open(&f, dest, &err))
        return WRONG;
    int first = sl_atomic_write(&f, new_text, 2 * CHUNK, &err); /* direct write: fails */
    sl_error later;
    sl_error_init(&later);
    int rc = sl_atomic_commit(&f, &later);
    return first != 0 && rc != 0 && later.code != SL_OK ? FAILED_WITH_MESSAGE : WRONG;
}

/* abort drops the temp; sl_atomic_cleanup_all (exit, signals) drops the live ones. */
static int abort_and_cleanup(void *arg)
{
    (void)arg;
    sl_error err;
    sl_error_init(&err);
    sl_atomic_file a, b;
    if (sl_atomic_open(&a, dest, &err) || sl_atomic_write(&a, "x", 1, &err))
        return WRONG;
    sl_atomic_abort(&a);
    if (durable_temps(dir) != 0)
        return WRONG;
    if (sl_atomic_open(&b, dest, &err) || sl_atomic_write(&b, "y", 1, &err) ||
        durable_temps(dir) != 1)
        return WRONG;
    sl_atomic_cleanup_all();
    return durable_temps(dir) == 0 ? WROTE : WRONG;
}

static void test_abort_and_poison(void)
{
    reset_dest(1);
    CHECK(durable_run(commit_after_failed_write, NULL, "write:1:EIO") == FAILED_WITH_MESSAGE);
    CHECK(holds_old());
    CHECK(durable_temps(dir) == 0);
    CHECK(durable_run(abort_and_cleanup, NULL, NULL) == WROTE);
    CHECK(holds_old());
}

int main(void)
{
    if (durable_scratch("test_atomicfile", dir)) {
        perror("mkdtemp");
        return 1;
    }
    snprintf(dest, sizeof dest, "%s/dest", dir);
    old_size = 1000;
    new_size = (size_t)CHUNK * CHUNKS;
    old_text = malloc(old_size);
    new_text = malloc(new_size);
    for (size_t i = 0; i < old_size; i++)
        old_text[i] = (char)('a' + i % 26);
    for (size_t i = 0; i < new_size; i++)
        new_text[i] = (char)(i * 2654435761u >> 24);
    test_plain_write();
    test_every_call_fails_in_turn();
    test_crash_at_every_point();
    test_abort_and_poison();
    free(old_text);
    free(new_text);
    durable_remove_tree(dir);
    return check_report();
}
