/* The collection manifest's readers (pipeline/manifest.h): CSV as spreadsheets write it,
 * JSON in both shapes, and every malformed manifest refused with SL_E_CONFIG naming the
 * file and the line. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "pipeline/manifest.h"
#include "tests/check.h"

static char dir[] = "/tmp/scanlod-manifest-XXXXXX";

/* Loads `text` as NAME; returns the rc, with the manifest in *m when 0. */
static int load(const char *name, const char *text, sl_manifest *m, sl_error *err)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    fwrite(text, 1, strlen(text), f);
    fclose(f);
    sl_error_init(err);
    int rc = sl_manifest_load(m, path, err);
    unlink(path);
    return rc;
}

static const char *field(const sl_manifest *m, const char *item, int c)
{
    const sl_manifest_row *r = sl_manifest_find(m, item);
    return r ? r->field[c] : "(no row)";
}

static void csv(void)
{
    sl_manifest m;
    sl_error err;
    /* A BOM, CRLF, quotes with a comma and a doubled quote, a description over two lines,
     * a blank line, a short row, case and blanks in the header and in units. */
    const char *text = "\xef\xbb\xbf" "File , Title,accession number,units,UP,credit,license,"
                       "description\r\n"
                       "busts/nefertiti.ply,\"Nefertiti, bust\",ÄM 21300,MM,Z,\"Neues "
                       "Museum, \"\"Berlin\"\"\",CC BY-SA 4.0,\"Painted limestone.\r\n"
                       "Found 1912.\"\r\n"
                       "\r\n"
                       "./cow.ply,Cow\r\n";
    CHECK(load("manifest.csv", text, &m, &err) == 0);
    CHECK_EQ_U64(m.count, 2);
    CHECK(!strcmp(field(&m, "busts/nefertiti.ply", SL_MF_TITLE), "Nefertiti, bust"));
    CHECK(!strcmp(field(&m, "busts/nefertiti.ply", SL_MF_ACCESSION), "ÄM 21300"));
    CHECK(!strcmp(field(&m, "busts/nefertiti.ply", SL_MF_UNITS), "mm"));
    CHECK(!strcmp(field(&m, "busts/nefertiti.ply", SL_MF_UP), "z"));
    CHECK(!strcmp(field(&m, "busts/nefertiti.ply", SL_MF_CREDIT), "Neues Museum, \"Berlin\""));
    CHECK(!strcmp(field(&m, "busts/nefertiti.ply", SL_MF_DESCRIPTION),
                  "Painted limestone.\r\nFound 1912."));
    CHECK(!strcmp(field(&m, "cow.ply", SL_MF_TITLE), "Cow"));
    CHECK(!strcmp(field(&m, "cow.ply", SL_MF_LICENCE), ""));
    const sl_manifest_row *r = sl_manifest_find(&m, "busts/nefertiti.ply");
    CHECK(r && r->line == 2 && !strcmp(r->meta.where, "manifest.csv:2") &&
          !strcmp(r->meta.title, "Nefertiti, bust"));
    CHECK(sl_manifest_find(&m, "cow.ply")->line == 5);
    CHECK(!sl_manifest_find(&m, "nope.ply"));
    sl_manifest_release(&m);
    /* A semicolon-separated export (comma-decimal locales). */
    CHECK(load("manifest.csv", "file;title\na.ply;A, the first\n", &m, &err) == 0);
    CHECK(!strcmp(field(&m, "a.ply", SL_MF_TITLE), "A, the first"));
    sl_manifest_release(&m);
}

static void hashes(void)
{
    sl_manifest a, b;
    sl_error err;
    CHECK(load("m.csv", "file,title\nx.ply,X\ny.ply,Y\n", &a, &err) == 0);
    CHECK(load("m.csv", "file,title\n\ny.ply,Y\nx.ply,X2\n", &b, &err) == 0);
    /* Moving a row changes no hash; editing one changes that one only. */
    CHECK(sl_hash_equal(sl_manifest_find(&a, "y.ply")->hash, sl_manifest_find(&b, "y.ply")->hash));
    CHECK(!sl_hash_equal(sl_manifest_find(&a, "x.ply")->hash, sl_manifest_find(&b, "x.ply")->hash));
    sl_manifest_release(&a);
    sl_manifest_release(&b);
}

