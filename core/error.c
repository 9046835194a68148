/* The error table and the first-failure-wins recorder (see error.h). */
#include "core/error.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

struct error_info {
    const char *name;
    enum sl_error_class cls;
    const char *message;
};

static const struct error_info error_table[] = {
#define SL_ERROR_INFO_(name, cls, msg) {#name, cls, msg},
    SL_ERROR_MAP(SL_ERROR_INFO_)
#undef SL_ERROR_INFO_
};

static const struct error_info *info_of(int code)
{
    int index = -1 - code;
    if (code >= 0 || index >= (int)(sizeof error_table / sizeof error_table[0]))
        return NULL;
    return &error_table[index];
}

void sl_error_init(sl_error *err)
{
    memset(err, 0, sizeof *err);
}

static void copy_string(char *dst, size_t size, const char *src)
{
    if (!src)
        src = "";
    snprintf(dst, size, "%s", src);
}

int sl_error_setv(sl_error *err, int code, int sys_errno, const char *file, const char *fmt,
                  va_list ap)
{
    if (!err || err->code != SL_OK)
        return code;
    err->code = code;
    err->sys_errno = sys_errno;
    copy_string(err->file, sizeof err->file, file);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    return code;
}

int sl_error_set(sl_error *err, int code, int sys_errno, const char *file, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    sl_error_setv(err, code, sys_errno, file, fmt, ap);
    va_end(ap);
    return code;
}

int sl_error_corrupt(sl_error *err, const char *file, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    sl_error_setv(err, SL_E_CORRUPT, 0, file, fmt, ap);
    va_end(ap);
    return SL_E_CORRUPT;
}

int sl_error_nomem(sl_error *err, const char *file, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    sl_error_setv(err, SL_E_NOMEM, ENOMEM, file, fmt, ap);
    va_end(ap);
    return SL_E_NOMEM;
}

int sl_error_code_of_errno(int sys_errno)
{
    switch (sys_errno) {
    case ENOSPC:
    case EDQUOT: return SL_E_NOSPACE;
    case ENOMEM: return SL_E_NOMEM;
    case EROFS:
    case EACCES:
    case EPERM:
    case ENOTDIR:
    case ENAMETOOLONG: return SL_E_STORAGE;
    case EINTR: return SL_E_INTERRUPTED;
    default: return SL_E_IO;
    }
}

int sl_error_errno(sl_error *err, int sys_errno, const char *file, const char *what)
{
    return sl_error_set(err, sl_error_code_of_errno(sys_errno), sys_errno, file,
                        "%s failed: %s", what, strerror(sys_errno));
}

void sl_error_merge(sl_error *dst, const sl_error *src)
{
    if (dst && src && dst->code == SL_OK && src->code != SL_OK)
        *dst = *src;
}

void sl_error_context(sl_error *err, const char *stage, const char *item)
{
    if (!err)
        return;
    if (stage && !err->stage[0])
        copy_string(err->stage, sizeof err->stage, stage);
    if (item && !err->item[0])
        copy_string(err->item, sizeof err->item, item);
}

const char *sl_error_format(const sl_error *err, char *buf, size_t size)
{
    if (err->code == SL_OK) {
        snprintf(buf, size, "ok");
        return buf;
    }
    const char *msg = err->message[0] ? err->message : sl_strerror(err->code);
    if (err->file[0])
        snprintf(buf, size, "%s: %s", err->file, msg);
    else
        snprintf(buf, size, "%s", msg);
    return buf;
}

const char *sl_error_name(int code)
{
    const struct error_info *info = info_of(code);
    return code == SL_OK ? "OK" : info ? info->name : "UNKNOWN";
}

const char *sl_strerror(int code)
{
    const struct error_info *info = info_of(code);
    return code == SL_OK ? "ok" : info ? info->message : "unknown error";
}

enum sl_error_class sl_error_class_of(int code)
{
    const struct error_info *info = info_of(code);
    return code == SL_OK ? SL_CLASS_OK : info ? info->cls : SL_CLASS_INTERNAL;
}

int sl_error_input_exit_code(int code)
{
    if (code == SL_E_NOMEM || code == SL_E_INTERRUPTED)
        return SL_EXIT_TEMPFAIL;
    if (code == SL_OK || sl_error_class_of(code) == SL_CLASS_INTERNAL)
        return sl_error_exit_code(code);
    return SL_EXIT_DATAERR;
}

int sl_error_exit_code(int code)
{
    switch (sl_error_class_of(code)) {
    case SL_CLASS_OK: return SL_EXIT_OK;
    case SL_CLASS_BADINPUT: return SL_EXIT_DATAERR;
    case SL_CLASS_TRANSIENT: return SL_EXIT_TEMPFAIL;
    case SL_CLASS_STORAGE: return SL_EXIT_IOERR;
    case SL_CLASS_CONFIG: return SL_EXIT_CONFIG;
    case SL_CLASS_USAGE: return SL_EXIT_USAGE;
    case SL_CLASS_INTERNAL: break;
    }
    return SL_EXIT_SOFTWARE;
}
