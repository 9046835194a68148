/* glTF 2.0 documents: the container (GLB chunks, or the JSON text of a .gltf), the required
 * extensions, and buffers, bufferViews and accessors as checked tables (gltf_internal.h).
 *
 * What is checked here: every index names an element that exists; sizes are integers a
 * file can have; component types and element types are glTF's; a view lies inside its
 * buffer as declared. Whether an accessor's elements lie inside its view is checked when
 * it is read (gltf_data.c), so a file with a broken accessor no primitive uses still
 * reads. Nothing is allocated from a declared size here but tables of the JSON's own
 * arrays (bounded by the JSON's values).
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "core/io.h"
#include "formats/gltf_internal.h"

#define GLB_JSON 0x4E4F534Au
#define GLB_BIN 0x004E4942u
#define MAX_SIZE (1ull << 53) /* sizes beyond JSON's exact integers */

int gltf_error(const gltf_doc *g, int code, const char *fmt, ...)
{
    char msg[700];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return sl_error_set(g->s->err, code, 0, g->s->name, "%s", msg);
}

void gltf_warn(const gltf_doc *g, const char *fmt, ...)
{
    if (!g->m)
        return;
    char msg[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    sl_mesh_warn(g->m, "%s", msg);
}

int gltf_component_size(uint32_t c)
{
    switch (c) {
    case GLTF_BYTE: case GLTF_UNSIGNED_BYTE: return 1;
    case GLTF_SHORT: case GLTF_UNSIGNED_SHORT: return 2;
    case GLTF_UNSIGNED_INT: case GLTF_FLOAT: return 4;
    default: return 0;
    }
}

int gltf_index(const gltf_doc *g, uint32_t object, const char *key, uint64_t limit,
               const char *where, uint32_t *out)
{
    uint64_t v;
    int got = sl_jdoc_index(&g->j, sl_jdoc_get(&g->j, object, key), limit, &v);
    if (got < 0)
        return gltf_error(g, SL_E_BADINPUT, "%s.%s: not an index below %llu", where, key,
                          (unsigned long long)limit);
    if (got)
        *out = (uint32_t)v;
    return got;
}

/* A member that must be a size (a non-negative integer) when present; `dflt` when absent. */
static int size_member(const gltf_doc *g, uint32_t object, const char *key, uint64_t dflt,
                       int required, const char *where, uint64_t *out)
{
    uint64_t v = dflt;
    uint32_t t = sl_jdoc_get(&g->j, object, key);
    int got = sl_jdoc_index(&g->j, t, MAX_SIZE, &v);
    if (got < 0 || (!got && required))
        return gltf_error(g, SL_E_BADINPUT, "%s.%s: %s", where, key,
                          got ? "not a size" : "missing");
    *out = v;
    return 0;
}

/* ---- the container ---- */

static int open_glb(gltf_doc *g, const unsigned char **json, uint64_t *json_size)
{
    const unsigned char *d = g->s->data;
    uint64_t size = g->s->size;
    if (size < 20)
        return gltf_error(g, SL_E_BADINPUT, "%llu bytes: too short for a GLB",
                          (unsigned long long)size);
    uint32_t version = sl_get_u32(d + 4), length = sl_get_u32(d + 8);
    if (version != 2)
        return gltf_error(g, SL_E_UNSUPPORTED, "GLB version %u (only glTF 2.0)", version);
    if (length > size || length < 20)
        return gltf_error(g, SL_E_BADINPUT, "GLB declares %u bytes, the file holds %llu", length,
                          (unsigned long long)size);
    if (length < size)
        gltf_warn(g, "%llu bytes after the GLB", (unsigned long long)(size - length));
    uint64_t json_len = sl_get_u32(d + 12);
    if (sl_get_u32(d + 16) != GLB_JSON || 20 + json_len > length)
        return gltf_error(g, SL_E_BADINPUT, "GLB: the first chunk is not a JSON chunk inside "
                          "the file");
    *json = d + 20;
    *json_size = json_len;
    uint64_t at = 20 + json_len;
    if (at + 8 <= length && sl_get_u32(d + at + 4) == GLB_BIN) {
        uint64_t bin_len = sl_get_u32(d + at);
        if (at + 8 + bin_len > length)
            return gltf_error(g, SL_E_BADINPUT, "GLB: the BIN chunk (%llu bytes) runs past the "
                              "end of the file", (unsigned long long)bin_len);
        g->bin = d + at + 8;
        g->bin_size = bin_len;
    }
    return 0;
}

static int check_required(const gltf_doc *g)
{
    static const char *const known[] = {
        "KHR_mesh_quantization", "KHR_draco_mesh_compression", "EXT_meshopt_compression",
        "KHR_meshopt_compression", "KHR_texture_transform", "KHR_texture_basisu",
        "EXT_texture_webp", "EXT_texture_avif", "KHR_lights_punctual", "KHR_materials_"};
    const sl_jdoc *j = &g->j;
    uint32_t list = sl_jdoc_get(j, 0, "extensionsRequired");
    uint32_t n = sl_jdoc_type(j, list) == SL_JDOC_ARRAY ? j->tokens[list].count : 0;
    for (uint32_t i = 0, t = list + 1; i < n; i++, t = j->tokens[t].next) {
        char name[128];
        sl_jdoc_string(j, t, name, sizeof name);
        int ok = 0;
        for (size_t k = 0; k < sizeof known / sizeof known[0]; k++)
            ok |= !strncmp(name, known[k], strlen(known[k]));
        if (!ok)
            return gltf_error(g, SL_E_UNSUPPORTED, "requires the extension %s, which scanlod "
                              "does not read", name);
    }
    return 0;
}

static int check_asset(const gltf_doc *g)
{
    char version[16] = "";
    uint32_t asset = sl_jdoc_get(&g->j, 0, "asset");
    if (g->j.tokens[0].type != SL_JDOC_OBJECT)
        return gltf_error(g, SL_E_BADINPUT, "the JSON is not an object");
    if (sl_jdoc_string(&g->j, sl_jdoc_get(&g->j, asset, "version"), version, sizeof version) < 0)
        return gltf_error(g, SL_E_BADINPUT, "no asset.version: not a glTF file");
    if (strncmp(version, "2.", 2) != 0)
        return gltf_error(g, SL_E_UNSUPPORTED, "glTF %s (only glTF 2.0)", version);
    return check_required(g);
}

/* ---- tables ---- */

/* The items of top-level array `key` into *tok (count in *n); `array` its token. */
static int item_tokens(gltf_doc *g, const char *key, uint32_t *array, uint32_t **tok,
                       uint32_t *n)
{
    const sl_jdoc *j = &g->j;
    *array = sl_jdoc_get(j, 0, key);
    *n = 0;
    *tok = NULL;
    if (!*array)
        return 0;
    if (sl_jdoc_type(j, *array) != SL_JDOC_ARRAY)
        return gltf_error(g, SL_E_BADINPUT, "'%s' is not an array", key);
    uint32_t count = j->tokens[*array].count;
    if (!(*tok = malloc(((size_t)count + 1) * sizeof **tok)))
        return sl_error_nomem(g->s->err, g->s->name, "out of memory for %u %s", count, key);
    for (uint32_t i = 0, t = *array + 1; i < count; i++, t = j->tokens[t].next) {
        if (j->tokens[t].type != SL_JDOC_OBJECT)
            return gltf_error(g, SL_E_BADINPUT, "%s[%u] is not an object", key, i);
        (*tok)[i] = t;
    }
    *n = count;
    return 0;
}

/* The meshopt extension object of a bufferView, or 0. */
static uint32_t meshopt_of(const gltf_doc *g, uint32_t view, const char **name)
{
    uint32_t ext = sl_jdoc_get(&g->j, view, "extensions"), t;
    *name = "EXT_meshopt_compression";
    if ((t = sl_jdoc_get(&g->j, ext, *name)))
        return t;
    *name = "KHR_meshopt_compression";
    return sl_jdoc_get(&g->j, ext, *name);
}

static int parse_meshopt(gltf_doc *g, uint32_t t, const char *name, const char *where,
                         gltf_meshopt *mo)
{
    static const char *const modes[] = {"ATTRIBUTES", "TRIANGLES", "INDICES"};
    static const char *const filters[] = {"NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL",
                                          "COLOR"};
    uint64_t stride;
    int rc, got;
    mo->extension = name;
    if ((got = gltf_index(g, t, "buffer", g->buffer_count, where, &mo->buffer)) <= 0)
        return got < 0 ? got : gltf_error(g, SL_E_BADINPUT, "%s: %s without a buffer", where, name);
    if ((rc = size_member(g, t, "byteOffset", 0, 0, where, &mo->offset)) ||
        (rc = size_member(g, t, "byteLength", 0, 1, where, &mo->length)) ||
        (rc = size_member(g, t, "byteStride", 0, 1, where, &stride)) ||
        (rc = size_member(g, t, "count", 0, 1, where, &mo->count)))
        return rc;
    mo->stride = stride <= 256 ? (uint32_t)stride : 0;
    mo->mode = -1;
    for (int k = 0; k < 3; k++)
        if (sl_jdoc_string_is(&g->j, sl_jdoc_get(&g->j, t, "mode"), modes[k]))
            mo->mode = k;
    mo->filter = MESHOPT_NONE;
    for (int k = 0; k < 5; k++)
        if (sl_jdoc_string_is(&g->j, sl_jdoc_get(&g->j, t, "filter"), filters[k]))
            mo->filter = k;
    if (mo->mode < 0 || !mo->stride)
        return gltf_error(g, SL_E_BADINPUT, "%s: %s mode or byteStride invalid", where, name);
    if (mo->offset > g->buffers[mo->buffer].byte_length ||
        mo->length > g->buffers[mo->buffer].byte_length - mo->offset)
        return gltf_error(g, SL_E_BADINPUT, "%s: the %s stream lies outside buffer %u", where,
                          name, mo->buffer);
    return 0;
}

static int parse_view(gltf_doc *g, uint32_t t, uint32_t i, gltf_view *v)
{
    char where[40];
    snprintf(where, sizeof where, "bufferViews[%u]", i);
    uint64_t stride;
    const char *name;
    int got = gltf_index(g, t, "buffer", g->buffer_count, where, &v->buffer), rc;
    if (got <= 0)
        return got < 0 ? got : gltf_error(g, SL_E_BADINPUT, "%s: no buffer", where);
    if ((rc = size_member(g, t, "byteOffset", 0, 0, where, &v->offset)) ||
        (rc = size_member(g, t, "byteLength", 0, 1, where, &v->length)) ||
        (rc = size_member(g, t, "byteStride", 0, 0, where, &stride)))
        return rc;
    if (stride && (stride < 4 || stride > 252 || stride % 4))
        return gltf_error(g, SL_E_BADINPUT, "%s: byteStride %llu (4..252, a multiple of 4)",
                          where, (unsigned long long)stride);
    v->stride = (uint32_t)stride;
    const gltf_buffer *b = &g->buffers[v->buffer];
    if (v->offset > b->byte_length || v->length > b->byte_length - v->offset)
        return gltf_error(g, SL_E_BADINPUT, "%s: bytes %llu..%llu lie outside buffer %u "
                          "(%llu bytes)", where, (unsigned long long)v->offset,
                          (unsigned long long)(v->offset + v->length), v->buffer,
                          (unsigned long long)b->byte_length);
    uint32_t mo = meshopt_of(g, t, &name);
    v->meshopt = mo != 0;
    return mo ? parse_meshopt(g, mo, name, where, &v->mo) : 0;
}

static int parse_buffer(gltf_doc *g, uint32_t t, uint32_t i, gltf_buffer *b)
{
    char where[40];
    snprintf(where, sizeof where, "buffers[%u]", i);
    int rc = size_member(g, t, "byteLength", 0, 1, where, &b->byte_length);
    if (rc)
        return rc;
    b->uri = sl_jdoc_get(&g->j, t, "uri");
    if (b->uri && sl_jdoc_type(&g->j, b->uri) != SL_JDOC_STRING)
        return gltf_error(g, SL_E_BADINPUT, "%s.uri is not a string", where);
    uint32_t ext = sl_jdoc_get(&g->j, t, "extensions");
    uint32_t mo = sl_jdoc_get(&g->j, ext, "EXT_meshopt_compression");
    mo = mo ? mo : sl_jdoc_get(&g->j, ext, "KHR_meshopt_compression");
    b->fallback = !b->uri && sl_jdoc_type(&g->j, sl_jdoc_get(&g->j, mo, "fallback")) ==
                                 SL_JDOC_TRUE;
    return 0;
}

static int parse_accessor_sparse(gltf_doc *g, uint32_t t, const char *where, gltf_sparse *sp)
{
    uint32_t sparse = sl_jdoc_get(&g->j, t, "sparse");
    if (!sparse)
        return 0;
    uint32_t idx = sl_jdoc_get(&g->j, sparse, "indices"), val = sl_jdoc_get(&g->j, sparse, "values");
    uint64_t component = 0;
    int rc;
    if ((rc = size_member(g, sparse, "count", 0, 1, where, &sp->count)) ||
        (rc = size_member(g, idx, "componentType", 0, 1, where, &component)) ||
        (rc = size_member(g, idx, "byteOffset", 0, 0, where, &sp->index_offset)) ||
        (rc = size_member(g, val, "byteOffset", 0, 0, where, &sp->value_offset)))
        return rc;
    sp->index_component = (uint32_t)component;
    if ((rc = gltf_index(g, idx, "bufferView", g->view_count, where, &sp->index_view)) <= 0 ||
        (rc = gltf_index(g, val, "bufferView", g->view_count, where, &sp->value_view)) <= 0)
        return rc < 0 ? rc : gltf_error(g, SL_E_BADINPUT, "%s.sparse: a bufferView is missing",
                                        where);
    if (component != GLTF_UNSIGNED_BYTE && component != GLTF_UNSIGNED_SHORT &&
        component != GLTF_UNSIGNED_INT)
        return gltf_error(g, SL_E_BADINPUT, "%s.sparse.indices.componentType %llu", where,
                          (unsigned long long)component);
    return 0;
}

static int parse_accessor(gltf_doc *g, uint32_t t, uint32_t i, gltf_accessor *a)
{
    static const struct { const char *name; int components; } types[] = {
        {"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT2", 0}, {"MAT3", 0}, {"MAT4", 0}};
    char where[40];
    snprintf(where, sizeof where, "accessors[%u]", i);
    uint64_t component;
    int rc, known = 0;
    a->view = GLTF_NONE;
    if ((rc = gltf_index(g, t, "bufferView", g->view_count, where, &a->view)) < 0 ||
        (rc = size_member(g, t, "byteOffset", 0, 0, where, &a->offset)) ||
        (rc = size_member(g, t, "count", 0, 1, where, &a->count)) ||
        (rc = size_member(g, t, "componentType", 0, 1, where, &component)))
        return rc;
    a->component = (uint32_t)component;
    for (size_t k = 0; k < sizeof types / sizeof types[0]; k++)
        if (sl_jdoc_string_is(&g->j, sl_jdoc_get(&g->j, t, "type"), types[k].name))
            a->components = types[k].components, known = 1;
    if (!known || !gltf_component_size(a->component) || a->count == 0)
        return gltf_error(g, SL_E_BADINPUT, "%s: type, componentType %u or count %llu invalid",
                          where, a->component, (unsigned long long)a->count);
    a->normalized = sl_jdoc_type(&g->j, sl_jdoc_get(&g->j, t, "normalized")) == SL_JDOC_TRUE;
    return parse_accessor_sparse(g, t, where, &a->sparse);
}

/* One table: the items of `key` parsed by `parse` into an array of `item` bytes. */
static int table(gltf_doc *g, const char *key, size_t item, void **out, uint32_t *n,
                 int (*parse)(gltf_doc *, uint32_t, uint32_t, void *))
{
    uint32_t array, *tok;
    int rc = item_tokens(g, key, &array, &tok, n);
    if (!rc && !(*out = calloc((size_t)*n + 1, item)))
        rc = sl_error_nomem(g->s->err, g->s->name, "out of memory for %u %s", *n, key);
    for (uint32_t i = 0; !rc && i < *n; i++)
        rc = parse(g, tok[i], i, (char *)*out + i * item);
    free(tok);
    return rc;
}

static int parse_buffer_item(gltf_doc *g, uint32_t t, uint32_t i, void *b)
{
    return parse_buffer(g, t, i, b);
}
static int parse_view_item(gltf_doc *g, uint32_t t, uint32_t i, void *v)
{
    return parse_view(g, t, i, v);
}
static int parse_accessor_item(gltf_doc *g, uint32_t t, uint32_t i, void *a)
{
    return parse_accessor(g, t, i, a);
}

static int parse_json(gltf_doc *g, const unsigned char *json, uint64_t size)
{
    if (size >= 3 && json[0] == 0xEF && json[1] == 0xBB && json[2] == 0xBF)
        json += 3, size -= 3; /* a BOM, which the spec forbids and some writers add */
    char why[300];
    int rc = sl_jdoc_parse(&g->j, (const char *)json, size, GLTF_MAX_TOKENS, why, sizeof why);
    if (rc == SL_E_NOMEM)
        return sl_error_nomem(g->s->err, g->s->name, "%s", why);
    return rc ? gltf_error(g, rc, "%s", why) : 0;
}

int gltf_open(gltf_doc *g, const scan_src *s, sl_mesh *warnings_to)
{
    memset(g, 0, sizeof *g);
    g->s = s;
    g->m = warnings_to;
    g->texture_image = g->texture_material = GLTF_NONE;
    const unsigned char *json = s->data;
    uint64_t json_size = s->size;
    int rc = 0;
    g->glb = s->size >= 4 && !memcmp(s->data, "glTF", 4);
    if ((g->glb && (rc = open_glb(g, &json, &json_size))) ||
        (rc = parse_json(g, json, json_size)) || (rc = check_asset(g)) ||
        (rc = table(g, "buffers", sizeof(gltf_buffer), (void **)&g->buffers, &g->buffer_count,
                    parse_buffer_item)) ||
        (rc = table(g, "bufferViews", sizeof(gltf_view), (void **)&g->views, &g->view_count,
                    parse_view_item)) ||
        (rc = table(g, "accessors", sizeof(gltf_accessor), (void **)&g->accessors,
                    &g->accessor_count, parse_accessor_item)))
        return rc;
    if ((rc = item_tokens(g, "meshes", &g->meshes, &g->mesh_tok, &g->mesh_count)) ||
        (rc = item_tokens(g, "nodes", &g->nodes, &g->node_tok, &g->node_count)) ||
        (rc = item_tokens(g, "materials", &g->materials, &g->material_tok, &g->material_count)) ||
        (rc = item_tokens(g, "textures", &g->textures, &g->texture_tok, &g->texture_count)) ||
        (rc = item_tokens(g, "images", &g->images, &g->image_tok, &g->image_count)))
        return rc;
    g->scenes = sl_jdoc_get(&g->j, 0, "scenes");
    return 0;
}

void gltf_close(gltf_doc *g)
{
    for (uint32_t i = 0; g->buffers && i < g->buffer_count; i++) {
        free(g->buffers[i].owned);
        sl_io_unmap(g->buffers[i].map, g->buffers[i].map_size);
    }
    for (uint32_t i = 0; g->views && i < g->view_count; i++)
        free(g->views[i].decoded);
    for (uint64_t i = 0; g->draws && i < g->draw_count; i++)
        if (g->draws[i].decoded) {
            sl_draco_mesh_release(g->draws[i].decoded);
            free(g->draws[i].decoded);
        }
    free(g->buffers), free(g->views), free(g->accessors);
    free(g->mesh_tok), free(g->node_tok), free(g->material_tok), free(g->texture_tok);
    free(g->image_tok), free(g->draws);
    sl_jdoc_release(&g->j);
    memset(g, 0, sizeof *g);
}
