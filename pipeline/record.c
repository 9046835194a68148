/* Commit records (see record.h). */
#include "pipeline/record.h"

#include <dirent.h>
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/atomicfile.h"
#include "core/escape.h"

sl_hash sl_stage_key(const char *stage, uint32_t stage_version, uint64_t config_hash,
                     sl_hash upstream)
{
    char text[256];
    char hex[SL_HASH_HEX_SIZE];
    sl_hash_hex(upstream, hex);
    int n = snprintf(text, sizeof text, "scanlod-stage-key 1\n%s\n%u\n%016" PRIx64 "\n%s\n",
                     stage, stage_version, config_hash, hex);
    return sl_hash_bytes(text, (size_t)n);
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* Output files of an artifact directory, sorted (deterministic record). */
static int list_outputs(const char *dir, char names[][128], int *count, sl_error *err)
{
    DIR *d = opendir(dir);
    if (!d)
        return sl_error_errno(err, errno, dir, "opendir");
    char *found[SL_RECORD_MAX_OUTPUTS];
    int n = 0, rc = 0;
    struct dirent *de;
    while ((de = readdir(d))) {
        if (de->d_name[0] == '.' || de->d_name[0] == '_' || !strcmp(de->d_name, SL_RECORD_FILE))
            continue;
        if (n == SL_RECORD_MAX_OUTPUTS || strlen(de->d_name) >= 128) {
            rc = sl_error_set(err, SL_E_INTERNAL, 0, dir, "too many or too long output names");
            break;
        }
        found[n++] = strdup(de->d_name);
    }
    closedir(d);
    qsort(found, (size_t)n, sizeof *found, compare_names);
    for (int i = 0; i < n; i++) {
        snprintf(names[i], 128, "%s", found[i]);
        free(found[i]);
    }
    *count = rc ? 0 : n;
    return rc;
}

static sl_hash digest_outputs(const sl_record *r)
{
    char line[256];
    char *text = malloc((size_t)r->output_count * sizeof line + 1);
    size_t len = 0;
    if (!text)
        return (sl_hash){0, 0};
    for (int i = 0; i < r->output_count; i++) {
        char hex[SL_HASH_HEX_SIZE];
        sl_hash_hex(r->outputs[i].hash, hex);
        int n = snprintf(line, sizeof line, "%s %" PRIu64 " %s\n", r->outputs[i].name,
                         r->outputs[i].size, hex);
        memcpy(text + len, line, (size_t)n);
        len += (size_t)n;
    }
    sl_hash h = sl_hash_bytes(text, len);
    free(text);
    return h;
}

int sl_record_commit(const char *record_path, const char *dir, const char *const *names,
                     const char *stage, uint32_t stage_version, const char *item, sl_hash key,
                     sl_record *out, sl_error *err)
{
    sl_record *r = calloc(1, sizeof *r);
    if (!r)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, record_path, "out of memory");
    int rc = 0;
    if (!names) {
        char(*listed)[128] = calloc(SL_RECORD_MAX_OUTPUTS, 128);
        rc = listed ? list_outputs(dir, listed, &r->output_count, err)
                    : sl_error_set(err, SL_E_NOMEM, ENOMEM, dir, "out of memory");
        for (int i = 0; rc == 0 && i < r->output_count; i++)
            snprintf(r->outputs[i].name, sizeof r->outputs[i].name, "%s", listed[i]);
        free(listed);
    } else {
        for (; names[r->output_count] && r->output_count < SL_RECORD_MAX_OUTPUTS; r->output_count++)
            snprintf(r->outputs[r->output_count].name, 128, "%s", names[r->output_count]);
    }
    for (int i = 0; rc == 0 && i < r->output_count; i++) {
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/%s", dir, r->outputs[i].name);
        rc = sl_hash_file(path, &r->outputs[i].hash, &r->outputs[i].size, err);
    }
    if (rc) {
        free(r);
        return rc;
    }
    snprintf(r->stage, sizeof r->stage, "%s", stage);
    snprintf(r->item, sizeof r->item, "%s", item);
    r->stage_version = stage_version;
    r->key = key;
    r->outputs_digest = digest_outputs(r);

    sl_atomic_file f;
    rc = sl_atomic_open(&f, record_path, err);
    if (rc == 0) {
        char key_hex[SL_HASH_HEX_SIZE], digest_hex[SL_HASH_HEX_SIZE];
        sl_hash_hex(r->key, key_hex);
        sl_hash_hex(r->outputs_digest, digest_hex);
        char item_line[3 * sizeof r->item]; /* one line, whatever the name holds */
        if (sl_escape(r->item, 0, 0, item_line, sizeof item_line) < 0)
            rc = sl_error_set(err, SL_E_INTERNAL, 0, record_path, "item id too long");
        if (rc == 0)
            rc = sl_atomic_printf(&f, err, "format=scanlod-record 1\nstage=%s\nstage_version=%u\n"
                                  "item=%s\nkey=%s\n",
                                  r->stage, r->stage_version, item_line, key_hex);
        for (int i = 0; rc == 0 && i < r->output_count; i++) {
            char hex[SL_HASH_HEX_SIZE];
            sl_hash_hex(r->outputs[i].hash, hex);
            rc = sl_atomic_printf(&f, err, "output=%s %" PRIu64 " %s\n", r->outputs[i].name,
                                  r->outputs[i].size, hex);
        }
        if (rc == 0)
            rc = sl_atomic_printf(&f, err, "outputs_digest=%s\nend\n", digest_hex);
        rc = rc ? (sl_atomic_abort(&f), rc) : sl_atomic_commit(&f, err);
    }
    if (rc == 0 && out)
        *out = *r;
    free(r);
    return rc;
}

