/* The engine's own options ([run], [queue]) and the list of every option table. */
#include "pipeline/config.h"
#include "pipeline/stage.h"

static const sl_option run_options[] = {
    {"run", "input", SL_OPT_PATH, NULL, 0, 0, NULL,
     "Folder tree of scans to convert (every file named as a format scanlod reads: "
     "docs/inputs.md), searched recursively; one file is one item, "
     "its id the file's path relative to this folder (published at OUTPUT/ID/). Links to "
     "folders are not followed. Never written to."},
    {"run", "manifest", SL_OPT_STRING, "", 0, 0, NULL,
     "The collection manifest (docs/metadata.md): per item its title, accession number, "
     "units, up axis, credit, licence and description, for the pages, the Voyager scene and "
     "the item's frame. Empty = manifest.csv or manifest.json at the root of input, if there "
     "is one; none = no manifest; else the file (CSV, or JSON by its .json suffix; relative "
     "to this config file's folder). Read once per run; a malformed manifest stops the run "
     "before any work (exit 78), naming its file and line. Editing an item's row reruns "
     "that item's export only."},
    {"run", "work", SL_OPT_PATH, NULL, 0, 0, NULL,
     "Work directory: queues, intermediate artifacts and their commit records. Share it "
     "between hosts to run workers on a cluster."},
    {"run", "output", SL_OPT_PATH, NULL, 0, 0, NULL,
     "Published results: one folder per item, replaced atomically. Input, work, output "
     "and logs must be four folders none of which contains another."},
    {"run", "logs", SL_OPT_PATH, "logs", 0, 0, NULL,
     "Folder for the human log and the JSON-lines event log of each run (relative to the "
     "current directory when left at the default)."},
    {"run", "threads", SL_OPT_INT, "0", 0, 1024, NULL,
     "OpenMP threads per item; 0 = OMP_NUM_THREADS when set (as job scripts set it), else all cores."},
    {"run", "memory_limit_mb", SL_OPT_INT, "0", 0, 1 << 30, NULL,
     "Memory limit per item process in MiB (setrlimit RLIMIT_DATA: the heap and other "
     "private writable memory, not mapped libraries); 0 = none. An item over it fails as "
     "out of memory and is retried on the next run, never quarantined. Also the budget of "
     "memory_check (0: the node's memory, or its cgroup's limit). Allocated memory is at "
     "least the peak RSS `scanlod plan` predicts: leave 30 % headroom over it."},
    {"run", "memory_check", SL_OPT_BOOL, "true", 0, 0, NULL,
     "Before each stage, estimate the item's peak memory from its PLY header (the model of "
     "`scanlod plan`) and do not run an item expected over the budget (memory_limit_mb, or "
     "the node's memory): it fails as out of memory at once, with what it needs, instead "
     "of being killed hours in, every night."},
    {"run", "item_timeout_s", SL_OPT_INT, "0", 0, 30 * 86400, NULL,
     "Wall-time limit of one stage of one item in seconds; 0 = none. A timed-out item counts "
     "as a crash: retried once, then quarantined."},
    {"run", "log_level", SL_OPT_ENUM, "info", 0, 0, "error|warn|info|debug",
     "Least severe message written to the log files."},
    {"run", "log_keep", SL_OPT_INT, "200", 0, 1000000, NULL,
     "Every run and worker writes two log files (RUN.log, RUN.jsonl) into [run] logs; "
     "when one starts, the files of all but the newest this many runs there are deleted "
     "(never those of a run still going on this host). 0 = keep every log."},
    SL_OPTION_END,
};

static const sl_option lod_options[] = {
    {"lod", "method", SL_OPT_ENUM, "best", 0, 0, SL_METHOD_NAMES,
     "How the levels are made (docs/levels.md): octree = the marching-cube octree of paper 1 "
     "(any cut in O(m) from one model file, watertight, crack-free); segment = paper 3's "
     "segmentation (planes kept exactly, the scan's own vertices); cluster = paper 2's "
     "clustering passes with a bounded error; best = candidates from the methods in "
     "candidates and, for a mesh, the scan itself simplified, each refined ([refine]) and "
     "measured against the input, the most faithful published per level. Each method is "
     "its own path of stages after range; switching reruns the stages of the new path "
     "only."},
    {"lod", "candidates", SL_OPT_LIST, "octree", 0, 0, SL_CANDIDATE_NAMES,
     "method = best: the methods that build candidate levels besides the scan itself (a "
     "point set has only these). octree also gives the item its model.slod (any level in "
     "O(m) for viewers). segment and cluster cost more time (docs/benchmarks.md)."},
    SL_OPTION_END,
};

static const sl_option queue_options[] = {
    {"queue", "lease_seconds", SL_OPT_INT, "600", 2, 7 * 86400, NULL,
     "Lease of a claimed item; renewed every fifth of it while the item runs. Another host "
     "reclaims an item whose lease expired (dead node); on the same host a dead owner is "
     "seen at once. Keep it well above filesystem stalls (NFS attribute caches: 60 s)."},
    {"queue", "max_crashes", SL_OPT_INT, "2", 1, 100, NULL,
     "Crashes of our own code (segfault, abort, timeout) an item may cause before it is "
     "quarantined and flagged as a bug."},
    {"queue", "part_mb", SL_OPT_DOUBLE, "0", 0, 1 << 30, NULL,
     "Split a stage that can be split (today the samples stage) into work items of about "
     "this many MB of input PLY each, claimed, leased and committed like items, so that "
     "workers on many nodes share one large scan and a killed worker redoes only its part; "
     "the joined result is byte-identical to the unsplit one. 0 = never split (one process "
     "per item and stage)."},
    SL_OPTION_END,
};

/* A table several stages share is listed once. */
static void add_table(const sl_option **tables, int *n, const sl_option *table)
{
    for (int i = 0; table && i < *n; i++)
        if (tables[i] == table)
            return;
    if (table && *n < SL_MAX_OPTION_TABLES)
        tables[(*n)++] = table;
}

void sl_all_option_tables(const sl_stage *const *stages,
                          const sl_option *tables[SL_MAX_OPTION_TABLES + 1])
{
    int n = 0;
    tables[n++] = run_options;
    tables[n++] = lod_options;
    tables[n++] = queue_options;
    /* Tables several stages share (the ladder) first: they are about the whole method. */
    for (const sl_stage *const *s = stages; *s; s++)
        for (const sl_option *const *t = (*s)->shared_options; t && *t; t++)
            add_table(tables, &n, *t);
    for (const sl_stage *const *s = stages; *s; s++)
        add_table(tables, &n, (*s)->options);
    tables[n] = NULL;
}
