/* Engine internals shared by pipeline/engine*.c (not an interface for stages). */
#ifndef SCANLOD_PIPELINE_ENGINE_INTERNAL_H
#define SCANLOD_PIPELINE_ENGINE_INTERNAL_H

#include <limits.h>
#include <stdint.h>
#include <sys/types.h>

#include "core/hash.h"
#include "core/clock.h"
#include "pipeline/config.h"
#include "pipeline/engine.h"
#include "pipeline/queue.h"
#include "pipeline/record.h"
#include "pipeline/stage.h"

#define SL_MAX_STAGES 16

typedef struct sl_identity {
    char host[64];
    char boot[40];
    long pid;
    unsigned long long pid_start;
    char job[96];
} sl_identity;

typedef struct sl_engine_counts {
    uint64_t items;       /* items found by the scan */
    uint64_t ran;         /* stage executions that committed */
    uint64_t reused;      /* stage results found valid and kept */
    uint64_t published;
    uint64_t quarantined; /* newly quarantined in this run */
    uint64_t bugs;        /* quarantined as a crash in our code, this run */
    uint64_t transient;   /* failed transiently in this run */
    uint64_t untracked;   /* of those, failures no ticket shows (a publication, a scan
                             error): pending for the exit code all the same */
    uint64_t skipped;     /* input entries the scan did not take (hidden, links, ...) */
    uint64_t moved_aside; /* entries in published folders that were not the publication's */
    uint64_t manifest_unknown; /* manifest rows naming no item of the input tree */
} sl_engine_counts;

struct sl_engine {
    sl_config *cfg;
    const char *input, *work, *output, *logs;
    int threads;
    int64_t memory_limit_mb, item_timeout_s, lease_seconds;
    double part_mb;          /* [queue] part_mb: input MB per part of a splittable stage */
    int memory_check;        /* [run] memory_check: refuse items expected over the budget */
    char admission[512];     /* why the last item refused was not run */
    double (*expected_peak_mb)(const struct sl_engine_facts *, const char *, const char **);
    const char *const *input_suffixes; /* what the input walk takes (engine.h) */
    int64_t scan_mark_expires;    /* this process's scan mark (engine_work.c); 0 = none */
    int max_crashes;
    unsigned method;         /* [lod] method (sl_lod_method bit) */
    const sl_stage *stages[SL_MAX_STAGES]; /* the method's path, in order */
    uint64_t config_hash[SL_MAX_STAGES];
    int stage_count;
    sl_identity self;
    sl_engine_counts counts;
    int stop;                /* storage failure: stop claiming */
    sl_error storage_error;  /* why */
    /* Progress (engine_status.c): items in the collection and those needing nothing more
     * (published, quarantined), the settled count and the time when the work began, and
     * the bar's last fraction (it never goes back). */
    uint64_t items_total, items_settled, settled_at_start;
    double work_start, bar_fraction;
    char **items;            /* item ids found by the scan (for the collection summary) */
    sl_engine_item_fn item_fn; /* set by sl_engine_each_item: items are reported to it,
                                  not reconciled */
    void *item_ctx;
    uint64_t item_count, item_capacity;
    struct sl_manifest *manifest;  /* the collection manifest, or NULL (engine_manifest.c) */
    unsigned char *manifest_seen;  /* per row: the scan found its item */
};

/* engine_lease.c: who owns what. */
/* Start time of process `pid` in clock ticks after boot (/proc/PID/stat), 0 if unknown. */
unsigned long long sl_process_start_time(long pid);
void sl_identity_self(sl_identity *id);
int sl_identity_alive(const sl_identity *self, const sl_ticket *t); /* 1 alive, 0 dead, -1 unknown */
void sl_random_nonce(char out[33]);
/* Stamps this process's identity and a lease of [queue] lease_seconds from now on `t`. */
void sl_engine_stamp_lease(const sl_engine *e, sl_ticket *t);
/* The owner of a leased ticket is gone: its lease expired (wherever it runs), or, on this
 * host, its pid died (or was reused). One rule for claims and scan marks. */
int sl_lease_owner_gone(const sl_engine *e, const sl_ticket *t, int64_t now);
/* Is the ticket also in a state other than claimed (a claim recreated by a late write)? */
int sl_engine_ticket_elsewhere(const sl_engine *e, const char *stage, const char *name);
int sl_engine_lease_renew(sl_engine *e, const char *stage, const char *name, sl_ticket *t,
                          sl_error *err);
int sl_engine_lease_check(sl_engine *e, const char *stage, const char *name,
                          const sl_ticket *t, sl_error *err);
