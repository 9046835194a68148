/* Model format 5 cut by prefixes (runtime/lod_prefix.h, lod_order.h): the bundled models
 * (marching-cube and quadric-vertex ones), written as format 5 in small pieces so every
 * section spans many, give at every k -- from a fresh open, stepping up on one open file,
 * through the public API -- the very mesh the whole model gives, while holding only a
 * prefix of its nodes; the level tables and bounds are the whole model's; a damaged piece
 * past the prefix a cut needs leaves that cut alone and fails the one that reads it, naming
 * the file; LOD arrays, child masks and crossing codes (a distance, an entry of the parent's
 * record) that do not make one tree are refused on both paths.
 */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/artifact.h"
#include "runtime/lod_io.h"
#include "runtime/lod_order.h"
#include "runtime/lod_pack.h"
#include "runtime/lod_prefix.h"
#include "scanlod/scanlod.h"
#include "tests/check.h"

#define SMALL_PIECE 4096

static int same_bytes(const void *a, const void *b, size_t n)
{
    return n == 0 || memcmp(a, b, n) == 0;
}

static int same_mesh(const sl_lod_mesh *x, const sl_lod_mesh *y)
{
    return x->triangle_count == y->triangle_count && x->vertex_count == y->vertex_count &&
           same_bytes(x->positions, y->positions, 12 * (size_t)x->vertex_count) &&
           same_bytes(x->normals, y->normals, 12 * (size_t)x->vertex_count) &&
           same_bytes(x->indices, y->indices, 12 * (size_t)x->triangle_count);
}

/* The cut at k of `cut` (a prefix model) equals the whole model's. */
static void check_cut(sl_lod_model *whole, sl_lod_model *cut, uint32_t k, const char *what)
{
    sl_lod_mesh x, y;
    CHECK(sl_lod_generate(whole, k, &x, NULL) == 0 && sl_lod_generate(cut, k, &y, NULL) == 0);
    CHECK_MSG(same_mesh(&x, &y), "%s, k %u: %llu / %llu triangles, %llu / %llu vertices", what,
              k, (unsigned long long)x.triangle_count, (unsigned long long)y.triangle_count,
              (unsigned long long)x.vertex_count, (unsigned long long)y.vertex_count);
    sl_lod_mesh_release(&x);
    sl_lod_mesh_release(&y);
}

static int write_body(const char *path, const void *body, size_t size)
{
    sl_error err;
    sl_error_init(&err);
    sl_artifact_part part = {body, size};
    return sl_artifact_write(path, SL_LOD_MAGIC, SL_LOD_FORMAT_VERSION, 1, &part, 1, &err);
}

static int write_small_pieces(const char *path, const sl_lod_model *m)
{
    void *body = NULL;
    size_t size = 0;
    int rc = sl_lod_order_pack(m, SMALL_PIECE, &body, &size);
    if (rc == 0)
        rc = write_body(path, body, size);
    free(body);
    return rc;
}

static void temp_path(char *path)
{
    int fd = mkstemp(path);
    if (fd >= 0)
        close(fd);
}

static void test_levels(sl_lod_file *f, const sl_lod_model *whole)
{
    const sl_lod_model *l = sl_lod_file_levels(f);
    uint32_t e = whole->expansion_count;
    CHECK(l->expansion_count == e &&
          same_bytes(l->accumulation, whole->accumulation, 8 * ((size_t)e + 1)) &&
          same_bytes(l->error_after, whole->error_after, 4 * ((size_t)e + 1)) &&
          same_bytes(l->surface_before, whole->surface_before, 4 * ((size_t)e + 1)));
    float lo[3], hi[3];
    sl_lod_file_bounds(f, lo, hi);
    const sl_octree *t = &whole->tree;
    int inside = 1, touched[6] = {0};
    for (uint32_t i = 0; i < t->crossing_count; i++)
        for (int a = 0; a < 3; a++) {
            float v = t->crossing_position[3 * (size_t)i + a];
            inside &= v >= lo[a] && v <= hi[a];
            touched[a] |= v == lo[a];
            touched[3 + a] |= v == hi[a];
        }
    CHECK_MSG(inside && touched[0] && touched[1] && touched[2] && touched[3] && touched[4] &&
                  touched[5],
              "bounds are not the crossings' box");
}

