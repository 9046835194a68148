/* Running one stage of one item in a child process, and what its outcome means.
 *
 * Isolation (reliability rule 13): OpenMP threads share fate, so each (item, stage) runs
 * in a fork()ed child with its own address-space limit; a crash or an OOM kill costs that
 * item only. The child dies with its parent (PR_SET_PDEATHSIG), so a kill -9 of the
 * worker never leaves an orphan writing into the work dir. The parent renews the lease,
 * forwards interrupts, enforces the timeout and draws the progress bar meanwhile.
 *
 * Outcome -> ticket (ARCHITECTURE section 3, failure classes):
 *   success                       -> record committed, ticket done, next stage enqueued
 *   bad input (BADINPUT/LIMIT/..) -> quarantine at once, with the reason
 *   interrupted                   -> ready again (not the item's fault)
 *   ENOSPC, EIO, OOM, killed, lost lease -> failed (retried by the next run), never quarantined
 *   crash/abort/timeout/internal  -> ready again, until max_crashes: then quarantine as a bug
 *   storage needs a human         -> failed, and the worker stops (exit 74)
 */
#include "pipeline/engine_internal.h"

#include <errno.h>
#include <omp.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/dirs.h"
#include "core/io.h"
#include "core/json.h"
#include "core/log.h"
#include "core/progress.h"

typedef struct child_result {
    sl_error err;
    double cpu_seconds;
    long max_rss_kb;
} child_result;

typedef struct shared_progress {
    volatile double fraction;
    char phase[32];
} shared_progress;

static void report_to_parent(void *ctx, const char *phase, double fraction)
{
    shared_progress *sp = ctx;
    sp->fraction = fraction;
    snprintf(sp->phase, sizeof sp->phase, "%s", phase ? phase : "");
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

/* The work of a claim: which stage of which item, and which part of it (part -1: the
 * whole stage, or the join of its `parts` parts when parts > 1). */
typedef struct claim_work {
    int s;
    const char *item, *source, *in_dir, *out_dir;
    int part, parts;
} claim_work;

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
    sl_json report;
    sl_json_init(&report, 1);
    sl_json_object_begin(&report, NULL);
    sl_progress progress;
    memset(&progress, 0, sizeof progress);
    progress.report = report_to_parent;
    progress.ctx = sp;
    progress.interrupt_flag = sl_interrupt_flag();
    sl_stage_io io = {.item = item, .source_path = source, .in_dir = in_dir,
                      .out_dir = out_dir, .report = &report, .progress = &progress,
                      .threads = omp_get_max_threads(), .upstream = upstream};
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
    sl_json_release(&report);
    if (stage->release_config)
        stage->release_config(stage_config);
    return rc;
}

static void child_main(sl_engine *e, const claim_work *w, shared_progress *sp, int result_fd,
                       pid_t parent)
{
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent)
        _exit(SL_EXIT_TEMPFAIL);
    sl_io_fault_enter_child();
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
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    result.cpu_seconds = (double)ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 +
                         (double)ru.ru_stime.tv_sec + ru.ru_stime.tv_usec * 1e-6;
    result.max_rss_kb = ru.ru_maxrss;
    write_all(result_fd, &result, sizeof result);
    close(result_fd);
    _exit(rc == 0 ? 0 : 1);
}

typedef struct child_outcome {
    int have_result;
    child_result result;
    int status;       /* waitpid status */
    int timed_out;
    int interrupted;  /* we forwarded an interrupt */
    int lease_lost;
    double seconds;
} child_outcome;

