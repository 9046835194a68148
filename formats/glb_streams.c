/* The data of a GLB (glb_internal.h): one bufferView per vertex attribute, the indices and
 * the image; quantised per KHR_mesh_quantization, compressed per EXT_meshopt_compression
 * or replaced by one KHR_draco_mesh_compression stream; and what a viewer will decode,
 * measured against the mesh given.
 *
 * Quantisation (docs/glb.md "Quantisation and its error"):
 *   - positions: q = round((p - lo) / s) on one grid for all three axes, s = the largest
 *     bounding-box extent / (2^bits - 1), unsigned integers (not normalized) with the
 *     node's translation lo and uniform scale s, as gltfpack writes them. One step for all
 *     axes keeps the error isotropic and the node's scale uniform (normals need no
 *     correction). Each coordinate moves at most s/2, a vertex at most sqrt(3)/2 s;
 *   - normals: signed normalized bytes (shorts above 8 bits); in meshopt files the
 *     octahedral filter (meshopt_encodeFilterOct), as gltfpack -cc does;
 *   - colours: sRGB bytes -> linear (glTF: COLOR_0 is a linear multiplier), then unsigned
 *     normalized at color_bits: 8 bits of *linear* light lose the dark tones (sRGB 10
 *     becomes 13), 12 bits keep every sRGB byte within half a step;
 *   - texture coordinates: unsigned normalized shorts when all lie in [0, 1], else float.
 * Layout per stream as gltfpack: 8-byte stride for 3 x 16 bits, 4 for 3 x 8 bits, so every
 * element is 4-byte aligned (glTF) and meshopt's vertex codec (strides multiple of 4) takes
 * the stream as is; the padding component is 0 and costs nothing once encoded.
 */
#include <math.h>
#include <meshoptimizer.h>
#include <stdlib.h>
#include <string.h>

#include "formats/glb_internal.h"
#include "geometry/kdtree.h"
#include "shim/draco_shim.h"

#define DRACO_SPEED 5 /* encoder and decoder speed, as gltf-transform's default */

