/* Durable, atomic file publication (see atomicfile.h for the protocol). */
#include "core/atomicfile.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <linux/fs.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/io.h"

#define WRITE_BUFFER_SIZE (1u << 20)
#define MAX_LIVE_TEMPS 256

/* Live temp files, removed at exit (a kill -9 leaves them; the engine's cleanup of an
 * artifact directory before a rerun removes those). */
static pthread_mutex_t live_lock = PTHREAD_MUTEX_INITIALIZER;
static char *live_temps[MAX_LIVE_TEMPS];
static atomic_uint temp_counter;
static int atexit_registered;

static void live_add(const char *path)
{
    pthread_mutex_lock(&live_lock);
    if (!atexit_registered) {
        atexit(sl_atomic_cleanup_all);
        atexit_registered = 1;
    }
    for (int i = 0; i < MAX_LIVE_TEMPS; i++)
        if (!live_temps[i]) {
            live_temps[i] = strdup(path);
            break;
        }
    pthread_mutex_unlock(&live_lock);
}

static void live_remove(const char *path)
{
    pthread_mutex_lock(&live_lock);
    for (int i = 0; i < MAX_LIVE_TEMPS; i++)
        if (live_temps[i] && strcmp(live_temps[i], path) == 0) {
            free(live_temps[i]);
            live_temps[i] = NULL;
            break;
        }
    pthread_mutex_unlock(&live_lock);
}

void sl_atomic_cleanup_all(void)
{
    for (int i = 0; i < MAX_LIVE_TEMPS; i++)
        if (live_temps[i])
            unlink(live_temps[i]);
}

static void split_path(const char *path, char *dir, size_t dir_size, const char **base)
{
    const char *slash = strrchr(path, '/');
    if (!slash) {
        snprintf(dir, dir_size, ".");
        *base = path;
    } else if (slash == path) {
        snprintf(dir, dir_size, "/");
        *base = slash + 1;
    } else {
        snprintf(dir, dir_size, "%.*s", (int)(slash - path), path);
        *base = slash + 1;
    }
}

int sl_fsync_dir(const char *dir, sl_error *err)
{
    int fd = sl_io_open(dir, O_RDONLY | O_DIRECTORY, 0);
    if (fd < 0)
        return sl_error_errno(err, errno, dir, "open directory");
    int rc = sl_io_fsync(fd);
    int saved = errno;
    close(fd);
    /* Some filesystems refuse fsync on directories (EINVAL); their renames are already
     * as durable as they get, so this is not an item failure. */
    if (rc != 0 && saved != EINVAL)
        return sl_error_errno(err, saved, dir, "fsync directory");
    return 0;
}

int sl_mkdirs(const char *path, sl_error *err)
{
    char buf[PATH_MAX];
    if (snprintf(buf, sizeof buf, "%s", path) >= (int)sizeof buf)
        return sl_error_set(err, SL_E_STORAGE, ENAMETOOLONG, path, "path too long");
    size_t len = strlen(buf);
    while (len > 1 && buf[len - 1] == '/')
        buf[--len] = '\0';
    struct stat st;
    if (stat(buf, &st) == 0) {
        if (S_ISDIR(st.st_mode))
            return 0;
        return sl_error_set(err, SL_E_STORAGE, ENOTDIR, buf, "exists and is not a directory");
    }
    char *slash = strrchr(buf, '/');
    if (slash && slash != buf) {
        *slash = '\0';
        int rc = sl_mkdirs(buf, err);
        if (rc)
            return rc;
        *slash = '/';
    }
    if (sl_io_mkdir(buf, 0777) != 0 && errno != EEXIST)
        return sl_error_errno(err, errno, buf, "mkdir");
    /* The new entry lives in the parent: make it durable. */
    char parent[PATH_MAX];
    const char *base;
    split_path(buf, parent, sizeof parent, &base);
    return sl_fsync_dir(parent, err);
}

