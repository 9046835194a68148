/* On-disk queues (pipeline/queue.h): create, put, find, move between states, list; many
 * processes claiming one ticket by rename: exactly one wins, the others hear SL_E_BUSY;
 * a move that fails (injected) leaves the ticket where it was; torn tickets are refused;
 * item ids that need escaping get distinct ticket names that a listing never hides. */
#include "pipeline/queue.h"
#include "tests/check.h"
#include "tests/unit/durable_checks.h"

#include <errno.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#define CLAIMERS 8
#define ROUNDS 25

static char work[PATH_MAX];
static const char *const stage = "range";

/* The path of ticket `name` in `state`, plain (for the checks). */
static void ticket_path(int state, const char *name, char *path, size_t size)
{
    CHECK(sl_queue_path(path, size, work, stage, state, name) == 0);
}

static sl_ticket ticket_for(const char *item)
{
    sl_ticket t;
    sl_ticket_init(&t);
    snprintf(t.item, sizeof t.item, "%s", item);
    snprintf(t.source, sizeof t.source, "%s.ply", item);
    snprintf(t.key, sizeof t.key, "0123456789abcdef0123456789abcdef");
    t.attempt = 2;
    t.epoch = 7;
    snprintf(t.host, sizeof t.host, "node-1");
    t.pid = 4242;
    t.expires = 1700000000;
    snprintf(t.reason, sizeof t.reason, "first line\nsecond line");
    t.memory_limit_mb = 90;
    snprintf(t.run, sizeof t.run, "20261206T092636Z-run-node-1-4242");
    t.parts = 8;
    return t;
}

static void test_create_put_move_find(void)
{
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_queue_create(work, stage, &err) == 0);
    for (int s = 0; s < SL_STATE_COUNT; s++) {
        char path[PATH_MAX];
        ticket_path(s, NULL, path, sizeof path);
        struct stat st;
        CHECK_MSG(stat(path, &st) == 0 && S_ISDIR(st.st_mode), "no %s/", sl_queue_state_name(s));
    }
    CHECK(sl_queue_create(work, stage, &err) == 0); /* again: nothing to do */
    CHECK(sl_queue_find(work, stage, "cow") == SL_STATE_NONE);

    sl_ticket t = ticket_for("cow");
    CHECK(sl_queue_put(work, stage, SL_STATE_READY, "cow", &t, &err) == 0);
    CHECK(sl_queue_find(work, stage, "cow") == SL_STATE_READY);
    char path[PATH_MAX];
    ticket_path(SL_STATE_READY, "cow", path, sizeof path);
    sl_ticket back;
    CHECK(sl_ticket_read(path, &back, &err) == 0);
    CHECK(!strcmp(back.item, "cow") && !strcmp(back.source, "cow.ply"));
    CHECK(!strcmp(back.key, t.key) && back.attempt == 2 && back.epoch == 7 && back.pid == 4242);
    CHECK(!strcmp(back.host, "node-1") && back.expires == 1700000000);
    CHECK_MSG(!strcmp(back.reason, "first line second line"), "reason '%s'", back.reason);
    /* What issue 34 added: the limit a crash ran under, the run a failure waits out, the
     * split a part belongs to. A ticket of an older build has no limit: -1, not 0. */
    CHECK(back.memory_limit_mb == 90 && back.parts == 8 &&
          !strcmp(back.run, "20261206T092636Z-run-node-1-4242"));
    FILE *old = fopen(path, "w");
    fputs("item=cow\nsource=cow.ply\nkey=0123456789abcdef0123456789abcdef\nclass=bug\nend\n", old);
    fclose(old);
    CHECK(sl_ticket_read(path, &back, &err) == 0 && back.memory_limit_mb == -1 &&
          back.parts == 0 && !back.run[0]);

    /* ready -> claimed -> done; a move from a state that no longer holds it is BUSY. */
    CHECK(sl_queue_move(work, stage, "cow", SL_STATE_READY, SL_STATE_CLAIMED, &err) == 0);
    CHECK(sl_queue_find(work, stage, "cow") == SL_STATE_CLAIMED);
    CHECK(sl_queue_move(work, stage, "cow", SL_STATE_READY, SL_STATE_CLAIMED, &err) == SL_E_BUSY);
    CHECK(sl_queue_move(work, stage, "cow", SL_STATE_CLAIMED, SL_STATE_DONE, &err) == 0);
    CHECK(sl_queue_find(work, stage, "cow") == SL_STATE_DONE);
    ticket_path(SL_STATE_CLAIMED, "cow", path, sizeof path);
    CHECK(access(path, F_OK) != 0);
    CHECK(sl_queue_move(work, stage, "cow", SL_STATE_DONE, SL_STATE_READY, &err) == 0);
    CHECK(err.code == SL_OK);
}