double glb_srgb_to_linear(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

double glb_linear_to_srgb(double l)
{
    l = l < 0 ? 0 : l > 1 ? 1 : l;
    return l <= 0.0031308 ? 12.92 * l : 1.055 * pow(l, 1 / 2.4) - 0.055;
}

/* glTF asks for unit normals; lengths are normalised in double so the float result is
 * within 1e-7 of 1, far inside the validator's tolerance. */
static void unit_normal(const float *n, float out[3])
{
    double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
    if (!(len > 1e-30) || !isfinite(len)) {
        out[0] = out[1] = 0.0f;
        out[2] = 1.0f;
        return;
    }
    for (int k = 0; k < 3; k++)
        out[k] = (float)(n[k] / len);
}

static void put16(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v, p[1] = (unsigned char)(v >> 8);
}

/* x in [0, 1] held at `bits` precision as a normalized integer of `full` (255, 65535). */
static uint32_t unorm_at_bits(double x, int bits, uint32_t full)
{
    double top = (double)((1u << bits) - 1);
    x = x < 0 ? 0 : x > 1 ? 1 : x;
    return (uint32_t)lround(round(x * top) * full / top);
}

/* ---- positions ---- */

static void bounds(const sl_mesh *m, float lo[3], float hi[3])
{
    memcpy(lo, m->positions, 3 * sizeof *lo);
    memcpy(hi, m->positions, 3 * sizeof *hi);
    for (uint64_t i = 1; i < m->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            float v = m->positions[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
}

static int float_positions(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    unsigned char *data = malloc(12 * m->vertex_count);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    memcpy(data, m->positions, 12 * m->vertex_count); /* little-endian hosts only */
    int v = glb_add_view(d, data, 12 * m->vertex_count, 12, m->vertex_count, GLTF_ARRAY_BUFFER,
                     "ATTRIBUTES");
    glb_accessor *a = glb_add_accessor(d, "POSITION", v, GLTF_FLOAT, "VEC3", 0, m->vertex_count);
    float lo[3], hi[3];
    bounds(m, lo, hi);
    a->has_bounds = 1;
    for (int k = 0; k < 3; k++)
        a->min[k] = lo[k], a->max[k] = hi[k];
    return 0;
}

static int quantized_positions(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    int bits = d->opt->position_bits, wide = bits > 8;
    uint32_t top = (1u << bits) - 1, stride = wide ? 8 : 4;
    float lo[3], hi[3];
    bounds(m, lo, hi);
    double extent = 0;
    for (int k = 0; k < 3; k++)
        extent = (double)hi[k] - lo[k] > extent ? (double)hi[k] - lo[k] : extent;
    /* The float scale a viewer multiplies by, rounded up so the top of the grid reaches
     * the box's far side. */
    float s = extent > 0 ? (float)(extent / top) : 1.0f;
    while ((double)s * top < extent)
        s = nextafterf(s, INFINITY);
    unsigned char *data = calloc(m->vertex_count, stride);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    uint32_t qlo[3] = {top, top, top}, qhi[3] = {0, 0, 0};
    double sum2 = 0, max2 = 0;
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            double p = m->positions[3 * i + k];
            long q = lround((p - lo[k]) / s);
            uint32_t u = q < 0 ? 0 : q > (long)top ? top : (uint32_t)q;
            if (wide)
                put16(data + stride * i + 2 * k, u);
            else
                data[stride * i + k] = (unsigned char)u;
            qlo[k] = u < qlo[k] ? u : qlo[k];
            qhi[k] = u > qhi[k] ? u : qhi[k];
            double back = (float)((float)u * s + lo[k]); /* the viewer's float arithmetic */
            d2 += (back - p) * (back - p);
        }
        sum2 += d2;
        max2 = d2 > max2 ? d2 : max2;
    }
    int v = glb_add_view(d, data, stride * m->vertex_count, stride, m->vertex_count,
                     GLTF_ARRAY_BUFFER, "ATTRIBUTES");
    glb_accessor *a = glb_add_accessor(d, "POSITION", v, wide ? GLTF_UNSIGNED_SHORT
                                                          : GLTF_UNSIGNED_BYTE,
                                   "VEC3", 0, m->vertex_count);
    a->has_bounds = 1;
    for (int k = 0; k < 3; k++)
        a->min[k] = qlo[k], a->max[k] = qhi[k];
    d->quantized = d->node_transform = 1;
    memcpy(d->translation, lo, sizeof lo);
    d->scale = s;
    d->stats.position_step = s;
    d->stats.position_bound = sqrt(3.0) / 2 * s;
    d->stats.position_error_max = sqrt(max2);
    d->stats.position_error_rms = sqrt(sum2 / m->vertex_count);
    return 0;
}

/* ---- normals ---- */

static double angle_deg(const float a[3], const double b[3])
{
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (lb > 0 ? lb : 1);
    c = c > 1 ? 1 : c < -1 ? -1 : c;
    return acos(c) * 180 / 3.14159265358979323846;
}

static int float_normals(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    float *data = malloc(12 * m->vertex_count);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    for (uint64_t i = 0; i < m->vertex_count; i++)
        unit_normal(m->normals + 3 * i, data + 3 * i);
    int v = glb_add_view(d, (unsigned char *)data, 12 * m->vertex_count, 12, m->vertex_count,
                     GLTF_ARRAY_BUFFER, "ATTRIBUTES");
    glb_add_accessor(d, "NORMAL", v, GLTF_FLOAT, "VEC3", 0, m->vertex_count);
    return 0;
}

/* Signed normalized components at normal_bits; in meshopt files the octahedral filter's
 * input (the stream stores two components and the decoder rebuilds all three). */
static int quantized_normals(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    int bits = d->opt->normal_bits, wide = bits > 8;
    int oct = d->opt->compression == SL_GLB_MESHOPT;
    uint32_t stride = wide ? 8 : 4;
    double full = wide ? 32767 : 127, top = (double)((1u << (bits - 1)) - 1);
    unsigned char *data = calloc(m->vertex_count, stride);
    unsigned char *decoded = oct ? malloc(stride * m->vertex_count) : data;
    float *unit = malloc(16 * m->vertex_count);
    if (!data || !decoded || !unit) {
        free(data), free(unit);
        if (oct)
            free(decoded);
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    }
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        unit_normal(m->normals + 3 * i, unit + 4 * i);
        unit[4 * i + 3] = 0;
    }
    if (oct) {
        meshopt_encodeFilterOct(data, m->vertex_count, stride, bits, unit);
        memcpy(decoded, data, stride * m->vertex_count);
        meshopt_decodeFilterOct(decoded, m->vertex_count, stride);
    } else {
        for (uint64_t i = 0; i < m->vertex_count; i++)
            for (int k = 0; k < 3; k++) {
                long q = lround(round(unit[4 * i + k] * top) * full / top);
                if (wide)
                    put16(data + stride * i + 2 * k, (uint32_t)(uint16_t)(int16_t)q);
                else
                    data[stride * i + k] = (unsigned char)(int8_t)q;
            }
    }
    double worst = 0;
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        double back[3];
        for (int k = 0; k < 3; k++)
            back[k] = wide ? (int16_t)(decoded[stride * i + 2 * k] |
                                       decoded[stride * i + 2 * k + 1] << 8) / full
                           : (int8_t)decoded[stride * i + k] / full;
        double a = angle_deg(unit + 4 * i, back);
        worst = a > worst ? a : worst;
    }
    d->stats.normal_error_max_deg = worst;
    if (oct)
        free(decoded);
    free(unit);
    int v = glb_add_view(d, data, stride * m->vertex_count, stride, m->vertex_count,
                     GLTF_ARRAY_BUFFER, "ATTRIBUTES");
    d->views[v].filter = oct ? "OCTAHEDRAL" : NULL;
    glb_add_accessor(d, "NORMAL", v, wide ? GLTF_SHORT : GLTF_BYTE, "VEC3", 1, m->vertex_count);
    d->quantized = 1;
    return 0;
}