int sl_atomic_open(sl_atomic_file *f, const char *final_path, sl_error *err)
{
    memset(f, 0, sizeof *f);
    f->fd = -1;
    if (snprintf(f->final_path, sizeof f->final_path, "%s", final_path) >=
        (int)sizeof f->final_path)
        return sl_error_set(err, SL_E_STORAGE, ENAMETOOLONG, final_path, "path too long");
    char dir[PATH_MAX];
    const char *base;
    split_path(final_path, dir, sizeof dir, &base);
    char host[64] = "host";
    gethostname(host, sizeof host - 1);
    unsigned n = atomic_fetch_add(&temp_counter, 1);
    snprintf(f->tmp_path, sizeof f->tmp_path, "%s/.%.200s.%.40s.%ld.%u.tmp", dir, base, host,
             (long)getpid(), n);
    f->fd = sl_io_open(f->tmp_path, O_WRONLY | O_CREAT | O_EXCL, 0644);
    if (f->fd < 0) /* said of the file asked for: the temp name means nothing to a user */
        return sl_error_errno(err, errno, final_path, "create");
    live_add(f->tmp_path);
    f->buf = malloc(WRITE_BUFFER_SIZE);
    if (!f->buf) {
        sl_atomic_abort(f);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, final_path, "out of memory");
    }
    f->buf_cap = WRITE_BUFFER_SIZE;
    return 0;
}

static int flush_buffer(sl_atomic_file *f, sl_error *err)
{
    if (f->buf_len == 0)
        return 0;
    if (sl_io_write(f->fd, f->buf, f->buf_len) < 0) {
        f->failed = 1;
        return sl_error_errno(err, errno, f->final_path, "write");
    }
    f->buf_len = 0;
    return 0;
}

int sl_atomic_write(sl_atomic_file *f, const void *data, size_t size, sl_error *err)
{
    if (f->fd < 0 || f->failed)
        return sl_error_set(err, SL_E_INTERNAL, 0, f->final_path, "write after failure");
    const unsigned char *p = data;
    f->bytes_written += size;
    if (size >= f->buf_cap) {
        int rc = flush_buffer(f, err);
        if (rc)
            return rc;
        if (sl_io_write(f->fd, p, size) < 0) {
            f->failed = 1;
            return sl_error_errno(err, errno, f->final_path, "write");
        }
        return 0;
    }
    if (f->buf_len + size > f->buf_cap) {
        int rc = flush_buffer(f, err);
        if (rc)
            return rc;
    }
    memcpy(f->buf + f->buf_len, p, size);
    f->buf_len += size;
    return 0;
}

int sl_atomic_printf(sl_atomic_file *f, sl_error *err, const char *fmt, ...)
{
    char small[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0)
        return sl_error_set(err, SL_E_INTERNAL, 0, f->final_path, "format failed");
    if ((size_t)n < sizeof small)
        return sl_atomic_write(f, small, (size_t)n, err);
    char *big = malloc((size_t)n + 1);
    if (!big)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, f->final_path, "out of memory");
    va_start(ap, fmt);
    vsnprintf(big, (size_t)n + 1, fmt, ap);
    va_end(ap);
    int rc = sl_atomic_write(f, big, (size_t)n, err);
    free(big);
    return rc;
}

int sl_atomic_commit(sl_atomic_file *f, sl_error *err)
{
    int rc = f->failed ? SL_E_IO : flush_buffer(f, err);
    if (rc == 0 && sl_io_fsync(f->fd) != 0)
        rc = sl_error_errno(err, errno, f->final_path, "fsync");
    if (rc == 0) {
        int fd = f->fd;
        f->fd = -1;
        if (close(fd) != 0)
            rc = sl_error_errno(err, errno, f->final_path, "close");
    }
    if (rc == 0 && sl_io_rename(f->tmp_path, f->final_path) != 0)
        rc = sl_error_errno(err, errno, f->final_path, "rename");
    if (rc != 0) {
        if (f->failed && err && err->code == SL_OK)
            sl_error_set(err, SL_E_IO, 0, f->final_path, "earlier write failed");
        sl_atomic_abort(f);
        return rc ? rc : SL_E_IO;
    }
    live_remove(f->tmp_path);
    free(f->buf);
    f->buf = NULL;
    char dir[PATH_MAX];
    const char *base;
    split_path(f->final_path, dir, sizeof dir, &base);
    return sl_fsync_dir(dir, err);
}

