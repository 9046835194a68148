/* Texture atlases for the levels of a textured input (docs/glb.md "Textures").
 *
 * A level made of the scan's vertices carries the input's texture coordinates (range and
 * refine stages): with [export] texture = keep it embeds the input's image as read
 * (sl_export_texture_keeps). Another level takes coordinates projected from the input's
 * (export_uv.c) with the input's image; with texture = bake, or when projection is not
 * possible (the image neither JPEG nor PNG, coordinates outside [0, 1]), it gets its own
 * atlas, baked from the input texture, as follows.
 *
 * Charts: one per triangle, two triangles per square cell of c x c texels, cells in rows
 * in triangle order (the level's triangles come in vertex-cache order, so neighbours in
 * the atlas are mostly neighbours on the surface, which keeps mipmap averaging between
 * cells plausible). In a cell at (x0, y0), triangle A has its corners at (x0+1, y0+1),
 * (x0+c-3, y0+1), (x0+1, y0+c-3), triangle B the mirror image from the opposite corner:
 * a one-texel gutter at the cell's edges and two texels between the hypotenuses, so a
 * bilinear lookup anywhere in a triangle reads only texels of that triangle. Every texel
 * of the cell belongs to the triangle on its side of the diagonal and is baked at the
 * point of that triangle nearest to the texel centre (the gutter repeats the edge colour,
 * for filtering). Texel efficiency: (c-4)^2 of each c^2 cell hold the surface.
 *
 * Baking a texel: its point on the level triangle -> the closest point of the input
 * surface (geometry/triangle_bvh.h) -> that point's texture coordinates, interpolated
 * from its input triangle's corners -> the input texture, bilinear (the OpenGL convention
 * of the range stage: v = 0 is the bottom row, coordinates wrap). Texels are independent,
 * so the bake is parallel over cells and the same on any thread count.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/atomicfile.h"
#include "geometry/mesh_distance.h"
#include "formats/scan_read.h"
#include "formats/scan_texture.h"
#include "stages/export/export_internal.h"

#define TEXTURE_MAX_PIXELS (1ull << 28) /* 16k x 16k, as the range stage */
#define MIN_CELL 6                      /* texels: below this a chart holds (c-4)^2 < 4 */

#define ORIGINAL_MAX_BYTES (1ull << 30) /* a kept image larger than this is baked instead */

/* What glTF core takes (JPEG, PNG), by the bytes' signature; NULL for anything else. */
static const char *image_mime(const unsigned char *b, size_t n)
{
    if (n >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff)
        return "image/jpeg";
    if (n >= 8 && !memcmp(b, "\x89PNG\r\n\x1a\n", 8))
        return "image/png";
    return NULL;
}

/* The texture's encoded bytes as the input has them (levels that keep the input's
 * texture coordinates embed them unchanged); none when unreadable or not JPEG/PNG. */
static void read_original(const sl_mesh *input, const char *dir, sl_export_texture *t)
{
    if (input->texture_data) {
        t->original = input->texture_data;
        t->original_size = (size_t)input->texture_size;
    } else {
        char path[4096];
        char *data = NULL;
        size_t size = 0;
        sl_error err;
        sl_error_init(&err);
        if (sl_scan_sibling_path(dir, input->texture_file, path, sizeof path) ||
            sl_read_file(path, ORIGINAL_MAX_BYTES, &data, &size, &err))
            return;
        t->original = t->original_owned = data;
        t->original_size = size;
    }
    t->original_mime = image_mime(t->original, t->original_size);
    if (!t->original_mime) {
        free(t->original_owned);
        t->original = t->original_owned = NULL;
        t->original_size = 0;
    }
}

int sl_export_texture_keeps(const sl_export_config *c, const sl_export_texture *t,
                            const float *texcoords, uint64_t vertex_count)
{
    if (c->texture != SL_EXPORT_TEXTURE_KEEP || !t || !t->original || !texcoords)
        return 0;
    for (uint64_t i = 0; i < 2 * vertex_count; i++)
        if (!(texcoords[i] >= 0.0f && texcoords[i] <= 1.0f))
            return 0;
    return 1;
}

