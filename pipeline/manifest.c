/* The collection manifest's rows: the checks every row passes whatever its format, and
 * lookups (manifest.h). The two formats only cut the text into cells (manifest_csv.c,
 * manifest_json.c) and hand them here; manifest_load.c reads the file and picks the
 * format, so the parsers call into this file and nothing here calls them. */
#include "pipeline/manifest.h"

#include <ctype.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/atomicfile.h"

static const char *const column_names[SL_MF_COUNT] = {
    "file", "title", "accession", "units", "up", "credit", "licence", "description"};

int sl_manifest_column(const char *name, size_t len)
{
    while (len && isspace((unsigned char)*name))
        name++, len--;
    while (len && isspace((unsigned char)name[len - 1]))
        len--;
    static const struct { const char *name; int column; } aliases[] = {
        {"license", SL_MF_LICENCE},
        {"accession number", SL_MF_ACCESSION},
        {"accession_number", SL_MF_ACCESSION},
    };
    for (int c = 0; c < SL_MF_COUNT; c++)
        if (strlen(column_names[c]) == len && !strncasecmp(name, column_names[c], len))
            return c;
    for (size_t a = 0; a < sizeof aliases / sizeof aliases[0]; a++)
        if (strlen(aliases[a].name) == len && !strncasecmp(name, aliases[a].name, len))
            return aliases[a].column;
    return -1;
}

int sl_manifest_error(const sl_manifest *m, int line, sl_error *err, const char *fmt, ...)
{
    char where[sizeof m->path + 16], message[1024];
    snprintf(where, sizeof where, "%s:%d", m->path, line);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    return sl_error_set(err, SL_E_CONFIG, 0, where, "collection manifest: %s", message);
}

/* Length of the valid UTF-8 sequence at s (at most n bytes), 0 when it is not one. */
static size_t utf8_char(const unsigned char *s, size_t n)
{
    if (s[0] < 0x80)
        return 1;
    size_t len = s[0] >= 0xf0 && s[0] <= 0xf4 ? 4 : s[0] >= 0xe0 ? 3 : s[0] >= 0xc2 ? 2 : 0;
    if (!len || len > n || (s[0] >= 0xf8))
        return 0;
    for (size_t i = 1; i < len; i++)
        if ((s[i] & 0xc0) != 0x80)
            return 0;
    /* No overlong three- and four-byte forms, no surrogates, nothing above U+10FFFF. */
    if ((s[0] == 0xe0 && s[1] < 0xa0) || (s[0] == 0xed && s[1] >= 0xa0) ||
        (s[0] == 0xf0 && s[1] < 0x90) || (s[0] == 0xf4 && s[1] >= 0x90))
        return 0;
    return len;
}

/* A cell's text, checked: UTF-8, no control characters (but line breaks and tabs in a
 * description, which pages keep as paragraphs), blanks around it trimmed. */
static int copy_cell(const sl_manifest *m, int c, const char *text, size_t len, int line,
                     char **out, sl_error *err)
{
    while (len && isspace((unsigned char)*text))
        text++, len--;
    while (len && isspace((unsigned char)text[len - 1]))
        len--;
    if (len > SL_MANIFEST_MAX_CELL)
        return sl_manifest_error(m, line, err, "%s: %zu bytes, more than %u", column_names[c],
                                 len, SL_MANIFEST_MAX_CELL);
    const unsigned char *u = (const unsigned char *)text;
    for (size_t i = 0; i < len;) {
        size_t n = utf8_char(u + i, len - i);
        if (!n)
            return sl_manifest_error(m, line, err, "%s: not UTF-8 text (byte 0x%02x); save "
                                     "the manifest as UTF-8", column_names[c], u[i]);
        int control = u[i] < 0x20 || u[i] == 0x7f;
        if (control && !(c == SL_MF_DESCRIPTION && (u[i] == '\n' || u[i] == '\t' ||
                                                    u[i] == '\r')))
            return sl_manifest_error(m, line, err, "%s: a control character (0x%02x)",
                                     column_names[c], u[i]);
        i += n;
    }
    if (!(*out = malloc(len + 1)))
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, m->path, "out of memory");
    memcpy(*out, text, len);
    (*out)[len] = '\0';
    return 0;
}

/* The item id as the engine spells it: a path relative to [run] input ("./" dropped). */
static int check_file(const sl_manifest *m, char *file, int line, sl_error *err)
{
    while (file[0] == '.' && file[1] == '/')
        memmove(file, file + 2, strlen(file + 2) + 1);
    if (!file[0])
        return sl_manifest_error(m, line, err, "a row without a file (the item's path "
                                 "relative to [run] input)");
    const char *dots = strstr(file, "..");
    int up = dots && (dots == file || dots[-1] == '/') && (dots[2] == '/' || !dots[2]);
    if (file[0] == '/' || up || strstr(file, "//") || strstr(file, "/./"))
        return sl_manifest_error(m, line, err, "file '%s' is not a path relative to [run] "
                                 "input (an item id, e.g. 'busts/nefertiti.ply')", file);
    return 0;
}

