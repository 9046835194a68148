/* Binary glTF 2.0 writer (glTF 2.0 specification, section 4.4 "GLB File Format").
 *
 * A .glb is a 12-byte header (magic "glTF", version 2, total length), a JSON chunk and
 * one BIN chunk, each chunk an 8-byte (length, type) header plus a body padded to 4 bytes
 * (JSON with spaces, BIN with zeros). The BIN body holds one tightly packed block per
 * attribute, each its own bufferView (so no byteStride is needed), in the order
 * positions, normals, colours, indices. Every block size is a multiple of 4 except the
 * indices (2-byte indices with an odd triangle count), which come last so that only the
 * end of the buffer needs padding and every bufferView starts 4-byte aligned, as the
 * spec's data-alignment rules ask.
 *
 * Bytes are composed explicitly little endian (glTF's byte order) whatever the host, and
 * streamed through the atomic-write helper's buffer. The JSON is built first because the
 * header must carry the total length.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/atomicfile.h"
#include "core/json.h"
#include "geometry/glb.h"

/* glTF enums (the OpenGL values the spec reuses). */
enum {
    GLTF_TRIANGLES = 4,
    GLTF_UNSIGNED_BYTE = 5121,
    GLTF_UNSIGNED_SHORT = 5123,
    GLTF_UNSIGNED_INT = 5125,
    GLTF_FLOAT = 5126,
    GLTF_ARRAY_BUFFER = 34962,
    GLTF_ELEMENT_ARRAY_BUFFER = 34963
};

#define GLB_MAGIC 0x46546C67u      /* "glTF" */
#define GLB_CHUNK_JSON 0x4E4F534Au /* "JSON" */
#define GLB_CHUNK_BIN 0x004E4942u  /* "BIN\0" */

/* Where each block sits in the BIN chunk. */
typedef struct glb_layout {
    uint64_t positions, normals, colors, indices; /* byte offsets */
    uint64_t index_bytes;                         /* unpadded size of the index block */
    uint64_t bin_length;                          /* padded to 4 */
    int short_indices;
} glb_layout;

static uint64_t pad4(uint64_t n)
{
    return (n + 3) & ~(uint64_t)3;
}

static glb_layout make_layout(const sl_mesh *m)
{
    glb_layout l = {0};
    uint64_t vec3 = 12 * m->vertex_count, at = vec3;
    l.short_indices = m->vertex_count < 65536;
    l.normals = m->normals ? at : 0;
    at += m->normals ? vec3 : 0;
    l.colors = m->colors ? at : 0;
    at += m->colors ? 4 * m->vertex_count : 0;
    l.indices = at;
    l.index_bytes = 3 * m->triangle_count * (l.short_indices ? 2 : 4);
    l.bin_length = pad4(at + l.index_bytes);
    return l;
}

int sl_mesh_check_writable(const sl_mesh *m, const char *path, sl_error *err)
{
    if (m->vertex_count == 0 || m->triangle_count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, path,
                            "nothing to write: the mesh has %llu vertices and %llu triangles",
                            (unsigned long long)m->vertex_count,
                            (unsigned long long)m->triangle_count);
    if (!m->positions || !m->triangles)
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "mesh without positions or triangles");
    for (uint64_t i = 0; i < 3 * m->vertex_count; i++)
        if (!isfinite(m->positions[i]))
            return sl_error_set(err, SL_E_BADINPUT, 0, path,
                                "vertex %llu has a non-finite position",
                                (unsigned long long)(i / 3));
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count)
            return sl_error_set(err, SL_E_INTERNAL, 0, path,
                                "triangle %llu has vertex index %u (%llu vertices)",
                                (unsigned long long)(i / 3), m->triangles[i],
                                (unsigned long long)m->vertex_count);
    return 0;
}

/* The cheap shape check that catches a caller passing a fragment or a string; the text
 * itself is the caller's (a report fragment written with core/json.h). */
static int is_object_text(const char *s)
{
    const char *first = s + strspn(s, " \t\r\n");
    size_t n = strlen(first);
    while (n && strchr(" \t\r\n", first[n - 1]))
        n--;
    return n >= 2 && first[0] == '{' && first[n - 1] == '}';
}

static void json_buffer_view(sl_json *j, uint64_t offset, uint64_t length, int target)
{
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "buffer", 0);
    sl_json_u64(j, "byteOffset", offset);
    sl_json_u64(j, "byteLength", length);
    sl_json_u64(j, "target", (uint64_t)target);
    sl_json_object_end(j);
}

/* Opens an accessor object; the caller adds what is particular and closes it. */
static void json_accessor(sl_json *j, int view, int component, uint64_t count, const char *type)
{
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "bufferView", (uint64_t)view);
    sl_json_u64(j, "componentType", (uint64_t)component);
    sl_json_u64(j, "count", count);
    sl_json_string(j, "type", type);
}

