/* Point colours (docs/range-stage.md: an "oriented, coloured point set"; the samples and
 * merge stages carry them down to the LOD meshes, paper 1 section 2.2 "the color value is
 * copied in the same manner").
 *
 * Source, in order: the file's vertex colours; else the texture image the reader found
 * (PLY `comment TextureFile NAME`, OBJ's `map_Kd`, a glTF baseColor texture: a file
 * relative to the input's directory, or an image embedded in a GLB), sampled bilinearly at the
 * per-face texture coordinates (each point: mean of its corners' samples, so a UV seam
 * blends both sides) or at the per-vertex ones. Welded twins average their samples.
 * Texture lookup follows the OpenGL convention: v = 0 is the bottom row of the image,
 * pixel centres at half-integers, coordinates outside [0, 1] wrap (repeat).
 * A missing or unreadable texture is a warning in the report, never a failure: the item
 * still has geometry worth converting.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/scan_texture.h"
#include "shim/oiio_shim.h"
#include "stages/range/range_internal.h"

#define TEXTURE_MAX_PIXELS (1ull << 28) /* 16k x 16k */

typedef struct color_sum {
    double *rgba; /* 4 per point */
    uint32_t *samples;
} color_sum;

/* The first warning is kept in the report (cut to fit), every one counted. */
static void warn(sl_range_counts *counts, const char *msg)
{
    if (counts->texture_warnings++ == 0) {
        size_t n = strnlen(msg, sizeof counts->texture_warning - 1);
        memcpy(counts->texture_warning, msg, n);
        counts->texture_warning[n] = 0;
    }
}

static int wrap(int64_t i, int n)
{
    int64_t m = i % n;
    return (int)(m < 0 ? m + n : m);
}

static void texel(const sl_image *img, int x, int y, float out[4])
{
    const float *px = img->pixels + ((uint64_t)y * img->width + x) * img->channels;
    switch (img->channels) {
    case 1: out[0] = out[1] = out[2] = px[0], out[3] = 1.0f; break;
    case 2: out[0] = out[1] = out[2] = px[0], out[3] = px[1]; break;
    case 3: out[0] = px[0], out[1] = px[1], out[2] = px[2], out[3] = 1.0f; break;
    default: memcpy(out, px, 4 * sizeof(float)); break;
    }
}

/* Bilinear sample at (u, v); returns 0 for non-finite coordinates. */
static int sample_bilinear(const sl_image *img, float u, float v, double out[4])
{
    if (!isfinite(u) || !isfinite(v))
        return 0;
    double x = (double)u * img->width - 0.5, y = (1.0 - (double)v) * img->height - 0.5;
    double x0 = floor(x), y0 = floor(y), fx = x - x0, fy = y - y0;
    int xa = wrap((int64_t)x0, img->width), xb = wrap((int64_t)x0 + 1, img->width);
    int ya = wrap((int64_t)y0, img->height), yb = wrap((int64_t)y0 + 1, img->height);
    float t00[4], t10[4], t01[4], t11[4];
    texel(img, xa, ya, t00), texel(img, xb, ya, t10);
    texel(img, xa, yb, t01), texel(img, xb, yb, t11);
    for (int c = 0; c < 4; c++)
        out[c] = (1 - fy) * ((1 - fx) * t00[c] + fx * t10[c]) + fy * ((1 - fx) * t01[c] + fx * t11[c]);
    return 1;
}

static void add_sample(color_sum *s, uint32_t point, const double rgba[4])
{
    for (int c = 0; c < 4; c++)
        s->rgba[4 * (uint64_t)point + c] += rgba[c];
    s->samples[point]++;
}

static void sample_texture(const sl_mesh *mesh, const range_clean *clean, const sl_image *img,
                           color_sum *s)
{
    double rgba[4];
    if (mesh->face_texcoords) {
        for (uint64_t t = 0; t < clean->triangle_count; t++) {
            const float *uv = mesh->face_texcoords + 6 * clean->triangle_source[t];
            for (int c = 0; c < 3; c++)
                if (sample_bilinear(img, uv[2 * c], uv[2 * c + 1], rgba))
                    add_sample(s, clean->triangles[3 * t + c], rgba);
        }
        return;
    }
    for (uint64_t v = 0; v < mesh->vertex_count; v++) {
        uint32_t p = clean->vertex_point[v];
        if (p != RANGE_NONE &&
            sample_bilinear(img, mesh->texcoords[2 * v], mesh->texcoords[2 * v + 1], rgba))
            add_sample(s, p, rgba);
    }
}

static void sum_vertex_colors(const sl_mesh *mesh, const range_clean *clean, color_sum *s)
{
    for (uint64_t v = 0; v < mesh->vertex_count; v++) {
        uint32_t p = clean->vertex_point[v];
        if (p == RANGE_NONE)
            continue;
        double rgba[4];
        for (int c = 0; c < 4; c++)
            rgba[c] = mesh->colors[4 * v + c] / 255.0;
        add_sample(s, p, rgba);
    }
}

