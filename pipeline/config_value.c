/* Config values: parsing, range checks and canonical text per option type, and path
 * resolution (config.h says what each type accepts and how it is canonicalised). */
#include "pipeline/config_internal.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

int sl_config_because(char *cause, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cause, CAUSE_MAX, fmt, ap);
    va_end(ap);
    return -1;
}

/* ---- paths ------------------------------------------------------------------------ */

/* In place, for an absolute path: drops empty and "." segments and a trailing slash. */
static void normalize_absolute(char *p)
{
    char *out = p;
    const char *in = p;
    while (*in) {
        while (*in == '/')
            in++;
        const char *seg = in;
        while (*in && *in != '/')
            in++;
        size_t n = (size_t)(in - seg);
        if (n == 0 || (n == 1 && seg[0] == '.'))
            continue;
        *out++ = '/';
        memmove(out, seg, n);
        out += n;
    }
    if (out == p)
        *out++ = '/';
    *out = '\0';
}

/* `rel` made absolute against `base` (an absolute directory, "" if unknown). */
static char *resolve_path(const char *base, const char *rel, char *cause)
{
    size_t n = strlen(base) + strlen(rel) + 2;
    char *p = rel[0] == '/' || base[0] ? malloc(n) : NULL;
    if (!p) {
        sl_config_because(cause, rel[0] == '/' || base[0] ? "out of memory" : "no current directory");
        return NULL;
    }
    snprintf(p, n, "%s/%s", rel[0] == '/' ? "" : base, rel);
    normalize_absolute(p);
    return p;
}

/* The absolute directory holding `file` (as named: a symlinked file is not followed). */
char *sl_config_directory_of(const char *file, const char *cwd, char *cause)
{
    const char *slash = strrchr(file, '/');
    char dir[PATH_MAX];
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else
        snprintf(dir, sizeof dir, "%.*s", slash == file ? 1 : (int)(slash - file), file);
    return resolve_path(cwd, dir, cause);
}

/* ---- values ----------------------------------------------------------------------- */

static int out_of_range(const sl_option *o, double v, const char *text, char *cause)
{
    if (o->min < o->max && !(v >= o->min && v <= o->max))
        return sl_config_because(cause, "%.80s is out of range [%.17g, %.17g]", text, o->min, o->max);
    return 0;
}

static int parse_int(const sl_option *o, const char *text, int64_t *out, char *cause)
{
    char *end;
    errno = 0;
    long long v = strtoll(text, &end, 10);
    if (end == text || *end || isspace((unsigned char)text[0]))
        return sl_config_because(cause, "'%.80s' is not an integer", text);
    if (errno == ERANGE)
        return sl_config_because(cause, "%.80s does not fit in 64 bits", text);
    *out = v;
    return out_of_range(o, (double)v, text, cause);
}

static int parse_double(const sl_option *o, const char *text, double *out, char *cause)
{
    char *end;
    double v = strtod(text, &end);
    if (end == text || *end || isspace((unsigned char)text[0]))
        return sl_config_because(cause, "'%.80s' is not a number", text);
    if (!isfinite(v))
        return sl_config_because(cause, "'%.80s' is not a finite number", text);
    *out = v;
    return out_of_range(o, v, text, cause);
}

static int parse_bool(const char *text, int64_t *out, char *cause)
{
    static const char *const words[] = {"false", "true", "no", "yes", "off", "on", "0", "1"};
    for (int k = 0; k < 8; k++)
        if (!strcasecmp(text, words[k])) {
            *out = k & 1;
            return 0;
        }
    return sl_config_because(cause, "'%.80s' is not a bool (true/false, yes/no, on/off, 1/0)", text);
}

static int parse_enum(const sl_option *o, const char *text, char *cause)
{
    size_t n = strlen(text);
    for (const char *c = o->choices; c && *c;) {
        size_t len = strcspn(c, "|");
        if (len == n && !memcmp(c, text, n))
            return 0;
        c += len + (c[len] == '|');
    }
    return sl_config_because(cause, "'%.80s' is not one of %s", text, o->choices ? o->choices : "");
}

/* Appends one list element (p[0..len), trimmed) at *w: as written, or as %.17g when the
 * option has a range (then each element must be a number within it). */
static int append_element(const sl_option *o, const char *p, size_t len, char **w, int first,
                          char *cause)
{
    char word[128];
    double v;
    while (len && isspace((unsigned char)*p))
        p++, len--;
    while (len && isspace((unsigned char)p[len - 1]))
        len--;
    if (len == 0 || len >= sizeof word)
        return sl_config_because(cause, len ? "list element too long" : "empty list element");
    snprintf(word, sizeof word, "%.*s", (int)len, p);
    if (o->min < o->max && parse_double(o, word, &v, cause))
        return -1;
    if (o->choices && parse_enum(o, word, cause)) /* a list of choices ("ply|glb|obj") */
        return -1;
    if (o->min < o->max)
        *w += sprintf(*w, "%s%.17g", first ? "" : ",", v);
    else
        *w += sprintf(*w, "%s%s", first ? "" : ",", word);
    return 0;
}

static char *canonical_list(const sl_option *o, const char *text, char *cause)
{
    char *out = malloc(strlen(text) * 26 + 1), *w = out; /* "1" may become 25 chars */
    if (!out)
        return sl_config_because(cause, "out of memory"), NULL;
    *w = '\0';
    for (const char *p = text; *text; p++) { /* "" is the empty list */
        size_t len = strcspn(p, ",");
        if (append_element(o, p, len, &w, w == out, cause)) {
            free(out);
            return NULL;
        }
        p += len;
        if (!*p)
            break;
    }
    return out;
}

int sl_config_parse_value(const sl_option *o, const char *raw, const char *base, char **out,
                          int64_t *out_i, double *out_d, char *cause)
{
    char *text = NULL, number[32];
    int64_t i = 0;
    double d = 0;
    int bad = 0;
    switch (o->type) {
    case SL_OPT_BOOL:
        bad = parse_bool(raw, &i, cause);
        text = strdup(i ? "true" : "false");
        break;
    case SL_OPT_INT:
        bad = parse_int(o, raw, &i, cause);
        snprintf(number, sizeof number, "%lld", (long long)i);
        text = strdup(number);
        break;
    case SL_OPT_DOUBLE:
        bad = parse_double(o, raw, &d, cause);
        snprintf(number, sizeof number, "%.17g", d);
        text = strdup(number);
        break;
    case SL_OPT_ENUM:
        bad = parse_enum(o, raw, cause);
        text = strdup(raw);
        break;
    case SL_OPT_STRING:
        text = strdup(raw);
        break;
    case SL_OPT_LIST:
        text = canonical_list(o, raw, cause);
        bad = !text;
        break;
    case SL_OPT_PATH:
        if (!raw[0])
            sl_config_because(cause, "empty path");
        text = raw[0] ? resolve_path(base, raw, cause) : NULL;
        bad = !text;
        break;
    }
    if (!bad && !text)
        bad = sl_config_because(cause, "out of memory");
    if (bad) {
        free(text);
        return -1;
    }
    *out = text, *out_i = i, *out_d = d;
    return 0;
}
