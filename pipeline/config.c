/* Config loading, validation and hashing (see config.h; the reference file is written by
 * config_reference.c).
 *
 * Method: every declared option gets one slot. The file, then the `-s` overrides, then
 * the defaults fill the slots through one function, set_value(), which parses,
 * range-checks and canonicalises the text (config_value.c); so every source is validated
 * the same way.
 *
 * libinih does the INI syntax, but we feed it lines through our own reader because the
 * Debian library is built without INI_HANDLER_LINENO: the reader counts lines, so every
 * handler call knows its line. The reader also rejects an unknown [section] at its
 * header (inih reports no sections, only pairs), strips indentation (inih would glue an
 * indented line to the previous value as a multi-line continuation) and refuses lines
 * too long for inih's fixed buffer (it would split them silently).
 */
#define XXH_STATIC_LINKING_ONLY /* XXH3_state_t on the stack */
#include "pipeline/config.h"
#include "pipeline/config_internal.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <ini.h>
#include <limits.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include "core/io.h"

#define CONFIG_MAX_BYTES (1 << 20) /* a config file is a few KiB; refuse anything huge */
#define NAME_MAX_LEN 64

enum origin { FROM_NONE, FROM_FILE, FROM_OVERRIDE, FROM_DEFAULT };

typedef struct slot {
    const sl_option *opt;
    char *text;  /* canonical value */
    int64_t i;   /* INT, BOOL */
    double d;    /* DOUBLE */
    enum origin origin;
    int line;    /* line in the file, for "duplicate key" */
} slot;

struct sl_config {
    slot *slots;
    size_t count;
    char *path;
};

/* ---- lookup ---------------------------------------------------------------------- */

static slot *find_slot(const sl_config *cfg, const char *section, const char *name)
{
    for (size_t k = 0; k < cfg->count; k++)
        if (!strcmp(cfg->slots[k].opt->section, section) &&
            !strcmp(cfg->slots[k].opt->name, name))
            return &cfg->slots[k];
    return NULL;
}

static int section_known(const sl_config *cfg, const char *section, size_t len)
{
    for (size_t k = 0; k < cfg->count; k++) {
        const char *s = cfg->slots[k].opt->section;
        if (strlen(s) == len && !memcmp(s, section, len))
            return 1;
    }
    return 0;
}

/* Is slot k the first of its section? (Sections are listed in first-appearance order.) */
static int first_of_section(const sl_config *cfg, size_t k)
{
    for (size_t j = 0; j < k; j++)
        if (!strcmp(cfg->slots[j].opt->section, cfg->slots[k].opt->section))
            return 0;
    return 1;
}

/* "run, queue, range": the sections in first-appearance order, for messages. */
static void list_sections(const sl_config *cfg, char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (size_t k = 0; k < cfg->count && used < size; k++) {
        const char *s = cfg->slots[k].opt->section;
        if (!first_of_section(cfg, k))
            continue;
        used += (size_t)snprintf(buf + used, size - used, "%s%s", used ? ", " : "", s);
    }
}

/* Levenshtein distance (capped names), for "did you mean" on unknown keys. */
static size_t edit_distance(const char *a, const char *b)
{
    size_t la = strnlen(a, NAME_MAX_LEN), lb = strnlen(b, NAME_MAX_LEN);
    size_t row[NAME_MAX_LEN + 1];
    for (size_t j = 0; j <= lb; j++)
        row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t up = row[j], best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best)
                best = up + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            diag = up;
            row[j] = best;
        }
    }
    return row[lb];
}

static const char *closest_key(const sl_config *cfg, const char *section, const char *name)
{
    const char *best = NULL;
    size_t best_distance = 3; /* more than 2 edits away is not a typo */
    for (size_t k = 0; k < cfg->count; k++) {
        const sl_option *o = cfg->slots[k].opt;
        size_t d = strcmp(o->section, section) ? SIZE_MAX : edit_distance(name, o->name);
        if (d < best_distance)
            best_distance = d, best = o->name;
    }
    return best;
}

/* Parses `raw` for the slot's type (config_value.c); on success replaces its value.
 * `base` is the directory relative paths resolve against. */
static int set_value(slot *s, const char *raw, const char *base, enum origin origin, char *cause)
{
    char *text;
    int64_t i;
    double d;
    if (sl_config_parse_value(s->opt, raw, base, &text, &i, &d, cause))
        return -1;
    free(s->text);
    s->text = text, s->i = i, s->d = d, s->origin = origin;
    return 0;
}

/* ---- the file --------------------------------------------------------------------- */

