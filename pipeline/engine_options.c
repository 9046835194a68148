/* The engine's own options ([run], [queue]) and the list of every option table. */
#include "pipeline/config.h"
#include "pipeline/stage.h"

static const sl_option run_options[] = {
    {"run", "input", SL_OPT_PATH, NULL, 0, 0, NULL,
     "Folder tree of .ply files to convert, searched recursively; one file is one item, "
     "its id the file's path relative to this folder (published at OUTPUT/ID/). Links to "
     "folders are not followed. Never written to."},
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
     "OpenMP threads per item; 0 = all cores."},
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
    SL_OPTION_END,
};

static const sl_option lod_options[] = {
    {"lod", "method", SL_OPT_ENUM, "octree", 0, 0, SL_METHOD_NAMES,
     "How the levels are made: octree = the marching-cube octree of paper 1 (any cut in "
     "O(m) from one model file, watertight, crack-free); segment = paper 3's segmentation "
     "(planes kept exactly, the scan's own vertices); cluster = paper 2's clustering "
     "passes with a bounded error. Each method is its own path of stages after range; "
     "switching reruns the stages of the new path only."},
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

void sl_all_option_tables(const sl_stage *const *stages,
                          const sl_option *tables[SL_MAX_OPTION_TABLES + 1])
{
    int n = 0;
    tables[n++] = run_options;
    tables[n++] = lod_options;
    tables[n++] = queue_options;
    for (const sl_stage *const *s = stages; *s && n < SL_MAX_OPTION_TABLES; s++)
        if ((*s)->options)
            tables[n++] = (*s)->options;
    tables[n] = NULL;
}
