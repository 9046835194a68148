/* Hostile and broken inputs for every scan reader but PLY's (test_ply_malformed.c): each
 * gives one error of the right class naming the file and the cause, with nothing left in
 * the mesh, and nothing large is allocated for a small file (the counts are checked
 * first; this test runs under ASan with its allocator's limits in the sanitizer build).
 * What a reader keeps (NaN coordinates, a missing texture) reads without error.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/artifact.h"
#include "formats/scan_read.h"
#include "tests/check.h"
#include "tests/unit/scan_test_files.h"

/* SCANLOD_SCAN_SEED_DIR=DIR: every input is also written to DIR/<format>/<name>, the
 * fuzzers' seeds (tests/fuzz/README.md). */
static void keep_seed(const char *name, const void *data, size_t len)
{
    const char *dir = getenv("SCANLOD_SCAN_SEED_DIR"), *ext = strrchr(name, '.');
    if (!dir || !ext)
        return;
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, !strcmp(ext + 1, "glb") ? "gltf" : ext + 1);
    mkdir(path, 0777);
    snprintf(path + strlen(path), sizeof path - strlen(path), "/%s", name);
    FILE *f = fopen(path, "wb");
    if (f) {
        fwrite(data, 1, len, f);
        fclose(f);
    }
}

/* Reads `len` bytes as `name` and checks the outcome: `code` 0 for a success, else that
 * error with `cause` in its message. */
static void expect_n(const char *name, const void *data, size_t len, const sl_scan_limits *lim,
                     int code, const char *cause)
{
    keep_seed(name, data, len);
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_scan_read_memory(data, len, name, NULL, NULL, lim, &m, NULL, &err);
    if (code == 0) {
        CHECK_MSG(rc == 0, "%s: expected to read, got %d: %s", name, rc, err.message);
    } else {
        CHECK_MSG(rc == code && err.code == code && strstr(err.message, cause) &&
                      !strcmp(err.file, name),
                  "%s: expected %s '%s', got %s '%s: %s'", name, sl_error_name(code), cause,
                  sl_error_name(rc), err.file, err.message);
        CHECK_MSG(m.vertex_count == 0 && !m.positions && !m.triangles, "%s: mesh left", name);
    }
    sl_mesh_release(&m);
}

static void expect(const char *name, const char *text, int code, const char *cause)
{
    expect_n(name, text, strlen(text), NULL, code, cause);
}

/* A table of texts and what each must give. */
struct scan_case {
    const char *name, *text;
    int code;
    const char *cause;
};

static void expect_all(const struct scan_case *cases, size_t n)
{
    for (size_t i = 0; i < n; i++)
        expect(cases[i].name, cases[i].text, cases[i].code, cases[i].cause);
}

static void test_obj(void)
{
    static const struct scan_case cases[] = {
        {"range.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n",
         SL_E_BADINPUT, "line 3: vertex index 3 is out of range (2 vertices)"},
        {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
         SL_E_BADINPUT, "vertex index 0 is out of range"},
        {"back.obj", "v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n",
         SL_E_BADINPUT, "vertex index -2 is out of range"},
        {"vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
         SL_E_BADINPUT, "texture coordinate index 2 is out of range"},
        {"corner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", SL_E_BADINPUT, "bad face corner"},
        {"corner4.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1/1 2 3\n",
         SL_E_BADINPUT, "bad face corner"},
        {"short.obj", "v 1 2\n", SL_E_BADINPUT, "line 1: a vertex needs x y z"},
        {"word.obj", "v 1 2 three\n", SL_E_BADINPUT, "a vertex needs x y z (not a number)"},
        {"vn.obj", "vn 1 0\n", SL_E_BADINPUT, "a normal needs 3 numbers"},
        {"huge.obj", "v 0 0 0\nf 1 1 1 99999999999999999999\n", SL_E_BADINPUT, "bad face corner"},
        {"nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\nf 1 2\n", 0, NULL},
    };
    expect_all(cases, sizeof cases / sizeof cases[0]);
    /* kept: NaN coordinates (the range stage drops them), polygons fanned, short faces */
    char *big = malloc(20000);
    strcpy(big, "v 0 0 0\nf");
    for (int i = 0; i < 1100; i++)
        strcat(big, " 1");
    expect("corners.obj", big, SL_E_LIMIT, "face has more than 1024 corners");
    free(big);
    sl_scan_limits lim = sl_scan_default_limits();
    lim.max_vertices = 2;
    expect_n("limit.obj", "v 0 0 0\nv 0 0 0\nv 0 0 0\n", 24, &lim, SL_E_LIMIT,
             "3 vertices (limit 2)");
}

