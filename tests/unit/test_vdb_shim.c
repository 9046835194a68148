/* The OpenVDB shim: exact write/read roundtrip (coords, distances, colours, transform),
 * sorted output whatever OpenVDB's internal order, byte-identical files for the same
 * samples (also a second apart: no timestamps, no random UUID), refusal of unsorted input,
 * of too many samples (SL_E_LIMIT), of corrupted, truncated and foreign files
 * (SL_E_CORRUPT), and nothing left behind by a failed write. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "shim/vdb_shim.h"
#include "tests/check.h"

static char tmp_dir[256];

/* The whole file (malloc'd) through the project's reader, or NULL. */
static char *slurp(const char *path, long *size)
{
    char *data = NULL;
    size_t n = 0;
    sl_error err;
    sl_error_init(&err);
    if (sl_read_file(path, UINT64_C(1) << 32, &data, &n, &err) != SL_OK)
        return NULL;
    *size = (long)n;
    return data;
}

static void spit(const char *path, const char *data, long size)
{
    FILE *f = fopen(path, "wb");
    if (f) {
        fwrite(data, 1, size, f);
        fclose(f);
    }
}

/* A shell of samples spread over several OpenVDB leaves and internal nodes, including
 * negative coordinates, in lexicographic order. */
static sl_vdb_samples make_samples(int with_colors)
{
    sl_vdb_samples s;
    memset(&s, 0, sizeof s);
    uint64_t cap = 40 * 40 * 40;
    s.coords = malloc(3 * cap * sizeof(int32_t));
    s.distance = malloc(cap * sizeof(float));
    s.colors = with_colors ? malloc(4 * cap) : NULL;
    for (int x = -20; x < 20; x++)
        for (int y = -20; y < 20; y++)
            for (int z = -20; z < 20; z++) {
                double r = sqrt((double)x * x + (double)y * y + (double)z * z);
                if (fabs(r - 14.0) > 2.0 && !(x == 19 && y == -20 && z == 5))
                    continue;
                uint64_t i = s.count++;
                s.coords[3 * i] = x * 37; /* spread over internal nodes too */
                s.coords[3 * i + 1] = y;
                s.coords[3 * i + 2] = z - 3;
                s.distance[i] = (float)((r - 14.0) * 0.01);
                if (with_colors)
                    for (int k = 0; k < 4; k++)
                        s.colors[4 * i + k] = (uint8_t)(x * 7 + y * 3 + z + k * 50);
            }
    s.leaf_size = 0.0123456789;
    s.origin[0] = -1.5;
    s.origin[1] = 2.0 / 3.0;
    s.origin[2] = 1e-7;
    return s;
}

static int same_samples(const sl_vdb_samples *a, const sl_vdb_samples *b)
{
    if (a->count != b->count || a->leaf_size != b->leaf_size || !a->colors != !b->colors) {
        fprintf(stderr, "count %llu vs %llu, voxel %.17g vs %.17g\n", (unsigned long long)a->count,
                (unsigned long long)b->count, a->leaf_size, b->leaf_size);
        return 0;
    }
    for (int k = 0; k < 3; k++)
        if (a->origin[k] != b->origin[k]) {
            fprintf(stderr, "origin %d: %.17g vs %.17g\n", k, a->origin[k], b->origin[k]);
            return 0;
        }
    return memcmp(a->coords, b->coords, 3 * a->count * sizeof(int32_t)) == 0 &&
           memcmp(a->distance, b->distance, a->count * sizeof(float)) == 0 &&
           (!a->colors || memcmp(a->colors, b->colors, 4 * a->count) == 0);
}

static void test_roundtrip(int with_colors)
{
    char path[300], path2[300];
    snprintf(path, sizeof path, "%s/a.vdb", tmp_dir);
    snprintf(path2, sizeof path2, "%s/b.vdb", tmp_dir);
    sl_vdb_samples s = make_samples(with_colors), r;
    sl_error err;
    sl_error_init(&err);
    CHECK(s.count > 5000);
    CHECK(sl_vdb_samples_write(path, &s, &err) == SL_OK);
    CHECK(sl_vdb_samples_read(path, s.count, &r, &err) == SL_OK);
    CHECK_MSG(same_samples(&s, &r), "roundtrip differs (colors %d)", with_colors);
    sl_vdb_samples_release(&r);

    /* Same samples, a second later: the same bytes. */
    sleep(1);
    CHECK(sl_vdb_samples_write(path2, &s, &err) == SL_OK);
    long n1 = 0, n2 = 0;
    char *a = slurp(path, &n1), *b = slurp(path2, &n2);
    CHECK_MSG(a && b && n1 == n2 && memcmp(a, b, n1) == 0, "two writes differ");
    /* The UUID field holds the content hash, not a random value. */
    CHECK(a && n1 > 57 && a[29] == '-' && a[34] == '-' && a[39] == '-' && a[44] == '-');

    /* One sample fewer: a different file and a different UUID. */
    s.count--;
    CHECK(sl_vdb_samples_write(path2, &s, &err) == SL_OK);
    free(b);
    b = slurp(path2, &n2);
    CHECK(b && n2 > 57 && memcmp(a + 21, b + 21, 36) != 0);
    s.count++;

    /* Limit. */
    sl_error_init(&err);
    CHECK(sl_vdb_samples_read(path, s.count - 1, &r, &err) == SL_E_LIMIT);
    CHECK(r.count == 0 && r.coords == NULL);
    free(a), free(b);
    sl_vdb_samples_release(&s);
}