static void json(void)
{
    sl_manifest m;
    sl_error err;
    CHECK(load("manifest.json", "[\n {\"file\": \"a.ply\", \"title\": \"A \\u00e9\\ud83d\\ude00\","
                                "\n  \"accession\": 1998.123, \"up\": null},\n"
                                " {\"file\": \"b.ply\", \"units\": \"cm\"}\n]\n", &m, &err) == 0);
    CHECK_EQ_U64(m.count, 2);
    CHECK(!strcmp(field(&m, "a.ply", SL_MF_TITLE), "A \xc3\xa9\xf0\x9f\x98\x80"));
    CHECK(!strcmp(field(&m, "a.ply", SL_MF_ACCESSION), "1998.123"));
    CHECK(!strcmp(field(&m, "b.ply", SL_MF_UNITS), "cm"));
    CHECK(sl_manifest_find(&m, "b.ply")->line == 4);
    sl_manifest_release(&m);
    CHECK(load("manifest.json", "{\"a.ply\": {\"title\": \"A\"},\n \"b.ply\": {}}", &m, &err) == 0);
    CHECK(!strcmp(field(&m, "a.ply", SL_MF_TITLE), "A") && sl_manifest_find(&m, "b.ply"));
    sl_manifest_release(&m);
}

/* Each malformed manifest: SL_E_CONFIG, err->file ending ":LINE", the message saying why. */
static void refused(const char *name, const char *text, int line, const char *why)
{
    sl_manifest m;
    sl_error err;
    int rc = load(name, text, &m, &err);
    char want[32];
    snprintf(want, sizeof want, ":%d", line);
    size_t n = strlen(err.file), w = strlen(want);
    CHECK_MSG(rc == SL_E_CONFIG && n >= w && !strcmp(err.file + n - w, want) &&
                  strstr(err.message, why),
              "%s: rc %d, '%s: %s' (want line %d, '%s')", name, rc, err.file, err.message,
              line, why);
    if (rc == 0)
        sl_manifest_release(&m);
}

static void malformed(void)
{
    refused("m.csv", "", 1, "empty");
    refused("m.csv", "file,titel\n", 1, "unknown column 'titel'");
    refused("m.csv", "title\nX\n", 1, "no 'file' column");
    refused("m.csv", "file,title,title\n", 1, "column 'title' twice");
    refused("m.csv", "file,title\na.ply,\"open\nb.ply,B\n", 2, "never closed");
    refused("m.csv", "file,title\na.ply,\"A\"x\n", 2, "after the closing quote");
    refused("m.csv", "file,title\na.ply,A\nb.ply,B,extra\n", 3, "3 cells");
    refused("m.csv", "file,units\na.ply,mm\nb.ply,metres\n", 3, "units 'metres'");
    refused("m.csv", "file,up\n\na.ply,x\n", 3, "up 'x'");
    refused("m.csv", "file,title\na.ply,A\nb.ply,B\na.ply,C\n", 4, "line 2");
    refused("m.csv", "file,title\n,A\n", 2, "without a file");
    refused("m.csv", "file,title\n../a.ply,A\n", 2, "not a path relative");
    refused("m.csv", "file,title\n/abs/a.ply,A\n", 2, "not a path relative");
    refused("m.csv", "file,title\na.ply,\xe9t\xe9\n", 2, "not UTF-8");
    refused("m.csv", "file,title\na.ply,A\x01\n", 2, "control character");
    refused("m.json", "[{\"file\": \"a.ply\"},\n {\"file\": \"b.ply\", \"colour\": 1}]", 2,
            "unknown column 'colour'");
    refused("m.json", "[{\"file\": \"a.ply\"},\n {\"file\": \"b.ply\", \"title\": [1]}]", 2,
            "string, number or null");
    refused("m.json", "[{\"file\": \"a.ply\"}\n {\"file\": \"b.ply\"}]", 2, "',' or ']'");
    refused("m.json", "[{\"file\": \"a.ply\"}] x", 1, "nothing after");
    refused("m.json", "{\"a.ply\": {\"title\": \"A\"},\n\n \"a.ply\": {}}", 3, "line 1");
    refused("m.json", "[{\"file\": \"a.ply\", \"title\": \"\\q\"}]", 1, "unknown escape");
}

int main(void)
{
    if (!mkdtemp(dir))
        return 1;
    csv();
    hashes();
    json();
    malformed();
    rmdir(dir);
    return check_report();
}
