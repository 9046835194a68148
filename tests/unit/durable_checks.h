/* What the tests of the durability core (test_atomicfile.c, test_queue.c, test_record.c)
 * share: a scratch directory, plain-POSIX file helpers that go around core/io.c, and
 * running a piece of work in a child process with a fault injected.
 *
 * Fault injection (core/io.h) reads SCANLOD_FAULT once per process, at the first call
 * of core/io.c, and counts calls per process. So every injected run forks: the child sets
 * the spec, does the work through the code under test and exits with a verdict; the
 * parent then looks at the files with plain system calls. The parent itself must never
 * call core/io.c before its last fork (it would fix the spec its children inherit).
 */
#ifndef SCANLOD_TESTS_UNIT_DURABLE_CHECKS_H
#define SCANLOD_TESTS_UNIT_DURABLE_CHECKS_H

#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* A fresh directory under $TMPDIR (or /tmp) named after `tag`, into dir[PATH_MAX]. */
static inline int durable_scratch(const char *tag, char *dir)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, PATH_MAX, "%s/%s_XXXXXX", tmp && tmp[0] ? tmp : "/tmp", tag);
    return mkdtemp(dir) ? 0 : -1;
}

/* rm -r, plain unlink/rmdir. */
static inline void durable_remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) {
        unlink(dir);
        return;
    }
    struct dirent *de;
    while ((de = readdir(d))) {
        if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, ".."))
            continue;
        char path[PATH_MAX];
        if (snprintf(path, sizeof path, "%s/%s", dir, de->d_name) >= (int)sizeof path)
            continue;
        struct stat st;
        if (lstat(path, &st) == 0 && S_ISDIR(st.st_mode))
            durable_remove_tree(path);
        else
            unlink(path);
    }
    closedir(d);
    rmdir(dir);
}

/* The whole file (malloc'd, NUL-terminated), or NULL when it does not exist. */
static inline char *durable_slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    char *data = NULL;
    size_t n = 0, cap = 0, got;
    char buf[65536];
    while ((got = fread(buf, 1, sizeof buf, f)) > 0) {
        if (n + got + 1 > cap) {
            cap = 2 * (n + got + 1);
            data = realloc(data, cap);
        }
        memcpy(data + n, buf, got);
        n += got;
    }
    fclose(f);
    if (!data)
        data = calloc(1, 1);
    data[n] = '\0';
    if (size)
        *size = n;
    return data;
}

/* Writes a file with plain stdio (not through the code under test). */
static inline int durable_put(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    size_t put = fwrite(data, 1, size, f);
    return fclose(f) == 0 && put == size ? 0 : -1;
}

/* Does `path` hold exactly data[0..size)? */
static inline int durable_holds(const char *path, const void *data, size_t size)
{
    size_t n = 0;
    char *got = durable_slurp(path, &n);
    int same = got && n == size && memcmp(got, data, size) == 0;
    free(got);
    return same;
}

/* Entries of `dir` whose name ends in ".tmp" (the atomic writer's temps). */
static inline int durable_temps(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *de;
    while (d && (de = readdir(d))) {
        size_t len = strlen(de->d_name);
        n += len > 4 && !strcmp(de->d_name + len - 4, ".tmp");
    }
    if (d)
        closedir(d);
    return n;
}

/* Runs fn(arg) in a child with SCANLOD_FAULT = `fault` (NULL: none) and returns the
 * child's exit code (fn's return value, 0..98), 99 for an injected crash, -1 when the
 * child died otherwise. */
static inline int durable_run(int (*fn)(void *arg), void *arg, const char *fault)
{
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0)
        return -1;
    if (pid == 0) {
        if (fault)
            setenv("SCANLOD_FAULT", fault, 1);
        else
            unsetenv("SCANLOD_FAULT");
        setenv("SCANLOD_FAULT_SCOPE", "all", 1);
        _exit(fn(arg));
    }
    int status;
    if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status))
        return -1;
    return WEXITSTATUS(status);
}

#endif