static void supervise(sl_engine *e, int s, const char *name, sl_ticket *t, pid_t pid, int fd,
                      shared_progress *sp, child_outcome *out)
{
    double start = sl_now_seconds(), last_renew = start;
    size_t got = 0;
    char *buf = (char *)&out->result;
    for (;;) {
        struct pollfd pfd = {fd, POLLIN, 0};
        int ready = poll(&pfd, 1, 200);
        if (ready > 0) {
            ssize_t r = read(fd, buf + got, sizeof out->result - got);
            if (r > 0)
                got += (size_t)r;
            else if (r == 0 || (errno != EINTR && errno != EAGAIN))
                break;
        }
        double now = sl_now_seconds();
        if (*sl_interrupt_flag() && !out->interrupted) {
            out->interrupted = 1;
            kill(pid, SIGTERM);
        }
        if (e->item_timeout_s > 0 && now - start > (double)e->item_timeout_s && !out->timed_out) {
            out->timed_out = 1;
            kill(pid, SIGKILL);
        }
        if (!out->lease_lost && now - last_renew > (double)e->lease_seconds / 5.0) {
            sl_error lerr;
            sl_error_init(&lerr);
            if (sl_engine_lease_renew(e, e->stages[s]->name, name, t, &lerr) != 0) {
                out->lease_lost = 1; /* self-fence: stop, never commit */
                kill(pid, SIGKILL);
            }
            last_renew = now;
        }
        sl_engine_progress(e, s, t->item, sp->fraction);
    }
    close(fd);
    while (waitpid(pid, &out->status, 0) < 0 && errno == EINTR)
        ;
    out->have_result = got == sizeof out->result;
    out->seconds = sl_now_seconds() - start;
}

static int move_with_reason(sl_engine *e, int s, const char *name, sl_ticket *t, int to,
                            const char *cls, const char *reason, sl_error *err)
{
    const char *stage = e->stages[s]->name;
    snprintf(t->cls, sizeof t->cls, "%s", cls);
    /* The error line, cut to the ticket's field (a long path makes it longer). */
    snprintf(t->reason, sizeof t->reason, "%.*s", (int)sizeof t->reason - 1, reason);
    if (to == SL_STATE_QUARANTINE)
        e->items_settled++; /* nothing more to do for it until it changes */
    sl_error werr;
    sl_error_init(&werr);
    /* Only a claim still ours is moved (a woken owner's late write must not recreate one
     * another worker finished meanwhile). Without space to rewrite the ticket, the
     * rename alone still records the state. */
    if (sl_engine_lease_renew(e, stage, name, t, &werr) == SL_E_LEASE_LOST)
        return 0;
    int rc = sl_queue_move(e->work, stage, name, SL_STATE_CLAIMED, to, err);
    return rc == SL_E_BUSY ? 0 : rc;
}

static int advance(sl_engine *e, int from, const sl_ticket *t, sl_error *err);

/* The stage process wrote into `staged`, a private sibling of `out_dir`; the record is
 * committed there, and the folder swapped in whole after the last fencing check: an owner
 * that lost its claim while it was frozen can then never empty or half-write the folder a
 * newer owner committed (at worst it swaps in a complete, identical one). */
