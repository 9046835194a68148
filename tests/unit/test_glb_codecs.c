/* GLB quantisation and compression (formats/glb.h), checked by decoding what was written
 * with the tests' own reader (glb_reader.h: meshoptimizer's decoders, Draco's decoder) and
 * comparing with the mesh given, in every encoding:
 *   - positions within the documented bound (sqrt(3)/2 x the grid step), the measured
 *     error in sl_glb_stats equal to the decoded one, POSITION min/max equal to the data;
 *   - the triangles: the same corners (Draco: the same triangles, found through the
 *     nearest given vertex, as Draco reorders and may split vertices);
 *   - normals within the angle their bits allow; texture coordinates within half a step;
 *   - colours: linear in the file, and every sRGB byte back within half a 1/255 step after
 *     linear -> sRGB at the default 12 bits (and not at 8, which is why 12 is the default);
 *   - meshopt bitstreams: the index codec's header byte 0xe1 that EXT_meshopt_compression
 *     requires (Debian's 0.18 writes 0xe0 unless told; its decoder accepts both), 0xa0 for
 *     the vertex codec;
 *   - the same bytes on a second write.
 * With SCANLOD_GLB_OUT set, also writes the quantised, meshopt and Draco variants of the
 * validator samples there (tests/export/test_gltf_validator.sh).
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "../check.h"
#include "core/atomicfile.h"
#include "formats/glb.h"
#include "geometry/kdtree.h"
#include "glb_meshes.h"
#include "glb_reader.h"
#include "shim/oiio_shim.h"

typedef struct mode {
    const char *name;
    int compression, quantize;
} mode;

static const mode modes[] = {{"float", SL_GLB_UNCOMPRESSED, 0},
                             {"quantized", SL_GLB_UNCOMPRESSED, 1},
                             {"meshopt", SL_GLB_MESHOPT, 1},
                             {"meshopt_float", SL_GLB_MESHOPT, 0},
                             {"draco", SL_GLB_DRACO, 0}};

static char tmpdir[512];

/* A 16 x 8 PNG checkerboard, encoded by OpenImageIO, for the textured samples. */
static char *png;
static size_t png_size;

static void make_png(void)
{
    float px[16 * 8 * 3];
    for (int i = 0; i < 16 * 8; i++)
        for (int c = 0; c < 3; c++)
            px[3 * i + c] = ((i % 16) / 4 + (i / 16) / 4) % 2 ? 0.9f : 0.2f * c;
    char path[600];
    snprintf(path, sizeof path, "%s/checker.png", tmpdir);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_image_write(path, 16, 8, 3, px, &err) == 0);
    CHECK(sl_read_file(path, 1 << 20, &png, &png_size, &err) == 0);
    unlink(path);
}

static double extent_of(const sl_mesh *m)
{
    double e = 0;
    for (int k = 0; k < 3; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (uint64_t i = 0; i < m->vertex_count; i++) {
            lo = fmin(lo, m->positions[3 * i + k]);
            hi = fmax(hi, m->positions[3 * i + k]);
        }
        e = fmax(e, hi - lo);
    }
    return e;
}

/* How unlike given vertex j decoded vertex i is in its other attributes (Draco keeps
 * vertices at one position apart when their normals, colours or texcoords differ). */
static double attribute_mismatch(const sl_mesh *m, const glb_decoded *g, uint64_t i, uint32_t j)
{
    double d = 0;
    for (int k = 0; k < 3 && g->normals && m->normals; k++)
        d += fabs(g->normals[3 * i + k] - m->normals[3 * j + k]);
    for (int k = 0; k < 3 && g->colors && m->colors; k++)
        d += fabs(255 * glb_reader_linear_to_srgb(g->colors[4 * i + k]) - m->colors[4 * j + k]);
    for (int k = 0; k < 2 && g->texcoords && m->texcoords; k++)
        d += 100 * fabs(g->texcoords[2 * i + k] -
                        (k ? 1.0 - m->texcoords[2 * j + 1] : m->texcoords[2 * j]));
    return d;
}

/* The given vertex each decoded vertex stands for: the same index, or (Draco) among the
 * given vertices within `radius` of it the one whose other attributes match best. */