/* ---- colours, texture coordinates ---- */

/* RGBA: sRGB bytes to linear, alpha (already linear) as it is; the largest decoded error
 * in sRGB 1/255 steps over the bytes the mesh uses. */
static int colors(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    int bits = d->opt->color_bits, wide = bits > 8;
    uint32_t stride = wide ? 8 : 4, full = wide ? 65535 : 255;
    uint32_t code[256], alpha[256];
    double miss[256];
    for (int b = 0; b < 256; b++) {
        code[b] = unorm_at_bits(glb_srgb_to_linear(b / 255.0), bits, full);
        alpha[b] = unorm_at_bits(b / 255.0, bits, full);
        miss[b] = fabs(glb_linear_to_srgb((double)code[b] / full) * 255 - b);
    }
    unsigned char *data = malloc(stride * m->vertex_count);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    double worst = 0;
    for (uint64_t i = 0; i < m->vertex_count; i++)
        for (int k = 0; k < 4; k++) {
            uint8_t b = m->colors[4 * i + k];
            uint32_t c = k < 3 ? code[b] : alpha[b];
            if (k < 3 && miss[b] > worst)
                worst = miss[b];
            if (wide)
                put16(data + stride * i + 2 * k, c);
            else
                data[stride * i + k] = (unsigned char)c;
        }
    d->stats.color_error_max = worst;
    int v = glb_add_view(d, data, stride * m->vertex_count, stride, m->vertex_count,
                     GLTF_ARRAY_BUFFER, "ATTRIBUTES");
    glb_add_accessor(d, "COLOR_0", v, wide ? GLTF_UNSIGNED_SHORT : GLTF_UNSIGNED_BYTE, "VEC4", 1,
                 m->vertex_count);
    return 0;
}

/* glTF's (u, v) origin is the image's top left, the PLY/OpenGL one its bottom left. */
static float flipped(const float *uv, int k)
{
    float t = k ? 1.0f - uv[1] : uv[0];
    return isfinite(t) ? t : 0.0f;
}

