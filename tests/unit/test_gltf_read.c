/* The glTF/GLB reader beyond plain float files (test_scan_read.c has those):
 * - the bundled sphere written by scanlod's own GLB writer quantised (KHR_mesh_quantization),
 *   meshopt-compressed (EXT_meshopt_compression) and Draco-compressed
 *   (KHR_draco_mesh_compression), read back within the writer's own error bounds;
 * - gltfpack's files (an independent writer, when the benchmark's npm peers are installed):
 *   quantised with KHR_texture_transform and EXT meshopt, and KHR meshopt with the vertex
 *   codec version 1 that Debian's meshoptimizer 0.18 cannot decode (refused, said so);
 * - primitive modes (strip, fan, points, lines), sparse accessors, data: URIs, a mirroring
 *   node, TEXCOORD_1 with a texture transform, primitives with other materials, a meshopt
 *   stream that does not decode with and without its fallback.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "formats/glb.h"
#include "formats/scan_read.h"
#include "tests/check.h"
#include "tests/unit/scan_test_files.h"

static sl_mesh ref;
static unsigned char png[4096];
static size_t png_size;
static char tmp[] = "/tmp/scanlod-gltf-XXXXXX";

static long nearest(const float *p, double *dist)
{
    long best = -1;
    *dist = INFINITY;
    for (uint64_t i = 0; i < ref.vertex_count; i++) {
        const float *q = ref.positions + 3 * i;
        double d = 0;
        for (int k = 0; k < 3; k++)
            d += ((double)p[k] - q[k]) * ((double)p[k] - q[k]);
        d = sqrt(d);
        if (d < *dist)
            *dist = d, best = (long)i;
    }
    return best;
}

typedef struct tolerances {
    double position, normal_deg, uv;
    int color; /* -1: no colours expected */
} tolerances;

/* Every vertex of m is a reference vertex (within the tolerances) with its attributes. */
static void check_like_reference(const char *what, const sl_mesh *m, tolerances t)
{
    double worst[4] = {0, 0, 0, 0};
    CHECK_MSG(m->triangle_count == ref.triangle_count && m->vertex_count >= ref.vertex_count &&
                  m->normals && m->texcoords && (t.color < 0) == (m->colors == NULL),
              "%s: %llu triangles, %llu vertices", what, (unsigned long long)m->triangle_count,
              (unsigned long long)m->vertex_count);
    for (uint64_t v = 0; m->normals && m->texcoords && v < m->vertex_count; v++) {
        double d, dot = 0;
        long r = nearest(m->positions + 3 * v, &d);
        for (int k = 0; k < 3; k++)
            dot += (double)m->normals[3 * v + k] * ref.normals[3 * r + k];
        worst[0] = fmax(worst[0], d);
        worst[1] = fmax(worst[1], acos(fmin(1.0, dot)) * 180 / M_PI);
        for (int k = 0; k < 2; k++)
            worst[2] = fmax(worst[2], fabs(m->texcoords[2 * v + k] - ref.texcoords[2 * r + k]));
        for (int k = 0; m->colors && k < 3; k++)
            worst[3] = fmax(worst[3], abs(m->colors[4 * v + k] - ref.colors[4 * r + k]));
    }
    CHECK_MSG(worst[0] <= t.position && worst[1] <= t.normal_deg && worst[2] <= t.uv &&
                  worst[3] <= (t.color < 0 ? 0 : t.color),
              "%s: position %.3g (%.3g), normal %.3g deg (%.3g), uv %.3g (%.3g), colour %.0f",
              what, worst[0], t.position, worst[1], t.normal_deg, worst[2], t.uv, worst[3]);
}

/* SCANLOD_SCAN_SEED_DIR=DIR: the files written here are kept in DIR/gltf as fuzz seeds
 * (tests/fuzz/README.md); otherwise removed. */
static void keep_seed(const char *path)
{
    const char *dir = getenv("SCANLOD_SCAN_SEED_DIR"), *base = strrchr(path, '/');
    char to[1024];
    snprintf(to, sizeof to, "%s/gltf", dir ? dir : "");
    if (!dir || (mkdir(to, 0777) != 0 && access(to, W_OK) != 0)) {
        unlink(path);
        return;
    }
    snprintf(to + strlen(to), sizeof to - strlen(to), "%s", base);
    if (rename(path, to) != 0)
        unlink(path);
}

