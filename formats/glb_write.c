/* Binary glTF 2.0 writer (glTF 2.0 specification, section 4.4 "GLB File Format").
 *
 * A .glb is a 12-byte header (magic "glTF", version 2, total length), a JSON chunk and
 * one BIN chunk, each chunk an 8-byte (length, type) header plus a body padded to 4 bytes
 * (JSON with spaces, BIN with zeros). glb_streams.c makes the bufferViews (one per
 * attribute, the indices, the image, or one Draco stream); here they are laid out, each
 * at a 4-byte aligned offset as the spec's data-alignment rules ask, in the BIN chunk
 * (buffer 0). A meshopt file stores the compressed streams in buffer 0 and describes the
 * decoded data in a fallback buffer 1 without data (EXT_meshopt_compression: a reader
 * that knows the extension never reads it; one that does not fails cleanly because the
 * extension is required).
 *
 * Bytes are composed explicitly little endian (glTF's byte order) and streamed through
 * the atomic-write helper's buffer. The JSON is built first because the header must carry
 * the total length.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/atomicfile.h"
#include "core/json.h"
#include "formats/glb.h"
#include "formats/glb_internal.h"

#define GLB_MAGIC 0x46546C67u      /* "glTF" */
#define GLB_CHUNK_JSON 0x4E4F534Au /* "JSON" */
#define GLB_CHUNK_BIN 0x004E4942u  /* "BIN\0" */

static uint64_t pad4(uint64_t n)
{
    return (n + 3) & ~(uint64_t)3;
}

sl_glb_options sl_glb_default_options(void)
{
    sl_glb_options o = {SL_GLB_UNCOMPRESSED, 0, 14, 8, 12, 12, NULL, 0, NULL, NULL, 0, NULL};
    return o;
}

/* Offsets of every view; returns the BIN chunk's length, *fallback the meshopt fallback
 * buffer's. */
static uint64_t layout(glb_doc *d, uint64_t *fallback)
{
    uint64_t bin = 0;
    *fallback = 0;
    for (int i = 0; i < d->view_count; i++) {
        glb_view *v = &d->views[i];
        if (v->mode) {
            v->offset = *fallback;
            *fallback += pad4(v->size);
            v->packed_offset = bin;
            bin += pad4(v->packed_size);
        } else {
            v->offset = bin;
            bin += pad4(v->size);
        }
    }
    return bin;
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

/* The extensions the file uses (required: those a viewer must know to read it; a WebP
 * texture with a JPEG fallback is used, not required). The array only when not empty. */
static void json_extension_names(sl_json *j, const char *key, const glb_doc *d, int required)
{
    int webp = d->image_view >= 0 && glb_webp(d) && (!required || d->fallback_view < 0);
    if (!d->quantized && d->opt->compression == SL_GLB_UNCOMPRESSED && !webp)
        return;
    sl_json_array_begin(j, key);
    if (d->quantized)
        sl_json_string(j, NULL, "KHR_mesh_quantization");
    if (d->opt->compression == SL_GLB_MESHOPT)
        sl_json_string(j, NULL, "EXT_meshopt_compression");
    if (d->opt->compression == SL_GLB_DRACO)
        sl_json_string(j, NULL, "KHR_draco_mesh_compression");
    if (webp)
        sl_json_string(j, NULL, "EXT_texture_webp");
    sl_json_array_end(j);
}

static void json_scene_and_node(sl_json *j, const glb_doc *d)
{
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
    if (d->node_transform) { /* positions' dequantisation; floats printed exactly */
        sl_json_array_begin(j, "translation");
        for (int k = 0; k < 3; k++)
            sl_json_double(j, NULL, d->translation[k]);
        sl_json_array_end(j);
        sl_json_array_begin(j, "scale");
        for (int k = 0; k < 3; k++)
            sl_json_double(j, NULL, d->scale);
        sl_json_array_end(j);
    }
    sl_json_object_end(j);
    sl_json_array_end(j);
}

static void json_mesh(sl_json *j, const glb_doc *d, const char *extras_json)
{
    sl_json_array_begin(j, "meshes");
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "name", "scan");
    sl_json_array_begin(j, "primitives");
    sl_json_object_begin(j, NULL);
    sl_json_object_begin(j, "attributes");
    for (int i = 0; i < d->accessor_count; i++)
        if (d->accessors[i].semantic && !d->accessors[i].morph)
            sl_json_u64(j, d->accessors[i].semantic, (uint64_t)i);
    sl_json_object_end(j);
    if (d->stats.morph) {
        sl_json_array_begin(j, "targets");
        sl_json_object_begin(j, NULL);
        for (int i = 0; i < d->accessor_count; i++)
            if (d->accessors[i].morph)
                sl_json_u64(j, d->accessors[i].semantic, (uint64_t)i);
        sl_json_object_end(j);
        sl_json_array_end(j);
    }
    sl_json_u64(j, "indices", (uint64_t)d->indices);
    sl_json_u64(j, "material", 0);
    sl_json_u64(j, "mode", GLTF_TRIANGLES);
    if (d->draco_view >= 0) {
        sl_json_object_begin(j, "extensions");
        sl_json_object_begin(j, "KHR_draco_mesh_compression");
        sl_json_u64(j, "bufferView", (uint64_t)d->draco_view);
        sl_json_object_begin(j, "attributes");
        for (int i = 0; i < d->accessor_count; i++)
            if (d->accessors[i].semantic && !d->accessors[i].morph)
                sl_json_u64(j, d->accessors[i].semantic, (uint64_t)d->accessors[i].draco_id);
        sl_json_object_end(j);
        sl_json_object_end(j);
        sl_json_object_end(j);
    }
    sl_json_object_end(j);
    sl_json_array_end(j);
    if (d->stats.morph) { /* weight 0: the mesh as given until a viewer blends */
        sl_json_array_begin(j, "weights");
        sl_json_double(j, NULL, 0);
        sl_json_array_end(j);
    }
    if (extras_json)
        sl_json_raw(j, "extras", extras_json);
    sl_json_object_end(j);
    sl_json_array_end(j);
}

