/* A GLB reader for the tests, written from the specifications and not from the writer:
 * the container (glTF 2.0 section 4.4), a small JSON parser, accessors with any component
 * type, normalization and byteStride (KHR_mesh_quantization), EXT_meshopt_compression
 * streams through meshoptimizer's decoders (and its octahedral filter), and
 * KHR_draco_mesh_compression through the Draco shim's decoder. The result is what a viewer
 * draws: positions with the node's translation and scale applied (metres), unit normals,
 * linear RGBA colours and texture coordinates in doubles, and the indices.
 *
 * glb_decode() returns 0, or -1 with the reason in `why`. Header-only; test code only.
 */
#ifndef SCANLOD_TESTS_GLB_READER_H
#define SCANLOD_TESTS_GLB_READER_H

#include <math.h>
#include <meshoptimizer.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/atomicfile.h"
#include "shim/draco_shim.h"

/* ---- JSON ---- */

enum { JV_NULL, JV_BOOL, JV_NUM, JV_STR, JV_ARR, JV_OBJ };

typedef struct jv {
    int type;
    double num;
    char *str;         /* JV_STR */
    int n;             /* items of JV_ARR / JV_OBJ */
    struct jv *items;
    char **keys;       /* JV_OBJ */
} jv;

static const jv jv_none_ = {JV_NULL, 0, NULL, 0, NULL, NULL};

typedef struct jparse {
    const char *p, *end;
    int failed;
} jparse;

static void jp_ws(jparse *j)
{
    while (j->p < j->end && strchr(" \t\r\n", *j->p) && *j->p)
        j->p++;
}

static char *jp_string(jparse *j)
{
    if (j->p >= j->end || *j->p != '"') {
        j->failed = 1;
        return NULL;
    }
    const char *s = ++j->p;
    while (j->p < j->end && *j->p != '"')
        j->p += *j->p == '\\' ? 2 : 1; /* escapes kept as written: the tests use none */
    if (j->p >= j->end) {
        j->failed = 1;
        return NULL;
    }
    char *out = malloc((size_t)(j->p - s) + 1);
    memcpy(out, s, (size_t)(j->p - s));
    out[j->p - s] = 0;
    j->p++;
    return out;
}

static void jp_value(jparse *j, jv *v, int depth)
{
    memset(v, 0, sizeof *v);
    jp_ws(j);
    if (j->p >= j->end || depth > 64) {
        j->failed = 1;
        return;
    }
    char c = *j->p;
    if (c == '{' || c == '[') {
        v->type = c == '{' ? JV_OBJ : JV_ARR;
        j->p++;
        int cap = 0;
        for (;;) {
            jp_ws(j);
            if (j->p < j->end && *j->p == (c == '{' ? '}' : ']')) {
                j->p++;
                return;
            }
            if (v->n && (j->p >= j->end || *j->p++ != ',')) {
                j->failed = 1;
                return;
            }
            if (v->n == cap) {
                cap = cap ? 2 * cap : 8;
                v->items = realloc(v->items, (size_t)cap * sizeof *v->items);
                if (c == '{')
                    v->keys = realloc(v->keys, (size_t)cap * sizeof *v->keys);
            }
            if (c == '{') {
                jp_ws(j);
                v->keys[v->n] = jp_string(j);
                jp_ws(j);
                if (j->failed || j->p >= j->end || *j->p++ != ':') {
                    j->failed = 1;
                    return;
                }
            }
            jp_value(j, &v->items[v->n++], depth + 1);
            if (j->failed)
                return;
        }
    }
    if (c == '"') {
        v->type = JV_STR;
        v->str = jp_string(j);
        return;
    }
    if (!strncmp(j->p, "true", 4) || !strncmp(j->p, "false", 5)) {
        v->type = JV_BOOL;
        v->num = *j->p == 't';
        j->p += *j->p == 't' ? 4 : 5;
        return;
    }
    if (!strncmp(j->p, "null", 4)) {
        j->p += 4;
        return;
    }
    char *after;
    v->type = JV_NUM;
    v->num = strtod(j->p, &after);
    if (after == j->p)
        j->failed = 1;
    j->p = after;
}

