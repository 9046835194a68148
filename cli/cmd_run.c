/* scanlod run | worker | status | verify | plan CONFIG [-s section.key=value]... */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/plan.h"
#include "core/error.h"
#include "core/log.h"
#include "core/signals.h"
#include "formats/scan_read.h"
#include "pipeline/engine.h"
#include "stages/registry.h"

#define MAX_OVERRIDES 128

typedef struct cli_args {
    const char *config;
    const char *overrides[MAX_OVERRIDES];
    int override_count;
    char threads_override[64];
    int quiet, verbose, help, json;
    const char *after_scan; /* worker: the Slurm job whose scan to wait for */
    long wait_seconds;      /* worker: how long to wait for a scan */
} cli_args;

static const char *const usage_text[] = {
    "run", "usage: scanlod run CONFIG [-s section.key=value]... [--threads N] [-q|-v]\n"
           "Converts the whole collection named by CONFIG, resumably: what is done and\n"
           "unchanged is kept, what is missing or stale is (re)built. Exit codes:\n"
           "0 all done, 65 done except quarantined inputs, 75 incomplete (rerun),\n"
           "74 storage needs a human, 70 internal error, 64 usage, 78 bad config.\n",
    "worker", "usage: scanlod worker CONFIG [-s section.key=value]... [--threads N] [-q|-v]\n"
              "                      [--after-scan JOB] [--wait SECONDS]\n"
              "One worker on the queues of CONFIG's work dir (which `scanlod run` fills):\n"
              "claims ready items until none is left. Many may run at once, on many hosts.\n"
              "Before any scan has run in the work dir it waits for one (--wait, default\n"
              "600 s; none came: exit 75). --after-scan JOB waits for the scan of that Slurm\n"
              "job (array job id) instead: the workers of an array start with its run.\n",
    "verify", "usage: scanlod verify CONFIG [-s section.key=value]...\n"
              "Checks that every commit record in the work dir still matches its files\n"
              "(sizes and content hashes). Exit 0 when all do, 65 otherwise.\n",
    "plan", "usage: scanlod plan CONFIG [-s section.key=value]... [--threads N] [--json]\n"
            "Before a run: per item of the collection, the expected peak memory, time and\n"
            "disk, from each scan's PLY header, its shape (a mesh of up to 2 M triangles is\n"
            "read once) and the config (a cost model fitted on this project's runs; nothing\n"
            "is run or written). Exit 0, or 65 when a scan's header cannot be read (said\n"
            "per item).\n",
    "status", "usage: scanlod status CONFIG [-s section.key=value]...\n"
              "Per stage: ready / claimed / done / failed / quarantined, and the reasons.\n",
};

static const char *usage_of(const char *command)
{
    for (size_t i = 0; i < sizeof usage_text / sizeof usage_text[0]; i += 2)
        if (!strcmp(usage_text[i], command))
            return usage_text[i + 1];
    return "";
}

static int parse_args(int argc, char **argv, cli_args *a)
{
    memset(a, 0, sizeof *a);
    a->wait_seconds = 600;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
            a->help = 1;
        } else if (!strcmp(arg, "-q") || !strcmp(arg, "--quiet")) {
            a->quiet = 1;
        } else if (!strcmp(arg, "-v") || !strcmp(arg, "--verbose")) {
            a->verbose = 1;
        } else if ((!strcmp(arg, "-s") || !strcmp(arg, "--set")) && i + 1 < argc) {
            if (a->override_count == MAX_OVERRIDES)
                return -1;
            a->overrides[a->override_count++] = argv[++i];
        } else if (!strcmp(arg, "--threads") && i + 1 < argc) {
            snprintf(a->threads_override, sizeof a->threads_override, "run.threads=%s", argv[++i]);
            if (a->override_count == MAX_OVERRIDES)
                return -1;
            a->overrides[a->override_count++] = a->threads_override;
        } else if (!strcmp(argv[0], "plan") && !strcmp(arg, "--json")) {
            a->json = 1;
        } else if (!strcmp(argv[0], "worker") && !strcmp(arg, "--after-scan") && i + 1 < argc) {
            a->after_scan = argv[++i];
        } else if (!strcmp(argv[0], "worker") && !strcmp(arg, "--wait") && i + 1 < argc) {
            char *end;
            const char *v = argv[++i];
            a->wait_seconds = strtol(v, &end, 10);
            if (*v < '0' || *v > '9' || *end || a->wait_seconds > 7 * 86400) {
                fprintf(stderr, "scanlod worker: --wait takes seconds from 0 to 604800, not '%s'\n",
                        v);
                return -1;
            }
        } else if (arg[0] == '-') {
            fprintf(stderr, "scanlod %s: unknown option '%s'\n", argv[0], arg);
            return -1;
        } else if (!a->config) {
            a->config = arg;
        } else {
            fprintf(stderr, "scanlod %s: unexpected argument '%s'\n", argv[0], arg);
            return -1;
        }
    }
    return 0;
}

