/* JSON writer: exact bytes for compact and pretty output, escaping of control characters
 * and invalid UTF-8, deterministic numbers, and valid JSON whatever bytes go in. */
#include "core/json.h"
#include "tests/check.h"
#include "tests/unit/json_validate.h"

#include <locale.h>
#include <stdint.h>
#include <string.h>

static void build_sample(sl_json *j)
{
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "item", "bunny/bun000");
    sl_json_u64(j, "points", UINT64_MAX);
    sl_json_i64(j, "delta", INT64_MIN);
    sl_json_double(j, "ratio", 0.1);
    sl_json_double(j, "nan", NAN);
    sl_json_bool(j, "ok", 1);
    sl_json_string(j, "none", NULL);
    sl_json_array_begin(j, "list");
    sl_json_double(j, NULL, 1e300);
    sl_json_double(j, NULL, -0.0);
    sl_json_double(j, NULL, 2.0 / 3.0);
    sl_json_object_begin(j, NULL);
    sl_json_object_end(j);
    sl_json_array_begin(j, NULL);
    sl_json_array_end(j);
    sl_json_array_end(j);
    sl_json_raw(j, "range", "{\"welded\":3}");
    sl_json_raw_members(j, "\"a\":1,\"b\":[2]");
    sl_json_object_end(j);
}

static void test_compact_and_pretty(void)
{
    sl_json j;
    sl_json_init(&j, 0);
    CHECK(!strcmp(sl_json_text(&j), ""));
    build_sample(&j);
    const char *compact =
        "{\"item\":\"bunny/bun000\",\"points\":18446744073709551615,"
        "\"delta\":-9223372036854775808,\"ratio\":0.1,\"nan\":null,\"ok\":true,\"none\":null,"
        "\"list\":[1e+300,-0,0.666666667,{},[]],\"range\":{\"welded\":3},\"a\":1,\"b\":[2]}";
    CHECK_MSG(!strcmp(sl_json_text(&j), compact), "%s", sl_json_text(&j));
    CHECK(!j.failed && j.depth == 0 && j.len == strlen(compact));
    CHECK(json_valid(j.buf, j.len));
    sl_json_release(&j);

    sl_json_init(&j, 1);
    build_sample(&j);
    const char *pretty = "{\n"
                         "  \"item\": \"bunny/bun000\",\n"
                         "  \"points\": 18446744073709551615,\n"
                         "  \"delta\": -9223372036854775808,\n"
                         "  \"ratio\": 0.1,\n"
                         "  \"nan\": null,\n"
                         "  \"ok\": true,\n"
                         "  \"none\": null,\n"
                         "  \"list\": [\n"
                         "    1e+300,\n"
                         "    -0,\n"
                         "    0.666666667,\n"
                         "    {},\n"
                         "    []\n"
                         "  ],\n"
                         "  \"range\": {\"welded\":3},\n"
                         "  \"a\":1,\"b\":[2]\n"
                         "}";
    CHECK_MSG(!strcmp(sl_json_text(&j), pretty), "%s", sl_json_text(&j));
    CHECK(json_valid(j.buf, j.len));
    sl_json_release(&j);
}

static void expect_string(const char *in, const char *out)
{
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_string(&j, NULL, in);
    CHECK_MSG(!strcmp(sl_json_text(&j), out), "\n got: %s\nwant: %s", sl_json_text(&j), out);
    CHECK(json_valid(j.buf, j.len));
    sl_json_release(&j);
}