/* Whether every texture coordinate of the input lies in [0, 1]. */
static int input_uvs_in_unit(const sl_mesh *in)
{
    const float *uv = in->face_texcoords ? in->face_texcoords : in->texcoords;
    uint64_t n = in->face_texcoords ? 6 * in->triangle_count : 2 * in->vertex_count;
    for (uint64_t i = 0; i < n; i++)
        if (!(uv[i] >= 0.0f && uv[i] <= 1.0f))
            return 0;
    return 1;
}

int sl_export_texture_open(const sl_mesh *input, const char *dir, sl_export_texture *t,
                           char *why, size_t why_size)
{
    memset(t, 0, sizeof *t);
    sl_error err;
    sl_error_init(&err);
    if (!sl_scan_has_texture(input)) {
        snprintf(why, why_size, "the input names no texture");
        return 0;
    }
    if (!input->texcoords && !input->face_texcoords) {
        snprintf(why, why_size, "the input has no texture coordinates");
        return 0;
    }
    if (input->triangle_count == 0 || sl_mesh_check_surface(input, NULL, &err) != 0) {
        snprintf(why, why_size, "the input has no surface to bake from");
        return 0;
    }
    if (!sl_scan_texture_read(input, dir, TEXTURE_MAX_PIXELS, &t->image, why, why_size))
        return 0;
    if (sl_triangle_bvh_build(&t->bvh, input, &err)) {
        sl_image_release(&t->image);
        snprintf(why, why_size, "no memory for the input's triangle tree");
        return 0;
    }
    t->input = input;
    read_original(input, dir, t);
    if (t->original && input_uvs_in_unit(input) && sl_export_texture_charts(input, &t->chart)) {
        free(t->original_owned); /* no memory for the charts: every level is baked */
        t->original = t->original_owned = NULL;
    }
    return 1;
}

void sl_export_texture_close(sl_export_texture *t)
{
    if (t->input) {
        sl_image_release(&t->image);
        sl_triangle_bvh_release(&t->bvh);
        free(t->original_owned);
        free(t->chart);
    }
    memset(t, 0, sizeof *t);
}

void sl_export_baked_release(sl_export_baked *b)
{
    free(b->positions), free(b->normals), free(b->texcoords), free(b->triangles);
    free(b->image), free(b->fallback_image);
    memset(b, 0, sizeof *b);
}

static int wrap(int64_t i, int n)
{
    int64_t m = i % n;
    return (int)(m < 0 ? m + n : m);
}

/* Bilinear RGB lookup at (u, v), OpenGL convention, wrapping. */
static void sample(const sl_image *img, double u, double v, float rgb[3])
{
    if (!isfinite(u) || !isfinite(v))
        u = v = 0;
    double x = u * img->width - 0.5, y = (1.0 - v) * img->height - 0.5;
    double x0 = floor(x), y0 = floor(y), fx = x - x0, fy = y - y0;
    int xs[2] = {wrap((int64_t)x0, img->width), wrap((int64_t)x0 + 1, img->width)};
    int ys[2] = {wrap((int64_t)y0, img->height), wrap((int64_t)y0 + 1, img->height)};
    for (int c = 0; c < 3; c++) {
        double acc = 0;
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 2; i++) {
                const float *px = img->pixels + ((uint64_t)ys[j] * img->width + xs[i]) * img->channels;
                double w = (i ? fx : 1 - fx) * (j ? fy : 1 - fy);
                acc += w * px[img->channels >= 3 ? c : 0];
            }
        rgb[c] = (float)acc;
    }
}

/* The chart corners of triangle t in texel space (x right, y down). */
static void chart(uint64_t t, int n, int c, double q[3][3])
{
    uint64_t cell = t / 2;
    double x0 = (double)(cell % (uint64_t)n) * c, y0 = (double)(cell / (uint64_t)n) * c;
    double near = 1, far = c - 3;
    if (t % 2 == 0) {
        double a[3][2] = {{near, near}, {far, near}, {near, far}};
        for (int k = 0; k < 3; k++)
            q[k][0] = x0 + a[k][0], q[k][1] = y0 + a[k][1], q[k][2] = 0;
    } else {
        double a[3][2] = {{c - near, c - near}, {c - far, c - near}, {c - near, c - far}};
        for (int k = 0; k < 3; k++)
            q[k][0] = x0 + a[k][0], q[k][1] = y0 + a[k][1], q[k][2] = 0;
    }
}

