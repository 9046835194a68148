/* Range stage on meshes built in memory: exact drop/weld counts, face normals, file
 * normal fallback, grid triangulation and its orientation, PCA normals on spheres
 * (propagated and viewpoint), degenerate clouds, texture sampling, point set round trip
 * and corruption, and the weld of a large scrambled soup on 1 and 2 threads. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <omp.h>
#include <unistd.h>

#include "shim/oiio_shim.h"
#include "core/artifact.h"
#include "stages/range/range.h"
#include "tests/check.h"
#include "tests/unit/sealed_file.h"

static float *copy_floats(const float *src, size_t n)
{
    float *p = malloc(n * sizeof *p);
    memcpy(p, src, n * sizeof *p);
    return p;
}

static int run(sl_range_config *cfg, sl_mesh *m, const char *dir, sl_pointset *ps,
               sl_range_counts *c)
{
    sl_error err;
    sl_error_init(&err);
    int rc = sl_range_points_from_mesh(cfg, m, dir, ps, c, NULL, &err);
    if (rc != SL_OK)
        fprintf(stderr, "  (range: %s: %s)\n", sl_error_name(rc), err.message);
    return rc;
}

static double angle_deg(const float *a, const double *b)
{
    double la = sqrt((double)a[0] * a[0] + (double)a[1] * a[1] + (double)a[2] * a[2]);
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb);
    return acos(c > 1 ? 1 : c < -1 ? -1 : c) * 180.0 / 3.14159265358979;
}

/* Vertices 4 and 7 weld (7 by -0.0 == +0.0), 5 is NaN, 6 and 8 end up unreferenced;
 * faces: 2 kept + 1 kept after weld, 1 non-finite, 3 degenerate. */
static void build_defect_mesh(sl_mesh *m)
{
    const float v[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 0,
                       NAN, 0, 0, 5, 5, 5, -0.0f, 1, 0, 2, 0, 0, 0, 0, 1};
    const uint32_t t[] = {0, 1, 2, 1, 3, 7, 0, 1, 5, 4, 0, 9, 0, 1, 8, 2, 2, 3, 0, 2, 9};
    sl_mesh_init(m);
    m->vertex_count = 10;
    m->positions = copy_floats(v, 30);
    m->triangle_count = 7;
    m->triangles = malloc(sizeof t);
    memcpy(m->triangles, t, sizeof t);
    m->colors = calloc(40, 1);
    for (int i = 0; i < 10; i++)
        m->colors[4 * i + 3] = 255;
    memcpy(m->colors + 16, "\xc8\x64\x32\xff", 4); /* vertex 4, welded into vertex 0 */
}

static void test_defects(void)
{
    sl_range_config cfg = sl_range_default_config();
    sl_mesh m;
    sl_pointset ps;
    sl_range_counts c;
    build_defect_mesh(&m);
    CHECK(run(&cfg, &m, NULL, &ps, &c) == SL_OK);
    CHECK_EQ_U64(c.points, 5);
    CHECK_EQ_U64(c.welded, 2);
    CHECK_EQ_U64(c.unreferenced, 2);
    CHECK_EQ_U64(c.nonfinite_vertices, 1);
    CHECK_EQ_U64(c.nonfinite_faces, 1);
    CHECK_EQ_U64(c.degenerate_faces, 3);
    CHECK_EQ_U64(c.input_vertices, c.points + c.welded + c.unreferenced + c.nonfinite_vertices);
    CHECK(c.normal_source == SL_NORMALS_FACES);
    /* Point 0 (vertex 0) touches a +z face and a +x face of equal area. */
    CHECK_NEAR(ps.normals[0], sqrt(0.5), 1e-6);
    CHECK_NEAR(ps.normals[1], 0.0, 1e-6);
    CHECK_NEAR(ps.normals[2], sqrt(0.5), 1e-6);
    CHECK_NEAR(ps.normals[3 * 3 + 2], 1.0, 1e-6); /* point 3 = vertex 3: +z only */
    CHECK_NEAR(ps.positions[3 * 4 + 2], 1.0, 0);  /* point 4 = vertex 9 */
    /* Welded colours average: (0,0,0) and (200,100,50). */
    CHECK(ps.colors && ps.colors[0] == 100 && ps.colors[1] == 50 && ps.colors[2] == 25);
    CHECK(strcmp(c.color_source, "vertex") == 0);
    CHECK(ps.bbox_min[0] == 0.0f && ps.bbox_max[0] == 1.0f && ps.bbox_max[2] == 1.0f);
    sl_pointset_release(&ps);
    sl_mesh_release(&m);

    /* More than half the vertices non-finite: garbage, refused. */
    build_defect_mesh(&m);
    for (int i = 0; i < 6; i++)
        m.positions[3 * i + 1] = INFINITY;
    CHECK(run(&cfg, &m, NULL, &ps, &c) == SL_E_BADINPUT);
    sl_mesh_release(&m);
    /* Only degenerate faces: nothing usable. */
    build_defect_mesh(&m);
    m.triangle_count = 1;
    m.triangles[0] = m.triangles[1] = 0;
    CHECK(run(&cfg, &m, NULL, &ps, &c) == SL_E_BADINPUT);
    sl_mesh_release(&m);
}