/* Scans are matte and often open (holes, single scanned side): metallic 0, high
 * roughness and double-sided. Vertex colours multiply the white base colour. A texture is
 * an atlas of small charts (stages/export/export_texture.c): sampled without mipmaps,
 * whose averaging would mix neighbouring charts across their two-texel gaps (seen as
 * light seams along every edge), and clamped at its edges (an atlas does not repeat). */
static void json_material(sl_json *j, const glb_doc *d)
{
    sl_json_array_begin(j, "materials");
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "name", "scan");
    sl_json_object_begin(j, "pbrMetallicRoughness");
    if (d->image_view >= 0) {
        sl_json_object_begin(j, "baseColorTexture");
        sl_json_u64(j, "index", 0);
        sl_json_object_end(j);
    }
    sl_json_double(j, "metallicFactor", 0);
    sl_json_double(j, "roughnessFactor", 0.9);
    sl_json_object_end(j);
    sl_json_bool(j, "doubleSided", 1);
    sl_json_object_end(j);
    sl_json_array_end(j);
    if (d->image_view < 0)
        return;
    sl_json_array_begin(j, "samplers");
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "magFilter", 9729);  /* LINEAR */
    sl_json_u64(j, "minFilter", 9729);  /* LINEAR */
    sl_json_u64(j, "wrapS", 33071);     /* CLAMP_TO_EDGE */
    sl_json_u64(j, "wrapT", 33071);
    sl_json_object_end(j);
    sl_json_array_end(j);
    sl_json_array_begin(j, "textures");
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "sampler", 0);
    if (!glb_webp(d)) {
        sl_json_u64(j, "source", 0);
    } else { /* images[0] the WebP, images[1] its JPEG fallback when there is one */
        if (d->fallback_view >= 0)
            sl_json_u64(j, "source", 1);
        sl_json_object_begin(j, "extensions");
        sl_json_object_begin(j, "EXT_texture_webp");
        sl_json_u64(j, "source", 0);
        sl_json_object_end(j);
        sl_json_object_end(j);
    }
    sl_json_object_end(j);
    sl_json_array_end(j);
    sl_json_array_begin(j, "images");
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "bufferView", (uint64_t)d->image_view);
    sl_json_string(j, "mimeType", d->opt->image_mime_type);
    sl_json_object_end(j);
    if (d->fallback_view >= 0) {
        sl_json_object_begin(j, NULL);
        sl_json_u64(j, "bufferView", (uint64_t)d->fallback_view);
        sl_json_string(j, "mimeType", "image/jpeg");
        sl_json_object_end(j);
    }
    sl_json_array_end(j);
}