/* Bakes the texels of triangle t's half of its cell into `rgb` (size x size x 3). */
static void bake_triangle(const sl_export_texture *src, const sl_lod_mesh *level, uint64_t t,
                          int n, int c, int size, float *rgb)
{
    double q[3][3], v[3][3];
    chart(t, n, c, q);
    for (int k = 0; k < 3; k++)
        for (int d = 0; d < 3; d++)
            v[k][d] = level->positions[3 * (uint64_t)level->indices[3 * t + k] + d];
    uint64_t cell = t / 2;
    int x0 = (int)(cell % (uint64_t)n) * c, y0 = (int)(cell / (uint64_t)n) * c;
    uint32_t hint = UINT32_MAX;
    for (int j = 0; j < c; j++)
        for (int i = 0; i < c; i++) {
            int side = (i + j + 1 >= c); /* texel centre sum vs the cell's diagonal */
            if (side != (int)(t % 2))
                continue;
            double p[3] = {x0 + i + 0.5, y0 + j + 0.5, 0}, on[3], w[3], x[3] = {0, 0, 0};
            sl_closest_point_triangle(p, q[0], q[1], q[2], on);
            sl_export_plane_weights(on, q[0], q[1], q[2], w);
            for (int k = 0; k < 3; k++)
                for (int d = 0; d < 3; d++)
                    x[d] += w[k] * v[k][d];
            sl_closest hit;
            sl_triangle_bvh_closest(&src->bvh, x, hint, &hit);
            hint = hit.triangle;
            const float *corner = src->bvh.corners + 9 * (uint64_t)hit.triangle;
            double a[3] = {corner[0], corner[1], corner[2]}, b[3] = {corner[3], corner[4], corner[5]};
            double cc[3] = {corner[6], corner[7], corner[8]}, wi[3], uv[2] = {0, 0};
            sl_export_plane_weights(hit.point, a, b, cc, wi);
            uint32_t tri = src->bvh.source[hit.triangle];
            for (int k = 0; k < 3; k++) {
                double cuv[2];
                sl_export_input_uv(src->input, tri, k, cuv);
                uv[0] += wi[k] * cuv[0], uv[1] += wi[k] * cuv[1];
            }
            sample(&src->image, uv[0], uv[1], rgb + 3 * ((uint64_t)(y0 + j) * size + x0 + i));
        }
}

/* The atlas edge: the configured one, or less when the level's cells would be larger
 * than 64 texels (a small level needs no large image). 0 when cells would be too small. */
static int atlas_size(uint64_t triangles, int configured, int *n, int *c)
{
    uint64_t cells = (triangles + 1) / 2;
    *n = (int)ceil(sqrt((double)cells));
    int size = configured;
    while (size > 64 && size / 2 / *n >= 64)
        size /= 2;
    *c = size / *n;
    return *c >= MIN_CELL ? size : 0;
}

/* Encodes `rgb` (w x h x 3) as [export] texture_format says into out->image and
 * out->mime_type, and for WebP with its fallback the JPEG into out->fallback_image. */
static int encode(const sl_export_config *c, int w, int h, const float *rgb,
                  sl_export_baked *out, sl_error *err)
{
    static const char *const ext[] = {"jpg", "png", "webp"};
    static const char *const mime[] = {"image/jpeg", "image/png", "image/webp"};
    int f = c->texture_format;
    int rc = sl_image_encode(ext[f], w, h, 3, rgb, c->texture_quality, &out->image,
                             &out->image_size, err);
    if (rc == 0 && f == SL_EXPORT_IMAGE_WEBP && c->texture_webp_fallback)
        rc = sl_image_encode("jpg", w, h, 3, rgb, c->texture_quality, &out->fallback_image,
                             &out->fallback_image_size, err);
    out->mime_type = mime[f];
    return rc;
}