/* Every k of a spread, from a fresh open each, then stepping up on one open file. */
static void test_cuts(const char *path, sl_lod_model *whole, const char *what)
{
    uint32_t e = whole->expansion_count;
    uint32_t ks[] = {0, 1, 2, e / 50, e / 10, e / 3, e / 2, e - 1, e};
    sl_error err;
    sl_error_init(&err);
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; i++) {
        sl_lod_file *f = NULL;
        sl_lod_model *cut = NULL;
        int rc = sl_lod_file_open(path, &f, &err);
        CHECK_MSG(rc == 0, "%s: open: %s", what, err.message);
        if (rc)
            return;
        if (i == 0)
            test_levels(f, whole);
        rc = sl_lod_file_reach(f, ks[i], &cut, &err);
        CHECK_MSG(rc == 0, "%s: reach %u: %s", what, ks[i], err.message);
        if (rc == 0) {
            CHECK(sl_lod_file_reached(f) >= ks[i] && cut->expansion_count == sl_lod_file_reached(f));
            /* A prefix: a small level holds a small part of the tree. */
            if (ks[i] <= e / 10)
                CHECK_MSG(cut->tree.node_count * 4 < whole->tree.node_count,
                          "%s: k %u holds %u of %u nodes", what, ks[i], cut->tree.node_count,
                          whole->tree.node_count);
            check_cut(whole, cut, ks[i], what);
        }
        sl_lod_file_close(f);
    }
    sl_lod_file *f = NULL;
    CHECK(sl_lod_file_open(path, &f, &err) == 0);
    for (size_t i = 0; f && i < sizeof ks / sizeof ks[0]; i++) {
        sl_lod_model *cut = NULL;
        int rc = sl_lod_file_reach(f, ks[i], &cut, &err);
        CHECK_MSG(rc == 0, "%s: stepping to %u: %s", what, ks[i], err.message);
        if (rc == 0)
            check_cut(whole, cut, ks[i], "stepping up");
    }
    sl_lod_file_close(f);
}

/* The public API on the same file: counts and meshes of the whole model. */
static void test_api(const char *path, sl_lod_model *whole)
{
    scanlod_model *m = NULL;
    char why[256] = "";
    CHECK_MSG(scanlod_model_open(path, &m, why, sizeof why) == 0, "api open: %s", why);
    if (!m)
        return;
    uint32_t e = whole->expansion_count, k = e / 4;
    CHECK(scanlod_model_expansions(m) == e);
    CHECK(scanlod_expansions_for_triangles(m, 300) == sl_lod_expansions_for_triangles(whole, 300));
    CHECK(scanlod_expansions_for_percent(m, 37) == sl_lod_expansions_for_percent(whole, 37));
    scanlod_mesh_bound b = scanlod_extract_bound(m, k), got;
    float *pos = malloc(12 * (b.vertices + 1));
    uint32_t *idx = malloc(12 * (b.triangles + 1));
    sl_lod_mesh x;
    CHECK(pos && idx && scanlod_extract(m, k, pos, NULL, NULL, idx, &got) == 0);
    CHECK(sl_lod_generate(whole, k, &x, NULL) == 0);
    CHECK_MSG(got.triangles == x.triangle_count && got.vertices == x.vertex_count &&
                  same_bytes(pos, x.positions, 12 * (size_t)x.vertex_count) &&
                  same_bytes(idx, x.indices, 12 * (size_t)x.triangle_count),
              "api cut at %u differs", k);
    sl_lod_mesh_release(&x);
    free(pos);
    free(idx);
    scanlod_model_free(m);
}

/* The last piece's stored bytes changed: what comes before it still cuts; the finest
 * level, which reads it, fails naming the file and the piece's check. */