void sl_atomic_abort(sl_atomic_file *f)
{
    if (f->fd >= 0) {
        close(f->fd);
        f->fd = -1;
    }
    if (f->tmp_path[0]) {
        unlink(f->tmp_path);
        live_remove(f->tmp_path);
        f->tmp_path[0] = '\0';
    }
    free(f->buf);
    f->buf = NULL;
}

int sl_write_file_atomic(const char *path, const void *data, size_t size, sl_error *err)
{
    sl_atomic_file f;
    int rc = sl_atomic_open(&f, path, err);
    if (rc)
        return rc;
    rc = sl_atomic_write(&f, data, size, err);
    if (rc) {
        sl_atomic_abort(&f);
        return rc;
    }
    return sl_atomic_commit(&f, err);
}

int sl_read_file(const char *path, uint64_t max_size, char **data, size_t *size, sl_error *err)
{
    *data = NULL;
    *size = 0;
    struct stat st;
    int fd = sl_io_open_regular(path, &st, err);
    if (fd < 0)
        return fd;
    if ((uint64_t)st.st_size > max_size) {
        close(fd);
        return sl_error_set(err, SL_E_LIMIT, 0, path, "file is %llu bytes, limit %llu",
                            (unsigned long long)st.st_size, (unsigned long long)max_size);
    }
    size_t want = (size_t)st.st_size;
    char *buf = malloc(want + 1);
    if (!buf) {
        close(fd);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    }
    size_t got = 0;
    while (got < want) {
        ssize_t r = read(fd, buf + got, want - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0) {
            int saved = r < 0 ? errno : EIO;
            free(buf);
            close(fd);
            if (r == 0)
                return sl_error_set(err, SL_E_IO, 0, path, "file shrank while reading");
            return sl_error_errno(err, saved, path, "read");
        }
        got += (size_t)r;
    }
    close(fd);
    buf[got] = '\0';
    *data = buf;
    *size = got;
    return 0;
}

/* Copies the open file `in` into the open temp of `f`: a reflink when the filesystem
 * shares extents (btrfs, XFS: instant, no space), else copy_file_range, else read/write. */
static int copy_contents(int in, const char *from, sl_atomic_file *f, sl_error *err)
{
    if (!sl_io_faults_armed() && ioctl(f->fd, FICLONE, in) == 0)
        return 0;
    while (!sl_io_faults_armed()) {
        ssize_t n = copy_file_range(in, NULL, f->fd, NULL, 1 << 30, 0);
        if (n == 0)
            return 0;
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            break; /* not supported here (or cross-device on old kernels): plain copy */
    }
    if (lseek(in, 0, SEEK_SET) != 0 || ftruncate(f->fd, 0) != 0 || lseek(f->fd, 0, SEEK_SET) != 0)
        return sl_error_errno(err, errno, from, "seek");
    for (;;) {
        ssize_t n = read(in, f->buf, f->buf_cap);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            return sl_error_errno(err, errno, from, "read");
        if (n == 0)
            return 0;
        if (sl_io_write(f->fd, f->buf, (size_t)n) < 0) {
            f->failed = 1;
            return sl_error_errno(err, errno, f->final_path, "write");
        }
    }
}

int sl_copy_file(const char *from, const char *to, sl_error *err)
{
    int in = sl_io_open_regular(from, NULL, err);
    if (in < 0)
        return in;
    sl_atomic_file f;
    int rc = sl_atomic_open(&f, to, err);
    if (rc == 0)
        rc = copy_contents(in, from, &f, err);
    close(in);
    if (rc == 0)
        return sl_atomic_commit(&f, err);
    sl_atomic_abort(&f);
    return rc;
}

int sl_link_or_copy(const char *from, const char *to, sl_error *err)
{
    unlink(to);
    if (link(from, to) == 0)
        return 0;
    return sl_copy_file(from, to, err);
}
