/* PLY reader: every encoding, scalar type, layout and convention the reader promises
 * (formats/ply.h), each written by tests/unit/ply_builder.h in ascii, binary LE and
 * binary BE and read back through both sl_ply_read (mmap) and sl_ply_read_memory; the
 * three encodings must give the same, exactly expected mesh.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "tests/check.h"
#include "formats/ply.h"
#include "tests/unit/ply_builder.h"

static char tmpdir[256];
static int files_written;

static int arrays_equal(const void *a, const void *b, size_t n)
{
    return (!a && !b) || (a && b && memcmp(a, b, n) == 0);
}

static int meshes_equal(const sl_mesh *a, const sl_mesh *b)
{
    uint64_t v = a->vertex_count, t = a->triangle_count;
    uint64_t cells = (uint64_t)a->grid_cols * a->grid_rows;
    return v == b->vertex_count && t == b->triangle_count &&
           arrays_equal(a->positions, b->positions, 12 * v) &&
           arrays_equal(a->normals, b->normals, 12 * v) &&
           arrays_equal(a->colors, b->colors, 4 * v) &&
           arrays_equal(a->texcoords, b->texcoords, 8 * v) &&
           arrays_equal(a->triangles, b->triangles, 12 * t) &&
           arrays_equal(a->face_texcoords, b->face_texcoords, 24 * t) &&
           a->grid_cols == b->grid_cols && a->grid_rows == b->grid_rows &&
           arrays_equal(a->grid_index, b->grid_index, 8 * cells) &&
           strcmp(a->texture_file, b->texture_file) == 0 &&
           a->has_viewpoint == b->has_viewpoint &&
           memcmp(a->viewpoint, b->viewpoint, sizeof a->viewpoint) == 0 &&
           memcmp(&a->stats, &b->stats, sizeof a->stats) == 0;
}

/* Reads b from memory and (every file, as `name`) through sl_ply_read; both must agree. */
static int read_case(const plyb *b, const char *name, sl_mesh *m, sl_error *err)
{
    char path[1024], fname[200];
    sl_error_init(err);
    int rc = sl_ply_read_memory(b->buf, b->len, name, NULL, m, NULL, err);
    snprintf(fname, sizeof fname, "%s.%s.ply", name, plyb_format_name(b->format));
    plyb_save(b, tmpdir, fname, path, sizeof path);
    files_written++;
    sl_mesh from_file;
    sl_error ferr;
    sl_error_init(&ferr);
    int frc = sl_ply_read(path, NULL, &from_file, NULL, NULL, &ferr);
    CHECK_MSG(frc == rc && meshes_equal(m, &from_file), "%s: file and memory reads differ", fname);
    CHECK_MSG(rc == 0, "%s: %s", fname, err->message);
    sl_mesh_release(&from_file);
    unlink(path);
    return rc;
}

/* Every scalar type name for x y z; face lists of every count and index type. */
static void test_scalar_types(int format)
{
    for (int i = 0; i < PLYB_NTYPES; i++) {
        const struct plyb_type *t = &plyb_types[i];
        for (int j = 0; j < PLYB_NTYPES; j++) {
            const struct plyb_type *ct = &plyb_types[j];
            const struct plyb_type *it = &plyb_types[(i + j) % PLYB_NTYPES];
            if (ct->is_float)
                continue;
            if (it->is_float)
                it = &plyb_types[j];
            plyb b;
            plyb_init(&b, format);
            plyb_begin(&b);
            plyb_text(&b, "element vertex 4\nproperty %s x\nproperty %s y\nproperty %s z\n"
                          "element face 2\nproperty list %s %s vertex_indices\nend_header\n",
                      t->name, t->name, t->name, ct->name, it->name);
            float expect[12];
            for (int v = 0; v < 4; v++) {
                expect[3 * v] = (float)(v + 1);
                expect[3 * v + 1] = t->is_signed ? (float)-(v + 2) : (float)(v + 2);
                expect[3 * v + 2] = t->is_float ? 0.5f + (float)v : (float)(100 + v);
                for (int c = 0; c < 3; c++)
                    plyb_val(&b, t->name, expect[3 * v + c]);
                plyb_eol(&b);
            }
            const int faces[] = {3, 0, 1, 2, 4, 3, 2, 1, 0};
            for (int k = 0; k < 9; k++) {
                plyb_val(&b, k == 0 || k == 4 ? ct->name : it->name, faces[k]);
                if (k == 3 || k == 8)
                    plyb_eol(&b);
            }
            const uint32_t tris[] = {0, 1, 2, 3, 2, 1, 3, 1, 0};
            sl_mesh m;
            sl_error err;
            char name[96];
            snprintf(name, sizeof name, "types_%s_%s_%s", t->name, ct->name, it->name);
            if (read_case(&b, name, &m, &err) == 0) {
                CHECK_EQ_U64(m.vertex_count, 4);
                CHECK_MSG(memcmp(m.positions, expect, sizeof expect) == 0, "%s positions", name);
                CHECK_EQ_U64(m.triangle_count, 3);
                CHECK_MSG(memcmp(m.triangles, tris, sizeof tris) == 0, "%s triangles", name);
                CHECK_EQ_U64(m.stats.polygons_triangulated, 1);
                CHECK(!m.normals && !m.colors && !m.texcoords && !m.face_texcoords);
            }
            sl_mesh_release(&m);
            plyb_free(&b);
        }
    }
}

