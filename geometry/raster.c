/* Thumbnail rasteriser (see geometry/raster.h for the view and shading contract).
 *
 * Method: deferred shading on a supersampled grid. Pass 1 projects every vertex once
 * (orthographic camera fitted to the mesh), then scan-converts each triangle with edge
 * functions over its bounding box, keeping per sample the nearest depth and the triangle
 * index (a strict comparison, so at equal depth the earlier triangle stays: deterministic).
 * Pass 2, per output pixel, shades only the visible samples of its ss x ss block,
 * recomputing the barycentric coordinates from the stored triangle (so the cost of shading
 * does not grow with overdraw), darkens samples on the silhouette and on depth jumps,
 * box-filters the block in linear light and encodes sRGB. Pass 1 is parallel over bands
 * of rows, pass 2 over rows; every sample and pixel depends only on the mesh (pass 1) and
 * on pass 1's buffers (pass 2), so the result does not depend on the thread count.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/raster.h"
#include "geometry/vec3.h"
#include "shim/oiio_shim.h"

#define AZIMUTH_DEG 30.0
#define ELEVATION_DEG 20.0
#define MARGIN 0.06           /* of the image side, each side */
#define MAX_SAMPLES (8u << 20) /* supersampled grid cap: 8 Mi samples, 64 MiB */
#define NO_TRIANGLE UINT32_MAX
#define EDGE_DARKEN 0.45f      /* linear-light factor on silhouette samples */
#define DEPTH_JUMP 0.04        /* fraction of the view extent that counts as an edge */

static const float BACKGROUND_SRGB = 0.94f;
static const float CLAY_SRGB[3] = {0.78f, 0.72f, 0.64f};

typedef struct camera {
    double center[3];            /* world point mapped to the image centre */
    double right[3], up[3], back[3]; /* orthonormal; back points towards the viewer */
    double scale;                /* samples per world unit */
    int width, height;           /* of the sample grid */
} camera;

typedef struct sample_grid {
    int width, height, ss;
    float *depth;     /* towards the viewer is larger; -FLT_MAX = background */
    uint32_t *tri;    /* visible triangle or NO_TRIANGLE */
} sample_grid;

static void normalize3(double *v)
{
    double l = sqrt(sl_dot3(v, v));
    if (l > 0)
        for (int k = 0; k < 3; k++)
            v[k] /= l;
}

static float srgb_to_linear(float c)
{
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

static float linear_to_srgb(float c)
{
    c = c < 0 ? 0 : c > 1 ? 1 : c;
    return c <= 0.0031308f ? 12.92f * c : 1.055f * powf(c, 1.0f / 2.4f) - 0.055f;
}

/* Camera basis from the fixed direction, then the orthographic fit: the projected extent
 * of the vertices that triangles use (stray unreferenced vertices do not shrink the
 * object) is centred and scaled into the grid less the margin. */
static void fit_camera(const sl_mesh *m, int width, int height, camera *c)
{
    const double pi = 3.14159265358979323846;
    double az = AZIMUTH_DEG * pi / 180, el = ELEVATION_DEG * pi / 180;
    double back[3] = {cos(el) * sin(az), sin(el), cos(el) * cos(az)};
    double right[3] = {back[2], 0, -back[0]}; /* world_up x back, world_up = +Y */
    normalize3(right);
    double up[3] = {back[1] * right[2] - back[2] * right[1],
                    back[2] * right[0] - back[0] * right[2],
                    back[0] * right[1] - back[1] * right[0]};
    memcpy(c->back, back, sizeof back);
    memcpy(c->right, right, sizeof right);
    memcpy(c->up, up, sizeof up);

    double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX};
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++) {
        const float *p = m->positions + 3 * (uint64_t)m->triangles[i];
        double q[3] = {p[0], p[1], p[2]}, r = sl_dot3(q, right), u = sl_dot3(q, up);
        lo[0] = r < lo[0] ? r : lo[0];
        hi[0] = r > hi[0] ? r : hi[0];
        lo[1] = u < lo[1] ? u : lo[1];
        hi[1] = u > hi[1] ? u : hi[1];
    }
    double mid_r = 0.5 * (lo[0] + hi[0]), mid_u = 0.5 * (lo[1] + hi[1]);
    for (int k = 0; k < 3; k++)
        c->center[k] = mid_r * right[k] + mid_u * up[k];
    double ext_r = hi[0] - lo[0], ext_u = hi[1] - lo[1];
    double sx = width * (1 - 2 * MARGIN) / (ext_r > 0 ? ext_r : 1);
    double sy = height * (1 - 2 * MARGIN) / (ext_u > 0 ? ext_u : 1);
    c->scale = sx < sy ? sx : sy;
    c->width = width;
    c->height = height;
}