static void expect_corrupt(const char *path, const char *what)
{
    sl_vdb_samples r;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_vdb_samples_read(path, 1u << 30, &r, &err);
    CHECK_MSG(rc == SL_E_CORRUPT, "%s: rc %d (%s)", what, rc, err.message);
    CHECK_MSG(strstr(err.file, path) != NULL, "%s: error names %s", what, err.file);
    CHECK(r.count == 0 && r.coords == NULL && r.distance == NULL);
    printf("  %s: %s\n", what, err.message);
}

static void test_corrupt(void)
{
    char path[300], bad[300];
    snprintf(path, sizeof path, "%s/c.vdb", tmp_dir);
    snprintf(bad, sizeof bad, "%s/bad.vdb", tmp_dir);
    sl_vdb_samples s = make_samples(1);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_vdb_samples_write(path, &s, &err) == SL_OK);
    long n = 0;
    char *data = slurp(path, &n);
    CHECK(data && n > 200);
    /* 300 bytes spread over the file flipped in turn (header, metadata, topology, data):
     * each must be caught. */
    int caught = 0, tried = 0;
    for (long at = 0; data && at < n; at += n / 300 + 1) {
        data[at] ^= 0x5a;
        spit(bad, data, n);
        sl_vdb_samples r;
        sl_error_init(&err);
        caught += sl_vdb_samples_read(bad, 1u << 30, &r, &err) == SL_E_CORRUPT;
        tried++;
        data[at] ^= 0x5a;
    }
    CHECK_MSG(caught == tried, "%d of %d flipped bytes caught", caught, tried);
    spit(bad, data, n / 2);
    expect_corrupt(bad, "truncated");
    spit(bad, data, 10);
    expect_corrupt(bad, "10 bytes");
    spit(bad, "", 0);
    expect_corrupt(bad, "empty");
    spit(bad, "solid cube\nfacet normal 0 0 1\n", 31);
    expect_corrupt(bad, "not a VDB file");
    free(data);

    /* A missing file is an I/O failure naming the file, not a crash. */
    sl_vdb_samples r;
    sl_error_init(&err);
    snprintf(bad, sizeof bad, "%s/missing.vdb", tmp_dir);
    CHECK(sl_vdb_samples_read(bad, 100, &r, &err) != SL_OK && strstr(err.file, "missing.vdb"));
    sl_vdb_samples_release(&s);
}

static void test_refusals(void)
{
    char dir[300], path[400];
    snprintf(dir, sizeof dir, "%s/refuse", tmp_dir);
    CHECK(mkdir(dir, 0755) == 0);
    snprintf(path, sizeof path, "%s/x.vdb", dir);
    sl_vdb_samples s = make_samples(0);
    sl_error err;
    /* Unsorted. */
    int32_t t[3];
    memcpy(t, s.coords, sizeof t);
    memcpy(s.coords, s.coords + 3, sizeof t);
    memcpy(s.coords + 3, t, sizeof t);
    sl_error_init(&err);
    CHECK(sl_vdb_samples_write(path, &s, &err) == SL_E_INTERNAL);
    memcpy(s.coords + 3, s.coords, sizeof t);
    memcpy(s.coords, t, sizeof t);
    /* Bad voxel size, non-finite distance. */
    s.leaf_size = 0;
    sl_error_init(&err);
    CHECK(sl_vdb_samples_write(path, &s, &err) == SL_E_INTERNAL);
    s.leaf_size = 1;
    s.distance[5] = NAN;
    sl_error_init(&err);
    CHECK(sl_vdb_samples_write(path, &s, &err) == SL_E_INTERNAL);
    CHECK_MSG(rmdir(dir) == 0 && mkdir(dir, 0755) == 0, "a failed write left files behind");
    /* Into a missing directory: an error naming the file. */
    s.distance[5] = 0;
    snprintf(path, sizeof path, "%s/no/such/dir/x.vdb", tmp_dir);
    sl_error_init(&err);
    CHECK(sl_vdb_samples_write(path, &s, &err) != SL_OK && strstr(err.file, "x.vdb"));
    /* Empty samples are a valid (empty) file. */
    sl_vdb_samples e = s, r;
    e.count = 0;
    snprintf(path, sizeof path, "%s/empty.vdb", dir);
    sl_error_init(&err);
    CHECK(sl_vdb_samples_write(path, &e, &err) == SL_OK);
    CHECK(sl_vdb_samples_read(path, 10, &r, &err) == SL_OK && r.count == 0 && r.leaf_size == 1);
    sl_vdb_samples_release(&r);
    sl_vdb_samples_release(&s);
}

int main(void)
{
    snprintf(tmp_dir, sizeof tmp_dir, "/tmp/test_vdb_shim.XXXXXX");
    if (!mkdtemp(tmp_dir))
        return 1;
    sl_vdb_set_threads(2);
    test_roundtrip(0);
    test_roundtrip(1);
    test_corrupt();
    test_refusals();
    sl_vdb_set_threads(0);
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_dir);
    if (system(cmd) != 0)
        fprintf(stderr, "cannot remove %s\n", tmp_dir);
    return check_report();
}