static void json_buffers(sl_json *j, uint64_t bin, uint64_t fallback)
{
    sl_json_array_begin(j, "buffers");
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "byteLength", bin);
    sl_json_object_end(j);
    if (fallback) {
        sl_json_object_begin(j, NULL);
        sl_json_u64(j, "byteLength", fallback);
        sl_json_object_begin(j, "extensions");
        sl_json_object_begin(j, "EXT_meshopt_compression");
        sl_json_bool(j, "fallback", 1);
        sl_json_object_end(j);
        sl_json_object_end(j);
        sl_json_object_end(j);
    }
    sl_json_array_end(j);
}

static void json_view(sl_json *j, const glb_view *v)
{
    sl_json_object_begin(j, NULL);
    sl_json_u64(j, "buffer", v->mode ? 1 : 0);
    sl_json_u64(j, "byteOffset", v->offset);
    sl_json_u64(j, "byteLength", v->size);
    if (v->target == GLTF_ARRAY_BUFFER)
        sl_json_u64(j, "byteStride", v->stride);
    if (v->target)
        sl_json_u64(j, "target", (uint64_t)v->target);
    if (v->mode) {
        sl_json_object_begin(j, "extensions");
        sl_json_object_begin(j, "EXT_meshopt_compression");
        sl_json_u64(j, "buffer", 0);
        sl_json_u64(j, "byteOffset", v->packed_offset);
        sl_json_u64(j, "byteLength", v->packed_size);
        sl_json_u64(j, "byteStride", v->stride);
        sl_json_u64(j, "count", v->count);
        sl_json_string(j, "mode", v->mode);
        if (v->filter)
            sl_json_string(j, "filter", v->filter);
        sl_json_object_end(j);
        sl_json_object_end(j);
    }
    sl_json_object_end(j);
}

/* POSITION's min/max are required and compared with the data by validators: %.9g
 * (core/json.h) round-trips a float exactly, and quantised bounds are integers. */
static void json_accessor(sl_json *j, const glb_accessor *a)
{
    sl_json_object_begin(j, NULL);
    if (a->view >= 0)
        sl_json_u64(j, "bufferView", (uint64_t)a->view);
    sl_json_u64(j, "componentType", (uint64_t)a->component);
    if (a->normalized)
        sl_json_bool(j, "normalized", 1);
    sl_json_u64(j, "count", a->count);
    sl_json_string(j, "type", a->type);
    if (a->has_bounds) {
        sl_json_array_begin(j, "min");
        for (int k = 0; k < 3; k++)
            sl_json_double(j, NULL, a->min[k]);
        sl_json_array_end(j);
        sl_json_array_begin(j, "max");
        for (int k = 0; k < 3; k++)
            sl_json_double(j, NULL, a->max[k]);
        sl_json_array_end(j);
    }
    sl_json_object_end(j);
}

static void build_json(sl_json *j, const glb_doc *d, const char *extras_json, uint64_t bin,
                       uint64_t fallback)
{
    sl_json_object_begin(j, NULL);
    sl_json_object_begin(j, "asset");
    sl_json_string(j, "version", "2.0");
    sl_json_string(j, "generator", "scanlod");
    sl_json_object_end(j);
    json_extension_names(j, "extensionsUsed", d, 0);
    json_extension_names(j, "extensionsRequired", d, 1);
    json_scene_and_node(j, d);
    json_mesh(j, d, extras_json);
    json_material(j, d);
    json_buffers(j, bin, fallback);
    sl_json_array_begin(j, "bufferViews");
    for (int i = 0; i < d->view_count; i++)
        json_view(j, &d->views[i]);
    sl_json_array_end(j);
    sl_json_array_begin(j, "accessors");
    for (int i = 0; i < d->accessor_count; i++)
        json_accessor(j, &d->accessors[i]);
    sl_json_array_end(j);
    sl_json_object_end(j);
}

