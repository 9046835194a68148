/* Garbage collection of temp files and staged folders left by killed processes, and
 * `scanlod verify` (every commit record still vouches for its files).
 *
 * Temp names carry their writer: `.NAME.HOST.PID.N.tmp` (atomicfile.c) and
 * `.NAME.publish.HOST.PID` (engine_publish.c), `.NAME.stage.HOST.PID` (engine_child.c). On this host a temp whose writer pid is gone
 * is removed at once; another host's temps are left to that host (we cannot judge its
 * pids), unless older than a day.
 */
#include "pipeline/engine_internal.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/dirs.h"
#include "core/log.h"

#define FOREIGN_TEMP_MAX_AGE_S (24 * 3600)

/* The writer pid of a temp name if it was written on this host, else 0. */
static long own_temp_pid(const char *name, const char *host)
{
    char buf[512];
    snprintf(buf, sizeof buf, "%s", name);
    size_t len = strlen(buf);
    if (len > 4 && strcmp(buf + len - 4, ".tmp") == 0) {
        buf[len - 4] = '\0';
        char *dot = strrchr(buf, '.'); /* ".N" */
        if (!dot)
            return 0;
        *dot = '\0';
    }
    char *dot = strrchr(buf, '.'); /* ".PID" */
    if (!dot)
        return 0;
    char *end;
    long pid = strtol(dot + 1, &end, 10);
    if (*end || pid <= 0)
        return 0;
    *dot = '\0';
    size_t hl = strlen(host), bl = strlen(buf);
    if (bl <= hl || buf[bl - hl - 1] != '.' || strcmp(buf + bl - hl, host) != 0)
        return 0;
    return pid;
}

static void gc_dir(const sl_engine *e, const char *dir, int depth, uint64_t *removed)
{
    if (depth > 64)
        return;
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *de;
    time_t now = time(NULL);
    while ((de = readdir(d))) {
        if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, ".."))
            continue;
        char path[PATH_MAX];
        if (sl_engine_path(path, sizeof path, "%s/%s", dir, de->d_name))
            continue;
        struct stat st;
        if (lstat(path, &st) != 0)
            continue;
        if (de->d_name[0] != '.') {
            if (S_ISDIR(st.st_mode))
                gc_dir(e, path, depth + 1, removed);
            continue;
        }
        long pid = own_temp_pid(de->d_name, e->self.host);
        int dead = pid > 0 && pid != e->self.pid && kill((pid_t)pid, 0) != 0 && errno == ESRCH;
        int ancient = pid == 0 && now - st.st_mtime > FOREIGN_TEMP_MAX_AGE_S &&
                      (strstr(de->d_name, ".tmp") || strstr(de->d_name, ".publish.") ||
                       strstr(de->d_name, ".stage."));
        sl_error ignored;
        sl_error_init(&ignored);
        if ((dead || ancient) && sl_remove_tree(path, 0, &ignored) == 0)
            (*removed)++;
    }
    closedir(d);
}

void sl_engine_gc(sl_engine *e)
{
    uint64_t removed = 0;
    gc_dir(e, e->work, 0, &removed);
    gc_dir(e, e->output, 0, &removed);
    if (removed)
        SL_LOG(SL_LOG_INFO, "gc", NULL, "removed %llu temp files of dead processes",
               (unsigned long long)removed);
}

