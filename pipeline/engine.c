/* Opening and closing an engine: the config, the logs, the work folder (docs/engine.md). */
#include "pipeline/engine_internal.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stddef.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/dirs.h"
#include "core/io.h"
#include "core/json.h"
#include "core/log.h"

static void make_run_id(const sl_identity *id, const char *command, char *buf, size_t size)
{
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    char stamp[32];
    strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
    snprintf(buf, size, "%s-%s-%.32s-%ld", stamp, command, id->host, id->pid);
}

/* A log file of a run: RUN_ID.log or RUN_ID.jsonl, RUN_ID as make_run_id writes it
 * (stamp first); the run id's length (the stem) or 0. */
static size_t run_log_stem(const char *name)
{
    size_t n = strlen(name), stem = 0;
    if (n > 4 && !strcmp(name + n - 4, ".log"))
        stem = n - 4;
    else if (n > 6 && !strcmp(name + n - 6, ".jsonl"))
        stem = n - 6;
    static const char shape[] = "ddddddddTddddddZ-"; /* 20261206T092636Z- */
    for (size_t i = 0; stem && i < sizeof shape - 1; i++)
        if (i >= stem || (shape[i] == 'd' ? !isdigit((unsigned char)name[i]) : name[i] != shape[i]))
            stem = 0;
    return stem;
}

/* When process `pid` started, in seconds since the epoch (0 if unknown). */
static time_t process_started(long pid)
{
    unsigned long long ticks = sl_process_start_time(pid), boot = 0;
    FILE *f = fopen("/proc/stat", "r");
    char line[256];
    while (f && fgets(line, sizeof line, f) && sscanf(line, "btime %llu", &boot) != 1)
        ;
    if (f)
        fclose(f);
    long hz = sysconf(_SC_CLK_TCK);
    return ticks && boot && hz > 0 ? (time_t)(boot + ticks / (unsigned long long)hz) : 0;
}

/* Whether the run of log stem `name` (STAMP-COMMAND-HOST-PID) is still going here: its
 * pid lives and started no later than the stamp (a pid reused since started after). */
static int run_alive(const sl_engine *e, const char *name, size_t stem)
{
    char own[64];
    snprintf(own, sizeof own, "-%.32s-", e->self.host);
    const char *pid_at = name + stem;
    while (pid_at > name && pid_at[-1] != '-')
        pid_at--;
    size_t own_len = strlen(own);
    if (pid_at - name < (ptrdiff_t)own_len || strncmp(pid_at - own_len, own, own_len))
        return 0; /* another host's: its own runs prune it (we cannot judge its pids) */
    long pid = strtol(pid_at, NULL, 10);
    struct tm tm;
    memset(&tm, 0, sizeof tm);
    time_t started = process_started(pid);
    return pid > 0 && kill((pid_t)pid, 0) == 0 && strptime(name, "%Y%m%dT%H%M%SZ", &tm) &&
           started && started <= timegm(&tm) + 1;
}

/* Deletes the log files of all but the newest [run] log_keep runs in the logs folder
 * (this run's and live runs' excepted). Only one-shot cron used to delete any, so 50
 * runs with nothing to do left 100 files (issue 34 item 6). Best effort. */
static void prune_logs(const sl_engine *e, int64_t keep)
{
    char **names;
    size_t count, runs = 0, removed = 0;
    sl_error err;
    sl_error_init(&err);
    if (keep <= 0 || sl_dir_list(e->logs, SL_DIR_NO_HIDDEN, &names, &count, &err) != 0)
        return;
    /* Newest first: names sort by their stamp; a run's two files are neighbours. */
    for (size_t i = count; i-- > 0;) {
        size_t stem = run_log_stem(names[i]);
        if (!stem)
            continue;
        if (i + 1 >= count || strncmp(names[i], names[i + 1], stem) ||
            run_log_stem(names[i + 1]) != stem)
            runs++; /* a run not counted yet */
        char path[PATH_MAX];
        if (runs > (size_t)keep && strncmp(names[i], sl_log_run_id(), stem) &&
            !run_alive(e, names[i], stem) &&
            sl_engine_path(path, sizeof path, "%s/%s", e->logs, names[i]) == 0 &&
            unlink(path) == 0)
            removed++;
    }
    free(names);
    if (removed)
        SL_LOG(SL_LOG_INFO, NULL, NULL, "deleted %zu log files of runs older than the newest "
               "%lld ([run] log_keep)", removed, (long long)keep);
}

/* The bit of `name` in a "a|b|c" list of names (bit order), 0 if it is not there. */
static unsigned name_bit(const char *names, const char *name, size_t n)
{
    for (unsigned bit = 1; names; bit <<= 1, names = strchr(names, '|'), names += !!names)
        if (!strncmp(names, name, n) && (names[n] == '|' || names[n] == '\0'))
            return bit;
    return 0;
}

/* The stages of [lod] method's path, in registry order (stage.h, sl_lod_method): best takes
 * the stages of itself and of each method in [lod] candidates. */
