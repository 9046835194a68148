/* The engine: scans a collection, keeps the per-stage queues, runs items through the
 * stages in child processes, commits and publishes (docs/engine.md).
 *
 * Lifecycle: sl_engine_open (config, logs, work dir) -> sl_engine_scan (enqueue what is
 * missing or stale; `run` only) -> sl_engine_work (claim, run, commit until no ready work)
 * -> sl_engine_exit_code -> sl_engine_close. Several engines (processes, hosts) may work on
 * one work dir at once: they cooperate through the queues and leases.
 */
#ifndef SCANLOD_PIPELINE_ENGINE_H
#define SCANLOD_PIPELINE_ENGINE_H

#include <stdint.h>
#include <stdio.h>

#include "core/error.h"
#include "pipeline/config.h"

typedef struct sl_engine sl_engine;
struct sl_stage;
struct sl_engine_facts;

typedef struct sl_engine_options {
    const char *config_path;
    const char *const *overrides; /* "section.key=value" */
    int override_count;
    const char *command;          /* "run", "worker", "status": names the log file */
    int quiet;                    /* stderr: errors only */
    int verbose;                  /* stderr: debug */
    int open_logs;                /* 0 for read-only commands (status) */
    /* The stages, in pipeline order, NULL-terminated (the program's registry:
     * stages/registry.h). */
    const struct sl_stage *const *stages;
    /* Optional: the expected peak RSS in MB of the item at `path` (its largest stage,
     * named in *stage), 0 when unknown: the pre-flight cost model (cli/plan.c). With it
     * and `[run] memory_check`, an item expected over the memory budget is not run
     * (docs/engine.md, "Memory admission"). */
    double (*expected_peak_mb)(const struct sl_engine_facts *facts, const char *path,
                               const char **stage);
    /* The file-name suffixes the input walk takes as items (".ply", ".obj", ...; compared
     * without case), NULL-terminated: the formats the program reads, which the engine does
     * not name (cli/ passes formats/scan_read.h's). NULL: ".ply" alone. */
    const char *const *input_suffixes;
} sl_engine_options;

int sl_engine_open(sl_engine **out, const sl_engine_options *opts, sl_error *err);
void sl_engine_close(sl_engine *e);

/* Walks [run] input and makes every item's queue state match its current keys. */
int sl_engine_scan(sl_engine *e, sl_error *err);

/* A worker started with (or before) the run that scans: waits until a scan of Slurm job
 * `job` ("" = any scan at all) is under way or has finished in this work folder, for at
 * most `seconds`; SL_E_BUSY when none came (the worker then exits 75, not 0: it did
 * nothing, and nothing says the collection is done). */
int sl_engine_wait_for_scan(sl_engine *e, const char *job, int64_t seconds, sl_error *err);

/* Claims and runs ready work until none is left (or an interrupt / storage failure). */
int sl_engine_work(sl_engine *e, sl_error *err);

/* Exit code from the state of every item of the collection (docs/exit-codes.md);
 * prints the one-paragraph summary to stdout and writes logs/<run>.summary.json. */
int sl_engine_finish(sl_engine *e);

/* Checks every commit record in the work dir against its files; prints each mismatch.
 * Returns 0 or SL_E_CORRUPT. */
int sl_engine_verify(sl_engine *e, FILE *out, uint64_t *checked, uint64_t *bad);

/* Per stage: ready / claimed / done / failed / quarantined counts, and the reasons. */
int sl_engine_status(sl_engine *e, FILE *out, sl_error *err);

/* One entry of the input tree as the scan takes it: `rel` the item id, `path` its file,
 * `unreadable` why it cannot be a scan (NULL when it can). */
typedef void (*sl_engine_item_fn)(void *ctx, const char *rel, const char *path,
                                  const char *unreadable);

/* Walks [run] input with the scan's rules and order but only reports each item to `fn`:
 * nothing is queued or written (`scanlod plan`). */
int sl_engine_each_item(sl_engine *e, sl_engine_item_fn fn, void *ctx, sl_error *err);

/* How many parts the stage named `stage` of the item at `source_rel` (relative to [run]
 * input) is split into by [queue] part_mb (docs/engine.md, "Parts"); 0 when it is not. */
int sl_engine_stage_parts(const sl_engine *e, const char *stage, const char *source_rel);

/* What the engine was opened with, for commands that describe a run without running it. */
typedef struct sl_engine_facts {
    const sl_config *cfg;
    int threads;                       /* [run] threads, 0 resolved to the cores online */
    int64_t memory_limit_mb;           /* 0 = none */
    const char *method;                /* [lod] method */
    const struct sl_stage *const *stages; /* the method's path, in order */
    int stage_count;
} sl_engine_facts;
void sl_engine_facts_of(const sl_engine *e, sl_engine_facts *out);

#endif
