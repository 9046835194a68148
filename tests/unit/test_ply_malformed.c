/* Hostile PLY input (reference/reliability.md section 4): every file in
 * tests/data/malformed (written by make_malformed.sh), a 10 MB header line, custom limits,
 * and every truncation of small good files must give exactly one SL_E_BADINPUT or
 * SL_E_LIMIT whose message names the cause, fast, without allocating much. Each committed
 * case runs in a forked child whose address space is capped (or, under ASan, whose
 * allocator refuses blocks over 64 MB) and whose peak RSS growth is measured.
 */
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "formats/ply.h"
#include "tests/check.h"
#include "tests/unit/ply_builder.h"

#if defined(__SANITIZE_ADDRESS__) || defined(SCANLOD_SANITIZED)
#define UNDER_ASAN 1
/* Under ASan the address space cannot be capped; refuse big blocks instead. */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
    return "allocator_may_return_null=1:max_allocation_size_mb=64";
}
#else
#define UNDER_ASAN 0
#endif

#define MAX_RSS_GROWTH_KB (64 * 1024)
#define MAX_SECONDS 1.0

static const struct expect {
    const char *file;
    int code; /* 0: must read (non-finite values are kept) */
    const char *cause;
} expected[] = {
    {"empty.ply", SL_E_BADINPUT, "empty file"},
    {"garbage_header.ply", SL_E_BADINPUT, "not a PLY file"},
    {"no_end_header.ply", SL_E_BADINPUT, "no end_header"},
    {"no_end_header_body.ply", SL_E_BADINPUT, "unknown header keyword '1'"},
    {"cr_only_lines.ply", SL_E_BADINPUT, "no end_header"},
    {"format_missing.ply", SL_E_BADINPUT, "before the format line"},
    {"unknown_format.ply", SL_E_BADINPUT, "unknown format 'binary_middle_endian'"},
    {"unknown_version.ply", SL_E_BADINPUT, "unsupported PLY version '2.0'"},
    {"unknown_type.ply", SL_E_BADINPUT, "unknown property type 'float128'"},
    {"negative_count.ply", SL_E_BADINPUT, "negative count '-5'"},
    {"property_before_element.ply", SL_E_BADINPUT, "property before any element"},
    {"duplicate_vertex_element.ply", SL_E_BADINPUT, "second element 'vertex'"},
    {"duplicate_property.ply", SL_E_BADINPUT, "'x' (or a synonym) twice"},
    {"missing_xyz.ply", SL_E_BADINPUT, "lacks property x, y or z"},
    {"list_in_vertex.ply", SL_E_BADINPUT, "'x' of element vertex must not be a list"},
    {"scalar_indices.ply", SL_E_BADINPUT, "'vertex_indices' of element face must be a list"},
    {"float_count_type.ply", SL_E_BADINPUT, "count type float is not an integer type"},
    {"float_index_type.ply", SL_E_BADINPUT, "non-integer index type float"},
    {"face_without_indices.ply", SL_E_BADINPUT, "no vertex_indices list"},
    {"texture_name_too_long.ply", SL_E_LIMIT, "TextureFile name longer than 255 bytes"},
    {"too_many_elements.ply", SL_E_LIMIT, "more than 64 elements"},
    {"vertex_2e32.ply", SL_E_BADINPUT, "declares 4294967295 vertices"},
    {"vertex_2e32_binary.ply", SL_E_BADINPUT,
     "header line 3: element vertex declares 4294967295 vertices (at least 12 bytes each) but "
     "the file has 36 bytes after the header"},
    {"vertex_2e64_minus_1.ply", SL_E_BADINPUT, "declares 18446744073709551615 vertices"},
    {"count_2e64.ply", SL_E_BADINPUT, "'18446744073709551616' does not fit 64 bits"},
    {"face_2e32.ply", SL_E_BADINPUT, "declares 4294967296 faces"},
    {"faces_1e9_with_10.ply", SL_E_BADINPUT, "declares 1000000000 faces"},
    {"list_count_huge.ply", SL_E_BADINPUT, "face 0: list 'vertex_indices' declares 4294967295 items"},
    {"list_count_huge_ascii.ply", SL_E_BADINPUT, "declares 4294967295 items"},
    {"list_count_negative.ply", SL_E_BADINPUT, "face 0: list 'vertex_indices' has negative length -1"},
    {"list_count_negative_ascii.ply", SL_E_BADINPUT, "negative length -3"},
    {"list_too_many_corners.ply", SL_E_LIMIT, "face has 2000 corners (limit 1024)"},
    {"int_out_of_range.ply", SL_E_BADINPUT, "300 is out of range for uchar"},
    {"texcoord_mismatch.ply", SL_E_BADINPUT, "texcoord list has 5 values for 3 corners"},
    {"index_out_of_range.ply", SL_E_BADINPUT, "face 1: vertex index 5 is out of range (3 vertices)"},
    {"index_negative.ply", SL_E_BADINPUT, "face 0: vertex index -1 is out of range"},
    {"index_negative_ascii.ply", SL_E_BADINPUT, "face 0: vertex index -1 is out of range"},
    {"range_grid_bad_index.ply", SL_E_BADINPUT, "range_grid row 1: vertex index 99"},
    {"wrong_endianness.ply", SL_E_BADINPUT, "vertex index 16777216 is out of range"},
    {"all_nan.ply", 0, NULL},
    {"nan_inf_ascii.ply", 0, NULL},
    {"truncated_binary_header.ply", SL_E_BADINPUT, "declares 3 vertices"},
    {"truncated_binary.ply", SL_E_BADINPUT, "face 1: list 'vertex_indices' declares 3 items"},
    {"truncated_ascii.ply", SL_E_BADINPUT, "face 1: list 'vertex_indices' declares 3 items"},
    {"trailing_bytes_binary.ply", SL_E_BADINPUT, "2 bytes after the last element"},
    {"trailing_garbage_ascii.ply", SL_E_BADINPUT, "line 9: unexpected data after the last element"},
    {"bad_number.ply", SL_E_BADINPUT, "'abc' is not a valid float"},
};
#define NEXPECTED (sizeof expected / sizeof expected[0])

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static long rss_now_kb(void)
{
    long pages = 0, resident = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (f && fscanf(f, "%ld %ld", &pages, &resident) != 2)
        resident = 0;
    if (f)
        fclose(f);
    return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

static void cap_address_space(void)
{
    long pages = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (f && fscanf(f, "%ld", &pages) == 1) {
        rlim_t cap = (rlim_t)pages * (rlim_t)sysconf(_SC_PAGESIZE) + (256u << 20);
        struct rlimit rl = {cap, cap};
        setrlimit(RLIMIT_AS, &rl);
    }
    if (f)
        fclose(f);
}

typedef struct outcome {
    int rc;
    long rss_growth_kb;
    double seconds;
    uint64_t vertices;
    char message[800];
} outcome;

/* Reads `path` (or the buffer) in a child with capped memory; the result comes back
 * through a pipe. */
static outcome read_isolated(const char *path, const void *buf, size_t size)
{
    outcome out = {.rc = 1, .message = "child failed"};
    int fds[2];
    if (pipe(fds) != 0)
        return out;
    double t0 = now();
    pid_t pid = fork();
    if (pid == 0) {
        close(fds[0]);
        if (!UNDER_ASAN)
            cap_address_space();
        long before = rss_now_kb();
        sl_mesh m;
        sl_error err;
        sl_error_init(&err);
        outcome res = {0};
        res.rc = path ? sl_ply_read(path, NULL, &m, NULL, NULL, &err)
                      : sl_ply_read_memory(buf, size, "memory.ply", NULL, &m, NULL, &err);
        struct rusage ru;
        getrusage(RUSAGE_SELF, &ru);
        res.rss_growth_kb = ru.ru_maxrss - before;
        res.vertices = m.vertex_count;
        snprintf(res.message, sizeof res.message, "%s", err.message);
        if (res.rc != err.code)
            res.rc = 1000; /* the return value and the recorded error disagree */
        sl_mesh_release(&m);
        ssize_t w = write(fds[1], &res, sizeof res);
        _exit(w == (ssize_t)sizeof res ? 0 : 1);
    }
    close(fds[1]);
    if (pid > 0) {
        ssize_t n = read(fds[0], &out, sizeof out);
        int status = 0;
        waitpid(pid, &status, 0);
        if (n != (ssize_t)sizeof out || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
            out.rc = 1;
            snprintf(out.message, sizeof out.message, "child crashed (status %d)", status);
        }
    }
    close(fds[0]);
    out.seconds = now() - t0;
    return out;
}

static void check_outcome(const char *what, const outcome *o, int code, const char *cause)
{
    CHECK_MSG(o->rc == code, "%s: rc %d (%s), want %d", what, o->rc, o->message, code);
    if (cause)
        CHECK_MSG(strstr(o->message, cause) != NULL, "%s: message '%s' lacks '%s'", what,
                  o->message, cause);
    CHECK_MSG(!strchr(o->message, '\n'), "%s: message has several lines", what);
    CHECK_MSG(o->seconds < MAX_SECONDS, "%s: took %.3f s", what, o->seconds);
    CHECK_MSG(o->rss_growth_kb < MAX_RSS_GROWTH_KB, "%s: RSS grew by %ld kB", what,
              o->rss_growth_kb);
}

static void test_committed_files(void)
{
    char dir[1024], path[1400];
    check_source_path("tests/data/malformed", dir, sizeof dir);
    for (size_t i = 0; i < NEXPECTED; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, expected[i].file);
        outcome o = read_isolated(path, NULL, 0);
        check_outcome(expected[i].file, &o, expected[i].code, expected[i].cause);
        if (expected[i].code == SL_E_BADINPUT || expected[i].code == SL_E_LIMIT)
            CHECK_MSG(strstr(o.message, "line") || strstr(o.message, "byte") ||
                      strstr(o.message, "empty"), "%s: '%s' says not where", expected[i].file,
                      o.message);
    }
    /* every committed file has an expectation */
    DIR *d = opendir(dir);
    CHECK(d != NULL);
    struct dirent *ent;
    int files = 0;
    while (d && (ent = readdir(d))) {
        size_t n = strlen(ent->d_name);
        if (n < 4 || strcmp(ent->d_name + n - 4, ".ply") != 0)
            continue;
        int known = 0;
        for (size_t i = 0; i < NEXPECTED; i++)
            known |= strcmp(expected[i].file, ent->d_name) == 0;
        CHECK_MSG(known, "%s has no expectation in test_ply_malformed.c", ent->d_name);
        files++;
    }
    if (d)
        closedir(d);
    CHECK_EQ_U64(files, NEXPECTED);
}

