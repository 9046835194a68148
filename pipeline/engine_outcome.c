/* What the end of a stage process means for its ticket: the failure classes
 * (docs/engine.md, "Failure classes").
 *
 *   bad input (BADINPUT/LIMIT/..)      -> quarantine at once, with the reason
 *   interrupted                        -> ready again (not the item's fault)
 *   ENOSPC, EIO, out of memory, killed -> failed (retried by the next run), never quarantined
 *   crash/abort/timeout/internal       -> ready again, until max_crashes: then quarantine
 *                                         flagged as a bug
 *   storage needs a human              -> failed, and the worker stops (exit 74)
 *
 * Out of memory has many faces, and each is out of memory, never a crash of ours: an
 * allocation that fails (SL_E_NOMEM), a std::bad_alloc nobody caught (the terminate
 * handler reports it: engine_child.c), a mapping the loader is refused
 * (shim/oiio_loader.c), and the kernel's OOM killer, whose SIGKILL the parent sees. A
 * SIGKILL the engine did not send is taken for the OOM killer; the cgroup's oom_kill
 * count says when it surely was. And a quarantine that was a memory failure after all
 * heals (sl_engine_quarantine_holds): the next run retries it.
 */
#include "pipeline/engine_internal.h"

#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>

#include "core/log.h"

