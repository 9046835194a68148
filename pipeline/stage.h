/* The contract of a stage (docs/adding-a-stage.md; docs/architecture.md, "The flow").
 *
 * A stage is a pure function of (its input artifacts, its config section, its code
 * version): the same inputs give byte-identical outputs whatever the thread count. The
 * engine calls `run` in a child process per item (a crash or OOM costs one item), with
 * the OpenMP thread count already set. The stage:
 *   - reads the source file and/or the upstream stage's artifact directory `in_dir`;
 *   - writes its artifacts into `out_dir` through core/atomicfile.h only (the engine
 *     hashes every file in `out_dir` and writes the commit record last);
 *   - adds counts to `report` (an open JSON object: the stage's part of the item report);
 *   - polls `progress` and returns SL_E_INTERRUPTED at a safe point when asked to stop
 *     (sl_stage_step);
 *   - returns 0 or a negative SL_E_* with `err` naming the file and the cause. Bad input
 *     must be SL_E_BADINPUT/SL_E_LIMIT/SL_E_UNSUPPORTED (the item is quarantined).
 *
 * Its face (stages/NAME/NAME.h): `sl_NAME_config`, a flat struct of the resolved section
 * (every field commented); `sl_NAME_default_config()`, that struct with every option at
 * the default of the stage's option table (sl_stage_default_config: the defaults are
 * written once, in the table); the functions that do its work; and `sl_NAME_stage`.
 */
#ifndef SCANLOD_PIPELINE_STAGE_H
#define SCANLOD_PIPELINE_STAGE_H

#include <limits.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/json.h"
#include "core/progress.h"
#include "pipeline/config.h"

/* An item's row of the collection manifest (docs/metadata.md): what a museum says about the
 * object, read by the engine once per run from [run] input/manifest.csv or .json (or [run]
 * manifest). Every field is a NUL-terminated UTF-8 text, "" when the manifest leaves it
 * empty; `units` is "", "mm", "cm", "m", "in" or "ft" and `up` "", "y" or "z" (the manifest
 * reader refuses anything else). Owned by the engine; valid while the stage runs. */
typedef struct sl_item_metadata {
    const char *title, *accession, *units, *up, *credit, *licence, *description;
    const char *where; /* "manifest.csv:12": the row's file and line, for messages only
                          (not hashed: moving a row does not rerun anything) */
} sl_item_metadata;

typedef struct sl_stage_io {
    const char *item;        /* item id: input path relative to [run] input, suffix kept */
    const char *source_path; /* the item's input file */
    const char *in_dir;      /* upstream stage's artifact directory; NULL for the first */
    const char *out_dir;     /* this stage's artifact directory (exists and is empty) */
    sl_json *report;         /* open object: this stage's section of the item report */
    /* Open object, or NULL: the stage's own timings (wall seconds of its steps), which
     * differ run to run and so go to timings.json ("detail"), never to an artifact. */
    sl_json *timings;
    sl_progress *progress;
    int threads;             /* OpenMP threads for this item (already set) */
    /* The memory this stage may use, MB: [run] memory_limit_mb, else the node's or its
     * cgroup's (docs/engine.md, "Memory admission"); 0 when unknown. A stage that can do
     * its work by bricks chooses them by it (docs/bricks.md). */
    uint64_t memory_budget_mb;
    /* Every earlier stage's artifact directory, in pipeline order, ended by {NULL, NULL};
     * the stage key chains over all of them. Find one by name with sl_stage_dir(). */
    const struct sl_stage_dir_entry {
        const char *stage, *dir;
    } *upstream;
    /* Parts (docs/engine.md, "Parts"): a stage with `run_part` may have its work for one
     * item split into `parts` work items, each run by `run_part` with `part` in
     * [0, parts) into its own out_dir, then joined by `run`, which finds part p's
     * artifacts in part_dirs[p]. parts = 0 (and part_dirs NULL): not split. */
    int part, parts;
    const char *const *part_dirs;
    /* The item's manifest row, for a stage that declares `reads_metadata` (its key then
     * hashes the row); NULL for other stages and for an item the manifest has no row for. */
    const sl_item_metadata *metadata;
} sl_stage_io;