/* A 10 MB header line: refused at the header size limit, in well under a second. */
static void test_long_header_line(void)
{
    size_t n = 10u << 20;
    char *buf = malloc(n + 64);
    int len = sprintf(buf, "ply\nformat ascii 1.0\ncomment ");
    memset(buf + len, 'x', n);
    strcpy(buf + len + n, "\nend_header\n");
    outcome o = read_isolated(NULL, buf, strlen(buf));
    check_outcome("10 MB header line", &o, SL_E_LIMIT, "header size limit");
    free(buf);
}

static int read_with(const char *text, const sl_ply_limits *lim, sl_error *err)
{
    sl_mesh m;
    sl_error_init(err);
    int rc = sl_ply_read_memory(text, strlen(text), "limits.ply", lim, &m, NULL, err);
    sl_mesh_release(&m);
    return rc;
}

static void test_limits(void)
{
    const char *quad = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\n"
                       "property list uchar int vertex_indices\nend_header\n"
                       "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    sl_error err;
    sl_ply_limits lim = sl_ply_default_limits();
    CHECK(read_with(quad, &lim, &err) == 0);
    lim.max_vertices = 3;
    CHECK(read_with(quad, &lim, &err) == SL_E_LIMIT && strstr(err.message, "(limit 3)"));
    lim = sl_ply_default_limits();
    lim.max_faces = 0;
    CHECK(read_with(quad, &lim, &err) == SL_E_LIMIT && strstr(err.message, "1 faces (limit 0)"));
    lim = sl_ply_default_limits();
    lim.max_face_corners = 3;
    CHECK(read_with(quad, &lim, &err) == SL_E_LIMIT && strstr(err.message, "4 corners (limit 3)"));
    lim = sl_ply_default_limits();
    lim.max_header_bytes = 64;
    CHECK(read_with(quad, &lim, &err) == SL_E_LIMIT && strstr(err.message, "first 64 bytes"));
}

