/* manifest.csv: RFC 4180 as spreadsheets write it (manifest.h). The first record names
 * the columns; a cell may be quoted ("...", a quote inside doubled), and a quoted cell
 * may hold line breaks (a description's paragraphs). The separator is the header's: a
 * comma, or a semicolon or tab where the header has more of those than commas (what a
 * spreadsheet in a comma-decimal locale saves). Lines end in LF, CRLF or CR. A record
 * with more cells than the header has columns is refused; fewer are empty cells (a
 * spreadsheet drops trailing empty ones). Blank lines are skipped. */
#include "pipeline/manifest.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#define MAX_COLUMNS 64

typedef struct csv {
    const char *p, *end;
    char sep;
    int line;       /* of the next character */
    char *buf;      /* the record's cells, unescaped, each NUL-ended */
    size_t used, cap;
    size_t start[MAX_COLUMNS], len[MAX_COLUMNS];
    int cells;
} csv;

static int put(csv *c, char ch)
{
    if (c->used == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 4096;
        char *grown = realloc(c->buf, cap);
        if (!grown)
            return -1;
        c->buf = grown, c->cap = cap;
    }
    c->buf[c->used++] = ch;
    return 0;
}

/* At a line end: consumes it (CRLF as one) and counts the line. */
static int line_end(csv *c)
{
    if (c->p < c->end && (*c->p == '\n' || *c->p == '\r')) {
        if (*c->p == '\r' && c->p + 1 < c->end && c->p[1] == '\n')
            c->p++;
        c->p++;
        c->line++;
        return 1;
    }
    return 0;
}

/* One cell into c->buf; stops before its separator or line end. */
static int cell(csv *c, const sl_manifest *m, sl_error *err)
{
    if (c->cells == MAX_COLUMNS)
        return sl_manifest_error(m, c->line, err, "more than %d cells in a row", MAX_COLUMNS);
    c->start[c->cells] = c->used;
    int oom = 0;
    if (c->p < c->end && *c->p == '"') {
        int opened = c->line;
        for (c->p++;; c->p++) {
            if (c->p >= c->end)
                return sl_manifest_error(m, opened, err, "a quote opened here is never "
                                         "closed");
            if (*c->p == '"' && (c->p + 1 >= c->end || c->p[1] != '"'))
                break;
            if (*c->p == '"')
                c->p++; /* "" is a quote */
            if (*c->p == '\n' || (*c->p == '\r' && (c->p + 1 >= c->end || c->p[1] != '\n')))
                c->line++;
            oom |= put(c, *c->p);
        }
        c->p++;
        if (c->p < c->end && *c->p != c->sep && *c->p != '\n' && *c->p != '\r')
            return sl_manifest_error(m, c->line, err, "text after the closing quote of a "
                                     "cell (a quote inside a cell is written \"\")");
    } else {
        for (; c->p < c->end && *c->p != c->sep && *c->p != '\n' && *c->p != '\r'; c->p++)
            oom |= put(c, *c->p);
    }
    c->len[c->cells] = c->used - c->start[c->cells];
    oom |= put(c, '\0');
    c->cells++;
    return oom ? sl_error_set(err, SL_E_NOMEM, ENOMEM, m->path, "out of memory") : 0;
}

/* One record; 1 when one was read, 0 at the end, negative on error. */
static int record(csv *c, const sl_manifest *m, sl_error *err)
{
    c->used = 0;
    c->cells = 0;
    if (c->p >= c->end)
        return 0;
    for (;;) {
        int rc = cell(c, m, err);
        if (rc)
            return rc;
        if (c->p < c->end && *c->p == c->sep) {
            c->p++;
            continue;
        }
        line_end(c);
        return 1;
    }
}

static int blank(const csv *c)
{
    for (int i = 0; i < c->cells; i++)
        for (size_t k = 0; k < c->len[i]; k++)
            if (c->buf[c->start[i] + k] != ' ' && c->buf[c->start[i] + k] != '\t')
                return 0;
    return 1;
}

/* The separator: the header line's most frequent of , ; TAB outside quotes. */
static char separator(const char *p, const char *end)
{
    size_t n[3] = {0, 0, 0};
    int quoted = 0;
    for (; p < end && (quoted || (*p != '\n' && *p != '\r')); p++) {
        quoted ^= *p == '"';
        if (!quoted)
            n[0] += *p == ',', n[1] += *p == ';', n[2] += *p == '\t';
    }
    return n[1] > n[0] && n[1] >= n[2] ? ';' : n[2] > n[0] ? '\t' : ',';
}

/* The header: which column each cell is (column[i]). */
static int header(csv *c, const sl_manifest *m, int column[MAX_COLUMNS], sl_error *err)
{
    int rc, line;
    do {
        line = c->line;
        rc = record(c, m, err);
    } while (rc == 1 && blank(c));
    if (rc < 0)
        return rc;
    if (rc == 0)
        return sl_manifest_error(m, line, err, "empty: the first line names the columns "
                                 "(file,title,accession,units,up,credit,licence,description)");
    int seen[SL_MF_COUNT] = {0};
    for (int i = 0; i < c->cells; i++) {
        const char *name = c->buf + c->start[i];
        column[i] = sl_manifest_column(name, c->len[i]);
        if (column[i] < 0)
            return sl_manifest_error(m, line, err, "unknown column '%.60s' (the "
                                     "columns are file, title, accession, units, up, "
                                     "credit, licence, description)", name);
        if (seen[column[i]]++)
            return sl_manifest_error(m, line, err, "column '%.60s' twice", name);
    }
    if (!seen[SL_MF_FILE])
        return sl_manifest_error(m, line, err, "no 'file' column (the item's path "
                                 "relative to [run] input)");
    return 0;
}

int sl_manifest_parse_csv(sl_manifest *m, const char *text, size_t size, sl_error *err)
{
    csv c = {text, text + size, separator(text, text + size), 1, NULL, 0, 0, {0}, {0}, 0};
    int column[MAX_COLUMNS];
    int rc = header(&c, m, column, err), columns = c.cells;
    while (rc == 0) {
        int line = c.line;
        rc = record(&c, m, err);
        if (rc <= 0)
            break;
        rc = 0;
        if (blank(&c))
            continue;
        if (c.cells > columns) {
            rc = sl_manifest_error(m, line, err, "%d cells, but the header names %d columns "
                                   "(a cell with a '%c' in it must be quoted)",
                                   c.cells, columns, c.sep == '\t' ? ' ' : c.sep);
            break;
        }
        const char *cells[SL_MF_COUNT] = {NULL};
        size_t lens[SL_MF_COUNT] = {0};
        for (int i = 0; i < c.cells; i++)
            cells[column[i]] = c.buf + c.start[i], lens[column[i]] = c.len[i];
        rc = sl_manifest_add_row(m, cells, lens, line, err);
    }
    free(c.buf);
    return rc < 0 ? rc : 0;
}
