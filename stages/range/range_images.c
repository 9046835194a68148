/* Six orthographic range images of the point set, one per axis direction (paper 1
 * section 4: "we generate the range image data from them"), behind [range] range_images.
 *
 * Layout (docs/range-stage.md): `range_<view>.exr`, view in xpos xneg ypos yneg zpos zneg
 * = the camera on that side of the bounding box looking inwards. Square images of
 * [range] range_image_size pixels covering the larger of the two in-plane box extents,
 * centred on the box; row 0 at the top. Four float channels stored as R, G, B, A =
 * depth, nx, ny, nz: depth is the world distance from the box face on the camera side,
 * the normal is in world coordinates. Background pixels are NaN in all four channels (NaN
 * cannot be mistaken for a depth, and is what OpenEXR tools show as "no data").
 * Meshes are rasterised (z-buffer, pixel centres, barycentric normals); point clouds are
 * splatted one pixel per point. Each view is independent and serial inside, so the
 * images are identical on any thread count.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "shim/oiio_shim.h"
#include "stages/range/range.h"

typedef struct view {
    const char *name;
    int axis, sign;        /* camera on the `sign` side of `axis`, looking inwards */
    int right, up;         /* image axes (world axis index) */
    float right_sign, up_sign;
} view;

static const view views[6] = {
    {"xpos", 0, +1, 2, 1, -1.0f, +1.0f}, {"xneg", 0, -1, 2, 1, +1.0f, +1.0f},
    {"ypos", 1, +1, 0, 2, +1.0f, -1.0f}, {"yneg", 1, -1, 0, 2, +1.0f, +1.0f},
    {"zpos", 2, +1, 0, 1, +1.0f, +1.0f}, {"zneg", 2, -1, 0, 1, -1.0f, +1.0f},
};

typedef struct raster {
    const view *v;
    const sl_pointset *ps;
    int size;
    double left, top, pixel; /* image-plane coordinates of the top-left corner; pixel size */
    float *pixels;           /* size * size * 4 */
} raster;

/* Continuous pixel coordinates and depth of a point. */
static void project(const raster *r, const float *p, double *x, double *y, double *depth)
{
    const view *v = r->v;
    *x = (v->right_sign * p[v->right] - r->left) / r->pixel;
    *y = (r->top - v->up_sign * p[v->up]) / r->pixel;
    *depth = v->sign > 0 ? (double)r->ps->bbox_max[v->axis] - p[v->axis]
                         : (double)p[v->axis] - r->ps->bbox_min[v->axis];
}

static void write_pixel(raster *r, int x, int y, double depth, const double n[3])
{
    float *px = r->pixels + 4 * ((size_t)y * r->size + x);
    if (!(depth < px[0]) && !isnan(px[0]))
        return;
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0))
        len = 1;
    px[0] = (float)depth;
    for (int k = 0; k < 3; k++)
        px[1 + k] = (float)(n[k] / len);
}

static void raster_triangle(raster *r, const uint32_t *tri)
{
    double x[3], y[3], d[3];
    for (int c = 0; c < 3; c++)
        project(r, r->ps->positions + 3 * (uint64_t)tri[c], &x[c], &y[c], &d[c]);
    double area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    if (area == 0.0)
        return; /* edge-on in this view */
    int x0 = (int)floor(fmin(x[0], fmin(x[1], x[2])) - 0.5), x1 = (int)ceil(fmax(x[0], fmax(x[1], x[2])));
    int y0 = (int)floor(fmin(y[0], fmin(y[1], y[2])) - 0.5), y1 = (int)ceil(fmax(y[0], fmax(y[1], y[2])));
    x0 = x0 < 0 ? 0 : x0, y0 = y0 < 0 ? 0 : y0;
    x1 = x1 >= r->size ? r->size - 1 : x1, y1 = y1 >= r->size ? r->size - 1 : y1;
    for (int py = y0; py <= y1; py++)
        for (int px = x0; px <= x1; px++) {
            double cx = px + 0.5, cy = py + 0.5, w[3];
            for (int c = 0; c < 3; c++) {
                int a = (c + 1) % 3, b = (c + 2) % 3;
                w[c] = ((x[b] - x[a]) * (cy - y[a]) - (cx - x[a]) * (y[b] - y[a])) / area;
            }
            if (w[0] < 0 || w[1] < 0 || w[2] < 0)
                continue;
            double depth = w[0] * d[0] + w[1] * d[1] + w[2] * d[2], n[3] = {0, 0, 0};
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 3; k++)
                    n[k] += w[c] * r->ps->normals[3 * (uint64_t)tri[c] + k];
            write_pixel(r, px, py, depth, n);
        }
}