static int commit_success(sl_engine *e, int s, const char *name, sl_ticket *t, sl_hash key,
                          int join_parts, const char *staged, const char *out_dir,
                          const child_outcome *o, int *taken_over, sl_error *err)
{
    *taken_over = 0;
    const sl_stage *stage = e->stages[s];
    int rc = sl_engine_lease_check(e, stage->name, name, t, err);
    char path[PATH_MAX];
    if (rc == 0) {
        char stats[256];
        int n = snprintf(stats, sizeof stats,
                         "{\"seconds\":%.3f,\"cpu_seconds\":%.3f,\"peak_rss_kb\":%ld,"
                         "\"threads\":%d",
                         o->seconds, o->result.cpu_seconds, o->result.max_rss_kb,
                         e->threads > 0 ? e->threads : omp_get_num_procs());
        /* A join's timings carry its parts' (their folders go once it is committed). */
        char *text = sl_engine_parts_stats(e, s, name, join_parts, stats, (size_t)n);
        sl_engine_path(path, sizeof path, "%s/_stats.json", staged);
        rc = text ? sl_write_file_atomic(path, text, strlen(text), err)
                  : sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
        free(text);
    }
    if (rc == 0) {
        sl_engine_path(path, sizeof path, "%s/%s", staged, SL_RECORD_FILE);
        rc = sl_record_commit(path, staged, NULL, stage->name, stage->version, t->item, key,
                              NULL, err);
    }
    if (rc == 0)
        rc = sl_engine_lease_check(e, stage->name, name, t, err);
    if (rc == 0) {
        char parent[PATH_MAX];
        snprintf(parent, sizeof parent, "%s", out_dir);
        char *slash = strrchr(parent, '/');
        if (slash)
            *slash = '\0';
        rc = sl_engine_swap_in(staged, out_dir, parent, err);
    }
    if (rc == 0) {
        /* The claim is rewritten only while it is still ours: an owner frozen during the
         * swap-in whose claim was taken over and released meanwhile must not re-create
         * it (it did: the woken owner then moved its own new ticket to done and logged
         * the stage done a second time; tests/faults/test_frozen_owner.sh). The
         * artifact is in place either way, and the new owner finds its record. */
        sl_hash_hex(key, t->key);
        t->cls[0] = t->reason[0] = '\0';
        rc = sl_engine_lease_renew(e, stage->name, name, t, err);
        if (rc == SL_E_LEASE_LOST)
            *taken_over = 1;
    }
    return rc;
}

/* Releases a committed claim: first the item's next step (the next stage's ticket, or
 * the publication after the last stage), then the claim moves to done. In that order an
 * unfinished item always has a ready or claimed ticket somewhere, so a run that finds
 * none can call the collection finished (docs/engine.md, "When a run is finished"). */
static int release_done(sl_engine *e, int s, const char *name, const sl_ticket *t,
                        int is_part, int *released, sl_error *err)
{
    /* A part's next step is its own stage's: the join, once every part is committed. */
    int rc = advance(e, is_part ? s : s + 1, t, err);
    sl_error merr;
    sl_error_init(&merr);
    int moved = sl_queue_move(e->work, e->stages[s]->name, name, SL_STATE_CLAIMED,
                              SL_STATE_DONE, &merr);
    if (released)
        *released = moved == 0;
    if (rc)
        return rc;
    if (moved == SL_E_BUSY)
        return 0; /* lost the lease after committing: the new owner finds the record */
    if (moved)
        sl_error_merge(err, &merr);
    return moved;
}

static int classify_signal(int sig)
{
    switch (sig) {
    case SIGSEGV: case SIGBUS: case SIGILL: case SIGFPE: case SIGABRT: case SIGSYS:
        return SL_E_INTERNAL;
    default:
        return SL_E_IO; /* SIGKILL from the OOM killer, SIGTERM from an operator */
    }
}