static void test_damaged_piece(const char *path, sl_lod_model *whole)
{
    FILE *fp = fopen(path, "r+b");
    CHECK(fp != NULL);
    if (!fp)
        return;
    CHECK(fseek(fp, -3, SEEK_END) == 0);
    int c = fgetc(fp);
    CHECK(fseek(fp, -3, SEEK_END) == 0 && fputc(c ^ 0x5a, fp) != EOF);
    fclose(fp);
    sl_error err;
    sl_error_init(&err);
    sl_lod_file *f = NULL;
    sl_lod_model *cut = NULL;
    CHECK_MSG(sl_lod_file_open(path, &f, &err) == 0, "damaged: open: %s", err.message);
    if (!f)
        return;
    CHECK_MSG(sl_lod_file_reach(f, 1, &cut, &err) == 0, "damaged: small cut: %s", err.message);
    if (cut)
        check_cut(whole, cut, 1, "before the damage");
    int rc = sl_lod_file_reach(f, whole->expansion_count, &cut, &err);
    CHECK_MSG(rc == SL_E_CORRUPT && strstr(err.message, "checksum mismatch") &&
                  strcmp(err.file, path) == 0,
              "damaged: finest cut gave %d (%s)", rc, err.message);
    sl_lod_file_close(f);
    sl_lod_model back;
    sl_error_init(&err);
    rc = sl_lod_model_read(path, &back, &err);
    CHECK_MSG(rc == SL_E_CORRUPT, "damaged: whole read gave %d (%s)", rc, err.message);
    if (rc == 0)
        sl_lod_model_release(&back);
}

/* Plain body edits, packed again section by section as the writer does: refused by the
 * whole reader and by a prefix cut (what it checks as it reads). */
static void expect_rc(const unsigned char *plain, const sl_lod_sections *sec, const char *path,
                      const char *what, int want)
{
    sl_packer *pk = sl_packer_new(1, SMALL_PIECE);
    void *body = NULL;
    size_t body_size = 0;
    int packed = pk != NULL;
    for (int s = 0; packed && s < SL_SEC_COUNT; s++)
        packed = sl_packer_add(pk, plain + sec->at[s], sec->size[s],
                               s == SL_SEC_OCTREE_HEADER || s == SL_SEC_LOD_HEADER ? 0 : 4) == 0;
    CHECK(packed && sl_packer_finish(pk, &body, &body_size) == 0);
    sl_lod_model m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_lod_model_parse(body, body_size, "hostile.slod", &m, &err);
    CHECK_MSG(rc == want, "%s: whole read gave %d (%s)", what, rc, err.message);
    if (rc == 0)
        sl_lod_model_release(&m);
    CHECK(write_body(path, body, body_size) == 0);
    free(body);
    sl_lod_file *f = NULL;
    sl_lod_model *cut = NULL;
    sl_error_init(&err);
    rc = sl_lod_file_open(path, &f, &err);
    if (rc == 0)
        rc = sl_lod_file_reach(f, UINT32_MAX, &cut, &err);
    CHECK_MSG(rc == want, "%s: prefix read gave %d (%s)", what, rc, err.message);
    sl_lod_file_close(f);
}

