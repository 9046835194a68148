/* The ascii number parsers (formats/ply_number.c) must give exactly what strtof/strtod
 * give, bit for bit: on the ways writers print floats (%g/%f/%e at every precision, the
 * shortest round-trip form), on random decimal strings of any length and exponent, and on
 * the special cases (signed zeros, subnormals, overflow, nan/inf, half-way values).
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/ply_internal.h"
#include "tests/check.h"

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static uint64_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

static int mismatches;

static void check_float_token(const char *s)
{
    float got = 12345.0f;
    char *stop;
    float want = strtof(s, &stop);
    const char *end = s + strlen(s);
    const char *q = sl_ply_parse_float(s, end, &got);
    int ok = q == end && *stop == 0 && memcmp(&got, &want, sizeof got) == 0;
    if (!ok && mismatches++ < 10)
        fprintf(stderr, "float '%s': got %.9g, strtof %.9g\n", s, (double)got, (double)want);
    CHECK(ok || mismatches > 10);
}

static void check_double_token(const char *s)
{
    double got = 12345.0;
    char *stop;
    double want = strtod(s, &stop);
    const char *end = s + strlen(s);
    const char *q = sl_ply_parse_double(s, end, &got);
    int ok = q == end && *stop == 0 && memcmp(&got, &want, sizeof got) == 0;
    if (!ok && mismatches++ < 10)
        fprintf(stderr, "double '%s': got %.17g, strtod %.17g\n", s, got, want);
    CHECK(ok || mismatches > 10);
}

static float random_float(void)
{
    for (;;) {
        uint32_t bits = (uint32_t)rng();
        float f;
        memcpy(&f, &bits, sizeof f);
        if (isfinite(f))
            return f;
    }
}

/* Floats printed the ways PLY writers print them. */
static void test_printed_floats(void)
{
    const char *formats[] = {"%.1g", "%.3g", "%.6g", "%.7g", "%.8g", "%.9g", "%f",
                             "%.4f", "%.9f", "%e", "%.8e", "%.12g", "%.17g"};
    char buf[128];
    for (int i = 0; i < 100000; i++) {
        float f = random_float();
        if (i % 2) /* the typical scan range */
            f = (float)((double)(int32_t)rng() / 2147483648.0 * pow(10, (int)(rng() % 7) - 3));
        for (size_t k = 0; k < sizeof formats / sizeof formats[0]; k++) {
            snprintf(buf, sizeof buf, formats[k], (double)f);
            check_float_token(buf);
            check_double_token(buf);
        }
    }
}

/* Random decimal strings: 1..30 digits, a point anywhere, exponents -60..60. */
static void test_random_decimals(void)
{
    char buf[128];
    for (int i = 0; i < 300000; i++) {
        int len = 0, digits = 1 + (int)(rng() % 30), point = (int)(rng() % (digits + 1));
        if (rng() % 2)
            buf[len++] = '-';
        for (int d = 0; d < digits; d++) {
            if (d == point && d > 0)
                buf[len++] = '.';
            buf[len++] = (char)('0' + rng() % 10);
        }
        if (rng() % 3 == 0)
            len += sprintf(buf + len, "e%d", (int)(rng() % 121) - 60);
        buf[len] = 0;
        check_float_token(buf);
        check_double_token(buf);
    }
}

static void test_special_tokens(void)
{
    const char *tokens[] = {
        "0", "-0", "+0", "0.0", "-0.000", "00012", "1", "-1", "+1.5", ".5", "5.", "-.5",
        "1e10", "1E10", "1e+10", "1e-10", "1.5e-45", "1e-45", "7e-46", "1.17549435e-38",
        "1.1754942e-38", "3.4028235e38", "3.4028236e38", "3.5e38", "1e39", "1e400",
        "-1e400", "1e-400", "2.2250738585072014e-308", "4.9e-324", "1.7976931348623157e308",
        "16777216", "16777217", "16777219", "9007199254740993", "0.1", "0.2", "0.3",
        "123456789012345678901234567890", "0.000000000000000000000000000001",
        "1.00000005960464477539062500", "1.000000059604644775390625",
        "1.0000000596046447753906251", "nan", "NaN", "-nan", "inf", "-inf", "Infinity",
        "-INFINITY", "0x1p3", "1e0000000000000000000000003",
        /* the double nearest to these is exactly half-way between two floats */
        "1.000000536441803", "1.000000774860382", "1.000001609325409", "1.000001847743988",
    };
    for (size_t i = 0; i < sizeof tokens / sizeof tokens[0]; i++) {
        check_float_token(tokens[i]);
        check_double_token(tokens[i]);
    }
}

/* Tokens end at whitespace or at the end of the data, and nothing else. */
static void test_token_ends(void)
{
    const char *good = "1.5 2";
    float f = 0;
    int64_t v = 0;
    CHECK(sl_ply_parse_float(good, good + 5, &f) == good + 3 && f == 1.5f);
    CHECK(sl_ply_parse_float(good, good + 2, &f) == good + 2 && f == 1.0f); /* cut at "1." */
    const char *bad[] = {"1.5x", "abc", "", "-", ".", "1e", "1e+", "--1", "1..2", "1,5"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        const char *s = bad[i];
        CHECK_MSG(!sl_ply_parse_float(s, s + strlen(s), &f), "'%s' parsed as float", s);
    }
    const char *ints[] = {"0", "-7", "+7", "4294967295", "-2147483648", "007"};
    const int64_t want[] = {0, -7, 7, 4294967295LL, -2147483648LL, 7};
    for (size_t i = 0; i < sizeof ints / sizeof ints[0]; i++) {
        const char *s = ints[i];
        CHECK(sl_ply_parse_int(s, s + strlen(s), &v) == s + strlen(s) && v == want[i]);
    }
    const char *bad_ints[] = {"1.0", "1e3", "", "-", "x1", "99999999999999999999999"};
    for (size_t i = 0; i < sizeof bad_ints / sizeof bad_ints[0]; i++) {
        const char *s = bad_ints[i];
        CHECK_MSG(!sl_ply_parse_int(s, s + strlen(s), &v), "'%s' parsed as int", s);
    }
}

int main(void)
{
    test_special_tokens();
    test_token_ends();
    test_printed_floats();
    test_random_decimals();
    return check_report();
}