static int report_error(const char *command, const sl_error *err)
{
    char line[1600];
    sl_error_format(err, line, sizeof line);
    fprintf(stderr, "scanlod %s: %s\n", command, line);
    return sl_error_exit_code(err->code);
}

static int open_engine(const char *command, int argc, char **argv, int open_logs,
                       sl_engine **e, int *exit_code)
{
    cli_args a;
    if (parse_args(argc, argv, &a) != 0 || (!a.help && !a.config)) {
        fputs(usage_of(command), stderr);
        *exit_code = SL_EXIT_USAGE;
        return -1;
    }
    if (a.help) {
        fputs(usage_of(command), stdout);
        *exit_code = SL_EXIT_OK;
        return -1;
    }
    sl_engine_options opts = {a.config, a.overrides, a.override_count, command,
                              a.quiet, a.verbose, open_logs, sl_stage_registry(),
                              sl_plan_peak_mb, sl_scan_suffixes()};
    sl_error err;
    sl_error_init(&err);
    if (sl_engine_open(e, &opts, &err) != 0) {
        *exit_code = report_error(command, &err);
        return -1;
    }
    return 0;
}

static int run_or_work(int argc, char **argv, int scan)
{
    sl_engine *e;
    int exit_code;
    cli_args a;
    if (open_engine(argv[0], argc, argv, 1, &e, &exit_code) != 0)
        return exit_code;
    parse_args(argc, argv, &a); /* parsed once already by open_engine */
    sl_signals_install();
    sl_error err;
    sl_error_init(&err);
    if (scan) {
        sl_engine_scan(e, &err);
    } else if (sl_engine_wait_for_scan(e, a.after_scan ? a.after_scan : "", a.wait_seconds,
                                       &err) != 0) {
        char line[1600];
        SL_LOG(SL_LOG_ERROR, "worker", NULL, "%s", sl_error_format(&err, line, sizeof line));
        sl_log_close();
        sl_engine_close(e);
        return SL_EXIT_TEMPFAIL;
    }
    sl_error_init(&err);
    if (sl_engine_work(e, &err) != 0) {
        char line[1600];
        SL_LOG(SL_LOG_ERROR, NULL, NULL, "stopped working: %s",
               sl_error_format(&err, line, sizeof line));
    }
    exit_code = sl_engine_finish(e);
    if (sl_signals_received())
        SL_LOG(SL_LOG_WARN, NULL, NULL, "stopped by signal %d; rerun to finish",
               sl_signals_received());
    sl_log_close();
    sl_engine_close(e);
    return exit_code;
}

int sl_cmd_run(int argc, char **argv)
{
    return run_or_work(argc, argv, 1);
}

int sl_cmd_worker(int argc, char **argv)
{
    return run_or_work(argc, argv, 0);
}

int sl_cmd_status(int argc, char **argv)
{
    sl_engine *e;
    int exit_code;
    if (open_engine(argv[0], argc, argv, 0, &e, &exit_code) != 0)
        return exit_code;
    sl_error err;
    sl_error_init(&err);
    exit_code = sl_engine_status(e, stdout, &err) ? report_error(argv[0], &err) : SL_EXIT_OK;
    sl_engine_close(e);
    return exit_code;
}

int sl_cmd_verify(int argc, char **argv)
{
    sl_engine *e;
    int exit_code;
    if (open_engine(argv[0], argc, argv, 0, &e, &exit_code) != 0)
        return exit_code;
    uint64_t checked, bad;
    int rc = sl_engine_verify(e, stdout, &checked, &bad);
    printf("%llu records checked, %llu do not match their files\n", (unsigned long long)checked,
           (unsigned long long)bad);
    sl_engine_close(e);
    return rc ? SL_EXIT_DATAERR : SL_EXIT_OK;
}

int sl_cmd_plan(int argc, char **argv)
{
    sl_engine *e;
    int exit_code;
    cli_args a;
    if (open_engine(argv[0], argc, argv, 0, &e, &exit_code) != 0)
        return exit_code;
    parse_args(argc, argv, &a);
    sl_error err;
    sl_error_init(&err);
    uint64_t unplanned = 0;
    if (sl_plan_print(e, stdout, a.json, &unplanned, &err) != 0)
        exit_code = report_error(argv[0], &err);
    else
        exit_code = unplanned ? SL_EXIT_DATAERR : SL_EXIT_OK;
    sl_engine_close(e);
    return exit_code;
}