static void test_file_normals(void)
{
    sl_range_config cfg = sl_range_default_config();
    cfg.normals_from_file = 1;
    sl_mesh m;
    sl_pointset ps;
    sl_range_counts c;
    build_defect_mesh(&m);
    m.normals = calloc(30, sizeof(float));
    for (int i = 0; i < 10; i++)
        m.normals[3 * i] = 2.0f; /* not unit length: normalised */
    m.normals[3 * 3] = 0.0f;     /* vertex 3: zero -> falls back to its face normal */
    CHECK(run(&cfg, &m, NULL, &ps, &c) == SL_OK);
    CHECK(c.normal_source == SL_NORMALS_FILE);
    CHECK_EQ_U64(c.normal_fallbacks, 1);
    CHECK_NEAR(ps.normals[0], 1.0, 1e-6);
    CHECK_NEAR(ps.normals[3 * 3 + 2], 1.0, 1e-6);
    sl_pointset_release(&ps);
    sl_mesh_release(&m);
}

/* 4 x 4 samples on z = 0 at (x, y) = (col, flip ? -row : row); sample (0,0) missing,
 * sample (3,3) lifted by 100 (a depth jump). */
static void build_grid(sl_mesh *m, int flip)
{
    sl_mesh_init(m);
    m->grid_cols = m->grid_rows = 4;
    m->grid_index = malloc(16 * sizeof *m->grid_index);
    m->positions = malloc(16 * 3 * sizeof(float));
    uint32_t n = 0;
    for (int r = 0; r < 4; r++)
        for (int col = 0; col < 4; col++) {
            if (r == 0 && col == 0) {
                m->grid_index[r * 4 + col] = -1;
                continue;
            }
            m->positions[3 * n] = (float)col;
            m->positions[3 * n + 1] = (float)(flip ? -r : r);
            m->positions[3 * n + 2] = (r == 3 && col == 3) ? 100.0f : 0.0f;
            m->grid_index[r * 4 + col] = n++;
        }
    m->vertex_count = n;
}

static void test_grid(void)
{
    sl_range_config cfg = sl_range_default_config();
    for (int flip = 0; flip < 3; flip++) {
        sl_mesh m;
        sl_pointset ps;
        sl_range_counts c;
        build_grid(&m, flip == 1);
        if (flip == 2) { /* scanner stated below the plane: normals face -z */
            m.has_viewpoint = 1;
            m.viewpoint[2] = -10;
        }
        CHECK(run(&cfg, &m, NULL, &ps, &c) == SL_OK);
        CHECK_EQ_U64(c.grid_triangles, 16);
        CHECK_EQ_U64(c.grid_long_edges, 1);
        CHECK_NEAR(c.grid_max_edge, 4.0, 1e-9);
        CHECK_EQ_U64(c.points, 14);
        CHECK_EQ_U64(c.unreferenced, 1);
        CHECK(c.normal_source == SL_NORMALS_RANGE_GRID);
        CHECK(c.grid_flipped == (flip != 0));
        int facing = 0;
        for (uint64_t i = 0; i < ps.count; i++)
            facing += ps.normals[3 * i + 2] == (flip == 2 ? -1.0f : 1.0f);
        CHECK_EQ_U64(facing, ps.count);
        sl_pointset_release(&ps);
        sl_mesh_release(&m);
    }
}

