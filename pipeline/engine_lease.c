/* Who owns what: this process's identity, the leases of claimed tickets and the scan's
 * announcement (docs/engine.md, "Leases and
 * liveness"). The bottom of the engine: the worker loop, the stage runner and the scan
 * all ask it, and it asks none of them.
 *
 * Liveness: a claim whose lease expired is reclaimed, on any host: a live pid is not a
 * live owner once it stopped renewing (SIGSTOP, a Slurm suspend, a process stuck in
 * NFS D-state). On the same host (and boot) a claim whose pid is gone -- or belongs to a
 * newer process -- is also reclaimed at once, without waiting for its lease; across
 * hosts a pid is never judged. Each claim bumps the ticket's epoch (the fencing token)
 * and draws a fresh nonce; the committing worker checks both before it publishes
 * anything, so an owner that wakes up after its lease was taken commits nothing.
 */
#include "pipeline/engine_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "core/log.h"
#include "core/progress.h"

#define SCAN_QUEUE "_scan"

unsigned long long sl_process_start_time(long pid)
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
    id->pid_start = sl_process_start_time(id->pid);
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
    unsigned long long start = sl_process_start_time(t->pid);
    if (start == 0)
        return 0;
    return t->pid_start == 0 || start == t->pid_start;
}

void sl_random_nonce(char out[33])
{
    unsigned char bytes[16];
    FILE *f = fopen("/dev/urandom", "rb");
    size_t n = f ? fread(bytes, 1, sizeof bytes, f) : 0;
    if (f)
        fclose(f);
    if (n != sizeof bytes) { /* no urandom: time and pid are unique enough per claim */
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        sl_hash h = sl_hash_bytes(&ts, sizeof ts);
        memcpy(bytes, &h, sizeof bytes);
        bytes[0] ^= (unsigned char)getpid();
    }
    for (int i = 0; i < 16; i++)
        snprintf(out + 2 * i, 3, "%02x", bytes[i]);
}

void sl_engine_stamp_lease(const sl_engine *e, sl_ticket *t)
{
    snprintf(t->host, sizeof t->host, "%s", e->self.host);
    snprintf(t->boot, sizeof t->boot, "%s", e->self.boot);
    snprintf(t->job, sizeof t->job, "%s", e->self.job);
    t->pid = e->self.pid;
    t->pid_start = e->self.pid_start;
    t->expires = (int64_t)sl_now_seconds() + e->lease_seconds;
    t->memory_limit_mb = e->memory_limit_mb; /* what a crash happened under */
}

/* Is the claimed ticket still ours (same nonce and epoch)? */
static int lease_held(const sl_engine *e, const char *stage, const char *name, const sl_ticket *mine)
{
    sl_ticket now;
    return sl_queue_get(e->work, stage, SL_STATE_CLAIMED, name, &now) == 0 &&
           now.epoch == mine->epoch && strcmp(now.nonce, mine->nonce) == 0;
}

/* Whether ticket `name` of `stage` is also in a state other than claimed. A claimer
 * frozen between its rename and its lease write (SIGSTOP, a Slurm suspend) may wake after
 * another worker reclaimed the ticket, finished it and released it: the late lease write
 * then recreates the claim beside the ticket's true state (seen in test_liveness: the
 * woken run redid a done stage). A ticket is never in two states otherwise: every move
 * is one rename. */
int sl_engine_ticket_elsewhere(const sl_engine *e, const char *stage, const char *name)
{
    static const int others[] = {SL_STATE_READY, SL_STATE_DONE, SL_STATE_FAILED,
                                 SL_STATE_QUARANTINE};
    for (size_t k = 0; k < sizeof others / sizeof *others; k++) {
        char path[PATH_MAX];
        if (sl_queue_path(path, sizeof path, e->work, stage, others[k], name) == 0 &&
            access(path, F_OK) == 0)
            return 1;
    }
    return 0;
}

/* The check and the write are two steps: an owner frozen between them (at the write's
 * rename: tests/faults/test_frozen_owner.sh) wakes to write its lease over a claim that
 * was taken over, finished and released meanwhile, recreating it, and would then find the
 * lease "held" and run the stage again. The check after the write catches that: the
 * ticket is in its true state too, and the recreated claim is removed. */
int sl_engine_lease_renew(sl_engine *e, const char *stage, const char *name, sl_ticket *t,
                          sl_error *err)
{
    if (!lease_held(e, stage, name, t))
        return sl_error_set(err, SL_E_LEASE_LOST, 0, name, "lease lost to another worker");
    sl_engine_stamp_lease(e, t);
    int rc = sl_queue_put(e->work, stage, SL_STATE_CLAIMED, name, t, err);
    if (rc == 0 && sl_engine_ticket_elsewhere(e, stage, name)) {
        char path[PATH_MAX];
        sl_queue_path(path, sizeof path, e->work, stage, SL_STATE_CLAIMED, name);
        unlink(path);
        return sl_error_set(err, SL_E_LEASE_LOST, 0, name,
                            "lease lost to another worker (finished meanwhile)");
    }
    return rc;
}

int sl_engine_lease_check(sl_engine *e, const char *stage, const char *name,
                          const sl_ticket *t, sl_error *err)
{
    if (!lease_held(e, stage, name, t))
        return sl_error_set(err, SL_E_LEASE_LOST, 0, name, "lease lost to another worker");
    return 0;
}

/* The owner of a leased ticket is gone: its lease expired (wherever it runs), or, on
 * this host, its pid died (or was reused). One rule for claims and scan marks. */
