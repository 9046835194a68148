/* Writing text from names the user chose (item ids from file paths, level names from the
 * config) into the Markdown summaries, so a `|`, `]`, `<` or newline in a name cannot
 * break a table, an image or the page. */
#ifndef SCANLOD_CORE_MARKDOWN_H
#define SCANLOD_CORE_MARKDOWN_H

#include <stdio.h>

/* `s` as literal text in a heading, table cell or image text: the characters that can
 * start emphasis, code, links, HTML or a cell (\ ` * _ [ ] < > | ~) backslash-escaped,
 * line breaks as spaces. */
void sl_md_text(FILE *out, const char *s);
/* `s` as a link destination written inside <...>: `<`, `>` and `\` escaped, line breaks
 * and other control characters percent-encoded. */
void sl_md_link(FILE *out, const char *s);

#endif
