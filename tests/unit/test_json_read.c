/* The JSON reader of input files (formats/json_read.h): what RFC 8259 allows reads, with
 * members, items, numbers and decoded strings as written; what it does not is refused
 * with the byte it failed at; the token and depth limits hold.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "formats/json_read.h"
#include "tests/check.h"

static int parse(const char *text, uint32_t max_tokens, sl_jdoc *d, char *why)
{
    return sl_jdoc_parse(d, text, strlen(text), max_tokens, why, 300);
}

static void test_document(void)
{
    const char *text = " {\"a\": [1, -2.5e1, true, null, {\"b\": \"x\\u00e9\\n\\\"y\"}],"
                       " \"c\\/d\": 0, \"e\": \"\\ud83d\\ude00\"} ";
    sl_jdoc d;
    char why[300], s[64];
    CHECK(parse(text, 100, &d, why) == 0);
    uint32_t a = sl_jdoc_get(&d, 0, "a");
    double v;
    CHECK(sl_jdoc_type(&d, a) == SL_JDOC_ARRAY && d.tokens[a].count == 5);
    CHECK(sl_jdoc_number(&d, sl_jdoc_item(&d, a, 1), &v) && v == -25);
    CHECK(sl_jdoc_type(&d, sl_jdoc_item(&d, a, 2)) == SL_JDOC_TRUE);
    CHECK(sl_jdoc_type(&d, sl_jdoc_item(&d, a, 3)) == SL_JDOC_NULL);
    CHECK(sl_jdoc_item(&d, a, 5) == 0 && sl_jdoc_get(&d, 0, "z") == 0);
    uint32_t b = sl_jdoc_get(&d, sl_jdoc_item(&d, a, 4), "b");
    CHECK(sl_jdoc_string(&d, b, s, sizeof s) == 6 && !strcmp(s, "x\xc3\xa9\n\"y"));
    CHECK(sl_jdoc_get(&d, 0, "c/d") != 0); /* keys compare decoded */
    CHECK(sl_jdoc_string(&d, sl_jdoc_get(&d, 0, "e"), s, sizeof s) == 4 &&
          !strcmp(s, "\xf0\x9f\x98\x80"));
    uint64_t i;
    CHECK(sl_jdoc_index(&d, sl_jdoc_item(&d, a, 0), 2, &i) == 1 && i == 1);
    CHECK(sl_jdoc_index(&d, sl_jdoc_item(&d, a, 0), 1, &i) == -1);
    CHECK(sl_jdoc_index(&d, sl_jdoc_item(&d, a, 1), 100, &i) == -1);
    CHECK(sl_jdoc_string(&d, b, s, 3) == 6 && !strcmp(s, "x\xc3")); /* cut to fit */
    sl_jdoc_release(&d);
}

static void test_refused(void)
{
    static const struct { const char *text, *why; } bad[] = {
        {"", "byte 0: a value is missing"},
        {"[1,]", "byte 3: unexpected character ']'"},
        {"{\"a\":1,}", "byte 7: expected a member name"},
        {"{'a':1}", "expected a member name"},
        {"[01]", "bad number"},
        {"[1.]", "bad number"},
        {"[-]", "bad number"},
        {"[1e]", "bad number"},
        {"\"a\x01\"", "control character"},
        {"\"\\x\"", "bad escape"},
        {"\"\\u12\"", "bad \\u escape"},
        {"\"abc", "unterminated string"},
        {"[1 2]", "expected ',' or ']'"},
        {"{\"a\" 1}", "expected ':'"},
        {"[1] x", "text after the document"},
        {"[[[", "unterminated array"},
        {"/* c */ 1", "unexpected character '/'"},
        {"tru", "unexpected character 't'"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        sl_jdoc d;
        char why[300] = "";
        int rc = parse(bad[k].text, 100, &d, why);
        CHECK_MSG(rc == SL_E_BADINPUT && strstr(why, bad[k].why), "'%s': %d %s", bad[k].text, rc,
                  why);
        CHECK(d.tokens == NULL);
    }
}

static void test_limits(void)
{
    sl_jdoc d;
    char why[300];
    CHECK(parse("[1,2,3]", 3, &d, why) == SL_E_LIMIT && strstr(why, "more than 3 values"));
    CHECK(parse("[1,2,3]", 4, &d, why) == 0);
    sl_jdoc_release(&d);
    char deep[200];
    for (int levels = 65; levels <= 66; levels++) { /* the top and 64 below it, then one more */
        memset(deep, '[', (size_t)levels);
        memset(deep + levels, ']', (size_t)levels);
        deep[2 * levels] = 0;
        int rc = parse(deep, 1000, &d, why);
        CHECK(levels == 65 ? rc == 0 : rc == SL_E_BADINPUT && strstr(why, "nested deeper than 64"));
        sl_jdoc_release(&d);
    }
}

int main(void)
{
    test_document();
    test_refused();
    test_limits();
    return check_report();
}