static void raster_point(raster *r, uint64_t i)
{
    double x, y, depth, n[3];
    project(r, r->ps->positions + 3 * i, &x, &y, &depth);
    int px = (int)floor(x), py = (int)floor(y);
    if (px < 0 || py < 0 || px >= r->size || py >= r->size)
        return;
    for (int k = 0; k < 3; k++)
        n[k] = r->ps->normals[3 * i + k];
    write_pixel(r, px, py, depth, n);
}

static void setup_view(raster *r, const view *v, const sl_pointset *ps, int size, float *pixels)
{
    r->v = v, r->ps = ps, r->size = size, r->pixels = pixels;
    double lo_r = v->right_sign > 0 ? ps->bbox_min[v->right] : -(double)ps->bbox_max[v->right];
    double hi_r = v->right_sign > 0 ? ps->bbox_max[v->right] : -(double)ps->bbox_min[v->right];
    double lo_u = v->up_sign > 0 ? ps->bbox_min[v->up] : -(double)ps->bbox_max[v->up];
    double hi_u = v->up_sign > 0 ? ps->bbox_max[v->up] : -(double)ps->bbox_min[v->up];
    double extent = fmax(hi_r - lo_r, hi_u - lo_u);
    if (!(extent > 0))
        extent = 1.0; /* a single point or a line seen end-on */
    extent *= 1.0 + 1e-6; /* the max face maps inside the last pixel */
    r->pixel = extent / size;
    r->left = 0.5 * (lo_r + hi_r) - 0.5 * extent;
    r->top = 0.5 * (lo_u + hi_u) + 0.5 * extent;
    for (size_t i = 0; i < 4 * (size_t)size * size; i++)
        pixels[i] = NAN;
}

int sl_range_images_write(const char *dir, const sl_pointset *ps, int size,
                          sl_progress *progress, sl_error *err)
{
    const uint32_t *triangles = ps->triangles;
    uint64_t triangle_count = ps->triangle_count;
    size_t per_view = 4 * (size_t)size * (size_t)size;
    float *pixels = malloc(6 * per_view * sizeof *pixels);
    if (!pixels)
        return sl_error_set(err, SL_E_NOMEM, 0, dir, "range images: out of memory (%d px)", size);
    int stop = 0;
#pragma omp parallel for schedule(static, 1)
    for (int vi = 0; vi < 6; vi++) {
        raster r;
        setup_view(&r, &views[vi], ps, size, pixels + vi * per_view);
        uint64_t count = triangles ? triangle_count : ps->count;
        for (uint64_t i = 0; i < count; i++) {
            if ((i & 0xffff) == 0 && sl_progress_interrupted(progress)) {
#pragma omp atomic write
                stop = 1;
                break;
            }
            if (triangles)
                raster_triangle(&r, triangles + 3 * i);
            else
                raster_point(&r, i);
        }
    }
    int rc = stop ? SL_E_INTERRUPTED : SL_OK;
    for (int vi = 0; rc == SL_OK && vi < 6; vi++) {
        char path[1100];
        snprintf(path, sizeof path, "%s/range_%s.exr", dir, views[vi].name);
        rc = sl_image_write(path, size, size, 4, pixels + vi * per_view, err);
    }
    free(pixels);
    return rc;
}
