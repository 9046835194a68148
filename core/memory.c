/* The process's memory ceiling (core/memory.h). */
#include "core/memory.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

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

/* This process's cgroup limit in bytes, 0 when none: the v2 line of /proc/self/cgroup
 * ("0::/PATH") names /sys/fs/cgroup/PATH/memory.max; a v1 "memory" line names
 * /sys/fs/cgroup/memory/PATH/memory.limit_in_bytes. */
static uint64_t cgroup_limit(void)
{
    FILE *f = fopen("/proc/self/cgroup", "r");
    if (!f)
        return 0;
    char line[4096], path[4200];
    uint64_t limit = 0;
    while (!limit && fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = '\0';
        char *first = strchr(line, ':'), *second = first ? strchr(first + 1, ':') : NULL;
        if (!second)
            continue;
        *second = '\0';
        const char *controllers = first + 1, *rel = second + 1;
        if (!*controllers)
            snprintf(path, sizeof path, "/sys/fs/cgroup%s/memory.max", rel);
        else if (strstr(controllers, "memory") != NULL)
            snprintf(path, sizeof path, "/sys/fs/cgroup/memory%s/memory.limit_in_bytes", rel);
        else
            continue;
        limit = cgroup_bytes(path);
    }
    fclose(f);
    return limit;
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