/* units and up, in their canonical spelling ("MM" -> "mm", "Z" -> "z"). */
static int check_frame(const sl_manifest *m, sl_manifest_row *r, sl_error *err)
{
    static const char *const units[] = {"mm", "cm", "m", "in", "ft"};
    char *u = r->field[SL_MF_UNITS], *up = r->field[SL_MF_UP];
    for (char *p = u; *p; p++)
        *p = (char)tolower((unsigned char)*p);
    for (char *p = up; *p; p++)
        *p = (char)tolower((unsigned char)*p);
    int ok = !u[0];
    for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
        ok |= !strcmp(u, units[i]);
    if (!ok)
        return sl_manifest_error(m, r->line, err, "units '%s' is not one of mm, cm, m, in, ft",
                                 u);
    if (up[0] && strcmp(up, "y") && strcmp(up, "z"))
        return sl_manifest_error(m, r->line, err, "up '%s' is not y or z", up);
    return 0;
}

static void row_release(sl_manifest_row *r)
{
    for (int c = 0; c < SL_MF_COUNT; c++)
        free(r->field[c]);
    memset(r, 0, sizeof *r);
}

int sl_manifest_add_row(sl_manifest *m, const char *const cells[SL_MF_COUNT],
                        const size_t lens[SL_MF_COUNT], int line, sl_error *err)
{
    if (m->count == m->capacity) {
        size_t cap = m->capacity ? 2 * m->capacity : 64;
        sl_manifest_row *grown = realloc(m->rows, cap * sizeof *grown);
        if (!grown)
            return sl_error_set(err, SL_E_NOMEM, ENOMEM, m->path, "out of memory");
        m->rows = grown;
        m->capacity = cap;
    }
    sl_manifest_row *r = &m->rows[m->count];
    memset(r, 0, sizeof *r);
    r->line = line;
    int rc = 0;
    for (int c = 0; c < SL_MF_COUNT && rc == 0; c++)
        rc = copy_cell(m, c, cells[c] ? cells[c] : "", cells[c] ? lens[c] : 0, line,
                       &r->field[c], err);
    if (rc == 0)
        rc = check_file(m, r->field[SL_MF_FILE], line, err);
    if (rc == 0)
        rc = check_frame(m, r, err);
    if (rc) {
        row_release(r);
        return rc;
    }
    m->count++;
    return 0;
}

static int by_file(const void *a, const void *b)
{
    const sl_manifest_row *x = a, *y = b;
    int c = strcmp(x->field[SL_MF_FILE], y->field[SL_MF_FILE]);
    return c ? c : (x->line > y->line) - (x->line < y->line);
}

int sl_manifest_finish_rows(sl_manifest *m, sl_error *err)
{
    if (m->count > 1)
        qsort(m->rows, m->count, sizeof *m->rows, by_file);
    const char *base = strrchr(m->path, '/');
    base = base ? base + 1 : m->path;
    for (size_t i = 0; i < m->count; i++) {
        sl_manifest_row *r = &m->rows[i];
        if (i && !strcmp(r->field[SL_MF_FILE], m->rows[i - 1].field[SL_MF_FILE]))
            return sl_manifest_error(m, r->line, err, "file '%s' has a row already (line %d)",
                                     r->field[SL_MF_FILE], m->rows[i - 1].line);
        snprintf(r->where, sizeof r->where, "%.60s:%d", base, r->line);
        char **f = r->field;
        r->meta = (sl_item_metadata){f[SL_MF_TITLE], f[SL_MF_ACCESSION], f[SL_MF_UNITS],
                                     f[SL_MF_UP], f[SL_MF_CREDIT], f[SL_MF_LICENCE],
                                     f[SL_MF_DESCRIPTION], r->where};
        /* Every field a stage reads, each ended by its NUL: no two rows collide. */
        size_t n = 0;
        for (int c = SL_MF_TITLE; c < SL_MF_COUNT; c++)
            n += strlen(f[c]) + 1;
        char *all = malloc(n), *at = all;
        if (!all)
            return sl_error_set(err, SL_E_NOMEM, ENOMEM, m->path, "out of memory");
        for (int c = SL_MF_TITLE; c < SL_MF_COUNT; c++)
            at += strlen(strcpy(at, f[c])) + 1;
        r->hash = sl_hash_bytes(all, n);
        free(all);
    }
    return 0;
}

void sl_manifest_release(sl_manifest *m)
{
    for (size_t i = 0; i < m->count; i++)
        row_release(&m->rows[i]);
    free(m->rows);
    m->rows = NULL;
    m->count = m->capacity = 0;
}

const sl_manifest_row *sl_manifest_find(const sl_manifest *m, const char *item)
{
    size_t lo = 0, hi = m ? m->count : 0;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        int c = strcmp(m->rows[mid].field[SL_MF_FILE], item);
        if (c == 0)
            return &m->rows[mid];
        if (c < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    return NULL;
}
