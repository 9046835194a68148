/* Percent-escaping of names that must fit a file name or one line of a text file (ticket
 * names, the item lines of tickets and records): '%' and control characters become %XX
 * (a newline in an input's name must not end a line), plus any byte the caller names. */
#ifndef SCANLOD_CORE_ESCAPE_H
#define SCANLOD_CORE_ESCAPE_H

#include <stddef.h>

/* Escapes `in` into `out` (room for `size` bytes, NUL included): '%', bytes below 0x20 and
 * 0x7f, every `extra` byte (0: none) and a first byte equal to `lead` (0: none). Returns
 * the length, or -1 if it does not fit (out is then unspecified). */
long sl_escape(const char *in, char extra, char lead, char *out, size_t size);

/* Undoes sl_escape in place (a '%' not followed by two hex digits stays as it is). */
void sl_unescape(char *s);

#endif
