/* Running one stage of one item: what happens inside the forked stage process.
 *
 * The child loads the stage's config, runs the stage (or one part of it) into its private
 * staging folder, writes report.json and _timings.json, and sends its sl_error, CPU time and
 * peak RSS to the parent through a pipe. Memory runs out here as an error where it can be
 * returned, and as a last word through the same pipe where it cannot (an uncaught
 * std::bad_alloc: core/memory.h), so the parent classes it as transient, never as a bug.
 * The parent's side (claim, supervise, commit) is engine_child.c.
 */
#include "pipeline/engine_internal.h"

#include <errno.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <signal.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/clock.h"
#include "core/io.h"
#include "core/json.h"
#include "core/log.h"
#include "core/memory.h"
#include "core/progress.h"

/* Where a stage's time went, by the phases it reports progress in: wall and CPU seconds
 * per phase name (a phase met again adds to its first entry), written to the stage's
 * _timings.json as "phases" and so to its _stats.json. The time before the first phase
 * is "start" (mostly reading the stage's input). Phases change on the reporting thread
 * only (core/progress.h), so one writer. */
#define PHASE_CLOCK_MAX 32

typedef struct phase_clock {
    shared_progress *sp;
    int count, current;
    char name[PHASE_CLOCK_MAX][sizeof ((shared_progress *)0)->phase];
    double wall[PHASE_CLOCK_MAX], cpu[PHASE_CLOCK_MAX];
    double wall_mark, cpu_mark;
} phase_clock;

static double process_cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 +
           (double)ru.ru_stime.tv_sec + ru.ru_stime.tv_usec * 1e-6;
}

/* The current phase's time so far goes to its entry; then `phase` (NULL: none) is current. */
static void phase_clock_switch(phase_clock *c, const char *phase)
{
    double wall = sl_now_seconds(), cpu = process_cpu_seconds();
    if (c->current >= 0) {
        c->wall[c->current] += wall - c->wall_mark;
        c->cpu[c->current] += cpu - c->cpu_mark;
    }
    c->wall_mark = wall;
    c->cpu_mark = cpu;
    c->current = -1;
    if (!phase)
        return;
    for (int i = 0; i < c->count && c->current < 0; i++)
        if (strncmp(c->name[i], phase, sizeof c->name[i] - 1) == 0)
            c->current = i;
    if (c->current < 0 && c->count < PHASE_CLOCK_MAX) {
        c->current = c->count++;
        snprintf(c->name[c->current], sizeof c->name[c->current], "%s", phase);
        c->wall[c->current] = c->cpu[c->current] = 0;
    }
}

static void report_to_parent(void *ctx, const char *phase, double fraction)
{
    phase_clock *c = ctx;
    shared_progress *sp = c->sp;
    const char *name = phase ? phase : "";
    if (strncmp(sp->phase, name, sizeof sp->phase - 1) != 0)
        phase_clock_switch(c, name);
    sp->fraction = fraction;
    snprintf(sp->phase, sizeof sp->phase, "%s", name);
}

/* "phases": {"name": [wall seconds, CPU seconds], ...}, in the order first met. */
static void phase_clock_write(phase_clock *c, sl_json *timings)
{
    phase_clock_switch(c, NULL);
    sl_json_object_begin(timings, "phases");
    for (int i = 0; i < c->count; i++) {
        sl_json_array_begin(timings, c->name[i]);
        sl_json_double(timings, NULL, c->wall[i]);
        sl_json_double(timings, NULL, c->cpu[i]);
        sl_json_array_end(timings);
    }
    sl_json_object_end(timings);
}

static void write_all(int fd, const void *data, size_t size)
{
    const char *p = data;
    while (size > 0) {
        ssize_t w = write(fd, p, size);
        if (w <= 0 && errno != EINTR)
            return;
        if (w > 0) {
            p += w;
            size -= (size_t)w;
        }
    }
}