static int handle_failure(sl_engine *e, int s, const char *name, sl_ticket *t,
                          const child_outcome *o, sl_error *item_err, sl_error *err)
{
    const char *stage = e->stages[s]->name;
    int code = item_err->code;
    char line[1500];
    if (o->interrupted && (code == SL_E_INTERRUPTED || !o->have_result))
        return move_with_reason(e, s, name, t, SL_STATE_READY, "", "", err);
    if (o->lease_lost) {
        e->counts.transient++;
        SL_LOG(SL_LOG_WARN, stage, t->item, "lease lost: another worker owns the item now");
        return 0;
    }
    if (code == SL_OK) { /* died without a word */
        if (o->timed_out)
            code = sl_error_set(item_err, SL_E_INTERNAL, 0, t->source,
                                "timed out after %lld s", (long long)e->item_timeout_s);
        else if (WIFSIGNALED(o->status))
            code = sl_error_set(item_err, classify_signal(WTERMSIG(o->status)), 0, t->source,
                                "killed by signal %d (%s)", WTERMSIG(o->status),
                                strsignal(WTERMSIG(o->status)));
        else
            code = sl_error_set(item_err, SL_E_INTERNAL, 0, t->source,
                                "stage process exited with status %d and no result",
                                WEXITSTATUS(o->status));
    }
    sl_error_format(item_err, line, sizeof line);
    sl_log_event("stage_failed", stage, t->item, o->seconds, item_err, NULL);
    switch (sl_error_class_of(code)) {
    case SL_CLASS_BADINPUT:
        e->counts.quarantined++;
        SL_LOG(SL_LOG_ERROR, stage, t->item, "quarantined: %s", line);
        return move_with_reason(e, s, name, t, SL_STATE_QUARANTINE, "badinput", line, err);
    case SL_CLASS_TRANSIENT:
        e->counts.transient++;
        SL_LOG(SL_LOG_ERROR, stage, t->item, "failed (will retry on the next run): %s", line);
        return move_with_reason(e, s, name, t, SL_STATE_FAILED, "transient", line, err);
    case SL_CLASS_STORAGE:
    case SL_CLASS_CONFIG:
    case SL_CLASS_USAGE:
        e->stop = 1;
        sl_error_merge(&e->storage_error, item_err);
        SL_LOG(SL_LOG_ERROR, stage, t->item, "stopping: %s", line);
        return move_with_reason(e, s, name, t, SL_STATE_FAILED, "storage", line, err);
    default:
        break;
    }
    t->crashes++;
    if (t->crashes >= e->max_crashes) {
        e->counts.bugs++;
        SL_LOG(SL_LOG_ERROR, stage, t->item, "quarantined as a scanlod bug after %d crashes: %s",
               t->crashes, line);
        return move_with_reason(e, s, name, t, SL_STATE_QUARANTINE, "bug", line, err);
    }
    SL_LOG(SL_LOG_WARN, stage, t->item, "crashed, retrying once: %s", line);
    return move_with_reason(e, s, name, t, SL_STATE_READY, "crash", line, err);
}

/* Reconciles the item from stage `from` on: after stage s committed, from = s + 1
 * enqueues the next stage or publishes the item. */
static int advance(sl_engine *e, int from, const sl_ticket *t, sl_error *err)
{
    sl_error aerr;
    sl_error_init(&aerr);
    int rc = sl_engine_reconcile(e, t->item, t->source, from, NULL, &aerr);
    if (rc == 0)
        return 0;
    char line[1500];
    SL_LOG(SL_LOG_ERROR, "engine", t->item, "cannot go on: %s",
           sl_error_format(&aerr, line, sizeof line));
    if (sl_error_class_of(rc) == SL_CLASS_STORAGE) {
        sl_error_merge(err, &aerr);
        return rc;
    }
    e->counts.transient++;
    e->counts.untracked++;
    /* Leave the item retryable: the next run's scan finds the last stage done and
     * publishes again (and this run's exit code says it is not done). */
    return 0;
}

static int item_paths(sl_engine *e, int s, const char *name, const char *ticket,
                      const sl_ticket *t, char *source, char *in_dir, char *out_dir,
                      sl_error *err)
{
    if (sl_engine_path(source, PATH_MAX, "%s/%s", e->input, t->source) ||
        sl_artifact_dir(e, s, name, out_dir, PATH_MAX) ||
        (s > 0 && sl_artifact_dir(e, s - 1, ticket, in_dir, PATH_MAX)))
        return sl_error_set(err, SL_E_LIMIT, 0, t->source, "path too long");
    return 0;
}

