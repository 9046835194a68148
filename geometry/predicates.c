/* Robust 2D predicates: a floating-point filter, then an exact evaluation.
 *
 * Filter: J. R. Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
 * Geometric Predicates", Discrete Comput. Geom. 18(3), 1997, section 4.2, stage A: the
 * rounded determinant differs from the true one by at most (3 + 16 eps) eps times
 * |detleft| + |detright| (orient2d) and (10 + 96 eps) eps times the permanent (incircle),
 * eps = 2^-53, evaluated in exactly the operation order below. His proof assumes that no
 * operation overflows or underflows. Overflow cannot hide: an infinity or NaN makes the
 * test fail. Underflow can, so we take the filter's answer only when every coordinate
 * difference is 0 or at least 2^-200 in magnitude: then every product in the evaluation is
 * 0 or a normal number and the bound holds as proved (docs/mesh-toolkit.md).
 *
 * Exact stage: when the coordinate differences are exact and few bits wide (grids, nearby
 * points), the plain evaluation is exact and suffices. Otherwise the same determinants in
 * expansion arithmetic (a value held as a sum of
 * nonoverlapping doubles of increasing magnitude; Shewchuk sections 2.2-2.8), built from
 * two error-free transforms: Knuth's two-sum and the fused multiply-add's exact product
 * error. We skip his adaptive stages B and C: degenerate calls are rare in our inputs,
 * and one exact stage is easier to trust. Signs are read off the largest component.
 *
 * An error term is only exact if it is representable. We first scale one call's
 * coordinates by a power of two (exact) so the largest is below 1: then nothing overflows.
 * If every coordinate is an integer multiple of 2^q, every intermediate of a degree-k
 * determinant is a multiple of 2^(kq), and representable when kq >= -1074. Coordinates
 * spanning more binary orders than that (1.0 next to 1e-300) go to big integers instead.
 */
#include "geometry/predicates.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#if FLT_EVAL_METHOD != 0
#error "the predicates' error bounds assume double arithmetic without excess precision"
#endif

#define EPS 0x1p-53
#define ORIENT_BOUND ((3.0 + 16.0 * EPS) * EPS)
#define INCIRCLE_BOUND ((10.0 + 96.0 * EPS) * EPS)
/* Differences at least this large (or 0) keep every filter product normal: incircle
 * multiplies four of them, and a difference of two such products is at least their ulp. */
#define FILTER_MIN_DIFF 0x1p-200
/* The widest exponent span (highest bit bound minus lowest set bit) that expansions hold
 * exactly: 2 (hi - lo) <= 1074 for a degree-2 determinant, 4 (hi - lo) <= 1074 for the
 * degree-4 incircle. */
#define ORIENT_SPAN 537
#define INCIRCLE_SPAN 268

static inline int filter_safe(double d)
{
    return d == 0.0 || fabs(d) >= FILTER_MIN_DIFF;
}

static inline int sign_of(double x)
{
    return (x > 0.0) - (x < 0.0);
}

/* ---- error-free transforms and expansions --------------------------------------- */

static inline void two_sum(double a, double b, double *sum, double *err)
{
    double s = a + b;
    double bv = s - a;
    double av = s - bv;
    *sum = s;
    *err = (a - av) + (b - bv);
}

static inline void two_product(double a, double b, double *prod, double *err)
{
    double p = a * b;
    *prod = p;
    *err = fma(a, b, -p);
}

/* x - y exactly, as an expansion of at most 2 components; returns its length. */
static int difference(double x, double y, double *h)
{
    double s, e;
    two_sum(x, -y, &s, &e);
    int n = 0;
    if (e != 0.0)
        h[n++] = e;
    if (s != 0.0)
        h[n++] = s;
    return n;
}

/* h = e + f (Shewchuk's fast expansion sum with zero elimination: merge by magnitude,
 * then sweep with two-sum). h has room for elen + flen; returns its length. */
static int expansion_sum(int elen, const double *e, int flen, const double *f, double *h)
{
    int i = 0, j = 0, k = 0;
    double q = 0.0;
    while (i < elen || j < flen) {
        double g;
        if (j == flen || (i < elen && fabs(e[i]) < fabs(f[j])))
            g = e[i++];
        else
            g = f[j++];
        double err;
        two_sum(q, g, &q, &err);
        if (err != 0.0)
            h[k++] = err;
    }
    if (q != 0.0)
        h[k++] = q;
    return k;
}