static void test_escaping(void)
{
    expect_string("plain", "\"plain\"");
    expect_string("q\"b\\s/", "\"q\\\"b\\\\s/\"");
    expect_string("\b\f\n\r\t", "\"\\b\\f\\n\\r\\t\"");
    expect_string("\x01\x1f\x7f", "\"\\u0001\\u001f\x7f\"");
    expect_string("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80", "\"caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80\"");
    expect_string("a\xff" "b", "\"a\\ufffdb\"");
    expect_string("\xc0\xaf", "\"\\ufffd\\ufffd\"");             /* overlong "/" */
    expect_string("\xed\xa0\x80", "\"\\ufffd\\ufffd\\ufffd\"");    /* surrogate */
    expect_string("\xf4\x90\x80\x80", "\"\\ufffd\\ufffd\\ufffd\\ufffd\""); /* > U+10FFFF */
    expect_string("\xe2\x82", "\"\\ufffd\\ufffd\"");              /* truncated at the end */
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "k\"\n", "v");
    sl_json_object_end(&j);
    CHECK(!strcmp(sl_json_text(&j), "{\"k\\\"\\n\":\"v\"}"));
    sl_json_release(&j);
}

/* Whatever bytes a file name holds, the output is valid JSON. */
static void test_random_bytes(void)
{
    uint64_t state = 0x9E3779B97F4A7C15u;
    int all_valid = 1;
    for (int round = 0; round < 2000; round++) {
        unsigned char text[64];
        size_t n = 1 + round % 63;
        for (size_t k = 0; k < n; k++) {
            state = state * 6364136223846793005u + 1442695040888963407u;
            text[k] = (unsigned char)(state >> 56);
            if (!text[k])
                text[k] = 0xC3;
        }
        text[n] = '\0';
        sl_json j;
        sl_json_init(&j, round & 1);
        sl_json_array_begin(&j, NULL);
        sl_json_string(&j, NULL, (const char *)text);
        sl_json_array_end(&j);
        all_valid &= json_valid(j.buf, j.len) && !j.failed;
        sl_json_release(&j);
    }
    CHECK(all_valid);
}

static void test_determinism(void)
{
    sl_json a, b;
    sl_json_init(&a, 1);
    sl_json_init(&b, 1);
    build_sample(&a);
    /* a locale with a decimal comma must not leak into the numbers */
    const char *locales[] = {"de_DE.UTF-8", "fr_FR.UTF-8", "de_DE", NULL};
    for (int k = 0; locales[k] && !setlocale(LC_NUMERIC, locales[k]); k++)
        ;
    build_sample(&b);
    setlocale(LC_NUMERIC, "C");
    CHECK(a.len == b.len && !memcmp(a.buf, b.buf, a.len));
    sl_json_release(&a);
    sl_json_release(&b);
}

static void test_misuse(void)
{
    sl_json j;
    sl_json_init(&j, 0);
    for (int k = 0; k <= SL_JSON_MAX_DEPTH; k++)
        sl_json_array_begin(&j, NULL);
    CHECK(j.failed);
    sl_json_release(&j);
    CHECK(!j.failed && j.buf == NULL);
    sl_json_object_end(&j);
    CHECK(j.failed);
    sl_json_release(&j);

    sl_json_init(&j, 0); /* growth past the first allocation */
    sl_json_array_begin(&j, NULL);
    for (int k = 0; k < 10000; k++)
        sl_json_u64(&j, NULL, (uint64_t)k);
    sl_json_array_end(&j);
    CHECK(!j.failed && json_valid(j.buf, j.len) && strlen(j.buf) == j.len);
    sl_json_release(&j);
}

static void test_validator(void)
{
    const char *good[] = {"{}", " [1, -0.5e+3, \"\\u00e9\", true, null] ", "\"\\/\""};
    const char *bad[] = {"{", "[1,]", "01", "\"\x01\"", "\"\\x\"", "{\"a\" 1}", "1 2", "\"\xff\""};
    for (size_t k = 0; k < sizeof good / sizeof good[0]; k++)
        CHECK(json_valid(good[k], strlen(good[k])));
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++)
        CHECK_MSG(!json_valid(bad[k], strlen(bad[k])), "%s", bad[k]);
}

int main(void)
{
    test_validator();
    test_compact_and_pretty();
    test_escaping();
    test_random_bytes();
    test_determinism();
    test_misuse();
    return check_report();
}