static uint32_t *vertex_map(const sl_mesh *m, const glb_decoded *g, int same_order,
                            double radius)
{
    uint32_t *map = malloc(g->vertex_count * sizeof *map + 4);
    sl_kdtree *tree = NULL;
    sl_error err;
    sl_error_init(&err);
    if (!same_order && sl_kdtree_build(&tree, m->positions, m->vertex_count, &err))
        return NULL;
    enum { K = 16 };
    for (uint64_t i = 0; i < g->vertex_count; i++) {
        float q[3] = {(float)g->positions[3 * i], (float)g->positions[3 * i + 1],
                      (float)g->positions[3 * i + 2]};
        if (same_order) {
            map[i] = (uint32_t)i;
            continue;
        }
        uint32_t idx[K];
        float d2[K];
        uint32_t n = sl_kdtree_knn(tree, q, K, idx, d2);
        map[i] = idx[0];
        double best = attribute_mismatch(m, g, i, idx[0]);
        for (uint32_t c = 1; c < n && d2[c] <= radius * radius; c++) {
            double a = attribute_mismatch(m, g, i, idx[c]);
            if (a < best)
                best = a, map[i] = idx[c];
        }
    }
    sl_kdtree_free(tree);
    return map;
}

static int near3(const double *p, const float *q, double radius)
{
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (p[k] - q[k]) * (p[k] - q[k]);
    return d2 <= radius * radius;
}

/* Every decoded triangle is a given one: the same corners in the same order (files that
 * keep the vertex order), or (Draco, which renumbers, splits and may merge vertices that
 * look alike) a given triangle of the same orientation whose corners each lie within
 * `radius` of the decoded ones. */
static void check_triangles(const char *what, const sl_mesh *m, const glb_decoded *g,
                            int same_order, double radius)
{
    CHECK_MSG(g->triangle_count == m->triangle_count, "%s: %llu triangles, %llu given", what,
              (unsigned long long)g->triangle_count, (unsigned long long)m->triangle_count);
    uint64_t missing = 0, n = m->vertex_count;
    if (same_order) {
        /* meshopt's index codec may rotate a triangle's corners; order and winding stay */
        for (uint64_t t = 0; t < g->triangle_count && t < m->triangle_count; t++) {
            const uint32_t *a = g->triangles + 3 * t, *b = m->triangles + 3 * t;
            int same = 0;
            for (int r = 0; r < 3; r++)
                same |= a[0] == b[r] && a[1] == b[(r + 1) % 3] && a[2] == b[(r + 2) % 3];
            missing += !same;
        }
        CHECK_MSG(missing == 0, "%s: %llu triangles differ", what, (unsigned long long)missing);
        return;
    }
    uint32_t *first = calloc(n + 1, sizeof *first), *tris = malloc(12 * m->triangle_count + 4);
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        first[m->triangles[i] + 1]++;
    for (uint64_t v = 0; v < n; v++)
        first[v + 1] += first[v];
    uint32_t *fill = malloc((n + 1) * sizeof *fill);
    memcpy(fill, first, (n + 1) * sizeof *fill);
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        tris[fill[m->triangles[i]]++] = (uint32_t)(i / 3);
    sl_kdtree *tree = NULL;
    sl_error err;
    sl_error_init(&err);
    if (sl_kdtree_build(&tree, m->positions, n, &err) == 0)
        for (uint64_t t = 0; t < g->triangle_count; t++) {
            const double *p[3];
            for (int k = 0; k < 3; k++)
                p[k] = g->positions + 3 * (uint64_t)g->triangles[3 * t + k];
            float q[3] = {(float)p[0][0], (float)p[0][1], (float)p[0][2]};
            uint32_t idx[128]; /* a sphere's pole is 49 vertices at one place */
            float d2[128];
            uint32_t found = sl_kdtree_knn(tree, q, 128, idx, d2), hit = 0;
            for (uint32_t c = 0; c < found && !hit && d2[c] <= radius * radius; c++)
                for (uint32_t e = first[idx[c]]; e < first[idx[c] + 1] && !hit; e++) {
                    const uint32_t *v = m->triangles + 3 * (uint64_t)tris[e];
                    for (int r = 0; r < 3 && !hit; r++)
                        hit = near3(p[0], m->positions + 3 * (uint64_t)v[r], radius) &&
                              near3(p[1], m->positions + 3 * (uint64_t)v[(r + 1) % 3], radius) &&
                              near3(p[2], m->positions + 3 * (uint64_t)v[(r + 2) % 3], radius);
                }
            if (!hit && getenv("DEBUG_TRI"))
                fprintf(stderr, "miss (%g %g %g) (%g %g %g) (%g %g %g)\n", p[0][0], p[0][1],
                        p[0][2], p[1][0], p[1][1], p[1][2], p[2][0], p[2][1], p[2][2]);
            missing += !hit;
        }
    sl_kdtree_free(tree);
    CHECK_MSG(missing == 0, "%s: %llu decoded triangles are not given ones", what,
              (unsigned long long)missing);
    free(first), free(fill), free(tris);
}

