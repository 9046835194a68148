/* Number parsing for the text formats (ascii PLY, OBJ, OFF, ascii STL, XYZ/PTS): exact and
 * fast (the method is in formats/ply_number.c). Shared by every text reader so that a
 * coordinate reads the same bits whatever format it came in.
 */
#ifndef SCANLOD_FORMATS_TEXT_NUMBER_H
#define SCANLOD_FORMATS_TEXT_NUMBER_H

#include <stdint.h>

/* double -> float without the undefined out-of-range conversion (saturates to inf). */
static inline float sl_ply_to_float(double v)
{
    return v > 3.4028234663852886e38 ? __builtin_inff()
           : v < -3.4028234663852886e38 ? -__builtin_inff() : (float)v;
}
/* Number parsers. They parse one token starting at p (no leading
 * whitespace) that must end at `end` or at whitespace, and return the position after it,
 * or NULL when the token is not a number of that kind. Floats equal strtof/strtod of the
 * token (a fast exact path for up to 19 significant digits, strtof/strtod otherwise). */
const char *sl_ply_parse_float(const char *p, const char *end, float *out);
const char *sl_ply_parse_double(const char *p, const char *end, double *out);
const char *sl_ply_parse_int(const char *p, const char *end, int64_t *out);

/* How many of the 8 bytes at p are leading ASCII digits (0..8), and their value: eight
 * characters at a time (SWAR, the method of Lemire's fast_float). Reads 8 bytes. */
static inline int sl_ply_digits8(const char *p, uint64_t *value)
{
    uint64_t v;
    __builtin_memcpy(&v, p, sizeof v);
#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    v = __builtin_bswap64(v); /* first character in the low byte */
#endif
    uint64_t nondigit = ((v + 0x4646464646464646ull) | (v - 0x3030303030303030ull)) &
                        0x8080808080808080ull;
    int n = nondigit ? __builtin_ctzll(nondigit) / 8 : 8;
    if (n == 0)
        return 0;
    if (n < 8) /* keep the n digits, as the last ones of "000..." */
        v = v << (8 * (8 - n)) | (0x3030303030303030ull >> (8 * n));
    v -= 0x3030303030303030ull;
    v = v * 10 + (v >> 8);
    *value = (((v & 0x000000FF000000FFull) * 0x000F424000000064ull) +
              (((v >> 16) & 0x000000FF000000FFull) * 0x0000271000000001ull)) >> 32;
    return n;
}

/* sl_ply_parse_int inline, for the ascii hot loops: [sign] 1..18 digits. */
static inline const char *sl_ply_scan_int(const char *p, const char *end, int64_t *out)
{
    int neg = 0;
    uint64_t v = 0;
    if (p < end && (*p == '-' || *p == '+'))
        neg = *p++ == '-';
    const char *start = p;
    if (end - p > 19) /* no end checks needed: at most 20 bytes are looked at */
        while ((unsigned)(*p - '0') < 10u && p - start < 19)
            v = v * 10 + (uint64_t)(*p++ - '0');
    else
        while (p < end && (unsigned)(*p - '0') < 10u)
            v = v * 10 + (uint64_t)(*p++ - '0');
    if (p == start || p - start > 18 ||
        (p < end && *p != ' ' && (unsigned)(*p - '\t') >= 5u))
        return NULL;
    *out = neg ? -(int64_t)v : (int64_t)v;
    return p;
}

#endif