static void test_stl(void)
{
    static const struct scan_case cases[] = {
        {"solid.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n",
         SL_E_BADINPUT, "line 4: expected three numbers"},
        {"word.stl", "solid x\nfacet normal 0 0 1\nbanana\n",
         SL_E_BADINPUT, "line 3: unexpected 'banana'"},
        {"nan.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex nan 0 0\nvertex 1 0 0\n"
         "" "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n",
         0, NULL},
    };
    expect_all(cases, sizeof cases / sizeof cases[0]);
    unsigned char bin[134] = "binary";
    sl_put_u32(bin + 80, 1000);
    expect_n("short.stl", bin, sizeof bin, NULL, SL_E_BADINPUT,
             "declares 1000 triangles (50084 bytes) but holds 134 bytes");
    sl_put_u32(bin + 80, 0xFFFFFFFFu); /* 200 GB of triangles in 134 bytes */
    expect_n("huge.stl", bin, sizeof bin, NULL, SL_E_BADINPUT, "declares 4294967295 triangles");
    expect_n("tiny.stl", "abc", 3, NULL, SL_E_BADINPUT, "too short for a binary STL");
    unsigned char pad[84 + 50 + 2] = "binary";
    sl_put_u32(pad + 80, 1);
    expect_n("padded.stl", pad, sizeof pad, NULL, 0, NULL); /* extra bytes: a warning */
}

static void test_off(void)
{
    static const struct scan_case cases[] = {
        {"huge.off", "OFF\n1000000000 1 0\n0 0 0\n",
         SL_E_BADINPUT, "declares 1000000000 vertices and 1 faces but only"},
        {"faces.off", "OFF\n3 1000000000000000000 0\n0 0 0\n1 0 0\n0 1 0\n",
         SL_E_BADINPUT, "but only"},
        {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n",
         SL_E_BADINPUT, "line 6: vertex index 5 is out of range (3)"},
        {"ends.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
         SL_E_BADINPUT, "the file ends after 1 of 2 faces"},
        {"cols.off", "NOFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
         SL_E_BADINPUT, "vertex 0: 3 numbers do not fit 'NOFF'"},
        {"4d.off", "4OFF\n1 0 0\n0 0 0 1\n", SL_E_UNSUPPORTED, "'4OFF' is not supported"},
        {"bin.off", "OFF BINARY\n", SL_E_UNSUPPORTED, "'OFF BINARY' is not supported"},
        {"neg.off", "OFF\n-3 1 0\n", SL_E_BADINPUT, "expected the vertex and face counts"},
        {"tail.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n7 7\n",
         SL_E_BADINPUT, "unexpected data after the last face"},
        {"corners.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n5000 0 1 2\n",
         SL_E_BADINPUT, "corner count 5000 is out of range"},
        {"ok.off", "OFF # a comment\n3 1 0\n0 0 0 # one\n1 0 0\n0 1 0\n\n3 0 1 2\n", 0, NULL},
        {"nan.off", "OFF\n3 1 0\nnan 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 0, NULL},
    };
    expect_all(cases, sizeof cases / sizeof cases[0]);
}

static void test_xyz(void)
{
    static const struct scan_case cases[] = {
        {"five.xyz", "0 0 0 1 2\n", SL_E_UNSUPPORTED, "5 columns"},
        {"mixed.xyz", "0 0 0\n1 1\n", SL_E_BADINPUT,
         "line 2: 2 numbers where the file's points have 3"},
        {"word.xyz", "0 0 0\n1 1 x\n", SL_E_BADINPUT, "line 2: not a number"},
        {"none.xyz", "x y z\n", SL_E_BADINPUT, "no line with three numbers"},
        {"what.xyz", "0 0 0 100 -3 2.5\n1 0 0 7 8 9\n",
         SL_E_UNSUPPORTED, "cannot tell colours from normals"},
        {"two.xyz", "0 0 0 0 0 1 0 0 1\n", SL_E_UNSUPPORTED, "the same kind as the other"},
        {"csv.xyz", "X,Y,Z\n0.5,1,2\n3,4,5e0\n", 0, NULL},
        {"nan.xyz", "nan 0 0\n1 0 0\n", 0, NULL},
    };
    expect_all(cases, sizeof cases / sizeof cases[0]);
}

#define TRIANGLE_ACCESSORS                                                                  \
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}," \
    "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}],"            \
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,"    \
    "\"byteLength\":6}],\"buffers\":[{\"byteLength\":44}],"                                 \
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"

