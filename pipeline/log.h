/* Logging: a human log and a JSON-lines event log per run, in `[run] logs`.
 *
 * Every line carries the run id, stage and item. Results go to stdout (by the commands),
 * chatter to stderr and the human log; the progress bar is drawn on stderr only when it
 * is a terminal, and is cleared before any log line. Child processes (one per item) keep
 * writing to the same files: each line is a single O_APPEND write.
 */
#ifndef SCANLOD_PIPELINE_LOG_H
#define SCANLOD_PIPELINE_LOG_H

#include <stdint.h>

#include "pipeline/error.h"

enum sl_log_level { SL_LOG_ERROR = 0, SL_LOG_WARN, SL_LOG_INFO, SL_LOG_DEBUG };

extern int sl_log_level_current; /* messages above it are skipped */

/* Opens `<dir>/<run_id>.log` and `<dir>/<run_id>.jsonl` (creating dir). With dir == NULL
 * logs only to stderr. `stderr_level` caps what is echoed to stderr. */
int sl_log_open(const char *dir, const char *run_id, int stderr_level, sl_error *err);
void sl_log_close(void);
const char *sl_log_run_id(void);

#define SL_LOG(level, stage, item, ...)                                               \
    do {                                                                              \
        if ((level) <= sl_log_level_current)                                          \
            sl_log_write((level), (stage), (item), __VA_ARGS__);                      \
    } while (0)

void sl_log_write(int level, const char *stage, const char *item, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* One JSON line: {"time":..,"run":..,"host":..,"pid":..,"event":..,"stage":..,"item":..,
 * "duration_s":..,"error":{"code":..,"class":..,"file":..,"message":..},<extra>} where
 * `extra_json` (may be NULL) is a comma-separated list of members ("\"k\":1,\"j\":2"). */
void sl_log_event(const char *event, const char *stage, const char *item, double duration_s,
                  const sl_error *err, const char *extra_json);

/* Progress bar on stderr when it is a TTY (no-op otherwise). label may be NULL. */
void sl_log_progress(uint64_t done, uint64_t total, const char *label, double item_fraction);
void sl_log_progress_clear(void);

#endif