/* Fibonacci sphere of radius r around `centre`, appended at positions[3 * first]. */
static void sphere_points(float *positions, int first, int n, const double centre[3], double r)
{
    for (int i = 0; i < n; i++) {
        double z = 1.0 - (2.0 * i + 1.0) / n, rho = sqrt(1.0 - z * z);
        double phi = i * 2.39996322972865332;
        double p[3] = {rho * cos(phi), rho * sin(phi), z};
        for (int k = 0; k < 3; k++)
            positions[3 * (first + i) + k] = (float)(centre[k] + r * p[k]);
    }
}

static void check_outward(const sl_pointset *ps, const double centre[3], uint64_t first,
                          uint64_t n, double tolerance_deg, const char *what)
{
    uint64_t bad = 0;
    double worst = 0;
    for (uint64_t i = first; i < first + n; i++) {
        double out[3];
        for (int k = 0; k < 3; k++)
            out[k] = ps->positions[3 * i + k] - centre[k];
        double a = angle_deg(ps->normals + 3 * i, out);
        worst = a > worst ? a : worst;
        bad += a > tolerance_deg;
    }
    CHECK_MSG(bad == 0, "%s: %llu of %llu normals off by more than %g deg (worst %.2f)", what,
              (unsigned long long)bad, (unsigned long long)n, tolerance_deg, worst);
}

static void test_pca_spheres(void)
{
    sl_range_config cfg = sl_range_default_config();
    const double c0[3] = {-3, 0.5, 0}, c1[3] = {3, 0, 0.25};
    sl_mesh m;
    sl_pointset ps;
    sl_range_counts c;
    sl_mesh_init(&m);
    m.vertex_count = 6000;
    m.positions = malloc(3 * 6000 * sizeof(float));
    sphere_points(m.positions, 0, 4000, c0, 1.0);
    sphere_points(m.positions, 4000, 2000, c1, 0.5);
    CHECK(run(&cfg, &m, NULL, &ps, &c) == SL_OK);
    CHECK(c.normal_source == SL_NORMALS_PCA_PROPAGATED);
    CHECK_EQ_U64(c.pca_components, 2);
    check_outward(&ps, c0, 0, 4000, 5.0, "sphere 1 (propagated)");
    check_outward(&ps, c1, 4000, 2000, 5.0, "sphere 2 (propagated)");
    sl_pointset_release(&ps);
    sl_mesh_release(&m);

    /* The half facing a stated viewpoint: every normal faces it. */
    sl_mesh_init(&m);
    m.positions = malloc(3 * 4000 * sizeof(float));
    sphere_points(m.positions, 0, 4000, c0, 1.0);
    /* The cap z > 0.1 (generated from z = 1 down), all of it visible from the viewpoint. */
    m.vertex_count = 1800;
    m.has_viewpoint = 1;
    m.viewpoint[0] = c0[0], m.viewpoint[1] = c0[1], m.viewpoint[2] = 100;
    CHECK(run(&cfg, &m, NULL, &ps, &c) == SL_OK);
    CHECK(c.normal_source == SL_NORMALS_PCA_VIEWPOINT);
    check_outward(&ps, c0, 0, 1800, 5.0, "cap (viewpoint)");
    sl_pointset_release(&ps);
    sl_mesh_release(&m);
}