typedef struct reader {
    sl_config *cfg;
    const char *path;
    const char *base; /* the file's directory */
    const char *data;
    size_t size, pos;
    int line;
    int error_line; /* line of our first error, 0 = none */
    sl_error first; /* our first error; reported unless inih saw an earlier syntax error */
} reader;

static int reader_fail(reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int reader_fail(reader *r, const char *fmt, ...)
{
    char where[PATH_MAX + 16];
    va_list ap;
    snprintf(where, sizeof where, "%s:%d", r->path, r->line);
    va_start(ap, fmt);
    sl_error_setv(&r->first, SL_E_CONFIG, 0, where, fmt, ap);
    va_end(ap);
    r->error_line = r->line;
    return 0; /* what an inih handler returns on error */
}

/* A "[name]" line naming no declared section fails here, at its header. */
static int check_section_header(reader *r, const char *line, size_t len)
{
    const char *close = memchr(line, ']', len);
    if (!close) /* inih reports the syntax error */
        return 1;
    size_t n = (size_t)(close - line - 1);
    if (section_known(r->cfg, line + 1, n))
        return 1;
    char known[256];
    list_sections(r->cfg, known, sizeof known);
    return reader_fail(r, "[%.*s]: unknown section (known: %s)", (int)(n > 80 ? 80 : n), line + 1,
                       known);
}

/* inih's fgets-like reader over the file in memory. */
static char *read_line(char *buf, int num, void *stream)
{
    reader *r = stream;
    if (r->error_line || r->pos >= r->size)
        return NULL;
    const char *line = r->data + r->pos, *nl = memchr(line, '\n', r->size - r->pos);
    size_t len = nl ? (size_t)(nl - line) : r->size - r->pos;
    r->pos += len + (nl != NULL);
    r->line++;
    if (r->line == 1 && len >= 3 && !memcmp(line, "\xEF\xBB\xBF", 3))
        line += 3, len -= 3; /* UTF-8 byte order mark */
    while (len && (*line == ' ' || *line == '\t'))
        line++, len--;
    if (memchr(line, '\0', len))
        return reader_fail(r, "NUL byte in line"), NULL;
    if (len + 2 > (size_t)num)
        return reader_fail(r, "line longer than %d characters", num - 2), NULL;
    if (len && line[0] == '[' && !check_section_header(r, line, len))
        return NULL;
    memcpy(buf, line, len);
    buf[len] = '\n';
    buf[len + 1] = '\0';
    return buf;
}

static int on_pair(void *user, const char *section, const char *name, const char *value)
{
    reader *r = user;
    char cause[CAUSE_MAX];
    if (!section[0])
        return reader_fail(r, "%s: key outside any [section]", name);
    slot *s = find_slot(r->cfg, section, name);
    if (!s) {
        const char *hint = closest_key(r->cfg, section, name);
        return reader_fail(r, "[%s] %s: unknown key%s%s%s", section, name,
                           hint ? " (did you mean " : "", hint ? hint : "", hint ? "?)" : "");
    }
    if (s->origin == FROM_FILE)
        return reader_fail(r, "[%s] %s: duplicate key (first set on line %d)", section, name,
                           s->line);
    if (set_value(s, value, r->base, FROM_FILE, cause))
        return reader_fail(r, "[%s] %s: %s", section, name, cause);
    s->line = r->line;
    return 1;
}

static int read_file(const char *path, char **data, size_t *size, sl_error *err)
{
    struct stat st;
    sl_error open_err;
    sl_error_init(&open_err);
    int fd = sl_io_open_regular(path, &st, &open_err); /* a FIFO or folder: refused, no hang */
    if (fd < 0)
        return sl_error_set(err, SL_E_CONFIG, open_err.sys_errno, path,
                            "cannot read config file: %s", open_err.message);
    int e;
    if (st.st_size > CONFIG_MAX_BYTES) {
        close(fd);
        return sl_error_set(err, SL_E_CONFIG, 0, path, "config file larger than %d bytes",
                            CONFIG_MAX_BYTES);
    }
    *data = malloc((size_t)st.st_size + 1);
    ssize_t got = *data ? read(fd, *data, (size_t)st.st_size + 1) : -1;
    e = *data ? errno : ENOMEM;
    close(fd);
    if (got < 0 || got > st.st_size) /* a growing file is not a config */
        return sl_error_set(err, SL_E_CONFIG, got < 0 ? e : 0, path, "cannot read config file: %s",
                            got < 0 ? strerror(e) : "file changed while reading");
    *size = (size_t)got;
    return 0;
}

static int load_file(sl_config *cfg, const char *path, const char *cwd, sl_error *err)
{
    char cause[CAUSE_MAX], *data = NULL;
    reader r = {.cfg = cfg, .path = path};
    sl_error_init(&r.first);
    char *base = sl_config_directory_of(path, cwd, cause);
    if (!base)
        return sl_error_set(err, SL_E_CONFIG, 0, path, "%s", cause);
    int rc = read_file(path, &data, &r.size, err);
    if (rc == 0) {
        r.data = data, r.base = base;
        int syntax_line = ini_parse_stream(read_line, &r, on_pair, &r);
        if (syntax_line > 0 && (!r.error_line || syntax_line < r.error_line)) {
            char where[PATH_MAX + 16];
            snprintf(where, sizeof where, "%s:%d", path, syntax_line);
            rc = sl_error_set(err, SL_E_CONFIG, 0, where,
                              "syntax error: expected [section], key = value or a comment");
        } else if (syntax_line < 0 && !r.error_line) {
            rc = sl_error_set(err, SL_E_CONFIG, 0, path, "out of memory while parsing");
        } else if (r.error_line) {
            sl_error_merge(err, &r.first);
            rc = SL_E_CONFIG;
        }
    }
    free(data);
    free(base);
    return rc;
}

/* ---- overrides and defaults --------------------------------------------------------- */

/* Copies s[0..n) without surrounding blanks into buf (size NAME_MAX_LEN). */
static const char *trimmed(const char *s, size_t n, char *buf)
{
    while (n && isspace((unsigned char)*s))
        s++, n--;
    while (n && isspace((unsigned char)s[n - 1]))
        n--;
    snprintf(buf, NAME_MAX_LEN, "%.*s", (int)n, s);
    return buf;
}

static int apply_override(sl_config *cfg, const char *arg, const char *cwd, sl_error *err)
{
    char where[PATH_MAX], section[NAME_MAX_LEN], name[NAME_MAX_LEN], cause[CAUSE_MAX];
    snprintf(where, sizeof where, "-s %s", arg);
    const char *eq = strchr(arg, '=');
    const char *dot = eq ? memchr(arg, '.', (size_t)(eq - arg)) : NULL;
    if (!dot)
        return sl_error_set(err, SL_E_CONFIG, 0, where, "expected section.key=value");
    trimmed(arg, (size_t)(dot - arg), section);
    trimmed(dot + 1, (size_t)(eq - dot - 1), name);
    slot *s = find_slot(cfg, section, name);
    if (!s && !section_known(cfg, section, strlen(section)))
        return sl_error_set(err, SL_E_CONFIG, 0, where, "unknown section [%s]", section);
    if (!s)
        return sl_error_set(err, SL_E_CONFIG, 0, where, "unknown key %s in [%s]", name, section);
    const char *value = eq + 1 + strspn(eq + 1, " \t");
    size_t n = strlen(value);
    while (n && isspace((unsigned char)value[n - 1]))
        n--;
    char *copy = strndup(value, n);
    int bad = copy ? set_value(s, copy, cwd, FROM_OVERRIDE, cause)
                   : sl_config_because(cause, "out of memory");
    free(copy);
    return bad ? sl_error_set(err, SL_E_CONFIG, 0, where, "%s", cause) : 0;
}

static int apply_defaults(sl_config *cfg, const char *path, const char *cwd, sl_error *err)
{
    char cause[CAUSE_MAX];
    for (size_t k = 0; k < cfg->count; k++) {
        slot *s = &cfg->slots[k];
        const sl_option *o = s->opt;
        if (s->origin != FROM_NONE)
            continue;
        if (!o->default_value && path)
            return sl_error_set(err, SL_E_CONFIG, 0, path, "[%s] %s is required", o->section,
                                o->name);
        if (!o->default_value)
            return sl_error_set(err, SL_E_CONFIG, 0, NULL,
                                "[%s] %s is required (no config file; use -s %s.%s=VALUE)",
                                o->section, o->name, o->section, o->name);
        if (set_value(s, o->default_value, cwd, FROM_DEFAULT, cause))
            return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "option table: [%s] %s: default: %s",
                                o->section, o->name, cause);
    }
    return 0;
}