/* Every proper prefix of a good file fails cleanly; an ascii prefix may read only when
 * the cut falls inside the last row (its last number may just look shorter). */
static void truncations(const char *what, const unsigned char *data, size_t size, size_t step)
{
    size_t last_row = size - 1;
    while (last_row > 0 && data[last_row - 1] != '\n')
        last_row--;
    int ascii = memmem(data, size < 64 ? size : 64, "ascii", 5) != NULL;
    int bad = 0;
    double t0 = now();
    for (size_t cut = 0; cut < size && bad < 5; cut += step) {
        sl_mesh m;
        sl_error err;
        sl_error_init(&err);
        int rc = sl_ply_read_memory(data, cut, what, NULL, &m, NULL, &err);
        sl_mesh_release(&m);
        int ok = rc == 0 ? ascii && cut >= last_row
                         : (rc == SL_E_BADINPUT || rc == SL_E_LIMIT) && rc == err.code &&
                               err.message[0] && !strchr(err.message, '\n');
        if (!ok)
            bad++;
        CHECK_MSG(ok, "%s cut at %zu of %zu: rc %d '%s'", what, cut, size, rc, err.message);
    }
    double per_cut = (now() - t0) / (double)((size + step - 1) / step);
    CHECK_MSG(per_cut < 0.1, "%s: %.3f s per truncated read", what, per_cut);
}