static int run_stage_in_child(sl_engine *e, const claim_work *w, shared_progress *sp,
                              sl_error *err)
{
    int s = w->s;
    const char *item = w->item, *source = w->source, *in_dir = w->in_dir;
    const char *out_dir = w->out_dir;
    /* Every earlier stage's artifact directory, for stages that read more than the
     * previous one (the key chain covers them all). */
    static char dirs[SL_MAX_STAGES][PATH_MAX];
    struct sl_stage_dir_entry upstream[SL_MAX_STAGES + 1] = {{NULL, NULL}};
    char ticket[SL_TICKET_NAME_MAX + 1];
    if (sl_ticket_name(item, ticket, sizeof ticket, err))
        return err->code;
    for (int i = 0; i < s; i++) {
        sl_artifact_dir(e, i, ticket, dirs[i], sizeof dirs[i]);
        upstream[i].stage = e->stages[i]->name;
        upstream[i].dir = dirs[i];
    }
    const sl_stage *stage = e->stages[s];
    void *stage_config = NULL;
    int rc = stage->configure(e->cfg, &stage_config, err);
    if (rc)
        return rc;
    sl_json report, timings;
    sl_json_init(&report, 1);
    sl_json_object_begin(&report, NULL);
    sl_json_init(&timings, 0);
    sl_json_object_begin(&timings, NULL);
    phase_clock phases;
    memset(&phases, 0, sizeof phases);
    phases.sp = sp;
    phases.current = -1;
    sp->phase[0] = '\0';
    phase_clock_switch(&phases, "start");
    sl_progress progress;
    memset(&progress, 0, sizeof progress);
    progress.report = report_to_parent;
    progress.ctx = &phases;
    progress.interrupt_flag = sl_interrupt_flag();
    char budget_what[64];
    sl_stage_io io = {.item = item, .source_path = source, .in_dir = in_dir,
                      .out_dir = out_dir, .report = &report, .timings = &timings,
                      .progress = &progress,
                      .threads = omp_get_max_threads(), .upstream = upstream,
                      .memory_budget_mb = sl_engine_memory_budget(e, budget_what,
                                                                   sizeof budget_what),
                      .metadata = sl_engine_item_metadata(e, s, item)};
    char **part_dirs = NULL;
    if (w->parts > 1) {
        io.part = w->part;
        io.parts = w->parts;
        if (w->part < 0 && !(part_dirs = sl_engine_part_dirs(e, s, ticket, w->parts)))
            rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
        io.part_dirs = (const char *const *)part_dirs;
    }
    if (rc == 0)
        rc = w->part >= 0 ? stage->run_part(stage_config, &io, err)
                          : stage->run(stage_config, &io, err);
    free(part_dirs);
    sl_json_object_end(&report);
    if (rc == 0 && report.failed)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "report too large");
    if (rc == 0) {
        char path[PATH_MAX];
        sl_engine_path(path, sizeof path, "%s/report.json", out_dir);
        rc = sl_write_file_atomic(path, report.buf, report.len, err);
    }
    phase_clock_write(&phases, &timings);
    sl_json_object_end(&timings);
    if (rc == 0 && !timings.failed && timings.len > 2) { /* more than "{}" */
        char path[PATH_MAX];
        sl_engine_path(path, sizeof path, "%s/_timings.json", out_dir);
        rc = sl_write_file_atomic(path, timings.buf, timings.len, err);
    }
    sl_json_release(&report);
    sl_json_release(&timings);
    if (stage->release_config)
        stage->release_config(stage_config);
    return rc;
}

/* CPU time and peak RSS of this (child) process so far. */
static void fill_usage(child_result *result)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    result->cpu_seconds = (double)ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 +
                          (double)ru.ru_stime.tv_sec + ru.ru_stime.tv_usec * 1e-6;
    result->max_rss_kb = ru.ru_maxrss;
}

/* The stage process's result pipe and memory limit, for its last word when memory runs
 * out where no error can be returned (an uncaught std::bad_alloc: core/memory.h). */
static int last_word_fd = -1;
static int64_t last_word_limit_mb;

static void report_out_of_memory(const char *what)
{
    child_result result;
    memset(&result, 0, sizeof result);
    sl_error_init(&result.err);
    if (last_word_limit_mb > 0)
        sl_error_set(&result.err, SL_E_NOMEM, ENOMEM, NULL,
                     "out of memory under [run] memory_limit_mb = %lld (%s)",
                     (long long)last_word_limit_mb, what);
    else
        sl_error_set(&result.err, SL_E_NOMEM, ENOMEM, NULL, "out of memory (%s)", what);
    fill_usage(&result);
    write_all(last_word_fd, &result, sizeof result);
    _exit(1);
}

void sl_engine_child_main(sl_engine *e, const claim_work *w, shared_progress *sp, int result_fd,
                       pid_t parent)
{
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent)
        _exit(SL_EXIT_TEMPFAIL);
    sl_io_fault_enter_child();
    last_word_fd = result_fd;
    last_word_limit_mb = e->memory_limit_mb;
    sl_memory_on_exhausted(report_out_of_memory);
#ifndef SCANLOD_SANITIZED /* ASan reserves terabytes of address space */
    /* RLIMIT_DATA (Linux 4.7+: private writable mappings, i.e. the heap, anonymous maps
     * and thread stacks) rather than RLIMIT_AS: the address space also counts every
     * mapped library and reserved arena, so an address-space cap of 300 MB failed to
     * load OpenImageIO for a 6k-triangle export whose peak RSS is 120 MB. */
    if (e->memory_limit_mb > 0) {
        struct rlimit rl = {(rlim_t)e->memory_limit_mb << 20, (rlim_t)e->memory_limit_mb << 20};
        setrlimit(RLIMIT_DATA, &rl);
    }
#endif
    omp_set_num_threads(e->threads > 0 ? e->threads : omp_get_num_procs());
    child_result result;
    memset(&result, 0, sizeof result);
    sl_error_init(&result.err);
    int rc = run_stage_in_child(e, w, sp, &result.err);
    if (rc && result.err.code == SL_OK)
        sl_error_set(&result.err, rc, 0, NULL, "%s", sl_strerror(rc));
    fill_usage(&result);
    write_all(result_fd, &result, sizeof result);
    close(result_fd);
    _exit(rc == 0 ? 0 : 1);
}