/* h = e * b (Shewchuk's scale expansion with zero elimination); h has room for 2 elen. */
static int scale_expansion(int elen, const double *e, double b, double *h)
{
    if (elen == 0 || b == 0.0)
        return 0;
    int k = 0;
    double q, err;
    two_product(e[0], b, &q, &err);
    if (err != 0.0)
        h[k++] = err;
    for (int i = 1; i < elen; i++) {
        double hi, lo, sum;
        two_product(e[i], b, &hi, &lo);
        two_sum(q, lo, &sum, &err);
        if (err != 0.0)
            h[k++] = err;
        two_sum(hi, sum, &q, &err);
        if (err != 0.0)
            h[k++] = err;
    }
    if (q != 0.0)
        h[k++] = q;
    return k;
}

/* h = e * f as the sum of e scaled by each component of the shorter factor. h and tmp
 * have room for 2 elen flen, part for 2 max(elen, flen). */
static int expansion_product(int elen, const double *e, int flen, const double *f, double *h,
                             double *tmp, double *part)
{
    if (flen > elen) {
        const double *x = e;
        int xlen = elen;
        e = f, elen = flen, f = x, flen = xlen;
    }
    if (flen == 0)
        return 0;
    double *acc = h, *spare = tmp;
    int hlen = scale_expansion(elen, e, f[0], acc);
    for (int j = 1; j < flen; j++) {
        int plen = scale_expansion(elen, e, f[j], part);
        hlen = expansion_sum(hlen, acc, plen, part, spare);
        double *x = acc;
        acc = spare, spare = x;
    }
    if (acc != h)
        memcpy(h, acc, (size_t)hlen * sizeof *h);
    return hlen;
}

/* Rewrites e[0..n) in place as an equal expansion with fewer components (Shewchuk's
 * compress, Theorem 23: a top-down then a bottom-up two-sum sweep). A lift or 2x2 minor
 * of 16 components usually shrinks to 2 or 3, which keeps their product short. */
static int compress(int n, double *e)
{
    if (n <= 1)
        return n;
    int bottom = n - 1;
    double q = e[bottom];
    for (int i = n - 2; i >= 0; i--) {
        double sum, err;
        two_sum(q, e[i], &sum, &err);
        if (err != 0.0) {
            e[bottom--] = sum;
            q = err;
        } else {
            q = sum;
        }
    }
    int top = 0;
    for (int i = bottom + 1; i < n; i++) {
        double sum, err;
        two_sum(e[i], q, &sum, &err);
        if (err != 0.0)
            e[top++] = err;
        q = sum;
    }
    if (q != 0.0)
        e[top++] = q;
    return top;
}

static void negate(int n, double *e)
{
    for (int i = 0; i < n; i++)
        e[i] = -e[i];
}

/* A nonoverlapping expansion's sign is its largest component's. */
static int expansion_sign(int n, const double *e)
{
    return n ? sign_of(e[n - 1]) : 0;
}

/* ---- the exponent range of one call ------------------------------------------------ */

/* Over the nonzero coordinates x[0..n): *hi bounds them (|x| < 2^hi), *lo is the exponent
 * of the lowest set bit among them, *unit the smallest binary unit (2^unit is the ulp of
 * the smallest-exponent one). Returns -1 if one is not finite, 0 if all are zero, else 1. */
static int exponent_range(const double *x, int n, int *hi, int *lo, int *unit)
{
    int h = INT_MIN, l = INT_MAX, u = INT_MAX;
    for (int i = 0; i < n; i++) {
        uint64_t bits;
        memcpy(&bits, &x[i], sizeof bits);
        int e = (int)((bits >> 52) & 0x7ff);
        uint64_t m = bits & ((1ull << 52) - 1);
        if (e == 0x7ff)
            return -1;
        if (e == 0 && m == 0)
            continue;
        int un = e ? e - 1075 : -1074;
        if (e)
            m |= 1ull << 52;
        int top = un + 64 - __builtin_clzll(m);
        int low = un + __builtin_ctzll(m);
        h = top > h ? top : h;
        l = low < l ? low : l;
        u = un < u ? un : u;
    }
    if (h == INT_MIN)
        return 0;
    *hi = h, *lo = l, *unit = u;
    return 1;
}