int sl_engine_process(sl_engine *e, int s, const char *name, sl_ticket *t, sl_error *err)
{
    const sl_stage *stage = e->stages[s];
    char source[PATH_MAX], in_dir[PATH_MAX] = "", out_dir[PATH_MAX], record[PATH_MAX];
    /* A part's claim (docs/engine.md, "Parts") reads the item's upstream like its join. */
    char ticket[SL_TICKET_NAME_MAX + 1];
    int part = -1;
    if (!sl_part_parse(name, ticket, sizeof ticket, &part))
        snprintf(ticket, sizeof ticket, "%s", name);
    int rc = item_paths(e, s, name, ticket, t, source, in_dir, out_dir, err);
    if (rc)
        return move_with_reason(e, s, name, t, SL_STATE_QUARANTINE, "badinput", err->message, err);

    /* The key from the current upstream; if the upstream is gone or changed, this ticket
     * is stale: drop it and let reconciliation decide what comes first. */
    sl_hash upstream;
    sl_error uerr;
    sl_error_init(&uerr);
    rc = sl_upstream_chain(e, ticket, t->source, s, 1, &upstream, &uerr);
    sl_hash key = sl_stage_key(stage->name, stage->version, e->config_hash[s], upstream);
    int parts = sl_engine_parts(e, s, t->source);
    if (rc == 0 && !sl_engine_parts_ready(e, s, ticket, part, parts, &key))
        rc = SL_E_CORRUPT; /* a stale part, or a join whose parts are not all committed */
    if (rc) {
        char path[PATH_MAX];
        sl_queue_path(path, sizeof path, e->work, stage->name, SL_STATE_CLAIMED, name);
        unlink(path);
        if (access(source, F_OK) != 0) {
            SL_LOG(SL_LOG_WARN, stage->name, t->item, "input vanished; dropped from the queue");
            return 0;
        }
        return advance(e, s, t, err);
    }
    sl_engine_path(record, sizeof record, "%s/%s", out_dir, SL_RECORD_FILE);
    sl_error verr;
    sl_error_init(&verr);
    if (sl_record_check(record, out_dir, &key, NULL, &verr) == 0) {
        e->counts.reused++; /* someone finished it meanwhile */
        /* Done already: the run that took this claim over (this one was frozen, say)
         * finished the stage and said so; nobody is to say it again. */
        int was_done = sl_queue_find(e->work, stage->name, name) == SL_STATE_DONE;
        sl_hash_hex(key, t->key);
        sl_error perr;
        sl_error_init(&perr);
        if (sl_engine_lease_renew(e, stage->name, name, t, &perr) == SL_E_LEASE_LOST)
            return 0; /* taken over again meanwhile: the new owner releases it */
        int released = 0;
        rc = release_done(e, s, name, t, part >= 0, &released, err);
        /* The owner that committed lost its claim before moving it to done and said
         * nothing; whoever moves it says the stage is done, once. */
        if (released && !was_done)
            sl_log_event("stage_done", stage->name, t->item, -1, NULL, "\"adopted\":true");
        return rc;
    }
    if (!sl_engine_admitted(e, s, t, source))
        return move_with_reason(e, s, name, t, SL_STATE_FAILED, "memory", e->admission, err);
    /* The claim is fenced by its lease right before the artifact folder is emptied: an
     * owner frozen since it claimed (SIGSTOP, a Slurm suspend, an NFS stall) whose claim
     * was taken over must not empty the folder the new owner has committed into (seen in
     * test_liveness: the woken run wiped a committed artifact, which verify, finding no
     * record, could not flag). */
    sl_error lerr;
    sl_error_init(&lerr);
    if (sl_engine_lease_renew(e, stage->name, name, t, &lerr) != 0) {
        e->counts.transient++;
        SL_LOG(SL_LOG_WARN, stage->name, t->item, "lease lost: another worker owns the item now");
        return 0;
    }
    char staged[PATH_MAX];
    rc = sl_engine_staged_path(e, out_dir, staged, err);
    if (rc == 0)
        rc = sl_mkdirs(staged, err);
    if (rc == 0)
        rc = sl_remove_dir_contents(staged, err);
    if (rc) { /* cannot even prepare the artifact directory (full disk, permissions) */
        sl_error prep_err = *err;
        child_outcome none;
        memset(&none, 0, sizeof none);
        handle_failure(e, s, name, t, &none, &prep_err, err);
        return rc;
    }

    if (part >= 0)
        SL_LOG(SL_LOG_INFO, stage->name, t->item, "start part %d of %d (attempt %d)", part + 1,
               parts, t->attempt);
    else
        SL_LOG(SL_LOG_INFO, stage->name, t->item, "start (attempt %d)", t->attempt);
    shared_progress *sp = mmap(NULL, sizeof *sp, PROT_READ | PROT_WRITE,
                               MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    int fds[2];
    if (sp == MAP_FAILED || pipe(fds) != 0) {
        if (sp != MAP_FAILED)
            munmap(sp, sizeof *sp);
        return sl_error_errno(err, errno, NULL, "pipe/mmap for the stage process");
    }
    memset(sp, 0, sizeof *sp);
    fflush(NULL);
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid == 0) {
        close(fds[0]);
        claim_work w = {s, t->item, source, s > 0 ? in_dir : NULL, staged, part, parts};
        child_main(e, &w, sp, fds[1], parent);
    }
    close(fds[1]);
    if (pid < 0) {
        close(fds[0]);
        munmap(sp, sizeof *sp);
        return sl_error_errno(err, errno, NULL, "fork");
    }
    child_outcome outcome;
    memset(&outcome, 0, sizeof outcome);
    supervise(e, s, name, t, pid, fds[0], sp, &outcome);
    munmap(sp, sizeof *sp);

    sl_error item_err;
    sl_error_init(&item_err);
    if (outcome.have_result)
        item_err = outcome.result.err;
    int ok = outcome.have_result && item_err.code == SL_OK && WIFEXITED(outcome.status) &&
             WEXITSTATUS(outcome.status) == 0 && !outcome.lease_lost;
    if (ok) {
        int taken_over = 0;
        rc = commit_success(e, s, name, t, key, part < 0 ? parts : 0, staged, out_dir,
                            &outcome, &taken_over, &item_err);
        if (taken_over) { /* committed; the claim and what follows are the new owner's */
            e->counts.ran++;
            SL_LOG(SL_LOG_WARN, stage->name, t->item,
                   "committed, but the claim was taken over meanwhile");
            return 0;
        }
        if (rc == 0) {
            e->counts.ran++;
            int released = 0;
            rc = release_done(e, s, name, t, part >= 0, &released, err);
            /* Said only by the owner that moved the claim to done: an owner that lost
             * its lease after the commit (the record is the same either way) is silent,
             * so the log shows each stage done once. */
            if (part < 0 && parts > 1)
                sl_engine_parts_remove(e, s, ticket, parts); /* joined: no longer read */
            if (released) {
                char extra[160];
                snprintf(extra, sizeof extra, "\"cpu_seconds\":%.3f,\"peak_rss_kb\":%ld",
                         outcome.result.cpu_seconds, outcome.result.max_rss_kb);
                if (part >= 0)
                    snprintf(extra + strlen(extra), sizeof extra - strlen(extra),
                             ",\"part\":%d,\"parts\":%d", part, parts);
                sl_log_event("stage_done", stage->name, t->item, outcome.seconds, NULL, extra);
                SL_LOG(SL_LOG_INFO, stage->name, t->item, "done in %.2f s, peak RSS %ld MiB",
                       outcome.seconds, outcome.result.max_rss_kb / 1024);
            } else {
                SL_LOG(SL_LOG_WARN, stage->name, t->item,
                       "committed, but the claim was taken over meanwhile");
            }
            return rc;
        }
        if (rc == SL_E_LEASE_LOST)
            outcome.lease_lost = 1;
    }
    sl_error ignored;
    sl_error_init(&ignored);
    sl_remove_tree(staged, 0, &ignored); /* never committed: nothing in it is trusted */
    sl_error_context(&item_err, stage->name, t->item);
    return handle_failure(e, s, name, t, &outcome, &item_err, err);
}