static int choose_method(sl_engine *e, const sl_stage *const *stages, sl_error *err)
{
    const char *method = sl_config_string(e->cfg, "lod", "method");
    unsigned bit = name_bit(SL_METHOD_NAMES, method, strlen(method)); /* the enum admits
                                                                         only these */
    unsigned path = bit;
    if (bit == SL_METHOD_BEST)
        for (const char *c = sl_config_string(e->cfg, "lod", "candidates"); *c;) {
            size_t n = strcspn(c, ",");
            path |= name_bit(SL_CANDIDATE_NAMES, c, n);
            c += n + (c[n] == ',');
        }
    e->method = bit;
    int own = 0; /* stages of this method alone: without one it has no way to make levels */
    for (const sl_stage *const *s = stages; *s && e->stage_count < SL_MAX_STAGES; s++) {
        if (!((*s)->methods & path))
            continue;
        own += (*s)->methods != SL_METHODS_ALL;
        e->config_hash[e->stage_count] = sl_stage_config_hash(e->cfg, *s);
        e->stages[e->stage_count++] = *s;
    }
    if (own || bit == SL_METHOD_BEST) /* best without candidates: the scan alone */
        return 0;
    char where[PATH_MAX];
    sl_config_where(e->cfg, "lod", "method", where, sizeof where);
    return sl_error_set(err, SL_E_CONFIG, 0, where,
                        "[lod] method = %s: this build has no stages for it yet", method);
}

/* [run] threads = 0: the OMP_NUM_THREADS a job script set (a batch system's CPU share), as
 * every OpenMP program honours it; without it (or unreadable), 0 stays "all cores". */
static int threads_from_environment(void)
{
    const char *text = getenv("OMP_NUM_THREADS");
    if (!text || !*text)
        return 0;
    char *end;
    errno = 0;
    long n = strtol(text, &end, 10);
    if (errno || *end != '\0' || n < 1 || n > 1024)
        return 0;
    return (int)n;
}

int sl_engine_open(sl_engine **out, const sl_engine_options *opts, sl_error *err)
{
    *out = NULL;
    sl_engine *e = calloc(1, sizeof *e);
    if (!e)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    sl_io_fault_init();
    const sl_option *tables[SL_MAX_OPTION_TABLES + 1];
    sl_all_option_tables(opts->stages, tables);
    int rc = sl_config_load(&e->cfg, tables, opts->config_path,
                            opts->overrides, opts->override_count, err);
    if (rc) {
        free(e);
        return rc;
    }
    e->input = sl_config_string(e->cfg, "run", "input");
    e->work = sl_config_string(e->cfg, "run", "work");
    e->output = sl_config_string(e->cfg, "run", "output");
    e->logs = sl_config_string(e->cfg, "run", "logs");
    e->threads = (int)sl_config_int(e->cfg, "run", "threads");
    if (e->threads == 0)
        e->threads = threads_from_environment();
    e->memory_limit_mb = sl_config_int(e->cfg, "run", "memory_limit_mb");
    e->memory_check = sl_config_bool(e->cfg, "run", "memory_check");
    e->expected_peak_mb = opts->expected_peak_mb;
    static const char *const ply_only[] = {".ply", NULL};
    e->input_suffixes = opts->input_suffixes ? opts->input_suffixes : ply_only;
    e->item_timeout_s = sl_config_int(e->cfg, "run", "item_timeout_s");
    e->lease_seconds = sl_config_int(e->cfg, "queue", "lease_seconds");
    e->part_mb = sl_config_double(e->cfg, "queue", "part_mb");
    e->max_crashes = (int)sl_config_int(e->cfg, "queue", "max_crashes");
    rc = choose_method(e, opts->stages, err);
    sl_identity_self(&e->self);

    /* Every stage reads its section now, once, so a value only a stage can judge (a
     * level name, a list) stops the run before any work, as a bad key does. */
    for (int i = 0; rc == 0 && i < e->stage_count; i++) {
        void *stage_config = NULL;
        if (!e->stages[i]->configure)
            continue;
        rc = e->stages[i]->configure(e->cfg, &stage_config, err);
        if (rc == 0 && e->stages[i]->release_config)
            e->stages[i]->release_config(stage_config);
    }
    if (rc == 0)
        rc = sl_engine_check_input(e, err);
    if (rc == 0)
        rc = sl_engine_check_trees(e, err);
    if (rc == 0) /* before any work: a malformed manifest is a config error (exit 78) */
        rc = sl_engine_manifest_open(e, err);
    if (rc == 0 && opts->open_logs) {
        char run_id[160];
        make_run_id(&e->self, opts->command, run_id, sizeof run_id);
        static const char *const levels[] = {"error", "warn", "info", "debug"};
        const char *level = sl_config_string(e->cfg, "run", "log_level");
        for (int i = 0; i < 4; i++)
            if (!strcmp(levels[i], level))
                sl_log_level_current = i;
        int stderr_level = opts->quiet ? SL_LOG_ERROR : opts->verbose ? SL_LOG_DEBUG : SL_LOG_INFO;
        if (opts->verbose)
            sl_log_level_current = SL_LOG_DEBUG;
        rc = sl_log_open(e->logs, run_id, stderr_level, err);
        if (rc == 0)
            prune_logs(e, sl_config_int(e->cfg, "run", "log_keep"));
    }
    if (rc == 0 && opts->open_logs)
        rc = sl_engine_make_work_layout(e, err);
    if (rc == 0 && opts->open_logs)
        rc = sl_engine_check_writable(e, err);
    if (rc) {
        sl_engine_close(e);
        return rc;
    }
    *out = e;
    return 0;
}

void sl_engine_close(sl_engine *e)
{
    if (!e)
        return;
    sl_engine_manifest_close(e);
    sl_config_free(e->cfg);
    for (uint64_t i = 0; i < e->item_count; i++)
        free(e->items[i]);
    free(e->items);
    free(e);
}


