/* The parts of the item's pages (export_html.h): what a curator reads first (title,
 * accession number, credit, licence, description, how the model is oriented and scaled),
 * the levels as labelled thumbnails with their error in millimetres, and the engineering
 * figures folded away. docs/formats.md, "The HTML report". */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/html.h"
#include "stages/export/export_html.h"

void sl_html_grouped(FILE *out, uint64_t n)
{
    char digits[32];
    int len = snprintf(digits, sizeof digits, "%llu", (unsigned long long)n);
    for (int i = 0; i < len; i++) {
        if (i && (len - i) % 3 == 0)
            fputc(',', out);
        fputc(digits[i], out);
    }
}

void sl_html_size(FILE *out, uint64_t bytes)
{
    if (bytes < 10000)
        fprintf(out, "%llu B", (unsigned long long)bytes);
    else if (bytes < 1000000)
        fprintf(out, "%.0f kB", bytes / 1e3);
    else
        fprintf(out, "%.1f MB", bytes / 1e6);
}

/* Three significant digits at most, never a bare exponent: 0.00042, 0.84, 12.3, 415. */
void sl_html_mm(FILE *out, double mm)
{
    fprintf(out, mm >= 100 ? "%.0f mm" : mm >= 10 ? "%.1f mm" : mm >= 0.01 ? "%.2f mm"
                 : "%.2g mm", mm);
}

void sl_html_link(FILE *out, const char *prefix, const char *file, const char *text)
{
    fprintf(out, "<a href=\"%s", prefix);
    sl_html_url(out, file);
    fputs("\">", out);
    sl_html_text(out, text);
    fputs("</a>", out);
}

static int by_triangles(const sl_export_item *it, int a, int b)
{
    uint64_t x = it->results[a].triangles, y = it->results[b].triangles;
    return x != y ? (x > y) - (x < y) : (a > b) - (a < b);
}

int sl_html_published(const sl_export_item *it, int order[SL_EXPORT_MAX_LEVELS])
{
    int n = 0;
    for (int i = 0; i < it->c->level_count; i++) {
        if (it->results[i].file != i)
            continue;
        int at = n++;
        for (; at > 0 && by_triangles(it, order[at - 1], i) > 0; at--)
            order[at] = order[at - 1];
        order[at] = i;
    }
    return n;
}

static const char *source_words(const char *from)
{
    return !strcmp(from, "manifest") ? "the collection manifest"
           : !strcmp(from, "config") ? "the collection's config" : "the file itself";
}

static const char *unit_words(const char *units)
{
    static const char *const names[][2] = {{"mm", "millimetres"}, {"cm", "centimetres"},
                                           {"m", "metres"}, {"in", "inches"}, {"ft", "feet"}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(units, names[i][0]))
            return names[i][1];
    return units;
}

/* How the model is oriented and scaled, and on what authority; an estimate is a warning. */
static void frame_note(FILE *out, const sl_html_page *p)
{
    const sl_export_frame *f = p->it->frame;
    int guessed_units = !strcmp(f->units_from, "estimated");
    int guessed_up = !strcmp(f->up_from, "estimated");
    if (!guessed_units && !guessed_up) {
        fprintf(out, "<p class=\"frame\">Shown with %c up, in %s (up from %s, units from "
                     "%s).</p>\n", f->up, unit_words(f->units), source_words(f->up_from),
                source_words(f->units_from));
        return;
    }
    fputs("<p class=\"frame estimated\"><strong>Frame estimated</strong> (no manifest row, "
          "config or file said it): ", out);
    if (guessed_up) {
        fprintf(out, "%c up, because ", f->up);
        sl_html_text(out, f->up_why);
        fputs(guessed_units ? "; " : ". ", out);
    } else {
        fprintf(out, "%c up (from %s); ", f->up, source_words(f->up_from));
    }
    if (guessed_units) {
        fprintf(out, "%s, because ", unit_words(f->units));
        sl_html_text(out, f->units_why);
        fputs(". The model's scale and the errors in millimetres rest on this guess", out);
    } else {
        fprintf(out, "%s (from %s)", unit_words(f->units), source_words(f->units_from));
    }
    fputs(". Give <code>units</code> and <code>up</code> in the collection manifest to set "
          "them.</p>\n", out);
}

/* The description's lines as paragraphs. */
static void description(FILE *out, const char *text)
{
    fputs("<div class=\"description\">", out);
    while (*text) {
        size_t n = strcspn(text, "\r\n");
        char *line = n ? strndup(text, n) : NULL; /* NULL also when out of memory */
        if (line) {
            fputs("<p>", out);
            sl_html_text(out, line);
            fputs("</p>", out);
        }
        free(line);
        text += n + strspn(text + n, "\r\n");
    }
    fputs("</div>\n", out);
}

