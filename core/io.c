/* System calls for durable writes, with fault injection for the crash and disk-full
 * tests (see io.h), and the one open of files read whole. The counters are per process:
 * the engine forks one child per item, so a fault index addresses the N-th call inside
 * one process. With SCANLOD_FAULT_COUNT each counted call also appends a line to that
 * file, so a test learns how many points a run has and which one a crash reached. */
#include "core/io.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

enum io_op { OP_WRITE, OP_FSYNC, OP_RENAME, OP_UNLINK, OP_MKDIR, OP_OPEN, OP_ANY, OP_COUNT };
static const char *const op_names[OP_COUNT] = {"write", "fsync",  "rename", "unlink",
                                               "mkdir", "open", "any"};

static struct {
    int initialised;
    int op;            /* -1: no fault */
    long at;           /* 1-based call index */
    int err;           /* errno to inject, 0 = crash, halt or stop */
    int halt;          /* a per-item child takes the engine down with it */
    int stop;          /* SIGSTOP this process, then make the call: a frozen owner */
    char what[16];     /* its name, as given: "ENOSPC", "crash", "halt" */
    int scope;         /* SCOPE_* bits: which processes inject */
    long only_child;   /* SCANLOD_FAULT_SCOPE=child:K: only the K-th child injects; else 0 */
    int armed;         /* this process injects */
    long child;        /* in a per-item child: its place in the engine's forks, from 1 */
    pid_t engine;      /* in a per-item child: the engine that forked it; else 0 */
    int count_fd;      /* SCANLOD_FAULT_COUNT, O_APPEND; -1: not counting */
    atomic_long *forks; /* shared with the children: how many have entered so far */
    atomic_long calls[OP_COUNT];
} fault = {.op = -1, .count_fd = -1};

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

/* SCANLOD_FAULT_SCOPE: all (default) | parent | child | child:K. */
static void parse_scope(const char *scope)
{
    char *end;
    fault.scope = SCOPE_PARENT | SCOPE_CHILD;
    if (!scope || !strcmp(scope, "all"))
        return;
    fault.scope = SCOPE_PARENT;
    if (!strcmp(scope, "child"))
        fault.scope = SCOPE_CHILD;
    else if (!strncmp(scope, "child:", 6) && (fault.only_child = strtol(scope + 6, &end, 10)) > 0 &&
             !*end)
        fault.scope = SCOPE_CHILD;
    else
        fault.only_child = 0;
}

/* SCANLOD_FAULT: OP:N[:ERRNO|crash|halt]; anything else injects nothing. */
static void parse_spec(const char *spec)
{
    char op[16] = {0}, what[16] = "crash";
    const char *c1 = strchr(spec, ':');
    if (!c1 || (size_t)(c1 - spec) >= sizeof op)
        return;
    memcpy(op, spec, (size_t)(c1 - spec));
    char *end;
    long at = strtol(c1 + 1, &end, 10);
    if (*end == ':')
        snprintf(what, sizeof what, "%s", end + 1);
    for (int i = 0; i < OP_COUNT; i++)
        if (strcmp(op_names[i], op) == 0)
            fault.op = i;
    fault.at = at;
    fault.halt = strcmp(what, "halt") == 0;
    fault.stop = strcmp(what, "stop") == 0;
    fault.err = fault.halt || fault.stop || strcmp(what, "crash") == 0 ? 0
                                                                       : errno_from_name(what);
    memcpy(fault.what, what, sizeof fault.what);
    if (fault.err < 0 || at <= 0)
        fault.op = -1;
}

