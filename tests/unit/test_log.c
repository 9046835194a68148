/* Logs: the human line format, JSON-lines events (checked by a strict validator), both
 * files shared by forked children without torn lines, the stderr cap, the progress bar
 * on a pseudo-terminal, and logging before sl_log_open. */
#include "core/log.h"
#include "core/progress.h"
#include "tests/check.h"
#include "tests/unit/json_validate.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

static char dir[PATH_MAX];

static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    char *text = NULL;
    size_t n = 0;
    if (f) {
        FILE *mem = open_memstream(&text, &n);
        int c;
        while ((c = fgetc(f)) != EOF)
            fputc(c, mem);
        fclose(mem);
        fclose(f);
    }
    if (size)
        *size = n;
    return text;
}

/* Does `line` start with "YYYY-MM-DDTHH:MM:SS.mmmZ " followed by `rest`? */
static int human_line_is(const char *line, const char *rest)
{
    const char *shape = "dddd-dd-ddTdd:dd:dd.dddZ ";
    for (int k = 0; shape[k]; k++)
        if (shape[k] == 'd' ? (line[k] < '0' || line[k] > '9') : line[k] != shape[k])
            return 0;
    return !strncmp(line + strlen(shape), rest, strlen(rest));
}

/* Runs fn with stderr sent to a file; returns what it wrote (caller frees). */
static char *capture_stderr(void (*fn)(void))
{
    char path[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/stderr.txt", dir);
    int saved = dup(STDERR_FILENO), fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, STDERR_FILENO);
    close(fd);
    fn();
    dup2(saved, STDERR_FILENO);
    close(saved);
    return slurp(path, NULL);
}

static void log_before_open(void)
{
    SL_LOG(SL_LOG_WARN, "range", "bunny/bun000", "no %s yet", "files");
    SL_LOG(SL_LOG_DEBUG, "range", NULL, "skipped: above the level");
    sl_log_event("item_done", "range", "x", 1.0, NULL, NULL); /* no file: dropped */
    sl_log_bar bar = {1, 2, 0.5, 1, -1, "x", 0.5};
    sl_log_progress(&bar);                                     /* not a terminal */
    sl_log_close();
}

static void test_before_open(void)
{
    char *out = capture_stderr(log_before_open);
    CHECK(out && human_line_is(out, "WARN  [range] bunny/bun000: no files yet\n"));
    CHECK(out && strlen(out) == 25 + strlen("WARN  [range] bunny/bun000: no files yet\n"));
    free(out);
}

static void log_some_lines(void)
{
    SL_LOG(SL_LOG_INFO, "range", "bunny/bun000", "read %d points", 40256);
    SL_LOG(SL_LOG_WARN, NULL, "bunny/bun001", "two\nlines");
    SL_LOG(SL_LOG_ERROR, "queue", NULL, "plain");
    SL_LOG(SL_LOG_DEBUG, "range", "x", "not written: above sl_log_level_current");
}

static void test_files(void)
{
    char logs[PATH_MAX + 32], path[PATH_MAX + 64];
    sl_error err;
    sl_error_init(&err);
    snprintf(logs, sizeof logs, "%s/a/b/logs", dir);
    CHECK(sl_log_open(logs, "20261122T054012Z-1234", SL_LOG_WARN, &err) == 0);
    CHECK(!strcmp(sl_log_run_id(), "20261122T054012Z-1234"));
    char *echo = capture_stderr(log_some_lines);
    sl_error_set(&err, SL_E_BADINPUT, 0, "scans/bad \"1\".ply", "vertex count 4294967295\nexceeds");
    sl_log_event("item_failed", "range", "bad \"1\"\xff", 0.25, &err, "\"points\":0");
    sl_log_event("run_start", NULL, NULL, -1, NULL, NULL);
    sl_log_close();

    /* stderr got WARN and ERROR only (stderr_level = WARN) */
    CHECK(echo && !strstr(echo, "read 40256") && strstr(echo, "WARN  bunny/bun001: two lines\n"));
    free(echo);

    snprintf(path, sizeof path, "%s/20261122T054012Z-1234.log", logs);
    char *human = slurp(path, NULL);
    CHECK(human != NULL);
    const char *want[] = {"INFO  [range] bunny/bun000: read 40256 points\n",
                          "WARN  bunny/bun001: two lines\n", "ERROR [queue] plain\n"};
    const char *line = human;
    for (int k = 0; human && k < 3; k++, line = strchr(line, '\n') + 1)
        CHECK_MSG(human_line_is(line, want[k]), "line %d: %s", k, line);
    CHECK(human && *line == '\0');
    free(human);

    snprintf(path, sizeof path, "%s/20261122T054012Z-1234.jsonl", logs);
    char *events = slurp(path, NULL);
    CHECK(events != NULL);
    char *second = events ? strchr(events, '\n') + 1 : NULL;
    CHECK(second && json_valid(events, (size_t)(second - events)));
    CHECK(second && json_valid(second, strlen(second)) && second[strlen(second) - 1] == '\n');
    CHECK(events && strstr(events, "\"run\":\"20261122T054012Z-1234\"") &&
          strstr(events, "\"event\":\"item_failed\",\"stage\":\"range\",\"item\":\"bad \\\"1\\\"\\ufffd\","
                         "\"duration_s\":0.25,\"error\":{\"code\":\"BADINPUT\",\"class\":"
                         "\"badinput\",\"errno\":0,\"file\":\"scans/bad \\\"1\\\".ply\","
                         "\"message\":\"vertex count 4294967295\\nexceeds\"},\"points\":0}\n") &&
          strstr(events, "\"event\":\"run_start\",\"stage\":null,\"item\":null,"
                         "\"duration_s\":null,\"error\":null}\n"));
    free(events);
}