static void jv_free(jv *v)
{
    for (int i = 0; i < v->n; i++) {
        jv_free(&v->items[i]);
        if (v->keys)
            free(v->keys[i]);
    }
    free(v->items);
    free(v->keys);
    free(v->str);
}

static const jv *jv_get(const jv *o, const char *key)
{
    for (int i = 0; o && o->type == JV_OBJ && i < o->n; i++)
        if (o->keys[i] && !strcmp(o->keys[i], key))
            return &o->items[i];
    return &jv_none_;
}

static const jv *jv_at(const jv *a, int i)
{
    return a && a->type == JV_ARR && i >= 0 && i < a->n ? &a->items[i] : &jv_none_;
}

static double jv_num(const jv *v, double otherwise)
{
    return v->type == JV_NUM || v->type == JV_BOOL ? v->num : otherwise;
}

/* ---- the decoded mesh ---- */

typedef struct glb_decoded {
    uint64_t vertex_count, triangle_count;
    double *positions;   /* 3 per vertex, node transform applied */
    double *normals;     /* 3 per vertex or NULL */
    double *colors;      /* 4 per vertex, linear, or NULL */
    double *texcoords;   /* 2 per vertex (glTF convention) or NULL */
    double *morph;       /* targets[0].POSITION: 3 per vertex, metres (node scale applied),
                            or NULL */
    uint32_t *triangles;
    int compression;     /* 0 none, 1 meshopt, 2 draco */
    int quantized;       /* KHR_mesh_quantization in extensionsRequired */
    int index_header;    /* meshopt: first byte of the TRIANGLES stream, else -1 */
    int vertex_header;   /* meshopt: first byte of the POSITION stream, else -1 */
    uint64_t image_size; /* embedded image bytes (0: none) */
    const unsigned char *image;
    char mime[32];
    char *file;          /* the whole file */
    size_t file_size;
    jv json;
} glb_decoded;

static int glb_fail_(char *why, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, n, fmt, ap);
    va_end(ap);
    return -1;
}

