/* Markdown escaping for the summaries (see markdown.h). */
#include "core/markdown.h"

#include <string.h>

void sl_md_text(FILE *out, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '\n' || c == '\r')
            fputc(' ', out);
        else {
            if (strchr("\\`*_[]<>|~", c))
                fputc('\\', out);
            fputc(c, out);
        }
    }
}

void sl_md_link(FILE *out, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c < 0x20 || c == 0x7f)
            fprintf(out, "%%%02X", c);
        else {
            if (c == '<' || c == '>' || c == '\\')
                fputc('\\', out);
            fputc(c, out);
        }
    }
}
