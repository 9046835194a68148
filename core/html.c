/* HTML escaping and the report pages' frame (see html.h). */
#include "core/html.h"

#include <string.h>

void sl_html_text(FILE *out, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        switch (c) {
        case '&': fputs("&amp;", out); break;
        case '<': fputs("&lt;", out); break;
        case '>': fputs("&gt;", out); break;
        case '"': fputs("&quot;", out); break;
        case '\'': fputs("&#39;", out); break;
        default: fputc(c < 0x20 || c == 0x7f ? ' ' : c, out);
        }
    }
}

void sl_html_url(FILE *out, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
            (c && strchr("-._~/", c)))
            fputc(c, out);
        else
            fprintf(out, "%%%02X", c);
    }
}

/* Light, print-friendly, no web fonts: nothing to fetch. The view background matches the
 * thumbnails' light grey. */
static const char style[] =
    "body{font:15px/1.45 system-ui,sans-serif;margin:1.5em auto;max-width:84em;padding:0 1em;"
    "color:#222;background:#fff}\n"
    "h1{font-size:1.6em}h2{font-size:1.3em;margin-top:2em;border-bottom:1px solid #ccc}\n"
    "table{border-collapse:collapse;margin:.8em 0}th,td{padding:.2em .6em;border-bottom:1px "
    "solid #e4e4e4;text-align:left}td.n,th.n{text-align:right;white-space:nowrap;"
    "font-variant-numeric:tabular-nums}\n"
    "code{font-size:.92em}.files{font-size:.92em}.files a{margin-right:.7em;white-space:nowrap}\n"
    "figure.sl-view{margin:.6em 0;display:flex;flex-wrap:wrap;gap:1em;align-items:flex-start}\n"
    "figure.sl-view canvas{width:320px;height:320px;display:block;background:#f0f0f0 "
    "center/contain no-repeat;border:1px solid #ddd;cursor:grab;touch-action:none}\n"
    "figure.sl-main{display:block}figure.sl-main canvas{width:100%;height:min(62vh,640px)}\n"
    "figure.sl-view figcaption{flex:1;min-width:16em;font-size:.9em}\n"
    ".hint{color:#555;margin:.3em 0}\n"
    ".levels{display:flex;flex-wrap:wrap;gap:.6em;margin:.4em 0}\n"
    ".level{display:flex;flex-direction:column;width:146px;padding:.4em;border:1px solid #ccc;"
    "border-radius:4px;background:#fff;font:inherit;font-size:.85em;text-align:left;"
    "color:inherit}\n"
    "button.level{cursor:pointer}button.level:hover{border-color:#888}\n"
    "button.level.on{border-color:#1a6e3a;box-shadow:0 0 0 2px #1a6e3a inset}\n"
    ".level img{width:128px;height:128px;margin-bottom:.3em;background:#f0f0f0}\n"
    ".level .q{font-weight:bold;font-size:1.1em}.level .e{color:#333}\n"
    ".level .w{color:#8a5a00}\n"
    ".ids{margin:.2em 0}.credit{color:#444;margin:.2em 0}.description p{margin:.4em 0;"
    "max-width:48em}\n"
    ".frame{font-size:.92em;color:#444}\n"
    ".frame.estimated{background:#fff3cd;border-left:4px solid #d9a400;padding:.4em .8em;"
    "color:#222}\n"
    "details.engineering{margin:1.2em 0;font-size:.92em}details.engineering summary"
    "{cursor:pointer;color:#555}\n"
    ".sl-error{color:#a00}.note{color:#555;font-size:.92em}\n"
    ".stale{background:#fff3cd;border-left:4px solid #d9a400;padding:.4em .8em}\n";

void sl_html_page_begin(FILE *out, const char *title)
{
    fputs("<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
          "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>",
          out);
    sl_html_text(out, title);
    fprintf(out, "</title>\n<link rel=\"icon\" href=\"data:,\">\n<style>\n%s</style>\n"
                 "</head>\n<body>\n",
            style);
}

void sl_html_page_end(FILE *out, const char *viewer_src)
{
    if (viewer_src)
        fprintf(out, "<script src=\"%s\"></script>\n", viewer_src);
    fputs("</body>\n</html>\n", out);
}
