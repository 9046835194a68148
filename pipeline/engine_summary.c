/* The collection summary: OUTPUT/summary.json (every published item's report, and the
 * quarantined items with their reasons) and OUTPUT/summary.md (per item the export stage's
 * summary-item.md: a Table-1-style table and the thumbnails; then the quarantine list). Both are
 * rewritten atomically at the end of every `scanlod run`. */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/json.h"
#include "core/log.h"
#include "core/markdown.h"
#include "pipeline/engine_internal.h"

static char *read_optional(const char *path)
{
    char *text = NULL;
    size_t size = 0;
    sl_error err;
    sl_error_init(&err);
    if (sl_read_file(path, 64 << 20, &text, &size, &err) != 0)
        return NULL;
    return text;
}

/* The item's quarantine ticket (any stage), or 0. */
static int quarantined(sl_engine *e, const char *item, sl_ticket *t)
{
    char name[SL_TICKET_NAME_MAX + 1];
    sl_error err;
    sl_error_init(&err);
    if (sl_ticket_name(item, name, sizeof name, &err))
        return 0;
    for (int s = 0; s < e->stage_count; s++) {
        if (sl_queue_get(e->work, e->stages[s]->name, SL_STATE_QUARANTINE, name, t) == 0)
            return 1;
    }
    return 0;
}

int sl_engine_write_summary(sl_engine *e, sl_error *err)
{
    sl_json js;
    sl_json_init(&js, 1);
    char *md = NULL;
    size_t md_size = 0;
    FILE *out = open_memstream(&md, &md_size);
    if (!out)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory");
    fprintf(out, "# scanlod collection summary\n\n%llu items in `%s`.\n\n",
            (unsigned long long)e->item_count, e->input);
    fprintf(out, "Per item, its levels as in Table 1 of the paper (k = expansions of the LOD "
                 "array; RMS and Hausdorff distance to the input in %% of its bounding-box "
                 "diagonal, symmetric) and their thumbnails. Everything per level: "
                 "`ITEM/report.json`; timings and memory: `ITEM/timings.json`.\n\n"
                 "## Items\n\n");
    sl_json_object_begin(&js, NULL);
    sl_json_array_begin(&js, "items");
    uint64_t published = 0;
    for (uint64_t i = 0; i < e->item_count; i++) {
        char path[PATH_MAX];
        sl_engine_path(path, sizeof path, "%s/%s/report.json", e->output, e->items[i]);
        char *report = read_optional(path);
        if (!report)
            continue;
        published++;
        sl_json_raw(&js, NULL, report);
        free(report);
        sl_engine_path(path, sizeof path, "%s/%s/summary-item.md", e->output, e->items[i]);
        char *section = read_optional(path);
        if (section)
            fputs(section, out);
        else {
            fputs("### ", out);
            sl_md_text(out, e->items[i]);
            fputs("\n\n(no levels)\n\n", out);
        }
        free(section);
    }
    sl_json_array_end(&js);
    if (!published)
        fprintf(out, "None published.\n\n");
    fprintf(out, "## Quarantined\n\n");
    sl_json_array_begin(&js, "quarantined");
    uint64_t bad = 0;
    for (uint64_t i = 0; i < e->item_count; i++) {
        sl_ticket t;
        if (!quarantined(e, e->items[i], &t))
            continue;
        bad++;
        fputs("- ", out);
        sl_md_text(out, e->items[i]);
        fprintf(out, " (%s): ", t.cls);
        sl_md_text(out, t.reason);
        fputc('\n', out);
        sl_json_object_begin(&js, NULL);
        sl_json_string(&js, "item", e->items[i]);
        sl_json_string(&js, "class", t.cls);
        sl_json_string(&js, "reason", t.reason);
        sl_json_object_end(&js);
    }
    if (!bad)
        fprintf(out, "None.\n");
    sl_json_array_end(&js);
    sl_json_u64(&js, "items_total", e->item_count);
    sl_json_u64(&js, "items_published", published);
    sl_json_u64(&js, "items_quarantined", bad);
    sl_json_object_end(&js);
    fclose(out);
    char path[PATH_MAX];
    int rc = js.failed ? sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory") : 0;
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/summary.json", e->output) == 0)
        rc = sl_write_file_atomic(path, js.buf, js.len, err);
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/summary.md", e->output) == 0)
        rc = sl_write_file_atomic(path, md, md_size, err);
    sl_json_release(&js);
    free(md);
    return rc;
}