static void expect_glb(const char *name, const char *json, const uint16_t idx[3], int code,
                       const char *cause)
{
    unsigned char bin[44] = {0};
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    memcpy(bin, pos, sizeof pos);
    memcpy(bin + 36, idx, 6);
    size_t size;
    unsigned char *file = gltf_build_glb(json, bin, sizeof bin, &size);
    expect_n(name, file, size, NULL, code, cause);
    free(file);
}

static void test_gltf(void)
{
    static const uint16_t good[3] = {0, 1, 2}, bad[3] = {0, 1, 7};
    const char *asset = "{\"asset\":{\"version\":\"2.0\"}," TRIANGLE_ACCESSORS
                        "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}";
    expect_glb("ok.glb", asset, good, 0, NULL);
    expect_glb("index.glb", asset, bad, SL_E_BADINPUT, "accessors[1] element 2 is vertex 7 of 3");
    expect_glb("cycle.glb", "{\"asset\":{\"version\":\"2.0\"}," TRIANGLE_ACCESSORS
               "\"nodes\":[{\"mesh\":0,\"children\":[1]},{\"children\":[0]}],"
               "\"scenes\":[{\"nodes\":[0]}]}", good, SL_E_BADINPUT, "not trees");
    /* no cycle, but node 3 has two parents: its mesh would be drawn twice per level */
    expect_glb("dag.glb", "{\"asset\":{\"version\":\"2.0\"}," TRIANGLE_ACCESSORS
               "\"nodes\":[{\"children\":[1,2]},{\"children\":[3]},{\"children\":[3]},"
               "{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}", good, SL_E_BADINPUT,
               "nodes[3] is reached twice");
    expect_glb("v1.glb", "{\"asset\":{\"version\":\"1.0\"}}", good, SL_E_UNSUPPORTED, "glTF 1.0");
    expect_glb("ext.glb", "{\"asset\":{\"version\":\"2.0\"},\"extensionsRequired\":"
               "[\"EXT_mesh_gpu_instancing\"]}", good, SL_E_UNSUPPORTED,
               "requires the extension EXT_mesh_gpu_instancing");
    expect_glb("json.glb", "{\"asset\":{\"version\":\"2.0\"},}", good, SL_E_BADINPUT,
               "JSON byte 27: expected a member name");
    expect_glb("count.glb", "{\"asset\":{\"version\":\"2.0\"},\"accessors\":[{\"bufferView\":0,"
               "\"componentType\":5126,\"count\":2000000000,\"type\":\"VEC3\"}],"
               "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"buffers\":[{\"byteLength\":44}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}]}", good,
               SL_E_BADINPUT, "runs past bufferViews[0]");
    expect_glb("zeros.glb", "{\"asset\":{\"version\":\"2.0\"},\"accessors\":[{"
               "\"componentType\":5126,\"count\":2000000000,\"type\":\"VEC3\"}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":0}]}]}",
               good, SL_E_BADINPUT, "has no bufferView and 2000000000 elements");
    expect_glb("view.glb", "{\"asset\":{\"version\":\"2.0\"},\"bufferViews\":[{\"buffer\":0,"
               "\"byteOffset\":40,\"byteLength\":36}],\"buffers\":[{\"byteLength\":44}]}", good,
               SL_E_BADINPUT, "bufferViews[0]: bytes 40..76 lie outside buffer 0");
    /* a .gltf whose buffer is a file: read from memory, there is no folder to look in */
    expect("ext.gltf", "{\"asset\":{\"version\":\"2.0\"},\"accessors\":[{\"bufferView\":0,"
           "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],\"bufferViews\":[{\"buffer\":0,"
           "\"byteLength\":36}],\"buffers\":[{\"byteLength\":36,\"uri\":\"missing.bin\"}],"
           "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}]}", SL_E_BADINPUT,
           "buffers[0] 'missing.bin': 'missing.bin': no folder to look in");
    expect("uri.gltf", "{\"asset\":{\"version\":\"2.0\"},\"accessors\":[{\"bufferView\":0,"
           "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],\"bufferViews\":[{\"buffer\":0,"
           "\"byteLength\":36}],\"buffers\":[{\"byteLength\":36,\"uri\":\"data:x/y;base64,A$==\"}],"
           "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}]}", SL_E_BADINPUT,
           "not valid base64");
    unsigned char head[20] = "glTF";
    sl_put_u32(head + 4, 2), sl_put_u32(head + 8, 1000000);
    expect_n("cut.glb", head, sizeof head, NULL, SL_E_BADINPUT, "GLB declares 1000000 bytes");
}