/* ---- container ---- */

static int put_u32(sl_atomic_file *f, uint32_t v, sl_error *err)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    return sl_atomic_write(f, b, 4, err);
}

static int write_bin(sl_atomic_file *f, const glb_doc *d, sl_error *err)
{
    static const unsigned char zeros[4];
    int rc = 0;
    for (int i = 0; i < d->view_count && !rc; i++) {
        const glb_view *v = &d->views[i];
        const unsigned char *bytes = v->mode ? v->packed : v->data;
        uint64_t size = v->mode ? v->packed_size : v->size;
        rc = sl_atomic_write(f, bytes, (size_t)size, err);
        if (!rc)
            rc = sl_atomic_write(f, zeros, (size_t)(pad4(size) - size), err);
    }
    return rc;
}

static int write_glb(sl_atomic_file *f, const glb_doc *d, const char *json,
                     uint64_t json_length, uint64_t bin, sl_error *err)
{
    uint64_t total = 12 + 8 + json_length + 8 + bin;
    int rc = put_u32(f, GLB_MAGIC, err);
    rc = rc ? rc : put_u32(f, 2, err);
    rc = rc ? rc : put_u32(f, (uint32_t)total, err);
    rc = rc ? rc : put_u32(f, (uint32_t)json_length, err);
    rc = rc ? rc : put_u32(f, GLB_CHUNK_JSON, err);
    rc = rc ? rc : sl_atomic_write(f, json, strlen(json), err);
    rc = rc ? rc : sl_atomic_write(f, "   ", (size_t)(json_length - strlen(json)), err);
    rc = rc ? rc : put_u32(f, (uint32_t)bin, err);
    rc = rc ? rc : put_u32(f, GLB_CHUNK_BIN, err);
    return rc ? rc : write_bin(f, d, err);
}

static int write_doc(const char *path, glb_doc *d, const char *extras_json, sl_error *err)
{
    uint64_t fallback, bin = layout(d, &fallback);
    sl_json j;
    sl_json_init(&j, 0);
    build_json(&j, d, extras_json, bin, fallback);
    if (j.failed) {
        sl_json_release(&j);
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory for the glTF JSON");
    }
    const char *json = sl_json_text(&j);
    uint64_t json_length = pad4(strlen(json)), total = 12 + 8 + json_length + 8 + bin;
    int rc = 0;
    if (total > UINT32_MAX)
        rc = sl_error_set(err, SL_E_LIMIT, 0, path,
                          "%llu vertices and %llu triangles exceed the 4 GiB of a GLB file",
                          (unsigned long long)d->stats.vertices,
                          (unsigned long long)d->stats.triangles);
    sl_atomic_file f;
    if (!rc && !(rc = sl_atomic_open(&f, path, err))) {
        rc = write_glb(&f, d, json, json_length, bin, err);
        rc = rc ? rc : sl_atomic_commit(&f, err);
        if (rc)
            sl_atomic_abort(&f);
    }
    d->stats.bytes = total;
    sl_json_release(&j);
    return rc;
}

int sl_glb_write(const char *path, const sl_mesh *m, const char *extras_json,
                 const sl_glb_options *options, sl_glb_stats *stats, sl_error *err)
{
    int rc = sl_mesh_check_writable(m, path, err);
    if (rc)
        return rc;
    if (extras_json && !is_object_text(extras_json))
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "GLB extras are not a JSON object");
    sl_glb_options plain = sl_glb_default_options();
    glb_doc d;
    memset(&d, 0, sizeof d);
    d.opt = options ? options : &plain;
    rc = glb_doc_build(&d, m, err);
    if (rc == 0)
        rc = write_doc(path, &d, extras_json, err);
    else if (!err->file[0] && path)
        snprintf(err->file, sizeof err->file, "%s", path); /* the streams know no path */
    if (rc == 0 && stats)
        *stats = d.stats;
    glb_doc_release(&d);
    return rc;
}
