/* The scan readers on the bundled model in every format (tests/data/inputs/, made by
 * make_inputs.py): each file reads back as sphere.ply does, in counts, positions, normals,
 * colours and texture coordinates; the entry point picks the reader by magic and name;
 * sl_scan_read_info gives the same counts without the body; a missing MTL or texture is a
 * warning; and, when ../shared/data is present, the real textured scans read with the
 * counts its README gives.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "formats/scan_read.h"
#include "formats/scan_texture.h"
#include "tests/check.h"
#include "tests/unit/scan_test_files.h"

static sl_mesh reference;

static int read_input(const char *name, sl_mesh *m, sl_scan_info *info)
{
    char rel[256], path[1024];
    snprintf(rel, sizeof rel, "tests/data/inputs/%s", name);
    check_source_path(rel, path, sizeof path);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_scan_read(path, NULL, m, info, NULL, &err);
    CHECK_MSG(rc == 0, "%s: %s", name, err.message);
    return rc;
}

/* The reference vertex at the position of m's vertex v (the formats may order vertices
 * differently: STL repeats them per triangle); -1 when none. */
static long reference_vertex(const sl_mesh *m, uint64_t v)
{
    for (uint64_t i = 0; i < reference.vertex_count; i++) {
        const float *a = reference.positions + 3 * i, *b = m->positions + 3 * v;
        if (fabsf(a[0] - b[0]) < 1e-5f && fabsf(a[1] - b[1]) < 1e-5f && fabsf(a[2] - b[2]) < 1e-5f)
            return (long)i;
    }
    return -1;
}

/* Each vertex is one of the reference's, with its normal and colour (within tolerances). */
static void check_vertices(const char *name, const sl_mesh *m, double normal_tol, int color_tol)
{
    int found = 1, normals = 1, colors = 1;
    for (uint64_t v = 0; v < m->vertex_count; v++) {
        long r = reference_vertex(m, v);
        found &= r >= 0;
        if (r < 0)
            continue;
        for (int k = 0; m->normals && k < 3; k++)
            normals &= fabs(m->normals[3 * v + k] - reference.normals[3 * r + k]) <= normal_tol;
        for (int k = 0; m->colors && k < 4; k++)
            colors &= abs(m->colors[4 * v + k] - reference.colors[4 * r + k]) <= color_tol;
    }
    CHECK_MSG(found, "%s: a vertex that is not the reference's", name);
    CHECK_MSG(normals, "%s: normals differ", name);
    CHECK_MSG(colors, "%s: colours differ", name);
}

/* Every triangle's corners are a reference triangle's, in its order (its winding). */
static void check_triangles(const char *name, const sl_mesh *m)
{
    CHECK_EQ_U64(m->triangle_count, reference.triangle_count);
    int same = m->triangle_count == reference.triangle_count;
    for (uint64_t t = 0; same && t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++)
            same &= reference_vertex(m, m->triangles[3 * t + k]) ==
                    (long)reference.triangles[3 * t + k];
    CHECK_MSG(same, "%s: triangles differ from the reference's", name);
}

/* Texture coordinates per corner (per-vertex ones taken at the corners). */
static void check_texcoords(const char *name, const sl_mesh *m)
{
    int same = m->texcoords || m->face_texcoords;
    for (uint64_t t = 0; same && t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = m->triangles[3 * t + k], r = reference.triangles[3 * t + k];
            const float *uv = m->face_texcoords ? m->face_texcoords + 6 * t + 2 * k
                                                : m->texcoords + 2 * (uint64_t)v;
            same &= fabsf(uv[0] - reference.texcoords[2 * r]) < 1e-6f &&
                    fabsf(uv[1] - reference.texcoords[2 * r + 1]) < 1e-6f;
        }
    CHECK_MSG(same, "%s: texture coordinates differ from the reference's", name);
}