/* Properties in odd order, skipped scalars and lists, extra elements before, between
 * and after, normals, uchar colours, u/v, per-face texcoords, TextureFile, a camera. */
static void test_everything_shuffled(int format)
{
    plyb b;
    plyb_init(&b, format);
    plyb_begin(&b);
    plyb_text(&b, "comment made by test_ply\ncomment TextureFile skin map.png\n"
                  "element material 2\nproperty uchar ambient_red\nproperty float power\n"
                  "element vertex 4\nproperty uchar green\nproperty float v\nproperty double z\n"
                  "property float nx\nproperty int confidence\nproperty float x\n"
                  "property uchar alpha\nproperty float ny\nproperty list uchar int extra\n"
                  "property float u\nproperty short y\nproperty float nz\nproperty uchar red\n"
                  "property uchar blue\n"
                  "element edge 2\nproperty int vertex1\nproperty list uchar uint path\n"
                  "element face 2\nproperty uchar flags\nproperty list uchar float texcoord\n"
                  "property list ushort uint vertex_indices\nproperty list uchar int extra2\n"
                  "obj_info some note\n"
                  "element camera 1\nproperty float view_px\nproperty float view_py\n"
                  "property float view_pz\nproperty float x_axisx\nend_header\n");
    for (int i = 0; i < 2; i++) {
        plyb_val(&b, "uchar", 10 * i);
        plyb_val(&b, "float", 1.25);
        plyb_eol(&b);
    }
    float pos[12], nrm[12], uv[8];
    uint8_t col[16];
    for (int i = 0; i < 4; i++) {
        pos[3 * i] = 0.1f * (float)i - 1.0f;
        pos[3 * i + 1] = (float)(i * 7 - 3);
        pos[3 * i + 2] = 1e-3f * (float)(i * i) + 2.0f;
        nrm[3 * i] = (float)i / 3.0f, nrm[3 * i + 1] = -0.5f, nrm[3 * i + 2] = 0.25f * (float)i;
        uv[2 * i] = 0.125f * (float)i, uv[2 * i + 1] = 1.0f - 0.125f * (float)i;
        col[4 * i] = (uint8_t)(i * 60), col[4 * i + 1] = (uint8_t)(255 - i);
        col[4 * i + 2] = (uint8_t)(i + 1), col[4 * i + 3] = (uint8_t)(200 + i);
        plyb_val(&b, "uchar", col[4 * i + 1]);
        plyb_val(&b, "float", uv[2 * i + 1]);
        plyb_val(&b, "double", pos[3 * i + 2]);
        plyb_val(&b, "float", nrm[3 * i]);
        plyb_val(&b, "int", -7 * i);
        plyb_val(&b, "float", pos[3 * i]);
        plyb_val(&b, "uchar", col[4 * i + 3]);
        plyb_val(&b, "float", nrm[3 * i + 1]);
        plyb_val(&b, "uchar", i);
        for (int k = 0; k < i; k++)
            plyb_val(&b, "int", 1000 + k);
        plyb_val(&b, "float", uv[2 * i]);
        plyb_val(&b, "short", pos[3 * i + 1]);
        plyb_val(&b, "float", nrm[3 * i + 2]);
        plyb_val(&b, "uchar", col[4 * i]);
        plyb_val(&b, "uchar", col[4 * i + 2]);
        plyb_eol(&b);
    }
    for (int i = 0; i < 2; i++) {
        plyb_val(&b, "int", i);
        plyb_val(&b, "uchar", 3);
        for (int k = 0; k < 3; k++)
            plyb_val(&b, "uint", k);
        plyb_eol(&b);
    }
    /* face 0: triangle with texcoords; face 1: quad with texcoords (two triangles) */
    const float ftc[2][8] = {{0, 0, 1, 0, 1, 1}, {0.5f, 0.5f, 0.25f, 0.75f, 0.125f, 0.0625f, 1, 0}};
    const int corners[2][4] = {{0, 1, 2}, {3, 2, 1, 0}};
    for (int f = 0; f < 2; f++) {
        int n = f == 0 ? 3 : 4;
        plyb_val(&b, "uchar", 1);
        plyb_val(&b, "uchar", 2 * n);
        for (int k = 0; k < 2 * n; k++)
            plyb_val(&b, "float", ftc[f][k]);
        plyb_val(&b, "ushort", n);
        for (int k = 0; k < n; k++)
            plyb_val(&b, "uint", corners[f][k]);
        plyb_val(&b, "uchar", 1);
        plyb_val(&b, "int", -5);
        plyb_eol(&b);
    }
    plyb_val(&b, "float", 10.5);
    plyb_val(&b, "float", -20.25);
    plyb_val(&b, "float", 30);
    plyb_val(&b, "float", 1);
    plyb_eol(&b);

    sl_mesh m;
    sl_error err;
    if (read_case(&b, "shuffled", &m, &err) == 0) {
        CHECK_EQ_U64(m.vertex_count, 4);
        CHECK(memcmp(m.positions, pos, sizeof pos) == 0);
        CHECK(m.normals && memcmp(m.normals, nrm, sizeof nrm) == 0);
        CHECK(m.colors && memcmp(m.colors, col, sizeof col) == 0);
        CHECK(m.texcoords && memcmp(m.texcoords, uv, sizeof uv) == 0);
        const uint32_t tris[] = {0, 1, 2, 3, 2, 1, 3, 1, 0};
        CHECK_EQ_U64(m.triangle_count, 3);
        CHECK(memcmp(m.triangles, tris, sizeof tris) == 0);
        const float tc[] = {0, 0, 1, 0, 1, 1,
                            0.5f, 0.5f, 0.25f, 0.75f, 0.125f, 0.0625f,
                            0.5f, 0.5f, 0.125f, 0.0625f, 1, 0};
        CHECK(m.face_texcoords && memcmp(m.face_texcoords, tc, sizeof tc) == 0);
        CHECK_EQ_U64(m.stats.texcoord_faces, 2);
        CHECK_EQ_U64(m.stats.polygons_triangulated, 1);
        CHECK(strcmp(m.texture_file, "skin map.png") == 0);
        CHECK(m.has_viewpoint && m.viewpoint[0] == 10.5 && m.viewpoint[1] == -20.25 &&
              m.viewpoint[2] == 30);
        CHECK(!m.grid_index);
    }
    sl_mesh_release(&m);
    plyb_free(&b);
}

