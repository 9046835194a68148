/* The engineering figures of the item's pages, folded under <details> (export_html.h):
 * per level the ladder's rung, the octree's expansions k, counts, the errors as shares of
 * the diagonal, watertightness, the Voyager qualities and every file; and the item's
 * other files. What a curator needs is above them (export_html_parts.c). */
#include <stdio.h>
#include <string.h>

#include "core/html.h"
#include "stages/export/export_html.h"

static const char *const level_exts[4] = {"glb", "ply", "obj", "png"};

static void level_files(FILE *out, const sl_html_page *p, int i)
{
    const char *name = p->it->c->levels[i].name;
    for (int e = 0; e < 4; e++) {
        uint64_t bytes = sl_export_file_bytes(p->it->io, name, level_exts[e]);
        if (!bytes)
            continue;
        char file[64];
        snprintf(file, sizeof file, "%s.%s", name, level_exts[e]);
        sl_html_link(out, p->prefix, file, file);
        fputs(" (", out);
        sl_html_size(out, bytes);
        fputs(") ", out);
    }
}

/* One row: the rung (LOD % or budget), k, counts, errors, watertight, quality, files. */
static void level_row(FILE *out, const sl_html_page *p, int i)
{
    const sl_export_item *it = p->it;
    const sl_export_level *lv = &it->c->levels[i];
    const sl_export_result *w = &it->results[i];
    fputs("<tr><td>", out);
    sl_html_text(out, lv->name);
    fputs("</td><td>", out);
    sl_html_text(out, lv->method);
    fputs("</td><td class=\"n\">", out);
    if (lv->by_percent)
        fprintf(out, "%g", lv->percent);
    else
        fputs("–", out);
    fputs("</td><td class=\"n\">", out);
    if (!lv->by_percent)
        sl_html_grouped(out, lv->budget);
    else
        fputs("–", out);
    if (!strcmp(lv->method, "octree"))
        fprintf(out, "</td><td class=\"n\">%u</td><td class=\"n\">", w->k);
    else /* not an octree cut: no expansions */
        fputs("</td><td class=\"n\">–</td><td class=\"n\">", out);
    sl_html_grouped(out, w->triangles);
    fputs("</td><td class=\"n\">", out);
    sl_html_grouped(out, w->vertices);
    if (w->measured)
        fprintf(out, "</td><td class=\"n\">%.3f %%</td><td class=\"n\">%.3f %%", 100 * w->rms,
                100 * w->hausdorff);
    else
        fputs("</td><td class=\"n\">–</td><td class=\"n\">–", out);
    fprintf(out, "</td><td>%s</td><td>", w->watertight ? "yes" : "no");
    if (w->file >= 0)
        sl_html_qualities(out, it, w->file, "–");
    else
        fputs("–", out);
    fputs("</td><td class=\"files\">", out);
    if (w->file == i)
        level_files(out, p, i);
    else if (w->file >= 0) {
        fputs("the same mesh as ", out);
        sl_html_text(out, it->c->levels[w->file].name);
        fputs(": its files", out);
    } else
        fputs("none (no triangles)", out);
    fputs("</td></tr>\n", out);
}

/* The methods that made the published levels, in the order first used. */
static void methods_used(FILE *out, const sl_export_config *c)
{
    for (int i = 0; i < c->level_count; i++) {
        int seen = 0;
        for (int j = 0; j < i; j++)
            seen |= !strcmp(c->levels[j].method, c->levels[i].method);
        if (!seen) {
            fputs(i ? ", " : "", out);
            sl_html_text(out, c->levels[i].method);
        }
    }
}

void sl_html_engineering(FILE *out, const sl_html_page *p)
{
    const sl_export_item *it = p->it;
    const sl_level_list *l = it->list;
    fputs("<details class=\"engineering\"><summary>Engineering details: how each level was "
          "made and measured</summary>\n<p>", out);
    if (l->model_expansions) {
        fprintf(out, "LOD model: %u expansions, ", l->model_expansions);
        sl_html_grouped(out, l->model_triangles);
        fputs(" triangles at the finest level; ", out);
    }
    fputs("levels made by ", out);
    methods_used(out, it->c);
    if (it->input) {
        fputs("; input: ", out);
        sl_html_grouped(out, it->input->triangle_count);
        fputs(" triangles", out);
    }
    fprintf(out, "; frame: units %s (%s), up %c (%s).</p>\n", it->frame->units,
            it->frame->units_from, it->frame->up, it->frame->up_from);
    fputs("<p>RMS and Hausdorff: symmetric distances between each level and the input "
          "surface, as shares of the input's bounding-box diagonal (the cards above give them "
          "in millimetres); k: expansions of the octree's LOD array; budget: the triangles "
          "asked for.</p>\n", out);
    fputs("<table>\n<tr><th>level</th><th>made by</th><th class=\"n\">LOD %</th>"
          "<th class=\"n\">budget</th><th class=\"n\">k</th><th class=\"n\">triangles</th>"
          "<th class=\"n\">vertices</th><th class=\"n\">RMS</th><th class=\"n\">Hausdorff</th>"
          "<th>watertight</th><th>Voyager</th><th>files</th></tr>\n",
          out);
    for (int i = 0; i < it->c->level_count; i++)
        level_row(out, p, i);
    fputs("</table>\n", out);
    sl_html_item_files(out, p);
    fputs("</details>\n", out);
}

void sl_html_item_files(FILE *out, const sl_html_page *p)
{
    const char *files[8];
    int n = 0;
    files[n++] = "index.html";
    files[n++] = "report.json";
    files[n++] = "timings.json";
    if (p->manifest)
        files[n++] = "scene.svx.json";
    if (p->it->list->model_expansions)
        files[n++] = "model.slod";
    files[n++] = "summary-item.md";
    if (p->views)
        files[n++] = SL_VIEWER_FILE;
    fputs("<p class=\"files\">Files:", out);
    for (int f = 0; f < n; f++) {
        fputc(' ', out);
        sl_html_link(out, p->prefix, files[f], files[f]);
    }
    if (p->manifest)
        fputs("<br>scene.svx.json: these GLBs as a Smithsonian Voyager scene, one derivative "
              "per quality, with the title and credit.",
              out);
    fputs("</p>\n", out);
}