/* ---- big integers: the reference, and the path for very wide exponent spans -------- */

/* Coordinates become integers X = x / 2^unit below 2^2098 (2^1024 over 2^-1074); the
 * incircle determinant of their differences is below 2^8400: 263 limbs of 32 bits. */
#define BN_LIMBS 272

typedef struct bn {
    int sign;               /* -1, 0, +1 */
    int n;                  /* limbs in use, no leading zero limb; 0 for zero */
    uint32_t d[BN_LIMBS];   /* magnitude, least significant first */
} bn;

static void bn_trim(bn *r)
{
    while (r->n > 0 && r->d[r->n - 1] == 0)
        r->n--;
    if (r->n == 0)
        r->sign = 0;
}

static void bn_from_double(double x, int unit, bn *r)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    int e = (int)((bits >> 52) & 0x7ff);
    uint64_t m = bits & ((1ull << 52) - 1);
    r->sign = 0, r->n = 0;
    if (e == 0 && m == 0)
        return;
    if (e)
        m |= 1ull << 52;
    int shift = (e ? e - 1075 : -1074) - unit; /* >= 0: unit is the smallest */
    int w = shift / 32, b = shift % 32;
    memset(r->d, 0, (size_t)(w + 3) * sizeof r->d[0]);
    uint64_t lo = m << b, hi = b ? m >> (64 - b) : 0;
    r->d[w] = (uint32_t)lo;
    r->d[w + 1] = (uint32_t)(lo >> 32);
    r->d[w + 2] = (uint32_t)hi;
    r->n = w + 3;
    r->sign = (bits >> 63) ? -1 : 1;
    bn_trim(r);
}

static int mag_cmp(const bn *a, const bn *b)
{
    if (a->n != b->n)
        return a->n < b->n ? -1 : 1;
    for (int i = a->n - 1; i >= 0; i--)
        if (a->d[i] != b->d[i])
            return a->d[i] < b->d[i] ? -1 : 1;
    return 0;
}

/* |r| = |a| + |b| */
static void mag_add(const bn *a, const bn *b, bn *r)
{
    int n = a->n > b->n ? a->n : b->n;
    uint64_t carry = 0;
    for (int i = 0; i < n; i++) {
        carry += (uint64_t)(i < a->n ? a->d[i] : 0) + (i < b->n ? b->d[i] : 0);
        r->d[i] = (uint32_t)carry;
        carry >>= 32;
    }
    if (carry)
        r->d[n++] = (uint32_t)carry;
    r->n = n;
}

/* |r| = |a| - |b|, given |a| >= |b| */
static void mag_sub(const bn *a, const bn *b, bn *r)
{
    int64_t borrow = 0;
    for (int i = 0; i < a->n; i++) {
        int64_t t = (int64_t)a->d[i] - (i < b->n ? b->d[i] : 0) - borrow;
        borrow = t < 0;
        r->d[i] = (uint32_t)(t + (borrow ? (int64_t)1 << 32 : 0));
    }
    r->n = a->n;
}

/* r = a + b_sign * |b| (b_sign = b->sign to add, -b->sign to subtract); r must not alias. */
static void bn_addsub(const bn *a, const bn *b, int b_sign, bn *r)
{
    if (b_sign == 0) {
        *r = *a;
        return;
    }
    if (a->sign == 0) {
        *r = *b;
        r->sign = b_sign;
        return;
    }
    if (a->sign == b_sign) {
        mag_add(a, b, r);
        r->sign = a->sign;
        return;
    }
    int c = mag_cmp(a, b);
    if (c >= 0) {
        mag_sub(a, b, r);
        r->sign = a->sign;
    } else {
        mag_sub(b, a, r);
        r->sign = b_sign;
    }
    bn_trim(r);
}

