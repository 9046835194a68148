/* Engine set-up, identity, paths, summary and status (docs/engine.md). */
#include "pipeline/engine_internal.h"

#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/io.h"
#include "core/json.h"
#include "core/log.h"

double sl_now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int sl_engine_path(char *buf, size_t size, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf, size, fmt, ap);
    va_end(ap);
    return n < 0 || (size_t)n >= size ? -1 : 0;
}

int sl_artifact_dir(const sl_engine *e, int stage, const char *ticket, char *buf, size_t size)
{
    return sl_engine_path(buf, size, "%s/artifacts/%s/%s", e->work, e->stages[stage]->name,
                          ticket);
}

static unsigned long long process_start_time(long pid)
{
    char path[64], text[1024];
    snprintf(path, sizeof path, "/proc/%ld/stat", pid);
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    /* comm may hold spaces and parentheses: fields restart after the last ')'. */
    char *p = strrchr(text, ')');
    if (!p)
        return 0;
    p++;
    for (int field = 3; field < 22 && p; field++) {
        p = strchr(p + 1, ' ');
    }
    return p ? strtoull(p + 1, NULL, 10) : 0;
}

void sl_identity_self(sl_identity *id)
{
    memset(id, 0, sizeof *id);
    if (gethostname(id->host, sizeof id->host - 1) != 0)
        snprintf(id->host, sizeof id->host, "unknown");
    FILE *f = fopen("/proc/sys/kernel/random/boot_id", "r");
    if (f) {
        if (!fgets(id->boot, sizeof id->boot, f))
            id->boot[0] = '\0';
        fclose(f);
        id->boot[strcspn(id->boot, "\n")] = '\0';
    }
    id->pid = (long)getpid();
    id->pid_start = process_start_time(id->pid);
    const char *job = getenv("SLURM_JOB_ID"), *task = getenv("SLURM_ARRAY_TASK_ID"),
               *restart = getenv("SLURM_RESTART_COUNT");
    /* In an array, the task's own SLURM_JOB_ID is not what scontrol/scancel take with
       "_TASK": name it ARRAYJOB_TASK, the id Slurm shows and accepts. */
    const char *array = getenv("SLURM_ARRAY_JOB_ID");
    if (task && array)
        job = array;
    else
        task = NULL;
    if (job)
        snprintf(id->job, sizeof id->job, "%s%s%s%s%s", job, task ? "_" : "", task ? task : "",
                 restart ? "+r" : "", restart ? restart : "");
}

int sl_identity_alive(const sl_identity *self, const sl_ticket *t)
{
    if (strcmp(self->host, t->host) != 0)
        return -1; /* another host: only the lease can tell */
    if (self->boot[0] && t->boot[0] && strcmp(self->boot, t->boot) != 0)
        return 0;  /* this host rebooted since the claim */
    if (t->pid <= 0)
        return 0;
    unsigned long long start = process_start_time(t->pid);
    if (start == 0)
        return 0;
    return t->pid_start == 0 || start == t->pid_start;
}

int sl_remove_dir_contents(const char *dir, sl_error *err)
{
    DIR *d = opendir(dir);
    if (!d)
        return errno == ENOENT ? 0 : sl_error_errno(err, errno, dir, "opendir");
    int rc = 0;
    struct dirent *de;
    /* The record goes first: without it nothing left here is trusted. */
    char path[PATH_MAX];
    if (sl_engine_path(path, sizeof path, "%s/%s", dir, SL_RECORD_FILE) == 0 &&
        sl_io_unlink(path) != 0 && errno != ENOENT)
        rc = sl_error_errno(err, errno, path, "unlink");
    while (rc == 0 && (de = readdir(d))) {
        if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, ".."))
            continue;
        if (sl_engine_path(path, sizeof path, "%s/%s", dir, de->d_name) == 0 &&
            sl_io_unlink(path) != 0 && errno != ENOENT)
            rc = sl_error_errno(err, errno, path, "unlink");
    }
    closedir(d);
    return rc ? rc : sl_fsync_dir(dir, err);
}

int sl_input_hash(sl_engine *e, const char *ticket, const char *source_rel, sl_hash *out,
                  sl_error *err)
{
    char source[PATH_MAX], cache[PATH_MAX];
    if (sl_engine_path(source, sizeof source, "%s/%s", e->input, source_rel) ||
        sl_engine_path(cache, sizeof cache, "%s/cache/input/%s", e->work, ticket))
        return sl_error_set(err, SL_E_LIMIT, 0, source_rel, "path too long");
    return sl_hash_file_cached(source, cache, out, err);
}

sl_hash sl_chain_hash(sl_hash chain, sl_hash digest)
{
    sl_hash pair[2] = {chain, digest};
    return sl_hash_bytes(pair, sizeof pair);
}