/* A missing buffer file and a missing image, on disk. */
static void test_gltf_files(void)
{
    static const char gltf[] =
        "{\"asset\":{\"version\":\"2.0\"},\"accessors\":[{\"bufferView\":0,\"componentType\":"
        "5126,\"count\":3,\"type\":\"VEC3\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
        "\"buffers\":[{\"byteLength\":36,\"uri\":\"a%20b.bin\"}],\"meshes\":[{\"primitives\":"
        "[{\"attributes\":{\"POSITION\":0},\"material\":0}]}],\"materials\":[{"
        "\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],\"textures\":"
        "[{\"source\":0}],\"images\":[{\"uri\":\"skin.jpg\"}]}";
    static const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const char *const names[] = {"a.gltf", "a b.bin"};
    char dir[] = "/tmp/scanlod-gltf-XXXXXX", path[256], bin[256];
    if (!mkdtemp(dir))
        return;
    scan_test_write(dir, "a.gltf", gltf, strlen(gltf), path, sizeof path);
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_scan_read(path, NULL, &m, NULL, NULL, &err);
    CHECK_MSG(rc == SL_E_BADINPUT && strstr(err.message, "buffers[0] 'a b.bin': No such file"),
              "%d %s", rc, err.message);
    sl_mesh_release(&m);
    scan_test_write(dir, "a b.bin", pos, sizeof pos, bin, sizeof bin);
    sl_error_init(&err);
    rc = sl_scan_read(path, NULL, &m, NULL, NULL, &err);
    CHECK_MSG(rc == 0 && m.triangle_count == 1 && !strcmp(m.texture_file, "skin.jpg") &&
                  !strcmp(m.warnings, "skin.jpg: missing"),
              "%d %s / %s", rc, err.message, m.warnings);
    sl_mesh_release(&m);
    scan_test_remove(dir, names, 2);
}

int main(void)
{
    test_obj();
    test_stl();
    test_off();
    test_xyz();
    test_gltf();
    test_gltf_files();
    return check_report();
}