/* r = a * b (schoolbook); r must not alias. */
static void bn_mul(const bn *a, const bn *b, bn *r)
{
    r->sign = a->sign * b->sign;
    if (r->sign == 0) {
        r->n = 0;
        return;
    }
    memset(r->d, 0, (size_t)(a->n + b->n) * sizeof r->d[0]);
    for (int i = 0; i < a->n; i++) {
        uint64_t carry = 0;
        for (int j = 0; j < b->n; j++) {
            uint64_t t = (uint64_t)a->d[i] * b->d[j] + r->d[i + j] + carry;
            r->d[i + j] = (uint32_t)t;
            carry = t >> 32;
        }
        r->d[i + b->n] = (uint32_t)carry;
    }
    r->n = a->n + b->n;
    bn_trim(r);
}

/* r = x - y for coordinates, as integers in units of 2^unit. */
static void bn_coordinate_difference(double x, double y, int unit, bn *r)
{
    bn bx, by;
    bn_from_double(x, unit, &bx);
    bn_from_double(y, unit, &by);
    bn_addsub(&bx, &by, -by.sign, r);
}

/* r = p * s - q * t */
static void bn_cross(const bn *p, const bn *s, const bn *q, const bn *t, bn *r)
{
    bn ps, qt;
    bn_mul(p, s, &ps);
    bn_mul(q, t, &qt);
    bn_addsub(&ps, &qt, -qt.sign, r);
}

int sl_orient2d_bigint(const double a[2], const double b[2], const double c[2])
{
    const double x[6] = {a[0], a[1], b[0], b[1], c[0], c[1]};
    int hi, lo, unit;
    if (exponent_range(x, 6, &hi, &lo, &unit) <= 0)
        return 0;
    bn acx, acy, bcx, bcy, det;
    bn_coordinate_difference(a[0], c[0], unit, &acx);
    bn_coordinate_difference(a[1], c[1], unit, &acy);
    bn_coordinate_difference(b[0], c[0], unit, &bcx);
    bn_coordinate_difference(b[1], c[1], unit, &bcy);
    bn_cross(&acx, &bcy, &acy, &bcx, &det);
    return det.sign;
}

/* r = lift * cross, with lift = dx^2 + dy^2 of one point and cross the 2x2 minor of the
 * other two. */
static void bn_incircle_term(const bn *dx, const bn *dy, const bn *cross, bn *r)
{
    bn xx, yy, lift;
    bn_mul(dx, dx, &xx);
    bn_mul(dy, dy, &yy);
    bn_addsub(&xx, &yy, yy.sign, &lift);
    bn_mul(&lift, cross, r);
}

int sl_incircle_bigint(const double a[2], const double b[2], const double c[2],
                       const double d[2])
{
    const double x[8] = {a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]};
    int hi, lo, unit;
    if (exponent_range(x, 8, &hi, &lo, &unit) <= 0)
        return 0;
    bn adx, ady, bdx, bdy, cdx, cdy, cross, term, sum, det;
    bn_coordinate_difference(a[0], d[0], unit, &adx);
    bn_coordinate_difference(a[1], d[1], unit, &ady);
    bn_coordinate_difference(b[0], d[0], unit, &bdx);
    bn_coordinate_difference(b[1], d[1], unit, &bdy);
    bn_coordinate_difference(c[0], d[0], unit, &cdx);
    bn_coordinate_difference(c[1], d[1], unit, &cdy);
    bn_cross(&bdx, &cdy, &cdx, &bdy, &cross);
    bn_incircle_term(&adx, &ady, &cross, &sum);
    bn_cross(&cdx, &ady, &adx, &cdy, &cross);
    bn_incircle_term(&bdx, &bdy, &cross, &term);
    bn_addsub(&sum, &term, term.sign, &det);
    bn_cross(&adx, &bdy, &bdx, &ady, &cross);
    bn_incircle_term(&cdx, &cdy, &cross, &term);
    bn_addsub(&det, &term, term.sign, &sum);
    return sum.sign;
}

/* ---- exact evaluation in expansions --------------------------------------------------- */

/* Scales x[0..n) by 2^-hi in place when the degree-k determinant could overflow
 * (2^(k hi) near 2^1024) or lose bits below 2^-1074 (k lo < -1074); the scaled values are
 * below 1 and exact, since the lowest bit lands at or above 2^-1074 whenever the span test
 * passed. Most calls need no scaling. */
