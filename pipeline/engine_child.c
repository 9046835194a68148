/* Running one stage of one item in a child process, and what its outcome means.
 *
 * Isolation (reliability rule 13): OpenMP threads share fate, so each (item, stage) runs
 * in a fork()ed child with its own address-space limit; a crash or an OOM kill costs that
 * item only. The child dies with its parent (PR_SET_PDEATHSIG), so a kill -9 of the
 * worker never leaves an orphan writing into the work dir. The parent renews the lease,
 * forwards interrupts, enforces the timeout and draws the progress bar meanwhile.
 *
 * What runs inside the child is engine_stage_child.c; what the end of the child means for
 * the ticket (the failure classes) is decided in engine_outcome.c.
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
#include "core/memory.h"
#include "core/progress.h"

static void supervise(sl_engine *e, int s, const char *name, sl_ticket *t, pid_t pid, int fd,
                      shared_progress *sp, child_result *result, sl_child_outcome *out)
{
    double start = sl_now_seconds(), last_renew = start;
    uint64_t oom_kills = sl_memory_oom_kills();
    size_t got = 0;
    char *buf = (char *)result;
    for (;;) {
        struct pollfd pfd = {fd, POLLIN, 0};
        int ready = poll(&pfd, 1, 200);
        if (ready > 0) {
            ssize_t r = read(fd, buf + got, sizeof *result - got);
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
    struct rusage ru; /* wait4: the peak RSS of a child that was killed, too */
    memset(&ru, 0, sizeof ru);
    while (wait4(pid, &out->status, 0, &ru) < 0 && errno == EINTR)
        ;
    out->max_rss_kb = ru.ru_maxrss;
    out->oom_killed = sl_memory_oom_kills() > oom_kills;
    out->have_result = got == sizeof *result;
    out->seconds = sl_now_seconds() - start;
}

static int advance(sl_engine *e, int from, const sl_ticket *t, sl_error *err);

/* The stage process wrote into `staged`, a private sibling of `out_dir`; the record is
 * committed there, and the folder swapped in whole after the last fencing check: an owner
 * that lost its claim while it was frozen can then never empty or half-write the folder a
 * newer owner committed (at worst it swaps in a complete, identical one). */
/* The head of a stage's _stats.json (its timings.json entry, unclosed): wall and CPU
 * seconds, peak memory, threads, and the stage's own timings (`_timings.json`, which the
 * stage's child wrote beside its artifacts: figures that differ run to run, so never part
 * of an artifact or report.json). NULL when out of memory. */
static char *stats_head(const char *staged, double seconds, const child_result *r, int threads)
{
    char path[PATH_MAX], *detail = NULL, *head = NULL;
    size_t n = 0;
    sl_error ignored;
    sl_error_init(&ignored);
    if (sl_engine_path(path, sizeof path, "%s/_timings.json", staged) == 0 &&
        access(path, F_OK) == 0 && sl_read_file(path, 1 << 20, &detail, &n, &ignored) != 0)
        detail = NULL; /* diagnostics: left out when unreadable */
    if (asprintf(&head, "{\"seconds\":%.3f,\"cpu_seconds\":%.3f,\"peak_rss_kb\":%ld,"
                        "\"threads\":%d%s%.*s",
                 seconds, r->cpu_seconds, r->max_rss_kb, threads,
                 detail ? ",\"detail\":" : "", detail ? (int)n : 0, detail ? detail : "") < 0)
        head = NULL;
    free(detail);
    return head;
}

