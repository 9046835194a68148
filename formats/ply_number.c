/* Number parsing for ascii PLY: exact, and much faster than strtof/strtod.
 *
 * Method (Clinger, "How to read floating point numbers accurately", PLDI 1990, the fast
 * path): a decimal m * 10^e with m < 2^53 and |e| <= 22 is one correctly rounded IEEE
 * double operation, because m and 10^|e| are both exact doubles. For float results, a
 * second rounding double -> float is exact when the operands were floats themselves
 * (m < 2^24, |e| <= 10: Figueroa's theorem, 53 >= 2*24 + 2), and otherwise whenever the
 * double does not land exactly half-way between two floats (only then can rounding twice
 * differ from rounding once). Everything else (more than 19 significant digits, large
 * exponents, subnormals, nan/inf, hex) goes to strtof/strtod on a NUL-terminated copy,
 * so the result always equals the C library's.
 *
 * Speed: the scanners run without end-of-data checks. They stop at any byte that cannot
 * continue a number and read at most WINDOW bytes from a token's start (digit runs are
 * capped), so they run on the data in place while WINDOW bytes remain and on a
 * NUL-padded copy of the last few bytes otherwise.
 */
#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "formats/ply_internal.h"

static const double pow10_exact[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                     1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                     1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

#define WINDOW 64
#define MAX_RUN 24 /* digits per run the fast scanner looks at */

typedef struct decimal {
    uint64_t m;     /* the digits, exact when `exact` */
    int64_t exp10;  /* value = m * 10^exp10 */
    int neg;
    int exact;      /* at most 19 significant digits and a short exponent */
} decimal;

static inline int is_digit(char c)
{
    return (unsigned)(c - '0') < 10u;
}

static inline int is_space(char c)
{
    return c == ' ' || (unsigned)(c - '\t') < 5u; /* \t \n \v \f \r */
}

static inline int at_token_end(const char *p, const char *end)
{
    return p == end || is_space(*p);
}

static const uint64_t pow10_int[] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000,
                                     100000000};

/* A run of up to MAX_RUN digits into *m (which may overflow: the caller counts digits). */
static inline __attribute__((always_inline)) const char *scan_run(const char *p, uint64_t *m,
                                                                 int *n)
{
    const char *start = p;
    uint64_t v;
    int k;
    while (p - start < MAX_RUN && (k = sl_ply_digits8(p, &v)) > 0) {
        *m = *m * pow10_int[k] + v;
        p += k;
        if (k < 8)
            break;
    }
    *n = (int)(p - start);
    return p;
}

/* Significant digits: all digits but the leading zeros (the point is skipped). */
static int significant_digits(const char *digits, int total)
{
    int zeros = 0;
    for (const char *q = digits; zeros < total && (*q == '0' || *q == '.'); q++)
        zeros += *q == '0';
    return total - zeros;
}

static const char *scan_exponent(const char *p, decimal *d)
{
    const char *q = p + 1;
    int neg = 0, n = 0;
    if (*q == '-' || *q == '+')
        neg = *q++ == '-';
    if (!is_digit(*q))
        return p; /* "1e" stops before the 'e', like strtod */
    int64_t e = 0;
    for (; is_digit(*q) && n < 8; q++, n++)
        e = e * 10 + (*q - '0');
    d->exact &= !is_digit(*q);
    d->exp10 += neg ? -e : e;
    return q;
}

#define HOT static inline __attribute__((always_inline))

/* [sign] digits [. digits] [e [sign] digits]; NULL when there is no digit. */
HOT const char *scan_decimal(const char *p, decimal *d)
{
    int nint, nfrac = 0;
    *d = (decimal){.exact = 1};
    if (*p == '-' || *p == '+')
        d->neg = *p++ == '-';
    const char *digits = p;
    p = scan_run(p, &d->m, &nint);
    if (*p == '.')
        p = scan_run(p + 1, &d->m, &nfrac);
    if (nint + nfrac == 0)
        return NULL;
    d->exp10 = -nfrac;
    if (is_digit(*p) || (nint + nfrac > 19 && significant_digits(digits, nint + nfrac) > 19))
        d->exact = 0; /* m overflowed or was cut: let the C library round */
    if (*p == 'e' || *p == 'E')
        p = scan_exponent(p, d);
    return p;
}

