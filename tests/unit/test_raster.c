/* Thumbnail rasteriser: real outcomes on meshes whose picture is known. A unit sphere
 * fitted with a 6% margin covers pi/4 * 0.88^2 = 61% of the image; its centre is lit,
 * the corners are background, the side towards the key light (upper left) is brighter
 * than the opposite side; vertex colours show; a face seen from its back is still lit
 * (two-sided); the same input gives the same pixels, on 1 thread or 2; PNGs round-trip through
 * OpenImageIO at the requested size. With SCANLOD_THUMB_OUT set, also writes thumbnails
 * of the bundled scans there (to look at).
 */
#include <omp.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "../check.h"
#include "geometry/raster.h"
#include "glb_meshes.h"
#include "shim/oiio_shim.h"

#define SIDE 128

static int is_background(const float *px)
{
    return fabsf(px[0] - 0.94f) < 0.003f && fabsf(px[1] - 0.94f) < 0.003f &&
           fabsf(px[2] - 0.94f) < 0.003f;
}

static float luminance(const float *px)
{
    return 0.2126f * px[0] + 0.7152f * px[1] + 0.0722f * px[2];
}

static float *render(const sl_mesh *m, int w, int h)
{
    float *rgba = malloc((size_t)w * (size_t)h * 4 * sizeof *rgba);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_render_thumbnail(m, w, h, rgba, &err);
    CHECK_MSG(rc == 0, "%s", err.message);
    return rc ? (free(rgba), NULL) : rgba;
}

static void test_sphere(void)
{
    sl_mesh m;
    float c[3] = {3, -2, 1}; /* off the origin: the camera must follow the object */
    meshes_sphere(&m, 48, 96, c, 0);
    float *img = render(&m, SIDE, SIDE);
    if (img) {
        int covered = 0, alpha_one = 1;
        double lit_upper_left = 0, lit_lower_right = 0;
        int n_ul = 0, n_lr = 0;
        for (int y = 0; y < SIDE; y++)
            for (int x = 0; x < SIDE; x++) {
                const float *px = img + 4 * (y * SIDE + x);
                alpha_one &= px[3] == 1.0f;
                if (is_background(px))
                    continue;
                covered++;
                if (x < SIDE / 2 && y < SIDE / 2)
                    lit_upper_left += luminance(px), n_ul++;
                if (x >= SIDE / 2 && y >= SIDE / 2)
                    lit_lower_right += luminance(px), n_lr++;
            }
        double fraction = (double)covered / (SIDE * SIDE);
        CHECK_MSG(fraction > 0.57 && fraction < 0.65, "coverage %.3f", fraction);
        CHECK(alpha_one);
        const float *centre = img + 4 * ((SIDE / 2) * SIDE + SIDE / 2);
        CHECK(!is_background(centre));
        CHECK_MSG(luminance(centre) > 0.5f, "centre luminance %.3f", luminance(centre));
        int corners[4][2] = {{0, 0}, {SIDE - 1, 0}, {0, SIDE - 1}, {SIDE - 1, SIDE - 1}};
        for (int i = 0; i < 4; i++)
            CHECK(is_background(img + 4 * (corners[i][1] * SIDE + corners[i][0])));
        /* Symmetric placement: the margins left/right and top/bottom agree. */
        int left = SIDE, right = 0, top = SIDE, bottom = 0;
        for (int y = 0; y < SIDE; y++)
            for (int x = 0; x < SIDE; x++)
                if (!is_background(img + 4 * (y * SIDE + x))) {
                    left = x < left ? x : left, right = x > right ? x : right;
                    top = y < top ? y : top, bottom = y > bottom ? y : bottom;
                }
        CHECK_MSG(abs(left - (SIDE - 1 - right)) <= 1 && abs(top - (SIDE - 1 - bottom)) <= 1,
                  "bbox %d..%d x %d..%d", left, right, top, bottom);
        double ul = lit_upper_left / n_ul, lr = lit_lower_right / n_lr;
        CHECK_MSG(ul > lr + 0.15, "upper-left %.3f, lower-right %.3f", ul, lr);
        /* Same input, same pixels. */
        float *again = render(&m, SIDE, SIDE);
        CHECK(again && memcmp(img, again, sizeof(float) * 4 * SIDE * SIDE) == 0);
        free(again);
    }
    free(img);
    sl_mesh_release(&m);
}

/* A wide, short image: the sphere fills the height and sits in the middle. */
static void test_aspect(void)
{
    sl_mesh m;
    float c[3] = {0, 0, 0};
    meshes_sphere(&m, 24, 48, c, 0);
    int w = 200, h = 50, covered = 0;
    float *img = render(&m, w, h);
    for (int y = 0; img && y < h; y++)
        for (int x = 0; x < w; x++)
            covered += !is_background(img + 4 * (y * w + x)) && (x < 60 || x >= 140);
    CHECK_MSG(img && covered == 0, "%d pixels far from the centre", covered);
    CHECK(img && !is_background(img + 4 * (25 * w + 100)));
    free(img);
    sl_mesh_release(&m);
}