int sl_engine_move_with_reason(sl_engine *e, int s, const char *name, sl_ticket *t, int to,
                               const char *cls, const char *reason, sl_error *err)
{
    const char *stage = e->stages[s]->name;
    snprintf(t->cls, sizeof t->cls, "%s", cls);
    /* The error line, cut to the ticket's field (a long path makes it longer). */
    snprintf(t->reason, sizeof t->reason, "%.*s", (int)sizeof t->reason - 1, reason);
    /* A failed ticket waits for another run (reconciliation in this one leaves it). */
    snprintf(t->run, sizeof t->run, "%s", to == SL_STATE_FAILED ? sl_log_run_id() : "");
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

/* Why a stage process that ended without a result ended: its error, in `item_err`. */
static int death_error(const sl_engine *e, const sl_ticket *t, const sl_child_outcome *o,
                       sl_error *item_err)
{
    if (o->timed_out)
        return sl_error_set(item_err, SL_E_INTERNAL, 0, t->source, "timed out after %lld s",
                            (long long)e->item_timeout_s);
    if (!WIFSIGNALED(o->status))
        return sl_error_set(item_err, SL_E_INTERNAL, 0, t->source,
                            "stage process exited with status %d and no result",
                            WEXITSTATUS(o->status));
    int sig = WTERMSIG(o->status);
    if (sig == SIGKILL && o->oom_killed)
        return sl_error_set(item_err, SL_E_NOMEM, 0, t->source,
                            "killed by the kernel's out-of-memory killer (the cgroup counted "
                            "an OOM kill; peak RSS %ld MiB)", o->max_rss_kb / 1024);
    if (sig == SIGKILL) /* we kill only on a timeout or a lost lease, said above */
        return sl_error_set(item_err, SL_E_NOMEM, 0, t->source,
                            "killed by SIGKILL, not sent by scanlod: taken for the kernel's "
                            "out-of-memory killer (peak RSS %ld MiB)", o->max_rss_kb / 1024);
    switch (sig) {
    case SIGSEGV: case SIGBUS: case SIGILL: case SIGFPE: case SIGABRT: case SIGSYS:
        return sl_error_set(item_err, SL_E_INTERNAL, 0, t->source, "killed by signal %d (%s)",
                            sig, strsignal(sig));
    default: /* SIGTERM from an operator, SIGHUP: not the item's fault */
        return sl_error_set(item_err, SL_E_IO, 0, t->source, "killed by signal %d (%s)", sig,
                            strsignal(sig));
    }
}

/* A bad-input quarantine is a statement about the input: it names the input file, not
 * the work artifact a later stage found the fault in (a one-point cloud's error named
 * range's points.slpts). */
static void name_the_input(const sl_engine *e, const sl_ticket *t, sl_error *item_err)
{
    size_t n = strlen(e->work);
    if (item_err->file[0] && !(strncmp(item_err->file, e->work, n) == 0 &&
                               (item_err->file[n] == '/' || item_err->file[n] == '\0')))
        return;
    char source[PATH_MAX];
    if (sl_engine_path(source, sizeof source, "%s/%s", e->input, t->source) == 0 &&
        strlen(source) < sizeof item_err->file)
        memcpy(item_err->file, source, strlen(source) + 1);
}

int sl_engine_handle_failure(sl_engine *e, int s, const char *name, sl_ticket *t,
                             const sl_child_outcome *o, sl_error *item_err, sl_error *err)
{
    const char *stage = e->stages[s]->name;
    int code = item_err->code;
    char line[1500];
    if (o->interrupted && (code == SL_E_INTERRUPTED || !o->have_result))
        return sl_engine_move_with_reason(e, s, name, t, SL_STATE_READY, "", "", err);
    if (o->lease_lost) {
        e->counts.transient++;
        SL_LOG(SL_LOG_WARN, stage, t->item, "lease lost: another worker owns the item now");
        return 0;
    }
    if (code == SL_OK) /* died without a word */
        code = death_error(e, t, o, item_err);
    if (sl_error_class_of(code) == SL_CLASS_BADINPUT)
        name_the_input(e, t, item_err);
    sl_error_format(item_err, line, sizeof line);
    sl_log_event("stage_failed", stage, t->item, o->seconds, item_err, NULL);
    switch (sl_error_class_of(code)) {
    case SL_CLASS_BADINPUT:
        e->counts.quarantined++;
        SL_LOG(SL_LOG_ERROR, stage, t->item, "quarantined: %s", line);
        return sl_engine_move_with_reason(e, s, name, t, SL_STATE_QUARANTINE, "badinput", line,
                                          err);
    case SL_CLASS_TRANSIENT:
        e->counts.transient++;
        SL_LOG(SL_LOG_ERROR, stage, t->item, "failed (will retry on the next run): %s", line);
        return sl_engine_move_with_reason(e, s, name, t, SL_STATE_FAILED,
                                          code == SL_E_NOMEM ? "memory" : "transient", line, err);
    case SL_CLASS_STORAGE:
    case SL_CLASS_CONFIG:
    case SL_CLASS_USAGE:
        e->stop = 1;
        sl_error_merge(&e->storage_error, item_err);
        SL_LOG(SL_LOG_ERROR, stage, t->item, "stopping: %s", line);
        return sl_engine_move_with_reason(e, s, name, t, SL_STATE_FAILED, "storage", line, err);
    default:
        break;
    }
    t->crashes++;
    if (t->crashes >= e->max_crashes) {
        e->counts.bugs++;
        SL_LOG(SL_LOG_ERROR, stage, t->item, "quarantined as a scanlod bug after %d crashes: %s",
               t->crashes, line);
        return sl_engine_move_with_reason(e, s, name, t, SL_STATE_QUARANTINE, "bug", line, err);
    }
    SL_LOG(SL_LOG_WARN, stage, t->item, "crashed, retrying once: %s", line);
    return sl_engine_move_with_reason(e, s, name, t, SL_STATE_READY, "crash", line, err);
}

/* An error line that says the process ran out of memory, in any of the words our code,
 * the C++ runtime and the dynamic loader use for it. */
static int says_out_of_memory(const char *reason)
{
    static const char *const signs[] = {"out of memory", "bad_alloc", "cannot map zero-fill",
                                        "failed to map segment", "annot allocate memory"};
    for (size_t i = 0; i < sizeof signs / sizeof signs[0]; i++)
        if (strstr(reason, signs[i]))
            return 1;
    return 0;
}

int sl_engine_quarantine_holds(const sl_engine *e, const sl_ticket *t, char *why, size_t size)
{
    if (strcmp(t->cls, "badinput") && strcmp(t->cls, "bug")) {
        snprintf(why, size, "quarantined as '%s', a failure that is retried", t->cls);
        return 0;
    }
    if (strcmp(t->cls, "bug"))
        return 1; /* bad input stays until its input, config or code changes */
    if (says_out_of_memory(t->reason)) {
        snprintf(why, size, "quarantined as a scanlod bug, but it ran out of memory");
        return 0;
    }
    if (t->memory_limit_mb < 0) {
        snprintf(why, size, "quarantined as a scanlod bug by a build that took some memory "
                            "failures for crashes: tried once more");
        return 0;
    }
    if (t->memory_limit_mb > 0 &&
        (e->memory_limit_mb == 0 || e->memory_limit_mb > t->memory_limit_mb)) {
        snprintf(why, size, "crashed under [run] memory_limit_mb = %lld, which may have been "
                            "memory; the limit is now %lld (0: none)",
                 (long long)t->memory_limit_mb, (long long)e->memory_limit_mb);
        return 0;
    }
    return 1;
}