static void test_open_errors(void)
{
    char file[PATH_MAX + 16];
    sl_error err;
    snprintf(file, sizeof file, "%s/plain-file", dir);
    close(open(file, O_WRONLY | O_CREAT, 0644));
    sl_error_init(&err);
    CHECK(sl_log_open(file, "r", SL_LOG_INFO, &err) != 0 && err.sys_errno == ENOTDIR);
    sl_error_init(&err);
    CHECK(sl_log_open(dir, "../escape", SL_LOG_INFO, &err) == SL_E_USAGE);
    sl_error_init(&err);
    CHECK(sl_log_open(NULL, "stderr-only", SL_LOG_INFO, &err) == 0);
    sl_log_close();
}

/* Four children append 300 lines each to the shared files: no line may be torn. */
static void test_forked_children(void)
{
    char logs[PATH_MAX + 16], path[PATH_MAX + 64];
    sl_error err;
    sl_error_init(&err);
    snprintf(logs, sizeof logs, "%s/fork", dir);
    CHECK(sl_log_open(logs, "f", -1, &err) == 0);
    for (int c = 0; c < 4; c++)
        if (fork() == 0) {
            for (int k = 0; k < 300; k++) {
                SL_LOG(SL_LOG_INFO, "range", "item", "child %d line %03d %0200d", c, k, 0);
                sl_log_event("tick", "range", "item", k * 0.5, NULL, "\"n\":1");
            }
            _exit(0);
        }
    int status, all_ok = 1;
    while (wait(&status) > 0)
        all_ok &= WIFEXITED(status) && WEXITSTATUS(status) == 0;
    sl_log_close();
    CHECK(all_ok);
    snprintf(path, sizeof path, "%s/f.log", logs);
    char *human = slurp(path, NULL);
    int lines = 0, good = 1;
    for (char *l = human, *nl; l && (nl = strchr(l, '\n')); l = nl + 1, lines++)
        good &= human_line_is(l, "INFO  [range] item: child ") &&
                nl - l == 25 + (int)strlen("INFO  [range] item: child 0 line 000 ") + 200;
    CHECK_MSG(lines == 1200 && good, "%d lines", lines);
    free(human);
    snprintf(path, sizeof path, "%s/f.jsonl", logs);
    char *events = slurp(path, NULL);
    lines = 0, good = 1;
    for (char *l = events, *nl; l && (nl = strchr(l, '\n')); l = nl + 1, lines++)
        good &= json_valid(l, (size_t)(nl - l));
    CHECK_MSG(lines == 1200 && good, "%d lines", lines);
    free(events);
}

/* Reads what the pty master got until `want` shows up or a second passes. */
static int pty_saw(int master, const char *want, char *got, size_t size)
{
    size_t n = 0;
    got[0] = '\0';
    for (int tries = 0; tries < 20 && !strstr(got, want); tries++) {
        struct pollfd pfd = {master, POLLIN, 0};
        if (poll(&pfd, 1, 50) > 0) {
            ssize_t r = read(master, got + n, size - n - 1);
            n += r > 0 ? (size_t)r : 0;
            got[n] = '\0';
        }
    }
    return strstr(got, want) != NULL;
}

static void sleep_ms(int ms)
{
    struct timespec ts = {0, ms * 1000000L};
    nanosleep(&ts, NULL);
}

/* Draws on a pseudo-terminal; returns the number of failed expectations (CHECK would
 * print into the terminal under test, so the checks are counted here and reported after
 * stderr is back). */