static void test_colors_and_back_faces(void)
{
    sl_mesh m;
    float c[3] = {0, 0, 0};
    meshes_sphere(&m, 24, 48, c, 1);
    for (uint64_t i = 0; i < m.vertex_count; i++) {
        uint8_t red[4] = {230, 20, 20, 255};
        memcpy(m.colors + 4 * i, red, 4);
    }
    float *img = render(&m, 64, 64);
    if (img) {
        const float *px = img + 4 * (32 * 64 + 32);
        CHECK_MSG(px[0] > px[1] + 0.3f && px[0] > px[2] + 0.3f, "rgb %.2f %.2f %.2f", px[0],
                  px[1], px[2]);
    }
    free(img);
    sl_mesh_release(&m);

    /* A square whose normal points away from the camera, without vertex normals: lit. */
    sl_mesh q;
    meshes_cube(&q, 0, 1, 0, 0);
    q.triangle_count = 2; /* the x = 0 face: outward normal -x, seen from +x +z */
    img = render(&q, 64, 64);
    if (img) {
        const float *px = img + 4 * (32 * 64 + 32);
        CHECK(!is_background(px));
        CHECK_MSG(luminance(px) > 0.3f, "back face luminance %.3f", luminance(px));
    }
    free(img);
    sl_mesh_release(&q);
}

static void test_rejections(void)
{
    sl_mesh m;
    meshes_cube(&m, 0, 1, 1, 0);
    sl_mesh g = sl_mesh_view(m.vertex_count, m.positions, m.normals, m.colors,
                             m.triangle_count, m.triangles);
    float px[4 * 16];
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_render_thumbnail(&g, 0, 4, px, &err) == SL_E_INTERNAL);
    sl_error_init(&err);
    CHECK(sl_render_thumbnail(&g, 4, SL_THUMBNAIL_MAX_SIDE + 1, px, &err) == SL_E_INTERNAL);
    g.triangle_count = 0;
    sl_error_init(&err);
    CHECK(sl_render_thumbnail(&g, 4, 4, px, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.message, "nothing to write") != NULL);
    sl_mesh_release(&m);
}

/* sl_write_thumbnail: a PNG of the asked size that reads back with the same pixels
 * (8-bit quantised). */
static void test_png(void)
{
    char dir[512], path[600];
    snprintf(dir, sizeof dir, "%s/scanlod-raster.XXXXXX",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    CHECK(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/cube.png", dir);
    sl_mesh m;
    meshes_cube(&m, -1, 1, 1, 1);
    sl_mesh g = sl_mesh_view(m.vertex_count, m.positions, m.normals, m.colors,
                             m.triangle_count, m.triangles);
    sl_error err;
    sl_error_init(&err);
    CHECK_MSG(sl_write_thumbnail(path, &g, 96, &err) == 0, "%s", err.message);
    sl_image img = {0};
    CHECK(sl_image_read(path, 1 << 20, &img, &err) == 0);
    CHECK(img.width == 96 && img.height == 96 && img.channels == 4);
    float *ref = render(&m, 96, 96);
    if (ref && img.pixels && img.channels == 4) {
        float worst = 0;
        for (int i = 0; i < 96 * 96 * 4; i++)
            worst = fmaxf(worst, fabsf(img.pixels[i] - ref[i]));
        CHECK_MSG(worst <= 0.5f / 255 + 1e-6f, "max difference %g", worst);
    }
    free(ref);
    sl_image_release(&img);
    sl_error_init(&err);
    snprintf(path, sizeof path, "%s/none.png", dir);
    g.triangle_count = 0;
    CHECK(sl_write_thumbnail(path, &g, 96, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.file, "none.png") != NULL);
    CHECK(access(path, F_OK) != 0);
    sl_mesh_release(&m);
    snprintf(path, sizeof path, "%s/cube.png", dir);
    unlink(path);
    rmdir(dir);
}

/* Thumbnails of the bundled scans, with area-weighted normals and with face normals. */
static void write_scans(const char *dir)
{
    const char *scans[] = {"cow", "fandisk", "bun_zipper_res3", "bun_zipper_res4", "rocker_arm"};
    for (size_t i = 0; i < sizeof scans / sizeof scans[0]; i++) {
        sl_mesh m;
        if (meshes_read_scan(scans[i], &m) != 0) {
            CHECK_MSG(0, "cannot read %s", scans[i]);
            continue;
        }
        char path[1200];
        sl_error err;
        sl_error_init(&err);
        sl_mesh g = sl_mesh_view(m.vertex_count, m.positions, NULL, m.colors, m.triangle_count,
                                 m.triangles); /* face normals */
        snprintf(path, sizeof path, "%s/%s_flat.png", dir, scans[i]);
        CHECK_MSG(sl_write_thumbnail(path, &g, 256, &err) == 0, "%s", err.message);
        meshes_vertex_normals(&m);
        snprintf(path, sizeof path, "%s/%s.png", dir, scans[i]);
        CHECK_MSG(sl_write_thumbnail(path, &m, 256, &err) == 0, "%s", err.message);
        sl_mesh_release(&m);
    }
}

/* The same pixels whatever the thread count: pass 1 runs in bands, pass 2 in rows. */
static void test_threads(void)
{
    sl_mesh m;
    if (meshes_read_scan("cow", &m) != 0) {
        CHECK_MSG(0, "cannot read cow");
        return;
    }
    meshes_vertex_normals(&m);
    omp_set_num_threads(1);
    float *one = render(&m, 256, 256);
    omp_set_num_threads(2);
    float *two = render(&m, 256, 256);
    CHECK(one && two && memcmp(one, two, 256 * 256 * 4 * sizeof *one) == 0);
    int drawn = 0;
    for (int i = 0; one && i < 256 * 256; i++)
        drawn += !is_background(one + 4 * i);
    CHECK_MSG(drawn > 256 * 256 / 10, "the cow covers %d of 65536 pixels", drawn);
    free(one);
    free(two);
    sl_mesh_release(&m);
}

int main(void)
{
    sl_oiio_init();
    test_sphere();
    test_aspect();
    test_colors_and_back_faces();
    test_rejections();
    test_png();
    test_threads();
    const char *out = getenv("SCANLOD_THUMB_OUT");
    if (out && out[0])
        write_scans(out);
    return check_report();
}