int sl_upstream_chain(sl_engine *e, const char *ticket, const char *source_rel, int s,
                      int verify_last, sl_hash *out, sl_error *err)
{
    sl_hash chain;
    int rc = sl_input_hash(e, ticket, source_rel, &chain, err);
    for (int i = 0; rc == 0 && i < s; i++) {
        char dir[PATH_MAX], record[PATH_MAX];
        sl_artifact_dir(e, i, ticket, dir, sizeof dir);
        sl_engine_path(record, sizeof record, "%s/%s", dir, SL_RECORD_FILE);
        sl_record rec;
        sl_error rerr;
        sl_error_init(&rerr);
        int bad = verify_last && i == s - 1 ? sl_record_verify(record, dir, NULL, &rec, &rerr)
                                            : sl_record_read(record, &rec, &rerr);
        if (bad)
            return SL_E_CORRUPT; /* an upstream result is gone or stale */
        chain = sl_chain_hash(chain, rec.outputs_digest);
    }
    if (rc == 0)
        *out = chain;
    return rc;
}

static int make_work_layout(sl_engine *e, sl_error *err)
{
    char path[PATH_MAX];
    int rc = sl_mkdirs(e->work, err);
    for (int s = 0; rc == 0 && s < e->stage_count; s++) {
        rc = sl_queue_create(e->work, e->stages[s]->name, err);
        if (rc == 0 && sl_engine_path(path, sizeof path, "%s/artifacts/%s", e->work,
                                      e->stages[s]->name) == 0)
            rc = sl_mkdirs(path, err);
    }
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/artifacts/_publish", e->work) == 0)
        rc = sl_mkdirs(path, err);
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/cache/input", e->work) == 0)
        rc = sl_mkdirs(path, err);
    if (rc == 0)
        rc = sl_mkdirs(e->output, err);
    return rc;
}

/* Hash of every section the stage reads (its own by default), in declaration order. */
static uint64_t stage_config_hash(const sl_config *cfg, const sl_stage *stage)
{
    if (!stage->sections)
        return sl_config_section_hash(cfg, stage->name);
    uint64_t hashes[8] = {0};
    int n = 0;
    for (; stage->sections[n] && n < 8; n++)
        hashes[n] = sl_config_section_hash(cfg, stage->sections[n]);
    sl_hash h = sl_hash_bytes(hashes, (size_t)n * sizeof hashes[0]);
    return h.hi ^ h.lo;
}

static void make_run_id(const sl_identity *id, const char *command, char *buf, size_t size)
{
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    char stamp[32];
    strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
    snprintf(buf, size, "%s-%s-%.32s-%ld", stamp, command, id->host, id->pid);
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
    e->memory_limit_mb = sl_config_int(e->cfg, "run", "memory_limit_mb");
    e->item_timeout_s = sl_config_int(e->cfg, "run", "item_timeout_s");
    e->lease_seconds = sl_config_int(e->cfg, "queue", "lease_seconds");
    e->max_crashes = (int)sl_config_int(e->cfg, "queue", "max_crashes");
    for (const sl_stage *const *s = opts->stages; *s && e->stage_count < SL_MAX_STAGES;
         s++) {
        e->config_hash[e->stage_count] = stage_config_hash(e->cfg, *s);
        e->stages[e->stage_count++] = *s;
    }
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
    }
    if (rc == 0 && opts->open_logs)
        rc = make_work_layout(e, err);
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
    sl_config_free(e->cfg);
    for (uint64_t i = 0; i < e->item_count; i++)
        free(e->items[i]);
    free(e->items);
    free(e);
}

/* ---- summary and status ---------------------------------------------------------- */

typedef struct queue_counts {
    uint64_t n[SL_MAX_STAGES][SL_STATE_COUNT];
} queue_counts;

static int count_queues(const sl_engine *e, queue_counts *c, sl_error *err)
{
    memset(c, 0, sizeof *c);
    for (int s = 0; s < e->stage_count; s++)
        for (int st = 0; st < SL_STATE_COUNT; st++) {
            char **names;
            int count;
            int rc = sl_queue_list(e->work, e->stages[s]->name, st, &names, &count, err);
            if (rc)
                return rc;
            c->n[s][st] = (uint64_t)count;
            free(names);
        }
    return 0;
}

