/* Test helper: compose PLY files value by value in any of the three encodings, so one
 * description of a mesh yields the same file as ascii, binary LE and binary BE.
 *
 *   plyb b; plyb_init(&b, SL_PLY_BINARY_BE);
 *   plyb_text(&b, "element vertex 1\nproperty float x\n...end_header\n");
 *   plyb_val(&b, "float", 1.5); ... plyb_eol(&b);
 *
 * plyb_begin() writes "ply" and the format line. Ascii values are printed so they read
 * back exactly (%.9g for float, %.17g for double).
 */
#ifndef SCANLOD_TESTS_PLY_BUILDER_H
#define SCANLOD_TESTS_PLY_BUILDER_H

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/ply.h"

typedef struct plyb {
    char *buf;
    size_t len, cap;
    int format;
} plyb;

static const struct plyb_type {
    const char *name;
    int size, is_signed, is_float;
} plyb_types[] = {
    {"char", 1, 1, 0},   {"int8", 1, 1, 0},    {"uchar", 1, 0, 0},  {"uint8", 1, 0, 0},
    {"short", 2, 1, 0},  {"int16", 2, 1, 0},   {"ushort", 2, 0, 0}, {"uint16", 2, 0, 0},
    {"int", 4, 1, 0},    {"int32", 4, 1, 0},   {"uint", 4, 0, 0},   {"uint32", 4, 0, 0},
    {"float", 4, 1, 1},  {"float32", 4, 1, 1}, {"double", 8, 1, 1}, {"float64", 8, 1, 1},
};
#define PLYB_NTYPES ((int)(sizeof plyb_types / sizeof plyb_types[0]))

static inline const struct plyb_type *plyb_type_of(const char *name)
{
    /* Lengths first: GCC -O3 flags strcmp of a 7-character name against a constant
     * 6-character caller's string (-Wstring-compare), true but harmless. */
    size_t n = strlen(name);
    for (int i = 0; i < PLYB_NTYPES; i++)
        if (strlen(plyb_types[i].name) == n && memcmp(plyb_types[i].name, name, n) == 0)
            return &plyb_types[i];
    fprintf(stderr, "plyb: unknown type %s\n", name);
    abort();
}

static inline void plyb_raw(plyb *b, const void *data, size_t n)
{
    if (b->len + n + 1 > b->cap) {
        b->cap = (b->len + n + 1) * 2;
        b->buf = realloc(b->buf, b->cap);
        if (!b->buf)
            abort();
    }
    memcpy(b->buf + b->len, data, n);
    b->len += n;
    b->buf[b->len] = 0;
}

static inline void plyb_text(plyb *b, const char *fmt, ...)
{
    char tmp[4096];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    plyb_raw(b, tmp, (size_t)n);
}

static inline void plyb_init(plyb *b, int format)
{
    memset(b, 0, sizeof *b);
    b->format = format;
}

static inline const char *plyb_format_name(int format)
{
    return format == SL_PLY_ASCII ? "ascii"
           : format == SL_PLY_BINARY_LE ? "binary_little_endian" : "binary_big_endian";
}

static inline void plyb_begin(plyb *b)
{
    plyb_text(b, "ply\nformat %s 1.0\n", plyb_format_name(b->format));
}

static inline void plyb_val(plyb *b, const char *type, double v)
{
    const struct plyb_type *t = plyb_type_of(type);
    if (b->format == SL_PLY_ASCII) {
        if (t->is_float)
            plyb_text(b, t->size == 4 ? "%.9g " : "%.17g ", v);
        else
            plyb_text(b, "%lld ", (long long)v);
        return;
    }
    unsigned char bytes[8];
    uint64_t bits;
    if (t->is_float && t->size == 4) {
        float f = (float)v;
        uint32_t u;
        memcpy(&u, &f, 4);
        bits = u;
    } else if (t->is_float) {
        memcpy(&bits, &v, 8);
    } else {
        bits = (uint64_t)(int64_t)v;
    }
    for (int i = 0; i < t->size; i++) {
        int shift = b->format == SL_PLY_BINARY_LE ? 8 * i : 8 * (t->size - 1 - i);
        bytes[i] = (unsigned char)(bits >> shift);
    }
    plyb_raw(b, bytes, (size_t)t->size);
}

static inline void plyb_eol(plyb *b)
{
    if (b->format == SL_PLY_ASCII)
        plyb_raw(b, "\n", 1);
}

/* Writes the file to dir/name (and to $SCANLOD_PLY_SEED_DIR/name when set: that is how
 * tests/fuzz/corpus/ply was seeded). Returns the path in `path`. */
static inline const char *plyb_save(const plyb *b, const char *dir, const char *name, char *path,
                                    size_t size)
{
    const char *seeds = getenv("SCANLOD_PLY_SEED_DIR");
    for (int pass = 0; pass < 2; pass++) {
        const char *d = pass == 0 ? dir : seeds;
        if (!d || !d[0])
            continue;
        snprintf(path, size, "%s/%s", d, name);
        FILE *f = fopen(path, "wb");
        if (!f || fwrite(b->buf, 1, b->len, f) != b->len || fclose(f) != 0) {
            fprintf(stderr, "plyb: cannot write %s\n", path);
            abort();
        }
    }
    snprintf(path, size, "%s/%s", dir, name);
    return path;
}

static inline void plyb_free(plyb *b)
{
    free(b->buf);
    memset(b, 0, sizeof *b);
}

#endif
