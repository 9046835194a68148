/* The collection summary: OUTPUT/summary.json (every published item's report, the
 * quarantined items with their reasons, and the stale ones), OUTPUT/summary.md (per item the export stage's
 * summary-item.md: a Table-1-style table and the thumbnails; then the quarantine list) and
 * OUTPUT/summary.html (the same from each item's summary-item.html, with a 3D view per
 * item: docs/formats.md, "The HTML report"). All are rewritten atomically at the end of
 * every `scanlod run`.
 *
 * An item both published and quarantined is stale: its input changed, the new version was
 * quarantined, and the derivatives of the previous version stay published (a museum's
 * web page keeps working). Every summary says so where the item's levels are shown and in
 * the quarantine list, never listing the item as simply published (docs/engine.md).
 *
 * summary.html runs the viewer bundle from OUTPUT/scanlod-viewer.js, a copy of the first
 * published item's own (every item carries one, so that its folder works alone). */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "core/html.h"
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

/* The "Stale:" note of an item whose new input was quarantined (engine.md, "Stale
 * publications"), in Markdown or HTML. */
static void stale_note(FILE *out, const char *item, const sl_ticket *t, int html)
{
    void (*text)(FILE *, const char *) = html ? sl_html_text : sl_md_text;
    fputs(html ? "<p class=\"stale\"><strong>Stale:</strong> the input of <code>"
               : "> **Stale:** the input of `",
          out);
    text(out, item);
    fprintf(out, html ? "</code> changed and its new version was quarantined (%s): "
                      : "` changed and its new version was quarantined (%s): ",
            t->cls);
    text(out, t->reason);
    fputs(html ? ". The levels below are the previous version's.</p>\n"
               : "\n>\n> The levels below are the previous version's.\n\n",
          out);
}

/* An item's section of summary.md or .html (the export's summary-item.*), with the stale
 * note after its heading (the text up to the first `heading_end`); a stand-in heading
 * when the item has no section. */
static void put_section(FILE *out, const char *section, const char *heading_end,
                        const char *item, const sl_ticket *stale, int html)
{
    const char *rest = section;
    if (section && (rest = strstr(section, heading_end)))
        rest += strlen(heading_end);
    if (section && rest)
        fwrite(section, 1, (size_t)(rest - section), out);
    else {
        fputs(html ? "<section class=\"item\">\n<h2>" : "### ", out);
        (html ? sl_html_text : sl_md_text)(out, item);
        fputs(html ? "</h2>\n" : "\n\n", out);
        rest = NULL;
    }
    if (stale)
        stale_note(out, item, stale, html);
    if (rest)
        fputs(rest, out);
    else
        fputs(html ? "<p>(no levels)</p>\n</section>\n" : "(no levels)\n\n", out);
}

#define VIEWER_FILE "scanlod-viewer.js" /* stages/export/export_html.c */

static void html_begin(sl_engine *e, FILE *out)
{
    sl_html_page_begin(out, "scanlod collection summary");
    fprintf(out, "<h1>scanlod collection summary</h1>\n<p>%llu items in <code>",
            (unsigned long long)e->item_count);
    sl_html_text(out, e->input);
    fputs("</code>.</p>\n<p>Per item: its title, accession number, credit and licence from "
          "the collection manifest, and its levels for the web as Smithsonian Voyager names "
          "them (Thumb to Highest), each with its triangles, file size and largest distance "
          "from the scan in millimetres. Click a picture to turn the item in 3D; its title "
          "opens its own page. Every figure per level: <code>ITEM/report.json</code>.</p>\n",
          out);
    sl_engine_manifest_note(e, out);
    fputs("<h2>Items</h2>\n", out);
}

/* OUTPUT/scanlod-viewer.js from the first published item that has one; 0 when none has. */
static int copy_viewer(sl_engine *e, sl_error *err)
{
    for (uint64_t i = 0; i < e->item_count; i++) {
        char from[PATH_MAX], to[PATH_MAX];
        sl_engine_path(from, sizeof from, "%s/%s/" VIEWER_FILE, e->output, e->items[i]);
        if (access(from, R_OK) != 0)
            continue;
        sl_engine_path(to, sizeof to, "%s/" VIEWER_FILE, e->output);
        int rc = sl_copy_file(from, to, err);
        return rc ? rc : 1;
    }
    return 0;
}

/* Each published item's report into `js`'s "items", its sections into the Markdown and
 * the HTML page; returns how many were published. */
static uint64_t summary_items(sl_engine *e, FILE *out, FILE *page, sl_json *js)
{
    uint64_t published = 0;
    sl_json_array_begin(js, "items");
    for (uint64_t i = 0; i < e->item_count; i++) {
        char path[PATH_MAX];
        sl_engine_path(path, sizeof path, "%s/%s/report.json", e->output, e->items[i]);
        char *report = read_optional(path);
        if (!report)
            continue;
        published++;
        sl_json_raw(js, NULL, report);
        free(report);
        sl_ticket t;
        int stale = quarantined(e, e->items[i], &t);
        sl_engine_path(path, sizeof path, "%s/%s/summary-item.md", e->output, e->items[i]);
        char *section = read_optional(path);
        put_section(out, section, "\n", e->items[i], stale ? &t : NULL, 0);
        free(section);
        sl_engine_path(path, sizeof path, "%s/%s/summary-item.html", e->output, e->items[i]);
        section = read_optional(path);
        put_section(page, section, "</h2>\n", e->items[i], stale ? &t : NULL, 1);
        free(section);
    }
    sl_json_array_end(js);
    if (!published) {
        fprintf(out, "None published.\n\n");
        fputs("<p>None published.</p>\n", page);
    }
    return published;
}

