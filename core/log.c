/* Logging and the progress bar (see log.h; formats in docs/logs.md).
 *
 * Every line is assembled in memory and written with one write() on an O_APPEND file:
 * the engine's per-item child processes inherit the descriptors across fork(), and a
 * single append is the unit that keeps their lines whole and unmixed. A failed log write
 * is ignored on purpose: losing a log line must never fail an item or the run.
 *
 * The bar is the last thing on the terminal; any line echoed to stderr first overwrites
 * it with spaces in the same write (git's progress.c does the same), and the next
 * sl_log_progress() call draws it again.
 */
#include "core/log.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/json.h"

#define LINE_MAX_BYTES 4096 /* a longer message is cut, so a line stays one write */
#define BAR_MAX_COLUMNS 400
#define BAR_CELLS 10
#define BAR_INTERVAL_S 0.1 /* at most 10 redraws per second */

int sl_log_level_current = SL_LOG_INFO;

static struct {
    int human_fd, events_fd; /* -1 when closed: then lines go to stderr only */
    int stderr_level;
    char run_id[256];
    char host[256];
    double last_draw; /* CLOCK_MONOTONIC seconds of the last bar */
} state = {-1, -1, SL_LOG_INFO, "", "", -1.0};

/* Bytes of the bar now on the terminal (0 = none). Atomic because log lines from any
 * thread clear it; a lost race costs one redraw, never a torn line. */
static atomic_int bar_bytes;

static const char *const level_names[] = {"ERROR", "WARN", "INFO", "DEBUG"};
static const char *const class_names[] = {
    [SL_CLASS_OK] = "ok",           [SL_CLASS_BADINPUT] = "badinput",
    [SL_CLASS_TRANSIENT] = "transient", [SL_CLASS_STORAGE] = "storage",
    [SL_CLASS_CONFIG] = "config",   [SL_CLASS_USAGE] = "usage",
    [SL_CLASS_INTERNAL] = "internal",
};

/* One write(2), retried only on EINTR or a short write (both rare on regular files). */
static void write_all(int fd, const char *buf, size_t n)
{
    while (n > 0) {
        ssize_t done = write(fd, buf, n);
        if (done < 0 && errno == EINTR)
            continue;
        if (done <= 0)
            return; /* see the file comment: logging never fails the caller */
        buf += done;
        n -= (size_t)done;
    }
}

/* "2026-11-22T05:40:12.123Z" */
static void format_time(char *buf, size_t size)
{
    struct timespec ts;
    struct tm tm;
    clock_gettime(CLOCK_REALTIME, &ts);
    gmtime_r(&ts.tv_sec, &tm);
    size_t n = strftime(buf, size, "%Y-%m-%dT%H:%M:%S", &tm);
    snprintf(buf + n, size - n, ".%03ldZ", ts.tv_nsec / 1000000);
}

static double monotonic_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* "\r<spaces>\r" over the bar, if one is drawn; returns the bytes written to buf. */
static size_t take_bar_clear(char *buf)
{
    int n = atomic_exchange(&bar_bytes, 0);
    if (n <= 0)
        return 0;
    buf[0] = '\r';
    memset(buf + 1, ' ', (size_t)n);
    buf[n + 1] = '\r';
    return (size_t)n + 2;
}

void sl_log_progress_clear(void)
{
    char buf[BAR_MAX_COLUMNS + 2];
    size_t n = take_bar_clear(buf);
    if (n)
        write_all(STDERR_FILENO, buf, n);
}

static int stderr_columns(void)
{
    struct winsize ws;
    if (ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) != 0 || ws.ws_col == 0)
        return 80;
    return ws.ws_col > BAR_MAX_COLUMNS ? BAR_MAX_COLUMNS : ws.ws_col;
}

void sl_log_duration(double seconds, char *buf, size_t size)
{
    long long s = seconds > 0 && seconds < 1e9 ? (long long)(seconds + 0.5) : 0;
    long long d = s / 86400, h = s / 3600 % 24, m = s / 60 % 60;
    if (d)
        snprintf(buf, size, "%lldd %lld:%02lld:%02lld", d, h, m, s % 60);
    else if (h)
        snprintf(buf, size, "%lld:%02lld:%02lld", h, m, s % 60);
    else
        snprintf(buf, size, "%lld:%02lld", m, s % 60);
}

/* "[###.......] 12/40 items 31%  1:02 ETA 2:15  bunny/bun000.ply range 45%", cut to fit
 * the terminal (one column short of it, so the cursor never wraps) on a UTF-8 character
 * boundary. */