static void scale_if_needed(double *x, int n, int k, int hi, int lo)
{
    if (k * hi < 1000 && k * lo >= -1074)
        return;
    for (int i = 0; i < n; i++)
        x[i] = ldexp(x[i], -hi);
}

/* d = x - y; whether that was exact and the d are few bits wide. Then a degree-k
 * determinant of them makes no rounding error in plain doubles: with every d a multiple of
 * 2^lo below 2^hi, every intermediate is a multiple of 2^(k lo) below 2^(k hi + k), exact
 * when k (hi - lo + 1) <= 53, k lo >= -1074 and k (hi + 1) < 1024. Grids and nearby
 * points (x - y is exact when y/2 <= x <= 2y) are most degenerate calls: they skip the
 * expansions. */
static int exact_differences(const double *x, const double *y, int n, int k, double *d)
{
    for (int i = 0; i < n; i++) {
        double err;
        two_sum(x[i], -y[i], &d[i], &err);
        if (err != 0.0) /* also NaN: not finite */
            return 0;
    }
    int hi, lo, unit, range = exponent_range(d, n, &hi, &lo, &unit);
    return range == 0 ||
           (range > 0 && k * (hi - lo + 1) <= 53 && k * lo >= -1074 && k * (hi + 1) < 1024);
}

int sl_orient2d_exact(const double a[2], const double b[2], const double c[2])
{
    const double from[4] = {a[0], a[1], b[0], b[1]}, to[4] = {c[0], c[1], c[0], c[1]};
    double dd[4];
    if (exact_differences(from, to, 4, 2, dd))
        return sign_of(dd[0] * dd[3] - dd[1] * dd[2]);
    double x[6] = {a[0], a[1], b[0], b[1], c[0], c[1]};
    int hi, lo, unit;
    int range = exponent_range(x, 6, &hi, &lo, &unit);
    if (range <= 0)
        return 0;
    if (hi - lo > ORIENT_SPAN)
        return sl_orient2d_bigint(a, b, c);
    scale_if_needed(x, 6, 2, hi, lo);
    double acx[2], acy[2], bcx[2], bcy[2], left[8], right[8], det[16], tmp[8], part[4];
    int nacx = difference(x[0], x[4], acx), nacy = difference(x[1], x[5], acy);
    int nbcx = difference(x[2], x[4], bcx), nbcy = difference(x[3], x[5], bcy);
    int nl = expansion_product(nacx, acx, nbcy, bcy, left, tmp, part);
    int nr = expansion_product(nacy, acy, nbcx, bcx, right, tmp, part);
    negate(nr, right);
    int nd = expansion_sum(nl, left, nr, right, det);
    return expansion_sign(nd, det);
}

/* h = p * s - q * t for 2-component differences; h has room for 16. */
static int cross_expansion(int np, const double *p, int ns, const double *s, int nq,
                           const double *q, int nt, const double *t, double *h)
{
    double ps[8], qt[8], tmp[8], part[4];
    int nps = expansion_product(np, p, ns, s, ps, tmp, part);
    int nqt = expansion_product(nq, q, nt, t, qt, tmp, part);
    negate(nqt, qt);
    return compress(expansion_sum(nps, ps, nqt, qt, h), h);
}

/* h = (dx^2 + dy^2) * cross; h has room for 512 (16 * 16 * 2). */
static int incircle_term(int nx, const double *dx, int ny, const double *dy, int nc,
                         const double *cross, double *h)
{
    double xx[8], yy[8], lift[16], tmp[512], part[32];
    int nxx = expansion_product(nx, dx, nx, dx, xx, tmp, part);
    int nyy = expansion_product(ny, dy, ny, dy, yy, tmp, part);
    int nlift = compress(expansion_sum(nxx, xx, nyy, yy, lift), lift);
    return expansion_product(nc, cross, nlift, lift, h, tmp, part);
}