static int texcoords(glb_doc *d, const sl_mesh *m, int quantize, sl_error *err)
{
    int unit = quantize;
    for (uint64_t i = 0; i < 2 * m->vertex_count && unit; i++) {
        float t = flipped(m->texcoords + (i & ~(uint64_t)1), (int)(i & 1));
        unit = t >= 0 && t <= 1;
    }
    uint32_t stride = unit ? 4 : 8;
    unsigned char *data = malloc(stride * m->vertex_count);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    for (uint64_t i = 0; i < m->vertex_count; i++)
        for (int k = 0; k < 2; k++) {
            float t = flipped(m->texcoords + 2 * i, k);
            if (unit)
                put16(data + 4 * i + 2 * k, unorm_at_bits(t, d->opt->texcoord_bits, 65535));
            else
                memcpy(data + 8 * i + 4 * k, &t, 4);
        }
    int v = glb_add_view(d, data, stride * m->vertex_count, stride, m->vertex_count,
                     GLTF_ARRAY_BUFFER, "ATTRIBUTES");
    glb_add_accessor(d, "TEXCOORD_0", v, unit ? GLTF_UNSIGNED_SHORT : GLTF_FLOAT, "VEC2", unit,
                 m->vertex_count);
    d->quantized |= unit;
    return 0;
}

static int indices(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    int shorts = m->vertex_count < 65536;
    uint64_t n = 3 * m->triangle_count, size = n * (shorts ? 2 : 4);
    unsigned char *data = malloc(size);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    for (uint64_t i = 0; i < n; i++)
        if (shorts)
            put16(data + 2 * i, m->triangles[i]);
        else
            memcpy(data + 4 * i, &m->triangles[i], 4);
    int v = glb_add_view(d, data, size, shorts ? 2 : 4, n, GLTF_ELEMENT_ARRAY_BUFFER, "TRIANGLES");
    d->indices = d->accessor_count;
    glb_add_accessor(d, NULL, v, shorts ? GLTF_UNSIGNED_SHORT : GLTF_UNSIGNED_INT, "SCALAR", 0, n);
    return 0;
}

static int image(glb_doc *d, sl_error *err)
{
    unsigned char *data = malloc(d->opt->image_size);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    memcpy(data, d->opt->image, d->opt->image_size);
    d->image_view = glb_add_view(d, data, d->opt->image_size, 0, 0, 0, NULL);
    if (!glb_webp(d) || !d->opt->fallback_image || !d->opt->fallback_image_size)
        return 0;
    data = malloc(d->opt->fallback_image_size);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory");
    memcpy(data, d->opt->fallback_image, d->opt->fallback_image_size);
    d->fallback_view = glb_add_view(d, data, d->opt->fallback_image_size, 0, 0, 0, NULL);
    return 0;
}

/* ---- EXT_meshopt_compression ---- */

static int meshopt_pack(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    meshopt_encodeIndexVersion(1); /* the spec's TRIANGLES streams start with 0xe1 */
    for (int i = 0; i < d->view_count; i++) {
        glb_view *v = &d->views[i];
        if (!v->mode)
            continue;
        int tri = v->target == GLTF_ELEMENT_ARRAY_BUFFER;
        size_t bound = tri ? meshopt_encodeIndexBufferBound(v->count, m->vertex_count)
                           : meshopt_encodeVertexBufferBound(v->count, v->stride);
        if (!(v->packed = malloc(bound)))
            return sl_error_nomem(err, NULL, "GLB: out of memory");
        v->packed_size = tri ? meshopt_encodeIndexBuffer(v->packed, bound, m->triangles, v->count)
                             : meshopt_encodeVertexBuffer(v->packed, bound, v->data, v->count,
                                                          v->stride);
        if (v->packed_size == 0)
            return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "meshopt: stream %d not encoded", i);
    }
    return 0;
}

/* ---- KHR_draco_mesh_compression ---- */

static void draco_attribute(sl_draco_mesh *dm, int semantic, int type, int components,
                            int normalized, int bits, void *data)
{
    sl_draco_attribute *a = &dm->attributes[dm->attribute_count++];
    a->semantic = semantic, a->type = type, a->components = components;
    a->normalized = normalized, a->bits = bits, a->data = data, a->unique_id = -1;
}

/* Errors of the decoded mesh: each decoded vertex against the nearest vertex given (the
 * quantisation step is far below the vertex spacing of any mesh worth compressing); its
 * normal against the best matching normal among the given vertices within the position
 * bound (vertices at one place with different normals are common: creases, seams). */