static void check_format(const char *file, const char *format, int triangles, int normals,
                         int colors, int uvs, double normal_tol, int color_tol)
{
    sl_mesh m;
    sl_scan_info info;
    if (read_input(file, &m, &info)) {
        sl_mesh_release(&m);
        return;
    }
    CHECK_MSG(!strcmp(m.format, format) && !strcmp(info.format, format), "%s: format %s/%s",
              file, m.format, info.format);
    CHECK_MSG((m.normals != NULL) == normals && (m.colors != NULL) == colors,
              "%s: normals %d colours %d", file, m.normals != NULL, m.colors != NULL);
    CHECK_MSG(m.warning_count == 0, "%s: warnings: %s", file, m.warnings);
    check_vertices(file, &m, normal_tol, color_tol);
    if (triangles)
        check_triangles(file, &m);
    else
        CHECK_EQ_U64(m.vertex_count, reference.vertex_count);
    if (uvs)
        check_texcoords(file, &m);
    sl_mesh_release(&m);
}

static void test_formats(void)
{
    /* file, format, triangles, normals, colours, uvs, normal and colour tolerances */
    check_format("sphere.obj", "obj", 1, 1, 1, 1, 1e-6, 0);
    check_format("sphere.off", "off", 1, 1, 1, 1, 1e-6, 0);
    check_format("sphere.xyz", "xyz", 0, 1, 1, 0, 1e-6, 0);
    check_format("sphere.pts", "pts", 0, 0, 1, 0, 0, 0);
    check_format("sphere.gltf", "gltf", 1, 1, 1, 1, 1e-6, 1);
    check_format("sphere.glb", "glb", 1, 1, 1, 1, 1e-6, 1);
    /* STL: its facet normals, not the vertex normals; no colours */
    check_format("sphere.stl", "stl", 1, 1, 0, 0, 2.0, 0);
}

static void test_stl(void)
{
    sl_mesh m;
    if (read_input("sphere.stl", &m, NULL) == 0) {
        CHECK_EQ_U64(m.vertex_count, 3 * reference.triangle_count);
        float n[3]; /* the first facet's normal, as make_inputs.py computed it */
        const float *a = m.positions, *b = a + 3, *c = a + 6;
        float u[3], w[3];
        for (int k = 0; k < 3; k++)
            u[k] = b[k] - a[k], w[k] = c[k] - a[k];
        for (int k = 0; k < 3; k++)
            n[k] = u[(k + 1) % 3] * w[(k + 2) % 3] - u[(k + 2) % 3] * w[(k + 1) % 3];
        float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++)
            CHECK_NEAR(m.normals[k], n[k] / len, 1e-5);
    }
    sl_mesh_release(&m);
    if (read_input("cube_ascii.stl", &m, NULL) == 0) {
        CHECK_EQ_U64(m.vertex_count, 36);
        CHECK_EQ_U64(m.triangle_count, 12);
        CHECK(m.normals && m.normals[2] == -1.0f); /* the bottom face looks down */
    }
    sl_mesh_release(&m);
}

static void test_frames_and_textures(void)
{
    sl_mesh m;
    char name[300];
    if (read_input("sphere.glb", &m, NULL) == 0) {
        CHECK(!strcmp(m.units, "m") && m.up_axis == 'y'); /* glTF: metres, +Y up */
        CHECK(m.texture_data && m.texture_size == 124 && !strcmp(m.texture_mime, "image/png"));
        CHECK(!strcmp(sl_scan_texture_name(&m, name, sizeof name),
                      "embedded image/png (124 bytes)"));
    }
    sl_mesh_release(&m);
    if (read_input("sphere.obj", &m, NULL) == 0) {
        CHECK(!m.units[0] && !m.up_axis); /* OBJ says nothing */
        CHECK(!strcmp(m.texture_file, "sphere.png") && !m.texture_data);
    }
    sl_mesh_release(&m);
    if (read_input("sphere.gltf", &m, NULL) == 0)
        CHECK(!strcmp(m.texture_file, "sphere.png"));
    sl_mesh_release(&m);
}

