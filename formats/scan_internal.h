/* Internals shared by the scan readers of scan_read.h (not a public interface; the tests
 * may include it): the source a reader works on, its errors, its limits and growth, the
 * text-line cursor of the text formats, and each reader's entry.
 *
 * Every reader works on one contiguous byte range (an mmap of the file, or the caller's
 * buffer) and never reads past `end`; files beside the scan (MTL, glTF buffers) are read
 * through scan_sibling_map, inside `dir` only.
 */
#ifndef SCANLOD_FORMATS_SCAN_INTERNAL_H
#define SCANLOD_FORMATS_SCAN_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "formats/scan_read.h"
#include "formats/text_number.h"

typedef struct scan_src {
    const char *name;              /* the file, for messages */
    const char *dir;               /* where files beside it are, or NULL */
    const unsigned char *data;
    size_t size;
    const sl_scan_limits *lim;
    sl_progress *progress;
    sl_error *err;
} scan_src;

/* Records an error about the source: "NAME: line L: message" (line 0: no line). */
int scan_error(const scan_src *s, int code, uint64_t line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* SL_E_LIMIT when `count` `what`s exceed `limit` (the message names both). */
int scan_check_limit(const scan_src *s, const char *what, uint64_t count, uint64_t limit);

/* malloc of n items of `item` bytes with the product checked (NULL on overflow, n = 0
 * gives a 1-byte block); SL_E_NOMEM recorded about the source on failure. */
void *scan_alloc(const scan_src *s, uint64_t n, size_t item, int *rc);
/* Makes *ptr hold at least `need` items (doubling); 0 or SL_E_NOMEM. */
int scan_reserve(const scan_src *s, void **ptr, uint64_t *cap, uint64_t need, size_t item);

/* Interrupt check and progress ("read", the fraction of the source behind `at`). */
int scan_tick(const scan_src *s, const void *at);

/* ---- text lines ---- */

typedef struct text_cursor {
    const char *p, *end;     /* the rest of the source */
    const char *line, *eol;  /* the current line, without its terminator */
    uint64_t number;         /* its 1-based number */
} text_cursor;

void text_begin(text_cursor *c, const scan_src *s);
/* Moves to the next line (\n, \r\n or \r ends one); 0 at the end of the source. */
int text_next_line(text_cursor *c);

static inline int text_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\v' || c == '\f';
}
/* Skips blanks from p (never past eol). */
static inline const char *text_skip(const char *p, const char *eol)
{
    while (p < eol && text_blank(*p))
        p++;
    return p;
}
/* The end of the token at p (the next blank or eol). */
static inline const char *text_token_end(const char *p, const char *eol)
{
    while (p < eol && !text_blank(*p))
        p++;
    return p;
}
/* Whether the token [p, q) is `word`. */
int text_token_is(const char *p, const char *q, const char *word);

/* One number token at *p (after blanks) of the cursor's current line, into *out: 1 and *p
 * moved past it; 0 when the line has no more tokens; -1 when the next token is not a
 * number. The token ends at a blank or the end of the line; `seps` (may be NULL) names
 * more bytes that end one (the commas of a CSV export), skipped with it. */
int text_float(const text_cursor *c, const char **p, const char *seps, float *out);
int text_double(const text_cursor *c, const char **p, const char *seps, double *out);

/* The rest of the line from p, blanks trimmed at both ends, as [*b, *e). */
void text_rest(const char *p, const char *eol, const char **b, const char **e);

/* Colours written as numbers (OBJ `v x y z r g b`, COFF, XYZ columns) to RGBA bytes:
 * `channels` (3 or 4) values per item at `stride` floats, in [0, 1], or 0..255 when any of
 * them exceeds 1 (decided for the whole set); alpha 255 when not given. */
void scan_float_colors(const float *values, int stride, int channels, uint64_t n,
                       uint8_t *rgba);

/* ---- readers (each fills `out`, already initialised; on failure the caller releases) ---- */

int sl_obj_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info);
int sl_stl_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info);
int sl_off_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info);
int sl_xyz_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info);
int sl_gltf_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info);
/* The facts alone (sl_scan_read_info). */
int sl_obj_info_source(const scan_src *s, sl_scan_info *info);
int sl_stl_info_source(const scan_src *s, sl_scan_info *info);
int sl_off_info_source(const scan_src *s, sl_scan_info *info);
int sl_xyz_info_source(const scan_src *s, sl_scan_info *info);
int sl_gltf_info_source(const scan_src *s, sl_scan_info *info);

/* Whether the bytes look like each format (for names that do not say). */
int sl_stl_is_binary(const unsigned char *data, size_t size);
int sl_off_sniff(const unsigned char *data, size_t size);
int sl_xyz_sniff(const unsigned char *data, size_t size);

/* A file beside the scan, mapped whole: *map NULL and a negative code when `name` is not
 * inside `dir` or cannot be opened (the error recorded in `err`, naming the path). */
int scan_sibling_map(const scan_src *s, const char *name, void **map, size_t *size,
                     sl_error *err);

#endif
