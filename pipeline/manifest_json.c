/* manifest.json (manifest.h): either an array of rows,
 *   [ {"file": "busts/nefertiti.ply", "title": "Nefertiti", "units": "mm", "up": "z"}, ... ]
 * or an object whose keys are the files,
 *   { "busts/nefertiti.ply": {"title": "Nefertiti", "units": "mm", "up": "z"}, ... }
 * A value is a string, a number (kept as written: an accession number 1998.123) or null
 * (empty). Anything else, a key that is no column, and JSON that is not JSON are refused
 * with the line. A small reader of its own: the engine's floor has no JSON reader, and
 * this shape needs two levels and strings. */
#include "pipeline/manifest.h"

#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct reader {
    const char *p, *end;
    int line;
    const sl_manifest *m;
    sl_error *err;
    char *buf; /* the string just read, unescaped */
    size_t used, cap;
} reader;

static void blanks(reader *r)
{
    for (; r->p < r->end && strchr(" \t\r\n", *r->p); r->p++)
        r->line += *r->p == '\n';
}

static int fail(reader *r, const char *what)
{
    return sl_manifest_error(r->m, r->line, r->err, "not the JSON expected here: %s", what);
}

/* Next non-blank character is `ch`: consumed, 1; else 0. */
static int take(reader *r, char ch)
{
    blanks(r);
    if (r->p < r->end && *r->p == ch) {
        r->p++;
        return 1;
    }
    return 0;
}

static int put(reader *r, const char *bytes, size_t n)
{
    if (r->used + n + 1 > r->cap) {
        size_t cap = r->cap ? 2 * r->cap : 4096;
        while (cap < r->used + n + 1)
            cap *= 2;
        char *grown = realloc(r->buf, cap);
        if (!grown)
            return sl_error_set(r->err, SL_E_NOMEM, ENOMEM, r->m->path, "out of memory");
        r->buf = grown, r->cap = cap;
    }
    memcpy(r->buf + r->used, bytes, n);
    r->used += n;
    r->buf[r->used] = '\0';
    return 0;
}

static int hex4(reader *r, uint32_t *out)
{
    *out = 0;
    for (int i = 0; i < 4; i++, r->p++) {
        char ch = r->p < r->end ? *r->p : 0;
        int v = ch >= '0' && ch <= '9' ? ch - '0' : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10
              : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10 : -1;
        if (v < 0)
            return fail(r, "\\u needs four hex digits");
        *out = *out << 4 | (uint32_t)v;
    }
    return 0;
}

/* \uXXXX (a surrogate pair too) as UTF-8. */
static int unicode(reader *r)
{
    uint32_t u, lo;
    int rc = hex4(r, &u);
    if (rc == 0 && u >= 0xd800 && u < 0xdc00) {
        if (r->end - r->p < 2 || r->p[0] != '\\' || r->p[1] != 'u')
            return fail(r, "a lone surrogate \\u escape");
        r->p += 2;
        if ((rc = hex4(r, &lo)) == 0 && (lo < 0xdc00 || lo > 0xdfff))
            return fail(r, "a lone surrogate \\u escape");
        u = 0x10000 + ((u - 0xd800) << 10) + (lo - 0xdc00);
    } else if (rc == 0 && u >= 0xdc00 && u < 0xe000) {
        return fail(r, "a lone surrogate \\u escape");
    }
    char b[4];
    size_t n = u < 0x80 ? 1 : u < 0x800 ? 2 : u < 0x10000 ? 3 : 4;
    static const unsigned char lead[5] = {0, 0, 0xc0, 0xe0, 0xf0};
    for (size_t i = n; i-- > 1; u >>= 6)
        b[i] = (char)(0x80 | (u & 0x3f));
    b[0] = (char)(lead[n] | u);
    return rc ? rc : put(r, b, n);
}

/* A string (the opening quote next) into r->buf. */
static int string(reader *r)
{
    static const char from[] = "\"\\/bfnrt", to[] = "\"\\/\b\f\n\r\t";
    r->used = 0;
    int rc = put(r, "", 0);
    if (!take(r, '"'))
        return fail(r, "a string");
    while (rc == 0) {
        if (r->p >= r->end || *r->p == '\n')
            return fail(r, "a string that ends");
        char ch = *r->p++;
        if (ch == '"')
            return 0;
        if ((unsigned char)ch < 0x20)
            return fail(r, "a control character inside a string");
        if (ch != '\\') {
            rc = put(r, &ch, 1);
            continue;
        }
        const char *esc = r->p < r->end ? strchr(from, *r->p) : NULL;
        if (r->p < r->end && *r->p == 'u') {
            r->p++;
            rc = unicode(r);
        } else if (esc && *esc) {
            r->p++;
            rc = put(r, &to[esc - from], 1);
        } else {
            return fail(r, "an unknown escape in a string");
        }
    }
    return rc;
}