/* min/max of POSITION, required by the spec and compared with the data by validators:
 * %.9g (core/json.h) round-trips a float exactly. */
static void json_position_bounds(sl_json *j, const sl_mesh *m)
{
    float lo[3], hi[3];
    memcpy(lo, m->positions, sizeof lo);
    memcpy(hi, m->positions, sizeof hi);
    for (uint64_t i = 1; i < m->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            float v = m->positions[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    sl_json_array_begin(j, "min");
    for (int k = 0; k < 3; k++)
        sl_json_double(j, NULL, lo[k]);
    sl_json_array_end(j);
    sl_json_array_begin(j, "max");
    for (int k = 0; k < 3; k++)
        sl_json_double(j, NULL, hi[k]);
    sl_json_array_end(j);
}

static void json_mesh(sl_json *j, const char *extras_json, int nrm, int col, int idx)
{
    sl_json_array_begin(j, "meshes");
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "name", "scan");
    sl_json_array_begin(j, "primitives");
    sl_json_object_begin(j, NULL);
    sl_json_object_begin(j, "attributes");
    sl_json_u64(j, "POSITION", 0);
    if (nrm >= 0)
        sl_json_u64(j, "NORMAL", (uint64_t)nrm);
    if (col >= 0)
        sl_json_u64(j, "COLOR_0", (uint64_t)col);
    sl_json_object_end(j);
    sl_json_u64(j, "indices", (uint64_t)idx);
    sl_json_u64(j, "material", 0);
    sl_json_u64(j, "mode", GLTF_TRIANGLES);
    sl_json_object_end(j);
    sl_json_array_end(j);
    if (extras_json)
        sl_json_raw(j, "extras", extras_json);
    sl_json_object_end(j);
    sl_json_array_end(j);
}

/* Scans are matte and often open (holes, single scanned side): metallic 0, high
 * roughness and double-sided. Vertex colours multiply the white base colour. */
static void json_material(sl_json *j)
{
    sl_json_array_begin(j, "materials");
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "name", "scan");
    sl_json_object_begin(j, "pbrMetallicRoughness");
    sl_json_double(j, "metallicFactor", 0);
    sl_json_double(j, "roughnessFactor", 0.9);
    sl_json_object_end(j);
    sl_json_bool(j, "doubleSided", 1);
    sl_json_object_end(j);
    sl_json_array_end(j);
}

static void json_views_and_accessors(sl_json *j, const sl_mesh *m, const glb_layout *l)
{
    int views = 0;
    sl_json_array_begin(j, "bufferViews");
    json_buffer_view(j, l->positions, 12 * m->vertex_count, GLTF_ARRAY_BUFFER);
    if (m->normals)
        json_buffer_view(j, l->normals, 12 * m->vertex_count, GLTF_ARRAY_BUFFER);
    if (m->colors)
        json_buffer_view(j, l->colors, 4 * m->vertex_count, GLTF_ARRAY_BUFFER);
    json_buffer_view(j, l->indices, l->index_bytes, GLTF_ELEMENT_ARRAY_BUFFER);
    sl_json_array_end(j);

    /* Accessor i reads bufferView i. */
    sl_json_array_begin(j, "accessors");
    json_accessor(j, views++, GLTF_FLOAT, m->vertex_count, "VEC3");
    json_position_bounds(j, m);
    sl_json_object_end(j);
    if (m->normals) {
        json_accessor(j, views++, GLTF_FLOAT, m->vertex_count, "VEC3");
        sl_json_object_end(j);
    }
    if (m->colors) {
        json_accessor(j, views++, GLTF_UNSIGNED_BYTE, m->vertex_count, "VEC4");
        sl_json_bool(j, "normalized", 1);
        sl_json_object_end(j);
    }
    json_accessor(j, views, l->short_indices ? GLTF_UNSIGNED_SHORT : GLTF_UNSIGNED_INT,
                  3 * m->triangle_count, "SCALAR");
    sl_json_object_end(j);
    sl_json_array_end(j);
}

