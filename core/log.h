/* Logging: a human log and a JSON-lines event log per run, in `[run] logs`.
 *
 * Every line carries the stage and item; events carry the run id, human lines have it in
 * their file's name (`<run_id>.log`). Results go to stdout (by the commands),
 * chatter to stderr and the human log; the progress bar is drawn on stderr only when it
 * is a terminal, and is cleared before any log line. Child processes (one per item) keep
 * writing to the same files: each line is a single O_APPEND write.
 */
#ifndef SCANLOD_CORE_LOG_H
#define SCANLOD_CORE_LOG_H

#include <stdint.h>

#include "core/error.h"

enum sl_log_level { SL_LOG_ERROR = 0, SL_LOG_WARN, SL_LOG_INFO, SL_LOG_DEBUG };

extern int sl_log_level_current; /* messages above it are skipped */

/* Opens `<dir>/<run_id>.log` and `<dir>/<run_id>.jsonl` (creating dir like mkdir -p;
 * O_APPEND|O_CREAT|O_CLOEXEC, so forked children share them). With dir == NULL logs only
 * to stderr. `stderr_level` caps what is echoed to stderr (-1: nothing); the files get
 * everything up to sl_log_level_current. run_id: non-empty, no '/', under 256 bytes,
 * else SL_E_USAGE. Before sl_log_open and after sl_log_close, lines go to stderr only
 * (up to SL_LOG_INFO) and events are dropped. Not thread-safe against concurrent
 * logging; call it before starting threads or children. */
int sl_log_open(const char *dir, const char *run_id, int stderr_level, sl_error *err);
void sl_log_close(void);
const char *sl_log_run_id(void);

#define SL_LOG(level, stage, item, ...)                                               \
    do {                                                                              \
        if ((level) <= sl_log_level_current)                                          \
            sl_log_write((level), (stage), (item), __VA_ARGS__);                      \
    } while (0)

/* One line "2026-11-22T05:40:12.123Z INFO  [stage] item: message" (UTC; "[stage] " and
 * "item: " left out when NULL), written with one write() to the log file and, up to
 * stderr_level, to stderr. Control characters in the message become spaces; a line is
 * cut at 4 KiB ("..."). Safe from any thread and from forked children. */
void sl_log_write(int level, const char *stage, const char *item, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* One JSON line: {"time":..,"run":..,"host":..,"pid":..,"event":..,"stage":..,"item":..,
 * "duration_s":..,"error":{"code":..,"class":..,"errno":..,"file":..,"message":..},<extra>}
 * where `extra_json` (may be NULL) is a comma-separated list of members
 * ("\"k\":1,\"j\":2"). Every key is always present: stage/item null when NULL,
 * duration_s null when negative, error null when err is NULL or holds no failure.
 * Schema in docs/logs.md. */
void sl_log_event(const char *event, const char *stage, const char *item, double duration_s,
                  const sl_error *err, const char *extra_json);

/* What the progress bar shows. */
typedef struct sl_log_bar {
    uint64_t done, total;  /* items settled / items in the collection (total 0: unknown) */
    double fraction;       /* of the whole collection's work, 0..1 (the caller keeps it
                              monotone); < 0: not known */
    double elapsed_s;      /* since the work began */
    double eta_s;          /* time left; < 0: not known yet */
    const char *label;     /* "ITEM STAGE", or NULL */
    double stage_fraction; /* of the running stage, 0..1; < 0 leaves it out */
} sl_log_bar;

/* Progress bar on stderr when it is a TTY (no-op otherwise), redrawn with "\r" at most
 * 10 times a second (calls in between are dropped):
 *   "[###.......] 12/40 items 31%  1:02 ETA 2:15  bunny.ply samples 45%"
 * the cells filled by `fraction`; cut to the terminal width, never wrapping. Log lines
 * written meanwhile (by this process or a child sharing the terminal) start with "\r" and
 * an erase-line, so they never sit on the bar's line; the next call draws the bar again
 * below them. Call from one thread. */
void sl_log_progress(const sl_log_bar *bar);
void sl_log_progress_clear(void);
/* "1:02", "1:02:03" or "3d 4:05:06": a duration for people (size >= 16). */
void sl_log_duration(double seconds, char *buf, size_t size);

#endif
