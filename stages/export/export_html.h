/* The parts the item's pages are made of (export_html_parts.c), shared by index.html and
 * summary-item.html (export_html.c). */
#ifndef SCANLOD_STAGES_EXPORT_HTML_H
#define SCANLOD_STAGES_EXPORT_HTML_H

#include <stdio.h>

#include "stages/export/export_internal.h"

#define SL_VIEWER_FILE "scanlod-viewer.js"

/* One page: the item, and where its files are from the page (`prefix`, URL-encoded: ""
 * on index.html, "ITEM/" on the summary). */
typedef struct sl_html_page {
    const sl_export_item *it;
    const char *prefix;
    int views;     /* the viewer and the GLB scripts are there */
    int manifest;  /* scene.svx.json is there */
    int summary;   /* the collection page's section, not the item's own page */
} sl_html_page;

/* 30437 -> "30,437"; bytes as "41 kB"; a length in mm with a sensible precision. */
void sl_html_grouped(FILE *out, uint64_t n);
void sl_html_size(FILE *out, uint64_t bytes);
void sl_html_mm(FILE *out, double mm);
/* <a href="PREFIX+FILE">TEXT</a>. */
void sl_html_link(FILE *out, const char *prefix, const char *file, const char *text);

/* The curator's header: accession number and file, credit and licence, description, and
 * the frame (a warning when it was estimated). The title is the caller's. */
void sl_html_item_head(FILE *out, const sl_html_page *p);
/* The published levels, coarsest first, as labelled thumbnails: quality, triangles, GLB
 * size, error in mm. With views, each is a button that loads its level into the view. */
void sl_html_level_cards(FILE *out, const sl_html_page *p);
/* The engineering figures (the ladder, k, bounds, methods, every file) in a <details>. */
void sl_html_engineering(FILE *out, const sl_html_page *p);
/* The item's files that are not a level's. */
void sl_html_item_files(FILE *out, const sl_html_page *p);

/* The Voyager qualities published level i serves ("Medium, High"), or `none`. */
void sl_html_qualities(FILE *out, const sl_export_item *it, int i, const char *none);

/* The published levels, coarsest first (file == own index); their count. */
int sl_html_published(const sl_export_item *it, int order[SL_EXPORT_MAX_LEVELS]);

#endif