static void test_hostile_trees(const sl_lod_model *whole, const char *path)
{
    void *body = NULL, *plain = NULL;
    size_t size = 0;
    uint64_t plain_size = 0;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_lod_order_pack(whole, SMALL_PIECE, &body, &size) == 0);
    CHECK(body && sl_unpack(body, size, (uint64_t)1 << 40, "good", &plain, &plain_size, &err) == 0);
    free(body);
    if (!plain)
        return;
    sl_octree head;
    sl_octree_layout lay;
    sl_lod_sections sec;
    unsigned char *p = plain;
    CHECK(sl_octree_parse_header(p, plain_size, "good", &head, &lay, &err) == 0);
    CHECK(sl_lod_order_sections(&head, &lay, p + sl_lod_order_octree_size(&lay, head.node_count),
                                plain_size, "good", &sec, &err) == 0);
    /* Unedited, it reads: the repacking is the writer's. */
    unsigned char *copy = malloc(plain_size);
    if (!copy) {
        free(plain);
        return;
    }
    expect_rc(p, &sec, path, "unedited", 0);
    /* The 2nd expansion names a position no earlier expansion reached. */
    memcpy(copy, p, plain_size);
    sl_put_u32(copy + sec.at[SL_SEC_LOD_ARRAY] + 4, sec.nodes - 1);
    expect_rc(copy, &sec, path, "expansion of an unreached node", SL_E_CORRUPT);
    /* A leaf claiming children. */
    memcpy(copy, p, plain_size);
    unsigned char *last = copy + sec.at[SL_SEC_NODES] + SL_LOD_ORDER_NODE * ((size_t)sec.nodes - 1);
    last[1] = 0xff;
    expect_rc(copy, &sec, path, "leaf with children", SL_E_CORRUPT);
    /* Cells name their parent's record's ids (most of a model's codes): one past any
     * record (at most 48 ids). */
    size_t ids = sec.size[SL_SEC_IDS] / 4, from_parent = 0, first = 0;
    for (size_t i = 0; i < ids; i++)
        if (sl_get_u32(p + sec.at[SL_SEC_IDS] + 4 * i) & SL_LOD_ORDER_FROM_PARENT)
            if (!from_parent++)
                first = i;
    CHECK_MSG(from_parent * 4 > ids, "%zu of %zu codes name the parent's record", from_parent, ids);
    memcpy(copy, p, plain_size);
    sl_put_u32(copy + sec.at[SL_SEC_IDS] + 4 * first, SL_LOD_ORDER_FROM_PARENT | 63);
    expect_rc(copy, &sec, path, "a parent's record entry it does not have", SL_E_CORRUPT);
    /* Two records over each other: the second position with a record takes the first's. */
    memcpy(copy, p, plain_size);
    uint32_t with_record[2], found = 0;
    for (uint32_t i = 0; i < sec.nodes && found < 2; i++)
        if (sl_get_u32(p + sec.at[SL_SEC_TRANSITION_BASE] + 4 * (size_t)i) != SL_OCTREE_NONE)
            with_record[found++] = i;
    CHECK(found == 2);
    if (found == 2) {
        sl_put_u32(copy + sec.at[SL_SEC_TRANSITION_BASE] + 4 * (size_t)with_record[1],
                   sl_get_u32(p + sec.at[SL_SEC_TRANSITION_BASE] + 4 * (size_t)with_record[0]));
        expect_rc(copy, &sec, path, "records over each other", SL_E_CORRUPT);
    }
    /* A crossing code reaching before the first id. */
    memcpy(copy, p, plain_size);
    sl_put_u32(copy + sec.at[SL_SEC_IDS] + 4 * (sec.size[SL_SEC_IDS] / 4 - 1), 0x7fffffff);
    expect_rc(copy, &sec, path, "crossing code out of range", SL_E_CORRUPT);
    free(copy);
    free(plain);
}

static void test_model(const char *name)
{
    const char *src = getenv("SCANLOD_SOURCE_DIR");
    char in[4096], small[] = "/tmp/scanlod-test-prefix-XXXXXX", plain[] = "/tmp/scanlod-test-prefix-XXXXXX";
    snprintf(in, sizeof in, "%s/tests/data/models/%s", src ? src : ".", name);
    sl_lod_model whole;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_lod_model_read(in, &whole, &err);
    CHECK_MSG(rc == 0, "%s: %s", name, err.message);
    if (rc)
        return;
    temp_path(small);
    temp_path(plain);
    CHECK(write_small_pieces(small, &whole) == 0);
    CHECK(sl_lod_model_write(plain, &whole, 1, &err) == 0);
    test_cuts(small, &whole, name);
    test_cuts(plain, &whole, name);
    test_api(small, &whole);
    test_hostile_trees(&whole, plain);
    test_damaged_piece(small, &whole);
    unlink(small);
    unlink(plain);
    sl_lod_model_release(&whole);
}

int main(void)
{
    test_model("bun_zipper_res4-v2.slod");
    test_model("bun_zipper_res4-v3.slod");
    return check_report();
}
