/* The worker loop: claim ready tickets by rename, hold a lease while the item runs,
 * reclaim tickets whose owner is gone (docs/engine.md, "Leases and liveness").
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
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/log.h"
#include "core/progress.h"

/* A claimed ticket still without a lease after this long is abandoned (seconds). */
#define UNLEASED_CLAIM_S 10

/* A claimed ticket nobody can be working on any more goes back to ready. */
static void reclaim_stale(sl_engine *e, int s)
{
    const char *stage = e->stages[s]->name;
    char **names;
    int count;
    sl_error err;
    sl_error_init(&err);
    if (sl_queue_list(e->work, stage, SL_STATE_CLAIMED, &names, &count, &err) != 0)
        return;
    int64_t now = (int64_t)sl_now_seconds();
    for (int i = 0; i < count; i++) {
        char path[PATH_MAX];
        sl_queue_path(path, sizeof path, e->work, stage, SL_STATE_CLAIMED, names[i]);
        sl_ticket t;
        sl_error terr;
        sl_error_init(&terr);
        int stale;
        if (sl_ticket_read(path, &t, &terr) != 0) {
            /* Torn or still being renamed in: judge by age alone. */
            struct stat st;
            stale = stat(path, &st) == 0 && st.st_ctime + e->lease_seconds < now;
        } else if (t.expires == 0) {
            /* Renamed in but never leased: its claimer died (or ran out of space) between
             * the rename and the lease write, which a live claimer does at once. */
            struct stat st;
            stale = stat(path, &st) == 0 && st.st_ctime + UNLEASED_CLAIM_S < now;
        } else if (t.pid == e->self.pid && strcmp(t.host, e->self.host) == 0) {
            /* Ours: between two items this process holds no claim, so this is the
             * leftover of a release that failed half-way; waiting on it would wait on
             * ourselves forever. */
            stale = 1;
        } else {
            stale = sl_lease_owner_gone(e, &t, now);
        }
        if (!stale)
            continue;
        sl_error merr;
        sl_error_init(&merr);
        if (sl_queue_move(e->work, stage, names[i], SL_STATE_CLAIMED, SL_STATE_READY, &merr) == 0)
            SL_LOG(SL_LOG_INFO, stage, t.item, "reclaimed from %s pid %ld (owner gone)", t.host,
                   t.pid);
    }
    free(names);
}

/* Claims the first ready ticket of stage `s`; 1 claimed, 0 none, <0 error. */
static int claim_one(sl_engine *e, int s, char *name, size_t name_size, sl_ticket *t,
                     sl_error *err)
{
    const char *stage = e->stages[s]->name;
    char **names;
    int count;
    int rc = sl_queue_list(e->work, stage, SL_STATE_READY, &names, &count, err);
    if (rc)
        return rc;
    int claimed = 0;
    for (int i = 0; i < count && !claimed; i++) {
        sl_error merr;
        sl_error_init(&merr);
        rc = sl_queue_move(e->work, stage, names[i], SL_STATE_READY, SL_STATE_CLAIMED, &merr);
        if (rc == SL_E_BUSY) {
            rc = 0; /* another worker was first: not an error, even for the last name */
            continue;
        }
        if (rc) {
            sl_error_merge(err, &merr);
            break;
        }
        char path[PATH_MAX];
        sl_queue_path(path, sizeof path, e->work, stage, SL_STATE_CLAIMED, names[i]);
        sl_error terr;
        sl_error_init(&terr);
        if (sl_ticket_read(path, t, &terr) != 0) {
            unlink(path); /* unreadable ticket: the next scan recreates it */
            continue;
        }
        t->epoch++;
        t->attempt++;
        sl_random_nonce(t->nonce);
        sl_engine_stamp_lease(e, t);
        rc = sl_queue_put(e->work, stage, SL_STATE_CLAIMED, names[i], t, err);
        if (rc) {
            /* No lease could be written (full disk): hand the ticket back at once
             * rather than leave an ownerless claim (a rename needs no space). */
            sl_error ignored;
            sl_error_init(&ignored);
            sl_queue_move(e->work, stage, names[i], SL_STATE_CLAIMED, SL_STATE_READY, &ignored);
            break;
        }
        if (sl_engine_ticket_elsewhere(e, stage, names[i])) {
            unlink(path); /* a claim recreated by a late lease write: not ours */
            continue;
        }
        snprintf(name, name_size, "%s", names[i]);
        claimed = 1;
    }
    free(names);
    return rc ? rc : claimed;
}