void sl_io_fault_init(void)
{
    if (fault.initialised)
        return;
    fault.initialised = 1;
    const char *count = getenv("SCANLOD_FAULT_COUNT");
    if (count && *count) /* plain open: the count file is not a durable write */
        fault.count_fd = open(count, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    const char *spec = getenv("SCANLOD_FAULT");
    if (spec && *spec) {
        parse_spec(spec);
        parse_scope(getenv("SCANLOD_FAULT_SCOPE"));
        fault.armed = (fault.scope & SCOPE_PARENT) != 0;
    }
    /* The children's places in the run: a page the engine's forks share (the engine calls
     * this before its first fork). */
    if (fault.count_fd >= 0 || fault.only_child > 0) {
        void *page = mmap(NULL, sizeof *fault.forks, PROT_READ | PROT_WRITE,
                          MAP_SHARED | MAP_ANONYMOUS, -1, 0);
        fault.forks = page == MAP_FAILED ? NULL : page;
        if (!fault.forks && fault.only_child > 0)
            fault.op = -1; /* cannot tell the K-th child: inject nowhere */
    }
}

int sl_io_faults_armed(void)
{
    sl_io_fault_init();
    return (fault.armed && fault.op >= 0) || fault.count_fd >= 0;
}

void sl_io_fault_enter_child(void)
{
    sl_io_fault_init();
    fault.engine = getppid();
    fault.child = fault.forks ? atomic_fetch_add(fault.forks, 1) + 1 : 1;
    fault.armed = (fault.scope & SCOPE_CHILD) != 0 &&
                  (fault.only_child == 0 || fault.only_child == fault.child);
    for (int i = 0; i < OP_COUNT; i++)
        atomic_store(&fault.calls[i], 0);
}

/* "PID parent|child:K OP N ANY[ FAULT]": the engine or its K-th per-item child, this
 * process's N-th call of OP and its ANY-th durable call, and on the call that is failed
 * the fault's name (ENOENT, crash, halt). One write(2) of a short line to an O_APPEND
 * file: lines of concurrent processes and threads do not interleave. Written before the
 * fault takes effect, so a crash's line is there. */
static void count_line(enum io_op op, long n, long any, int hit)
{
    char line[112], role[32] = "parent";
    if (fault.engine)
        snprintf(role, sizeof role, "child:%ld", fault.child);
    int len = snprintf(line, sizeof line, "%ld %s %s %ld %ld%s%s\n", (long)getpid(), role,
                       op_names[op], n, any, hit ? " " : "", hit ? fault.what : "");
    if (len > 0 && write(fault.count_fd, line, (size_t)len) < 0)
        fault.count_fd = -1; /* a test helper: stop counting rather than fail the call */
}

/* Returns 0 to go on, or an errno to fail with; exits for "crash" and "halt". */
static int inject(enum io_op op)
{
    if (!fault.initialised)
        sl_io_fault_init();
    int counting = fault.count_fd >= 0;
    if (!counting && (fault.op < 0 || !fault.armed))
        return 0;
    long n = atomic_fetch_add(&fault.calls[op], 1) + 1;
    long any = atomic_fetch_add(&fault.calls[OP_ANY], 1) + 1;
    int hit = fault.op >= 0 && fault.armed &&
              ((fault.op == (int)op && n == fault.at) || (fault.op == OP_ANY && any == fault.at));
    if (counting)
        count_line(op, n, any, hit);
    if (!hit)
        return 0;
    if (fault.stop) {
        /* A Slurm suspend or an NFS stall at exactly this point: the test sends SIGCONT
         * once another worker has taken the claim over, and the call then goes ahead. */
        raise(SIGSTOP);
        return 0;
    }
    if (fault.err == 0) {
        /* halt: the whole run stops here, as on a power cut. The engine's own process
         * just exits (its children die with it: PR_SET_PDEATHSIG); a child kills the
         * engine first, so nothing of the run goes on to handle the crash. */
        if (fault.halt && fault.engine && getppid() == fault.engine)
            kill(fault.engine, SIGKILL);
        _exit(99);
    }
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

int sl_io_map(const char *path, size_t populate_max, void **map, size_t *size, sl_error *err)
{
    struct stat st;
    *map = NULL;
    *size = 0;
    int fd = sl_io_open_regular(path, &st, err);
    if (fd < 0)
        return fd;
    size_t n = (size_t)st.st_size;
    void *m = NULL;
    int populate = n <= populate_max ? MAP_POPULATE : 0;
    if (n > 0 && (m = mmap(NULL, n, PROT_READ, MAP_PRIVATE | populate, fd, 0)) == MAP_FAILED) {
        int e = errno;
        close(fd);
        return sl_error_errno(err, e, path, "mmap");
    }
    close(fd); /* the mapping keeps the file */
    *map = m;
    *size = n;
    return 0;
}

void sl_io_unmap(void *map, size_t size)
{
    if (map)
        munmap(map, size);
}