static int progress_bar_failures(int master)
{
    char got[4096], blank[64] = "\r";
    int failed = 0;
    sl_log_bar bar = {12, 40, 0.31, 62, 135, "bun range", 0.45};
    sl_log_progress(&bar);
    const char *first = "\r[###.......] 12/40 items 31%  1:02 ETA 2:15  bun range 45%";
    failed += !pty_saw(master, first, got, sizeof got);
    size_t drawn = strlen(first) - 1;
    bar.done = 13;
    sl_log_progress(&bar);                        /* within 0.1 s: not drawn */
    SL_LOG(SL_LOG_INFO, "range", NULL, "a line"); /* clears the bar first */
    failed += !pty_saw(master, "Z INFO  [range] a line\n", got, sizeof got);
    memset(blank + 1, ' ', drawn); /* the bytes of the bar */
    failed += strstr(got, "13/40") || strncmp(got, blank, drawn + 1) || got[drawn + 1] != '\r';
    /* A line from a process that drew no bar (a stage's child below the engine's bar)
     * erases the line it starts on. */
    SL_LOG(SL_LOG_INFO, "merge", NULL, "from a child");
    failed += !pty_saw(master, "\r\033[K2", got, sizeof got) || !strstr(got, "from a child\n");
    sleep_ms(120);
    sl_log_bar full = {40, 40, 1, 3725, -1,
                       "a label far too long for a sixty column terminal, so it is cut", -1};
    sl_log_progress(&full);
    failed += !pty_saw(master, "\r[##########] 40/40 items 100%  1:02:05  a label far too ",
                       got, sizeof got);
    failed += strlen(got) != 60; /* "\r" + 59 columns: never wraps */
    sl_log_close();
    memset(blank + 1, ' ', 59);
    strcpy(blank + 60, "\r");
    failed += !pty_saw(master, blank, got, sizeof got);
    return failed;
}

static void test_progress_bar(void)
{
    int master = posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || grantpt(master) || unlockpt(master)) {
        printf("no pseudo-terminal: progress bar test skipped\n");
        return;
    }
    int slave = open(ptsname(master), O_RDWR | O_NOCTTY);
    struct termios raw;
    tcgetattr(slave, &raw);
    cfmakeraw(&raw); /* no "\n" -> "\r\n" translation: compare bytes as written */
    tcsetattr(slave, TCSANOW, &raw);
    struct winsize ws = {.ws_row = 24, .ws_col = 60};
    ioctl(master, TIOCSWINSZ, &ws);
    int saved = dup(STDERR_FILENO);
    dup2(slave, STDERR_FILENO);
    int failed = progress_bar_failures(master);
    dup2(saved, STDERR_FILENO);
    close(saved);
    close(slave);
    close(master);
    CHECK_MSG(failed == 0, "%d progress bar expectations failed", failed);
}

static int reports, reports_off_master;
static double last_fraction;
static void count_report(void *ctx, const char *phase, double fraction)
{
#ifdef _OPENMP
    if (omp_get_thread_num() != 0) {
#pragma omp atomic
        reports_off_master++;
    }
#endif
    reports++;
    last_fraction = fraction;
}

/* Inside a parallel region only the master reports, so `report` needs no lock. (Every
 * thread walks all steps: in a worksharing loop the master may get no iterations.) */
static void test_progress_parallel(void)
{
#ifdef _OPENMP
    sl_progress p = {count_report, NULL, NULL};
    reports = 0;
#pragma omp parallel num_threads(4)
    for (int k = 0; k <= 200; k++)
        sl_progress_step(&p, "pca", k / 200.0);
    CHECK_MSG(reports_off_master == 0 && reports > 100, "%d reports, %d off the master",
              reports, reports_off_master);
#else
    printf("built without OpenMP: parallel progress test skipped\n");
#endif
}

static void test_progress_object(void)
{
    volatile sig_atomic_t *flag = sl_interrupt_flag();
    sl_progress p = {count_report, NULL, flag};
    CHECK(flag == sl_interrupt_flag() && *flag == 0);
    CHECK(sl_progress_step(NULL, "x", 0.5) == 0);
    for (int k = 0; k <= 100000; k++)
        sl_progress_step(&p, "normals", k / 100000.0);
    CHECK_MSG(reports == 201, "%d reports", reports); /* one per 1/200 step */
    CHECK(last_fraction == 1.0);
    sl_progress_step(&p, "weld", 1.0); /* a new phase reports at once */
    CHECK(reports == 202);
    *flag = 1;
    CHECK(sl_progress_step(&p, "weld", 1.0) != 0 && sl_progress_interrupted(&p));
    *flag = 0;
}

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/test_log_XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    if (!mkdtemp(dir))
        return 1;
    test_before_open();
    test_files();
    test_open_errors();
    test_forked_children();
    test_progress_bar();
    test_progress_object();
    test_progress_parallel();
    char cmd[PATH_MAX + 16];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
    return check_report();
}