static void test_list(void)
{
    sl_error err;
    sl_error_init(&err);
    const char *items[] = {"rocker_arm", "bun_zipper_res3", "cow2", "armadillo", "fandisk"};
    for (size_t i = 0; i < sizeof items / sizeof items[0]; i++) {
        sl_ticket t = ticket_for(items[i]);
        CHECK(sl_queue_put(work, stage, SL_STATE_FAILED, items[i], &t, &err) == 0);
    }
    /* A writer's temp and other dot files are never tickets. */
    char path[PATH_MAX];
    ticket_path(SL_STATE_FAILED, ".cow2.node-1.77.0.tmp", path, sizeof path);
    CHECK(durable_put(path, "item=x\n", 7) == 0);
    char **names = NULL;
    int count = -1;
    CHECK(sl_queue_list(work, stage, SL_STATE_FAILED, &names, &count, &err) == 0);
    CHECK_EQ_U64(count, 5);
    const char *sorted[] = {"armadillo", "bun_zipper_res3", "cow2", "fandisk", "rocker_arm"};
    for (int i = 0; i < count && i < 5; i++)
        CHECK_MSG(!strcmp(names[i], sorted[i]), "%d: %s", i, names[i]);
    free(names);
    CHECK(sl_queue_list(work, stage, SL_STATE_QUARANTINE, &names, &count, &err) == 0);
    CHECK(count == 0);
    free(names);
    /* A queue that was never created lists empty. */
    CHECK(sl_queue_list(work, "nosuchstage", SL_STATE_READY, &names, &count, &err) == 0);
    CHECK(count == 0);
    free(names);
}

/* ---- concurrent claims ------------------------------------------------------------- */

typedef struct claim {
    const char *name;
    int go; /* read end of the start pipe */
} claim;

enum { CLAIM_WON = 10, CLAIM_BUSY = 11, CLAIM_ERROR = 12 };

static int claim_one(void *arg)
{
    const claim *c = arg;
    char byte;
    if (read(c->go, &byte, 1) != 0) /* EOF: every claimer has been forked */
        return CLAIM_ERROR;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_queue_move(work, stage, c->name, SL_STATE_READY, SL_STATE_CLAIMED, &err);
    return rc == 0 ? CLAIM_WON : rc == SL_E_BUSY ? CLAIM_BUSY : CLAIM_ERROR;
}

/* Forks CLAIMERS processes that wait on one pipe and rename the same ticket at once. */
static void claim_race(const char *name, int *won, int *busy)
{
    int go[2];
    CHECK(pipe(go) == 0);
    claim c = {name, go[0]};
    pid_t pids[CLAIMERS];
    for (int i = 0; i < CLAIMERS; i++) {
        pids[i] = fork();
        if (pids[i] == 0) {
            close(go[1]);
            _exit(claim_one(&c));
        }
    }
    close(go[0]);
    close(go[1]); /* releases them all together */
    *won = *busy = 0;
    for (int i = 0; i < CLAIMERS; i++) {
        int status;
        waitpid(pids[i], &status, 0);
        int v = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        *won += v == CLAIM_WON;
        *busy += v == CLAIM_BUSY;
    }
}

static void test_concurrent_claims(void)
{
    sl_error err;
    sl_error_init(&err);
    for (int r = 0; r < ROUNDS; r++) {
        char name[32];
        snprintf(name, sizeof name, "race%02d", r);
        sl_ticket t = ticket_for(name);
        CHECK(sl_queue_put(work, stage, SL_STATE_READY, name, &t, &err) == 0);
        int won, busy;
        claim_race(name, &won, &busy);
        CHECK_MSG(won == 1 && busy == CLAIMERS - 1, "%s: %d won, %d busy", name, won, busy);
        CHECK(sl_queue_find(work, stage, name) == SL_STATE_CLAIMED);
        char path[PATH_MAX];
        ticket_path(SL_STATE_CLAIMED, name, path, sizeof path);
        sl_ticket back;
        CHECK(sl_ticket_read(path, &back, &err) == 0 && !strcmp(back.item, name));
    }
}

/* ---- a move or put that fails -------------------------------------------------------
 * Run first: the parent must not call core/io.c before these forks (durable_checks.h). */

