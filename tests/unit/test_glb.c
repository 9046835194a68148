/* GLB and OBJ writers: the container read back byte by byte (header, chunk lengths and
 * types, 4-byte alignment and padding), the JSON (valid, accessors, exact POSITION
 * min/max, index type by vertex count, extras), the binary blocks equal to the input
 * (normals unit length), rejections that leave no file, and the OBJ text.
 *
 * With SCANLOD_GLB_OUT set, also writes sample GLBs (synthetic and the bundled scans)
 * into that directory for tests/export/test_glb.sh to run the Khronos validator on.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../check.h"
#include "core/atomicfile.h"
#include "formats/glb.h"
#include "glb_meshes.h"
#include "json_validate.h"

static char tmpdir[512];

/* IEC 61966-2-1, written here again so that the test does not trust the writer's. */
static double glb_test_linear_to_srgb(double l)
{
    return l <= 0.0031308 ? 12.92 * l : 1.055 * pow(l, 1 / 2.4) - 0.055;
}

typedef struct glb_file {
    char *data;
    size_t size;
    char *json;              /* NUL-terminated copy of the JSON chunk */
    const unsigned char *bin;
    uint32_t bin_length;
} glb_file;

static uint32_t le32(const void *p)
{
    const unsigned char *b = p;
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* Reads and checks the container; 0 when the chunks could be located. */
static int glb_read(const char *path, glb_file *g)
{
    memset(g, 0, sizeof *g);
    sl_error err;
    sl_error_init(&err);
    if (sl_read_file(path, 1u << 30, &g->data, &g->size, &err))
        return -1;
    const char *d = g->data;
    CHECK(g->size >= 28 && g->size % 4 == 0);
    if (g->size < 28)
        return -1;
    CHECK(memcmp(d, "glTF", 4) == 0);
    CHECK_EQ_U64(le32(d + 4), 2);
    CHECK_EQ_U64(le32(d + 8), g->size);
    uint32_t json_length = le32(d + 12);
    CHECK(json_length % 4 == 0);
    CHECK(memcmp(d + 16, "JSON", 4) == 0);
    if (20 + (uint64_t)json_length + 8 > g->size)
        return -1;
    g->json = calloc(json_length + 1, 1);
    memcpy(g->json, d + 20, json_length);
    CHECK(json_valid(g->json, json_length)); /* trailing spaces are JSON whitespace */
    const char *bin = d + 20 + json_length;
    g->bin_length = le32(bin);
    CHECK(g->bin_length % 4 == 0);
    CHECK(memcmp(bin + 4, "BIN\0", 4) == 0);
    CHECK_EQ_U64(20 + (uint64_t)json_length + 8 + g->bin_length, g->size);
    g->bin = (const unsigned char *)bin + 8;
    return 0;
}

static void glb_free(glb_file *g)
{
    free(g->data);
    free(g->json);
}

/* The unsigned number after the n-th occurrence of `key` in the JSON, or -1. */
static long long json_number_after(const char *json, const char *key, int n)
{
    const char *p = json;
    for (int i = 0; i <= n; i++) {
        p = strstr(p, key);
        if (!p)
            return -1;
        p += strlen(key);
    }
    return strtoll(p, NULL, 10);
}

static void path_in_tmp(const char *name, char *buf, size_t size)
{
    snprintf(buf, size, "%s/%s", tmpdir, name);
}

static void test_cube_layout(void)
{
    sl_mesh m;
    meshes_cube(&m, -1, 2, 1, 1);
    char path[600];
    path_in_tmp("cube.glb", path, sizeof path);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_glb_write(path, &m, "{\"lod_percent\":20,\"triangles\":12}", NULL, NULL,
                       &err) == 0);
    glb_file f;
    if (glb_read(path, &f) == 0) {
        /* 24 positions + 24 normals (12 bytes each), 24 linear colours (4 x 16 bits), 36
         * short indices. */
        CHECK_EQ_U64(f.bin_length, 288 + 288 + 192 + 72);
        CHECK(strstr(f.json, "\"generator\":\"scanlod\"") != NULL);
        CHECK(strstr(f.json, "\"attributes\":{\"POSITION\":0,\"NORMAL\":1,\"COLOR_0\":2}"));
        CHECK(strstr(f.json, "\"indices\":3") != NULL);
        CHECK(strstr(f.json, "\"min\":[-1,-1,-1],\"max\":[2,2,2]") != NULL);
        CHECK(strstr(f.json, "\"componentType\":5123,\"count\":36,\"type\":\"SCALAR\""));
        CHECK(strstr(f.json, "\"componentType\":5123,\"normalized\":true,\"count\":24,"
                             "\"type\":\"VEC4\""));
        CHECK(strstr(f.json, "extensionsUsed") == NULL); /* plain glTF 2.0 */
        CHECK(strstr(f.json, "\"extras\":{\"lod_percent\":20,\"triangles\":12}") != NULL);
        CHECK_EQ_U64(json_number_after(f.json, "\"byteOffset\":", 1), 288);
        CHECK_EQ_U64(json_number_after(f.json, "\"byteOffset\":", 2), 576);
        CHECK_EQ_U64(json_number_after(f.json, "\"byteOffset\":", 3), 768);
        CHECK_EQ_U64(json_number_after(f.json, "\"target\":", 3), 34963);
        CHECK(memcmp(f.bin, m.positions, 288) == 0); /* the tests run on little-endian hosts */
        /* Colours are linear (glTF): sRGB 200 comes back as 200 after linear -> sRGB. */
        int colors_ok = 1;
        for (int i = 0; i < 24 * 4; i++) {
            double v = (f.bin[576 + 2 * i] | f.bin[577 + 2 * i] << 8) / 65535.0;
            double back = i % 4 == 3 ? v * 255 : 255 * glb_test_linear_to_srgb(v);
            colors_ok &= fabs(back - m.colors[i]) <= 0.5;
        }
        CHECK(colors_ok);
        int same = 1;
        for (int i = 0; i < 36; i++)
            same &= f.bin[768 + 2 * i] + 256u * f.bin[769 + 2 * i] == m.triangles[i];
        CHECK(same);
        glb_free(&f);
    }
    sl_mesh_release(&m);
}