static void test_truncations_of_small_files(void)
{
    const int formats[] = {SL_PLY_ASCII, SL_PLY_BINARY_LE, SL_PLY_BINARY_BE};
    for (int f = 0; f < 3; f++) {
        plyb b;
        plyb_init(&b, formats[f]);
        plyb_begin(&b);
        plyb_text(&b, "comment TextureFile t.png\nelement vertex 5\nproperty float x\n"
                      "property float y\nproperty float z\nproperty uchar red\n"
                      "property uchar green\nproperty uchar blue\nelement face 3\n"
                      "property list uchar int vertex_indices\n"
                      "property list uchar float texcoord\nend_header\n");
        for (int v = 0; v < 5; v++) {
            for (int k = 0; k < 3; k++)
                plyb_val(&b, "float", 0.25 * v + k);
            for (int k = 0; k < 3; k++)
                plyb_val(&b, "uchar", 50 * v + k);
            plyb_eol(&b);
        }
        const int faces[3][4] = {{0, 1, 2, -1}, {1, 2, 3, 4}, {4, 3, 0, -1}};
        for (int i = 0; i < 3; i++) {
            int n = faces[i][3] < 0 ? 3 : 4;
            plyb_val(&b, "uchar", n);
            for (int k = 0; k < n; k++)
                plyb_val(&b, "int", faces[i][k]);
            plyb_val(&b, "uchar", 2 * n);
            for (int k = 0; k < 2 * n; k++)
                plyb_val(&b, "float", 0.125 * k);
            plyb_eol(&b);
        }
        truncations(plyb_format_name(formats[f]), (const unsigned char *)b.buf, b.len, 1);
        plyb_free(&b);
    }
}

static void test_truncations_of_real_files(void)
{
    const char *files[] = {"tests/data/scans/cow.ply", "tests/data/scans/bun_zipper_res4.ply"};
    for (int i = 0; i < 2; i++) {
        char path[1024];
        check_source_path(files[i], path, sizeof path);
        FILE *f = fopen(path, "rb");
        CHECK_MSG(f != NULL, "cannot open %s", path);
        if (!f)
            continue;
        unsigned char *data = malloc(1 << 20);
        size_t n = fread(data, 1, 1 << 20, f);
        fclose(f);
        truncations(files[i], data, n, n / 200 + 1);
        truncations(files[i], data, 600 < n ? 600 : n, 1); /* every cut in and near the header */
        free(data);
    }
}

int main(void)
{
    test_committed_files();
    test_long_header_line();
    test_limits();
    test_truncations_of_small_files();
    test_truncations_of_real_files();
    return check_report();
}