/* Loads the texture; 1 on success, 0 after recording a warning. */
static int load_texture(const sl_mesh *mesh, const char *texture_dir, sl_image *img,
                        sl_range_counts *counts)
{
    char name[300], why[1600];
    if (!mesh->texcoords && !mesh->face_texcoords) {
        snprintf(why, sizeof why, "texture %s: the file has no texture coordinates",
                 sl_scan_texture_name(mesh, name, sizeof name));
        warn(counts, why);
        return 0;
    }
    if (sl_scan_texture_read(mesh, texture_dir, TEXTURE_MAX_PIXELS, img, why, sizeof why))
        return 1;
    warn(counts, why);
    return 0;
}

int range_colors(const sl_mesh *mesh, const range_clean *clean, const char *texture_dir,
                 int enabled, uint8_t **colors, sl_range_counts *counts, sl_error *err)
{
    *colors = NULL;
    counts->color_source = "none";
    int from_vertices = mesh->colors != NULL;
    if (!enabled || (!from_vertices && !sl_scan_has_texture(mesh)))
        return SL_OK;
    sl_image img = {0, 0, 0, NULL};
    if (!from_vertices && !load_texture(mesh, texture_dir, &img, counts))
        return SL_OK;
    uint64_t n = clean->point_count;
    color_sum s = {calloc(4 * n + 1, sizeof(double)), calloc(n + 1, sizeof(uint32_t))};
    uint8_t *out = malloc(4 * n + 1);
    if (!s.rgba || !s.samples || !out) {
        free(s.rgba), free(s.samples), free(out);
        sl_image_release(&img);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "colours: out of memory (%llu points)",
                            (unsigned long long)n);
    }
    if (from_vertices)
        sum_vertex_colors(mesh, clean, &s);
    else
        sample_texture(mesh, clean, &img, &s);
    sl_image_release(&img);
    for (uint64_t p = 0; p < n; p++) {
        if (!s.samples[p]) {
            counts->colors_unsampled++;
            memcpy(out + 4 * p, "\x80\x80\x80\xff", 4);
            continue;
        }
        for (int c = 0; c < 4; c++) {
            double x = s.rgba[4 * p + c] / s.samples[p];
            x = x < 0 ? 0 : x > 1 ? 1 : x;
            out[4 * p + c] = (uint8_t)lround(x * 255.0);
        }
    }
    free(s.rgba), free(s.samples);
    *colors = out;
    counts->color_source = from_vertices ? "vertex" : "texture";
    return SL_OK;
}

/* A point's texture coordinate is its vertices' (welded twins) or its corners' when they
 * all agree; where they differ (a seam, which this artifact has no room for) the point
 * set carries none and the export bakes as before. */
static int agree(float *uv, uint8_t *set, uint32_t p, float u, float v)
{
    if (!isfinite(u) || !isfinite(v))
        return 0;
    if (!set[p]) {
        set[p] = 1, uv[2 * (uint64_t)p] = u, uv[2 * (uint64_t)p + 1] = v;
        return 1;
    }
    return uv[2 * (uint64_t)p] == u && uv[2 * (uint64_t)p + 1] == v;
}

int range_texcoords(const sl_mesh *mesh, const range_clean *clean, float **texcoords,
                    sl_range_counts *counts, sl_error *err)
{
    *texcoords = NULL;
    counts->texcoord_source = "none";
    if ((!mesh->texcoords && !mesh->face_texcoords) || !clean->triangle_count ||
        !sl_scan_has_texture(mesh))
        return SL_OK;
    uint64_t n = clean->point_count;
    float *uv = malloc(8 * n + 1);
    uint8_t *set = calloc(n + 1, 1);
    if (!uv || !set) {
        free(uv), free(set);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "texture coordinates: out of memory");
    }
    uint64_t seams = 0;
    if (mesh->face_texcoords) {
        for (uint64_t t = 0; t < clean->triangle_count; t++) {
            const float *c = mesh->face_texcoords + 6 * clean->triangle_source[t];
            for (int k = 0; k < 3; k++)
                seams += !agree(uv, set, clean->triangles[3 * t + k], c[2 * k], c[2 * k + 1]);
        }
    } else {
        for (uint64_t v = 0; v < mesh->vertex_count; v++) {
            uint32_t p = clean->vertex_point[v];
            if (p != RANGE_NONE)
                seams += !agree(uv, set, p, mesh->texcoords[2 * v], mesh->texcoords[2 * v + 1]);
        }
    }
    for (uint64_t p = 0; p < n && !seams; p++)
        seams += !set[p];
    free(set);
    counts->texcoord_seams = seams;
    if (seams) {
        free(uv);
        return SL_OK;
    }
    *texcoords = uv;
    counts->texcoord_source = mesh->face_texcoords ? "corners" : "vertices";
    return SL_OK;
}