static int parse_record(char *text, sl_record *r)
{
    int complete = 0, have_key = 0, have_digest = 0;
    for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
        if (!strcmp(line, "end")) {
            complete = 1;
            break;
        }
        char *eq = strchr(line, '=');
        if (!eq)
            return -1;
        *eq = '\0';
        const char *k = line, *v = eq + 1;
        if (!strcmp(k, "format") && strcmp(v, "scanlod-record 1"))
            return -1;
        if (!strcmp(k, "stage"))
            snprintf(r->stage, sizeof r->stage, "%s", v);
        else if (!strcmp(k, "stage_version"))
            r->stage_version = (uint32_t)strtoul(v, NULL, 10);
        else if (!strcmp(k, "item"))
            snprintf(r->item, sizeof r->item, "%s", v), sl_unescape(r->item);
        else if (!strcmp(k, "key"))
            have_key = sl_hash_parse(v, &r->key) == 0;
        else if (!strcmp(k, "outputs_digest"))
            have_digest = sl_hash_parse(v, &r->outputs_digest) == 0;
        else if (!strcmp(k, "output")) {
            if (r->output_count == SL_RECORD_MAX_OUTPUTS)
                return -1;
            sl_record_output *o = &r->outputs[r->output_count++];
            char hex[64];
            unsigned long long size;
            if (sscanf(v, "%127s %llu %63s", o->name, &size, hex) != 3 ||
                sl_hash_parse(hex, &o->hash))
                return -1;
            o->size = size;
        }
    }
    return complete && have_key && have_digest ? 0 : -1;
}

int sl_record_verify(const char *record_path, const char *dir, const sl_hash *key,
                     sl_record *out, sl_error *err)
{
    char *text = NULL;
    size_t size = 0;
    sl_error read_err;
    sl_error_init(&read_err);
    if (sl_read_file(record_path, 1 << 20, &text, &size, &read_err))
        return sl_error_set(err, SL_E_CORRUPT, read_err.sys_errno, record_path, "no record");
    sl_record *r = calloc(1, sizeof *r);
    int rc = 0;
    if (!r) {
        free(text);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, record_path, "out of memory");
    }
    if (parse_record(text, r) != 0)
        rc = sl_error_set(err, SL_E_CORRUPT, 0, record_path, "record does not parse");
    else if (key && !sl_hash_equal(*key, r->key))
        rc = sl_error_set(err, SL_E_CORRUPT, 0, record_path, "record is for another key");
    else if (!sl_hash_equal(digest_outputs(r), r->outputs_digest))
        rc = sl_error_set(err, SL_E_CORRUPT, 0, record_path, "record digest mismatch");
    for (int i = 0; rc == 0 && i < r->output_count; i++) {
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/%s", dir, r->outputs[i].name);
        sl_hash h;
        uint64_t bytes = 0;
        sl_error hash_err;
        sl_error_init(&hash_err);
        if (sl_hash_file(path, &h, &bytes, &hash_err) != 0)
            rc = sl_error_set(err, SL_E_CORRUPT, hash_err.sys_errno, path, "output missing");
        else if (bytes != r->outputs[i].size || !sl_hash_equal(h, r->outputs[i].hash))
            rc = sl_error_set(err, SL_E_CORRUPT, 0, path, "output does not match its record");
    }
    if (rc == 0 && out)
        *out = *r;
    free(r);
    free(text);
    return rc;
}