int sl_engine_finish(sl_engine *e)
{
    sl_log_progress_clear();
    queue_counts c;
    sl_error err;
    sl_error_init(&err);
    uint64_t pending = 0, quarantined = 0;
    int exit_code;
    if (count_queues(e, &c, &err) != 0) {
        SL_LOG(SL_LOG_ERROR, NULL, NULL, "cannot read the queues: %s", err.message);
        exit_code = sl_error_exit_code(err.code);
    } else {
        for (int s = 0; s < e->stage_count; s++) {
            pending += c.n[s][SL_STATE_READY] + c.n[s][SL_STATE_CLAIMED] + c.n[s][SL_STATE_FAILED];
            quarantined += c.n[s][SL_STATE_QUARANTINE];
        }
        /* What failed transiently in this run without leaving a ticket behind (a
         * publication that found the output disk full, an input that could not be
         * hashed) is pending too: the next run retries it, and until then the collection
         * is not done. Exit 0 means every item is published. */
        pending += e->counts.untracked;
        if (e->stop)
            exit_code = sl_error_exit_code(e->storage_error.code);
        else if (pending || *sl_interrupt_flag())
            exit_code = SL_EXIT_TEMPFAIL;
        else if (e->counts.bugs)
            exit_code = SL_EXIT_SOFTWARE;
        else if (quarantined)
            exit_code = SL_EXIT_DATAERR;
        else
            exit_code = SL_EXIT_OK;
    }
    sl_error serr;
    sl_error_init(&serr);
    if (e->item_count && sl_engine_write_summary(e, &serr) != 0) {
        char line[1600];
        SL_LOG(SL_LOG_ERROR, NULL, NULL, "collection summary not written: %s",
               sl_error_format(&serr, line, sizeof line));
    }
    const sl_engine_counts *k = &e->counts;
    char skipped[64] = "";
    if (k->skipped)
        snprintf(skipped, sizeof skipped, ", %llu input entries skipped (see the log)",
                 (unsigned long long)k->skipped);
    if (k->ran == 0 && k->published == 0 && pending == 0 && !e->stop)
        printf("nothing to do: %llu items up to date (%llu quarantined)%s\n",
               (unsigned long long)k->items, (unsigned long long)quarantined, skipped);
    else
        printf("%llu items: %llu stage runs, %llu reused, %llu published, %llu newly "
               "quarantined, %llu failed transiently, %llu pending%s; exit %d\n",
               (unsigned long long)k->items, (unsigned long long)k->ran,
               (unsigned long long)k->reused, (unsigned long long)k->published,
               (unsigned long long)k->quarantined, (unsigned long long)k->transient,
               (unsigned long long)pending, skipped, exit_code);
    fflush(stdout);
    char extra[512];
    snprintf(extra, sizeof extra,
             "\"items\":%llu,\"ran\":%llu,\"reused\":%llu,\"published\":%llu,"
             "\"quarantined_new\":%llu,\"quarantined_total\":%llu,\"transient\":%llu,"
             "\"pending\":%llu,\"skipped\":%llu,\"exit\":%d",
             (unsigned long long)k->items, (unsigned long long)k->ran,
             (unsigned long long)k->reused, (unsigned long long)k->published,
             (unsigned long long)k->quarantined, (unsigned long long)quarantined,
             (unsigned long long)k->transient, (unsigned long long)pending,
             (unsigned long long)k->skipped, exit_code);
    sl_log_event("run_end", NULL, NULL, 0, e->stop ? &e->storage_error : NULL, extra);
    return exit_code;
}

int sl_engine_status(sl_engine *e, FILE *out, sl_error *err)
{
    queue_counts c;
    int rc = count_queues(e, &c, err);
    if (rc)
        return rc;
    fprintf(out, "%-10s %8s %8s %8s %8s %12s\n", "stage", "ready", "claimed", "done", "failed",
            "quarantined");
    for (int s = 0; s < e->stage_count; s++)
        fprintf(out, "%-10s %8llu %8llu %8llu %8llu %12llu\n", e->stages[s]->name,
                (unsigned long long)c.n[s][SL_STATE_READY],
                (unsigned long long)c.n[s][SL_STATE_CLAIMED],
                (unsigned long long)c.n[s][SL_STATE_DONE],
                (unsigned long long)c.n[s][SL_STATE_FAILED],
                (unsigned long long)c.n[s][SL_STATE_QUARANTINE]);
    sl_engine_unpublished(e, out);
    static const int listed[] = {SL_STATE_QUARANTINE, SL_STATE_FAILED, SL_STATE_CLAIMED};
    for (int s = 0; s < e->stage_count; s++)
        for (int l = 0; l < 3; l++) {
            char **names;
            int count;
            if (sl_queue_list(e->work, e->stages[s]->name, listed[l], &names, &count, err))
                return err->code;
            for (int i = 0; i < count; i++) {
                char path[PATH_MAX];
                sl_ticket t;
                sl_error terr;
                sl_error_init(&terr);
                sl_queue_path(path, sizeof path, e->work, e->stages[s]->name, listed[l], names[i]);
                if (sl_ticket_read(path, &t, &terr) != 0)
                    continue;
                if (listed[l] == SL_STATE_CLAIMED)
                    fprintf(out, "%s %s: claimed by %s pid %ld%s%s, lease epoch %llu\n",
                            e->stages[s]->name, t.item, t.host, t.pid, t.job[0] ? " job " : "",
                            t.job, (unsigned long long)t.epoch);
                else
                    fprintf(out, "%s %s: %s (%s): %s\n", e->stages[s]->name, t.item,
                            sl_queue_state_name(listed[l]), t.cls, t.reason);
            }
            free(names);
        }
    return 0;
}
