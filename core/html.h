/* Writing the HTML reports (OUTPUT/summary.html, OUTPUT/ITEM/index.html: docs/formats.md,
 * "The HTML report") from names the user chose (item ids from file paths, level names
 * from the config), so that no name can break the page, inject markup or turn a link
 * into another scheme. The pages' head (style sheet included: the pages fetch nothing)
 * and end are written here once, for both pages. */
#ifndef SCANLOD_CORE_HTML_H
#define SCANLOD_CORE_HTML_H

#include <stdio.h>

/* `s` as text or as a quoted attribute value: & < > " ' as character references, line
 * breaks and other control characters as spaces. */
void sl_html_text(FILE *out, const char *s);
/* `s` (a relative path: '/' separates folders) as an href/src value: every byte but
 * ASCII letters, digits, '-', '.', '_', '~' and '/' percent-encoded, so '%', '#', '?', ':'
 * and spaces in a name stay part of the path. */
void sl_html_url(FILE *out, const char *s);

/* <!doctype html> to <body>: UTF-8, the title (escaped), an empty icon (so browsers do
 * not request /favicon.ico) and the shared style sheet. */
void sl_html_page_begin(FILE *out, const char *title);
/* Closes the page; with `viewer_src` (a relative URL, already encoded) the viewer script
 * is loaded last, after every view it starts. */
void sl_html_page_end(FILE *out, const char *viewer_src);

#endif
