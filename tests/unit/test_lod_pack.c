/* Model format 3's packed parts (runtime/lod_pack.h, docs/formats.md "model.slod"): the
 * packing round-trips exactly and is the same on any thread count; a real model of format
 * 2 (the pipeline's model of bun_zipper_res4, tests/data/models/) still reads, rewritten
 * as format 3 it is several times smaller, cuts the same meshes and rebuilds the very
 * neighbour table format 2 stored; and packed bodies that lie (a truncated frame, plain
 * sizes that disagree with their frames, garbage, counts beyond the bytes, a neighbour
 * count the octree does not have, an envelope of the other version) are each refused with
 * their own cause, before anything the lie would size is allocated.
 */
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/artifact.h"
#include "runtime/lod_io.h"
#include "runtime/lod_order.h"
#include "runtime/lod_pack.h"
#include "runtime/octree_io.h"
#include "tests/check.h"
#include "tests/unit/lod_format4.h"

#define ENTRY(body, i) ((unsigned char *)(body) + 8 + SL_PACK_TABLE_ENTRY * (i))

static void test_round_trip(void)
{
    /* Parts of every record size the model uses, one over two pieces long, tails that
     * are not whole records. */
    size_t big = 2 * SL_PACK_PIECE + 1000;
    float *wave = malloc(big);
    uint32_t *ids = malloc(4 * 300001);
    unsigned char *nodes = malloc(32 * 5000 + 7), head[37];
    CHECK(wave && ids && nodes);
    if (!wave || !ids || !nodes)
        return;
    for (size_t i = 0; i < big / 4; i++)
        wave[i] = (float)(i % 3) + 0.001f * (float)((i * 2654435761u) % 977);
    for (uint32_t i = 0; i < 300001; i++)
        ids[i] = i * 7 + (i * 2654435761u >> 28);
    for (size_t i = 0; i < sizeof head; i++)
        head[i] = (unsigned char)(i * 31);
    for (size_t i = 0; i < 32 * 5000 + 7; i++)
        nodes[i] = (unsigned char)(i % 32 < 12 ? i / 32 >> (i % 4 * 2) : i % 5);
    sl_pack_part parts[] = {{head, sizeof head, 0}, {wave, big - 2, 12}, {ids, 4 * 300001, 4},
                            {nodes, 32 * 5000 + 7, 32}, {ids, 4 * 1001, 8}, {head, 0, 4}};
    int count = (int)(sizeof parts / sizeof parts[0]);
    size_t plain = 0;
    for (int i = 0; i < count; i++)
        plain += parts[i].size;
    void *one = NULL, *two = NULL, *back = NULL;
    size_t one_size = 0, two_size = 0;
    omp_set_num_threads(1);
    CHECK(sl_pack(parts, count, &one, &one_size) == 0);
    omp_set_num_threads(2);
    CHECK(sl_pack(parts, count, &two, &two_size) == 0);
    CHECK_MSG(one && two && one_size == two_size && memcmp(one, two, one_size) == 0,
              "1 and 2 threads pack differently (%zu, %zu bytes)", one_size, two_size);
    CHECK_MSG(one_size < plain / 2, "packed %zu of %zu bytes", one_size, plain);
    CHECK_EQ_U64(sl_get_u32((unsigned char *)one + 4), 1 + 3 + 1 + 1 + 1); /* pieces */
    sl_error err;
    sl_error_init(&err);
    uint64_t back_size = 0;
    CHECK(sl_unpack(one, one_size, (uint64_t)1 << 40, "round trip", &back, &back_size, &err) == 0);
    CHECK_EQ_U64(back_size, plain);
    size_t at = 0;
    for (int i = 0; back && i < count; at += parts[i].size, i++)
        CHECK_MSG(memcmp((unsigned char *)back + at, parts[i].data, parts[i].size) == 0,
                  "part %d differs after the round trip", i);
    free(one);
    free(two);
    free(back);
    free(wave);
    free(ids);
    free(nodes);
}

static void *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    unsigned char *data = NULL;
    if (f && fseek(f, 0, SEEK_END) == 0) {
        long n = ftell(f);
        data = n > 0 ? malloc((size_t)n) : NULL;
        if (data && (fseek(f, 0, SEEK_SET) || fread(data, 1, (size_t)n, f) != (size_t)n)) {
            free(data);
            data = NULL;
        }
        *size = data ? (size_t)n : 0;
    }
    if (f)
        fclose(f);
    return data;
}

