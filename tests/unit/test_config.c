/* Config: one exact "FILE:LINE: ..." error per kind of mistake, overrides, path
 * resolution, per-section hashes, and the reference file parsing back to the defaults. */
#include "pipeline/config.h"
#include "tests/check.h"

#include <errno.h>
#include <limits.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

static const sl_option run_options[] = {
    {"run", "input", SL_OPT_PATH, NULL, 0, 0, NULL, "The folder tree of scans."},
    {"run", "threads", SL_OPT_INT, "0", 0, 1024, NULL, "Threads; 0 = all cores."},
    {"run", "logs", SL_OPT_PATH, "logs", 0, 0, NULL, "Where the logs go."},
    SL_OPTION_END};

static const sl_option range_options[] = {
    {"range", "k", SL_OPT_INT, "12", 3, 64, NULL,
     "Neighbours used for normal estimation by local PCA. A long help text that must be "
     "wrapped over several comment lines in the reference file, at most 88 columns each, "
     "without breaking a word."},
    {"range", "weld", SL_OPT_BOOL, "true", 0, 0, NULL, "Weld exact duplicates."},
    {"range", "scale", SL_OPT_DOUBLE, "1.5", 0.001, 1000, NULL, "A scale."},
    {"range", "normals", SL_OPT_ENUM, "mesh", 0, 0, "mesh|file|pca", "Normal source."},
    {"range", "levels", SL_OPT_LIST, "0.5, 1,2", 0, 10, NULL, "Levels."},
    {"range", "tags", SL_OPT_LIST, "", 0, 0, NULL, "Free words."},
    {"range", "name", SL_OPT_STRING, "", 0, 0, NULL, "A name."},
    SL_OPTION_END};

static const sl_option *const tables[] = {run_options, range_options, NULL};

static char dir[PATH_MAX], cwd[PATH_MAX];

static const char *write_file(const char *name, const char *text, size_t size)
{
    static char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    fwrite(text, 1, size, f);
    fclose(f);
    return path;
}

/* Loads `text` as dir/a.ini; returns the error line ("" when it loaded). */
static const char *load(const char *text, const char *const *ov, int n, sl_config **out,
                        sl_error *err)
{
    static char msg[2048];
    sl_config *cfg = NULL;
    sl_error_init(err);
    const char *path = text ? write_file("a.ini", text, strlen(text)) : NULL;
    int rc = sl_config_load(&cfg, tables, path, ov, n, err);
    CHECK((rc == 0) == (cfg != NULL) && rc == err->code);
    if (out)
        *out = cfg;
    else
        sl_config_free(cfg);
    if (rc == 0)
        return "";
    return sl_error_format(err, msg, sizeof msg);
}

static void expect_error(const char *text, const char *expected_tail)
{
    sl_error err;
    char want[PATH_MAX + 256];
    snprintf(want, sizeof want, "%s/a.ini%s", dir, expected_tail);
    const char *got = load(text, NULL, 0, NULL, &err);
    CHECK_MSG(!strcmp(got, want), "\n got: %s\nwant: %s", got, want);
    CHECK(err.code == SL_E_CONFIG);
}