void sl_html_item_head(FILE *out, const sl_html_page *p)
{
    const sl_item_metadata *m = p->it->io->metadata;
    fputs("<p class=\"ids\">", out);
    if (m && m->accession[0]) {
        fputs("Accession number <strong class=\"accession\">", out);
        sl_html_text(out, m->accession);
        fputs("</strong> · ", out);
    }
    fputs("file <code>", out);
    sl_html_text(out, p->it->io->item);
    fputs("</code></p>\n", out);
    if (m && (m->credit[0] || m->licence[0])) {
        fputs("<p class=\"credit\">", out);
        if (m->credit[0]) {
            fputs("Credit: <span class=\"credit-line\">", out);
            sl_html_text(out, m->credit);
            fputs(m->licence[0] ? "</span> · " : "</span>", out);
        }
        if (m->licence[0]) {
            fputs("Licence: <span class=\"licence\">", out);
            sl_html_text(out, m->licence);
            fputs("</span>", out);
        }
        fputs("</p>\n", out);
    } else {
        fputs("<p class=\"credit note\">No credit or licence given (the collection manifest "
              "has none for this item).</p>\n", out);
    }
    if (m && m->description[0] && !p->summary)
        description(out, m->description);
    frame_note(out, p);
}

void sl_html_qualities(FILE *out, const sl_export_item *it, int i, const char *none)
{
    int any = 0;
    for (int q = 0; q < SL_EXPORT_QUALITIES; q++)
        if (it->quality[q] == i) {
            fputs(any++ ? ", " : "", out);
            fputs(sl_export_quality_names[q], out);
        }
    if (!any)
        sl_html_text(out, none);
}

/* The Voyager qualities level i serves ("Medium, High"), or its name when none. */
static void level_label(FILE *out, const sl_export_item *it, int i)
{
    sl_html_qualities(out, it, i, it->c->levels[i].name);
}

/* The level's measured error in millimetres: a fraction of the diagonal, times the
 * diagonal in the item's units, in metres, in mm. */
static void level_error(FILE *out, const sl_export_item *it, int i)
{
    const sl_export_result *w = &it->results[i];
    if (it->c->levels[i].scan) {
        fputs("the scan itself", out);
        return;
    }
    if (!w->measured) {
        fputs("error not measured", out);
        return;
    }
    double mm = 1000 * w->diagonal * it->frame->to_metres;
    fputs("max error ", out);
    sl_html_mm(out, w->hausdorff * mm);
    fputs(" · RMS ", out);
    sl_html_mm(out, w->rms * mm);
}

static void level_card(FILE *out, const sl_html_page *p, int i, int shown)
{
    const sl_export_item *it = p->it;
    const char *name = it->c->levels[i].name;
    if (p->views) {
        fprintf(out, "<button type=\"button\" class=\"level%s\" data-src=\"%s",
                i == shown ? " on" : "", p->prefix);
        sl_html_url(out, name);
        fputs(".glb.js\">", out);
    } else {
        fputs("<div class=\"level\">", out);
    }
    if (sl_export_file_bytes(it->io, name, "png")) {
        fprintf(out, "<img src=\"%s", p->prefix);
        sl_html_url(out, name);
        fputs(".png\" width=\"128\" height=\"128\" alt=\"", out);
        sl_html_text(out, sl_export_title(it->io));
        fputs(", ", out);
        level_label(out, it, i);
        fputs("\">", out);
    }
    fputs("<span class=\"q\">", out);
    level_label(out, it, i);
    fputs("</span><span class=\"n\">", out);
    sl_html_grouped(out, it->results[i].triangles);
    fputs(" triangles", out);
    uint64_t glb = sl_export_file_bytes(it->io, name, "glb");
    if (glb) {
        fputs(" · ", out);
        sl_html_size(out, glb);
    }
    if (it->results[i].morph_to >= 0) { /* viewer.js blends by camera distance */
        fputs(" · blends into ", out);
        sl_html_text(out, it->c->levels[it->results[i].morph_to].name);
        fputs(" as you zoom out", out);
    }
    fputs("</span><span class=\"e\">", out);
    level_error(out, it, i);
    if (it->results[i].texture < 0) /* a textured scan published untextured: say so here */
        fputs("</span><span class=\"w\">no texture: too many triangles for an atlas, "
              "vertex colours only", out);
    fputs(p->views ? "</span></button>\n" : "</span></div>\n", out);
}

void sl_html_level_cards(FILE *out, const sl_html_page *p)
{
    int order[SL_EXPORT_MAX_LEVELS];
    int n = sl_html_published(p->it, order);
    fputs("<div class=\"levels\">\n", out);
    for (int k = 0; k < n; k++)
        level_card(out, p, order[k], p->it->quality[1]);
    fputs("</div>\n", out);
}
