/* The bytes behind glTF accessors (gltf_internal.h): buffers loaded on first use (the GLB's
 * BIN chunk, a base64 data: URI, or a file beside the .gltf, mapped), meshopt-compressed
 * bufferViews decoded by meshoptimizer, and accessors read as floats or indices with
 * every element checked to lie inside its view first.
 *
 * meshoptimizer: Debian 12 ships 0.18, whose decoders read the vertex codec version 0 and
 * the index codecs EXT_meshopt_compression specifies, with the OCTAHEDRAL, QUATERNION and
 * EXPONENTIAL filters. KHR_meshopt_compression adds the vertex codec version 1 and the
 * COLOR filter, which 0.18 cannot decode: such a stream is refused as unsupported (or its
 * uncompressed fallback read, when the file has one). The decoders assert their
 * preconditions (stride, count) rather than refuse them, so those are checked here first.
 * A stream may claim at most 64 decoded bytes per compressed byte (no codec packs
 * tighter) before anything is allocated.
 */
#include <math.h>
#include <meshoptimizer.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "core/io.h"
#include "formats/gltf_internal.h"

#define MESHOPT_MAX_RATIO 64

/* ---- URIs ---- */

int gltf_is_data_uri(const gltf_doc *g, uint32_t uri)
{
    const sl_jdoc_token *t = &g->j.tokens[uri];
    return t->length >= 5 && !memcmp(g->j.text + t->start, "data:", 5);
}

static int base64_value(unsigned char c)
{
    return c >= 'A' && c <= 'Z' ? c - 'A' : c >= 'a' && c <= 'z' ? c - 'a' + 26
           : c >= '0' && c <= '9' ? c - '0' + 52 : c == '+' ? 62 : c == '/' ? 63 : -1;
}

/* Base64 text [p, end) into out (room for 3/4 of it); the bytes written, or -1. */
static long base64_decode(const char *p, const char *end, unsigned char *out)
{
    uint32_t acc = 0;
    int bits = 0;
    long n = 0;
    for (; p < end && *p != '='; p++) {
        int v = base64_value((unsigned char)*p);
        if (v < 0)
            return -1;
        acc = acc << 6 | (uint32_t)v;
        if ((bits += 6) >= 8) {
            bits -= 8;
            out[n++] = (unsigned char)(acc >> bits);
        }
    }
    while (p < end && *p == '=')
        p++;
    return p == end ? n : -1;
}

int gltf_data_uri(const gltf_doc *g, uint32_t uri, unsigned char **out, uint64_t *size,
                  char *mime, size_t mime_size, const char *where)
{
    *out = NULL;
    const sl_jdoc_token *t = &g->j.tokens[uri];
    char *text = malloc((size_t)t->length + 1);
    if (!text)
        return sl_error_nomem(g->s->err, g->s->name, "out of memory for %s", where);
    sl_jdoc_string(&g->j, uri, text, (size_t)t->length + 1);
    char *comma = strchr(text, ','), *semi = strchr(text, ';');
    if (!comma || !semi || semi > comma || strncmp(semi, ";base64,", 8)) {
        free(text);
        return gltf_error(g, SL_E_UNSUPPORTED, "%s: a data: URI that is not base64", where);
    }
    snprintf(mime, mime_size, "%.*s", (int)(semi - text - 5), text + 5);
    *out = malloc(strlen(comma + 1) / 4 * 3 + 3);
    long n = *out ? base64_decode(comma + 1, comma + 1 + strlen(comma + 1), *out) : 0;
    free(text);
    if (!*out)
        return sl_error_nomem(g->s->err, g->s->name, "out of memory for %s", where);
    if (n < 0) {
        free(*out), *out = NULL;
        return gltf_error(g, SL_E_BADINPUT, "%s: the data: URI is not valid base64", where);
    }
    *size = (uint64_t)n;
    return 0;
}