static int draco_errors(glb_doc *d, const sl_mesh *m, const sl_draco_mesh *out, sl_error *err)
{
    enum { K = 8 };
    sl_kdtree *tree = NULL;
    int rc = sl_kdtree_build(&tree, m->positions, m->vertex_count, err);
    if (rc)
        return rc;
    const float *pos = out->attributes[0].data;
    const float *nrm = m->normals ? out->attributes[1].data : NULL;
    double sum2 = 0, max2 = 0, worst = 0, r2 = 4 * d->stats.position_bound * d->stats.position_bound;
    for (uint64_t i = 0; i < out->vertex_count; i++) {
        uint32_t idx[K];
        float d2[K];
        uint32_t n = sl_kdtree_knn(tree, pos + 3 * i, K, idx, d2);
        sum2 += d2[0];
        max2 = d2[0] > max2 ? d2[0] : max2;
        double best = 180;
        for (uint32_t c = 0; nrm && c < n && (c == 0 || d2[c] <= r2); c++) {
            float given[3];
            unit_normal(m->normals + 3 * (uint64_t)idx[c], given);
            double back[3] = {nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]};
            double a = angle_deg(given, back);
            best = a < best ? a : best;
        }
        worst = nrm && best > worst ? best : worst;
    }
    sl_kdtree_free(tree);
    d->stats.position_error_max = sqrt(max2);
    d->stats.position_error_rms = out->vertex_count ? sqrt(sum2 / out->vertex_count) : 0;
    d->stats.normal_error_max_deg = worst;
    return 0;
}

/* Replaces the attribute and index views built so far by one Draco stream; their
 * accessors stay (with the decoded counts) and name the Draco attributes. */
static int draco_pack(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    sl_draco_mesh in = {m->vertex_count, m->triangle_count, m->triangles, 0, {{0}}};
    const int types[] = {[GLTF_FLOAT - GLTF_BYTE] = SL_DRACO_F32,
                         [GLTF_UNSIGNED_BYTE - GLTF_BYTE] = SL_DRACO_U8,
                         [GLTF_UNSIGNED_SHORT - GLTF_BYTE] = SL_DRACO_U16};
    int view_of[GLB_MAX_ACCESSORS];
    for (int i = 0; i < d->accessor_count; i++) {
        glb_accessor *a = &d->accessors[i];
        view_of[i] = a->view;
        if (!a->semantic)
            continue;
        int sem = !strcmp(a->semantic, "POSITION") ? SL_DRACO_POSITION
                  : !strcmp(a->semantic, "NORMAL") ? SL_DRACO_NORMAL
                  : !strcmp(a->semantic, "COLOR_0") ? SL_DRACO_COLOR : SL_DRACO_TEXCOORD;
        int bits = sem == SL_DRACO_POSITION ? d->opt->position_bits
                   : sem == SL_DRACO_NORMAL ? d->opt->normal_bits : d->opt->texcoord_bits;
        draco_attribute(&in, sem, types[a->component - GLTF_BYTE], a->type[3] - '0',
                        a->normalized, bits, d->views[a->view].data);
    }
    void *bytes = NULL;
    size_t size = 0;
    int rc = sl_draco_encode(&in, DRACO_SPEED, &bytes, &size, err);
    sl_draco_mesh out = in;
    if (rc == 0)
        rc = sl_draco_decode(bytes, size, &out, err);
    if (rc) {
        free(bytes);
        return rc;
    }
    if (out.vertex_count == 0 || out.triangle_count == 0) {
        free(bytes), sl_draco_mesh_release(&out);
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "Draco decoded an empty mesh");
    }
    rc = draco_errors(d, m, &out, err);
    for (int i = 0, attr = 0; i < d->accessor_count; i++) {
        glb_accessor *a = &d->accessors[i];
        a->view = -1;
        if (!a->semantic) {
            a->count = 3 * out.triangle_count;
            a->component = out.vertex_count < 65536 ? GLTF_UNSIGNED_SHORT : GLTF_UNSIGNED_INT;
            continue;
        }
        a->count = out.vertex_count;
        a->draco_id = out.attributes[attr].unique_id;
        if (a->has_bounds) { /* POSITION, float: the decoded values' bounds */
            const float *p = out.attributes[attr].data;
            for (int k = 0; k < 3; k++)
                a->min[k] = a->max[k] = p[k];
            for (uint64_t v = 1; v < out.vertex_count; v++)
                for (int k = 0; k < 3; k++) {
                    a->min[k] = p[3 * v + k] < a->min[k] ? p[3 * v + k] : a->min[k];
                    a->max[k] = p[3 * v + k] > a->max[k] ? p[3 * v + k] : a->max[k];
                }
        }
        attr++;
    }
    d->stats.vertices = out.vertex_count;
    d->stats.triangles = out.triangle_count;
    if (rc == 0 && d->opt->morph_positions) { /* the morph target's base */
        d->decoded_positions = malloc(12 * out.vertex_count);
        if (d->decoded_positions)
            memcpy(d->decoded_positions, out.attributes[0].data, 12 * out.vertex_count);
        else
            rc = sl_error_nomem(err, NULL, "GLB: out of memory");
    }
    sl_draco_mesh_release(&out);
    /* The per-attribute views are not written: drop them, keep the image's. */
    for (int i = 0; i < d->accessor_count; i++)
        if (view_of[i] >= 0) {
            free(d->views[view_of[i]].data);
            d->views[view_of[i]].data = NULL;
        }
    int kept = 0;
    for (int i = 0; i < d->view_count; i++)
        if (d->views[i].data)
            d->views[kept++] = d->views[i];
    d->view_count = kept;
    d->image_view = d->image_view >= 0 ? 0 : -1; /* the images stay, in their order */
    d->fallback_view = d->fallback_view >= 0 ? 1 : -1;
    d->draco_view = d->view_count++;
    memset(&d->views[d->draco_view], 0, sizeof d->views[0]);
    d->views[d->draco_view].data = bytes;
    d->views[d->draco_view].size = size;
    return rc;
}