/* A cell's value (string, number or null) into r->buf. */
static int value(reader *r)
{
    blanks(r);
    if (r->p < r->end && *r->p == '"')
        return string(r);
    r->used = 0;
    if (r->end - r->p >= 4 && !memcmp(r->p, "null", 4)) {
        r->p += 4;
        return put(r, "", 0);
    }
    const char *s = r->p;
    while (r->p < r->end && strchr("+-.0123456789eE", *r->p))
        r->p++;
    if (r->p == s)
        return fail(r, "a string, number or null as a column's value");
    return put(r, s, (size_t)(r->p - s));
}

/* One row object; `file` (may be NULL) is its key in the keyed form. */
static int row(reader *r, const char *file, int line)
{
    char *cell[SL_MF_COUNT] = {NULL};
    size_t len[SL_MF_COUNT] = {0};
    int rc = take(r, '{') ? 0 : fail(r, "an object for each row");
    if (rc == 0 && file && !(cell[SL_MF_FILE] = strdup(file)))
        rc = sl_error_set(r->err, SL_E_NOMEM, ENOMEM, r->m->path, "out of memory");
    len[SL_MF_FILE] = file ? strlen(file) : 0;
    int first = 1;
    while (rc == 0 && !take(r, '}')) {
        if (!first && !take(r, ','))
            rc = fail(r, "',' or '}' after a value");
        first = 0;
        if (rc == 0)
            rc = string(r);
        int c = rc ? -1 : sl_manifest_column(r->buf, r->used);
        if (rc == 0 && c < 0)
            rc = sl_manifest_error(r->m, r->line, r->err, "unknown column '%.60s' (the "
                                   "columns are file, title, accession, units, up, credit, "
                                   "licence, description)", r->buf);
        if (rc == 0 && cell[c])
            rc = sl_manifest_error(r->m, r->line, r->err, "column '%.60s' twice in a row",
                                   r->buf);
        if (rc == 0 && !take(r, ':'))
            rc = fail(r, "':' after a key");
        if (rc == 0)
            rc = value(r);
        if (rc == 0 && !(cell[c] = malloc(r->used + 1)))
            rc = sl_error_set(r->err, SL_E_NOMEM, ENOMEM, r->m->path, "out of memory");
        if (rc == 0)
            memcpy(cell[c], r->buf, r->used + 1), len[c] = r->used;
    }
    if (rc == 0)
        rc = sl_manifest_add_row((sl_manifest *)r->m, (const char *const *)cell, len, line,
                                 r->err);
    for (int c = 0; c < SL_MF_COUNT; c++)
        free(cell[c]);
    return rc;
}

static int rows(reader *r)
{
    int keyed = take(r, '{'), rc = 0;
    if (!keyed && !take(r, '['))
        return fail(r, "an array of rows, or an object of rows by file");
    for (int first = 1; rc == 0 && !take(r, keyed ? '}' : ']'); first = 0) {
        if (!first && !take(r, ','))
            return fail(r, keyed ? "',' or '}' after a row" : "',' or ']' after a row");
        blanks(r);
        int line = r->line;
        char *file = NULL;
        if (keyed && (rc = string(r)) == 0 && !(file = strdup(r->buf)))
            rc = sl_error_set(r->err, SL_E_NOMEM, ENOMEM, r->m->path, "out of memory");
        if (rc == 0 && keyed && !take(r, ':'))
            rc = fail(r, "':' after a file");
        if (rc == 0)
            rc = row(r, file, line);
        free(file);
    }
    if (rc == 0 && (blanks(r), r->p != r->end))
        rc = fail(r, "nothing after the rows");
    return rc;
}

int sl_manifest_parse_json(sl_manifest *m, const char *text, size_t size, sl_error *err)
{
    reader r = {text, text + size, 1, m, err, NULL, 0, 0};
    int rc = rows(&r);
    free(r.buf);
    return rc;
}