/* Grid coordinates (x right, y down, in samples) and depth of every vertex. */
static void project(const sl_mesh *m, const camera *c, float *screen)
{
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        const float *p = m->positions + 3 * i;
        double q[3] = {p[0] - c->center[0], p[1] - c->center[1], p[2] - c->center[2]};
        screen[3 * i] = (float)(0.5 * c->width + sl_dot3(q, c->right) * c->scale);
        screen[3 * i + 1] = (float)(0.5 * c->height - sl_dot3(q, c->up) * c->scale);
        screen[3 * i + 2] = (float)sl_dot3(q, c->back);
    }
}

static float edge(const float *a, const float *b, float px, float py)
{
    return (b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0]);
}

/* Pass 1 over the rows [row0, row1) of the grid: nearest triangle per sample, for the
 * triangles `list` names (in index order). */
static void scan_convert_rows(const sl_mesh *m, const float *screen, sample_grid *g,
                              int row0, int row1, const uint32_t *list, uint64_t count)
{
    for (uint64_t i = 0; i < count; i++) {
        uint64_t t = list[i];
        const float *a = screen + 3 * (uint64_t)m->triangles[3 * t];
        const float *b = screen + 3 * (uint64_t)m->triangles[3 * t + 1];
        const float *c = screen + 3 * (uint64_t)m->triangles[3 * t + 2];
        float y0 = fminf(a[1], fminf(b[1], c[1])), y1 = fmaxf(a[1], fmaxf(b[1], c[1]));
        float area = edge(a, b, c[0], c[1]);
        float x0 = fminf(a[0], fminf(b[0], c[0])), x1 = fmaxf(a[0], fmaxf(b[0], c[0]));
        int ix0 = x0 < 0 ? 0 : (int)x0, iy0 = y0 < row0 ? row0 : (int)y0;
        int ix1 = x1 >= g->width ? g->width - 1 : (int)x1;
        int iy1 = y1 >= row1 ? row1 - 1 : (int)y1;
        for (int y = iy0; y <= iy1; y++)
            for (int x = ix0; x <= ix1; x++) {
                float px = x + 0.5f, py = y + 0.5f;
                float w0 = edge(b, c, px, py) / area, w1 = edge(c, a, px, py) / area;
                float w2 = 1 - w0 - w1;
                if (w0 < 0 || w1 < 0 || w2 < 0)
                    continue;
                float z = w0 * a[2] + w1 * b[2] + w2 * c[2];
                size_t s = (size_t)y * (size_t)g->width + (size_t)x;
                if (z > g->depth[s]) {
                    g->depth[s] = z;
                    g->tri[s] = (uint32_t)t;
                }
            }
    }
}

/* Pass 1, in horizontal bands of the grid, in parallel: a band owns its samples and visits
 * its triangles in index order, so every sample ends as the serial pass would leave it,
 * whatever the thread count. A fixed band count keeps the work the same too. Each band
 * used to test every triangle (16 passes over a million-triangle level's vertices, the
 * export's largest cost at 1 M); the triangles are binned to the bands they meet first,
 * in one pass of fixed chunks (so the lists do not depend on the thread count either). */
#define SCAN_BANDS 16
#define BIN_CHUNKS 64

static int band_row(const sample_grid *g, int band)
{
    return (int)((int64_t)g->height * band / SCAN_BANDS);
}

