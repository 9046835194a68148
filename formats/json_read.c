/* JSON text -> flat tokens (json_read.h): recursive descent, at most SL_JDOC_MAX_DEPTH
 * deep, the token array grown by doubling up to the caller's limit.
 */
#include "formats/json_read.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "formats/text_number.h"

typedef struct jparse {
    sl_jdoc *d;
    const char *p, *end;
    uint32_t cap, max_tokens;
    int code;
    char *why;
    size_t why_size;
} jparse;

static int fail(jparse *j, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

static int fail(jparse *j, int code, const char *fmt, ...)
{
    if (j->code)
        return j->code;
    if (!j->why_size)
        return j->code = code;
    char msg[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    snprintf(j->why, j->why_size, "JSON byte %llu: %s",
             (unsigned long long)(j->p - j->d->text), msg);
    return j->code = code;
}

static void skip_ws(jparse *j)
{
    while (j->p < j->end && (*j->p == ' ' || *j->p == '\t' || *j->p == '\n' || *j->p == '\r'))
        j->p++;
}

/* A new token of `type` at the current position; its index in *at. */
static int add_token(jparse *j, int type, uint32_t *at)
{
    sl_jdoc *d = j->d;
    if (d->count == j->max_tokens)
        return fail(j, SL_E_LIMIT, "more than %u values", j->max_tokens);
    if (d->count == j->cap) {
        uint32_t cap = j->cap ? (j->cap > j->max_tokens / 2 ? j->max_tokens : 2 * j->cap) : 256;
        sl_jdoc_token *t = realloc(d->tokens, (size_t)cap * sizeof *t);
        if (!t)
            return fail(j, SL_E_NOMEM, "out of memory for %u values", cap);
        d->tokens = t;
        j->cap = cap;
    }
    *at = d->count++;
    sl_jdoc_token *t = &d->tokens[*at];
    memset(t, 0, sizeof *t);
    t->type = (uint8_t)type;
    t->start = (uint32_t)(j->p - d->text);
    return 0;
}

static int hex4(const char *p)
{
    int v = 0;
    for (int i = 0; i < 4; i++) {
        char c = p[i];
        int h = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10
                : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
        if (h < 0)
            return -1;
        v = v * 16 + h;
    }
    return v;
}

static int parse_string(jparse *j)
{
    uint32_t at;
    j->p++; /* the opening quote */
    int rc = add_token(j, SL_JDOC_STRING, &at);
    if (rc)
        return rc;
    sl_jdoc_token *t = &j->d->tokens[at];
    while (j->p < j->end && *j->p != '"') {
        unsigned char c = (unsigned char)*j->p;
        if (c < 0x20)
            return fail(j, SL_E_BADINPUT, "control character in a string");
        if (c == '\\') {
            t->escaped = 1;
            if (j->end - j->p < 2 || !strchr("\"\\/bfnrtu", j->p[1]))
                return fail(j, SL_E_BADINPUT, "bad escape in a string");
            if (j->p[1] == 'u' && (j->end - j->p < 6 || hex4(j->p + 2) < 0))
                return fail(j, SL_E_BADINPUT, "bad \\u escape in a string");
            j->p += j->p[1] == 'u' ? 6 : 2;
            continue;
        }
        j->p++;
    }
    if (j->p >= j->end)
        return fail(j, SL_E_BADINPUT, "unterminated string");
    t->length = (uint32_t)(j->p - j->d->text) - t->start;
    t->next = j->d->count;
    j->p++;
    return 0;
}

static const char *digits(const char *p, const char *end)
{
    while (p < end && *p >= '0' && *p <= '9')
        p++;
    return p;
}

static int parse_number(jparse *j)
{
    const char *s = j->p, *p = s + (s < j->end && *s == '-');
    const char *q = digits(p, j->end);
    if (q == p || (*p == '0' && q - p > 1))
        return fail(j, SL_E_BADINPUT, "bad number");
    if (q < j->end && *q == '.') {
        const char *f = digits(q + 1, j->end);
        if (f == q + 1)
            return fail(j, SL_E_BADINPUT, "bad number");
        q = f;
    }
    if (q < j->end && (*q == 'e' || *q == 'E')) {
        const char *e = q + 1 + (q + 1 < j->end && (q[1] == '+' || q[1] == '-'));
        const char *f = digits(e, j->end);
        if (f == e)
            return fail(j, SL_E_BADINPUT, "bad number");
        q = f;
    }
    uint32_t at;
    int rc = add_token(j, SL_JDOC_NUMBER, &at);
    if (rc)
        return rc;
    j->d->tokens[at].length = (uint32_t)(q - s);
    j->d->tokens[at].next = j->d->count;
    j->p = q;
    return 0;
}

static int parse_literal(jparse *j)
{
    static const struct { const char *word; int type; } words[] = {
        {"true", SL_JDOC_TRUE}, {"false", SL_JDOC_FALSE}, {"null", SL_JDOC_NULL}};
    for (int i = 0; i < 3; i++) {
        size_t n = strlen(words[i].word);
        if ((size_t)(j->end - j->p) >= n && !memcmp(j->p, words[i].word, n)) {
            uint32_t at;
            int rc = add_token(j, words[i].type, &at);
            if (rc)
                return rc;
            j->d->tokens[at].length = (uint32_t)n;
            j->d->tokens[at].next = j->d->count;
            j->p += n;
            return 0;
        }
    }
    return fail(j, SL_E_BADINPUT, "unexpected character '%c'",
                *j->p >= 0x20 && *j->p < 0x7f ? *j->p : '?');
}

static int parse_value(jparse *j, int depth);

/* An array or object after its opening bracket; `close` the closing one. */
static int parse_container(jparse *j, int depth, int object)
{
    uint32_t at;
    int rc = add_token(j, object ? SL_JDOC_OBJECT : SL_JDOC_ARRAY, &at);
    if (rc)
        return rc;
    char close = object ? '}' : ']';
    j->p++;
    skip_ws(j);
    uint32_t count = 0;
    while (j->p < j->end && *j->p != close) {
        if (count && *j->p++ != ',')
            return fail(j, SL_E_BADINPUT, "expected ',' or '%c'", close);
        skip_ws(j);
        if (object) {
            if (j->p >= j->end || *j->p != '"')
                return fail(j, SL_E_BADINPUT, "expected a member name");
            if ((rc = parse_string(j)))
                return rc;
            skip_ws(j);
            if (j->p >= j->end || *j->p++ != ':')
                return fail(j, SL_E_BADINPUT, "expected ':'");
        }
        if ((rc = parse_value(j, depth + 1)))
            return rc;
        count++;
        skip_ws(j);
    }
    if (j->p >= j->end)
        return fail(j, SL_E_BADINPUT, "unterminated %s", object ? "object" : "array");
    j->p++;
    sl_jdoc_token *t = &j->d->tokens[at];
    t->count = count;
    t->length = (uint32_t)(j->p - j->d->text) - t->start;
    t->next = j->d->count;
    return 0;
}

static int parse_value(jparse *j, int depth)
{
    skip_ws(j);
    if (j->p >= j->end)
        return fail(j, SL_E_BADINPUT, "a value is missing");
    if (depth > SL_JDOC_MAX_DEPTH)
        return fail(j, SL_E_BADINPUT, "nested deeper than %d", SL_JDOC_MAX_DEPTH);
    char c = *j->p;
    if (c == '{' || c == '[')
        return parse_container(j, depth, c == '{');
    if (c == '"')
        return parse_string(j);
    if (c == '-' || (c >= '0' && c <= '9'))
        return parse_number(j);
    return parse_literal(j);
}

int sl_jdoc_parse(sl_jdoc *d, const char *text, size_t size, uint32_t max_tokens, char *why,
                  size_t why_size)
{
    memset(d, 0, sizeof *d);
    d->text = text;
    d->size = size;
    jparse j = {d, text, text + size, 0, max_tokens ? max_tokens : 1, 0, why, why_size};
    if (size >= UINT32_MAX)
        return fail(&j, SL_E_LIMIT, "%zu bytes of JSON (limit 4 GiB)", size);
    int rc = parse_value(&j, 0);
    skip_ws(&j);
    if (!rc && j.p != j.end)
        rc = fail(&j, SL_E_BADINPUT, "text after the document");
    if (rc)
        sl_jdoc_release(d);
    return rc;
}

void sl_jdoc_release(sl_jdoc *d)
{
    free(d->tokens);
    d->tokens = NULL;
    d->count = 0;
}

int sl_jdoc_type(const sl_jdoc *d, uint32_t t)
{
    return t && t < d->count ? d->tokens[t].type : SL_JDOC_NULL;
}

uint32_t sl_jdoc_get(const sl_jdoc *d, uint32_t object, const char *key)
{
    if (object >= d->count || d->tokens[object].type != SL_JDOC_OBJECT)
        return 0;
    uint32_t t = object + 1;
    for (uint32_t i = 0; i < d->tokens[object].count; i++) {
        if (sl_jdoc_string_is(d, t, key))
            return t + 1;
        t = d->tokens[t + 1].next;
    }
    return 0;
}

uint32_t sl_jdoc_item(const sl_jdoc *d, uint32_t array, uint32_t i)
{
    if (!array || array >= d->count || d->tokens[array].type != SL_JDOC_ARRAY ||
        i >= d->tokens[array].count)
        return 0;
    uint32_t t = array + 1;
    while (i--)
        t = d->tokens[t].next;
    return t;
}

int sl_jdoc_number(const sl_jdoc *d, uint32_t t, double *out)
{
    if (sl_jdoc_type(d, t) != SL_JDOC_NUMBER)
        return 0;
    const sl_jdoc_token *k = &d->tokens[t];
    char buf[256];
    if (k->length >= sizeof buf) /* more digits than any number a glTF file needs */
        return 0;
    memcpy(buf, d->text + k->start, k->length);
    buf[k->length] = 0;
    return sl_ply_parse_double(buf, buf + k->length, out) != NULL;
}

int sl_jdoc_index(const sl_jdoc *d, uint32_t t, uint64_t limit, uint64_t *out)
{
    double v;
    if (!t)
        return 0;
    if (!sl_jdoc_number(d, t, &v) || !(v >= 0 && v < (double)limit && v < 1.8e19) ||
        v != (double)(uint64_t)v)
        return -1;
    *out = (uint64_t)v;
    return 1;
}

/* One decoded code point of a \u escape (a surrogate pair counts as one) at p[0] == '\\'. */
static unsigned long escape_point(const char *p, const char *end, const char **after)
{
    unsigned long u = (unsigned long)hex4(p + 2);
    *after = p + 6;
    if (u >= 0xD800 && u < 0xDC00 && end - *after >= 6 && (*after)[0] == '\\' &&
        (*after)[1] == 'u') {
        int lo = hex4(*after + 2);
        if (lo >= 0xDC00 && lo < 0xE000) {
            u = 0x10000 + ((u - 0xD800) << 10) + (unsigned long)(lo - 0xDC00);
            *after += 6;
        }
    }
    return u;
}

static size_t put_utf8(unsigned long u, char *out)
{
    if (u < 0x80)
        return out[0] = (char)u, 1;
    if (u < 0x800)
        return out[0] = (char)(0xC0 | (u >> 6)), out[1] = (char)(0x80 | (u & 0x3F)), 2;
    if (u < 0x10000)
        return out[0] = (char)(0xE0 | (u >> 12)), out[1] = (char)(0x80 | ((u >> 6) & 0x3F)),
               out[2] = (char)(0x80 | (u & 0x3F)), 3;
    out[0] = (char)(0xF0 | (u >> 18)), out[1] = (char)(0x80 | ((u >> 12) & 0x3F));
    out[2] = (char)(0x80 | ((u >> 6) & 0x3F)), out[3] = (char)(0x80 | (u & 0x3F));
    return 4;
}

long sl_jdoc_string(const sl_jdoc *d, uint32_t t, char *buf, size_t size)
{
    if (t >= d->count || d->tokens[t].type != SL_JDOC_STRING)
        return -1;
    const sl_jdoc_token *k = &d->tokens[t];
    const char *p = d->text + k->start, *end = p + k->length;
    size_t n = 0;
    while (p < end) {
        char enc[4];
        size_t len = 1;
        if (*p != '\\') {
            enc[0] = *p++;
        } else if (p[1] == 'u') {
            len = put_utf8(escape_point(p, end, &p), enc);
        } else {
            static const char from[] = "\"\\/bfnrt", to[] = "\"\\/\b\f\n\r\t";
            enc[0] = to[strchr(from, p[1]) - from];
            p += 2;
        }
        for (size_t i = 0; i < len; i++, n++)
            if (n + 1 < size)
                buf[n] = enc[i];
    }
    if (size)
        buf[n < size ? n : size - 1] = 0;
    return (long)n;
}

int sl_jdoc_string_is(const sl_jdoc *d, uint32_t t, const char *s)
{
    if (t >= d->count || d->tokens[t].type != SL_JDOC_STRING)
        return 0;
    const sl_jdoc_token *k = &d->tokens[t];
    size_t n = strlen(s);
    if (!k->escaped)
        return k->length == n && memcmp(d->text + k->start, s, n) == 0;
    char buf[256];
    long len = sl_jdoc_string(d, t, buf, sizeof buf);
    return len >= 0 && (size_t)len == n && n < sizeof buf && memcmp(buf, s, n) == 0;
}