/* Tickets of stage s in `state` (0 when the queue cannot be listed). */
static int count_tickets(const sl_engine *e, int s, int state)
{
    char **names;
    int count = 0;
    sl_error err;
    sl_error_init(&err);
    if (sl_queue_list(e->work, e->stages[s]->name, state, &names, &count, &err) == 0)
        free(names);
    return count;
}

/* Tickets of every stage in `state`. */
static int tickets_in(const sl_engine *e, int state)
{
    int total = 0;
    for (int s = 0; s < e->stage_count; s++)
        total += count_tickets(e, s, state);
    return total;
}

/* Ready and claimed tickets, read in the order tickets move (ready, claimed of stage 0,
 * then of stage 1, ...): a ticket moving on during the sweep moves ahead of it, where it
 * is still found unless it outruns the sweep through a whole stage. */
static int queues_unsettled(const sl_engine *e)
{
    int total = 0;
    for (int s = 0; s < e->stage_count; s++)
        total += count_tickets(e, s, SL_STATE_READY) + count_tickets(e, s, SL_STATE_CLAIMED);
    return total;
}

int sl_engine_work(sl_engine *e, sl_error *err)
{
    double last_reclaim = 0;
    int quiet_once = 0;
    for (;;) {
        if (*sl_interrupt_flag() || e->stop)
            break;
        if (sl_now_seconds() - last_reclaim > 1.0) {
            for (int s = 0; s < e->stage_count; s++)
                reclaim_stale(e, s);
            last_reclaim = sl_now_seconds();
        }
        /* Later stages first: finish items before starting new ones. */
        int claimed = 0, rc = 0;
        char name[SL_TICKET_NAME_MAX + 1];
        sl_ticket t;
        int s;
        for (s = e->stage_count - 1; s >= 0 && !claimed; s--) {
            rc = claim_one(e, s, name, sizeof name, &t, err);
            if (rc < 0)
                break;
            claimed = rc;
            if (claimed)
                break;
        }
        if (rc < 0) {
            if (sl_error_class_of(rc) == SL_CLASS_STORAGE) {
                e->stop = 1;
                sl_error_merge(&e->storage_error, err);
            }
            return rc;
        }
        if (!claimed) {
            /* Others still hold claims (their items may still fail back to ready or
             * enqueue a next stage) or are scanning (and may enqueue items), and the
             * exit code should describe the finished collection, so wait for them (a
             * dead owner is reclaimed above, a dead scanner's mark dropped). */
            if (tickets_in(e, SL_STATE_CLAIMED) > 0 || sl_engine_scans_elsewhere(e) > 0) {
                struct timespec pause = {0, 250 * 1000 * 1000};
                nanosleep(&pause, NULL);
                quiet_once = 0;
                continue;
            }
            /* The sweeps above read one directory after another while other workers
             * move tickets forward, so one can slip between them. An unfinished item
             * always has a ready or claimed ticket (engine_child.c enqueues the next
             * step before it releases a claim), so two counts a moment apart that
             * see neither mean the collection is settled. */
            if (queues_unsettled(e) == 0) {
                if (quiet_once)
                    break;
                quiet_once = 1; /* and once more a moment later */
                struct timespec moment = {0, 50 * 1000 * 1000};
                nanosleep(&moment, NULL);
            }
            continue;
        }
        quiet_once = 0;
        rc = sl_engine_process(e, s, name, &t, err);
        if (rc && sl_error_class_of(rc) == SL_CLASS_STORAGE) {
            e->stop = 1;
            sl_error_merge(&e->storage_error, err);
            return rc;
        }
    }
    return 0;
}