static size_t format_bar(char *buf, size_t size, const sl_log_bar *bar)
{
    double fraction = bar->fraction >= 0 ? (bar->fraction > 1 ? 1 : bar->fraction) : 0;
    int filled = fraction >= 1 ? BAR_CELLS : (int)(fraction * BAR_CELLS);
    char cells[BAR_CELLS + 1], total[32] = "", percent[16] = "", times[64] = "";
    memset(cells, '#', (size_t)filled);
    memset(cells + filled, '.', (size_t)(BAR_CELLS - filled));
    cells[BAR_CELLS] = '\0';
    if (bar->total)
        snprintf(total, sizeof total, "/%llu", (unsigned long long)bar->total);
    if (bar->fraction >= 0)
        snprintf(percent, sizeof percent, " %d%%", (int)(fraction * 100));
    if (bar->elapsed_s >= 0) {
        char elapsed[24], eta[24];
        sl_log_duration(bar->elapsed_s, elapsed, sizeof elapsed);
        sl_log_duration(bar->eta_s, eta, sizeof eta);
        snprintf(times, sizeof times, "  %s%s%s", elapsed, bar->eta_s >= 0 ? " ETA " : "",
                 bar->eta_s >= 0 ? eta : "");
    }
    int n = snprintf(buf, size, "[%s] %llu%s items%s%s%s%s", cells,
                     (unsigned long long)bar->done, total, percent, times,
                     bar->label ? "  " : "", bar->label ? bar->label : "");
    if (n >= 0 && (size_t)n < size && bar->stage_fraction >= 0 && bar->stage_fraction <= 1)
        n += snprintf(buf + n, size - (size_t)n, " %d%%", (int)(bar->stage_fraction * 100));
    size_t len = n < 0 ? 0 : (size_t)n < size ? (size_t)n : size - 1;
    size_t width = (size_t)stderr_columns() - 1;
    if (len > width) {
        len = width;
        while (len > 0 && ((unsigned char)buf[len] & 0xC0) == 0x80)
            len--;
    }
    buf[len] = '\0';
    return len;
}

void sl_log_progress(const sl_log_bar *bar)
{
    double now = monotonic_seconds();
    if (state.last_draw >= 0 && now - state.last_draw < BAR_INTERVAL_S)
        return;
    if (!isatty(STDERR_FILENO))
        return;
    state.last_draw = now;
    char text[BAR_MAX_COLUMNS + 1], buf[2 * BAR_MAX_COLUMNS + 2];
    size_t len = format_bar(text, sizeof text, bar);
    int old = atomic_exchange(&bar_bytes, (int)len);
    buf[0] = '\r';
    memcpy(buf + 1, text, len);
    size_t pad = old > (int)len ? (size_t)old - len : 0; /* blank what the old bar left */
    memset(buf + 1 + len, ' ', pad);
    write_all(STDERR_FILENO, buf, 1 + len + pad);
}

/* Control characters in a message would break the one-line-per-record format. */
static void flatten(char *s)
{
    for (; *s; s++)
        if ((unsigned char)*s < 0x20)
            *s = ' ';
}

void sl_log_write(int level, const char *stage, const char *item, const char *fmt, ...)
{
    if (level > sl_log_level_current)
        return;
    char line[LINE_MAX_BYTES], time_text[32];
    int lv = level < SL_LOG_ERROR ? SL_LOG_ERROR : level > SL_LOG_DEBUG ? SL_LOG_DEBUG : level;
    format_time(time_text, sizeof time_text);
    int n = snprintf(line, sizeof line - 1, "%s %-5s %s%s%s%s%s", time_text, level_names[lv],
                     stage ? "[" : "", stage ? stage : "", stage ? "] " : "", item ? item : "",
                     item ? ": " : "");
    size_t len = n < 0 ? 0 : (size_t)n < sizeof line - 1 ? (size_t)n : sizeof line - 2;
    va_list ap;
    va_start(ap, fmt);
    n = vsnprintf(line + len, sizeof line - 1 - len, fmt, ap);
    va_end(ap);
    if (n > 0 && (size_t)n >= sizeof line - 1 - len)
        memcpy(line + sizeof line - 5, "...", 3); /* cut: say so */
    flatten(line);
    len = strlen(line);
    line[len++] = '\n';
    if (state.human_fd >= 0)
        write_all(state.human_fd, line, len);
    if (level <= state.stderr_level) {
        char out[LINE_MAX_BYTES + BAR_MAX_COLUMNS + 8];
        size_t k = take_bar_clear(out);
        /* A bar drawn by another process on this terminal (the engine's, above a stage's
         * child) is not in bar_bytes here: "\r" + erase-line clears whatever line we are
         * on, so no message is ever glued onto a bar. */
        if (k == 0 && isatty(STDERR_FILENO)) {
            memcpy(out, "\r\033[K", 4);
            k = 4;
        }
        memcpy(out + k, line, len);
        write_all(STDERR_FILENO, out, k + len);
    }
}