/* The body refused as corrupt, naming the file, for `cause`. */
static void expect_refused(const void *body, size_t size, const char *what, const char *cause)
{
    sl_lod_model m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_lod_model_parse(body, size, "hostile.slod", &m, &err);
    CHECK_MSG(rc == SL_E_CORRUPT && strstr(err.message, cause) &&
                  strcmp(err.file, "hostile.slod") == 0,
              "%s: parse gave %d (%s), expected corrupt: %s", what, rc, err.message, cause);
    if (rc == 0)
        sl_lod_model_release(&m);
}

/* The largest zstd piece of a packed body, and where its stored bytes start. */
static uint32_t largest_frame(const unsigned char *body, size_t *at)
{
    uint32_t count = sl_get_u32(body + 4), best = 0;
    size_t offset = 8 + (size_t)SL_PACK_TABLE_ENTRY * count, best_size = 0;
    for (uint32_t i = 0; i < count; i++) {
        size_t s = sl_get_u64(ENTRY(body, i) + 8);
        if (ENTRY(body, i)[16] == 1 && s > best_size) {
            best = i;
            best_size = s;
            *at = offset;
        }
        offset += s;
    }
    return best;
}

/* `damaged`: the cause for stored bytes that are not what was packed (format 5 checks
 * each piece before its frame is read; format 4 finds the frame's sizes wrong). */
static void test_hostile_bodies(const unsigned char *good, size_t size, const char *damaged)
{
    unsigned char *b = malloc(size + 1);
    if (!b)
        return;
    size_t at = 0;
    uint32_t i = largest_frame(good, &at);
    uint64_t plain = sl_get_u64(ENTRY(good, i)), stored = sl_get_u64(ENTRY(good, i) + 8);
    /* A frame cut short: the table still adds up (its stored size says so too). */
    memcpy(b, good, size);
    sl_put_u64(ENTRY(b, i) + 8, stored - 9);
    memmove(b + at + stored - 9, good + at + stored, size - at - stored);
    expect_refused(b, size - 9, "truncated frame", damaged);
    /* Plain sizes that are not the frame's: one byte more, one less, far more. */
    memcpy(b, good, size);
    sl_put_u64(ENTRY(b, i), plain + 1);
    expect_refused(b, size, "plain size one more", "frame sizes disagree with the table");
    sl_put_u64(ENTRY(b, i), plain - 1);
    expect_refused(b, size, "plain size one less", "frame sizes disagree with the table");
    sl_put_u64(ENTRY(b, i), (uint64_t)1 << 38);
    expect_refused(b, size, "plain size of 256 GiB", "plain size out of range");
    /* Garbage: the whole frame, then its blocks behind an intact frame header. */
    memcpy(b, good, size);
    for (uint64_t j = 0; j < stored; j++)
        b[at + j] = (unsigned char)(j * 2654435761u >> 13);
    expect_refused(b, size, "garbage frame", damaged);
    memcpy(b, good, size);
    for (uint64_t j = 12; j + 4 < stored; j++)
        b[at + j] = (unsigned char)(j * 2654435761u >> 11);
    expect_refused(b, size, "garbage blocks", "");
    /* Counts beyond the bytes, bytes beyond the pieces, an unknown codec. */
    memcpy(b, good, size);
    sl_put_u32(b + 4, 0x7fffffff);
    expect_refused(b, size, "piece count", "do not fit");
    memcpy(b, good, size);
    b[size] = 0;
    expect_refused(b, size + 1, "trailing byte", "after the last piece");
    ENTRY(b, i)[16] = 7;
    expect_refused(b, size, "unknown codec", "unknown codec");
    free(b);
}

/* Unpacked, the neighbour count in the LOD header raised by one, packed again (as the
 * format was: checked pieces for format 5). */