static void test_file_errors(void)
{
    expect_error("[run]\ninput = x\n[rnage]\nk = 3\n",
                 ":3: [rnage]: unknown section (known: run, range)");
    expect_error("[run]\ninput = x\ninptu = y\n", ":3: [run] inptu: unknown key (did you mean input?)");
    expect_error("[run]\ninput = x\nzzz = y\n", ":3: [run] zzz: unknown key");
    expect_error("[run]\ninput = a\n\n[range]\n[run]\ninput = b\n",
                 ":6: [run] input: duplicate key (first set on line 2)");
    expect_error("[run]\ninput = x\nthreads = 4x\n", ":3: [run] threads: '4x' is not an integer");
    expect_error("[run]\ninput = x\nthreads = 99999999999999999999\n",
                 ":3: [run] threads: 99999999999999999999 does not fit in 64 bits");
    expect_error("[run]\ninput = x\nthreads = 1025\n",
                 ":3: [run] threads: 1025 is out of range [0, 1024]");
    expect_error("[range]\nscale = nan\n", ":2: [range] scale: 'nan' is not a finite number");
    expect_error("[range]\nscale = -inf\n", ":2: [range] scale: '-inf' is not a finite number");
    expect_error("[range]\nscale = 1.5.2\n", ":2: [range] scale: '1.5.2' is not a number");
    expect_error("[range]\nscale = 0\n", ":2: [range] scale: 0 is out of range [0.001, 1000]");
    expect_error("[range]\nweld = maybe\n",
                 ":2: [range] weld: 'maybe' is not a bool (true/false, yes/no, on/off, 1/0)");
    expect_error("[range]\nk = 2\n", ":2: [range] k: 2 is out of range [3, 64]");
    expect_error("[range]\nnormals = PCA\n", ":2: [range] normals: 'PCA' is not one of mesh|file|pca");
    expect_error("[range]\nlevels = 1,,2\n", ":2: [range] levels: empty list element");
    expect_error("[range]\nlevels = 1, 11\n", ":2: [range] levels: 11 is out of range [0, 10]");
    expect_error("[range]\nlevels = 1, x\n", ":2: [range] levels: 'x' is not a number");
    expect_error("[run]\ninput =\n", ":2: [run] input: empty path");
    expect_error("input = x\n", ":1: input: key outside any [section]");
    expect_error("[run]\ninput = x\nthis line has no equals sign\n",
                 ":3: syntax error: expected [section], key = value or a comment");
    /* a syntax error before a bad key is the one reported: errors come in file order */
    expect_error("[run]\noops\nthreads = x\n",
                 ":2: syntax error: expected [section], key = value or a comment");
    expect_error("[range]\nk = 5\n", ": [run] input is required");
    char long_line[400];
    snprintf(long_line, sizeof long_line, "[run]\ninput = %0300d\n", 0);
    expect_error(long_line, ":2: line longer than 198 characters");
    sl_config *cfg;
    sl_error err;
    sl_error_init(&err);
    sl_config_load(&cfg, tables, write_file("a.ini", "[run]\ninput = x\0y\n", 17), NULL, 0, &err);
    CHECK(!strcmp(err.message, "NUL byte in line") && strstr(err.file, "a.ini:2"));
}

static void test_unreadable(void)
{
    sl_config *cfg = (sl_config *)1;
    sl_error err;
    char path[PATH_MAX + 32], msg[1024];
    snprintf(path, sizeof path, "%s/missing.ini", dir);
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, tables, path, NULL, 0, &err) == SL_E_CONFIG && !cfg);
    CHECK(err.sys_errno == ENOENT && !strcmp(err.file, path));
    CHECK(strstr(sl_error_format(&err, msg, sizeof msg), "No such file or directory") != NULL);
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, tables, dir, NULL, 0, &err) == SL_E_CONFIG);
    CHECK(err.sys_errno == EISDIR);
}

static void test_values(void)
{
    sl_config *cfg;
    sl_error err;
    const char *text = "\xEF\xBB\xBF; comment\r\n[run]\r\n  input = scans ; inline comment\r\n"
                       "\tthreads = +8\r\n# another\n[range]\nweld = OFF\nscale=2.50\n"
                       "levels = 3 , 0.1\ntags = a b, c\nname = x;y\n";
    CHECK(!strcmp(load(text, NULL, 0, &cfg, &err), ""));
    if (!cfg)
        return;
    char want[PATH_MAX + 32];
    snprintf(want, sizeof want, "%s/scans", dir);
    CHECK(!strcmp(sl_config_string(cfg, "run", "input"), want));
    CHECK(sl_config_int(cfg, "run", "threads") == 8);
    CHECK(sl_config_int(cfg, "range", "k") == 12);
    CHECK(sl_config_bool(cfg, "range", "weld") == 0);
    CHECK(!strcmp(sl_config_string(cfg, "range", "weld"), "false"));
    CHECK(sl_config_double(cfg, "range", "scale") == 2.5);
    CHECK(!strcmp(sl_config_string(cfg, "range", "levels"), "3,0.10000000000000001"));
    CHECK(!strcmp(sl_config_string(cfg, "range", "tags"), "a b,c"));
    CHECK(!strcmp(sl_config_string(cfg, "range", "name"), "x;y"));
    snprintf(want, sizeof want, "%s/logs", cwd);
    CHECK(!strcmp(sl_config_string(cfg, "run", "logs"), want));
    snprintf(want, sizeof want, "%s/a.ini", dir);
    CHECK(!strcmp(sl_config_path(cfg), want));
    sl_config_free(cfg);
}

