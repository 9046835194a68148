/* A small JSON writer for reports and event logs (no reader is needed: reports are
 * assembled from fragments that stages write, see docs/formats.md).
 * Numbers are printed deterministically (%.9g for doubles, non-finite as null), so the same
 * report bytes come out whatever the thread count. Keys are given by the caller and must
 * be unique within an object. Out-of-memory sets `failed`; the text is then incomplete.
 *
 * Strings (values and keys) are escaped for RFC 8259: `"` and `\` with a backslash,
 * control characters below 0x20 as \b \f \n \r \t or \u00XX; valid UTF-8 passes through
 * unchanged; every byte that is not part of a valid UTF-8 sequence (overlong forms,
 * surrogates and code points above U+10FFFF included) becomes \ufffd, so the output is
 * always valid UTF-8 and valid JSON whatever bytes a file name holds (lossy for such
 * bytes, by choice: reports are for people and tools, not for round-tripping names).
 * Misuse (nesting deeper than SL_JSON_MAX_DEPTH, closing what is not open) sets
 * `failed` too.
 */
#ifndef SCANLOD_CORE_JSON_H
#define SCANLOD_CORE_JSON_H

#include <stddef.h>
#include <stdint.h>

#define SL_JSON_MAX_DEPTH 32

typedef struct sl_json {
    char *buf;
    size_t len, cap;
    int depth;
    unsigned char has_items[SL_JSON_MAX_DEPTH]; /* does the open container hold a value */
    int pretty;  /* newline + indent per value (reports); 0 = one line (event logs) */
    int failed;
} sl_json;

void sl_json_init(sl_json *j, int pretty);
void sl_json_release(sl_json *j);

/* `key` is NULL for values inside arrays and for the top-level value. */
void sl_json_object_begin(sl_json *j, const char *key);
void sl_json_object_end(sl_json *j);
void sl_json_array_begin(sl_json *j, const char *key);
void sl_json_array_end(sl_json *j);
void sl_json_string(sl_json *j, const char *key, const char *value); /* NULL -> null */
void sl_json_u64(sl_json *j, const char *key, uint64_t value);
void sl_json_i64(sl_json *j, const char *key, int64_t value);
void sl_json_double(sl_json *j, const char *key, double value);
void sl_json_bool(sl_json *j, const char *key, int value);
/* Inserts already-valid JSON text (a fragment written by a stage). */
void sl_json_raw(sl_json *j, const char *key, const char *json_text);
/* Inserts already-valid members ("\"k\":1,\"j\":2") into the open object; NULL or ""
 * adds nothing. */
void sl_json_raw_members(sl_json *j, const char *members);

/* The text so far, NUL-terminated ("" before anything was written). */
const char *sl_json_text(const sl_json *j);

#endif
