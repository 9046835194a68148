/* Percent-escaping for names in file names and text lines (escape.h). */
#include "core/escape.h"

#include <stdio.h>

static int needs_escape(unsigned char c)
{
    return c == '%' || c < 0x20 || c == 0x7f;
}

long sl_escape(const char *in, char extra, char lead, char *out, size_t size)
{
    size_t n = 0;
    for (const char *p = in; *p; p++) {
        unsigned char c = (unsigned char)*p;
        int esc = needs_escape(c) || (extra && *p == extra) || (lead && p == in && *p == lead);
        if (n + (esc ? 3 : 1) >= size)
            return -1;
        if (esc)
            n += (size_t)snprintf(out + n, 4, "%%%02X", c);
        else
            out[n++] = (char)c;
    }
    if (size == 0)
        return -1;
    out[n] = '\0';
    return (long)n;
}

static int hex_digit(char c)
{
    return c >= '0' && c <= '9' ? c - '0' : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

void sl_unescape(char *s)
{
    char *w = s;
    for (const char *p = s; *p; p++) {
        int hi, lo;
        if (*p == '%' && (hi = hex_digit(p[1])) >= 0 && (lo = hex_digit(p[2])) >= 0) {
            *w++ = (char)(hi * 16 + lo);
            p += 2;
        } else {
            *w++ = *p;
        }
    }
    *w = '\0';
}