static void test_neighbour_count_lie(const unsigned char *good, size_t size)
{
    sl_error err;
    sl_error_init(&err);
    void *plain = NULL, *packed = NULL;
    uint64_t plain_size = 0;
    size_t packed_size = 0;
    CHECK(sl_unpack(good, size, (uint64_t)1 << 40, "good", &plain, &plain_size, &err) == 0);
    sl_octree t;
    sl_octree_layout lay;
    CHECK(plain && sl_octree_parse_header(plain, plain_size, "good", &t, &lay, &err) == 0);
    if (!plain || !lay.total)
        return;
    int checked = sl_get_u32(good) == SL_PACK_MAGIC_CHECKED; /* format 5: compact nodes */
    unsigned char *lod = (unsigned char *)plain +
                         (checked ? sl_lod_order_octree_size(&lay, t.node_count) : lay.total);
    sl_put_u64(lod + 8, sl_get_u64(lod + 8) + 1);
    sl_packer *pk = sl_packer_new(checked, 0);
    CHECK(pk && sl_packer_add(pk, plain, plain_size, 4) == 0 &&
          sl_packer_finish(pk, &packed, &packed_size) == 0);
    expect_refused(packed, packed_size, "neighbour count", "neighbour count differs");
    free(plain);
    free(packed);
}

/* memcmp that an empty cut (NULL arrays) may pass. */
static int same_bytes(const void *a, const void *b, size_t n)
{
    return n == 0 || memcmp(a, b, n) == 0;
}

/* The same meshes from both models at k. */
/* `m` written to a fresh temporary file named from `path` (a mkstemp template). */
static int write_again(char *path, const sl_lod_model *m, sl_error *err)
{
    int fd = mkstemp(path);
    if (fd >= 0)
        close(fd);
    return fd >= 0 ? sl_lod_model_write(path, m, 1, err) : -1;
}

/* tests/data/models/NAME read into *m; 0, or the reader's code. */
static int read_bundled(const char *name, char *path, size_t size, sl_lod_model *m,
                        sl_error *err)
{
    const char *src = getenv("SCANLOD_SOURCE_DIR");
    snprintf(path, size, "%s/tests/data/models/%s", src ? src : ".", name);
    return sl_lod_model_read(path, m, err);
}

static void check_same_cut(sl_lod_model *a, sl_lod_model *b, uint32_t k)
{
    sl_lod_mesh x, y;
    CHECK(sl_lod_generate(a, k, &x, NULL) == 0 && sl_lod_generate(b, k, &y, NULL) == 0);
    CHECK_MSG(x.triangle_count == y.triangle_count && x.vertex_count == y.vertex_count &&
                  same_bytes(x.positions, y.positions, 12 * (size_t)x.vertex_count) &&
                  same_bytes(x.indices, y.indices, 12 * (size_t)x.triangle_count),
              "k %u: %llu / %llu triangles", k, (unsigned long long)x.triangle_count,
              (unsigned long long)y.triangle_count);
    sl_lod_mesh_release(&x);
    sl_lod_mesh_release(&y);
}

/* A model opened for cutting (sl_lod_model_open), from format 3 (rebuilt table) and
 * format 2 (stored table): every cut the same as the full reader's, holding no neighbour
 * table, node records but the root, Morton keys, expansion indices or transition bases
 * (sl_lod_model_prepare), the header's neighbour count kept; the writer refuses it. */
static void test_opened(const char *v2, const char *v3, sl_lod_model *full)
{
    const char *files[2] = {v3, v2};
    for (int f = 0; f < 2; f++) {
        sl_error err;
        sl_error_init(&err);
        sl_lod_model opened;
        int rc = sl_lod_model_open(files[f], &opened, &err);
        CHECK_MSG(rc == 0, "open %s: %s", files[f], err.message);
        if (rc)
            continue;
        CHECK_MSG(!opened.neighbours.mask && !opened.neighbours.index &&
                      opened.neighbour_links == full->neighbours.count,
                  "opened: table held or count %llu lost", (unsigned long long)opened.neighbour_links);
        CHECK(!opened.tree.morton && !opened.expansion_index && !opened.transitions.base);
        for (uint32_t k = 0; k <= full->expansion_count; k++)
            check_same_cut(full, &opened, k);
        char again[] = "/tmp/scanlod-test-pack-open-XXXXXX";
        sl_error_init(&err);
        CHECK(write_again(again, &opened, &err) == SL_E_INTERNAL);
        unlink(again);
        sl_lod_model_release(&opened);
    }
}

