/* The collection manifest in the engine (docs/metadata.md; docs/engine.md, "Item
 * metadata"): read once per run when the engine opens, before any work, so a malformed
 * one stops the run with exit 78 like a bad config key; each item's row reaches the stages
 * that declare `reads_metadata` (sl_stage_io.metadata), whose key hashes the row. A row
 * naming no item of the input tree is a warning in the log and the summaries. */
#include "pipeline/engine_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/html.h"
#include "core/json.h"
#include "core/log.h"
#include "pipeline/manifest.h"

static int is_file(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* [run] manifest as a path: "" = manifest.csv or manifest.json at the input's root (or
 * none), "none" = none, else the file (relative to the config file's folder when the
 * file set it, else to the current one). */
static int manifest_path(sl_engine *e, char *path, size_t size, sl_error *err)
{
    const char *value = sl_config_string(e->cfg, "run", "manifest");
    char where[PATH_MAX];
    sl_config_origin_kind kind = sl_config_origin(e->cfg, "run", "manifest", where,
                                                  sizeof where);
    path[0] = '\0';
    if (!strcmp(value, "none"))
        return 0;
    if (!value[0]) {
        char csv[PATH_MAX], json[PATH_MAX];
        sl_engine_path(csv, sizeof csv, "%s/manifest.csv", e->input);
        sl_engine_path(json, sizeof json, "%s/manifest.json", e->input);
        if (is_file(csv) && is_file(json))
            return sl_error_set(err, SL_E_CONFIG, 0, e->input, "both manifest.csv and "
                                "manifest.json are here: keep one, or name the one to use "
                                "with [run] manifest");
        snprintf(path, size, "%s", is_file(csv) ? csv : is_file(json) ? json : "");
        return 0;
    }
    const char *cfg = sl_config_path(e->cfg);
    const char *slash = strrchr(cfg, '/');
    if (value[0] == '/' || kind != SL_CONFIG_FROM_FILE || !slash)
        snprintf(path, size, "%s", value);
    else
        snprintf(path, size, "%.*s/%s", (int)(slash - cfg), cfg, value);
    if (!is_file(path))
        return sl_error_set(err, SL_E_CONFIG, 0, where, "[run] manifest: %s is not a file",
                            path);
    return 0;
}

int sl_engine_manifest_open(sl_engine *e, sl_error *err)
{
    char path[PATH_MAX];
    int rc = manifest_path(e, path, sizeof path, err);
    if (rc || !path[0])
        return rc;
    sl_manifest *m = calloc(1, sizeof *m);
    if (!m)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    rc = sl_manifest_load(m, path, err);
    if (rc == 0 && !(e->manifest_seen = calloc(m->count ? m->count : 1, 1)))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc) {
        sl_manifest_release(m);
        free(m);
        return rc;
    }
    e->manifest = m;
    return 0;
}

void sl_engine_manifest_close(sl_engine *e)
{
    if (e->manifest)
        sl_manifest_release(e->manifest);
    free(e->manifest);
    free(e->manifest_seen);
    e->manifest = NULL;
    e->manifest_seen = NULL;
}

const sl_item_metadata *sl_engine_item_metadata(const sl_engine *e, int s, const char *item)
{
    if (!e->manifest || !e->stages[s]->reads_metadata)
        return NULL;
    const sl_manifest_row *row = sl_manifest_find(e->manifest, item);
    return row ? &row->meta : NULL;
}

uint64_t sl_engine_stage_config_hash(const sl_engine *e, int s, const char *item)
{
    const sl_item_metadata *meta = sl_engine_item_metadata(e, s, item);
    if (!meta) /* no row: the key of a run without a manifest, so adding one for another
                  item reruns nothing here */
        return e->config_hash[s];
    const sl_manifest_row *row = sl_manifest_find(e->manifest, item);
    uint64_t words[3] = {e->config_hash[s], row->hash.hi, row->hash.lo};
    sl_hash h = sl_hash_bytes(words, sizeof words);
    return h.hi ^ h.lo;
}

static int by_text(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

void sl_engine_manifest_check(sl_engine *e)
{
    if (!e->manifest)
        return;
    char **ids = malloc((e->item_count ? e->item_count : 1) * sizeof *ids);
    if (!ids)
        return; /* only a warning is lost */
    memcpy(ids, e->items, e->item_count * sizeof *ids);
    qsort(ids, e->item_count, sizeof *ids, by_text);
    e->counts.manifest_unknown = 0;
    for (size_t i = 0; i < e->manifest->count; i++) {
        const sl_manifest_row *r = &e->manifest->rows[i];
        const char *file = r->field[SL_MF_FILE];
        e->manifest_seen[i] = bsearch(&file, ids, e->item_count, sizeof *ids, by_text) != NULL;
        if (e->manifest_seen[i])
            continue;
        e->counts.manifest_unknown++;
        SL_LOG(SL_LOG_WARN, "scan", file, "%s: the collection manifest has a row for it, but "
               "[run] input has no such item", r->where);
        sl_log_event("manifest_unknown_item", "scan", file, 0, NULL, NULL);
    }
    free(ids);
}

void sl_engine_manifest_summary(const sl_engine *e, sl_json *js)
{
    if (!e->manifest)
        return;
    sl_json_object_begin(js, "manifest");
    sl_json_string(js, "file", e->manifest->path);
    sl_json_u64(js, "rows", e->manifest->count);
    sl_json_array_begin(js, "unknown_items");
    for (size_t i = 0; i < e->manifest->count; i++)
        if (!e->manifest_seen[i])
            sl_json_string(js, NULL, e->manifest->rows[i].field[SL_MF_FILE]);
    sl_json_array_end(js);
    sl_json_object_end(js);
}

void sl_engine_manifest_note(const sl_engine *e, FILE *out)
{
    if (!e->manifest)
        return;
    const char *base = strrchr(e->manifest->path, '/');
    fputs("<p class=\"note\">Metadata: <code>", out);
    sl_html_text(out, base ? base + 1 : e->manifest->path);
    fprintf(out, "</code>, %zu rows.</p>\n", e->manifest->count);
    if (!e->counts.manifest_unknown)
        return;
    fprintf(out, "<p class=\"stale\"><strong>%llu manifest rows name no item</strong> of the "
                 "input (a typo in <code>file</code>, or a scan not there yet):",
            (unsigned long long)e->counts.manifest_unknown);
    for (size_t i = 0; i < e->manifest->count; i++)
        if (!e->manifest_seen[i]) {
            fputs(" <code>", out);
            sl_html_text(out, e->manifest->rows[i].where);
            fputs(" ", out);
            sl_html_text(out, e->manifest->rows[i].field[SL_MF_FILE]);
            fputs("</code>", out);
        }
    fputs("</p>\n", out);
}