/* The texture decodes the same from the file and from the GLB (OpenImageIO module). */
static void test_texture_decode(void)
{
    char dir[1024];
    check_source_path("tests/data/inputs", dir, sizeof dir);
    sl_mesh a, b;
    sl_image ia, ib;
    char why[1600];
    if (read_input("sphere.gltf", &a, NULL) || read_input("sphere.glb", &b, NULL))
        return;
    int ra = sl_scan_texture_read(&a, dir, 1 << 20, &ia, why, sizeof why);
    CHECK_MSG(ra, "file texture: %s", why);
    int rb = sl_scan_texture_read(&b, dir, 1 << 20, &ib, why, sizeof why);
    CHECK_MSG(rb, "embedded texture: %s", why);
    if (ra && rb) {
        CHECK(ia.width == 16 && ib.width == 16 && ia.channels == ib.channels);
        CHECK(!memcmp(ia.pixels, ib.pixels, 16 * 16 * (size_t)ia.channels * sizeof(float)));
    }
    sl_image_release(&ia), sl_image_release(&ib);
    CHECK(!sl_scan_texture_read(&b, dir, 100, &ib, why, sizeof why) && strstr(why, "exceeds"));
    sl_mesh_release(&a), sl_mesh_release(&b);
}

static void test_info(void)
{
    static const char *const files[] = {"sphere.ply", "sphere.obj", "sphere.off", "sphere.stl",
                                        "sphere.gltf", "sphere.glb", "sphere.xyz"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char rel[256], path[1024];
        snprintf(rel, sizeof rel, "tests/data/inputs/%s", files[i]);
        check_source_path(rel, path, sizeof path);
        sl_scan_info info;
        sl_error err;
        sl_error_init(&err);
        CHECK_MSG(sl_scan_read_info(path, NULL, &info, &err) == 0, "%s: %s", files[i], err.message);
        uint64_t faces = strstr(files[i], "xyz") ? 0 : 80;
        uint64_t vertices = strstr(files[i], "stl") ? 240 : 42;
        CHECK_MSG(info.declared_faces == faces && info.declared_vertices == vertices,
                  "%s: %llu vertices, %llu faces", files[i],
                  (unsigned long long)info.declared_vertices, (unsigned long long)info.declared_faces);
    }
}

static void test_names(void)
{
    CHECK(!strcmp(sl_scan_format_of("a/b/Mask.OBJ"), "obj"));
    CHECK(!strcmp(sl_scan_format_of("x.glb"), "glb"));
    CHECK(!strcmp(sl_scan_format_of("x.pts"), "pts"));
    CHECK(sl_scan_format_of("x.mtl") == NULL && sl_scan_format_of("x.bin") == NULL);
    CHECK(sl_scan_format_of("README.txt") == NULL && sl_scan_format_of(".obj") == NULL);
    CHECK(sl_scan_format_of("dir.obj/file") == NULL);
    int n = 0;
    for (const char *const *s = sl_scan_suffixes(); *s; s++)
        n += sl_scan_format_of(*s + 0) == NULL; /* ".ply" alone is no name */
    CHECK(n == 8);
}

/* By content: a mislabelled file and unknown names read by their magic. */
static void test_sniffing(void)
{
    static const char off[] = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    static const char obj[] = "# x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    static const char xyz[] = "0 0 0\n1 0 0\n0 1 0\n";
    static const char ply[] = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                              "property float y\nproperty float z\nend_header\n0 0 0\n";
    const struct { const char *text, *name, *format; } cases[] = {
        {off, "scan.txt", "off"}, {obj, "scan.dat", "obj"}, {xyz, "scan.txt", "xyz"},
        {ply, "scan.obj", "ply"}, /* the magic wins over the name */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        sl_mesh m;
        sl_error err;
        sl_error_init(&err);
        int rc = sl_scan_read_memory(cases[i].text, strlen(cases[i].text), cases[i].name, NULL,
                                     NULL, NULL, &m, NULL, &err);
        CHECK_MSG(rc == 0 && !strcmp(m.format, cases[i].format), "%s: rc %d format '%s' (%s)",
                  cases[i].name, rc, m.format, err.message);
        sl_mesh_release(&m);
    }
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_scan_read_memory("hello world\n", 12, "notes.txt", NULL, NULL, NULL, &m, NULL,
                              &err) == SL_E_UNSUPPORTED && strstr(err.message, "not a scan format"));
}

