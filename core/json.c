/* The JSON writer (see json.h): an append-only buffer plus one "has this container a
 * value yet" bit per open level, which is all it takes to place commas and indentation.
 */
#include "core/json.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sl_json_init(sl_json *j, int pretty)
{
    memset(j, 0, sizeof *j);
    j->pretty = pretty;
}

void sl_json_release(sl_json *j)
{
    free(j->buf);
    sl_json_init(j, j->pretty);
}

const char *sl_json_text(const sl_json *j)
{
    return j->buf ? j->buf : "";
}

/* Room for n more bytes and the terminating NUL; on failure marks the text failed. */
static int reserve(sl_json *j, size_t n)
{
    if (j->failed)
        return -1;
    if (n > SIZE_MAX / 4 - j->len) { /* absurd; also keeps the doubling below finite */
        j->failed = 1;
        return -1;
    }
    size_t need = j->len + n + 1, cap = j->cap ? j->cap : 256;
    if (need <= j->cap)
        return 0;
    while (cap < need)
        cap *= 2;
    char *buf = realloc(j->buf, cap);
    if (!buf) {
        j->failed = 1;
        return -1;
    }
    j->buf = buf;
    j->cap = cap;
    return 0;
}

static void put(sl_json *j, const char *s, size_t n)
{
    if (reserve(j, n))
        return;
    memcpy(j->buf + j->len, s, n);
    j->len += n;
    j->buf[j->len] = '\0';
}

static void put_str(sl_json *j, const char *s)
{
    put(j, s, strlen(s));
}

static void newline_indent(sl_json *j, int depth)
{
    put(j, "\n", 1);
    for (int k = 0; k < depth; k++)
        put(j, "  ", 2);
}

/* Length of the valid UTF-8 sequence at s (RFC 3629 table 3-7), 0 if invalid. The
 * string is NUL-terminated and NUL is no continuation byte, so this never reads past it. */
static int utf8_length(const unsigned char *s)
{
    unsigned char c = s[0], lo = 0x80, hi = 0xBF;
    int n;
    if (c < 0x80)
        return 1;
    if (c >= 0xC2 && c <= 0xDF)
        n = 2;
    else if (c >= 0xE0 && c <= 0xEF)
        n = 3, lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
    else if (c >= 0xF0 && c <= 0xF4)
        n = 4, lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
    else
        return 0;
    if (s[1] < lo || s[1] > hi)
        return 0;
    for (int k = 2; k < n; k++)
        if (s[k] < 0x80 || s[k] > 0xBF)
            return 0;
    return n;
}

static const char *short_escape(unsigned char c)
{
    switch (c) {
    case '"': return "\\\"";
    case '\\': return "\\\\";
    case '\b': return "\\b";
    case '\f': return "\\f";
    case '\n': return "\\n";
    case '\r': return "\\r";
    case '\t': return "\\t";
    default: return NULL;
    }
}

static void put_escaped(sl_json *j, const char *str)
{
    const unsigned char *s = (const unsigned char *)str;
    put(j, "\"", 1);
    while (*s) {
        size_t run = 0; /* bytes that need no escape, copied in one go */
        while (s[run] >= 0x20 && s[run] < 0x80 && s[run] != '"' && s[run] != '\\')
            run++;
        put(j, (const char *)s, run);
        s += run;
        if (!*s)
            break;
        int n = utf8_length(s);
        const char *escape = n == 1 ? short_escape(*s) : NULL;
        char code[8];
        if (n > 1) {
            put(j, (const char *)s, (size_t)n);
        } else if (n == 0) {
            put_str(j, "\\ufffd");
            n = 1;
        } else if (escape) {
            put_str(j, escape);
        } else {
            snprintf(code, sizeof code, "\\u%04x", *s);
            put_str(j, code);
        }
        s += n;
    }
    put(j, "\"", 1);
}

/* Comma, newline and indent before a value, then `"key":` when given. */
static void begin_value(sl_json *j, const char *key)
{
    if (j->depth > 0) {
        if (j->has_items[j->depth - 1])
            put(j, ",", 1);
        j->has_items[j->depth - 1] = 1;
        if (j->pretty)
            newline_indent(j, j->depth);
    }
    if (key) {
        put_escaped(j, key);
        put_str(j, j->pretty ? ": " : ":");
    }
}

static void open_container(sl_json *j, const char *key, const char *bracket)
{
    if (j->depth >= SL_JSON_MAX_DEPTH) {
        j->failed = 1;
        return;
    }
    begin_value(j, key);
    put(j, bracket, 1);
    j->has_items[j->depth++] = 0;
}

static void close_container(sl_json *j, const char *bracket)
{
    if (j->depth <= 0) {
        j->failed = 1;
        return;
    }
    j->depth--;
    if (j->pretty && j->has_items[j->depth])
        newline_indent(j, j->depth);
    put(j, bracket, 1);
}

void sl_json_object_begin(sl_json *j, const char *key)
{
    open_container(j, key, "{");
}

void sl_json_object_end(sl_json *j)
{
    close_container(j, "}");
}

void sl_json_array_begin(sl_json *j, const char *key)
{
    open_container(j, key, "[");
}

void sl_json_array_end(sl_json *j)
{
    close_container(j, "]");
}

void sl_json_string(sl_json *j, const char *key, const char *value)
{
    begin_value(j, key);
    if (value)
        put_escaped(j, value);
    else
        put(j, "null", 4);
}

void sl_json_u64(sl_json *j, const char *key, uint64_t value)
{
    char text[24];
    begin_value(j, key);
    put(j, text, (size_t)snprintf(text, sizeof text, "%" PRIu64, value));
}

void sl_json_i64(sl_json *j, const char *key, int64_t value)
{
    char text[24];
    begin_value(j, key);
    put(j, text, (size_t)snprintf(text, sizeof text, "%" PRId64, value));
}

void sl_json_double(sl_json *j, const char *key, double value)
{
    char text[32];
    begin_value(j, key);
    if (!isfinite(value)) {
        put(j, "null", 4);
        return;
    }
    int n = snprintf(text, sizeof text, "%.9g", value);
    /* A library that calls setlocale() could make printf write a decimal comma. */
    for (char *comma = strchr(text, ','); comma; comma = strchr(comma, ','))
        *comma = '.';
    put(j, text, (size_t)n);
}

void sl_json_bool(sl_json *j, const char *key, int value)
{
    begin_value(j, key);
    put_str(j, value ? "true" : "false");
}

void sl_json_raw(sl_json *j, const char *key, const char *json_text)
{
    begin_value(j, key);
    put_str(j, json_text ? json_text : "null");
}

void sl_json_raw_members(sl_json *j, const char *members)
{
    if (members && members[0]) {
        begin_value(j, NULL);
        put_str(j, members);
    }
}