static void test_real_model(void)
{
    char v2[4096], v3[] = "/tmp/scanlod-test-pack-XXXXXX";
    sl_error err;
    sl_error_init(&err);
    sl_lod_model old, now;
    int rc = read_bundled("bun_zipper_res4-v2.slod", v2, sizeof v2, &old, &err);
    CHECK_MSG(rc == 0, "format 2 model: %s", err.message);
    if (rc)
        return;
    CHECK(write_again(v3, &old, &err) == 0);
    size_t v2_size = 0, v3_size = 0;
    unsigned char *file2 = slurp(v2, &v2_size), *file3 = slurp(v3, &v3_size);
    CHECK(file2 && file3 && sl_get_u32(file3 + 8) == SL_LOD_FORMAT_VERSION);
    CHECK_MSG(v3_size * 8 < v2_size, "format 3: %zu bytes, format 2: %zu", v3_size, v2_size);
    printf("bun_zipper_res4: format 2 %zu bytes, written again as format %u %zu bytes\n", v2_size,
           SL_LOD_FORMAT_VERSION, v3_size);
    rc = sl_lod_model_read(v3, &now, &err);
    CHECK_MSG(rc == 0, "format 3 model: %s", err.message);
    if (rc == 0) {
        const sl_neighbours *a = &old.neighbours, *b = &now.neighbours;
        uint32_t n = old.tree.node_count;
        CHECK_MSG(a->count == b->count && same_bytes(a->mask, b->mask, 4 * (size_t)n) &&
                      same_bytes(a->base, b->base, 4 * (size_t)n) &&
                      same_bytes(a->index, b->index, 4 * a->count),
                  "rebuilt neighbour table differs from the stored one");
        uint32_t e = old.expansion_count;
        uint32_t ks[] = {0, 1, e / 3, e / 2, e - 1, e};
        for (int i = 0; i < 6; i++)
            check_same_cut(&old, &now, ks[i]);
        test_opened(v2, v3, &now);
        sl_lod_model_release(&now);
    }
    char v4[] = "/tmp/scanlod-test-pack-v4-XXXXXX";
    int fd4 = mkstemp(v4);
    if (fd4 >= 0)
        close(fd4);
    size_t v4_size = 0;
    unsigned char *file4 = NULL;
    CHECK(fd4 >= 0 && write_format4(v4, &old, &err) == 0 && (file4 = slurp(v4, &v4_size)));
    if (file3 && file4) {
        test_hostile_bodies(file3 + SL_ARTIFACT_HEADER_SIZE, v3_size - SL_ARTIFACT_HEADER_SIZE,
                            "checksum mismatch");
        test_hostile_bodies(file4 + SL_ARTIFACT_HEADER_SIZE, v4_size - SL_ARTIFACT_HEADER_SIZE,
                            "frame sizes disagree with the table");
        test_neighbour_count_lie(file3 + SL_ARTIFACT_HEADER_SIZE,
                                 v3_size - SL_ARTIFACT_HEADER_SIZE);
        test_neighbour_count_lie(file4 + SL_ARTIFACT_HEADER_SIZE,
                                 v4_size - SL_ARTIFACT_HEADER_SIZE);
        /* Envelopes of the other version: a packed body called format 2, a plain one
         * called format 3, format 5's body called 4 and format 4's called 5, and a format
         * from the future. */
        struct { uint32_t version; const unsigned char *body; size_t size; const char *cause; }
        cases[] = {{2, file3 + 32, v3_size - 32, "packed parts in a format 2 file"},
                   {3, file2 + 32, v2_size - 32, "format 3 without packed parts"},
                   {4, file3 + 32, v3_size - 32, "checked pieces in a format 3 or 4 file"},
                   {5, file4 + 32, v4_size - 32, "format 5 without checked pieces"},
                   {6, file3 + 32, v3_size - 32, "reads versions 2 to 5"}};
        for (int i = 0; i < 5 && file2; i++) {
            sl_artifact_part part = {cases[i].body, cases[i].size};
            CHECK(sl_artifact_write(v3, SL_LOD_MAGIC, cases[i].version, 1, &part, 1, &err) == 0);
            sl_error_init(&err);
            rc = sl_lod_model_read(v3, &now, &err);
            CHECK_MSG(rc == SL_E_CORRUPT && strstr(err.message, cases[i].cause),
                      "envelope %u: %d (%s)", cases[i].version, rc, err.message);
            if (rc == 0)
                sl_lod_model_release(&now);
        }
    }
    free(file2);
    free(file3);
    free(file4);
    unlink(v3);
    unlink(v4);
    sl_lod_model_release(&old);
}