static void add_error(sl_json *j, const sl_error *err)
{
    if (!err || err->code == SL_OK) {
        sl_json_raw(j, "error", "null");
        return;
    }
    enum sl_error_class cls = sl_error_class_of(err->code);
    sl_json_object_begin(j, "error");
    sl_json_string(j, "code", sl_error_name(err->code));
    sl_json_string(j, "class", class_names[cls]);
    sl_json_i64(j, "errno", err->sys_errno);
    sl_json_string(j, "file", err->file);
    sl_json_string(j, "message", err->message[0] ? err->message : sl_strerror(err->code));
    sl_json_object_end(j);
}

void sl_log_event(const char *event, const char *stage, const char *item, double duration_s,
                  const sl_error *err, const char *extra_json)
{
    if (state.events_fd < 0)
        return; /* events are for tools; without a log folder there is no one to read them */
    char time_text[32];
    sl_json j;
    format_time(time_text, sizeof time_text);
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "time", time_text);
    sl_json_string(&j, "run", state.run_id);
    sl_json_string(&j, "host", state.host);
    sl_json_i64(&j, "pid", (int64_t)getpid()); /* per call: children share the file */
    sl_json_string(&j, "event", event);
    sl_json_string(&j, "stage", stage);
    sl_json_string(&j, "item", item);
    if (duration_s >= 0 && isfinite(duration_s))
        sl_json_double(&j, "duration_s", duration_s);
    else
        sl_json_raw(&j, "duration_s", "null");
    add_error(&j, err);
    sl_json_raw_members(&j, extra_json);
    sl_json_object_end(&j);
    sl_json_raw(&j, NULL, "\n"); /* at the top level a raw value is appended as is */
    if (!j.failed)
        write_all(state.events_fd, j.buf, j.len);
    sl_json_release(&j);
}

/* mkdir -p: every missing component, 0777 less the umask. */
static int make_directories(const char *dir, sl_error *err)
{
    char path[4096];
    if (snprintf(path, sizeof path, "%s", dir) >= (int)sizeof path)
        return sl_error_errno(err, ENAMETOOLONG, dir, "mkdir");
    for (char *p = path + 1;; p++) {
        if (*p != '/' && *p != '\0')
            continue;
        char saved = *p;
        *p = '\0';
        if (mkdir(path, 0777) != 0 && errno != EEXIST)
            return sl_error_errno(err, errno, path, "mkdir");
        if (!saved)
            return 0;
        *p = saved;
    }
}

static int open_log_file(const char *dir, const char *suffix, int *fd, sl_error *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s%s", dir, state.run_id, suffix);
    *fd = open(path, O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0666);
    return *fd < 0 ? sl_error_errno(err, errno, path, "open") : 0;
}

int sl_log_open(const char *dir, const char *run_id, int stderr_level, sl_error *err)
{
    sl_log_close();
    state.stderr_level = stderr_level;
    if (gethostname(state.host, sizeof state.host) != 0)
        snprintf(state.host, sizeof state.host, "unknown");
    state.host[sizeof state.host - 1] = '\0';
    if (!run_id || !run_id[0] || strchr(run_id, '/') || strlen(run_id) >= sizeof state.run_id ||
        !strcmp(run_id, ".") || !strcmp(run_id, ".."))
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "bad run id '%.64s'", run_id ? run_id : "");
    snprintf(state.run_id, sizeof state.run_id, "%s", run_id);
    if (!dir)
        return 0;
    int rc = make_directories(dir, err);
    if (rc == 0)
        rc = open_log_file(dir, ".log", &state.human_fd, err);
    if (rc == 0)
        rc = open_log_file(dir, ".jsonl", &state.events_fd, err);
    if (rc != 0)
        sl_log_close();
    return rc;
}

void sl_log_close(void)
{
    sl_log_progress_clear();
    if (state.human_fd >= 0)
        close(state.human_fd);
    if (state.events_fd >= 0)
        close(state.events_fd);
    state.human_fd = state.events_fd = -1;
    state.stderr_level = SL_LOG_INFO; /* as if never opened */
    state.last_draw = -1.0;
}

const char *sl_log_run_id(void)
{
    return state.run_id;
}