/* Bit b set: triangle t meets band b (and is not seen edge-on, which covers no sample). */
static unsigned triangle_bands(const sl_mesh *m, const float *screen, const sample_grid *g,
                               uint64_t t)
{
    const float *a = screen + 3 * (uint64_t)m->triangles[3 * t];
    const float *b = screen + 3 * (uint64_t)m->triangles[3 * t + 1];
    const float *c = screen + 3 * (uint64_t)m->triangles[3 * t + 2];
    float y0 = fminf(a[1], fminf(b[1], c[1])), y1 = fmaxf(a[1], fmaxf(b[1], c[1]));
    if (fabsf(edge(a, b, c[0], c[1])) < 1e-12f)
        return 0;
    unsigned bands = 0;
    for (int band = 0; band < SCAN_BANDS; band++)
        if (!(y1 < band_row(g, band) || y0 >= band_row(g, band + 1)))
            bands |= 1u << band;
    return bands;
}

static int scan_convert(const sl_mesh *m, const float *screen, sample_grid *g)
{
    uint64_t n = m->triangle_count;
    uint64_t (*at)[SCAN_BANDS] = calloc(BIN_CHUNKS + 1, sizeof *at);
    uint16_t *bands = malloc((n ? n : 1) * sizeof *bands);
    if (!at || !bands) {
        free(at);
        free(bands);
        return -1;
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (int chunk = 0; chunk < BIN_CHUNKS; chunk++)
        for (uint64_t t = n * chunk / BIN_CHUNKS; t < n * (chunk + 1) / BIN_CHUNKS; t++) {
            bands[t] = (uint16_t)triangle_bands(m, screen, g, t);
            for (int band = 0; band < SCAN_BANDS; band++)
                at[chunk + 1][band] += bands[t] >> band & 1u;
        }
    /* at[chunk][band]: where the chunk's first triangle of that band goes; the bands'
     * lists follow one another. */
    uint64_t start[SCAN_BANDS + 1], total = 0;
    for (int band = 0; band < SCAN_BANDS; band++) {
        start[band] = total;
        for (int chunk = 0; chunk < BIN_CHUNKS; chunk++) {
            uint64_t c = at[chunk + 1][band];
            at[chunk][band] = total;
            total += c;
        }
    }
    start[SCAN_BANDS] = total;
    uint32_t *list = malloc((total ? total : 1) * sizeof *list);
    if (!list) {
        free(at);
        free(bands);
        return -1;
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (int chunk = 0; chunk < BIN_CHUNKS; chunk++)
        for (uint64_t t = n * chunk / BIN_CHUNKS; t < n * (chunk + 1) / BIN_CHUNKS; t++)
            for (int band = 0; band < SCAN_BANDS; band++)
                if (bands[t] >> band & 1u)
                    list[at[chunk][band]++] = (uint32_t)t;
    free(bands);
    free(at);
#pragma omp parallel for schedule(dynamic, 1)
    for (int band = 0; band < SCAN_BANDS; band++)
        scan_convert_rows(m, screen, g, band_row(g, band), band_row(g, band + 1),
                          list + start[band], start[band + 1] - start[band]);
    free(list);
    return 0;
}

/* What pass 2 needs besides the mesh. */
typedef struct shader {
    const sl_mesh *m;
    const camera *cam;
    const float *screen;
    double light[3];          /* world direction towards the key light */
    float color_lut[256];     /* sRGB byte -> linear */
    float clay[3], background; /* linear */
    float depth_jump;         /* world units */
} shader;

static void vertex_normal(const float *n, double out[3])
{
    double l = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
    for (int k = 0; k < 3; k++)
        out[k] = l > 1e-30 && isfinite(l) ? n[k] / l : 0;
}

/* Linear RGB of triangle t seen at sample centre (px, py). */
static void shade(const shader *sh, uint64_t t, float px, float py, float rgb[3])
{
    const sl_mesh *m = sh->m;
    const uint32_t *v = m->triangles + 3 * t;
    const float *a = sh->screen + 3 * (uint64_t)v[0], *b = sh->screen + 3 * (uint64_t)v[1];
    const float *c = sh->screen + 3 * (uint64_t)v[2];
    float area = edge(a, b, c[0], c[1]);
    double w[3] = {edge(b, c, px, py) / area, edge(c, a, px, py) / area, 0};
    w[2] = 1 - w[0] - w[1];

    /* Face normal turned towards the viewer: two-sided lighting. */
    const float *p0 = m->positions + 3 * (uint64_t)v[0], *p1 = m->positions + 3 * (uint64_t)v[1];
    const float *p2 = m->positions + 3 * (uint64_t)v[2];
    double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    normalize3(n);
    double facing = sl_dot3(n, sh->cam->back) < 0 ? -1 : 1;
    for (int k = 0; k < 3; k++)
        n[k] *= facing;
    if (m->normals) {
        /* Smooth normal, oriented like its face so inconsistent scan normals still light. */
        double s[3] = {0, 0, 0}, vn[3];
        for (int i = 0; i < 3; i++) {
            vertex_normal(m->normals + 3 * (uint64_t)v[i], vn);
            for (int k = 0; k < 3; k++)
                s[k] += w[i] * vn[k];
        }
        double along = sl_dot3(s, n) < 0 ? -1 : 1, len = sqrt(sl_dot3(s, s));
        if (len > 1e-6)
            for (int k = 0; k < 3; k++)
                n[k] = along * s[k] / len;
    }
    double key = sl_dot3(n, sh->light), head = sl_dot3(n, sh->cam->back);
    float light = (float)(0.10 + 0.80 * (key > 0 ? key : 0) + 0.14 * (head > 0 ? head : 0));
    for (int k = 0; k < 3; k++) {
        float albedo = sh->clay[k];
        if (m->colors)
            albedo = (float)(w[0] * sh->color_lut[m->colors[4 * (uint64_t)v[0] + k]] +
                             w[1] * sh->color_lut[m->colors[4 * (uint64_t)v[1] + k]] +
                             w[2] * sh->color_lut[m->colors[4 * (uint64_t)v[2] + k]]);
        rgb[k] = albedo * light;
    }
}

/* A visible sample is on an edge when a sample `reach` away is background or much
 * farther: the outline that separates the object from the background and from itself. */
static int on_edge(const sample_grid *g, int x, int y, int reach, float jump)
{
    static const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
    float z = g->depth[(size_t)y * (size_t)g->width + (size_t)x];
    for (int i = 0; i < 4; i++) {
        int nx = x + dx[i] * reach, ny = y + dy[i] * reach;
        if (nx < 0 || ny < 0 || nx >= g->width || ny >= g->height)
            continue;
        float nz = g->depth[(size_t)ny * (size_t)g->width + (size_t)nx];
        if (nz == -FLT_MAX || nz < z - jump)
            return 1;
    }
    return 0;
}

/* Pass 2 for output pixel (ox, oy). */
static void resolve_pixel(const shader *sh, const sample_grid *g, int ox, int oy, float *out)
{
    float sum[3] = {0, 0, 0};
    int ss = g->ss, reach = (ss + 1) / 2;
    for (int sy = 0; sy < ss; sy++)
        for (int sx = 0; sx < ss; sx++) {
            int x = ox * ss + sx, y = oy * ss + sy;
            uint32_t t = g->tri[(size_t)y * (size_t)g->width + (size_t)x];
            float rgb[3] = {sh->background, sh->background, sh->background};
            if (t != NO_TRIANGLE) {
                shade(sh, t, x + 0.5f, y + 0.5f, rgb);
                if (on_edge(g, x, y, reach, sh->depth_jump))
                    for (int k = 0; k < 3; k++)
                        rgb[k] *= EDGE_DARKEN;
            }
            for (int k = 0; k < 3; k++)
                sum[k] += rgb[k];
        }
    for (int k = 0; k < 3; k++)
        out[k] = linear_to_srgb(sum[k] / (float)(ss * ss));
    out[3] = 1.0f;
}

static void init_shader(shader *sh, const sl_mesh *m, const camera *cam, const float *screen)
{
    sh->m = m;
    sh->cam = cam;
    sh->screen = screen;
    /* Key light above and to the left of the camera, as in a studio product shot. */
    for (int k = 0; k < 3; k++)
        sh->light[k] = -0.6 * cam->right[k] + 0.7 * cam->up[k] + 0.45 * cam->back[k];
    normalize3(sh->light);
    for (int i = 0; i < 256; i++)
        sh->color_lut[i] = srgb_to_linear(i / 255.0f);
    for (int k = 0; k < 3; k++)
        sh->clay[k] = srgb_to_linear(CLAY_SRGB[k]);
    sh->background = srgb_to_linear(BACKGROUND_SRGB);
    double view_width = cam->width / cam->scale;
    sh->depth_jump = (float)(DEPTH_JUMP * view_width);
}

static int supersampling(int width, int height)
{
    uint64_t pixels = (uint64_t)width * (uint64_t)height;
    return pixels * 9 <= MAX_SAMPLES ? 3 : pixels * 4 <= MAX_SAMPLES ? 2 : 1;
}

/* `path` only names the file in messages (may be NULL). */
static int render(const sl_mesh *m, int width, int height, float *rgba, const char *path,
                  sl_error *err)
{
    int rc = sl_mesh_check_writable(m, path, err);
    if (rc)
        return rc;
    if (width < 1 || height < 1 || width > SL_THUMBNAIL_MAX_SIDE ||
        height > SL_THUMBNAIL_MAX_SIDE)
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "thumbnail size %dx%d outside 1..%d",
                            width, height, SL_THUMBNAIL_MAX_SIDE);
    if (m->triangle_count >= NO_TRIANGLE)
        return sl_error_set(err, SL_E_LIMIT, 0, path,
                            "%llu triangles are too many for the thumbnail rasteriser",
                            (unsigned long long)m->triangle_count);

    sample_grid g = {.ss = supersampling(width, height)};
    g.width = width * g.ss;
    g.height = height * g.ss;
    size_t samples = (size_t)g.width * (size_t)g.height;
    float *screen = malloc((size_t)m->vertex_count * 3 * sizeof *screen);
    g.depth = malloc(samples * sizeof *g.depth);
    g.tri = malloc(samples * sizeof *g.tri);
    if (!screen || !g.depth || !g.tri) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory for a %dx%d thumbnail",
                          width, height);
        goto done;
    }
    for (size_t s = 0; s < samples; s++) {
        g.depth[s] = -FLT_MAX;
        g.tri[s] = NO_TRIANGLE;
    }
    camera cam;
    fit_camera(m, g.width, g.height, &cam);
    project(m, &cam, screen);
    if (scan_convert(m, screen, &g) != 0) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory binning %llu triangles",
                          (unsigned long long)m->triangle_count);
        goto done;
    }

    shader sh;
    init_shader(&sh, m, &cam, screen);
#pragma omp parallel for schedule(static)
    for (int oy = 0; oy < height; oy++)
        for (int ox = 0; ox < width; ox++)
            resolve_pixel(&sh, &g, ox, oy, rgba + 4 * ((size_t)oy * (size_t)width + (size_t)ox));
done:
    free(screen);
    free(g.depth);
    free(g.tri);
    return rc;
}

int sl_render_thumbnail(const sl_mesh *m, int width, int height, float *rgba,
                        sl_error *err)
{
    return render(m, width, height, rgba, NULL, err);
}

int sl_write_thumbnail(const char *path, const sl_mesh *m, int size, sl_error *err)
{
    if (size < 1 || size > SL_THUMBNAIL_MAX_SIDE)
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "thumbnail size %d outside 1..%d", size,
                            SL_THUMBNAIL_MAX_SIDE);
    float *rgba = malloc((size_t)size * (size_t)size * 4 * sizeof *rgba);
    if (!rgba)
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory for a thumbnail");
    int rc = render(m, size, size, rgba, path, err);
    if (rc == 0)
        rc = sl_image_write(path, size, size, 4, rgba, err);
    free(rgba);
    return rc;
}