static double angle_deg(const double *a, const float *b)
{
    double lb = sqrt((double)b[0] * b[0] + (double)b[1] * b[1] + (double)b[2] * b[2]);
    double c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (lb > 0 ? lb : 1);
    return acos(c > 1 ? 1 : c < -1 ? -1 : c) * 180 / 3.14159265358979323846;
}

/* What the decoded file says against the mesh given. */
static void compare(const char *what, const sl_mesh *m, const glb_decoded *g,
                    const sl_glb_stats *st, const mode *mo, const sl_glb_options *o)
{
    int draco = mo->compression == SL_GLB_DRACO, quantized = mo->quantize || draco;
    CHECK_MSG(g->compression == mo->compression, "%s: compression %d", what, g->compression);
    CHECK_MSG(g->quantized == (mo->quantize && !draco), "%s: KHR_mesh_quantization", what);
    if (!draco)
        CHECK_EQ_U64(g->vertex_count, m->vertex_count);
    CHECK_EQ_U64(st->vertices, g->vertex_count);
    CHECK_EQ_U64(st->bytes, g->file_size);
    double e = extent_of(m), step = e / ((1 << o->position_bits) - 1);
    double bound = quantized ? sqrt(3.0) / 2 * step : 0;
    uint32_t *map = vertex_map(m, g, !draco, 2 * bound + 1e-6 * e);
    if (!map)
        return;
    check_triangles(what, m, g, !draco, 2 * bound + 1e-6 * e);
    double worst = 0, normal_worst = 0, color_worst = 0, uv_worst = 0;
    for (uint64_t i = 0; i < g->vertex_count; i++) {
        const float *p = m->positions + 3 * map[i];
        double d2 = 0;
        for (int k = 0; k < 3; k++)
            d2 += (g->positions[3 * i + k] - p[k]) * (g->positions[3 * i + k] - p[k]);
        worst = fmax(worst, sqrt(d2));
        const float *n = m->normals ? m->normals + 3 * map[i] : NULL;
        if (g->normals && n && n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0) /* 0: (0, 0, 1) */
            normal_worst = fmax(normal_worst, angle_deg(g->normals + 3 * i, m->normals + 3 * map[i]));
        for (int k = 0; g->colors && k < 4; k++) {
            double v = g->colors[4 * i + k];
            double back = 255 * (k < 3 ? glb_reader_linear_to_srgb(v) : v);
            color_worst = fmax(color_worst, fabs(back - m->colors[4 * map[i] + k]));
        }
        for (int k = 0; g->texcoords && k < 2; k++) {
            double t = k ? 1.0 - m->texcoords[2 * map[i] + 1] : m->texcoords[2 * map[i]];
            uv_worst = fmax(uv_worst, fabs(g->texcoords[2 * i + k] - t));
        }
    }
    CHECK_MSG(worst <= bound + 1e-6 * e, "%s: a vertex moved %.9g, bound %.9g", what, worst, bound);
    CHECK_MSG(fabs(st->position_bound - bound) <= 1e-6 * e, "%s: stats bound %.9g vs %.9g", what,
              st->position_bound, bound);
    CHECK_MSG(fabs(st->position_error_max - worst) <= 1e-6 * e, "%s: stats error %.9g, decoded %.9g",
              what, st->position_error_max, worst);
    if (quantized && m->vertex_count > 1000) /* a cube's corners lie on the grid */
        CHECK_MSG(worst > 0.1 * bound, "%s: a quantised mesh moved only %.3g of its bound", what,
                  worst / bound);
    if (m->normals) {
        double tol = quantized ? 200.0 / ((1 << (o->normal_bits - 1)) - 1) : 1e-4;
        CHECK_MSG(g->normals && normal_worst <= tol, "%s: normals off by %.3g deg (tol %.3g)",
                  what, normal_worst, tol);
    }
    if (m->colors)
        CHECK_MSG(g->colors && color_worst <= 0.5, "%s: an sRGB byte came back %.3g steps off",
                  what, color_worst);
    if (m->texcoords) {
        CHECK_MSG(g->image_size == png_size && !memcmp(g->image, png, png_size) &&
                      !strcmp(g->mime, "image/png"),
                  "%s: the embedded image", what);
        double tol = quantized ? 0.5 / ((1 << o->texcoord_bits) - 1) + 1e-6 : 1e-7;
        CHECK_MSG(g->texcoords && uv_worst <= tol, "%s: texcoords off by %.3g (tol %.3g)", what,
                  uv_worst, tol);
    }
    if (mo->compression == SL_GLB_MESHOPT) {
        CHECK_MSG(g->index_header == 0xe1, "%s: index stream header 0x%02x (must be 0xe1)", what,
                  g->index_header);
        CHECK_MSG(g->vertex_header == 0xa0, "%s: vertex stream header 0x%02x", what,
                  g->vertex_header);
    }
    free(map);
}