int sl_record_read(const char *record_path, sl_record *out, sl_error *err)
{
    char *text = NULL;
    size_t size = 0;
    int rc = sl_read_file(record_path, 1 << 20, &text, &size, err);
    if (rc)
        return rc;
    memset(out, 0, sizeof *out);
    if (parse_record(text, out) != 0)
        rc = sl_error_set(err, SL_E_CORRUPT, 0, record_path, "record does not parse");
    free(text);
    return rc;
}

/* "_verified" beside the record (a "_" file: part of no record); 0, or -1 when the path
 * does not fit. */
static int cache_path_of(const char *record_path, char *buf, size_t size)
{
    const char *slash = strrchr(record_path, '/');
    int dir_len = slash ? (int)(slash - record_path) : 1;
    int n = snprintf(buf, size, "%.*s/_verified", dir_len, slash ? record_path : ".");
    return n < 0 || (size_t)n >= size ? -1 : 0;
}

/* The identities of the record and its outputs, one line each, in record order; -1 when
 * one of them cannot be stat'ed (missing: the full check says so). */
static int identities(const char *record_path, const char *dir, const sl_record *r, char **text)
{
    size_t cap = (size_t)(r->output_count + 1) * (SL_STAT_IDENTITY_SIZE + 1) + 1, n = 0;
    char *buf = malloc(cap);
    if (!buf)
        return -1;
    for (int i = -1; i < r->output_count; i++) {
        char path[PATH_MAX];
        struct stat st;
        int len = i < 0 ? snprintf(path, sizeof path, "%s", record_path)
                        : snprintf(path, sizeof path, "%s/%s", dir, r->outputs[i].name);
        if (len < 0 || (size_t)len >= sizeof path || stat(path, &st) != 0) {
            free(buf);
            return -1;
        }
        sl_stat_identity(&st, buf + n, SL_STAT_IDENTITY_SIZE);
        n += strlen(buf + n);
        buf[n++] = '\n';
    }
    buf[n] = '\0';
    *text = buf;
    return 0;
}

int sl_record_check(const char *record_path, const char *dir, const sl_hash *key,
                    sl_record *out, sl_error *err)
{
    char cache[PATH_MAX];
    sl_record *r = malloc(sizeof *r);
    if (!r)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, record_path, "out of memory");
    sl_error ignored;
    sl_error_init(&ignored);
    char *now = NULL, *seen = NULL;
    size_t seen_size = 0;
    int fast = cache_path_of(record_path, cache, sizeof cache) == 0 &&
               sl_record_read(record_path, r, &ignored) == 0 &&
               (!key || sl_hash_equal(*key, r->key)) &&
               sl_hash_equal(digest_outputs(r), r->outputs_digest) &&
               identities(record_path, dir, r, &now) == 0 &&
               sl_read_file(cache, 1 << 20, &seen, &seen_size, &ignored) == 0 &&
               strcmp(now, seen) == 0;
    free(seen);
    int rc = 0;
    if (!fast) {
        rc = sl_record_verify(record_path, dir, key, r, err);
        free(now);
        now = NULL;
        /* What matched now is vouched for until it changes; a cache that cannot be
         * written costs a full check next time, never the item. */
        if (rc == 0 && identities(record_path, dir, r, &now) == 0) {
            sl_error werr;
            sl_error_init(&werr);
            sl_write_file_atomic(cache, now, strlen(now), &werr);
        }
    }
    if (rc == 0 && out)
        *out = *r;
    free(now);
    free(r);
    return rc;
}
