/* Markdown escaping of user-chosen names in the summaries (core/markdown.h): a name
 * with table, link, emphasis or line-break characters stays one literal cell or link. */
#include <stdlib.h>
#include <string.h>

#include "core/markdown.h"
#include "tests/check.h"

static void expect(void (*write)(FILE *, const char *), const char *in, const char *want)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    write(f, in);
    fclose(f);
    CHECK_MSG(strcmp(text, want) == 0, "'%s' -> '%s', expected '%s'", in, text, want);
    free(text);
}

int main(void)
{
    expect(sl_md_text, "armadillo_86kf", "armadillo\\_86kf");
    expect(sl_md_text, "a|b [1] <x> *y* `z` ~w\\", "a\\|b \\[1\\] \\<x\\> \\*y\\* \\`z\\` \\~w\\\\");
    expect(sl_md_text, "two\nlines\r", "two lines ");
    expect(sl_md_text, "plain name.v2 (copy) #3", "plain name.v2 (copy) #3");
    expect(sl_md_link, "dir/scan one.ply", "dir/scan one.ply");
    expect(sl_md_link, "a<b>c\\d", "a\\<b\\>c\\\\d");
    expect(sl_md_link, "line\nbreak\x7f", "line%0Abreak%7F");
    return check_report();
}
