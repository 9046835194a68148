/* System calls for durable writes, with fault injection for the crash and disk-full
 * tests (see io.h), and the one open of files read whole. The counters are per process:
 * the engine forks one child per item, so a fault index addresses the N-th call inside
 * one process. */
#include "core/io.h"

#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum io_op { OP_WRITE, OP_FSYNC, OP_RENAME, OP_UNLINK, OP_MKDIR, OP_OPEN, OP_ANY, OP_COUNT };
static const char *const op_names[OP_COUNT] = {"write", "fsync",  "rename", "unlink",
                                               "mkdir", "open", "any"};

static struct {
    int initialised;
    int op;        /* -1: no fault */
    long at;       /* 1-based call index */
    int err;       /* errno to inject, 0 = crash */
    int scope;     /* SCOPE_* bits: which processes inject */
    int armed;     /* this process injects */
    atomic_long calls[OP_COUNT];
} fault = {0, -1, 0, 0, 0, 0, {0}};

enum { SCOPE_PARENT = 1, SCOPE_CHILD = 2 };

static int errno_from_name(const char *name)
{
    static const struct { const char *name; int value; } names[] = {
        {"ENOSPC", ENOSPC}, {"EIO", EIO},       {"EDQUOT", EDQUOT}, {"EROFS", EROFS},
        {"EACCES", EACCES}, {"EINTR", EINTR},   {"ENOMEM", ENOMEM}, {"EINVAL", EINVAL},
        {"ENOENT", ENOENT}, /* a rename losing the race to another worker */
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strcmp(names[i].name, name) == 0)
            return names[i].value;
    return -1;
}

void sl_io_fault_init(void)
{
    if (fault.initialised)
        return;
    fault.initialised = 1;
    const char *spec = getenv("SCANLOD_FAULT");
    if (!spec || !*spec)
        return;
    char op[16] = {0}, what[16] = "crash";
    long at = 0;
    const char *c1 = strchr(spec, ':');
    if (!c1 || (size_t)(c1 - spec) >= sizeof op)
        return;
    memcpy(op, spec, (size_t)(c1 - spec));
    char *end;
    at = strtol(c1 + 1, &end, 10);
    if (*end == ':')
        snprintf(what, sizeof what, "%s", end + 1);
    for (int i = 0; i < OP_COUNT; i++)
        if (strcmp(op_names[i], op) == 0)
            fault.op = i;
    fault.at = at;
    fault.err = strcmp(what, "crash") == 0 ? 0 : errno_from_name(what);
    if (fault.err < 0 || at <= 0)
        fault.op = -1;
    const char *scope = getenv("SCANLOD_FAULT_SCOPE");
    fault.scope = !scope || !strcmp(scope, "all") ? SCOPE_PARENT | SCOPE_CHILD
                  : !strcmp(scope, "child")       ? SCOPE_CHILD
                                                  : SCOPE_PARENT;
    fault.armed = (fault.scope & SCOPE_PARENT) != 0;
}

int sl_io_faults_armed(void)
{
    sl_io_fault_init();
    return fault.armed && fault.op >= 0;
}

void sl_io_fault_enter_child(void)
{
    sl_io_fault_init();
    fault.armed = (fault.scope & SCOPE_CHILD) != 0;
    for (int i = 0; i < OP_COUNT; i++)
        atomic_store(&fault.calls[i], 0);
}

/* Returns 0 to go on, or an errno to fail with; crashes the process for "crash". */
static int inject(enum io_op op)
{
    if (!fault.initialised)
        sl_io_fault_init();
    if (fault.op < 0 || !fault.armed)
        return 0;
    long n = atomic_fetch_add(&fault.calls[op], 1) + 1;
    long any = atomic_fetch_add(&fault.calls[OP_ANY], 1) + 1;
    int hit = (fault.op == (int)op && n == fault.at) || (fault.op == OP_ANY && any == fault.at);
    if (!hit)
        return 0;
    if (fault.err == 0)
        _exit(99);
    return fault.err;
}

#define INJECT_OR_FAIL(op, retval)                                                      \
    do {                                                                                \
        int injected_ = inject(op);                                                     \
        if (injected_) {                                                                \
            errno = injected_;                                                          \
            return (retval);                                                            \
        }                                                                               \
    } while (0)

int sl_io_open(const char *path, int flags, mode_t mode)
{
    INJECT_OR_FAIL(OP_OPEN, -1);
    int fd;
    do
        fd = open(path, flags | O_CLOEXEC, mode);
    while (fd < 0 && errno == EINTR);
    return fd;
}

ssize_t sl_io_write(int fd, const void *buf, size_t n)
{
    INJECT_OR_FAIL(OP_WRITE, -1);
    const char *p = buf;
    size_t left = n;
    while (left > 0) {
        ssize_t w = write(fd, p, left);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            return -1;
        }
        if (w == 0) {
            errno = ENOSPC;
            return -1;
        }
        p += w;
        left -= (size_t)w;
    }
    return (ssize_t)n;
}

int sl_io_fsync(int fd)
{
    INJECT_OR_FAIL(OP_FSYNC, -1);
    /* No retry on EINTR-less failures: after a failed fsync the kernel may have dropped
     * the dirty pages, so a second fsync proves nothing (fsyncgate). */
    return fsync(fd);
}

int sl_io_rename(const char *from, const char *to)
{
    INJECT_OR_FAIL(OP_RENAME, -1);
    return rename(from, to);
}

int sl_io_unlink(const char *path)
{
    INJECT_OR_FAIL(OP_UNLINK, -1);
    return unlink(path);
}

int sl_io_mkdir(const char *path, mode_t mode)
{
    INJECT_OR_FAIL(OP_MKDIR, -1);
    return mkdir(path, mode);
}

static const char *not_regular(mode_t mode)
{
    return S_ISDIR(mode)    ? "is a directory"
           : S_ISFIFO(mode) ? "is a FIFO, not a regular file"
           : S_ISCHR(mode)  ? "is a character device, not a regular file"
           : S_ISBLK(mode)  ? "is a block device, not a regular file"
           : S_ISSOCK(mode) ? "is a socket, not a regular file"
                            : "is not a regular file";
}

/* Closes fd after a failed call on it, keeping that call's errno in the error. */
static int close_after(int fd, sl_error *err, const char *path, const char *what)
{
    int e = errno;
    close(fd);
    return sl_error_errno(err, e, path, what);
}

int sl_io_open_regular(const char *path, struct stat *st, sl_error *err)
{
    struct stat own;
    if (!st)
        st = &own;
    int fd;
    do
        fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    while (fd < 0 && errno == EINTR);
    if (fd < 0) {
        int e = errno;
        return sl_error_set(err, sl_error_code_of_errno(e), e, path, "%s", strerror(e));
    }
    if (fstat(fd, st) != 0)
        return close_after(fd, err, path, "fstat");
    if (!S_ISREG(st->st_mode)) {
        close(fd);
        return sl_error_set(err, SL_E_BADINPUT, S_ISDIR(st->st_mode) ? EISDIR : 0, path, "%s",
                            not_regular(st->st_mode));
    }
    int flags = fcntl(fd, F_GETFL);
    if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0)
        return close_after(fd, err, path, "fcntl");
    return fd;
}
