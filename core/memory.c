/* The process's memory ceiling, and what happens when it is reached (core/memory.h). */
#include "core/memory.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "core/error.h"

/* A cgroup file holding one number of bytes ("max" or an absurd v1 value: no limit). */
static uint64_t cgroup_bytes(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    unsigned long long v = 0;
    int ok = fscanf(f, "%llu", &v) == 1;
    fclose(f);
    return ok && v < (1ull << 60) ? (uint64_t)v : 0;
}

/* The path of this process's memory cgroup file: the v2 line of /proc/self/cgroup
 * ("0::/PATH") names /sys/fs/cgroup/PATH/V2_NAME; a v1 "memory" line names
 * /sys/fs/cgroup/memory/PATH/V1_NAME. 0 when found. */
static int cgroup_file(const char *v2_name, const char *v1_name, char *path, size_t size)
{
    FILE *f = fopen("/proc/self/cgroup", "r");
    if (!f)
        return -1;
    char line[4096];
    int found = -1;
    while (found && fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = '\0';
        char *first = strchr(line, ':'), *second = first ? strchr(first + 1, ':') : NULL;
        if (!second)
            continue;
        *second = '\0';
        const char *controllers = first + 1, *rel = second + 1;
        if (!*controllers)
            snprintf(path, size, "/sys/fs/cgroup%s/%s", rel, v2_name);
        else if (strstr(controllers, "memory") != NULL)
            snprintf(path, size, "/sys/fs/cgroup/memory%s/%s", rel, v1_name);
        else
            continue;
        found = access(path, R_OK);
    }
    fclose(f);
    return found;
}

/* This process's cgroup limit in bytes, 0 when none. */
static uint64_t cgroup_limit(void)
{
    char path[4200];
    if (cgroup_file("memory.max", "memory.limit_in_bytes", path, sizeof path) != 0)
        return 0;
    return cgroup_bytes(path);
}

uint64_t sl_memory_oom_kills(void)
{
    char path[4200], line[256];
    if (cgroup_file("memory.events", "memory.oom_control", path, sizeof path) != 0)
        return 0;
    FILE *f = fopen(path, "r");
    unsigned long long kills = 0;
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "oom_kill %llu", &kills) == 1)
            break;
    if (f)
        fclose(f);
    return kills;
}

static void (*exhausted_handler)(const char *what);

void sl_memory_on_exhausted(void (*handler)(const char *what))
{
    exhausted_handler = handler;
}

void sl_memory_exhausted(const char *what)
{
    if (exhausted_handler)
        exhausted_handler(what);
    char line[256];
    int n = snprintf(line, sizeof line, "scanlod: out of memory (%s)\n", what);
    if (n > 0) {
        ssize_t written = write(STDERR_FILENO, line, (size_t)n < sizeof line ? (size_t)n : sizeof line);
        (void)written; /* nothing is left to do about a failed last word */
    }
    _exit(SL_EXIT_TEMPFAIL);
}

uint64_t sl_memory_available_mb(char *what, size_t what_size)
{
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    uint64_t physical = pages > 0 && page > 0 ? (uint64_t)pages * (uint64_t)page : 0;
    uint64_t cgroup = cgroup_limit();
    int by_cgroup = cgroup && (!physical || cgroup < physical);
    if (what && what_size)
        snprintf(what, what_size, "%s",
                 by_cgroup ? "the cgroup's memory limit" : "the node's physical memory");
    return (by_cgroup ? cgroup : physical) >> 20;
}

uint64_t sl_memory_budget_mb(int64_t limit_mb, char *what, size_t what_size)
{
    if (limit_mb > 0) {
        if (what && what_size)
            snprintf(what, what_size, "[run] memory_limit_mb");
        return (uint64_t)limit_mb;
    }
    return sl_memory_available_mb(what, what_size);
}