static int bits_ok(const sl_glb_options *o)
{
    return o->compression >= SL_GLB_UNCOMPRESSED && o->compression <= SL_GLB_DRACO &&
           o->position_bits >= 8 && o->position_bits <= 16 && o->normal_bits >= 4 &&
           o->normal_bits <= 16 && o->color_bits >= 8 && o->color_bits <= 16 &&
           o->texcoord_bits >= 8 && o->texcoord_bits <= 16;
}

int glb_doc_build(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    const sl_glb_options *o = d->opt;
    d->image_view = d->fallback_view = d->draco_view = -1;
    d->stats.vertices = m->vertex_count;
    d->stats.triangles = m->triangle_count;
    if (!bits_ok(o))
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "GLB options out of range");
    /* Draco quantises floats itself: it is given float positions and normals. */
    int quantize = o->quantize && o->compression != SL_GLB_DRACO;
    int rc = quantize ? quantized_positions(d, m, err) : float_positions(d, m, err);
    if (rc == 0 && m->normals)
        rc = quantize ? quantized_normals(d, m, err) : float_normals(d, m, err);
    if (rc == 0 && m->colors)
        rc = colors(d, m, err);
    /* Texture coordinates without a texture would be an unused attribute. */
    int textured = o->image && o->image_size && m->texcoords;
    if (rc == 0 && textured)
        rc = texcoords(d, m, quantize, err);
    if (rc == 0)
        rc = indices(d, m, err);
    if (rc == 0 && textured)
        rc = image(d, err);
    if (rc == 0 && o->morph_positions && o->compression != SL_GLB_DRACO)
        rc = glb_morph_target(d, m, err);
    if (rc == 0 && o->compression == SL_GLB_MESHOPT)
        rc = meshopt_pack(d, m, err);
    if (rc == 0 && o->compression == SL_GLB_DRACO) {
        double extent = 0;
        float lo[3], hi[3];
        bounds(m, lo, hi);
        for (int k = 0; k < 3; k++)
            extent = (double)hi[k] - lo[k] > extent ? (double)hi[k] - lo[k] : extent;
        d->stats.position_step = extent / ((1u << o->position_bits) - 1);
        d->stats.position_bound = sqrt(3.0) / 2 * d->stats.position_step;
        rc = draco_pack(d, m, err);
        if (rc == 0 && o->morph_positions)
            rc = glb_morph_target(d, m, err);
    }
    return rc;
}

void glb_doc_release(glb_doc *d)
{
    for (int i = 0; i < d->view_count; i++) {
        free(d->views[i].data);
        free(d->views[i].packed);
    }
    d->view_count = 0;
    free(d->decoded_positions);
    d->decoded_positions = NULL;
}