/* The correctly rounded double of d, when the fast path applies. */
static int fast_double(const decimal *d, double *out)
{
    if (!d->exact || d->m >= (1ull << 53) || d->exp10 < -22 || d->exp10 > 22)
        return 0;
    double v = (double)d->m;
    v = d->exp10 < 0 ? v / pow10_exact[-d->exp10] : v * pow10_exact[d->exp10];
    *out = d->neg ? -v : v;
    return 1;
}

/* 10^-k as the nearest doubles (each within half an ulp; compiler-rounded literals). */
static const double pow10_inverse[] = {1e0,   1e-1,  1e-2,  1e-3,  1e-4,  1e-5,  1e-6,  1e-7,
                                       1e-8,  1e-9,  1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15,
                                       1e-16, 1e-17, 1e-18, 1e-19, 1e-20, 1e-21, 1e-22};

/* A float result without the division: m * 10^-k in double is within two double ulps of
 * the exact value, so rounding it to float gives the correct float unless it lies within
 * a few double ulps of a half-way point between two floats (then the caller divides). */
HOT int fast_float(const decimal *d, float *out)
{
    if (d->exact && d->m == 0) {
        *out = d->neg ? -0.0f : 0.0f;
        return 1;
    }
    if (!d->exact || d->m >= (1ull << 53) || d->exp10 < -22 || d->exp10 > 0)
        return 0;
    double v = (double)d->m * pow10_inverse[-d->exp10];
    if (!(v >= FLT_MIN && v <= FLT_MAX))
        return 0;
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    int64_t from_half_way = (int64_t)(bits & 0x1FFFFFFFu) - 0x10000000;
    if (from_half_way >= -4 && from_half_way <= 4)
        return 0;
    *out = (float)(d->neg ? -v : v);
    return 1;
}

static int float_rounding_safe(const decimal *d, double v)
{
    if (d->m < (1u << 24) && d->exp10 >= -10 && d->exp10 <= 10)
        return 1;
    double a = v < 0 ? -v : v;
    if (!(a >= FLT_MIN && a <= FLT_MAX))
        return 0;
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    return (bits & 0x1FFFFFFFu) != 0x10000000u; /* not half-way between two floats */
}

/* strtof/strtod on a NUL-terminated copy of the token. */
static const char *slow_parse(const char *p, const char *end, int is_float, double *out)
{
    char buf[256];
    const char *q = p;
    while (!at_token_end(q, end))
        q++;
    size_t n = (size_t)(q - p);
    if (n == 0 || n >= sizeof buf)
        return NULL;
    memcpy(buf, p, n);
    buf[n] = 0;
    char *stop;
    *out = is_float ? (double)strtof(buf, &stop) : strtod(buf, &stop);
    return stop == buf + n ? q : NULL;
}

static const char *float_window(const char *p, const char *end, int is_float, double *out)
{
    decimal d;
    double v;
    float f;
    const char *q = scan_decimal(p, &d);
    if (q && at_token_end(q, end) && d.exact && d.m == 0) {
        *out = d.neg ? -0.0 : 0.0;
        return q;
    }
    if (q && at_token_end(q, end) && is_float && fast_float(&d, &f)) {
        *out = f;
        return q;
    }
    if (q && at_token_end(q, end) && fast_double(&d, &v) && (!is_float || float_rounding_safe(&d, v))) {
        *out = v;
        return q;
    }
    return slow_parse(p, end, is_float, out);
}

/* Runs a scanner in place, or on a NUL-padded copy when fewer than WINDOW bytes remain. */
static const char *in_window(const char *p, const char *end, int is_float, double *out)
{
    char pad[WINDOW + 1];
    const char *s = p, *e = end, *q;
    if (end - p < WINDOW) {
        size_t n = (size_t)(end - p);
        memcpy(pad, p, n);
        memset(pad + n, 0, sizeof pad - n);
        s = pad;
        e = pad + n;
    }
    q = float_window(s, e, is_float, out);
    return q ? p + (q - s) : NULL;
}

const char *sl_ply_parse_float(const char *p, const char *end, float *out)
{
    decimal d;
    double v;
    const char *q;
    if (end - p >= WINDOW && (q = scan_decimal(p, &d)) && at_token_end(q, end) &&
        fast_float(&d, out))
        return q; /* the common case, all inline */
    if ((q = in_window(p, end, 1, &v)))
        *out = (float)v; /* exact: v is a float already (fast path or strtof) */
    return q;
}

const char *sl_ply_parse_double(const char *p, const char *end, double *out)
{
    return in_window(p, end, 0, out);
}

const char *sl_ply_parse_int(const char *p, const char *end, int64_t *out)
{
    return sl_ply_scan_int(p, end, out);
}