static void build_json(sl_json *j, const sl_mesh *m, const char *extras_json,
                       const glb_layout *l)
{
    int nrm = m->normals ? 1 : -1;
    int col = m->colors ? 1 + (nrm > 0) : -1;
    int idx = 1 + (nrm > 0) + (col > 0);

    sl_json_object_begin(j, NULL);
    sl_json_object_begin(j, "asset");
    sl_json_string(j, "version", "2.0");
    sl_json_string(j, "generator", "scanlod");
    sl_json_object_end(j);
    sl_json_u64(j, "scene", 0);
    sl_json_array_begin(j, "scenes");
    sl_json_object_begin(j, NULL);
    sl_json_array_begin(j, "nodes");
    sl_json_u64(j, NULL, 0);
    sl_json_array_end(j);
    sl_json_object_end(j);
    sl_json_array_end(j);
    sl_json_array_begin(j, "nodes");
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "name", "scan");
    sl_json_u64(j, "mesh", 0);
    sl_json_object_end(j);
    sl_json_array_end(j);
    json_mesh(j, extras_json, nrm, col, idx);
    json_material(j);
    sl_json_array_begin(j, "buffers");
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "byteLength", l->bin_length);
    sl_json_object_end(j);
    sl_json_array_end(j);
    json_views_and_accessors(j, m, l);
    sl_json_object_end(j);
}

/* ---- binary body ---- */

static int put_u32(sl_atomic_file *f, uint32_t v, sl_error *err)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    return sl_atomic_write(f, b, 4, err);
}

static int put_f32(sl_atomic_file *f, float v, sl_error *err)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    return put_u32(f, bits, err);
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

static int write_bin(sl_atomic_file *f, const sl_mesh *m, const glb_layout *l, sl_error *err)
{
    int rc = 0;
    for (uint64_t i = 0; i < 3 * m->vertex_count && !rc; i++)
        rc = put_f32(f, m->positions[i], err);
    for (uint64_t i = 0; m->normals && i < m->vertex_count && !rc; i++) {
        float n[3];
        unit_normal(m->normals + 3 * i, n);
        for (int k = 0; k < 3 && !rc; k++)
            rc = put_f32(f, n[k], err);
    }
    if (m->colors && !rc)
        rc = sl_atomic_write(f, m->colors, (size_t)(4 * m->vertex_count), err);
    for (uint64_t i = 0; i < 3 * m->triangle_count && !rc; i++) {
        uint32_t v = m->triangles[i];
        if (l->short_indices) {
            unsigned char b[2] = {(unsigned char)v, (unsigned char)(v >> 8)};
            rc = sl_atomic_write(f, b, 2, err);
        } else {
            rc = put_u32(f, v, err);
        }
    }
    uint64_t used = l->indices + l->index_bytes;
    static const unsigned char zeros[4];
    return rc ? rc : sl_atomic_write(f, zeros, (size_t)(l->bin_length - used), err);
}

static int write_glb(sl_atomic_file *f, const sl_mesh *m, const glb_layout *l,
                     const char *json, uint64_t json_length, sl_error *err)
{
    uint64_t total = 12 + 8 + json_length + 8 + l->bin_length;
    int rc = put_u32(f, GLB_MAGIC, err);
    rc = rc ? rc : put_u32(f, 2, err);
    rc = rc ? rc : put_u32(f, (uint32_t)total, err);
    rc = rc ? rc : put_u32(f, (uint32_t)json_length, err);
    rc = rc ? rc : put_u32(f, GLB_CHUNK_JSON, err);
    rc = rc ? rc : sl_atomic_write(f, json, strlen(json), err);
    rc = rc ? rc : sl_atomic_write(f, "   ", (size_t)(json_length - strlen(json)), err);
    rc = rc ? rc : put_u32(f, (uint32_t)l->bin_length, err);
    rc = rc ? rc : put_u32(f, GLB_CHUNK_BIN, err);
    return rc ? rc : write_bin(f, m, l, err);
}

int sl_glb_write(const char *path, const sl_mesh *m, const char *extras_json, sl_error *err)
{
    int rc = sl_mesh_check_writable(m, path, err);
    if (rc)
        return rc;
    if (extras_json && !is_object_text(extras_json))
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "GLB extras are not a JSON object");

    glb_layout layout = make_layout(m);
    sl_json j;
    sl_json_init(&j, 0);
    build_json(&j, m, extras_json, &layout);
    if (j.failed) {
        sl_json_release(&j);
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory for the glTF JSON");
    }
    const char *json = sl_json_text(&j);
    uint64_t json_length = pad4(strlen(json));
    if (12 + 8 + json_length + 8 + layout.bin_length > UINT32_MAX) {
        sl_json_release(&j);
        return sl_error_set(err, SL_E_LIMIT, 0, path,
                            "%llu vertices and %llu triangles exceed the 4 GiB of a GLB file",
                            (unsigned long long)m->vertex_count,
                            (unsigned long long)m->triangle_count);
    }
    sl_atomic_file f;
    if (!(rc = sl_atomic_open(&f, path, err))) {
        rc = write_glb(&f, m, &layout, json, json_length, err);
        rc = rc ? rc : sl_atomic_commit(&f, err);
        if (rc)
            sl_atomic_abort(&f);
    }
    sl_json_release(&j);
    return rc;
}