int sl_lease_owner_gone(const sl_engine *e, const sl_ticket *t, int64_t now)
{
    return t->expires < now || sl_identity_alive(&e->self, t) == 0;
}

void sl_engine_scan_mark(sl_engine *e, int mark)
{
    char name[128];
    snprintf(name, sizeof name, "%s.%ld", e->self.host, e->self.pid);
    sl_error err;
    sl_error_init(&err);
    if (!mark) {
        char path[PATH_MAX];
        sl_queue_path(path, sizeof path, e->work, SCAN_QUEUE, SL_STATE_CLAIMED, name);
        unlink(path);
        e->scan_mark_expires = 0;
        return;
    }
    if (e->scan_mark_expires &&
        (int64_t)sl_now_seconds() < e->scan_mark_expires - e->lease_seconds / 2)
        return;
    sl_ticket t;
    sl_ticket_init(&t);
    snprintf(t.item, sizeof t.item, "%s", "(scan)");
    sl_engine_stamp_lease(e, &t);
    /* Best effort: without it (full disk) others may finish early and exit 75. */
    if (sl_queue_create(e->work, SCAN_QUEUE, &err) == 0 &&
        sl_queue_put(e->work, SCAN_QUEUE, SL_STATE_CLAIMED, name, &t, &err) == 0)
        e->scan_mark_expires = t.expires;
}

void sl_engine_scan_stamp(sl_engine *e)
{
    sl_ticket t;
    sl_ticket_init(&t);
    snprintf(t.item, sizeof t.item, "%s", "(last scan)");
    sl_engine_stamp_lease(e, &t);
    t.expires = (int64_t)sl_now_seconds(); /* when it ended */
    sl_error err;
    sl_error_init(&err);
    if (sl_queue_put(e->work, SCAN_QUEUE, SL_STATE_DONE, "last", &t, &err) != 0)
        SL_LOG(SL_LOG_WARN, "scan", NULL, "scan stamp not written: %s", err.message);
}

/* Does a scan mark or stamp `t` come from job `job` ("" = any job)? Slurm array tasks
 * carry "ARRAYJOB_TASK[+rRESTART]" (sl_identity_self), so a job's array id names all of
 * its tasks. */
static int from_job(const sl_ticket *t, const char *job)
{
    size_t n = strlen(job);
    return !job[0] || (strncmp(t->job, job, n) == 0 &&
                       (t->job[n] == '\0' || t->job[n] == '_' || t->job[n] == '+'));
}

/* A live scan mark of `job` (other than ours), or the stamp of a finished one. */
static int scan_seen(const sl_engine *e, const char *job, int64_t now)
{
    sl_ticket t;
    sl_error err;
    sl_error_init(&err);
    if (sl_queue_get(e->work, SCAN_QUEUE, SL_STATE_DONE, "last", &t) == 0 && from_job(&t, job))
        return 1;
    char **names;
    int count = 0, seen = 0;
    if (sl_queue_list(e->work, SCAN_QUEUE, SL_STATE_CLAIMED, &names, &count, &err) != 0)
        return 0;
    for (int i = 0; i < count && !seen; i++)
        seen = sl_queue_get(e->work, SCAN_QUEUE, SL_STATE_CLAIMED, names[i], &t) == 0 &&
               t.expires >= now && from_job(&t, job);
    free(names);
    return seen;
}

int sl_engine_wait_for_scan(sl_engine *e, const char *job, int64_t seconds, sl_error *err)
{
    double start = sl_now_seconds();
    int said = 0;
    while (!scan_seen(e, job, (int64_t)sl_now_seconds())) {
        if (*sl_interrupt_flag())
            return sl_error_set(err, SL_E_INTERRUPTED, 0, e->work, "interrupted");
        if (sl_now_seconds() - start >= (double)seconds)
            return sl_error_set(err, SL_E_BUSY, 0, e->work,
                                "no scan %s%s%s within %lld s: nothing to work on yet",
                                job[0] ? "of job " : "has run in this work folder",
                                job[0] ? job : "", job[0] ? " began" : "", (long long)seconds);
        if (!said++)
            SL_LOG(SL_LOG_INFO, "worker", NULL, "waiting for a scan%s%s (up to %lld s)",
                   job[0] ? " of job " : "", job, (long long)seconds);
        struct timespec pause = {0, 500 * 1000 * 1000};
        nanosleep(&pause, NULL);
    }
    return 0;
}

/* Scans announced by other live processes (their announcements when dead are removed). */
int sl_engine_scans_elsewhere(const sl_engine *e)
{
    char **names;
    int count = 0, live = 0;
    sl_error err;
    sl_error_init(&err);
    if (sl_queue_list(e->work, SCAN_QUEUE, SL_STATE_CLAIMED, &names, &count, &err) != 0)
        return 0;
    int64_t now = (int64_t)sl_now_seconds();
    for (int i = 0; i < count; i++) {
        char path[PATH_MAX];
        sl_queue_path(path, sizeof path, e->work, SCAN_QUEUE, SL_STATE_CLAIMED, names[i]);
        sl_ticket t;
        sl_error terr;
        sl_error_init(&terr);
        if (sl_ticket_read(path, &t, &terr) != 0)
            continue; /* being written */
        if (t.pid == e->self.pid && strcmp(t.host, e->self.host) == 0)
            continue;
        if (sl_lease_owner_gone(e, &t, now))
            unlink(path);
        else
            live++;
    }
    free(names);
    return live;
}