/* A missing MTL, a missing texture: warnings, never failures. */
static void test_missing_siblings(void)
{
    static const char obj[] = "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\n"
                              "f 1/1 2/1 3/1\n";
    static const char mtl[] = "newmtl m\nmap_Kd -s 1 1 1 C:\\scans\\tex.jpg\n";
    static const char *const names[] = {"a.obj", "a.mtl"};
    char dir[] = "/tmp/scanlod-scan-XXXXXX", path[256], mtl_path[256];
    if (!mkdtemp(dir))
        return;
    scan_test_write(dir, "a.obj", obj, strlen(obj), path, sizeof path);
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_scan_read(path, NULL, &m, NULL, NULL, &err) == 0);
    CHECK_MSG(m.warning_count == 1 && !strcmp(m.warnings, "a.mtl: missing"), "%s", m.warnings);
    sl_mesh_release(&m);
    scan_test_write(dir, "a.mtl", mtl, strlen(mtl), mtl_path, sizeof mtl_path);
    CHECK(sl_scan_read(path, NULL, &m, NULL, NULL, &err) == 0);
    CHECK_MSG(!strcmp(m.texture_file, "tex.jpg") && m.warning_count == 2 &&
              strstr(m.warnings, "outside the folder") && strstr(m.warnings, "tex.jpg: missing"),
              "%s / %s", m.texture_file, m.warnings);
    sl_mesh_release(&m);
    scan_test_remove(dir, names, 2);
}

/* The real scans of ../shared/data/textured (counts from its README). */
static void test_shared_data(void)
{
    static const struct { const char *file; uint64_t vertices, triangles; int texture; } scans[] = {
        {"textured/mask_bali_blm_obj/mask.obj", 62383, 100000, 1},
        {"textured/mask_bali_blm_stl/mask.stl", 300000, 100000, 0},
        {"textured/mask_bali_blm/mask-gltf-2.0_separated-valid.gltf", 62383, 100000, 1},
        {"textured/sea_turtle_nmnh/sea_turtle-20k-thumb.glb", 12482, 20000, 1},
        {"textured/gui_food_vessel_mia/foodvessel.gltf", 39439, 64000, 1},
        {"textured/armadillo_xyz/armadillo_low.xyz", 12267, 0, 0},
    };
    for (size_t i = 0; i < sizeof scans / sizeof scans[0]; i++) {
        char path[1024];
        if (!check_shared_path(scans[i].file, path, sizeof path))
            return;
        sl_mesh m;
        sl_error err;
        sl_error_init(&err);
        int rc = sl_scan_read(path, NULL, &m, NULL, NULL, &err);
        CHECK_MSG(rc == 0, "%s: %s", scans[i].file, err.message);
        CHECK_MSG(rc || (m.vertex_count == scans[i].vertices && m.triangle_count ==
                         scans[i].triangles && sl_scan_has_texture(&m) == scans[i].texture),
                  "%s: %llu vertices, %llu triangles", scans[i].file,
                  (unsigned long long)m.vertex_count, (unsigned long long)m.triangle_count);
        sl_mesh_release(&m);
    }
}

int main(void)
{
    sl_scan_info info;
    if (read_input("sphere.ply", &reference, &info))
        return check_report();
    CHECK(reference.vertex_count == 42 && reference.triangle_count == 80 && reference.normals &&
          reference.colors && reference.texcoords);
    test_formats();
    test_stl();
    test_frames_and_textures();
    test_texture_decode();
    test_info();
    test_names();
    test_sniffing();
    test_missing_siblings();
    test_shared_data();
    sl_mesh_release(&reference);
    return check_report();
}
