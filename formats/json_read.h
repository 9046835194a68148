/* A JSON reader for input files (the glTF reader's; docs/inputs.md, "glTF"): RFC 8259 text
 * into one flat array of tokens in document order, so a document is one allocation of
 * at most `max_tokens` small tokens and the values stay in the caller's text (strings are
 * decoded only when asked for). Numbers are read by the text formats' parser
 * (text_number.h): exact, and the same whatever locale a library has set.
 *
 * Refused (SL_E_BADINPUT, the reason and byte offset in `why`): anything RFC 8259 does not
 * allow (trailing commas, comments, single quotes, control characters in strings, bad
 * escapes, leading zeros, text after the value); nesting deeper than SL_JDOC_MAX_DEPTH.
 * More than `max_tokens` values: SL_E_LIMIT. Texts of 4 GiB or more: SL_E_LIMIT. Invalid
 * UTF-8 passes as bytes (names are compared as bytes).
 *
 * Thread safety: reentrant; a parsed document is read-only.
 */
#ifndef SCANLOD_FORMATS_JSON_READ_H
#define SCANLOD_FORMATS_JSON_READ_H

#include <stddef.h>
#include <stdint.h>

#define SL_JDOC_MAX_DEPTH 64

enum sl_jdoc_type {
    SL_JDOC_NULL, SL_JDOC_FALSE, SL_JDOC_TRUE, SL_JDOC_NUMBER, SL_JDOC_STRING,
    SL_JDOC_ARRAY, SL_JDOC_OBJECT
};

typedef struct sl_jdoc_token {
    uint8_t type;       /* enum sl_jdoc_type */
    uint8_t escaped;    /* a string holding backslash escapes */
    uint32_t start;     /* the value's first byte (a string's first byte inside the quotes) */
    uint32_t length;    /* its bytes (a string's without the quotes) */
    uint32_t count;     /* array: items; object: members (each a key token, then a value) */
    uint32_t next;      /* the token after this value and everything inside it */
} sl_jdoc_token;

typedef struct sl_jdoc {
    const char *text;
    size_t size;
    sl_jdoc_token *tokens; /* tokens[0] is the document's value */
    uint32_t count;
} sl_jdoc;

/* Parses text[0..size) into `d` (the text is borrowed: keep it while `d` is used).
 * Returns 0, SL_E_BADINPUT / SL_E_LIMIT (why says what and where) or SL_E_NOMEM. */
int sl_jdoc_parse(sl_jdoc *d, const char *text, size_t size, uint32_t max_tokens, char *why,
                  size_t why_size);
void sl_jdoc_release(sl_jdoc *d);

/* The value of member `key` of object token `object`; 0 (never a member's value) when
 * absent or when `object` is 0 or not an object. */
uint32_t sl_jdoc_get(const sl_jdoc *d, uint32_t object, const char *key);
/* Array item `i` of token `array` (a walk: O(i)); 0 when out of range or not an array. */
uint32_t sl_jdoc_item(const sl_jdoc *d, uint32_t array, uint32_t i);
/* The type of token t; SL_JDOC_NULL for t = 0 (absent). */
int sl_jdoc_type(const sl_jdoc *d, uint32_t t);

/* Token t as a number: 1 and *out, or 0 (absent, not a number). */
int sl_jdoc_number(const sl_jdoc *d, uint32_t t, double *out);
/* Token t as an integer in [0, limit): 1 and *out; 0 when absent; -1 when present but not
 * such an integer. */
int sl_jdoc_index(const sl_jdoc *d, uint32_t t, uint64_t limit, uint64_t *out);
/* Token t as a string, decoded (escapes, \u as UTF-8; a NUL byte decoded from \u0000 ends
 * the copy) into buf, NUL-terminated and cut to fit: its decoded length, or -1 when t is
 * not a string. */
long sl_jdoc_string(const sl_jdoc *d, uint32_t t, char *buf, size_t size);
/* Whether token t is the string `s` (decoded). */
int sl_jdoc_string_is(const sl_jdoc *d, uint32_t t, const char *s);

#endif