/* With SCANLOD_SLOD_SEED_DIR=dir: the fuzz seed tiny-error (a plain body of format 2)
 * written again: dir/tiny-packed as format 4 and dir/tiny-ordered as format 5 (the
 * writer's) write it (tests/fuzz/README.md). */
static void write_packed_seed(const char *dir)
{
    char in[1200], out[1200], tmp[] = "/tmp/scanlod-test-pack-seed-XXXXXX";
    snprintf(in, sizeof in, "%s/tiny-error", dir);
    size_t size = 0;
    unsigned char *body = slurp(in, &size);
    sl_lod_model m;
    sl_error err;
    sl_error_init(&err);
    CHECK(body && sl_lod_model_parse(body, size, in, &m, &err) == 0);
    for (int format = 4; format <= 5; format++) {
        size_t file_size = 0;
        snprintf(out, sizeof out, "%s/%s", dir, format == 4 ? "tiny-packed" : "tiny-ordered");
        if (format == 4) {
            int fd = mkstemp(tmp);
            if (fd >= 0)
                close(fd);
            CHECK(fd >= 0 && write_format4(tmp, &m, &err) == 0);
        } else {
            CHECK(write_again(tmp, &m, &err) == 0);
        }
        unsigned char *file = slurp(tmp, &file_size);
        FILE *f = fopen(out, "wb");
        CHECK(file && f && fwrite(file + 32, 1, file_size - 32, f) == file_size - 32);
        if (f)
            fclose(f);
        unlink(tmp);
        memcpy(tmp + strlen(tmp) - 6, "XXXXXX", 6);
        free(file);
    }
    free(body);
    sl_lod_model_release(&m);
}

/* A format 3 model with quadric vertices (its octree with the node errors and areas; made
 * by the crack stage version 4, tests/data/models/README.md) is read, without those
 * arrays, and cuts the same as that model written again as format 4 and as format 5,
 * which leave them out (docs/formats.md): smaller files. */
static void test_format3_quadric_model(void)
{
    char v3[4096], v4[] = "/tmp/scanlod-test-pack-v4-XXXXXX";
    sl_error err;
    sl_error_init(&err);
    sl_lod_model old, now;
    int rc = read_bundled("bun_zipper_res4-v3.slod", v3, sizeof v3, &old, &err);
    CHECK_MSG(rc == 0, "format 3 quadric model: %s", err.message);
    if (rc)
        return;
    CHECK(sl_octree_dual(&old.tree) && !old.tree.node_error && !old.tree.node_area);
    char v5[] = "/tmp/scanlod-test-pack-v5-XXXXXX";
    CHECK(write_again(v5, &old, &err) == 0);
    int fd = mkstemp(v4);
    if (fd >= 0)
        close(fd);
    CHECK(fd >= 0 && write_format4(v4, &old, &err) == 0);
    size_t size3 = 0, size4 = 0, size5 = 0;
    unsigned char *file3 = slurp(v3, &size3), *file4 = slurp(v4, &size4), *file5 = slurp(v5, &size5);
    CHECK(file3 && file4 && file5 && sl_get_u32(file3 + 8) == 3 && sl_get_u32(file4 + 8) == 4 &&
          sl_get_u32(file5 + 8) == 5);
    CHECK_MSG(size4 * 10 < size3 * 9 && size5 * 10 < size3 * 9,
              "format 5: %zu bytes, 4: %zu, 3: %zu", size5, size4, size3);
    printf("bun_zipper_res4 (quadric vertices): format 3 %zu bytes, format 4 %zu, format 5 %zu\n",
           size3, size4, size5);
    free(file3);
    free(file4);
    free(file5);
    const char *written[2] = {v4, v5};
    for (int f = 0; f < 2; f++) {
        rc = sl_lod_model_read(written[f], &now, &err);
        CHECK_MSG(rc == 0, "format %d model: %s", 4 + f, err.message);
        if (rc == 0) {
            for (uint32_t k = 0; k <= old.expansion_count; k++)
                check_same_cut(&old, &now, k);
            sl_lod_model_release(&now);
        }
    }
    unlink(v4);
    unlink(v5);
    sl_lod_model_release(&old);
}

int main(void)
{
    const char *seed_dir = getenv("SCANLOD_SLOD_SEED_DIR");
    if (seed_dir && seed_dir[0]) {
        write_packed_seed(seed_dir);
        return check_report();
    }
    test_round_trip();
    test_real_model();
    test_format3_quadric_model();
    return check_report();
}