static int setup_faulty(void *arg)
{
    (void)arg;
    sl_error err;
    sl_error_init(&err);
    sl_ticket t = ticket_for("faulty");
    return sl_queue_create(work, stage, &err) || sl_queue_put(work, stage, SL_STATE_READY,
                                                              "faulty", &t, &err);
}

/* 0: done; 1: failed with the error recorded; 2: failed without it. */
static int failure_verdict(int rc, const sl_error *err)
{
    return rc == 0 ? 0 : err->code == rc && err->message[0] ? 1 : 2;
}

static int move_faulted(void *arg)
{
    (void)arg;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_queue_move(work, stage, "faulty", SL_STATE_READY, SL_STATE_CLAIMED, &err);
    return failure_verdict(rc, &err);
}

static int put_faulted(void *arg)
{
    (void)arg;
    sl_error err;
    sl_error_init(&err);
    sl_ticket t = ticket_for("fresh");
    return failure_verdict(sl_queue_put(work, stage, SL_STATE_READY, "fresh", &t, &err), &err);
}

static void test_failed_move_and_put(void)
{
    CHECK(durable_run(setup_faulty, NULL, NULL) == 0);
    /* The rename fails: the ticket stays ready, and the error is not "busy". */
    CHECK(durable_run(move_faulted, NULL, "rename:1:EIO") == 1);
    CHECK(sl_queue_find(work, stage, "faulty") == SL_STATE_READY);
    /* The rename is done but the new directory's fsync fails: claimed, the caller told. */
    CHECK(durable_run(move_faulted, NULL, "fsync:1:EIO") == 1);
    CHECK(sl_queue_find(work, stage, "faulty") == SL_STATE_CLAIMED);
    /* A ticket whose write or rename fails does not appear, and leaves no temp. */
    char ready[PATH_MAX];
    ticket_path(SL_STATE_READY, NULL, ready, sizeof ready);
    CHECK(durable_run(put_faulted, NULL, "write:1:ENOSPC") == 1);
    CHECK(sl_queue_find(work, stage, "fresh") == SL_STATE_NONE && durable_temps(ready) == 0);
    CHECK(durable_run(put_faulted, NULL, "rename:1:EIO") == 1);
    CHECK(sl_queue_find(work, stage, "fresh") == SL_STATE_NONE && durable_temps(ready) == 0);
    CHECK(durable_run(put_faulted, NULL, NULL) == 0);
    CHECK(sl_queue_find(work, stage, "fresh") == SL_STATE_READY);
}

/* ---- torn and malformed tickets ---------------------------------------------------- */

static void expect_torn(const char *text, const char *what)
{
    char path[PATH_MAX];
    ticket_path(SL_STATE_READY, "torn", path, sizeof path);
    CHECK(durable_put(path, text, strlen(text)) == 0);
    sl_ticket t;
    sl_error err;
    sl_error_init(&err);
    CHECK_MSG(sl_ticket_read(path, &t, &err) == SL_E_CORRUPT, "%s: accepted", what);
    CHECK_MSG(strstr(err.file, "torn") != NULL, "%s: error names '%s'", what, err.file);
    unlink(path);
}

static void test_torn_tickets(void)
{
    sl_ticket t = ticket_for("whole");
    char path[PATH_MAX], *text;
    size_t size = 0;
    sl_error err;
    sl_error_init(&err);
    ticket_path(SL_STATE_READY, "whole", path, sizeof path);
    CHECK(sl_ticket_write(path, &t, &err) == 0);
    text = durable_slurp(path, &size);
    CHECK(text && size > 20 && !strcmp(text + size - 4, "end\n"));
    /* Every strict prefix of a ticket (a write cut short) is refused... */
    int accepted = 0;
    for (size_t cut = 0; text && cut + 1 < size; cut++) {
        char *prefix = strndup(text, cut);
        ticket_path(SL_STATE_READY, "torn", path, sizeof path);
        durable_put(path, prefix, cut);
        sl_ticket back;
        sl_error_init(&err);
        accepted += sl_ticket_read(path, &back, &err) != SL_E_CORRUPT;
        free(prefix);
    }
    CHECK_MSG(accepted == 0, "%d torn prefixes accepted", accepted);
    /* ... except the one that lacks only the final newline. */
    ticket_path(SL_STATE_READY, "torn", path, sizeof path);
    durable_put(path, text, size - 1);
    sl_ticket back;
    CHECK(sl_ticket_read(path, &back, &err) == 0 && !strcmp(back.item, "whole"));
    unlink(path);
    free(text);
    expect_torn("", "empty file");
    expect_torn("item=a\nsource=a.ply\n", "no end line");
    expect_torn("source=a.ply\nkey=00\nend\n", "no item");
    expect_torn("item=\nend\n", "empty item");
    expect_torn("\n\n\nend\n", "only blank lines");
    char missing[PATH_MAX];
    ticket_path(SL_STATE_READY, "no-such-ticket", missing, sizeof missing);
    sl_error_init(&err);
    CHECK(sl_ticket_read(missing, &back, &err) != 0 && err.sys_errno == ENOENT);
}