static int read_file(const char *path, sl_mesh *m, sl_error *err)
{
    sl_error_init(err);
    return sl_scan_read(path, NULL, m, NULL, NULL, err);
}

/* The reference written by sl_glb_write with `o`, read back. */
static void round_trip(const char *what, sl_glb_options o, double normal_deg, double uv)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s.glb", tmp, what);
    o.image = png, o.image_size = png_size, o.image_mime_type = "image/png";
    sl_glb_stats stats;
    sl_error err;
    sl_error_init(&err);
    if (sl_glb_write(path, &ref, NULL, &o, &stats, &err)) {
        CHECK_MSG(0, "%s: cannot write: %s", what, err.message);
        return;
    }
    sl_mesh m;
    int rc = read_file(path, &m, &err);
    CHECK_MSG(rc == 0, "%s: %s", what, err.message);
    if (rc == 0) {
        tolerances t = {stats.position_bound + 1e-6, normal_deg, uv, 1};
        check_like_reference(what, &m, t);
        CHECK_MSG(m.texture_data && m.texture_size == png_size, "%s: the embedded texture", what);
    }
    sl_mesh_release(&m);
    keep_seed(path);
}

static void test_scanlod_writer(void)
{
    sl_glb_options o = sl_glb_default_options();
    round_trip("float", o, 1e-3, 1e-6);
    o.quantize = 1;
    round_trip("quantized", o, 1.0, 2.0 / 4095);
    o.compression = SL_GLB_MESHOPT;
    round_trip("meshopt", o, 1.0, 2.0 / 4095);
    o.compression = SL_GLB_DRACO;
    o.quantize = 0;
    round_trip("draco", o, 1.0, 2.0 / 4095);
}

/* gltfpack (meshoptimizer 1.3 from npm, the benchmark's peer) on sphere.gltf. */
static void test_gltfpack(void)
{
    char tool[1024], in[1024], out[256], cmd[3000];
    check_source_path("scripts/bench/peers/npm/node_modules/.bin/gltfpack", tool, sizeof tool);
    check_source_path("tests/data/inputs/sphere.gltf", in, sizeof in);
    if (access(tool, X_OK) != 0) {
        printf("SKIP: gltfpack: no %s (scripts/install-deps.sh installs it)\n", tool);
        return;
    }
    static const struct { const char *name, *flags; int code; } runs[] = {
        {"gp_c", "-c", 0}, {"gp_noq", "-c -noq", 0}, {"gp_khr", "-cc -ce khr", SL_E_UNSUPPORTED}};
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) {
        snprintf(out, sizeof out, "%s/%s.glb", tmp, runs[i].name);
        snprintf(cmd, sizeof cmd, "'%s' -i '%s' -o '%s' %s >/dev/null 2>&1", tool, in, out,
                 runs[i].flags);
        if (system(cmd) != 0) {
            CHECK_MSG(0, "gltfpack %s failed", runs[i].flags);
            continue;
        }
        sl_mesh m;
        sl_error err;
        int rc = read_file(out, &m, &err);
        CHECK_MSG(rc == runs[i].code, "gltfpack %s: %d %s", runs[i].flags, rc, err.message);
        if (rc == 0) {
            tolerances t = {2e-4, 3.0, 2e-3, 4}; /* COLOR_0 as 8-bit linear: +-3 in sRGB */
            check_like_reference(runs[i].name, &m, t);
        } else {
            CHECK_MSG(strstr(err.message, "vertex codec version 1 needs meshoptimizer"), "%s",
                      err.message);
        }
        sl_mesh_release(&m);
        keep_seed(out);
    }
}

static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