/* One triangle: 6 bytes of short indices padded with zeros to 8; no normals/colours. */
static void test_padding_and_minimal(void)
{
    float pos[9] = {0.1f, 0.2f, 0.3f, 1e-7f, -5.5f, 3.25f, 7.0f, 0.333333343f, -0.0f};
    uint32_t idx[3] = {0, 1, 2};
    sl_mesh g = sl_mesh_view(3, pos, NULL, NULL, 1, idx);
    char path[600];
    path_in_tmp("one.glb", path, sizeof path);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_glb_write(path, &g, NULL, NULL, NULL, &err) == 0);
    glb_file f;
    if (glb_read(path, &f) == 0) {
        CHECK_EQ_U64(f.bin_length, 36 + 8);
        CHECK(f.bin[36 + 6] == 0 && f.bin[36 + 7] == 0);
        CHECK(strstr(f.json, "\"attributes\":{\"POSITION\":0}") != NULL);
        CHECK(strstr(f.json, "extras") == NULL);
        /* min/max are the float values exactly (after a %.9g round trip). */
        const char *mn = strstr(f.json, "\"min\":["), *mx = strstr(f.json, "\"max\":[");
        CHECK(mn && mx);
        if (mn && mx) {
            char *p = (char *)mn + 7, *q = (char *)mx + 7;
            float lo[3] = {1e-7f, -5.5f, -0.0f}, hi[3] = {7.0f, 0.333333343f, 3.25f};
            for (int k = 0; k < 3; k++) {
                CHECK((float)strtod(p, &p) == lo[k]);
                CHECK((float)strtod(q, &q) == hi[k]);
                p++, q++;
            }
        }
        glb_free(&f);
    }
}

/* 300 x 300 vertices need 32-bit indices; normals of length 2 come out unit length. */
static void test_large_indices_and_normals(void)
{
    sl_mesh m;
    meshes_grid(&m, 300, 1, 0);
    m.normals[3 * 5 + 2] = 0; /* a zero normal becomes (0, 0, 1) */
    char path[600];
    path_in_tmp("grid.glb", path, sizeof path);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_glb_write(path, &m, NULL, NULL, NULL, &err) == 0);
    glb_file f;
    if (glb_read(path, &f) == 0) {
        uint64_t v = m.vertex_count, t = m.triangle_count;
        CHECK_EQ_U64(f.bin_length, 24 * v + 12 * t);
        CHECK(strstr(f.json, "\"componentType\":5125") != NULL);
        CHECK(strstr(f.json, "\"componentType\":5123") == NULL);
        int unit = 1;
        for (uint64_t i = 0; i < v; i++) {
            float n[3];
            memcpy(n, f.bin + 12 * v + 12 * i, sizeof n);
            unit &= n[0] == 0 && n[1] == 0 && n[2] == 1.0f;
        }
        CHECK(unit);
        CHECK(memcmp(f.bin + 24 * v, m.triangles, 12 * t) == 0);
        glb_free(&f);
    }
    sl_mesh_release(&m);
}