/* ---- names that need escaping ------------------------------------------------------- */

static void test_escaping(void)
{
    struct { const char *item, *name; } cases[] = {
        {"bunny/bun000", "bunny%2Fbun000"},
        {"50%", "50%25"},
        {".hidden", "%2Ehidden"},
        {"..", "%2E."},
        {"a.b", "a.b"},
        {"a/.b", "a%2F.b"},
        {"%2F", "%252F"},
        {"/", "%2F"},
        {"dir/sub/scan 1", "dir%2Fsub%2Fscan 1"},
        {"caf\xc3\xa9", "caf\xc3\xa9"},
    };
    size_t n = sizeof cases / sizeof cases[0];
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_queue_create(work, "escape", &err) == 0);
    for (size_t i = 0; i < n; i++) {
        char name[SL_TICKET_NAME_MAX + 1];
        CHECK(sl_ticket_name(cases[i].item, name, sizeof name, &err) == 0);
        CHECK_MSG(!strcmp(name, cases[i].name), "'%s' -> '%s'", cases[i].item, name);
        CHECK_MSG(name[0] != '.' && !strchr(name, '/'), "'%s' is not one plain file name", name);
        sl_ticket t = ticket_for(cases[i].item);
        CHECK(sl_queue_put(work, "escape", SL_STATE_READY, name, &t, &err) == 0);
    }
    /* Distinct items, distinct names: all listed (none hidden), each ticket its item. */
    char **names = NULL;
    int count = 0;
    CHECK(sl_queue_list(work, "escape", SL_STATE_READY, &names, &count, &err) == 0);
    CHECK_EQ_U64(count, n);
    for (int i = 0; i < count; i++) {
        size_t k = 0;
        while (k < n && strcmp(cases[k].name, names[i]))
            k++;
        char path[PATH_MAX];
        CHECK(sl_queue_path(path, sizeof path, work, "escape", SL_STATE_READY, names[i]) == 0);
        sl_ticket back;
        CHECK_MSG(k < n && sl_ticket_read(path, &back, &err) == 0 &&
                      !strcmp(back.item, cases[k].item), "ticket %s", names[i]);
    }
    free(names);
    /* A long id: a name within the limit, or a clean limit error. */
    char long_item[1000];
    memset(long_item, 'x', sizeof long_item - 1);
    long_item[sizeof long_item - 1] = '\0';
    char name[SL_TICKET_NAME_MAX + 1];
    sl_error_init(&err);
    int rc = sl_ticket_name(long_item, name, sizeof name, &err);
    CHECK(rc == SL_E_LIMIT || (rc == 0 && strlen(name) <= SL_TICKET_NAME_MAX));
}

/* Debug builds assert the state machine: a ready ticket moved straight to done aborts
 * (the sanitizer pass is a Debug build; a Release build has no assertions to check). */
static void test_illegal_move_aborts(void)
{
#ifndef NDEBUG
    sl_error err;
    sl_error_init(&err);
    sl_ticket t = ticket_for("sheep");
    CHECK(sl_queue_put(work, stage, SL_STATE_READY, "sheep", &t, &err) == 0);
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        fclose(stderr); /* the assertion's message is expected */
        sl_queue_move(work, stage, "sheep", SL_STATE_READY, SL_STATE_DONE, &err);
        _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    CHECK_MSG(WIFSIGNALED(status) && WTERMSIG(status) == SIGABRT,
              "ready -> done did not abort (status %d)", status);
    CHECK(sl_queue_find(work, stage, "sheep") == SL_STATE_READY); /* and did not move */
    CHECK(sl_queue_move(work, stage, "sheep", SL_STATE_READY, SL_STATE_CLAIMED, &err) == 0);
#endif
}

int main(void)
{
    if (durable_scratch("test_queue", work)) {
        perror("mkdtemp");
        return 1;
    }
    test_failed_move_and_put();
    test_create_put_move_find();
    test_list();
    test_concurrent_claims();
    test_torn_tickets();
    test_escaping();
    test_illegal_move_aborts();
    durable_remove_tree(work);
    return check_report();
}