/* Writes `m` in every mode, decodes and compares; the bytes must repeat. */
static void round_trips(const char *name, const sl_mesh *m, const char *out_dir)
{
    for (size_t i = 0; i < sizeof modes / sizeof modes[0]; i++) {
        const mode *mo = &modes[i];
        sl_glb_options o = sl_glb_default_options();
        o.compression = mo->compression;
        o.quantize = mo->quantize;
        if (m->texcoords) {
            o.image = png, o.image_size = png_size;
            o.image_mime_type = "image/png";
        }
        char path[700], again[700], what[128];
        snprintf(what, sizeof what, "%s %s", name, mo->name);
        snprintf(path, sizeof path, "%s/%s.%s.glb", tmpdir, name, mo->name);
        snprintf(again, sizeof again, "%s/%s.%s.again.glb", tmpdir, name, mo->name);
        sl_error err;
        sl_error_init(&err);
        sl_glb_stats st;
        int rc = sl_glb_write(path, m, "{\"scanlod\":{\"level\":0}}", &o, &st, &err);
        CHECK_MSG(rc == 0, "%s: %s", what, err.message);
        if (rc)
            continue;
        glb_decoded g;
        char why[256];
        if (glb_decode(path, &g, why, sizeof why) == 0)
            compare(what, m, &g, &st, mo, &o);
        else
            CHECK_MSG(0, "%s: %s", what, why);
        CHECK(sl_glb_write(again, m, "{\"scanlod\":{\"level\":0}}", &o, NULL, &err) == 0);
        char *a = NULL, *b = NULL;
        size_t na = 0, nb = 0;
        CHECK(sl_read_file(path, 1 << 28, &a, &na, &err) == 0 &&
              sl_read_file(again, 1 << 28, &b, &nb, &err) == 0);
        CHECK_MSG(na == nb && a && b && memcmp(a, b, na) == 0, "%s: not deterministic", what);
        free(a), free(b);
        if (out_dir && mo->quantize + mo->compression > 0) { /* float: test_glb's samples */
            char sample[1200];
            snprintf(sample, sizeof sample, "%s/%s.%s.glb", out_dir, name, mo->name);
            CHECK(sl_glb_write(sample, m, "{\"scanlod\":{\"level\":0}}", &o, NULL, &err) == 0);
        }
        glb_decoded_free(&g);
        unlink(path);
        unlink(again);
    }
}