static void expect_rejected(const sl_mesh *g, int code, const char *message_part)
{
    char path[600];
    path_in_tmp("rejected.glb", path, sizeof path);
    sl_error err;
    sl_error_init(&err);
    CHECK_MSG(sl_glb_write(path, g, NULL, NULL, NULL, &err) == code, "%s", sl_error_name(err.code));
    CHECK_MSG(strstr(err.message, message_part) != NULL, "%s", err.message);
    CHECK(access(path, F_OK) != 0 && errno == ENOENT);
    sl_error_init(&err);
    path_in_tmp("rejected.obj", path, sizeof path);
    if (code != SL_E_INTERNAL || strstr(message_part, "index"))
        CHECK(sl_obj_write(path, g, NULL, &err) == code);
    CHECK(access(path, F_OK) != 0);
}

static void test_rejections(void)
{
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t idx[3] = {0, 1, 2};
    sl_mesh empty = sl_mesh_view(3, pos, NULL, NULL, 0, idx);
    expect_rejected(&empty, SL_E_BADINPUT, "nothing to write");
    sl_mesh no_vertices = sl_mesh_view(0, pos, NULL, NULL, 1, idx);
    expect_rejected(&no_vertices, SL_E_BADINPUT, "nothing to write");
    uint32_t bad_idx[3] = {0, 1, 3};
    sl_mesh out_of_range = sl_mesh_view(3, pos, NULL, NULL, 1, bad_idx);
    expect_rejected(&out_of_range, SL_E_INTERNAL, "vertex index 3");
    float nan_pos[9] = {0, 0, 0, 1, NAN, 0, 0, 1, 0};
    sl_mesh nan = sl_mesh_view(3, nan_pos, NULL, NULL, 1, idx);
    expect_rejected(&nan, SL_E_BADINPUT, "vertex 1 has a non-finite position");
    float inf_pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, -INFINITY};
    sl_mesh inf = sl_mesh_view(3, inf_pos, NULL, NULL, 1, idx);
    expect_rejected(&inf, SL_E_BADINPUT, "vertex 2 has a non-finite position");
    sl_mesh not_object = sl_mesh_view(3, pos, NULL, NULL, 1, idx);
    char path[600];
    path_in_tmp("rejected.glb", path, sizeof path);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_glb_write(path, &not_object, "\"lod\"", NULL, NULL, &err) == SL_E_INTERNAL);
    CHECK(access(path, F_OK) != 0);
}

static void test_deterministic(void)
{
    sl_mesh m;
    float c[3] = {0.5f, 0, 0};
    meshes_sphere(&m, 12, 24, c, 1);

    char a[600], b[600];
    path_in_tmp("a.glb", a, sizeof a);
    path_in_tmp("b.glb", b, sizeof b);
    sl_error err;
    sl_error_init(&err);
    const char *extras = "{\"level\":1}";
    CHECK(sl_glb_write(a, &m, extras, NULL, NULL, &err) == 0 &&
          sl_glb_write(b, &m, extras, NULL, NULL, &err) == 0);
    char *da = NULL, *db = NULL;
    size_t na = 0, nb = 0;
    CHECK(sl_read_file(a, 1 << 24, &da, &na, &err) == 0);
    CHECK(sl_read_file(b, 1 << 24, &db, &nb, &err) == 0);
    CHECK(na == nb && na > 0 && memcmp(da, db, na) == 0);
    free(da);
    free(db);
    sl_mesh_release(&m);
}