/* A run's scan is announced like a claim (WORK/queue/_scan/claimed/HOST.PID, with a
 * lease): it may still enqueue work, so others do not call the collection finished while
 * it lasts. mark: 1 = announce or renew (when half the lease is gone), 0 = withdraw. */
void sl_engine_scan_mark(sl_engine *e, int mark);
/* A finished scan leaves its stamp (WORK/queue/_scan/done/last: host, pid, job, end time),
 * so a worker started before any scan can tell it has to wait (sl_engine_wait_for_scan). */
void sl_engine_scan_stamp(sl_engine *e);
/* Scans announced by other live processes (the marks of dead ones are removed). */
int sl_engine_scans_elsewhere(const sl_engine *e);

/* engine_layout.c: where things live, and the run's folders. */
int sl_engine_path(char *buf, size_t size, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int sl_artifact_dir(const sl_engine *e, int stage, const char *ticket, char *buf, size_t size);
/* Whether some version of `item` is published (its publish record exists), current or not:
 * a quarantined item with one is stale (engine_summary.c). */
int sl_engine_item_published(const sl_engine *e, const char *item);
/* Puts folder `staged` in place of `final_dir` (in folder `parent`) in one rename, or one
 * exchange when `final_dir` exists (whose old contents are then removed); durable. */
int sl_engine_swap_in(const char *staged, const char *final_dir, const char *parent,
                      sl_error *err);
/* Empties an artifact folder, its record first (without it nothing left is trusted). */
int sl_remove_dir_contents(const char *dir, sl_error *err);
int sl_engine_make_work_layout(sl_engine *e, sl_error *err);
/* [run] input must be a folder; input, work, output and logs must not contain one another
 * (SL_E_CONFIG naming FILE:LINE); work and output must take a new file (SL_E_STORAGE if
 * they cannot: read-only, permissions). */
int sl_engine_check_input(sl_engine *e, sl_error *err);
int sl_engine_check_trees(sl_engine *e, sl_error *err);
int sl_engine_check_writable(sl_engine *e, sl_error *err);

/* engine_keys.c: what results are trusted under. */
int sl_input_hash(sl_engine *e, const char *ticket, const char *source_rel, sl_hash *out,
                  sl_error *err);
/* The upstream chain stage s is keyed on: the input's content hash, then the outputs
 * digest of every earlier stage in order (chain = H(chain, digest)), so a change anywhere
 * upstream reruns it, and identical upstream outputs never do. SL_E_CORRUPT when an
 * earlier record is missing; `verify_last` re-hashes stage s-1's outputs. */
int sl_upstream_chain(sl_engine *e, const char *ticket, const char *source_rel, int s,
                      int verify_last, sl_hash *out, sl_error *err);
sl_hash sl_chain_hash(sl_hash chain, sl_hash digest);
/* Hash of every config section the stage reads (its own by default), in order. */
uint64_t sl_stage_config_hash(const sl_config *cfg, const sl_stage *stage);

/* engine_manifest.c: the collection manifest (docs/metadata.md). */
/* Reads [run] manifest (or manifest.csv/.json at the input's root); SL_E_CONFIG naming
 * FILE:LINE when it is malformed. No manifest: 0, e->manifest NULL. */
int sl_engine_manifest_open(sl_engine *e, sl_error *err);
void sl_engine_manifest_close(sl_engine *e);
/* The item's row for stage s: NULL unless the stage reads metadata and the row exists. */
const sl_item_metadata *sl_engine_item_metadata(const sl_engine *e, int s, const char *item);
/* What stage s of `item` is keyed on besides its upstream: its config sections' hash, and
 * for a stage that reads metadata the item's manifest row (when it has one). Every key
 * of a stage is made with this (reconciliation and the stage's own run). */
uint64_t sl_engine_stage_config_hash(const sl_engine *e, int s, const char *item);
/* After a scan: the rows naming no item found, each a WARN line and an event, counted. */
void sl_engine_manifest_check(sl_engine *e);
/* The summary's "manifest": its file, rows and the rows that named no item. */
struct sl_json;
void sl_engine_manifest_summary(const sl_engine *e, struct sl_json *js);
/* summary.html's note on the manifest: its file and rows, and those naming no item. */
void sl_engine_manifest_note(const sl_engine *e, FILE *out);

/* engine_reconcile.c: bring one item's tickets in line with its keys from stage `from`
 * on (publishing it when every stage is done). */
void sl_ticket_for(sl_ticket *t, const char *item, const char *source_rel, sl_hash key);
int sl_engine_reconcile(sl_engine *e, const char *item, const char *source_rel, int from,
                        int *settled, sl_error *err); /* settled (may be NULL): 1 when the
                                                         item needs nothing more */
/* A ticket `name` of `stage` for `key` in ready unless it is claimed,
 * already ready under that key, or quarantined under it (then *quarantined = 1). */
int sl_engine_ensure_ready(sl_engine *e, const char *stage, const char *name, const char *item,
                           const char *source_rel, sl_hash key, int parts, int *quarantined,
                           sl_error *err); /* parts: recorded in a part's ticket, else 0 */
/* Brings stage s's parts of the item in line with `key` (each part's record checked, a
 * ready ticket for every part that is neither done, claimed nor quarantined under its
 * key). *all_done: every part is committed; *quarantined: some part is quarantined. */
int sl_engine_reconcile_parts(sl_engine *e, int s, const char *item, const char *source_rel,
                              const char *ticket, sl_hash key, int parts, int *all_done,
                              int *quarantined, sl_error *err);

/* engine_parts.c: one item's stage split into parts (docs/engine.md, "Parts"). A part's
 * ticket and artifact folder are the item's ticket name + "#part-NNNN"; its key is the
 * stage key chained with (part, parts). */
#define SL_PART_SUFFIX "#part-"
#define SL_PARTS_MAX 1024
/* How many parts stage s of the item splits into: 0 when it is not split (the stage has
 * no run_part, [queue] part_mb is 0, or the input is at most one part's size). */
int sl_engine_parts(const sl_engine *e, int s, const char *source_rel);
int sl_part_name(const char *ticket, int part, char *out, size_t size);
/* 1 and the item's ticket name and the part's index when `name` names a part, else 0. */
int sl_part_parse(const char *name, char *ticket, size_t size, int *part);
sl_hash sl_part_key(sl_hash stage_key, int part, int parts);
/* Whether part `part_name` of stage s is committed under `key` (its record verifies). */
int sl_engine_part_committed(const sl_engine *e, int s, const char *part_name, sl_hash key);
/* Drops our claim on part `part` of the item's stage s, which is not of the item's split
 * of `parts`: back to ready for reconciliation to rewrite when its index is one of the
 * split's, else removed (with whatever lies above it, so no gap is left). */
void sl_engine_part_drop(sl_engine *e, int s, const char *ticket, int part, int parts);
/* Whether claim `part` (-1: the join) of stage s may run now, with *key turned into the
 * part's key: a part must be one of the item's current `parts`, a join needs every part
 * committed. 0: drop the claim and reconcile the item. */
int sl_engine_parts_ready(const sl_engine *e, int s, const char *ticket, int part, int parts,
                          sl_hash *key);
/* The parts' artifact folders, in order (one malloc'd block; NULL when out of memory). */
char **sl_engine_part_dirs(const sl_engine *e, int s, const char *ticket, int parts);
/* The text of a claim's _stats.json: `head` (an open JSON object), then, for the join of
 * a stage split into `parts` (0 for any other claim), its parts' own stats
 * (`"parts":[...]`), then "}\n"; malloc'd, NULL when out of memory. `name` is the claim's
 * ticket name. */
char *sl_engine_parts_stats(const sl_engine *e, int s, const char *name, int parts,
                            const char *head, size_t head_size);
/* The split the item's stage s works to (0: none): the config's (sl_engine_parts), unless
 * the parts on disk belong to another split that a live worker is running (a claim on one
 * of its parts other than `exclude`: the claim being judged, NULL for none) or whose
 * parts are all committed under stage key `key`. */
int sl_engine_item_parts(const sl_engine *e, int s, const char *ticket, const char *source_rel,
                         sl_hash key, const char *exclude);
/* Removes the item's parts `from` and above of stage s (tickets and artifact folders),
 * from the top down, stopping below one a live worker holds: 0 once the stage is
 * committed, else the item's split (the parts of others). Parts below `at_least` (the
 * config's split) are looked for even past a gap. Best effort: leftovers are only disk,
 * and the next reconciliation tries again. */
void sl_engine_parts_prune(sl_engine *e, int s, const char *ticket, int from, int at_least);
/* engine_admission.c: 1 when the item's expected peak memory for stage s fits the budget;
 * else 0, with the reason logged and left in e->admission (docs/engine.md). */
int sl_engine_admitted(sl_engine *e, int s, const sl_ticket *t, const char *source);
/* The memory an item's stage may use, MB: [run] memory_limit_mb when set, else what this
 * node or its cgroup has (core/memory.h); `what` says which. 0 when unknown. The
 * admission's budget, and the stages' (sl_stage_io.memory_budget_mb). */
uint64_t sl_engine_memory_budget(const sl_engine *e, char *what, size_t what_size);
/* engine_layout.c: the private folder a claim's stage process writes into, a hidden
 * sibling of `out_dir` named after this process (SL_E_LIMIT when too long). */
int sl_engine_staged_path(const sl_engine *e, const char *out_dir, char *buf, sl_error *err);

/* What a stage process reports to its parent through the result pipe. */
typedef struct child_result {
    sl_error err;
    double cpu_seconds;
    long max_rss_kb;
} child_result;

/* The stage process's progress, in a shared mapping the parent draws from. */
typedef struct shared_progress {
    volatile double fraction;
    char phase[32];
} shared_progress;

/* The work of a claim: which stage of which item, and which part of it (part -1: the
 * whole stage, or the join of its `parts` parts when parts > 1). */
typedef struct claim_work {
    int s;
    const char *item, *source, *in_dir, *out_dir;
    int part, parts;
} claim_work;

/* engine_stage_child.c: the forked stage process's body; never returns (_exit). */
void sl_engine_child_main(sl_engine *e, const claim_work *w, shared_progress *sp, int result_fd,
                          pid_t parent);

/* engine_child.c: runs stage `s` for the claimed ticket; moves the ticket on. */
int sl_engine_process(sl_engine *e, int s, const char *name, sl_ticket *t, sl_error *err);

/* How a stage process ended, as its parent saw it. */
typedef struct sl_child_outcome {
    int have_result;  /* the child reported its sl_error (and times) through the pipe */
    int status;       /* waitpid status */
    long max_rss_kb;  /* its peak RSS (wait4), also when it was killed */
    int oom_killed;   /* the cgroup's oom_kill count rose while it ran */
    int timed_out;    /* we killed it: [run] item_timeout_s */
    int interrupted;  /* we forwarded an interrupt */
    int lease_lost;   /* we killed it: the lease could not be renewed */
    double seconds;
} sl_child_outcome;

/* engine_outcome.c: the failure classes (docs/engine.md, "Failure classes"). */
/* Moves our claim to `to` with the class and reason written into the ticket (nothing when
 * the claim was taken over meanwhile). */
int sl_engine_move_with_reason(sl_engine *e, int s, const char *name, sl_ticket *t, int to,
                               const char *cls, const char *reason, sl_error *err);
/* The claim's stage failed (item_err; SL_OK: the process died without a word): counts it
 * and moves the ticket where its class says. */
int sl_engine_handle_failure(sl_engine *e, int s, const char *name, sl_ticket *t,
                             const sl_child_outcome *o, sl_error *item_err, sl_error *err);
/* Whether quarantined ticket `t` stays quarantined for this run: 1; 0 with the reason in
 * `why` when it is to be retried (a class that is never quarantined, a "bug" that was
 * out of memory, or one that crashed under a smaller [run] memory_limit_mb, or one from a
 * build that did not record the limit). */
int sl_engine_quarantine_holds(const sl_engine *e, const sl_ticket *t, char *why, size_t size);

/* engine_publish.c */
int sl_engine_publish(sl_engine *e, const char *item, const char *ticket, const char *source_rel,
                      int force, sl_error *err);
int sl_engine_publish_valid(sl_engine *e, const char *item, const char *ticket);
/* After every stage is done: a valid publication is kept (entries its record does not
 * list moved aside: the folder is the publication's alone) and *settled set; else the
 * item is published. */
int sl_engine_publication_settle(sl_engine *e, const char *item, const char *ticket,
                                 const char *source_rel, int *settled, sl_error *err);
/* Calls fn for each entry of published folder `dir` that the record at `record_path`
 * does not list (timings.json is the publication's too); their number. */
int sl_engine_foreign_entries(const char *record_path, const char *dir,
                              void (*fn)(void *ctx, const char *name), void *ctx);

/* engine_summary.c: OUTPUT/summary.json and summary.md over the scanned items. */
int sl_engine_write_summary(sl_engine *e, sl_error *err);

/* engine_gc.c: temp files and staged folders of dead processes. */
void sl_engine_gc(sl_engine *e);

/* engine_status.c: the progress bar for stage `s` of `item` at `stage_fraction` of it
 * (TTY only), and the same facts as text for log lines ("12/40 items, 31 %, 1:02
 * elapsed, ETA 2:15"). */
void sl_engine_progress(sl_engine *e, int s, const char *item, double stage_fraction);
void sl_engine_progress_text(sl_engine *e, char *buf, size_t size);

/* engine_verify.c: items whose last stage is done but that have no publication (each named
 * on `out`); their number. */
uint64_t sl_engine_unpublished(sl_engine *e, FILE *out);

#endif