/* One slot per option, in table order; a name declared twice is a bug in the tables. */
static int make_slots(sl_config *cfg, const sl_option *const *tables, sl_error *err)
{
    size_t n = 0;
    for (const sl_option *const *t = tables; t && *t; t++)
        for (const sl_option *o = *t; o->name; o++)
            n++;
    cfg->slots = calloc(n ? n : 1, sizeof *cfg->slots);
    if (!cfg->slots)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    for (const sl_option *const *t = tables; t && *t; t++)
        for (const sl_option *o = *t; o->name; o++) {
            if (find_slot(cfg, o->section, o->name))
                return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "option [%s] %s declared twice",
                                    o->section, o->name);
            cfg->slots[cfg->count++].opt = o;
        }
    return 0;
}

int sl_config_load(sl_config **out, const sl_option *const *tables, const char *path,
                   const char *const *overrides, int override_count, sl_error *err)
{
    char cwd[PATH_MAX];
    sl_config *cfg = calloc(1, sizeof *cfg);
    *out = NULL;
    if (!cfg || !(cfg->path = strdup(path ? path : ""))) {
        free(cfg);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    }
    if (!getcwd(cwd, sizeof cwd))
        cwd[0] = '\0'; /* only relative paths need it; they then fail with a clear cause */
    int rc = make_slots(cfg, tables, err);
    if (rc == 0 && path)
        rc = load_file(cfg, path, cwd, err);
    for (int k = 0; rc == 0 && k < override_count; k++)
        rc = apply_override(cfg, overrides[k], cwd, err);
    if (rc == 0)
        rc = apply_defaults(cfg, path, cwd, err);
    if (rc != 0)
        sl_config_free(cfg);
    else
        *out = cfg;
    return rc;
}