static uint32_t glb_le32_(const void *p)
{
    const unsigned char *b = p;
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static int glb_has_(const jv *list, const char *name)
{
    for (int i = 0; i < list->n; i++)
        if (list->items[i].type == JV_STR && !strcmp(list->items[i].str, name))
            return 1;
    return 0;
}

/* The decoded bytes of bufferView `view` (malloc'd), its stride and size. */
static unsigned char *glb_view_bytes_(glb_decoded *g, const unsigned char *bin, uint64_t bin_size,
                                      int view, uint64_t *stride, uint64_t *size, char *why,
                                      size_t n)
{
    const jv *bv = jv_at(jv_get(&g->json, "bufferViews"), view);
    const jv *ext = jv_get(jv_get(bv, "extensions"), "EXT_meshopt_compression");
    uint64_t length = (uint64_t)jv_num(jv_get(bv, "byteLength"), 0);
    *stride = (uint64_t)jv_num(jv_get(bv, "byteStride"), 0);
    *size = length;
    unsigned char *out = malloc(length ? length : 1);
    if (ext->type == JV_OBJ) {
        uint64_t off = (uint64_t)jv_num(jv_get(ext, "byteOffset"), 0);
        uint64_t len = (uint64_t)jv_num(jv_get(ext, "byteLength"), 0);
        uint64_t count = (uint64_t)jv_num(jv_get(ext, "count"), 0);
        uint64_t es = (uint64_t)jv_num(jv_get(ext, "byteStride"), 0);
        const char *mode = jv_get(ext, "mode")->str, *filter = jv_get(ext, "filter")->str;
        if (jv_num(jv_get(ext, "buffer"), -1) != 0 || off + len > bin_size || !mode ||
            count * es != length) {
            free(out);
            glb_fail_(why, n, "bufferView %d: bad EXT_meshopt_compression fields", view);
            return NULL;
        }
        int rc;
        if (!strcmp(mode, "TRIANGLES")) {
            g->index_header = len ? bin[off] : -1;
            rc = meshopt_decodeIndexBuffer(out, count, es, bin + off, len);
        } else {
            if (g->vertex_header < 0)
                g->vertex_header = len ? bin[off] : -1;
            rc = meshopt_decodeVertexBuffer(out, count, es, bin + off, len);
        }
        if (rc == 0 && filter && !strcmp(filter, "OCTAHEDRAL"))
            meshopt_decodeFilterOct(out, count, es);
        else if (rc == 0 && filter && strcmp(filter, "NONE"))
            rc = -99;
        if (rc) {
            free(out);
            glb_fail_(why, n, "bufferView %d: meshopt decoder returned %d", view, rc);
            return NULL;
        }
        *stride = es;
        return out;
    }
    uint64_t off = (uint64_t)jv_num(jv_get(bv, "byteOffset"), 0);
    if (jv_num(jv_get(bv, "buffer"), -1) != 0 || off + length > bin_size) {
        free(out);
        glb_fail_(why, n, "bufferView %d outside the BIN chunk", view);
        return NULL;
    }
    memcpy(out, bin + off, length);
    return out;
}

/* One component as a double: normalized integers per glTF 2.0 section 3.11. */
static double glb_component_(const unsigned char *p, int type, int normalized)
{
    switch (type) {
    case 5120: return normalized ? fmax((int8_t)p[0] / 127.0, -1) : (int8_t)p[0];
    case 5121: return normalized ? p[0] / 255.0 : p[0];
    case 5122: {
        int16_t v = (int16_t)(p[0] | p[1] << 8);
        return normalized ? fmax(v / 32767.0, -1) : v;
    }
    case 5123: {
        uint16_t v = (uint16_t)(p[0] | p[1] << 8);
        return normalized ? v / 65535.0 : v;
    }
    case 5125: return glb_le32_(p);
    default: {
        float f;
        memcpy(&f, p, 4);
        return f;
    }
    }
}

static int glb_component_size_(int type)
{
    return type == 5120 || type == 5121 ? 1 : type == 5122 || type == 5123 ? 2 : 4;
}

/* Accessor `index` (not Draco) as doubles: count x components. */
static double *glb_accessor_(glb_decoded *g, const unsigned char *bin, uint64_t bin_size,
                             int index, int components, uint64_t *count, char *why, size_t n)
{
    const jv *a = jv_at(jv_get(&g->json, "accessors"), index);
    int type = (int)jv_num(jv_get(a, "componentType"), 0);
    int normalized = jv_num(jv_get(a, "normalized"), 0) != 0;
    *count = (uint64_t)jv_num(jv_get(a, "count"), 0);
    uint64_t stride, size, cs = (uint64_t)glb_component_size_(type);
    unsigned char *bytes = glb_view_bytes_(g, bin, bin_size, (int)jv_num(jv_get(a, "bufferView"), -1),
                                           &stride, &size, why, n);
    if (!bytes)
        return NULL;
    stride = stride ? stride : cs * (uint64_t)components;
    uint64_t offset = (uint64_t)jv_num(jv_get(a, "byteOffset"), 0);
    if (*count == 0 || offset + (*count - 1) * stride + cs * components > size) {
        free(bytes);
        glb_fail_(why, n, "accessor %d does not fit its bufferView", index);
        return NULL;
    }
    double *out = malloc(*count * (uint64_t)components * sizeof *out);
    for (uint64_t i = 0; i < *count; i++)
        for (int k = 0; k < components; k++)
            out[i * components + k] =
                glb_component_(bytes + offset + i * stride + k * cs, type, normalized);
    free(bytes);
    return out;
}

static int glb_draco_(glb_decoded *g, const unsigned char *bin, uint64_t bin_size,
                      const jv *prim, const jv *ext, char *why, size_t n)
{
    static const char *const sem[4] = {"POSITION", "NORMAL", "COLOR_0", "TEXCOORD_0"};
    static const int comps[4] = {3, 3, 4, 2};
    const jv *bv = jv_at(jv_get(&g->json, "bufferViews"), (int)jv_num(jv_get(ext, "bufferView"), -1));
    uint64_t off = (uint64_t)jv_num(jv_get(bv, "byteOffset"), 0);
    uint64_t len = (uint64_t)jv_num(jv_get(bv, "byteLength"), 0);
    if (off + len > bin_size)
        return glb_fail_(why, n, "Draco bufferView outside the BIN chunk");
    sl_draco_mesh dm;
    memset(&dm, 0, sizeof dm);
    int slot[4];
    for (int s = 0; s < 4; s++) {
        const jv *id = jv_get(jv_get(ext, "attributes"), sem[s]);
        slot[s] = -1;
        if (id->type != JV_NUM)
            continue;
        const jv *acc = jv_at(jv_get(&g->json, "accessors"),
                              (int)jv_num(jv_get(jv_get(prim, "attributes"), sem[s]), -1));
        int ct = (int)jv_num(jv_get(acc, "componentType"), 0);
        sl_draco_attribute *a = &dm.attributes[dm.attribute_count];
        a->unique_id = (int)id->num;
        a->type = ct == 5126 ? SL_DRACO_F32 : ct == 5121 ? SL_DRACO_U8 : SL_DRACO_U16;
        a->components = comps[s];
        slot[s] = dm.attribute_count++;
    }
    sl_error err;
    sl_error_init(&err);
    if (sl_draco_decode(bin + off, len, &dm, &err))
        return glb_fail_(why, n, "Draco: %s", err.message);
    for (int s = 0; s < 4; s++) {
        const jv *acc = jv_at(jv_get(&g->json, "accessors"),
                              (int)jv_num(jv_get(jv_get(prim, "attributes"), sem[s]), -1));
        if (slot[s] >= 0 && jv_num(jv_get(acc, "count"), 0) != (double)dm.vertex_count) {
            sl_draco_mesh_release(&dm);
            return glb_fail_(why, n, "%s accessor count is not the decoded vertex count", sem[s]);
        }
    }
    const jv *ia = jv_at(jv_get(&g->json, "accessors"), (int)jv_num(jv_get(prim, "indices"), -1));
    if (jv_num(jv_get(ia, "count"), 0) != 3.0 * dm.triangle_count) {
        sl_draco_mesh_release(&dm);
        return glb_fail_(why, n, "indices accessor count is not 3 x the decoded triangles");
    }
    g->vertex_count = dm.vertex_count;
    g->triangle_count = dm.triangle_count;
    g->triangles = malloc(12 * dm.triangle_count + 12);
    memcpy(g->triangles, dm.triangles, 12 * dm.triangle_count);
    double **dst[4] = {&g->positions, &g->normals, &g->colors, &g->texcoords};
    for (int s = 0; s < 4; s++) {
        if (slot[s] < 0)
            continue;
        const sl_draco_attribute *a = &dm.attributes[slot[s]];
        double *out = malloc(dm.vertex_count * comps[s] * sizeof *out + 8);
        for (uint64_t i = 0; i < dm.vertex_count * comps[s]; i++)
            out[i] = a->type == SL_DRACO_F32 ? ((float *)a->data)[i]
                     : a->type == SL_DRACO_U8 ? ((uint8_t *)a->data)[i] / 255.0
                                              : ((uint16_t *)a->data)[i] / 65535.0;
        *dst[s] = out;
    }
    sl_draco_mesh_release(&dm);
    return 0;
}

static void glb_decoded_free(glb_decoded *g)
{
    free(g->positions), free(g->normals), free(g->colors), free(g->texcoords), free(g->morph);
    free(g->triangles), free(g->file);
    jv_free(&g->json);
    memset(g, 0, sizeof *g);
}

static int glb_decode(const char *path, glb_decoded *g, char *why, size_t n)
{
    memset(g, 0, sizeof *g);
    g->index_header = g->vertex_header = -1;
    sl_error err;
    sl_error_init(&err);
    if (sl_read_file(path, 1u << 30, &g->file, &g->file_size, &err))
        return glb_fail_(why, n, "%s: %s", path, err.message);
    const unsigned char *d = (const unsigned char *)g->file;
    if (g->file_size < 28 || memcmp(d, "glTF", 4) || glb_le32_(d + 4) != 2 ||
        glb_le32_(d + 8) != g->file_size)
        return glb_fail_(why, n, "not a GLB 2 file of its stated length");
    uint32_t json_length = glb_le32_(d + 12);
    if (memcmp(d + 16, "JSON", 4) || 28ull + json_length > g->file_size)
        return glb_fail_(why, n, "bad JSON chunk");
    jparse jp = {(const char *)d + 20, (const char *)d + 20 + json_length, 0};
    jp_value(&jp, &g->json, 0);
    if (jp.failed)
        return glb_fail_(why, n, "the JSON chunk does not parse");
    const unsigned char *bin = d + 28 + json_length;
    uint64_t bin_size = glb_le32_(d + 20 + json_length);
    if (memcmp(d + 24 + json_length, "BIN", 4) || 28ull + json_length + bin_size > g->file_size)
        return glb_fail_(why, n, "bad BIN chunk");
    const jv *req = jv_get(&g->json, "extensionsRequired");
    g->quantized = glb_has_(req, "KHR_mesh_quantization");
    g->compression = glb_has_(req, "EXT_meshopt_compression") ? 1
                     : glb_has_(req, "KHR_draco_mesh_compression") ? 2 : 0;
    const jv *prim = jv_at(jv_get(jv_at(jv_get(&g->json, "meshes"), 0), "primitives"), 0);
    const jv *attrs = jv_get(prim, "attributes");
    const jv *draco = jv_get(jv_get(prim, "extensions"), "KHR_draco_mesh_compression");
    if (draco->type == JV_OBJ) {
        if (glb_draco_(g, bin, bin_size, prim, draco, why, n))
            return -1;
    } else {
        static const char *const sem[4] = {"POSITION", "NORMAL", "COLOR_0", "TEXCOORD_0"};
        static const int comps[4] = {3, 3, 4, 2};
        double **dst[4] = {&g->positions, &g->normals, &g->colors, &g->texcoords};
        for (int s = 0; s < 4; s++) {
            const jv *idx = jv_get(attrs, sem[s]);
            if (idx->type != JV_NUM)
                continue;
            uint64_t count;
            if (!(*dst[s] = glb_accessor_(g, bin, bin_size, (int)idx->num, comps[s], &count, why, n)))
                return -1;
            if (s == 0)
                g->vertex_count = count;
            else if (count != g->vertex_count)
                return glb_fail_(why, n, "%s has %llu elements, POSITION %llu", sem[s],
                                 (unsigned long long)count, (unsigned long long)g->vertex_count);
        }
        uint64_t count;
        double *idx = glb_accessor_(g, bin, bin_size, (int)jv_num(jv_get(prim, "indices"), -1), 1,
                                    &count, why, n);
        if (!idx)
            return -1;
        g->triangle_count = count / 3;
        g->triangles = malloc(4 * count + 4);
        for (uint64_t i = 0; i < count; i++)
            g->triangles[i] = (uint32_t)idx[i];
        free(idx);
    }
    if (!g->positions)
        return glb_fail_(why, n, "no POSITION");
    for (uint64_t i = 0; i < 3 * g->triangle_count; i++)
        if (g->triangles[i] >= g->vertex_count)
            return glb_fail_(why, n, "index %u out of range", g->triangles[i]);
    /* POSITION's min/max must be the decoded data's (the validator cannot check that in
     * compressed files). */
    const jv *pa = jv_at(jv_get(&g->json, "accessors"), (int)jv_num(jv_get(attrs, "POSITION"), -1));
    for (int k = 0; k < 3; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (uint64_t i = 0; i < g->vertex_count; i++) {
            lo = fmin(lo, g->positions[3 * i + k]);
            hi = fmax(hi, g->positions[3 * i + k]);
        }
        /* Float bounds are written with 9 digits: equal as floats. */
        if ((float)jv_num(jv_at(jv_get(pa, "min"), k), NAN) != (float)lo ||
            (float)jv_num(jv_at(jv_get(pa, "max"), k), NAN) != (float)hi)
            return glb_fail_(why, n, "POSITION min/max[%d] = %.9g/%.9g, the data's %.9g/%.9g", k,
                             jv_num(jv_at(jv_get(pa, "min"), k), NAN),
                             jv_num(jv_at(jv_get(pa, "max"), k), NAN), lo, hi);
    }
    /* The node's transform: translation and scale (all scanlod writes; no rotation). */
    const jv *node = jv_at(jv_get(&g->json, "nodes"), 0);
    if (jv_get(node, "rotation")->type != JV_NULL || jv_get(node, "matrix")->type != JV_NULL)
        return glb_fail_(why, n, "the node has a rotation or matrix");
    /* A morph target: plain (or meshopt) accessors in every encoding, Draco's included. */
    const jv *target = jv_get(jv_at(jv_get(prim, "targets"), 0), "POSITION");
    if (target->type == JV_NUM) {
        uint64_t count;
        if (!(g->morph = glb_accessor_(g, bin, bin_size, (int)target->num, 3, &count, why, n)))
            return -1;
        if (count != g->vertex_count)
            return glb_fail_(why, n, "the morph target has %llu elements, POSITION %llu",
                             (unsigned long long)count, (unsigned long long)g->vertex_count);
        const jv *ta = jv_at(jv_get(&g->json, "accessors"), (int)target->num);
        for (int k = 0; k < 3; k++) { /* min/max are required and must be the data's */
            double lo = INFINITY, hi = -INFINITY;
            for (uint64_t i = 0; i < count; i++)
                lo = fmin(lo, g->morph[3 * i + k]), hi = fmax(hi, g->morph[3 * i + k]);
            if ((float)jv_num(jv_at(jv_get(ta, "min"), k), NAN) != (float)lo ||
                (float)jv_num(jv_at(jv_get(ta, "max"), k), NAN) != (float)hi)
                return glb_fail_(why, n, "morph target min/max[%d] are not the data's", k);
        }
        for (uint64_t i = 0; i < 3 * count; i++)
            g->morph[i] *= jv_num(jv_at(jv_get(node, "scale"), (int)(i % 3)), 1);
    }
    for (uint64_t i = 0; i < g->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            double s = jv_num(jv_at(jv_get(node, "scale"), k), 1);
            double t = jv_num(jv_at(jv_get(node, "translation"), k), 0);
            g->positions[3 * i + k] = g->positions[3 * i + k] * s + t;
        }
    for (uint64_t i = 0; g->normals && i < g->vertex_count; i++) {
        double *v = g->normals + 3 * i, l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3 && l > 0; k++)
            v[k] /= l;
    }
    const jv *image = jv_at(jv_get(&g->json, "images"), 0);
    if (image->type == JV_OBJ) {
        const jv *bv = jv_at(jv_get(&g->json, "bufferViews"), (int)jv_num(jv_get(image, "bufferView"), -1));
        uint64_t off = (uint64_t)jv_num(jv_get(bv, "byteOffset"), 0);
        g->image_size = (uint64_t)jv_num(jv_get(bv, "byteLength"), 0);
        if (off + g->image_size > bin_size)
            return glb_fail_(why, n, "image outside the BIN chunk");
        g->image = bin + off;
        snprintf(g->mime, sizeof g->mime, "%s", jv_get(image, "mimeType")->str ? jv_get(image, "mimeType")->str : "");
    }
    return 0;
}

/* IEC 61966-2-1, the tests' own copy. */
static double glb_reader_linear_to_srgb(double l)
{
    l = l < 0 ? 0 : l > 1 ? 1 : l;
    return l <= 0.0031308 ? 12.92 * l : 1.055 * pow(l, 1 / 2.4) - 0.055;
}

#endif
