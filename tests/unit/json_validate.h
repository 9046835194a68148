/* A strict RFC 8259 validator for the tests (test_json, test_log): written apart from
 * core/json.c so that a bug in the writer is not mirrored by the check. Accepts one
 * value with optional surrounding whitespace; strings must hold valid UTF-8, no raw
 * control characters and only the escapes the RFC allows.
 */
#ifndef SCANLOD_TESTS_JSON_VALIDATE_H
#define SCANLOD_TESTS_JSON_VALIDATE_H

#include <string.h>

typedef struct json_cursor {
    const unsigned char *p, *end;
    int depth;
} json_cursor;

static int json_value_(json_cursor *c);

static void json_ws_(json_cursor *c)
{
    while (c->p < c->end && (*c->p == ' ' || *c->p == '\t' || *c->p == '\n' || *c->p == '\r'))
        c->p++;
}

static int json_literal_(json_cursor *c, const char *word)
{
    size_t n = strlen(word);
    if ((size_t)(c->end - c->p) < n || memcmp(c->p, word, n))
        return 0;
    c->p += n;
    return 1;
}

static int json_digits_(json_cursor *c)
{
    const unsigned char *start = c->p;
    while (c->p < c->end && *c->p >= '0' && *c->p <= '9')
        c->p++;
    return c->p > start;
}

static int json_number_(json_cursor *c)
{
    if (c->p < c->end && *c->p == '-')
        c->p++;
    if (c->p < c->end && *c->p == '0')
        c->p++;
    else if (!json_digits_(c))
        return 0;
    if (c->p < c->end && *c->p == '.' && (c->p++, !json_digits_(c)))
        return 0;
    if (c->p < c->end && (*c->p == 'e' || *c->p == 'E')) {
        c->p++;
        if (c->p < c->end && (*c->p == '+' || *c->p == '-'))
            c->p++;
        return json_digits_(c);
    }
    return 1;
}

/* One UTF-8 sequence (shortest form, no surrogates, at most U+10FFFF). */
static int json_utf8_(json_cursor *c)
{
    unsigned char b = *c->p;
    int n = b < 0x80 ? 1 : b >= 0xC2 && b <= 0xDF ? 2 : b >= 0xE0 && b <= 0xEF ? 3
          : b >= 0xF0 && b <= 0xF4 ? 4 : 0;
    if (!n || c->end - c->p < n)
        return 0;
    unsigned long cp = n == 1 ? b : b & (0x7F >> n);
    for (int k = 1; k < n; k++) {
        if ((c->p[k] & 0xC0) != 0x80)
            return 0;
        cp = cp << 6 | (c->p[k] & 0x3F);
    }
    static const unsigned long min_of[] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < min_of[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
        return 0;
    c->p += n;
    return 1;
}

static int json_string_(json_cursor *c)
{
    c->p++; /* opening quote */
    while (c->p < c->end && *c->p != '"') {
        if (*c->p < 0x20)
            return 0;
        if (*c->p != '\\') {
            if (!json_utf8_(c))
                return 0;
            continue;
        }
        if (++c->p >= c->end)
            return 0;
        if (*c->p == 'u') {
            for (int k = 1; k <= 4; k++)
                if (c->p + k >= c->end || !strchr("0123456789abcdefABCDEF", c->p[k]) || !c->p[k])
                    return 0;
            c->p += 5;
        } else if (*c->p && strchr("\"\\/bfnrt", *c->p)) {
            c->p++;
        } else {
            return 0;
        }
    }
    return c->p < c->end && c->p++;
}

/* Members or elements up to `close`; `keyed` for objects. */
static int json_container_(json_cursor *c, unsigned char close, int keyed)
{
    if (++c->depth > 64)
        return 0;
    c->p++;
    json_ws_(c);
    if (c->p < c->end && *c->p == close)
        return c->p++, c->depth--, 1;
    for (;;) {
        json_ws_(c);
        if (keyed) {
            if (c->p >= c->end || *c->p != '"' || !json_string_(c))
                return 0;
            json_ws_(c);
            if (c->p >= c->end || *c->p++ != ':')
                return 0;
        }
        if (!json_value_(c))
            return 0;
        json_ws_(c);
        if (c->p < c->end && *c->p == ',') {
            c->p++;
            continue;
        }
        if (c->p < c->end && *c->p == close)
            return c->p++, c->depth--, 1;
        return 0;
    }
}

static int json_value_(json_cursor *c)
{
    json_ws_(c);
    if (c->p >= c->end)
        return 0;
    switch (*c->p) {
    case '{': return json_container_(c, '}', 1);
    case '[': return json_container_(c, ']', 0);
    case '"': return json_string_(c);
    case 't': return json_literal_(c, "true");
    case 'f': return json_literal_(c, "false");
    case 'n': return json_literal_(c, "null");
    default: return json_number_(c);
    }
}

/* Nonzero if text[0..len) is exactly one valid JSON value. */
static inline int json_valid(const char *text, size_t len)
{
    json_cursor c = {(const unsigned char *)text, (const unsigned char *)text + len, 0};
    if (!json_value_(&c))
        return 0;
    json_ws_(&c);
    return c.p == c.end;
}

#endif