void sl_config_free(sl_config *cfg)
{
    if (!cfg)
        return;
    for (size_t k = 0; k < cfg->count; k++)
        free(cfg->slots[k].text);
    free(cfg->slots);
    free(cfg->path);
    free(cfg);
}

/* ---- getters and hash --------------------------------------------------------------- */

static const slot *must_find(const sl_config *cfg, const char *section, const char *name,
                              int type)
{
    const slot *s = find_slot(cfg, section, name);
    if (!s || (type >= 0 && (int)s->opt->type != type)) {
        fprintf(stderr, "scanlod: bug: option [%s] %s %s\n", section, name,
                s ? "read with the wrong type" : "is not declared");
        abort();
    }
    return s;
}

const char *sl_config_string(const sl_config *cfg, const char *section, const char *name)
{
    return must_find(cfg, section, name, -1)->text;
}

int64_t sl_config_int(const sl_config *cfg, const char *section, const char *name)
{
    return must_find(cfg, section, name, SL_OPT_INT)->i;
}

double sl_config_double(const sl_config *cfg, const char *section, const char *name)
{
    return must_find(cfg, section, name, SL_OPT_DOUBLE)->d;
}

int sl_config_bool(const sl_config *cfg, const char *section, const char *name)
{
    return (int)must_find(cfg, section, name, SL_OPT_BOOL)->i;
}

const char *sl_config_path(const sl_config *cfg)
{
    return cfg->path;
}

sl_config_origin_kind sl_config_origin(const sl_config *cfg, const char *section,
                                       const char *name, char *buf, size_t size)
{
    const slot *s = must_find(cfg, section, name, -1);
    const char *file = cfg->path && cfg->path[0] ? cfg->path : "(no config file)";
    if (s->origin == FROM_FILE) {
        snprintf(buf, size, "%s:%d", file, s->line);
        return SL_CONFIG_FROM_FILE;
    }
    if (s->origin == FROM_OVERRIDE) {
        snprintf(buf, size, "-s %s.%s", section, name);
        return SL_CONFIG_FROM_OVERRIDE;
    }
    snprintf(buf, size, "%s", file);
    return SL_CONFIG_FROM_DEFAULT;
}

void sl_config_where(const sl_config *cfg, const char *section, const char *name, char *buf,
                     size_t size)
{
    sl_config_origin(cfg, section, name, buf, size);
}

int sl_config_key_error(sl_error *err, const sl_config *cfg, const char *section,
                        const char *name, const char *fmt, ...)
{
    char where[PATH_MAX + 32], message[CAUSE_MAX];
    sl_config_origin(cfg, section, name, where, sizeof where);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    return sl_error_set(err, SL_E_CONFIG, 0, where, "[%s] %s: %s", section, name, message);
}

uint64_t sl_config_section_hash(const sl_config *cfg, const char *section)
{
    XXH3_state_t state;
    XXH3_INITSTATE(&state);
    XXH3_64bits_reset(&state);
    for (size_t k = 0; k < cfg->count; k++) {
        const slot *s = &cfg->slots[k];
        if (strcmp(s->opt->section, section))
            continue;
        const char *parts[] = {s->opt->section, ".", s->opt->name, "=", s->text, "\n"};
        for (int p = 0; p < 6; p++)
            XXH3_64bits_update(&state, parts[p], strlen(parts[p]));
    }
    return XXH3_64bits_digest(&state);
}