/* The quarantined items, each with its class and reason, in all three; *stale counts
 * those whose previous version stays published. Returns how many there are. */
static uint64_t summary_quarantined(sl_engine *e, FILE *out, FILE *page, sl_json *js,
                                    uint64_t *stale)
{
    fprintf(out, "## Quarantined\n\n");
    fputs("<h2>Quarantined</h2>\n<ul>\n", page);
    sl_json_array_begin(js, "quarantined");
    uint64_t bad = 0;
    *stale = 0;
    for (uint64_t i = 0; i < e->item_count; i++) {
        sl_ticket t;
        if (!quarantined(e, e->items[i], &t))
            continue;
        bad++;
        int previous = sl_engine_item_published(e, e->items[i]);
        *stale += (uint64_t)previous;
        const char *kept = previous ? "; the previous version's levels stay published, "
                                      "marked stale"
                                    : "";
        fputs("- ", out);
        sl_md_text(out, e->items[i]);
        fprintf(out, " (%s): ", t.cls);
        sl_md_text(out, t.reason);
        fprintf(out, "%s\n", kept);
        fputs("<li>", page);
        sl_html_text(page, e->items[i]);
        fprintf(page, " (%s): ", t.cls);
        sl_html_text(page, t.reason);
        fprintf(page, "%s</li>\n", kept);
        sl_json_object_begin(js, NULL);
        sl_json_string(js, "item", e->items[i]);
        sl_json_string(js, "class", t.cls);
        sl_json_string(js, "reason", t.reason);
        sl_json_raw(js, "stale_publication", previous ? "true" : "false");
        sl_json_object_end(js);
    }
    if (!bad)
        fprintf(out, "None.\n");
    fputs(bad ? "</ul>\n" : "<li>None.</li>\n</ul>\n", page);
    sl_json_array_end(js);
    return bad;
}

/* summary.json, summary.md and summary.html, each written whole. */
static int summary_write(sl_engine *e, const sl_json *js, const char *md, size_t md_size,
                         const char *html, size_t html_size, sl_error *err)
{
    char path[PATH_MAX];
    int rc = 0;
    if (js->failed || !md || !html)
        rc = sl_error_nomem(err, NULL, "out of memory");
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/summary.json", e->output) == 0)
        rc = sl_write_file_atomic(path, js->buf, js->len, err);
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/summary.md", e->output) == 0)
        rc = sl_write_file_atomic(path, md, md_size, err);
    if (rc == 0 && sl_engine_path(path, sizeof path, "%s/summary.html", e->output) == 0)
        rc = sl_write_file_atomic(path, html, html_size, err);
    return rc;
}

int sl_engine_write_summary(sl_engine *e, sl_error *err)
{
    sl_json js;
    sl_json_init(&js, 1);
    char *md = NULL, *html = NULL;
    size_t md_size = 0, html_size = 0;
    FILE *out = open_memstream(&md, &md_size);
    FILE *page = out ? open_memstream(&html, &html_size) : NULL;
    if (!page) {
        if (out)
            fclose(out);
        free(md);
        return sl_error_nomem(err, NULL, "out of memory");
    }
    html_begin(e, page);
    fprintf(out, "# scanlod collection summary\n\n%llu items in `%s`.\n\n",
            (unsigned long long)e->item_count, e->input);
    fprintf(out, "Per item, its levels (k = expansions of the octree's LOD array; RMS and "
                 "Hausdorff distance to the input in %% of its bounding-box diagonal, "
                 "symmetric) and their thumbnails. Everything per level: "
                 "`ITEM/report.json`; timings and memory: `ITEM/timings.json`.\n\n"
                 "## Items\n\n");
    sl_json_object_begin(&js, NULL);
    uint64_t published = summary_items(e, out, page, &js), stale;
    uint64_t bad = summary_quarantined(e, out, page, &js, &stale);
    sl_json_u64(&js, "items_total", e->item_count);
    sl_json_u64(&js, "items_published", published);
    sl_json_u64(&js, "items_quarantined", bad);
    sl_json_u64(&js, "items_stale", stale);
    sl_engine_manifest_summary(e, &js);
    sl_json_object_end(&js);
    fclose(out);
    int viewer = copy_viewer(e, err);
    sl_html_page_end(page, viewer > 0 ? VIEWER_FILE : NULL);
    fclose(page);
    int rc = viewer < 0 ? viewer : summary_write(e, &js, md, md_size, html, html_size, err);
    sl_json_release(&js);
    free(md);
    free(html);
    return rc;
}
