/* Errors are values: every fallible function returns 0 or a negative SL_E* code and
 * fills a caller-owned sl_error that keeps the *first* failure (later ones are dropped,
 * so the message a user sees names the root cause, not its echo).
 *
 * Each code belongs to a failure class that decides what the engine does with the item
 * (docs/engine.md, "Failure classes"): bad input is quarantined at once, transient failures
 * (no space, I/O error, interrupt, lost lease, out of memory) are retried later and never
 * quarantined, storage failures that need a human stop the run, internal errors are bugs.
 *
 * Thread safety: an sl_error is owned by one thread; parallel code gives each thread its
 * own and merges them with sl_error_merge() in a fixed order (deterministic messages).
 */
#ifndef SCANLOD_CORE_ERROR_H
#define SCANLOD_CORE_ERROR_H

#include <stdarg.h>
#include <stddef.h>

/* X(name, class, message) -- codes are assigned in order, starting at -1. */
#define SL_ERROR_MAP(X)                                                              \
    X(BADINPUT, SL_CLASS_BADINPUT, "malformed input")                               \
    X(LIMIT, SL_CLASS_BADINPUT, "input exceeds a configured limit")                 \
    X(UNSUPPORTED, SL_CLASS_BADINPUT, "unsupported input")                          \
    X(NOSPACE, SL_CLASS_TRANSIENT, "no space left on device")                       \
    X(IO, SL_CLASS_TRANSIENT, "input/output error")                                 \
    X(NOMEM, SL_CLASS_TRANSIENT, "out of memory")                                   \
    X(INTERRUPTED, SL_CLASS_TRANSIENT, "interrupted")                               \
    X(LEASE_LOST, SL_CLASS_TRANSIENT, "lease lost to another worker")               \
    X(BUSY, SL_CLASS_TRANSIENT, "resource busy")                                    \
    X(STORAGE, SL_CLASS_STORAGE, "storage error")                                   \
    X(CORRUPT, SL_CLASS_TRANSIENT, "corrupt artifact")                              \
    X(CONFIG, SL_CLASS_CONFIG, "bad configuration")                                 \
    X(USAGE, SL_CLASS_USAGE, "usage error")                                         \
    X(INTERNAL, SL_CLASS_INTERNAL, "internal error")

enum sl_error_class {
    SL_CLASS_OK = 0,
    SL_CLASS_BADINPUT,  /* quarantine at once; exit 65 */
    SL_CLASS_TRANSIENT, /* retry later, never quarantine; exit 75 */
    SL_CLASS_STORAGE,   /* storage needs a human (read-only fs, permissions); exit 74 */
    SL_CLASS_CONFIG,    /* exit 78 */
    SL_CLASS_USAGE,     /* exit 64 */
    SL_CLASS_INTERNAL   /* a bug in scanlod; exit 70 */
};

/* Codes: SL_OK = 0, SL_E_BADINPUT = -1, SL_E_LIMIT = -2, ... in map order. */
#define SL_OK 0
enum sl_error_index {
#define SL_ERROR_INDEX_(name, cls, msg) SL_E_INDEX_##name,
    SL_ERROR_MAP(SL_ERROR_INDEX_)
#undef SL_ERROR_INDEX_
    SL_E_INDEX_COUNT_
};
#define SL_ERROR_CODE_(name, cls, msg) enum { SL_E_##name = -1 - SL_E_INDEX_##name };
SL_ERROR_MAP(SL_ERROR_CODE_)
#undef SL_ERROR_CODE_

/* Exit codes of the scanlod command (sysexits vocabulary; docs/exit-codes.md). */
enum sl_exit {
    SL_EXIT_OK = 0,
    SL_EXIT_USAGE = 64,
    SL_EXIT_DATAERR = 65,  /* done, except quarantined inputs */
    SL_EXIT_SOFTWARE = 70, /* internal error */
    SL_EXIT_IOERR = 74,    /* storage needs a human */
    SL_EXIT_TEMPFAIL = 75, /* incomplete, safe to rerun */
    SL_EXIT_CONFIG = 78
};

typedef struct sl_error {
    int code;           /* SL_OK or SL_E_*; first failure wins */
    int sys_errno;      /* errno at the failure, 0 if none */
    char stage[32];     /* stage name, "" outside a stage */
    char item[256];     /* item id, "" outside an item */
    char file[512];     /* the file the failure is about, "" if none */
    char message[768];  /* human cause, without the file name */
} sl_error;

void sl_error_init(sl_error *err);

/* Records a failure if none is recorded yet. `file` may be NULL. Returns `code`, so a
 * function can `return sl_error_set(err, SL_E_BADINPUT, 0, path, "...")`. */
int sl_error_set(sl_error *err, int code, int sys_errno, const char *file, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
int sl_error_setv(sl_error *err, int code, int sys_errno, const char *file, const char *fmt,
                  va_list ap);

/* The two failures every reader and builder reports: an artifact or file whose bytes
 * disagree with what its format says (SL_E_CORRUPT; the producing stage reruns), and an
 * allocation that failed (SL_E_NOMEM, ENOMEM; the item is retried). `file` may be NULL;
 * `fmt` says what, e.g. sl_error_corrupt(err, path, "level list: %s", "cut short"). */
int sl_error_corrupt(sl_error *err, const char *file, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int sl_error_nomem(sl_error *err, const char *file, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Maps an errno from a failed system call on `file` to the right code and class:
 * ENOSPC/EDQUOT -> NOSPACE, EIO -> IO, ENOMEM -> NOMEM, EROFS/EACCES/EPERM -> STORAGE,
 * EINTR -> INTERRUPTED, others -> IO. `what` names the operation ("write", "fsync"). */
int sl_error_errno(sl_error *err, int sys_errno, const char *file, const char *what);
int sl_error_code_of_errno(int sys_errno); /* that mapping alone */

/* Copies `src` into `dst` if `dst` holds no failure yet. */
void sl_error_merge(sl_error *dst, const sl_error *src);

/* Stage/item context stamped on a recorded failure (does not overwrite a set value). */
void sl_error_context(sl_error *err, const char *stage, const char *item);

/* One line "FILE: MESSAGE (strerror)" into buf; returns buf. */
const char *sl_error_format(const sl_error *err, char *buf, size_t size);

const char *sl_error_name(int code);    /* "BADINPUT" */
const char *sl_strerror(int code);      /* "malformed input" */
enum sl_error_class sl_error_class_of(int code);
int sl_error_exit_code(int code);       /* class -> sl_exit */
/* Exit code of a one-shot command (inspect, compare, extract) that failed to read the
 * file it was given: missing, unreadable, not a regular file, malformed or corrupt is
 * the user's data, 65 (docs/exit-codes.md); out of memory and interrupts stay 75 (try
 * again), internal errors 70. The engine keeps sl_error_exit_code: for it a missing or
 * unreadable artifact is transient. */
int sl_error_input_exit_code(int code);

#endif