static void test_obj(void)
{
    sl_mesh m;
    meshes_cube(&m, 0, 1, 1, 1);
    char path[600];
    path_in_tmp("cube.obj", path, sizeof path);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_obj_write(path, &m, "{\"level\":2}", &err) == 0);
    char *text = NULL;
    size_t size = 0;
    CHECK(sl_read_file(path, 1 << 20, &text, &size, &err) == 0);
    if (text) {
        int v = 0, vn = 0, faces = 0;
        for (const char *line = text, *next; *line; line = next + 1) {
            v += strncmp(line, "v ", 2) == 0;
            vn += strncmp(line, "vn ", 3) == 0;
            faces += strncmp(line, "f ", 2) == 0;
            if (!(next = strchr(line, '\n')))
                break;
        }
        CHECK(v == 24 && vn == 24 && faces == 12);
        CHECK(strstr(text, "# extras {\"level\":2}\n") != NULL);
        /* Face x = 0 (normal -x): vertex 1 at the origin, colour (200, 0, 0). */
        CHECK(strstr(text, "\nv 0 0 0 0.784314 0 0\n") != NULL);
        CHECK(strstr(text, "\nvn -1 0 0\n") != NULL);
        CHECK(strstr(text, "\nf 1//1 3//3 2//2\n") != NULL);
        free(text);
    }
    sl_mesh_release(&m);
}

/* Sample files for the Khronos validator (tests/export/test_glb.sh). */
static void write_samples(const char *dir)
{
    sl_error err;
    sl_error_init(&err);
    char path[1200];
    sl_mesh m;
    struct { const char *name; int normals, colors; } cubes[] = {
        {"cube_plain", 0, 0}, {"cube_normals", 1, 0}, {"cube_colors", 0, 1}, {"cube_all", 1, 1}};
    for (size_t i = 0; i < sizeof cubes / sizeof cubes[0]; i++) {
        meshes_cube(&m, -0.5f, 0.5f, cubes[i].normals, cubes[i].colors);
        snprintf(path, sizeof path, "%s/%s.glb", dir, cubes[i].name);
        CHECK(sl_glb_write(path, &m, "{\"scanlod\":{\"level\":0}}", NULL, NULL, &err) == 0);
        sl_mesh_release(&m);
    }
    float one_pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, one_nrm[9] = {0, 0, 3, 0, 0, 3, 0, 0, 3};
    uint32_t one_idx[3] = {0, 1, 2};
    sl_mesh one = sl_mesh_view(3, one_pos, one_nrm, NULL, 1, one_idx);
    snprintf(path, sizeof path, "%s/one_triangle.glb", dir);
    CHECK(sl_glb_write(path, &one, NULL, NULL, NULL, &err) == 0);
    meshes_grid(&m, 300, 1, 1);
    snprintf(path, sizeof path, "%s/grid_uint32.glb", dir);
    CHECK(sl_glb_write(path, &m, NULL, NULL, NULL, &err) == 0);
    sl_mesh_release(&m);
    const char *scans[] = {"cow", "fandisk", "bun_zipper_res3", "rocker_arm"};
    for (size_t i = 0; i < sizeof scans / sizeof scans[0]; i++) {
        if (meshes_read_scan(scans[i], &m) != 0) {
            CHECK_MSG(0, "cannot read scan %s", scans[i]);
            continue;
        }
        meshes_vertex_normals(&m);
        snprintf(path, sizeof path, "%s/%s.glb", dir, scans[i]);
        const char *extras = "{\"scanlod\":{\"item\":\"scan\",\"lod_percent\":100}}";
        CHECK_MSG(sl_glb_write(path, &m, extras, NULL, NULL, &err) == 0, "%s: %s", scans[i],
                  err.message);
        sl_mesh_release(&m);
    }
}

int main(void)
{
    snprintf(tmpdir, sizeof tmpdir, "%s/scanlod-glb.XXXXXX",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    if (!mkdtemp(tmpdir)) {
        perror("mkdtemp");
        return 1;
    }
    test_cube_layout();
    test_padding_and_minimal();
    test_large_indices_and_normals();
    test_rejections();
    test_deterministic();
    test_obj();
    const char *out = getenv("SCANLOD_GLB_OUT");
    if (out && out[0])
        write_samples(out);

    const char *names[] = {"cube.glb", "one.glb", "grid.glb", "a.glb", "b.glb", "cube.obj"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char path[600];
        path_in_tmp(names[i], path, sizeof path);
        unlink(path);
    }
    rmdir(tmpdir);
    return check_report();
}
