/* On-disk queues (docs/engine.md, "Queues and the life of an item"): one queue per stage under the work dir,
 *   WORK/queue/<stage>/{ready,claimed,done,failed,quarantine}/<ticket>
 * a state is a directory, a transition is one rename followed by an fsync of both
 * directories (Maildir). One small text ticket per item per stage. The ticket of a claimed
 * item carries the lease (host, boot id, pid + its start time, job id, epoch, expiry,
 * nonce), rewritten atomically on renewal.
 *
 * Ticket names are the item id percent-escaped: '%', '/', control characters and a
 * leading '.' (%25, %2F, %0A, %2E), so `bunny/bun000.ply` is `bunny%2Fbun000.ply`; a name
 * longer than SL_TICKET_NAME_MAX keeps a prefix and ends in "~" and the 128-bit hash of
 * the whole id. Every item id has a ticket. The item id itself is also inside the ticket
 * (its '%' and control characters escaped the same way, so it stays one line).
 */
#ifndef SCANLOD_PIPELINE_QUEUE_H
#define SCANLOD_PIPELINE_QUEUE_H

#include <limits.h>
#include <stdint.h>

#include "core/error.h"

enum sl_queue_state {
    SL_STATE_READY = 0,
    SL_STATE_CLAIMED,
    SL_STATE_DONE,
    SL_STATE_FAILED,
    SL_STATE_QUARANTINE,
    SL_STATE_COUNT,
    SL_STATE_NONE = -1
};

const char *sl_queue_state_name(int state); /* "ready", ... */

#define SL_TICKET_NAME_MAX 240

typedef struct sl_ticket {
    char item[PATH_MAX];  /* item id: input path relative to [run] input */
    char source[PATH_MAX]; /* the same (kept apart: the item id names, the source is read) */
    char key[33];         /* stage key (hex) the ticket belongs to */
    int attempt;          /* claims so far */
    int crashes;          /* crashes in our own code so far */
    uint64_t epoch;       /* fencing token, bumped by every reclaim */
    char host[64];
    char boot[40];        /* kernel boot id: pids are only comparable within one boot */
    long pid;
    unsigned long long pid_start; /* /proc/<pid>/stat starttime, against pid reuse */
    char job[96];         /* Slurm job/array/restart ids, "" outside Slurm */
    char nonce[33];       /* per-claim random id */
    int64_t expires;      /* lease expiry, unix seconds; 0 = none */
    char cls[16];         /* failed/quarantine: badinput, transient, memory, storage, bug */
    char reason[768];     /* failed/quarantine: the error line */
    int64_t memory_limit_mb; /* [run] memory_limit_mb of the owner that wrote it last: a
                                crash under a limit may have been a library out of memory
                                (docs/engine.md, "Failure classes"); -1 = not recorded
                                (tickets of builds before issue 34) */
    char run[96];         /* failed: the run it failed in (log run id); another retries it */
    int parts;            /* a part's ticket: how many parts its split has (0: not a part,
                             or not recorded) */
} sl_ticket;

/* An empty ticket (memory_limit_mb -1: not recorded). */
void sl_ticket_init(sl_ticket *t);
int sl_ticket_read(const char *path, sl_ticket *t, sl_error *err);
int sl_ticket_write(const char *path, const sl_ticket *t, sl_error *err); /* atomic */

/* The ticket name of an item id (`name`: SL_TICKET_NAME_MAX + 1 bytes). */
int sl_ticket_name(const char *item, char *name, size_t size, sl_error *err);

/* Reads ticket `name` of `stage` in `state`: 0, or nonzero when it is missing, torn or
 * unreadable (alike to callers that only look: nobody's ticket to act on). */
int sl_queue_get(const char *work, const char *stage, int state, const char *name,
                 sl_ticket *t);

/* WORK/queue/<stage>/<state>[/<name>] */
int sl_queue_path(char *buf, size_t size, const char *work, const char *stage, int state,
                  const char *name);
/* Creates every state directory of `stage`. */
int sl_queue_create(const char *work, const char *stage, sl_error *err);
/* Which state holds the ticket (SL_STATE_NONE if none). */
int sl_queue_find(const char *work, const char *stage, const char *name);
/* rename + fsync of both directories. Returns SL_E_BUSY if the ticket is no longer in
 * `from` (another worker moved it first). */
int sl_queue_move(const char *work, const char *stage, const char *name, int from, int to,
                  sl_error *err);
/* Writes a new ticket straight into `state` (atomic). */
int sl_queue_put(const char *work, const char *stage, int state, const char *name,
                 const sl_ticket *t, sl_error *err);
/* Ticket names in a state directory, sorted; *names is one malloc'd block. */
int sl_queue_list(const char *work, const char *stage, int state, char ***names, int *count,
                  sl_error *err);

#endif
