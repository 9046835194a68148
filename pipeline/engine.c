/* Opening and closing an engine: the config, the logs, the work folder (docs/engine.md). */
#include "pipeline/engine_internal.h"

#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/io.h"
#include "core/json.h"
#include "core/log.h"

static void make_run_id(const sl_identity *id, const char *command, char *buf, size_t size)
{
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    char stamp[32];
    strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
    snprintf(buf, size, "%s-%s-%.32s-%ld", stamp, command, id->host, id->pid);
}

/* The stages of [lod] method's path, in registry order (stage.h, sl_lod_method). */
static int choose_method(sl_engine *e, const sl_stage *const *stages, sl_error *err)
{
    const char *method = sl_config_string(e->cfg, "lod", "method");
    const char *names = SL_METHOD_NAMES;
    unsigned bit = 1;
    for (size_t n = strlen(method); strncmp(names, method, n) || (names[n] && names[n] != '|');
         bit <<= 1)
        names = strchr(names, '|') + 1; /* the enum option admits only these names */
    e->method = bit;
    int own = 0; /* stages of this method alone: without one it has no way to make levels */
    for (const sl_stage *const *s = stages; *s && e->stage_count < SL_MAX_STAGES; s++) {
        if (!((*s)->methods & bit))
            continue;
        own += (*s)->methods != SL_METHODS_ALL;
        e->config_hash[e->stage_count] = sl_stage_config_hash(e->cfg, *s);
        e->stages[e->stage_count++] = *s;
    }
    if (own)
        return 0;
    char where[PATH_MAX];
    sl_config_where(e->cfg, "lod", "method", where, sizeof where);
    return sl_error_set(err, SL_E_CONFIG, 0, where,
                        "[lod] method = %s: this build has no stages for it yet", method);
}

int sl_engine_open(sl_engine **out, const sl_engine_options *opts, sl_error *err)
{
    *out = NULL;
    sl_engine *e = calloc(1, sizeof *e);
    if (!e)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    sl_io_fault_init();
    const sl_option *tables[SL_MAX_OPTION_TABLES + 1];
    sl_all_option_tables(opts->stages, tables);
    int rc = sl_config_load(&e->cfg, tables, opts->config_path,
                            opts->overrides, opts->override_count, err);
    if (rc) {
        free(e);
        return rc;
    }
    e->input = sl_config_string(e->cfg, "run", "input");
    e->work = sl_config_string(e->cfg, "run", "work");
    e->output = sl_config_string(e->cfg, "run", "output");
    e->logs = sl_config_string(e->cfg, "run", "logs");
    e->threads = (int)sl_config_int(e->cfg, "run", "threads");
    e->memory_limit_mb = sl_config_int(e->cfg, "run", "memory_limit_mb");
    e->memory_check = sl_config_bool(e->cfg, "run", "memory_check");
    e->expected_peak_mb = opts->expected_peak_mb;
    e->item_timeout_s = sl_config_int(e->cfg, "run", "item_timeout_s");
    e->lease_seconds = sl_config_int(e->cfg, "queue", "lease_seconds");
    e->part_mb = sl_config_double(e->cfg, "queue", "part_mb");
    e->max_crashes = (int)sl_config_int(e->cfg, "queue", "max_crashes");
    rc = choose_method(e, opts->stages, err);
    sl_identity_self(&e->self);

    /* Every stage reads its section now, once, so a value only a stage can judge (a
     * level name, a list) stops the run before any work, as a bad key does. */
    for (int i = 0; rc == 0 && i < e->stage_count; i++) {
        void *stage_config = NULL;
        if (!e->stages[i]->configure)
            continue;
        rc = e->stages[i]->configure(e->cfg, &stage_config, err);
        if (rc == 0 && e->stages[i]->release_config)
            e->stages[i]->release_config(stage_config);
    }
    if (rc == 0)
        rc = sl_engine_check_input(e, err);
    if (rc == 0)
        rc = sl_engine_check_trees(e, err);
    if (rc == 0 && opts->open_logs) {
        char run_id[160];
        make_run_id(&e->self, opts->command, run_id, sizeof run_id);
        static const char *const levels[] = {"error", "warn", "info", "debug"};
        const char *level = sl_config_string(e->cfg, "run", "log_level");
        for (int i = 0; i < 4; i++)
            if (!strcmp(levels[i], level))
                sl_log_level_current = i;
        int stderr_level = opts->quiet ? SL_LOG_ERROR : opts->verbose ? SL_LOG_DEBUG : SL_LOG_INFO;
        if (opts->verbose)
            sl_log_level_current = SL_LOG_DEBUG;
        rc = sl_log_open(e->logs, run_id, stderr_level, err);
    }
    if (rc == 0 && opts->open_logs)
        rc = sl_engine_make_work_layout(e, err);
    if (rc == 0 && opts->open_logs)
        rc = sl_engine_check_writable(e, err);
    if (rc) {
        sl_engine_close(e);
        return rc;
    }
    *out = e;
    return 0;
}

void sl_engine_close(sl_engine *e)
{
    if (!e)
        return;
    sl_config_free(e->cfg);
    for (uint64_t i = 0; i < e->item_count; i++)
        free(e->items[i]);
    free(e->items);
    free(e);
}