/* Colours as float (0..1 scaled to 0..255), no alpha (255); s/t and texture_u/v names. */
static void test_float_colors_and_uv_names(int format)
{
    const char *uv_names[3][2] = {{"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
    for (int n = 0; n < 3; n++) {
        plyb b;
        plyb_init(&b, format);
        plyb_begin(&b);
        plyb_text(&b, "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "property float red\nproperty double green\nproperty float blue\n"
                      "property float %s\nproperty float %s\nend_header\n",
                  uv_names[n][0], uv_names[n][1]);
        const double rgb[3][3] = {{0, 0.5, 1}, {-1, 2, 0.2}, {1.0 / 255, 0.999, 0.0019}};
        const uint8_t expect[12] = {0, 128, 255, 255, 0, 255, 51, 255, 1, 255, 0, 255};
        for (int i = 0; i < 3; i++) {
            plyb_val(&b, "float", i);
            plyb_val(&b, "float", 0);
            plyb_val(&b, "float", 0);
            plyb_val(&b, "float", rgb[i][0]);
            plyb_val(&b, "double", rgb[i][1]);
            plyb_val(&b, "float", rgb[i][2]);
            plyb_val(&b, "float", 0.25 * i);
            plyb_val(&b, "float", 1 - 0.25 * i);
            plyb_eol(&b);
        }
        sl_mesh m;
        sl_error err;
        char name[64];
        snprintf(name, sizeof name, "float_colors_%s", uv_names[n][0]);
        if (read_case(&b, name, &m, &err) == 0) {
            CHECK_MSG(m.colors && memcmp(m.colors, expect, sizeof expect) == 0, "%s colours", name);
            CHECK(m.texcoords && m.texcoords[2] == 0.25f && m.texcoords[5] == 0.5f);
            CHECK(!m.triangles && m.triangle_count == 0 && !m.normals);
        }
        sl_mesh_release(&m);
        plyb_free(&b);
    }
}

/* Faces with 0, 1, 2 corners are dropped and counted; a pentagon gives 3 triangles. */
static void test_short_faces_and_polygons(int format)
{
    plyb b;
    plyb_init(&b, format);
    plyb_begin(&b);
    plyb_text(&b, "element face 5\nproperty list uchar int vertex_index\n"
                  "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                  "end_header\n");
    const int faces[] = {0, 1, 4, 2, 0, 1, 5, 0, 1, 2, 3, 4, 3, 4, 3, 2};
    for (size_t k = 0; k < sizeof faces / sizeof faces[0];) {
        int n = faces[k++];
        plyb_val(&b, "uchar", n);
        for (int i = 0; i < n; i++)
            plyb_val(&b, "int", faces[k++]);
        plyb_eol(&b);
    }
    for (int i = 0; i < 15; i++)
        plyb_val(&b, "float", i);
    plyb_eol(&b);
    sl_mesh m;
    sl_error err;
    if (read_case(&b, "short_faces", &m, &err) == 0) {
        const uint32_t tris[] = {0, 1, 2, 0, 2, 3, 0, 3, 4, 4, 3, 2};
        CHECK_EQ_U64(m.triangle_count, 4);
        CHECK(m.triangles && memcmp(m.triangles, tris, sizeof tris) == 0);
        CHECK_EQ_U64(m.stats.faces_too_short, 3);
        CHECK_EQ_U64(m.stats.polygons_triangulated, 1);
        CHECK(m.positions && m.positions[14] == 14.0f);
    }
    sl_mesh_release(&m);
    plyb_free(&b);
}

/* Stanford range_grid: kept with matching obj_info dims; skipped without or mismatched. */
static void test_range_grid(int format)
{
    for (int variant = 0; variant < 4; variant++) {
        plyb b;
        plyb_init(&b, format);
        plyb_begin(&b);
        if (variant == 0 || variant == 3)
            plyb_text(&b, "obj_info num_cols 3\nobj_info num_rows 2\n");
        if (variant == 1)
            plyb_text(&b, "obj_info num_cols 4\nobj_info num_rows 2\n");
        plyb_text(&b, "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                      "element range_grid 6\nproperty list uchar int vertex_indices\n%s"
                      "end_header\n", variant == 3 ? "property uchar intensity\n" : "");
        for (int i = 0; i < 12; i++)
            plyb_val(&b, "float", i * 0.5);
        plyb_eol(&b);
        const int cells[] = {1, 0, 0, 1, 1, 1, 2, 0, 2, 3, 0};
        for (size_t k = 0; k < sizeof cells / sizeof cells[0];) {
            int n = cells[k++];
            plyb_val(&b, "uchar", n);
            for (int i = 0; i < n; i++)
                plyb_val(&b, "int", cells[k++]);
            if (variant == 3)
                plyb_val(&b, "uchar", 77);
            plyb_eol(&b);
        }
        sl_mesh m;
        sl_error err;
        char name[64];
        snprintf(name, sizeof name, "range_grid_%d", variant);
        if (read_case(&b, name, &m, &err) == 0) {
            const int64_t grid[] = {0, -1, 1, 2, -1, 3};
            if (variant == 0 || variant == 3) {
                CHECK(m.grid_cols == 3 && m.grid_rows == 2);
                CHECK(m.grid_index && memcmp(m.grid_index, grid, sizeof grid) == 0);
            } else {
                CHECK(!m.grid_index && m.grid_cols == 0 && m.grid_rows == 0);
            }
            CHECK_EQ_U64(m.vertex_count, 4);
            CHECK_EQ_U64(m.triangle_count, 0);
        }
        sl_mesh_release(&m);
        plyb_free(&b);
    }
}

/* Viewpoint from comment, from obj_info, and a camera element that overrides them. */
static void test_viewpoint(int format)
{
    const char *lines[] = {"comment viewpoint 1 2.5 -3\n", "obj_info viewpoint 1 2.5 -3\n",
                           "comment viewpoint 9 9 9\n", "comment viewpoint 1 2\n"};
    for (int i = 0; i < 4; i++) {
        plyb b;
        plyb_init(&b, format);
        plyb_begin(&b);
        plyb_text(&b, "%selement vertex 1\nproperty float x\nproperty float y\n"
                      "property float z\n", lines[i]);
        if (i == 2)
            plyb_text(&b, "element camera 2\nproperty double view_pz\nproperty float view_px\n"
                          "property int view_py\n");
        plyb_text(&b, "end_header\n");
        for (int k = 0; k < 3; k++)
            plyb_val(&b, "float", k);
        plyb_eol(&b);
        for (int row = 0; i == 2 && row < 2; row++) {
            plyb_val(&b, "double", -3 + row);
            plyb_val(&b, "float", 1 + row);
            plyb_val(&b, "int", 2 + row);
            plyb_eol(&b);
        }
        sl_mesh m;
        sl_error err;
        char name[64];
        snprintf(name, sizeof name, "viewpoint_%d", i);
        if (read_case(&b, name, &m, &err) == 0) {
            double want_y = i == 2 ? 2 : 2.5;
            if (i < 3)
                CHECK(m.has_viewpoint && m.viewpoint[0] == 1 && m.viewpoint[1] == want_y &&
                      m.viewpoint[2] == -3);
            else
                CHECK(!m.has_viewpoint);
        }
        sl_mesh_release(&m);
        plyb_free(&b);
    }
}

/* Non-finite coordinates are kept (the range stage counts and drops them). */
static void test_nonfinite_kept(int format)
{
    plyb b;
    plyb_init(&b, format);
    plyb_begin(&b);
    plyb_text(&b, "element vertex 2\nproperty float x\nproperty float y\nproperty double z\n"
                  "end_header\n");
    if (format == SL_PLY_ASCII) {
        plyb_text(&b, "nan inf -inf\nNaN -Infinity 1e400\n");
    } else {
        const double v[] = {NAN, INFINITY, -INFINITY, NAN, -INFINITY, 1e300};
        for (int i = 0; i < 6; i++)
            plyb_val(&b, i % 3 == 2 ? "double" : "float", v[i]);
    }
    sl_mesh m;
    sl_error err;
    if (read_case(&b, "nonfinite", &m, &err) == 0) {
        CHECK(isnan(m.positions[0]) && isinf(m.positions[1]) && m.positions[1] > 0);
        CHECK(isinf(m.positions[2]) && m.positions[2] < 0);
        CHECK(isnan(m.positions[3]) && isinf(m.positions[4]) && isinf(m.positions[5]));
    }
    sl_mesh_release(&m);
    plyb_free(&b);
}

/* An element without properties and a huge count costs nothing and is skipped. */
static void test_empty_rows(void)
{
    const char *text = "ply\nformat binary_little_endian 1.0\nelement nothing "
                       "18446744073709551615\nelement vertex 0\nproperty float x\n"
                       "property float y\nproperty float z\nend_header\n";
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    clock_t t0 = clock();
    int rc = sl_ply_read_memory(text, strlen(text), "nothing.ply", NULL, &m, NULL, &err);
    CHECK_MSG(rc == 0, "%s", err.message);
    CHECK(m.vertex_count == 0 && !m.positions && m.triangle_count == 0);
    CHECK((double)(clock() - t0) / CLOCKS_PER_SEC < 0.5);
    sl_mesh_release(&m);
}

/* 64-bit offsets: a sparse 4.5 GiB file whose last bytes hold the vertices, after an
 * element of 4.5 billion one-byte rows (skipped, never touched, never allocated). */
static void test_beyond_4gib(void)
{
    char path[512];
    const uint64_t pad = 4500000000ull;
    snprintf(path, sizeof path, "%s/sparse.ply", tmpdir);
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    if (!f)
        return;
    fprintf(f, "ply\nformat binary_little_endian 1.0\nelement pad %llu\nproperty uchar p\n"
               "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
               "end_header\n", (unsigned long long)pad);
    const float xyz[6] = {1, 2, 3, -4, -5, -6};
    int ok = fseeko(f, (off_t)pad, SEEK_CUR) == 0 && fwrite(xyz, sizeof xyz, 1, f) == 1;
    ok = fclose(f) == 0 && ok;
    CHECK_MSG(ok, "cannot write the sparse file");
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    int rc = ok ? sl_ply_read(path, NULL, &m, NULL, NULL, &err) : -1;
    CHECK_MSG(rc == 0, "%s", err.message);
    CHECK(rc == 0 && m.vertex_count == 2 && memcmp(m.positions, xyz, sizeof xyz) == 0);
    if (rc == 0)
        sl_mesh_release(&m);
    unlink(path);
}

/* The info summary `scanlod inspect` prints. */
static void test_info(void)
{
    const char *text = "ply\r\nformat ascii 1.0\r\ncomment TextureFile a.png\r\n"
                       "element vertex 3\r\nproperty float x\r\nproperty float y\r\n"
                       "property float z\r\nproperty uchar red\r\nproperty uchar green\r\n"
                       "property uchar blue\r\nelement face 1\r\n"
                       "property list uchar int vertex_indices\r\nend_header\r\n"
                       "0 0 0 1 2 3\r\n1 0 0 4 5 6\r\n0 1 0 7 8 9\r\n3 0 1 2\r\n";
    sl_mesh m;
    sl_ply_info info;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_read_memory(text, strlen(text), "crlf.ply", NULL, &m, &info, &err);
    CHECK_MSG(rc == 0, "%s", err.message);
    CHECK(info.format == SL_PLY_ASCII && info.declared_vertices == 3 && info.declared_faces == 1);
    CHECK(info.element_count == 2 && info.has_colors && !info.has_normals);
    CHECK_MSG(strcmp(info.elements, "vertex 3 (x y z red green blue); face 1 (list uchar int "
                                    "vertex_indices)") == 0, "%s", info.elements);
    CHECK(rc == 0 && m.colors[4 * 2 + 2] == 9 && m.colors[3] == 255);
    CHECK(strcmp(m.texture_file, "a.png") == 0);
    sl_mesh_release(&m);
}

/* Unit and up-axis hints in comments (docs/glb.md "Units and up axis"); anything else
 * in a comment is free text and leaves them unset. */
static void test_frame_hints(void)
{
    static const struct { const char *lines, *units; char up; } cases[] = {
        {"comment units mm\ncomment up z\n", "mm", 'z'},
        {"comment Units: Millimeters\ncomment up_axis: +Z\n", "mm", 'z'},
        {"comment unit= inch\ncomment Y-up\n", "in", 'y'},
        {"comment units feet\ncomment upaxis Y\n", "ft", 'y'},
        {"comment units metres\ncomment up-axis z\n", "m", 'z'},
        {"comment units parsecs\ncomment up x\n", "", 0},
        {"comment scanned in mm, z is up\ncomment units\n", "", 0},
        {"comment Z-up model\ncomment units cm extra\n", "", 0}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        plyb b;
        plyb_init(&b, SL_PLY_ASCII);
        plyb_begin(&b);
        plyb_text(&b, "%selement vertex 1\nproperty float x\nproperty float y\n"
                      "property float z\nend_header\n", cases[i].lines);
        for (int k = 0; k < 3; k++)
            plyb_val(&b, "float", k);
        plyb_eol(&b);
        sl_mesh m;
        sl_error err;
        char name[64];
        snprintf(name, sizeof name, "frame_%zu", i);
        if (read_case(&b, name, &m, &err) == 0)
            CHECK_MSG(!strcmp(m.units, cases[i].units) && m.up_axis == cases[i].up,
                      "case %zu: units '%s' up '%c'", i, m.units, m.up_axis ? m.up_axis : '-');
        sl_mesh_release(&m);
        plyb_free(&b);
    }
}

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/test_ply.XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    if (!mkdtemp(tmpdir)) {
        perror("mkdtemp");
        return 1;
    }
    const int formats[] = {SL_PLY_ASCII, SL_PLY_BINARY_LE, SL_PLY_BINARY_BE};
    for (int f = 0; f < 3; f++) {
        test_scalar_types(formats[f]);
        test_everything_shuffled(formats[f]);
        test_float_colors_and_uv_names(formats[f]);
        test_short_faces_and_polygons(formats[f]);
        test_range_grid(formats[f]);
        test_viewpoint(formats[f]);
        test_nonfinite_kept(formats[f]);
    }
    test_empty_rows();
    test_frame_hints();
    test_info();
    if (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ && sizeof(size_t) == 8)
        test_beyond_4gib();
    printf("%d files written and read back\n", files_written);
    rmdir(tmpdir);
    return check_report();
}