static int hex_digit(char c)
{
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10
           : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

void gltf_uri_name(const gltf_doc *g, uint32_t uri, char *out, size_t size)
{
    char raw[1024];
    sl_jdoc_string(&g->j, uri, raw, sizeof raw);
    size_t n = 0;
    for (const char *p = raw; *p && n + 1 < size; p++) { /* %XX escapes (RFC 3986) */
        int hi = p[0] == '%' ? hex_digit(p[1]) : -1, lo = hi >= 0 ? hex_digit(p[2]) : -1;
        if (lo >= 0 && (hi || lo)) {
            out[n++] = (char)(hi * 16 + lo);
            p += 2;
        } else {
            out[n++] = *p;
        }
    }
    out[n] = 0;
}

/* ---- buffers ---- */

static int load_external(gltf_doc *g, uint32_t i, gltf_buffer *b)
{
    char name[1024];
    gltf_uri_name(g, b->uri, name, sizeof name);
    sl_error e;
    sl_error_init(&e);
    if (scan_sibling_map(g->s, name, &b->map, &b->map_size, &e)) {
        char msg[1400];
        return gltf_error(g, e.code == SL_E_NOMEM ? SL_E_NOMEM : SL_E_BADINPUT,
                          "buffers[%u] '%s': %s", i, name,
                          e.message[0] ? e.message : sl_error_format(&e, msg, sizeof msg));
    }
    b->data = b->map ? b->map : (const unsigned char *)""; /* an empty file maps nothing */
    if (b->map_size < b->byte_length)
        return gltf_error(g, SL_E_BADINPUT, "buffers[%u] '%s' holds %zu bytes, declares %llu",
                          i, name, b->map_size, (unsigned long long)b->byte_length);
    return 0;
}

static int load_buffer(gltf_doc *g, uint32_t i)
{
    gltf_buffer *b = &g->buffers[i];
    char where[40], mime[64];
    uint64_t size = 0;
    int rc;
    if (b->loaded)
        return 0;
    snprintf(where, sizeof where, "buffers[%u]", i);
    if (b->fallback)
        return gltf_error(g, SL_E_BADINPUT, "%s is a meshopt fallback and holds no data", where);
    if (!b->uri) {
        if (!g->glb || i != 0 || !g->bin || g->bin_size < b->byte_length)
            return gltf_error(g, SL_E_BADINPUT, "%s has no uri and no GLB BIN chunk of %llu "
                              "bytes to stand for it", where, (unsigned long long)b->byte_length);
        b->data = g->bin;
    } else if (gltf_is_data_uri(g, b->uri)) {
        if ((rc = gltf_data_uri(g, b->uri, &b->owned, &size, mime, sizeof mime, where)))
            return rc;
        if (size < b->byte_length)
            return gltf_error(g, SL_E_BADINPUT, "%s: the data: URI holds %llu bytes, declares "
                              "%llu", where, (unsigned long long)size,
                              (unsigned long long)b->byte_length);
        b->data = b->owned;
    } else if ((rc = load_external(g, i, b))) {
        return rc;
    }
    b->loaded = 1;
    return 0;
}

/* ---- meshopt ---- */

static int meshopt_checks(const gltf_doc *g, uint32_t v, const gltf_meshopt *mo)
{
    uint32_t s = mo->stride;
    int ok = mo->mode == MESHOPT_ATTRIBUTES ? s % 4 == 0 && s <= 256 &&
                 (mo->filter != MESHOPT_OCTAHEDRAL || s == 4 || s == 8) &&
                 (mo->filter != MESHOPT_QUATERNION || s == 8)
             : mo->mode == MESHOPT_TRIANGLES ? (s == 2 || s == 4) && mo->count % 3 == 0
                                             : s == 2 || s == 4;
    if (!ok)
        return gltf_error(g, SL_E_BADINPUT, "bufferViews[%u]: %s byteStride %u or count %llu "
                          "do not fit its mode", v, mo->extension, s,
                          (unsigned long long)mo->count);
    if (mo->filter == MESHOPT_COLOR)
        return gltf_error(g, SL_E_UNSUPPORTED, "bufferViews[%u]: the %s COLOR filter needs "
                          "meshoptimizer 0.25 or later; Debian 12 has 0.18", v, mo->extension);
    return 0;
}

static int meshopt_run(const gltf_meshopt *mo, unsigned char *dst, const unsigned char *src)
{
    if (mo->mode == MESHOPT_TRIANGLES)
        return meshopt_decodeIndexBuffer(dst, mo->count, mo->stride, src, mo->length);
    if (mo->mode == MESHOPT_INDICES)
        return meshopt_decodeIndexSequence(dst, mo->count, mo->stride, src, mo->length);
    int rc = meshopt_decodeVertexBuffer(dst, mo->count, mo->stride, src, mo->length);
    if (rc == 0 && mo->filter == MESHOPT_OCTAHEDRAL)
        meshopt_decodeFilterOct(dst, mo->count, mo->stride);
    else if (rc == 0 && mo->filter == MESHOPT_QUATERNION)
        meshopt_decodeFilterQuat(dst, mo->count, mo->stride);
    else if (rc == 0 && mo->filter == MESHOPT_EXPONENTIAL)
        meshopt_decodeFilterExp(dst, mo->count, mo->stride);
    return rc;
}

/* Why a stream did not decode, in the words of its header byte. */
static int meshopt_failed(const gltf_doc *g, uint32_t v, const gltf_meshopt *mo,
                          const unsigned char *src)
{
    unsigned header = mo->length ? src[0] : 0, version = header & 0x0f;
    if (mo->mode == MESHOPT_ATTRIBUTES && (header & 0xf0) == 0xa0 && version > 0)
        return gltf_error(g, SL_E_UNSUPPORTED, "bufferViews[%u]: %s vertex codec version %u "
                          "needs meshoptimizer 0.23 or later; Debian 12 has 0.18, which decodes "
                          "version 0", v, mo->extension, version);
    return gltf_error(g, SL_E_BADINPUT, "bufferViews[%u]: the %s stream does not decode", v,
                      mo->extension);
}

static int meshopt_decode(gltf_doc *g, uint32_t v)
{
    gltf_view *view = &g->views[v];
    const gltf_meshopt *mo = &view->mo;
    uint64_t bytes;
    int rc = meshopt_checks(g, v, mo);
    if (rc)
        return rc;
    if (__builtin_mul_overflow(mo->count, (uint64_t)mo->stride, &bytes) || bytes > view->length ||
        bytes / MESHOPT_MAX_RATIO > mo->length + 64)
        return gltf_error(g, SL_E_BADINPUT, "bufferViews[%u]: %llu x %u decoded bytes from a "
                          "%llu-byte %s stream for a %llu-byte view", v,
                          (unsigned long long)mo->count, mo->stride,
                          (unsigned long long)mo->length, mo->extension,
                          (unsigned long long)view->length);
    if ((rc = load_buffer(g, mo->buffer)))
        return rc;
    const unsigned char *src = g->buffers[mo->buffer].data + mo->offset;
    if (!(view->decoded = calloc(1, view->length)))
        return sl_error_nomem(g->s->err, g->s->name, "out of memory for bufferViews[%u]", v);
    if (meshopt_run(mo, view->decoded, src) == 0)
        return 0;
    free(view->decoded);
    view->decoded = NULL;
    gltf_buffer *plain = &g->buffers[view->buffer];
    if (!plain->fallback && (plain->uri || (g->glb && view->buffer == 0 && g->bin))) {
        gltf_warn(g, "bufferViews[%u]: the %s stream does not decode here; its uncompressed "
                  "fallback is read", v, mo->extension);
        view->meshopt = 0;
        return 0;
    }
    return meshopt_failed(g, v, mo, src);
}

int gltf_view_bytes(gltf_doc *g, uint32_t v, const unsigned char **data, uint64_t *size)
{
    gltf_view *view = &g->views[v];
    int rc = 0;
    if (view->meshopt && !view->decoded && (rc = meshopt_decode(g, v)))
        return rc;
    if (view->meshopt) {
        *data = view->decoded;
    } else {
        if ((rc = load_buffer(g, view->buffer)))
            return rc;
        *data = g->buffers[view->buffer].data + view->offset;
    }
    *size = view->length;
    return 0;
}

/* ---- accessors ---- */

static double component_value(const unsigned char *p, uint32_t component, int normalized)
{
    switch (component) {
    case GLTF_BYTE: {
        double v = (int8_t)p[0];
        return normalized ? fmax(v / 127.0, -1.0) : v;
    }
    case GLTF_UNSIGNED_BYTE:
        return normalized ? p[0] / 255.0 : p[0];
    case GLTF_SHORT: {
        double v = (int16_t)(uint16_t)(p[0] | p[1] << 8);
        return normalized ? fmax(v / 32767.0, -1.0) : v;
    }
    case GLTF_UNSIGNED_SHORT: {
        double v = (uint16_t)(p[0] | p[1] << 8);
        return normalized ? v / 65535.0 : v;
    }
    case GLTF_UNSIGNED_INT:
        return sl_get_u32(p);
    default:
        return sl_get_f32(p);
    }
}

void gltf_convert(const unsigned char *src, uint32_t component, int normalized, int components,
                  uint64_t stride, uint64_t count, int want, float *out)
{
    int size = gltf_component_size(component);
    for (uint64_t i = 0; i < count; i++)
        for (int k = 0; k < want; k++)
            out[i * want + k] = k < components
                ? (float)component_value(src + i * stride + (uint64_t)k * size, component,
                                         normalized)
                : 0.0f;
}

/* The elements of accessor a: *base, their stride and size, all inside its view. */
static int accessor_bytes(gltf_doc *g, uint32_t ai, const unsigned char **base,
                          uint64_t *stride, const char *what)
{
    const gltf_accessor *a = &g->accessors[ai];
    const unsigned char *data;
    uint64_t size, elem = (uint64_t)gltf_component_size(a->component) * a->components, end;
    int rc = gltf_view_bytes(g, a->view, &data, &size);
    if (rc)
        return rc;
    *stride = g->views[a->view].stride ? g->views[a->view].stride : elem;
    if (__builtin_mul_overflow(*stride, a->count - 1, &end) ||
        __builtin_add_overflow(end, a->offset + elem, &end) || a->offset > size || end > size)
        return gltf_error(g, SL_E_BADINPUT, "%s: accessors[%u] (%llu x %llu bytes from %llu) "
                          "runs past bufferViews[%u] (%llu bytes)", what, ai,
                          (unsigned long long)a->count, (unsigned long long)elem,
                          (unsigned long long)a->offset, a->view, (unsigned long long)size);
    *base = data + a->offset;
    return 0;
}

/* A tightly packed array of `count` elements of `elem` bytes at `offset` in view v. */
static int packed_bytes(gltf_doc *g, uint32_t v, uint64_t offset, uint64_t count, uint64_t elem,
                        const unsigned char **base, const char *what)
{
    const unsigned char *data;
    uint64_t size, need;
    int rc = gltf_view_bytes(g, v, &data, &size);
    if (!rc && (__builtin_mul_overflow(count, elem, &need) || offset > size || need > size - offset))
        rc = gltf_error(g, SL_E_BADINPUT, "%s: sparse data runs past bufferViews[%u]", what, v);
    *base = rc ? NULL : data + offset;
    return rc;
}

static uint32_t index_value(const unsigned char *p, uint32_t component)
{
    return component == GLTF_UNSIGNED_BYTE ? p[0] : component == GLTF_UNSIGNED_SHORT
           ? (uint32_t)(p[0] | p[1] << 8) : sl_get_u32(p);
}

static int apply_sparse(gltf_doc *g, uint32_t ai, int want, float *out, const char *what)
{
    const gltf_accessor *a = &g->accessors[ai];
    const gltf_sparse *sp = &a->sparse;
    const unsigned char *idx, *val;
    uint64_t isize = (uint64_t)gltf_component_size(sp->index_component);
    uint64_t elem = (uint64_t)gltf_component_size(a->component) * a->components;
    int rc;
    if (sp->count > a->count)
        return gltf_error(g, SL_E_BADINPUT, "%s: accessors[%u] has more sparse values than "
                          "elements", what, ai);
    if ((rc = packed_bytes(g, sp->index_view, sp->index_offset, sp->count, isize, &idx, what)) ||
        (rc = packed_bytes(g, sp->value_view, sp->value_offset, sp->count, elem, &val, what)))
        return rc;
    for (uint64_t i = 0; i < sp->count; i++) {
        uint32_t at = index_value(idx + i * isize, sp->index_component);
        if (at >= a->count)
            return gltf_error(g, SL_E_BADINPUT, "%s: accessors[%u] sparse index %u out of range",
                              what, ai, at);
        gltf_convert(val + i * elem, a->component, a->normalized, a->components, elem, 1, want,
                     out + (uint64_t)at * want);
    }
    return 0;
}

int gltf_check_accessor(gltf_doc *g, uint32_t ai, const char *what)
{
    const gltf_accessor *a = &g->accessors[ai];
    const unsigned char *base;
    uint64_t stride;
    if (a->components < 1)
        return gltf_error(g, SL_E_BADINPUT, "%s: accessors[%u] is a matrix", what, ai);
    if (a->view != GLTF_NONE)
        return accessor_bytes(g, ai, &base, &stride, what);
    /* All zeros (and sparse values): only what a file this size could mean. */
    if (a->count > g->s->size)
        return gltf_error(g, SL_E_BADINPUT, "%s: accessors[%u] has no bufferView and %llu "
                          "elements, more than the file's %zu bytes", what, ai,
                          (unsigned long long)a->count, g->s->size);
    return 0;
}

int gltf_read_floats(gltf_doc *g, uint32_t ai, int want, float *out, const char *what)
{
    const gltf_accessor *a = &g->accessors[ai];
    const unsigned char *base;
    uint64_t stride;
    int rc;
    if (a->components < 1)
        return gltf_error(g, SL_E_BADINPUT, "%s: accessors[%u] is a matrix", what, ai);
    if (a->view == GLTF_NONE)
        memset(out, 0, a->count * (uint64_t)want * sizeof *out);
    else if ((rc = accessor_bytes(g, ai, &base, &stride, what)))
        return rc;
    else
        gltf_convert(base, a->component, a->normalized, a->components, stride, a->count, want,
                     out);
    return a->sparse.count ? apply_sparse(g, ai, want, out, what) : 0;
}

int gltf_read_indices(gltf_doc *g, uint32_t ai, uint64_t vertices, uint32_t *out)
{
    const gltf_accessor *a = &g->accessors[ai];
    const unsigned char *base;
    uint64_t stride;
    int rc;
    if (a->components != 1 || a->normalized || a->sparse.count || a->view == GLTF_NONE ||
        (a->component != GLTF_UNSIGNED_BYTE && a->component != GLTF_UNSIGNED_SHORT &&
         a->component != GLTF_UNSIGNED_INT))
        return gltf_error(g, SL_E_BADINPUT, "indices: accessors[%u] is not a plain SCALAR of "
                          "unsigned integers", ai);
    if ((rc = accessor_bytes(g, ai, &base, &stride, "indices")))
        return rc;
    for (uint64_t i = 0; i < a->count; i++) {
        out[i] = index_value(base + i * stride, a->component);
        if (out[i] >= vertices)
            return gltf_error(g, SL_E_BADINPUT, "indices: accessors[%u] element %llu is vertex "
                              "%u of %llu", ai, (unsigned long long)i, out[i],
                              (unsigned long long)vertices);
    }
    return 0;
}