/* Per-vertex texture coordinates from the positions' x and y (in [0, 1]). */
static void add_texcoords(sl_mesh *m)
{
    double e = extent_of(m);
    m->texcoords = malloc(8 * m->vertex_count);
    for (uint64_t i = 0; i < m->vertex_count; i++)
        for (int k = 0; k < 2; k++)
            m->texcoords[2 * i + k] = (float)(0.5 + 0.45 * m->positions[3 * i + k] / e);
}

/* Every sRGB byte in every channel, alpha too. */
static void add_ramp_colors(sl_mesh *m)
{
    free(m->colors);
    m->colors = malloc(4 * m->vertex_count);
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        m->colors[4 * i] = (uint8_t)i;
        m->colors[4 * i + 1] = (uint8_t)(255 - i);
        m->colors[4 * i + 2] = (uint8_t)(i * 7);
        m->colors[4 * i + 3] = (uint8_t)(i * 3);
    }
}

/* 8 bits of linear light cannot hold the dark sRGB bytes: why color_bits defaults to 12. */
static void test_eight_bit_linear_is_not_enough(void)
{
    sl_mesh m;
    meshes_grid(&m, 17, 1, 1);
    add_ramp_colors(&m);
    sl_glb_options o = sl_glb_default_options();
    o.color_bits = 8;
    char path[600];
    snprintf(path, sizeof path, "%s/ramp8.glb", tmpdir);
    sl_error err;
    sl_error_init(&err);
    sl_glb_stats st;
    CHECK(sl_glb_write(path, &m, NULL, &o, &st, &err) == 0);
    CHECK_MSG(st.color_error_max > 1.0, "8-bit linear: worst %.3g sRGB steps", st.color_error_max);
    o.color_bits = 12;
    CHECK(sl_glb_write(path, &m, NULL, &o, &st, &err) == 0);
    CHECK_MSG(st.color_error_max <= 0.5, "12-bit linear: worst %.3g sRGB steps",
              st.color_error_max);
    unlink(path);
    sl_mesh_release(&m);
}

static void test_options_rejected(void)
{
    sl_mesh m;
    meshes_cube(&m, 0, 1, 1, 1);
    sl_glb_options o = sl_glb_default_options();
    o.position_bits = 17;
    char path[600];
    snprintf(path, sizeof path, "%s/bad.glb", tmpdir);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_glb_write(path, &m, NULL, &o, NULL, &err) == SL_E_INTERNAL);
    CHECK(access(path, F_OK) != 0);
    sl_mesh_release(&m);
}

int main(void)
{
    snprintf(tmpdir, sizeof tmpdir, "%s/scanlod-glbc.XXXXXX",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    if (!mkdtemp(tmpdir)) {
        perror("mkdtemp");
        return 1;
    }
    const char *out = getenv("SCANLOD_GLB_OUT");
    out = out && out[0] ? out : NULL;
    make_png();
    sl_mesh m;
    meshes_cube(&m, -0.5f, 0.5f, 1, 1);
    round_trips("cube_all", &m, out);
    sl_mesh_release(&m);
    float c[3] = {0.5f, -2, 3};
    meshes_sphere(&m, 24, 48, c, 1);
    add_texcoords(&m);
    round_trips("sphere_uv", &m, out);
    sl_mesh_release(&m);
    meshes_grid(&m, 17, 1, 1);
    add_ramp_colors(&m);
    round_trips("color_ramp", &m, out);
    sl_mesh_release(&m);
    meshes_grid(&m, 300, 1, 1); /* 90000 vertices: 32-bit indices */
    round_trips("grid_uint32", &m, out);
    sl_mesh_release(&m);
    const char *scans[] = {"cow", "fandisk", "bun_zipper_res3", "rocker_arm"};
    for (size_t i = 0; i < sizeof scans / sizeof scans[0]; i++) {
        if (meshes_read_scan(scans[i], &m) != 0) {
            CHECK_MSG(0, "cannot read scan %s", scans[i]);
            continue;
        }
        meshes_vertex_normals(&m);
        round_trips(scans[i], &m, out);
        sl_mesh_release(&m);
    }
    test_eight_bit_linear_is_not_enough();
    test_options_rejected();
    free(png);
    rmdir(tmpdir);
    return check_report();
}
