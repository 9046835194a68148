/* What the scan readers share: errors about the source, limits, checked allocation, the
 * progress tick, and the text-line cursor with its number tokens (scan_internal.h).
 *
 * Numbers go through the ascii PLY parser (text_number.h), so a coordinate reads the same
 * bits in every text format; a token that ends at a separator other than a blank (CSV)
 * is copied first, since that parser wants a token to end at a blank or at `end`.
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/scan_internal.h"

int scan_error(const scan_src *s, int code, uint64_t line, const char *fmt, ...)
{
    char msg[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (line)
        return sl_error_set(s->err, code, 0, s->name, "line %llu: %s", (unsigned long long)line,
                            msg);
    return sl_error_set(s->err, code, 0, s->name, "%s", msg);
}

int scan_check_limit(const scan_src *s, const char *what, uint64_t count, uint64_t limit)
{
    if (count <= limit)
        return 0;
    return scan_error(s, SL_E_LIMIT, 0, "%llu %s (limit %llu)", (unsigned long long)count, what,
                      (unsigned long long)limit);
}

void *scan_alloc(const scan_src *s, uint64_t n, size_t item, int *rc)
{
    size_t bytes = 0;
    void *p = NULL;
    if (*rc)
        return NULL;
    if (n <= SIZE_MAX && !__builtin_mul_overflow((size_t)n, item, &bytes))
        p = malloc(bytes ? bytes : 1);
    if (!p)
        *rc = sl_error_set(s->err, SL_E_NOMEM, ENOMEM, s->name,
                           "out of memory for %llu items of %zu bytes", (unsigned long long)n,
                           item);
    return p;
}

int scan_reserve(const scan_src *s, void **ptr, uint64_t *cap, uint64_t need, size_t item)
{
    if (need <= *cap)
        return 0;
    uint64_t n = *cap > need / 2 ? 2 * *cap : need;
    size_t bytes;
    void *p = NULL;
    if (n <= SIZE_MAX && !__builtin_mul_overflow((size_t)n, item, &bytes))
        p = realloc(*ptr, bytes ? bytes : 1);
    if (!p)
        return sl_error_set(s->err, SL_E_NOMEM, ENOMEM, s->name,
                            "out of memory for %llu items of %zu bytes", (unsigned long long)n,
                            item);
    *ptr = p;
    *cap = n;
    return 0;
}

int scan_tick(const scan_src *s, const void *at)
{
    sl_progress *p = s->progress;
    if (!p)
        return 0;
    if (sl_progress_interrupted(p))
        return sl_error_set(s->err, SL_E_INTERRUPTED, 0, s->name, "interrupted while reading");
    double done = (double)((const unsigned char *)at - s->data) / (double)(s->size + 1);
    if (p->report) /* directly: the readers depend on error.c alone (fuzz targets) */
        p->report(p->ctx, "read", done);
    return 0;
}

void text_begin(text_cursor *c, const scan_src *s)
{
    c->p = (const char *)s->data;
    c->end = c->p + s->size;
    c->line = c->eol = c->p;
    c->number = 0;
}

int text_next_line(text_cursor *c)
{
    if (c->p >= c->end)
        return 0;
    const char *q = c->p;
    while (q < c->end && *q != '\n' && *q != '\r')
        q++;
    c->line = c->p;
    c->eol = q;
    c->number++;
    if (q < c->end && *q == '\r')
        q++;
    if (q < c->end && *q == '\n' && (q == c->eol || q[-1] == '\r'))
        q++;
    c->p = q;
    return 1;
}

int text_token_is(const char *p, const char *q, const char *word)
{
    size_t n = strlen(word);
    return (size_t)(q - p) == n && memcmp(p, word, n) == 0;
}

void text_rest(const char *p, const char *eol, const char **b, const char **e)
{
    p = text_skip(p, eol);
    while (eol > p && text_blank(eol[-1]))
        eol--;
    *b = p;
    *e = eol;
}

/* Where the token at p ends: a blank, eol, or a byte of `seps`. */
static const char *token_end(const char *p, const char *eol, const char *seps)
{
    while (p < eol && !text_blank(*p) && !(seps && strchr(seps, *p)))
        p++;
    return p;
}

static int number_token(const text_cursor *c, const char **p, const char *seps, int is_float,
                        double *out)
{
    const char *eol = c->eol, *s = text_skip(*p, eol);
    if (s == eol)
        return 0;
    const char *q = token_end(s, eol, seps), *r;
    if (q == s)
        return -1;
    char buf[80];
    float f;
    if (q == c->end || text_blank(*q) || *q == '\n' || *q == '\r') {
        /* In place, against the end of the source (what keeps the parser on its fast
         * path): the token ends at a blank or a line end, which that parser stops at. */
        r = is_float ? sl_ply_parse_float(s, c->end, &f) : sl_ply_parse_double(s, c->end, out);
        if (r != q)
            return -1;
    } else {
        size_t n = (size_t)(q - s);
        if (n >= sizeof buf)
            return -1;
        memcpy(buf, s, n);
        buf[n] = 0;
        r = is_float ? sl_ply_parse_float(buf, buf + n, &f)
                     : sl_ply_parse_double(buf, buf + n, out);
        if (r != buf + n)
            return -1;
        q += q < eol; /* past the separator (a comment cut at eol stays) */
    }
    if (is_float)
        *out = f;
    *p = q;
    return 1;
}

int text_float(const text_cursor *c, const char **p, const char *seps, float *out)
{
    double v;
    int rc = number_token(c, p, seps, 1, &v);
    if (rc == 1)
        *out = (float)v; /* exact: v holds a float */
    return rc;
}

int text_double(const text_cursor *c, const char **p, const char *seps, double *out)
{
    return number_token(c, p, seps, 0, out);
}

void scan_float_colors(const float *values, int stride, int channels, uint64_t n, uint8_t *rgba)
{
    float top = 0;
    for (uint64_t i = 0; i < n; i++)
        for (int k = 0; k < channels; k++)
            top = values[i * stride + k] > top ? values[i * stride + k] : top;
    double scale = top > 1.0f ? 1.0 : 255.0; /* 0..255 integers, or the usual [0, 1] */
    for (uint64_t i = 0; i < n; i++) {
        rgba[4 * i + 3] = 255;
        for (int k = 0; k < channels; k++) {
            double v = values[i * stride + k] * scale;
            rgba[4 * i + k] = !(v > 0) ? 0 : v >= 255 ? 255 : (uint8_t)lround(v);
        }
    }
}