static void test_overrides(void)
{
    sl_config *cfg;
    sl_error err;
    const char *ok[] = {"run.threads=8", " range.k = 20 ", "run.input=rel/dir", "range.k=21"};
    CHECK(!strcmp(load("[run]\ninput = x\nthreads = 3\n", ok, 4, &cfg, &err), ""));
    if (cfg) {
        char want[PATH_MAX + 32];
        snprintf(want, sizeof want, "%s/rel/dir", cwd);
        CHECK(sl_config_int(cfg, "run", "threads") == 8);
        CHECK(sl_config_int(cfg, "range", "k") == 21); /* the later override wins */
        CHECK(!strcmp(sl_config_string(cfg, "run", "input"), want));
        sl_config_free(cfg);
    }
    const char *input_only[] = {"run.input=/data/scans/./x//"};
    CHECK(!strcmp(load(NULL, input_only, 1, &cfg, &err), ""));
    if (cfg) {
        CHECK(!strcmp(sl_config_string(cfg, "run", "input"), "/data/scans/x"));
        CHECK(!strcmp(sl_config_path(cfg), ""));
        sl_config_free(cfg);
    }
    struct {
        const char *arg, *message;
    } bad[] = {
        {"run.thraeds=8", "-s run.thraeds=8: unknown key thraeds in [run]"},
        {"runn.threads=8", "-s runn.threads=8: unknown section [runn]"},
        {"threads=8", "-s threads=8: expected section.key=value"},
        {"run.threads", "-s run.threads: expected section.key=value"},
        {"range.k=1", "-s range.k=1: 1 is out of range [3, 64]"},
        {"range.weld=", "-s range.weld=: '' is not a bool (true/false, yes/no, on/off, 1/0)"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        const char *got = load("[run]\ninput = x\n", &bad[k].arg, 1, NULL, &err);
        CHECK_MSG(!strcmp(got, bad[k].message), "\n got: %s\nwant: %s", got, bad[k].message);
    }
    const char *got = load(NULL, NULL, 0, NULL, &err);
    CHECK(!strcmp(got, "[run] input is required (no config file; use -s run.input=VALUE)"));
}

/* sl_config_origin and sl_config_key_error: where a key was set, for an error that only a
 * check across keys finds (the export's level ladder: two budgets with one name). */
static void test_origin(void)
{
    sl_config *cfg;
    sl_error err;
    const char *ov[] = {"range.scale=2", "run.threads=4"};
    CHECK(!strcmp(load("[run]\ninput = x\nthreads = 3\n\n[range]\nk = 20\n", ov, 2, &cfg, &err), ""));
    if (!cfg)
        return;
    char buf[PATH_MAX + 64], want[PATH_MAX + 64];
    snprintf(want, sizeof want, "%s/a.ini:6", dir);
    CHECK(sl_config_origin(cfg, "range", "k", buf, sizeof buf) == SL_CONFIG_FROM_FILE);
    CHECK_MSG(!strcmp(buf, want), "got %s", buf);
    CHECK(sl_config_origin(cfg, "range", "scale", buf, sizeof buf) == SL_CONFIG_FROM_OVERRIDE);
    CHECK(!strcmp(buf, "-s range.scale"));
    /* set in the file and again by -s: the override is where the value came from */
    CHECK(sl_config_origin(cfg, "run", "threads", buf, sizeof buf) == SL_CONFIG_FROM_OVERRIDE);
    CHECK(!strcmp(buf, "-s run.threads"));
    snprintf(want, sizeof want, "%s/a.ini", dir);
    CHECK(sl_config_origin(cfg, "range", "weld", buf, sizeof buf) == SL_CONFIG_FROM_DEFAULT);
    CHECK(!strcmp(buf, want));
    char where[16];
    sl_config_origin(cfg, "range", "k", where, sizeof where); /* cut, never overrun */
    CHECK(strlen(where) == sizeof where - 1);

    char line[PATH_MAX + 256];
    sl_error_init(&err);
    CHECK(sl_config_key_error(&err, cfg, "range", "k", "two levels named %s", "thumb") ==
          SL_E_CONFIG);
    snprintf(want, sizeof want, "%s/a.ini:6: [range] k: two levels named thumb", dir);
    CHECK_MSG(!strcmp(sl_error_format(&err, line, sizeof line), want), "got %s", line);
    sl_error_init(&err);
    sl_config_key_error(&err, cfg, "range", "scale", "must exceed [range] k / 10");
    CHECK(!strcmp(sl_error_format(&err, line, sizeof line),
                  "-s range.scale: [range] scale: must exceed [range] k / 10"));
    CHECK(sl_error_exit_code(err.code) == SL_EXIT_CONFIG);
    sl_config_free(cfg);

    const char *input_only[] = {"run.input=/x"};
    CHECK(!strcmp(load(NULL, input_only, 1, &cfg, &err), ""));
    if (cfg) {
        CHECK(sl_config_origin(cfg, "range", "k", buf, sizeof buf) == SL_CONFIG_FROM_DEFAULT);
        CHECK(!strcmp(buf, "(no config file)"));
        sl_config_free(cfg);
    }
}

static void test_paths(void)
{
    char sub[PATH_MAX + 32], want[PATH_MAX + 64];
    snprintf(sub, sizeof sub, "%s/sub", dir);
    mkdir(sub, 0755);
    const char *b = "[run]\ninput = ../x/./y//z/\nlogs = /var/log/./scanlod\n";
    write_file("sub/b.ini", b, strlen(b));
    CHECK(chdir(dir) == 0);
    sl_config *cfg = NULL;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, tables, "sub/b.ini", NULL, 0, &err) == 0);
    if (cfg) {
        snprintf(want, sizeof want, "%s/sub/../x/y/z", dir); /* ".." kept: symlinks */
        CHECK(!strcmp(sl_config_string(cfg, "run", "input"), want));
        CHECK(!strcmp(sl_config_string(cfg, "run", "logs"), "/var/log/scanlod"));
        sl_config_free(cfg);
    }
    write_file("c.ini", "[run]\ninput = scans\n", 19);
    CHECK(sl_config_load(&cfg, tables, "c.ini", NULL, 0, &err) == 0);
    if (cfg) {
        snprintf(want, sizeof want, "%s/scans", dir);
        CHECK(!strcmp(sl_config_string(cfg, "run", "input"), want));
        sl_config_free(cfg);
    }
    CHECK(chdir(cwd) == 0);
}