int sl_export_bake(const sl_export_config *cfg, const sl_export_texture *src,
                   const sl_lod_mesh *level, int max_size, sl_export_baked *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    int n, c, size = atlas_size(level->triangle_count, max_size, &n, &c);
    if (!size)
        return 1; /* too many triangles for this atlas: the level keeps vertex colours */
    uint64_t t_count = level->triangle_count, v_count = 3 * t_count;
    float *rgb = calloc((size_t)size * size, 3 * sizeof *rgb);
    out->positions = malloc(v_count * 3 * sizeof(float));
    out->normals = malloc(v_count * 3 * sizeof(float));
    out->texcoords = malloc(v_count * 2 * sizeof(float));
    out->triangles = malloc(v_count * sizeof(uint32_t));
    if (!rgb || !out->positions || !out->normals || !out->texcoords || !out->triangles) {
        free(rgb);
        sl_export_baked_release(out);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory for a %d px atlas", size);
    }
#pragma omp parallel for schedule(dynamic, 64)
    for (int64_t t = 0; t < (int64_t)t_count; t++)
        bake_triangle(src, level, (uint64_t)t, n, c, size, rgb);
    for (uint64_t t = 0; t < t_count; t++) {
        double q[3][3];
        chart(t, n, c, q);
        for (int k = 0; k < 3; k++) {
            uint64_t o = 3 * t + (uint64_t)k, v = level->indices[o];
            memcpy(out->positions + 3 * o, level->positions + 3 * v, 3 * sizeof(float));
            memcpy(out->normals + 3 * o, level->normals + 3 * v, 3 * sizeof(float));
            out->texcoords[2 * o] = (float)(q[k][0] / size);
            out->texcoords[2 * o + 1] = (float)(1.0 - q[k][1] / size); /* OpenGL: v up */
            out->triangles[o] = (uint32_t)o;
        }
    }
    out->vertex_count = v_count;
    out->triangle_count = t_count;
    int rc = encode(cfg, size, size, rgb, out, err);
    free(rgb);
    if (rc) {
        sl_export_baked_release(out);
        return rc;
    }
    out->size = size;
    out->cell = c;
    out->texel_efficiency = (double)t_count / 2 * (c - 4) * (c - 4) / ((double)size * size);
    return 0;
}

int sl_export_texture_scaled(const sl_export_config *cfg, const sl_export_texture *src,
                             int max_edge, sl_export_baked *out, sl_error *err)
{
    const sl_image *im = &src->image;
    int big = im->width > im->height ? im->width : im->height;
    if (max_edge <= 0 || big <= max_edge)
        return 0; /* within the level's size: the input's own bytes */
    double scale = (double)big / max_edge; /* source texels per output texel, > 1 */
    int w = (int)fmax(1, floor(im->width / scale + 0.5));
    int h = (int)fmax(1, floor(im->height / scale + 0.5));
    float *rgb = malloc((size_t)w * h * 3 * sizeof *rgb);
    if (!rgb)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory for a %d x %d texture",
                            w, h);
    double sx = (double)im->width / w, sy = (double)im->height / h;
    /* a box filter: each output texel the mean of the source texels whose centres fall
     * in its footprint (in the stored, sRGB, values) */
#pragma omp parallel for schedule(dynamic, 16)
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int x0 = (int)ceil(x * sx - 0.5), x1 = (int)ceil((x + 1) * sx - 0.5);
            int y0 = (int)ceil(y * sy - 0.5), y1 = (int)ceil((y + 1) * sy - 0.5);
            x1 = x1 > x0 ? x1 : x0 + 1, y1 = y1 > y0 ? y1 : y0 + 1;
            double acc[3] = {0, 0, 0};
            int n = 0;
            for (int j = y0; j < y1 && j < im->height; j++)
                for (int i = x0; i < x1 && i < im->width; i++, n++) {
                    const float *px = im->pixels + ((uint64_t)j * im->width + i) * im->channels;
                    for (int c = 0; c < 3; c++)
                        acc[c] += px[im->channels >= 3 ? c : 0];
                }
            for (int c = 0; c < 3; c++)
                rgb[((uint64_t)y * w + x) * 3 + c] = (float)(n ? acc[c] / n : 0);
        }
    int rc = encode(cfg, w, h, rgb, out, err);
    free(rgb);
    if (rc)
        return rc;
    out->size = w > h ? w : h;
    return 0;
}

int sl_export_texture_size(const sl_export_config *c, const char *level)
{
    const char *p = c->texture_sizes;
    size_t len = strlen(level);
    while (p && *p) {
        size_t n = strcspn(p, ",");
        if (n > len && p[len] == ':' && !strncmp(p, level, len))
            return atoi(p + len + 1);
        p += n + (p[n] == ',');
    }
    return c->texture_size;
}