static void base64(const void *data, size_t n, char *out)
{
    const unsigned char *p = data;
    size_t i = 0;
    for (; i + 3 <= n; i += 3) {
        uint32_t v = (uint32_t)p[i] << 16 | (uint32_t)p[i + 1] << 8 | p[i + 2];
        for (int k = 0; k < 4; k++)
            *out++ = b64[(v >> (18 - 6 * k)) & 63];
    }
    if (i < n) { /* one or two bytes left: two or three digits and padding */
        uint32_t v = (uint32_t)p[i] << 16 | (i + 1 < n ? (uint32_t)p[i + 1] << 8 : 0);
        *out++ = b64[v >> 18], *out++ = b64[(v >> 12) & 63];
        *out++ = i + 1 < n ? b64[(v >> 6) & 63] : '=';
        *out++ = '=';
    }
    *out = 0;
}

static int read_json(const char *json, sl_mesh *m, sl_error *err)
{
    sl_error_init(err);
    return sl_scan_read_memory(json, strlen(json), "test.gltf", NULL, NULL, NULL, m, NULL, err);
}

/* A unit quad: 4 positions (data: URI), a strip, a fan with indices, a mirrored node. */
static void test_modes(void)
{
    float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    uint16_t idx[4] = {0, 1, 3, 2};
    unsigned char bin[56];
    memcpy(bin, pos, 48), memcpy(bin + 48, idx, 8);
    char data[200], json[2000];
    base64(bin, sizeof bin, data);
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":56,\"uri\":"
             "\"data:application/octet-stream;base64,%s\"}],\"bufferViews\":[{\"buffer\":0,"
             "\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":8}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":"
             "\"VEC3\"},{\"bufferView\":1,\"componentType\":5123,\"count\":4,\"type\":\"SCALAR\"}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":5},"
             "{\"attributes\":{\"POSITION\":0},\"indices\":1,\"mode\":6},"
             "{\"attributes\":{\"POSITION\":0},\"mode\":0},"
             "{\"attributes\":{\"POSITION\":0},\"mode\":1}]}],"
             "\"nodes\":[{\"mesh\":0},{\"mesh\":0,\"scale\":[-1,1,1]}],"
             "\"scenes\":[{\"nodes\":[0,1]}]}",
             data);
    sl_mesh m;
    sl_error err;
    int rc = read_json(json, &m, &err);
    CHECK_MSG(rc == 0, "%s", err.message);
    /* per node: strip 2 + fan 2 triangles; points add 4 vertices; lines are skipped */
    CHECK_MSG(rc || (m.triangle_count == 8 && m.vertex_count == 24), "%llu %llu",
              (unsigned long long)m.triangle_count, (unsigned long long)m.vertex_count);
    static const uint32_t expect[12] = {0, 1, 2, 1, 3, 2, 5, 7, 4, 7, 6, 4};
    CHECK(rc || !memcmp(m.triangles, expect, sizeof expect));
    int facing = 1; /* the mirrored copy's triangles still face +z: their winding turned */
    for (uint64_t t = 0; rc == 0 && t < m.triangle_count; t++) {
        const uint32_t *tri = m.triangles + 3 * t;
        const float *a = m.positions + 3 * tri[0], *b = m.positions + 3 * tri[1],
                    *c = m.positions + 3 * tri[2];
        facing &= (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0;
    }
    CHECK(facing);
    CHECK_MSG(rc || strstr(m.warnings, "line primitives are not read"), "%s", m.warnings);
    sl_mesh_release(&m);
}

/* Sparse values over a zero accessor and over a view; TEXCOORD_1 with a transform; a
 * second material without the texture. */