static uint64_t hash_of(const char *text, const char *section)
{
    sl_config *cfg;
    sl_error err;
    load(text, NULL, 0, &cfg, &err);
    CHECK(cfg != NULL);
    uint64_t h = cfg ? sl_config_section_hash(cfg, section) : 0;
    sl_config_free(cfg);
    return h;
}

static void test_hash(void)
{
    const char *base = "[run]\ninput = x\n[range]\nk = 12\n";
    uint64_t range = hash_of(base, "range"), run = hash_of(base, "run");
    const char *canonical = "range.k=12\nrange.weld=true\nrange.scale=1.5\nrange.normals=mesh\n"
                            "range.levels=0.5,1,2\nrange.tags=\nrange.name=\n";
    CHECK(range == XXH3_64bits(canonical, strlen(canonical)));
    /* comments, whitespace, key order, defaults written out, synonyms: same hash */
    CHECK(hash_of("; note\n[range]\n  k=12   ; same\nweld = yes\n[run]\ninput=x\n", "range") == range);
    CHECK(hash_of("[run]\ninput = x\n[range]\nlevels = 0.50,1.0, 2\n", "range") == range);
    /* a key of another section changes only that section's hash */
    CHECK(hash_of("[run]\ninput = x\nthreads = 4\n[range]\n", "range") == range);
    CHECK(hash_of("[run]\ninput = x\nthreads = 4\n[range]\n", "run") != run);
    /* a key of this section changes it */
    CHECK(hash_of(base, "range") != hash_of("[run]\ninput = x\n[range]\nk = 13\n", "range"));
    CHECK(hash_of(base, "range") != hash_of("[run]\ninput = x\n[range]\nname = a\n", "range"));
    CHECK(hash_of(base, "nosuch") == XXH3_64bits("", 0));
}