static int commit_success(sl_engine *e, int s, const char *name, sl_ticket *t, sl_hash key,
                          int join_parts, const char *staged, const char *out_dir,
                          const sl_child_outcome *o, const child_result *r, int *taken_over,
                          sl_error *err)
{
    *taken_over = 0;
    const sl_stage *stage = e->stages[s];
    int rc = sl_engine_lease_check(e, stage->name, name, t, err);
    char path[PATH_MAX];
    if (rc == 0) {
        char *head = stats_head(staged, o->seconds, r,
                                e->threads > 0 ? e->threads : omp_get_num_procs());
        /* A join's timings carry its parts' (their folders go once it is committed). */
        char *text = head ? sl_engine_parts_stats(e, s, name, join_parts, head, strlen(head))
                          : NULL;
        sl_engine_path(path, sizeof path, "%s/_stats.json", staged);
        rc = text ? sl_write_file_atomic(path, text, strlen(text), err)
                  : sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
        free(text);
        free(head);
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

/* One claim of stage s as sl_engine_process works on it. */
typedef struct claim_ctx {
    char source[PATH_MAX], in_dir[PATH_MAX], out_dir[PATH_MAX];
    char ticket[SL_TICKET_NAME_MAX + 1]; /* the item's ticket (a part's is its join's) */
    int part, parts;                      /* part -1: the item's stage whole (or the join) */
    sl_hash key, stage_key;               /* the artifact's key (a join's chains its parts) */
} claim_ctx;

/* The claim's paths, key and split. 1: go on; 0: the claim was stale, a part of another
 * split, or its input is gone, and has been dealt with (*rc says how that went). */
static int resolve_claim(sl_engine *e, int s, const char *name, sl_ticket *t, claim_ctx *c,
                         int *rc, sl_error *err)
{
    const sl_stage *stage = e->stages[s];
    /* A part's claim (docs/engine.md, "Parts") reads the item's upstream like its join. */
    c->in_dir[0] = '\0';
    c->part = -1;
    if (!sl_part_parse(name, c->ticket, sizeof c->ticket, &c->part))
        snprintf(c->ticket, sizeof c->ticket, "%s", name);
    *rc = item_paths(e, s, name, c->ticket, t, c->source, c->in_dir, c->out_dir, err);
    if (*rc) {
        *rc = sl_engine_move_with_reason(e, s, name, t, SL_STATE_QUARANTINE, "badinput",
                                         err->message, err);
        return 0;
    }
    /* The key from the current upstream; if the upstream is gone or changed, this ticket
     * is stale: drop it and let reconciliation decide what comes first. */
    sl_hash upstream;
    sl_error uerr;
    sl_error_init(&uerr);
    int stale = sl_upstream_chain(e, c->ticket, t->source, s, 1, &upstream, &uerr) != 0;
    c->key = c->stage_key = sl_stage_key(stage->name, stage->version,
                                         sl_engine_stage_config_hash(e, s, t->item), upstream);
    c->parts = sl_engine_item_parts(e, s, c->ticket, t->source, c->stage_key, name);
    /* A part runs as a part of the item's split only (its ticket says which it is of). */
    int other_split = !stale && c->part >= 0 &&
                      ((t->parts >= 2 && t->parts != c->parts) || c->part >= c->parts);
    if (!stale && !other_split &&
        !sl_engine_parts_ready(e, s, c->ticket, c->part, c->parts, &c->key))
        stale = 1; /* a join whose parts are not all committed */
    if (!stale && !other_split)
        return 1;
    char path[PATH_MAX];
    sl_queue_path(path, sizeof path, e->work, stage->name, SL_STATE_CLAIMED, name);
    if (other_split)
        sl_engine_part_drop(e, s, c->ticket, c->part, c->parts);
    else
        unlink(path); /* stale: reconciliation decides what comes first */
    if (access(c->source, F_OK) != 0) {
        SL_LOG(SL_LOG_WARN, stage->name, t->item, "input vanished; dropped from the queue");
        *rc = 0;
        return 0;
    }
    *rc = advance(e, s, t, err);
    return 0;
}

/* Someone committed the claim's artifact meanwhile: the claim is released as done. 1 (and
 * *rc) when that was so, else 0. */
static int committed_meanwhile(sl_engine *e, int s, const char *name, sl_ticket *t,
                               const claim_ctx *c, int *rc, sl_error *err)
{
    const sl_stage *stage = e->stages[s];
    char record[PATH_MAX];
    sl_engine_path(record, sizeof record, "%s/%s", c->out_dir, SL_RECORD_FILE);
    sl_error verr;
    sl_error_init(&verr);
    if (sl_record_check(record, c->out_dir, &c->key, NULL, &verr) != 0)
        return 0;
    e->counts.reused++;
    /* Done already: the run that took this claim over (this one was frozen, say) finished
     * the stage and said so; nobody is to say it again. */
    int was_done = sl_queue_find(e->work, stage->name, name) == SL_STATE_DONE;
    sl_hash_hex(c->key, t->key);
    sl_error perr;
    sl_error_init(&perr);
    *rc = 0;
    if (sl_engine_lease_renew(e, stage->name, name, t, &perr) == SL_E_LEASE_LOST)
        return 1; /* taken over again meanwhile: the new owner releases it */
    int released = 0;
    *rc = release_done(e, s, name, t, c->part >= 0, &released, err);
    /* The owner that committed lost its claim before moving it to done and said nothing;
     * whoever moves it says the stage is done, once. */
    if (released && !was_done)
        sl_log_event("stage_done", stage->name, t->item, -1, NULL, "\"adopted\":true");
    return 1;
}

/* The staging folder of the claim, fenced by its lease right before it is emptied: an
 * owner frozen since it claimed (SIGSTOP, a Slurm suspend, an NFS stall) whose claim was
 * taken over must not empty the folder the new owner has committed into (seen in
 * test_liveness: the woken run wiped a committed artifact, which verify, finding no
 * record, could not flag). 1: ready in `staged`; 0: not to run (*rc says why). */
static int prepare_staging(sl_engine *e, int s, const char *name, sl_ticket *t,
                           const claim_ctx *c, char staged[PATH_MAX], int *rc, sl_error *err)
{
    const sl_stage *stage = e->stages[s];
    if (!sl_engine_admitted(e, s, t, c->source)) {
        *rc = sl_engine_move_with_reason(e, s, name, t, SL_STATE_FAILED, "memory",
                                         e->admission, err);
        return 0;
    }
    sl_error lerr;
    sl_error_init(&lerr);
    if (sl_engine_lease_renew(e, stage->name, name, t, &lerr) != 0) {
        e->counts.transient++;
        SL_LOG(SL_LOG_WARN, stage->name, t->item, "lease lost: another worker owns the item now");
        *rc = 0;
        return 0;
    }
    *rc = sl_engine_staged_path(e, c->out_dir, staged, err);
    if (*rc == 0)
        *rc = sl_mkdirs(staged, err);
    if (*rc == 0)
        *rc = sl_remove_dir_contents(staged, err);
    if (*rc) { /* cannot even prepare the artifact directory (full disk, permissions) */
        sl_error prep_err = *err;
        sl_child_outcome none;
        memset(&none, 0, sizeof none);
        sl_engine_handle_failure(e, s, name, t, &none, &prep_err, err);
        return 0;
    }
    return 1;
}

/* The stage run in a child process on the claim, supervised to its end. */
static int run_child(sl_engine *e, int s, const char *name, sl_ticket *t, const claim_ctx *c,
                     const char *staged, sl_child_outcome *outcome, child_result *result,
                     sl_error *err)
{
    const sl_stage *stage = e->stages[s];
    if (c->part >= 0)
        SL_LOG(SL_LOG_INFO, stage->name, t->item, "start part %d of %d (attempt %d)",
               c->part + 1, c->parts, t->attempt);
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
        claim_work w = {s, t->item, c->source, s > 0 ? c->in_dir : NULL, staged, c->part,
                        c->parts};
        sl_engine_child_main(e, &w, sp, fds[1], parent);
    }
    close(fds[1]);
    if (pid < 0) {
        close(fds[0]);
        munmap(sp, sizeof *sp);
        return sl_error_errno(err, errno, NULL, "fork");
    }
    memset(outcome, 0, sizeof *outcome);
    memset(result, 0, sizeof *result);
    supervise(e, s, name, t, pid, fds[0], sp, result, outcome);
    munmap(sp, sizeof *sp);
    return 0;
}

/* A stage run that succeeded: committed, released as done, said once. 1 when committed
 * (*rc: how the release went), 0 when the commit failed (item_err says why; a lost lease
 * marks the outcome): then it is a failure like any. */
static int finish_success(sl_engine *e, int s, const char *name, sl_ticket *t,
                          const claim_ctx *c, const char *staged, sl_child_outcome *outcome,
                          const child_result *result, int *rc, sl_error *item_err,
                          sl_error *err)
{
    const sl_stage *stage = e->stages[s];
    int taken_over = 0;
    *rc = commit_success(e, s, name, t, c->key, c->part < 0 ? c->parts : 0, staged,
                         c->out_dir, outcome, result, &taken_over, item_err);
    if (taken_over) { /* committed; the claim and what follows are the new owner's */
        e->counts.ran++;
        SL_LOG(SL_LOG_WARN, stage->name, t->item,
               "committed, but the claim was taken over meanwhile");
        *rc = 0;
        return 1;
    }
    if (*rc) {
        if (*rc == SL_E_LEASE_LOST)
            outcome->lease_lost = 1;
        return 0;
    }
    e->counts.ran++;
    int released = 0;
    *rc = release_done(e, s, name, t, c->part >= 0, &released, err);
    /* Joined (or run whole): no part is read any more. A part committed after its stage
     * was (another split finished first) goes too. */
    if (c->part < 0 || sl_engine_part_committed(e, s, c->ticket, c->stage_key))
        sl_engine_parts_prune(e, s, c->ticket, 0, sl_engine_parts(e, s, t->source));
    /* Said only by the owner that moved the claim to done: an owner that lost its lease
     * after the commit (the record is the same either way) is silent, so the log shows
     * each stage done once. */
    if (!released) {
        SL_LOG(SL_LOG_WARN, stage->name, t->item,
               "committed, but the claim was taken over meanwhile");
        return 1;
    }
    char extra[160];
    snprintf(extra, sizeof extra, "\"cpu_seconds\":%.3f,\"peak_rss_kb\":%ld",
             result->cpu_seconds, result->max_rss_kb);
    if (c->part >= 0)
        snprintf(extra + strlen(extra), sizeof extra - strlen(extra),
                 ",\"part\":%d,\"parts\":%d", c->part, c->parts);
    sl_log_event("stage_done", stage->name, t->item, outcome->seconds, NULL, extra);
    SL_LOG(SL_LOG_INFO, stage->name, t->item, "done in %.2f s, peak RSS %ld MiB",
           outcome->seconds, result->max_rss_kb / 1024);
    return 1;
}

int sl_engine_process(sl_engine *e, int s, const char *name, sl_ticket *t, sl_error *err)
{
    claim_ctx c;
    char staged[PATH_MAX];
    int rc = 0;
    if (!resolve_claim(e, s, name, t, &c, &rc, err) ||
        committed_meanwhile(e, s, name, t, &c, &rc, err) ||
        !prepare_staging(e, s, name, t, &c, staged, &rc, err))
        return rc;
    sl_child_outcome outcome;
    child_result result;
    if ((rc = run_child(e, s, name, t, &c, staged, &outcome, &result, err)))
        return rc;
    sl_error item_err;
    sl_error_init(&item_err);
    if (outcome.have_result)
        item_err = result.err;
    int ok = outcome.have_result && item_err.code == SL_OK && WIFEXITED(outcome.status) &&
             WEXITSTATUS(outcome.status) == 0 && !outcome.lease_lost;
    if (ok && finish_success(e, s, name, t, &c, staged, &outcome, &result, &rc, &item_err, err))
        return rc;
    sl_error ignored;
    sl_error_init(&ignored);
    sl_remove_tree(staged, 0, &ignored); /* never committed: nothing in it is trusted */
    sl_error_context(&item_err, e->stages[s]->name, t->item);
    return sl_engine_handle_failure(e, s, name, t, &outcome, &item_err, err);
}
