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
 */
#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/ply_internal.h"

static const double pow10_exact[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                     1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                     1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

typedef struct decimal {
    uint64_t m;     /* up to 19 significant digits */
    int64_t exp10;  /* value = m * 10^exp10 */
    int neg;
    int exact;      /* no nonzero digit was dropped */
} decimal;

static inline int is_digit(char c)
{
    return (unsigned)(c - '0') < 10u;
}

static inline int at_token_end(const char *p, const char *end)
{
    return p == end || *p == ' ' || *p == '\n' || *p == '\r' || *p == '\t' || *p == '\v' ||
           *p == '\f';
}

static inline void add_digit(decimal *d, int *sig, char c, int fraction)
{
    if (*sig < 19) {
        d->m = d->m * 10 + (uint64_t)(c - '0');
        *sig += d->m != 0;
        d->exp10 -= fraction;
    } else {
        d->exp10 += !fraction;
        if (c != '0')
            d->exact = 0;
    }
}

static const char *scan_exponent(const char *p, const char *end, decimal *d)
{
    const char *q = p + 1;
    int neg = 0;
    if (q < end && (*q == '-' || *q == '+'))
        neg = *q++ == '-';
    if (q == end || !is_digit(*q))
        return p; /* "1e" stops before the 'e', like strtod */
    int64_t e = 0;
    for (; q < end && is_digit(*q); q++)
        if (e < 100000)
            e = e * 10 + (*q - '0');
    d->exp10 += neg ? -e : e;
    return q;
}

/* [sign] digits [. digits] [e [sign] digits]; NULL when there is no digit. */
static const char *scan_decimal(const char *p, const char *end, decimal *d)
{
    int sig = 0, any = 0;
    *d = (decimal){.exact = 1};
    if (p < end && (*p == '-' || *p == '+'))
        d->neg = *p++ == '-';
    for (; p < end && is_digit(*p); p++, any = 1)
        add_digit(d, &sig, *p, 0);
    if (p < end && *p == '.')
        for (p++; p < end && is_digit(*p); p++, any = 1)
            add_digit(d, &sig, *p, 1);
    if (!any)
        return NULL;
    if (p < end && (*p == 'e' || *p == 'E'))
        p = scan_exponent(p, end, d);
    return p;
}

/* The correctly rounded double of d, when the fast path applies. */
static int fast_double(const decimal *d, double *out)
{
    if (d->m >= (1ull << 53) || d->exp10 < -22 || d->exp10 > 22)
        return 0;
    double v = (double)d->m;
    v = d->exp10 < 0 ? v / pow10_exact[-d->exp10] : v * pow10_exact[d->exp10];
    *out = d->neg ? -v : v;
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

const char *sl_ply_parse_float(const char *p, const char *end, float *out)
{
    decimal d;
    double v;
    const char *q = scan_decimal(p, end, &d);
    if (q && at_token_end(q, end) && d.exact) {
        if (d.m == 0) {
            *out = d.neg ? -0.0f : 0.0f;
            return q;
        }
        if (fast_double(&d, &v) && float_rounding_safe(&d, v)) {
            *out = (float)v;
            return q;
        }
    }
    q = slow_parse(p, end, 1, &v);
    if (q)
        *out = (float)v; /* exact: v came from strtof */
    return q;
}

const char *sl_ply_parse_double(const char *p, const char *end, double *out)
{
    decimal d;
    const char *q = scan_decimal(p, end, &d);
    if (q && at_token_end(q, end) && d.exact) {
        if (d.m == 0) {
            *out = d.neg ? -0.0 : 0.0;
            return q;
        }
        if (fast_double(&d, out))
            return q;
    }
    return slow_parse(p, end, 0, out);
}

const char *sl_ply_parse_int(const char *p, const char *end, int64_t *out)
{
    int neg = 0;
    uint64_t v = 0;
    if (p < end && (*p == '-' || *p == '+'))
        neg = *p++ == '-';
    const char *digits = p;
    for (; p < end && is_digit(*p); p++) {
        v = v * 10 + (uint64_t)(*p - '0');
        if (v > (1ull << 62))
            return NULL;
    }
    if (p == digits || !at_token_end(p, end))
        return NULL;
    *out = neg ? -(int64_t)v : (int64_t)v;
    return p;
}