/* Degenerate clouds give unit normals and no crash; a plane gets one consistent side. */
static void test_degenerate_clouds(void)
{
    sl_range_config cfg = sl_range_default_config();
    const int sizes[] = {1, 2, 5, 400};
    for (int c = 0; c < 4; c++) {
        sl_mesh m;
        sl_pointset ps;
        sl_range_counts counts;
        sl_mesh_init(&m);
        m.vertex_count = (uint64_t)sizes[c];
        m.positions = calloc(3 * (size_t)sizes[c], sizeof(float));
        for (int i = 0; i < sizes[c]; i++) {
            m.positions[3 * i] = (float)(i % 20);         /* collinear below 20 points */
            m.positions[3 * i + 1] = (float)(i / 20) * 0.5f; /* then a 20 x 20 plane z = 0 */
        }
        CHECK(run(&cfg, &m, NULL, &ps, &counts) == SL_OK);
        CHECK_EQ_U64(ps.count, (uint64_t)sizes[c]);
        int unit = 0, up = 0;
        for (uint64_t i = 0; i < ps.count; i++) {
            const float *n = ps.normals + 3 * i;
            unit += fabs(sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]) - 1) < 1e-5;
            up += n[2] > 0.999f;
        }
        CHECK_EQ_U64(unit, ps.count);
        if (sizes[c] == 400)
            CHECK(up == 0 || up == 400);
        sl_pointset_release(&ps);
        sl_mesh_release(&m);
    }
    /* A scanner grid naming a vertex that does not exist is bad input. */
    sl_mesh m;
    sl_pointset ps;
    sl_range_counts counts;
    build_grid(&m, 0);
    m.grid_index[5] = (int64_t)m.vertex_count;
    CHECK(run(&cfg, &m, NULL, &ps, &counts) == SL_E_BADINPUT);
    sl_mesh_release(&m);
}