static void test_sparse_and_texcoords(void)
{
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, uv[6] = {0, 0, 1, 0, 0, 1}, moved[3] = {5, 5, 5};
    uint8_t which[1] = {2};
    unsigned char bin[64] = {0};
    memcpy(bin, pos, 36), memcpy(bin + 36, uv, 24), memcpy(bin + 60, which, 1);
    unsigned char bin2[100] = {0};
    memcpy(bin2, bin, 64), memcpy(bin2 + 64, moved, 12);
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":76}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,"
        "\"byteLength\":24},{\"buffer\":0,\"byteOffset\":60,\"byteLength\":1},{\"buffer\":0,"
        "\"byteOffset\":64,\"byteLength\":12}],\"accessors\":[{\"bufferView\":0,\"componentType\":"
        "5126,\"count\":3,\"type\":\"VEC3\",\"sparse\":{\"count\":1,\"indices\":{\"bufferView\":2,"
        "\"componentType\":5121},\"values\":{\"bufferView\":3}}},{\"bufferView\":1,"
        "\"componentType\":5126,\"count\":3,\"type\":\"VEC2\"}],\"meshes\":[{\"primitives\":["
        "{\"attributes\":{\"POSITION\":0,\"TEXCOORD_1\":1},\"material\":0},"
        "{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"material\":1}]}],"
        "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0,\"texCoord\":1,"
        "\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.5,0.25],\"scale\":[0.5,0.5]}}}}},"
        "{}],\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"skin.png\"}]}";
    size_t size;
    unsigned char *file = gltf_build_glb(json, bin2, 76, &size);
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_scan_read_memory(file, size, "sparse.glb", NULL, NULL, NULL, &m, NULL, &err);
    CHECK_MSG(rc == 0, "%s", err.message);
    if (rc == 0) {
        CHECK(m.vertex_count == 6 && m.positions[6] == 5 && m.positions[15] == 5);
        /* vertex 1: uv (1, 0) -> (0.5 * 1 + 0.5, 0.5 * 0 + 0.25) = (1, 0.25) -> v up 0.75 */
        CHECK_NEAR(m.texcoords[2], 1.0, 1e-6);
        CHECK_NEAR(m.texcoords[3], 0.75, 1e-6);
        CHECK(isnan(m.texcoords[6]) && isnan(m.texcoords[11])); /* the other material's */
        CHECK(!strcmp(m.texture_file, "skin.png"));
    }
    sl_mesh_release(&m);
    free(file);
}

/* A meshopt view whose stream does not decode: its plain bytes when the buffer holds them
 * (a warning), else the reason; a version-1 vertex stream said so. */
static void test_meshopt_fallback(void)
{
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    unsigned char bin[52] = {0};
    memcpy(bin, pos, 36);
    bin[36] = 0xa1; /* a vertex stream of codec version 1, then garbage */
    char json[2000];
    for (int fallback = 0; fallback < 2; fallback++) {
        snprintf(json, sizeof json,
                 "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":52},"
                 "{\"byteLength\":36%s}],\"bufferViews\":[{\"buffer\":%d,\"byteLength\":36,"
                 "\"extensions\":{\"EXT_meshopt_compression\":{\"buffer\":0,\"byteOffset\":36,"
                 "\"byteLength\":16,\"byteStride\":12,\"count\":3,\"mode\":\"ATTRIBUTES\"}}}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":"
                 "\"VEC3\"}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}]}",
                 fallback ? ",\"extensions\":{\"EXT_meshopt_compression\":{\"fallback\":true}}" : "",
                 fallback ? 1 : 0);
        size_t size;
        unsigned char *file = gltf_build_glb(json, bin, sizeof bin, &size);
        sl_mesh m;
        sl_error err;
        sl_error_init(&err);
        int rc = sl_scan_read_memory(file, size, "mo.glb", NULL, NULL, NULL, &m, NULL, &err);
        if (!fallback)
            CHECK_MSG(rc == 0 && m.positions[3] == 1 && strstr(m.warnings, "fallback is read"),
                      "%d %s %s", rc, err.message, m.warnings);
        else
            CHECK_MSG(rc == SL_E_UNSUPPORTED && strstr(err.message, "vertex codec version 1"),
                      "%d %s", rc, err.message);
        sl_mesh_release(&m);
        free(file);
    }
}

int main(void)
{
    char path[1024];
    sl_error err;
    check_source_path("tests/data/inputs/sphere.ply", path, sizeof path);
    if (read_file(path, &ref, &err) || !mkdtemp(tmp)) {
        CHECK_MSG(0, "%s", err.message);
        return check_report();
    }
    check_source_path("tests/data/inputs/sphere.png", path, sizeof path);
    FILE *f = fopen(path, "rb");
    png_size = f ? fread(png, 1, sizeof png, f) : 0;
    if (f)
        fclose(f);
    test_scanlod_writer();
    test_gltfpack();
    test_modes();
    test_sparse_and_texcoords();
    test_meshopt_fallback();
    rmdir(tmp);
    sl_mesh_release(&ref);
    return check_report();
}