int sl_incircle_exact(const double a[2], const double b[2], const double c[2],
                      const double d[2])
{
    const double from[6] = {a[0], a[1], b[0], b[1], c[0], c[1]};
    const double to[6] = {d[0], d[1], d[0], d[1], d[0], d[1]};
    double e[6];
    if (exact_differences(from, to, 6, 4, e))
        return sign_of((e[0] * e[0] + e[1] * e[1]) * (e[2] * e[5] - e[4] * e[3]) +
                       (e[2] * e[2] + e[3] * e[3]) * (e[4] * e[1] - e[0] * e[5]) +
                       (e[4] * e[4] + e[5] * e[5]) * (e[0] * e[3] - e[2] * e[1]));
    double x[8] = {a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]};
    int hi, lo, unit;
    int range = exponent_range(x, 8, &hi, &lo, &unit);
    if (range <= 0)
        return 0;
    if (hi - lo > INCIRCLE_SPAN)
        return sl_incircle_bigint(a, b, c, d);
    scale_if_needed(x, 8, 4, hi, lo);
    double adx[2], ady[2], bdx[2], bdy[2], cdx[2], cdy[2], cross[16];
    int nadx = difference(x[0], x[6], adx), nady = difference(x[1], x[7], ady);
    int nbdx = difference(x[2], x[6], bdx), nbdy = difference(x[3], x[7], bdy);
    int ncdx = difference(x[4], x[6], cdx), ncdy = difference(x[5], x[7], cdy);
    double term[512], sum[1024], det[1536];
    int nc = cross_expansion(nbdx, bdx, ncdy, cdy, ncdx, cdx, nbdy, bdy, cross);
    int nsum = incircle_term(nadx, adx, nady, ady, nc, cross, sum);
    nc = cross_expansion(ncdx, cdx, nady, ady, nadx, adx, ncdy, cdy, cross);
    int nterm = incircle_term(nbdx, bdx, nbdy, bdy, nc, cross, term);
    int ndet = expansion_sum(nsum, sum, nterm, term, det);
    memcpy(sum, det, (size_t)ndet * sizeof *det);
    nsum = ndet;
    nc = cross_expansion(nadx, adx, nbdy, bdy, nbdx, bdx, nady, ady, cross);
    nterm = incircle_term(ncdx, cdx, ncdy, cdy, nc, cross, term);
    ndet = expansion_sum(nsum, sum, nterm, term, det);
    return expansion_sign(ndet, det);
}

/* ---- the filtered predicates ------------------------------------------------------------ */

int sl_orient2d(const double a[2], const double b[2], const double c[2])
{
    double acx = a[0] - c[0], bcx = b[0] - c[0];
    double acy = a[1] - c[1], bcy = b[1] - c[1];
    double detleft = acx * bcy, detright = acy * bcx;
    double det = detleft - detright;
    double detsum = fabs(detleft) + fabs(detright);
    if (fabs(det) > ORIENT_BOUND * detsum && filter_safe(acx) && filter_safe(bcx) &&
        filter_safe(acy) && filter_safe(bcy))
        return sign_of(det);
    return sl_orient2d_exact(a, b, c);
}

int sl_incircle(const double a[2], const double b[2], const double c[2], const double d[2])
{
    double adx = a[0] - d[0], bdx = b[0] - d[0], cdx = c[0] - d[0];
    double ady = a[1] - d[1], bdy = b[1] - d[1], cdy = c[1] - d[1];
    double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy, alift = adx * adx + ady * ady;
    double cdxady = cdx * ady, adxcdy = adx * cdy, blift = bdx * bdx + bdy * bdy;
    double adxbdy = adx * bdy, bdxady = bdx * ady, clift = cdx * cdx + cdy * cdy;
    double det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) +
                 clift * (adxbdy - bdxady);
    double permanent = (fabs(bdxcdy) + fabs(cdxbdy)) * alift +
                       (fabs(cdxady) + fabs(adxcdy)) * blift +
                       (fabs(adxbdy) + fabs(bdxady)) * clift;
    if (fabs(det) > INCIRCLE_BOUND * permanent && filter_safe(adx) && filter_safe(bdx) &&
        filter_safe(cdx) && filter_safe(ady) && filter_safe(bdy) && filter_safe(cdy))
        return sign_of(det);
    return sl_incircle_exact(a, b, c, d);
}