static void make_temp_dir(char *dir, size_t size)
{
    snprintf(dir, size, "%s/scanlod-test-range-XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    if (!mkdtemp(dir))
        dir[0] = 0;
}

/* 2 x 2 texture: red, green (top row), blue, white (bottom row). */
static void test_texture(const char *dir)
{
    const float px[] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    char path[1100];
    sl_error err;
    sl_error_init(&err);
    snprintf(path, sizeof path, "%s/tex.png", dir);
    CHECK(sl_image_write(path, 2, 2, 3, px, &err) == SL_OK);
    sl_range_config cfg = sl_range_default_config();
    for (int per_face = 0; per_face < 3; per_face++) {
        sl_mesh m;
        sl_pointset ps;
        sl_range_counts c;
        const float v[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        const float uv[] = {0.25f, 0.75f, 0.5f, 0.5f, 0.75f, 0.25f};
        sl_mesh_init(&m);
        m.vertex_count = 3;
        m.positions = copy_floats(v, 9);
        m.triangle_count = 1;
        m.triangles = calloc(3, sizeof(uint32_t));
        m.triangles[1] = 1, m.triangles[2] = 2;
        if (per_face == 1)
            m.face_texcoords = copy_floats(uv, 6);
        else
            m.texcoords = copy_floats(uv, 6);
        snprintf(m.texture_file, sizeof m.texture_file, per_face == 2 ? "missing.png" : "tex.png");
        CHECK(run(&cfg, &m, dir, &ps, &c) == SL_OK);
        if (per_face == 2) {
            CHECK_EQ_U64(c.texture_warnings, 1);
            CHECK(ps.colors == NULL && strcmp(c.color_source, "none") == 0);
        } else {
            CHECK(strcmp(c.color_source, "texture") == 0 && ps.colors);
            /* (0.25, 0.75) is the centre of the top-left texel; (0.5, 0.5) the mean of all
             * four; (0.75, 0.25) the bottom-right one. */
            CHECK(ps.colors && memcmp(ps.colors, "\xff\x00\x00\xff", 4) == 0);
            CHECK(ps.colors && memcmp(ps.colors + 4, "\x80\x80\x80\xff", 4) == 0);
            CHECK(ps.colors && memcmp(ps.colors + 8, "\xff\xff\xff\xff", 4) == 0);
            /* Every point has one texture coordinate: carried, and through the file. */
            CHECK(ps.texcoords && memcmp(ps.texcoords, uv, sizeof uv) == 0);
            CHECK(strcmp(c.texcoord_source, per_face ? "corners" : "vertices") == 0);
            char file[1100];
            snprintf(file, sizeof file, "%s/uv.slpts", dir);
            sl_pointset back;
            CHECK(sl_pointset_write(file, &ps, &err) == SL_OK);
            CHECK(sl_pointset_read(file, &back, &err) == SL_OK);
            CHECK(back.texcoords && memcmp(back.texcoords, uv, sizeof uv) == 0);
            sl_pointset_release(&back);
            unlink(file);
        }
        sl_pointset_release(&ps);
        sl_mesh_release(&m);
    }
    /* A seam: two triangles whose corners give their shared points different texture
     * coordinates. The point set carries none (the export bakes), and says why. */
    sl_mesh m;
    sl_pointset ps;
    sl_range_counts c;
    const float v[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    const uint32_t tri[] = {0, 1, 2, 2, 1, 3};
    const float uv[] = {0, 0, 0.5f, 0, 0, 0.5f, 0.6f, 0.5f, 0.5f, 0.1f, 1, 1};
    sl_mesh_init(&m);
    m.vertex_count = 4;
    m.positions = copy_floats(v, 12);
    m.triangle_count = 2;
    m.triangles = malloc(sizeof tri);
    memcpy(m.triangles, tri, sizeof tri);
    m.face_texcoords = copy_floats(uv, 12);
    snprintf(m.texture_file, sizeof m.texture_file, "tex.png");
    CHECK(run(&cfg, &m, dir, &ps, &c) == SL_OK);
    CHECK(ps.texcoords == NULL && strcmp(c.texcoord_source, "none") == 0);
    CHECK_EQ_U64(c.texcoord_seams, 2);
    sl_pointset_release(&ps);
    sl_mesh_release(&m);
    unlink(path);
}

static void test_pointset_file(const char *dir)
{
    sl_range_config cfg = sl_range_default_config();
    sl_mesh m;
    sl_pointset ps, back;
    sl_range_counts c;
    sl_error err;
    sl_error_init(&err);
    build_defect_mesh(&m);
    CHECK(run(&cfg, &m, NULL, &ps, &c) == SL_OK);
    char path[1100];
    snprintf(path, sizeof path, "%s/%s", dir, SL_POINTSET_FILE);
    CHECK(sl_pointset_write(path, &ps, &err) == SL_OK);
    CHECK(sl_pointset_read(path, &back, &err) == SL_OK);
    CHECK(back.count == ps.count && back.normal_source == ps.normal_source);
    CHECK(memcmp(back.positions, ps.positions, 12 * ps.count) == 0);
    CHECK(memcmp(back.normals, ps.normals, 12 * ps.count) == 0);
    CHECK(back.colors && memcmp(back.colors, ps.colors, 4 * ps.count) == 0);
    CHECK(memcmp(back.bbox_min, ps.bbox_min, 12) == 0 && memcmp(back.bbox_max, ps.bbox_max, 12) == 0);
    CHECK(memcmp(&back.mean_spacing, &ps.mean_spacing, sizeof(double)) == 0);
    sl_pointset_release(&back);

    /* One flipped byte anywhere (header or body) is refused as corrupt. */
    FILE *f = fopen(path, "r+b");
    long offsets[] = {3, 40, 100};
    for (int i = 0; i < 3 && f; i++) {
        unsigned char b;
        fseek(f, offsets[i], SEEK_SET);
        CHECK(fread(&b, 1, 1, f) == 1);
        b ^= 0x10;
        fseek(f, offsets[i], SEEK_SET);
        fwrite(&b, 1, 1, f);
        fflush(f);
        sl_error_init(&err);
        CHECK_MSG(sl_pointset_read(path, &back, &err) == SL_E_CORRUPT, "flip at %ld: %s",
                  offsets[i], err.message);
        fseek(f, offsets[i], SEEK_SET);
        b ^= 0x10;
        fwrite(&b, 1, 1, f);
        fflush(f);
    }
    if (f)
        fclose(f);
    /* Sealed again (size and checksum right, as a producer with a bug would write it): a
     * point count the body cannot hold is refused before it sizes an allocation, and a
     * triangle index past the points after the read. */
    size_t size = 0;
    unsigned char *bytes = sealed_file_bytes(path, 0, &size);
    CHECK(bytes && size > 100 && ps.triangle_count > 0);
    const char *why[2] = {"disagrees with the body size", "triangle index out of range"};
    for (int m_ = 0; bytes && size > 100 && m_ < 2; m_++) {
        unsigned char *b = malloc(size);
        memcpy(b, bytes, size);
        if (m_ == 0)
            sl_put_u64(b + SL_ARTIFACT_HEADER_SIZE, (uint64_t)1 << 40);
        else /* the last triangle's last index: the point count */
            sl_put_u32(b + size - 4, (uint32_t)ps.count);
        CHECK(sealed_file_write(path, b, size, 1) == 0);
        sl_error_init(&err);
        CHECK_MSG(sl_pointset_read(path, &back, &err) == SL_E_CORRUPT && strstr(err.message, why[m_]),
                  "sealed mutant %d: %s", m_, err.message);
        free(b);
    }
    free(bytes);
    sl_error_init(&err);
    CHECK(truncate(path, 60) == 0);
    CHECK(sl_pointset_read(path, &back, &err) == SL_E_CORRUPT);
    unlink(path);
    sl_pointset_release(&ps);
    sl_mesh_release(&m);
}

/* --- the weld of a large soup: every triangle with its own three vertices ------------------ */

static int cmp_position(const void *x, const void *y)
{
    const float *a = x, *b = y;
    for (int k = 0; k < 3; k++) {
        float u = a[k] == 0.0f ? 0.0f : a[k], v = b[k] == 0.0f ? 0.0f : b[k];
        if (u != v)
            return u < v ? -1 : 1;
    }
    return 0;
}

/* Two sheets of a G x G grid of a rough height field, one above the other (positions
 * that differ in z alone), as a soup: their triangles in a scrambled order,
 * each with three vertices of its own (so a position is held by up to six vertices far
 * apart in the file), a zero coordinate written as -0.0 on some of them, and a few
 * vertices NaN (their faces dropped). About 4 G^2 triangles, 12 G^2 vertices: enough for
 * the sort's parallel slices and for groups across the weld's 64 slices. */
static void build_soup(sl_mesh *m, int g)
{
    uint64_t cells = (uint64_t)(g - 1) * (g - 1), nt = 4 * cells, nv = 3 * nt;
    sl_mesh_init(m);
    m->vertex_count = nv;
    m->triangle_count = nt;
    m->positions = malloc(12 * nv);
    m->triangles = malloc(12 * nt);
    uint64_t *order = malloc(nt * sizeof *order);
    for (uint64_t t = 0; t < nt; t++)
        order[t] = t;
    uint64_t state = 12345;
    for (uint64_t t = nt - 1; t > 0; t--) { /* Fisher-Yates with a fixed LCG */
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        uint64_t j = (state >> 33) % (t + 1), swap = order[t];
        order[t] = order[j];
        order[j] = swap;
    }
    for (uint64_t slot = 0; slot < nt; slot++) {
        uint64_t t = order[slot], cell = t / 2 % cells, sheet = t / (2 * cells);
        int x = (int)(cell % (uint64_t)(g - 1)), y = (int)(cell / (uint64_t)(g - 1));
        int corners[2][3][2] = {{{0, 0}, {1, 0}, {1, 1}}, {{0, 0}, {1, 1}, {0, 1}}};
        for (int c = 0; c < 3; c++) {
            int cx = x + corners[t % 2][c][0], cy = y + corners[t % 2][c][1];
            uint64_t v = 3 * slot + (uint64_t)c;
            float *p = m->positions + 3 * v;
            p[0] = (float)cx / (float)g;
            p[1] = (float)cy / (float)g;
            uint32_t h = (uint32_t)cx * 73856093u ^ (uint32_t)cy * 19349663u; /* rough */
            p[2] = 0.05f * sinf(0.37f * (float)cx) * cosf(0.23f * (float)cy) +
                   0.01f * (float)(h % 1000) / 1000.0f + 0.5f * (float)sheet;
            if (cx == 0 && (v % 3) == 1)
                p[0] = -0.0f; /* welds with +0.0 */
            if (v % 9973 == 17)
                p[1] = NAN;
            m->triangles[3 * slot + c] = (uint32_t)v;
        }
    }
    free(order);
}

static void test_weld_soup(void)
{
    sl_range_config cfg = sl_range_default_config();
    sl_mesh m;
    build_soup(&m, 300);
    sl_pointset ps[2];
    sl_range_counts c[2];
    int saved = omp_get_max_threads();
    for (int r = 0; r < 2; r++) {
        omp_set_num_threads(r + 1);
        CHECK(run(&cfg, &m, ".", &ps[r], &c[r]) == SL_OK);
    }
    omp_set_num_threads(saved);
    /* The same bits on 1 and 2 threads. */
    CHECK_EQ_U64(ps[0].count, ps[1].count);
    CHECK_EQ_U64(ps[0].triangle_count, ps[1].triangle_count);
    CHECK_EQ_U64(c[0].welded, c[1].welded);
    if (ps[0].count == ps[1].count && ps[0].triangle_count == ps[1].triangle_count) {
        CHECK(memcmp(ps[0].positions, ps[1].positions, 12 * ps[0].count) == 0);
        CHECK(memcmp(ps[0].normals, ps[1].normals, 12 * ps[0].count) == 0);
        CHECK(memcmp(ps[0].triangles, ps[1].triangles, 12 * ps[0].triangle_count) == 0);
    }
    /* Against the positions themselves: finite vertices = distinct finite positions +
     * welded; no two points at one position; every kept triangle keeps its corners. */
    uint64_t finite = 0;
    float *sorted = malloc(12 * m.vertex_count);
    for (uint64_t v = 0; v < m.vertex_count; v++) {
        const float *p = m.positions + 3 * v;
        if (isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))
            memcpy(sorted + 3 * finite++, p, 12);
    }
    qsort(sorted, finite, 12, cmp_position);
    uint64_t distinct = finite > 0;
    for (uint64_t i = 1; i < finite; i++)
        distinct += cmp_position(sorted + 3 * (i - 1), sorted + 3 * i) != 0;
    CHECK_EQ_U64(c[1].nonfinite_vertices, m.vertex_count - finite);
    CHECK_EQ_U64(c[1].welded, finite - distinct);
    CHECK(c[1].welded > 4 * ps[1].count); /* about five twins a position: it welded */
    float *points = malloc(12 * ps[1].count);
    memcpy(points, ps[1].positions, 12 * ps[1].count);
    qsort(points, ps[1].count, 12, cmp_position);
    uint64_t twins = 0;
    for (uint64_t i = 1; i < ps[1].count; i++)
        twins += cmp_position(points + 3 * (i - 1), points + 3 * i) == 0;
    CHECK_EQ_U64(twins, 0);
    uint64_t moved = 0, kept = 0;
    for (uint64_t t = 0; t < m.triangle_count; t++) {
        const uint32_t *in = m.triangles + 3 * t;
        int usable = 1;
        for (int k = 0; k < 3; k++)
            usable &= isfinite(m.positions[3 * (uint64_t)in[k] + 1]) != 0;
        if (!usable)
            continue;
        const uint32_t *out = ps[1].triangles + 3 * kept++;
        for (int k = 0; k < 3 && kept <= ps[1].triangle_count; k++)
            moved += cmp_position(ps[1].positions + 3 * (uint64_t)out[k],
                                  m.positions + 3 * (uint64_t)in[k]) != 0;
    }
    CHECK_EQ_U64(kept, ps[1].triangle_count);
    CHECK_EQ_U64(moved, 0);
    free(points);
    free(sorted);
    for (int r = 0; r < 2; r++)
        sl_pointset_release(&ps[r]);
    sl_mesh_release(&m);
}

int main(void)
{
    char dir[512];
    make_temp_dir(dir, sizeof dir);
    CHECK(dir[0] != 0);
    test_defects();
    test_file_normals();
    test_grid();
    test_pca_spheres();
    test_degenerate_clouds();
    test_texture(dir);
    test_pointset_file(dir);
    test_weld_soup();
    rmdir(dir);
    return check_report();
}
