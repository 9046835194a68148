/* A small JSON writer for reports and event logs (no reader is needed: reports are
 * assembled from fragments that stages write, see docs/formats.md).
 * Numbers are printed deterministically (%.9g for doubles, non-finite as null), so the same
 * report bytes come out whatever the thread count. Keys are given by the caller and must
 * be unique within an object. Out-of-memory sets `failed`; the text is then incomplete.
 */
#ifndef SCANLOD_PIPELINE_JSON_H
#define SCANLOD_PIPELINE_JSON_H

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

#endif