static char *reference_text(const sl_option *const *t)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    sl_config_write_reference(f, t);
    fclose(f);
    return text;
}

static void test_reference(void)
{
    char *text = reference_text(tables), *again = reference_text(tables);
    CHECK(!strcmp(text, again));
    CHECK(strstr(text, "\n[run]\n") && strstr(text, "\n[range]\n"));
    CHECK(strstr(text, "# type: path; required\n; input =\n") != NULL);
    CHECK(strstr(text, "# type: integer, range [3, 64]\nk = 12\n") != NULL);
    CHECK(strstr(text, "# type: one of mesh|file|pca\nnormals = mesh\n") != NULL);
    CHECK(strstr(text, "; logs = logs\n") != NULL); /* relative default: stays a comment */
    CHECK(strstr(text, "\nname =\n") != NULL);
    for (const char *line = text; *line; line = strchr(line, '\n') + 1)
        CHECK(line[0] != '#' || strcspn(line, "\n") <= 88);

    /* parsed back with the same tables it gives the defaults */
    const char *input[] = {"run.input=/in"};
    sl_config *from_file, *defaults;
    sl_error err;
    CHECK(!strcmp(load(text, input, 1, &from_file, &err), ""));
    CHECK(!strcmp(load(NULL, input, 1, &defaults, &err), ""));
    for (const sl_option *const *t = tables; from_file && defaults && *t; t++)
        for (const sl_option *o = *t; o->name; o++)
            CHECK_MSG(!strcmp(sl_config_string(from_file, o->section, o->name),
                              sl_config_string(defaults, o->section, o->name)),
                      "[%s] %s", o->section, o->name);
    sl_config_free(from_file);
    sl_config_free(defaults);
    free(text);
    free(again);
}

static void test_table_bugs(void)
{
    static const sl_option twice[] = {{"run", "threads", SL_OPT_INT, "1", 0, 0, NULL, "x"},
                                      SL_OPTION_END};
    static const sl_option bad_default[] = {{"q", "n", SL_OPT_INT, "ten", 0, 0, NULL, "x"},
                                            SL_OPTION_END};
    const sl_option *const dup_tables[] = {run_options, twice, NULL};
    const sl_option *const bad_tables[] = {bad_default, NULL};
    const char *input[] = {"run.input=/in"};
    sl_config *cfg;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, dup_tables, NULL, input, 1, &err) == SL_E_INTERNAL);
    sl_error_init(&err);
    CHECK(sl_config_load(&cfg, bad_tables, NULL, NULL, 0, &err) == SL_E_INTERNAL);
    CHECK(strstr(err.message, "[q] n: default: 'ten' is not an integer") != NULL);
}

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/test_config_XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    if (!mkdtemp(dir) || !getcwd(cwd, sizeof cwd))
        return 1;
    test_file_errors();
    test_unreadable();
    test_values();
    test_overrides();
    test_origin();
    test_paths();
    test_hash();
    test_reference();
    test_table_bugs();
    char cmd[PATH_MAX + 16];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
    return check_report();
}