/* The artifact directory of the earlier stage `name` for this item, or NULL. */
const char *sl_stage_dir(const sl_stage_io *io, const char *name);

/* "dir/name" into `path` (an artifact file of io->in_dir, io->out_dir or an upstream
 * dir); SL_E_STORAGE (ENAMETOOLONG) when it does not fit. */
int sl_stage_path(char path[PATH_MAX], const char *dir, const char *name, sl_error *err);

/* A safe point of `run`: reports `phase` at `fraction` done; SL_E_INTERRUPTED (with `err`
 * set) when the run has been asked to stop, else 0. */
int sl_stage_step(const sl_stage_io *io, const char *phase, double fraction, sl_error *err);

/* The LOD methods (docs/architecture.md, "The flow"): each is a path of stages from the
 * range stage to the export stage, picked per run by `[lod] method`; a stage names the
 * methods whose path it is on. The engine runs the registry's stages of the chosen method,
 * in order.
 *   octree  (paper 1): range -> samples -> merge -> priority -> crack -> refine -> export
 *   segment (paper 3): range -> segment -> refine -> export
 *   cluster (paper 2): range -> cluster -> refine -> export
 *   best             : range -> the stages of each method in [lod] candidates -> refine ->
 *                      export (refine publishes the most faithful candidate per level) */
enum sl_lod_method {
    SL_METHOD_OCTREE = 1 << 0,
    SL_METHOD_SEGMENT = 1 << 1,
    SL_METHOD_CLUSTER = 1 << 2,
    SL_METHOD_BEST = 1 << 3,
};
#define SL_METHODS_ALL (SL_METHOD_OCTREE | SL_METHOD_SEGMENT | SL_METHOD_CLUSTER | SL_METHOD_BEST)
/* "octree|segment|cluster|best": the [lod] method choices, in bit order. */
#define SL_METHOD_NAMES "octree|segment|cluster|best"
/* The methods `best` may build candidates with ([lod] candidates), in bit order. */
#define SL_CANDIDATE_NAMES "octree|segment|cluster"

typedef struct sl_stage {
    const char *name;         /* also the config section */
    unsigned methods;         /* the methods whose path includes it (sl_lod_method bits) */
    const char *description;  /* one line, for --help and docs */
    uint32_t version;         /* bump when the output for the same input changes */
    const sl_option *options; /* the options this stage declares (usually section == name) */
    /* NULL, or more option tables the stage reads, NULL-terminated, declared once
     * elsewhere and shared by several stages (levels/ladder.h's [levels]). */
    const sl_option *const *shared_options;
    /* Config sections the stage reads, NULL-terminated; NULL = just its own. The stage key
     * hashes exactly these, so a key of another section never reruns this stage. */
    const char *const *sections;
    /* Reads the stage's section into a freshly allocated config struct. */
    int (*configure)(const sl_config *cfg, void **stage_config, sl_error *err);
    void (*release_config)(void *stage_config);
    int (*run)(const void *stage_config, const sl_stage_io *io, sl_error *err);
    /* NULL, or one part of the item's work (io->part of io->parts) into io->out_dir; `run`
     * then joins the parts. The joined result must be byte-identical to `run` alone. */
    int (*run_part)(const void *stage_config, const sl_stage_io *io, sl_error *err);
    /* Nonzero: the stage's output files (all but its report.json) are published with the
     * item under [run] output/ITEM/. */
    int publish;
    /* Nonzero: the stage reads the item's manifest row (io->metadata). Its key then also
     * hashes that row, so editing one item's row reruns this stage of that item only, and
     * stages that do not declare it never rerun for a manifest edit. */
    int reads_metadata;
} sl_stage;

/* Fills `out` (`size` bytes: the stage's flat config struct) with the stage's config at
 * the defaults of its option table, through its own `configure`: what
 * sl_NAME_default_config() returns, for tools and tests that call a stage's work
 * directly. Defaults that fail their own table are a bug: it aborts with a message. */
void sl_stage_default_config(const sl_stage *stage, void *out, size_t size);

/* The engine knows no stage by name: the program hands it the list of stages, in pipeline
 * order (stages/registry.h), when it opens it. */

#endif
