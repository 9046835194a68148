/* glTF 2.0 / GLB reader (docs/inputs.md, "glTF"): every primitive the default scene draws
 * onto one sl_mesh, with its node's transform applied (positions by the world matrix,
 * normals by its inverse transpose, winding turned where the matrix mirrors), texture
 * coordinates turned to the mesh's convention (v up: glTF's origin is the image's top
 * left), vertex colours from linear to sRGB bytes. KHR_draco_mesh_compression primitives
 * are decoded through the Draco shim; attributes the Draco stream does not hold are read
 * from their accessors, as the extension allows.
 *
 * Attributes the mesh keeps: normals and colours when every drawn primitive has them
 * (else dropped, with a warning); texture coordinates when any has them (NaN where a
 * primitive has none or draws another material than the textured one). glTF says metres
 * and +Y up: the mesh's units and up axis say so.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "formats/gltf_internal.h"
#include "shim/draco_shim.h"

enum { ATTR_POSITION, ATTR_NORMAL, ATTR_COLOR, ATTR_TEXCOORD, ATTR_COUNT };

typedef struct fill {
    gltf_doc *g;
    sl_mesh *m;
    uint64_t v0;              /* the draw's first vertex in the mesh */
    int keep[ATTR_COUNT];     /* the mesh has that array */
} fill;

static double det3(const double w[16])
{
    return w[0] * (w[5] * w[10] - w[9] * w[6]) - w[4] * (w[1] * w[10] - w[9] * w[2]) +
           w[8] * (w[1] * w[6] - w[5] * w[2]);
}

static void transform(const double w[16], float *p, uint64_t n)
{
    for (uint64_t i = 0; i < n; i++, p += 3) {
        double x = p[0], y = p[1], z = p[2];
        for (int r = 0; r < 3; r++)
            p[r] = sl_ply_to_float(w[r] * x + w[4 + r] * y + w[8 + r] * z + w[12 + r]);
    }
}

/* Normals by the cofactor matrix (the inverse transpose times the determinant), unit. */
static void transform_normals(const double w[16], float *p, uint64_t n)
{
    double c[9];
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            c[3 * r + k] = w[4 * k1 + r1] * w[4 * k2 + r2] - w[4 * k2 + r1] * w[4 * k1 + r2];
        }
    for (uint64_t i = 0; i < n; i++, p += 3) {
        double v[3];
        for (int r = 0; r < 3; r++)
            v[r] = c[3 * r] * p[0] + c[3 * r + 1] * p[1] + c[3 * r + 2] * p[2];
        double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int r = 0; r < 3; r++)
            p[r] = len > 0 ? (float)(v[r] / len) : 0.0f;
    }
}

static uint8_t srgb_byte(float linear)
{
    double c = linear <= 0 ? 0 : linear >= 1 ? 1 : linear;
    double s = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1 / 2.4) - 0.055;
    return (uint8_t)lround(s * 255.0);
}

static uint32_t component_of(int draco_type)
{
    static const uint32_t map[] = {GLTF_FLOAT, GLTF_UNSIGNED_BYTE, GLTF_UNSIGNED_SHORT,
                                   GLTF_BYTE, GLTF_SHORT, GLTF_UNSIGNED_INT};
    return draco_type >= 0 && draco_type < 6 ? map[draco_type] : 0;
}

/* Attribute `k` (accessor `acc`) of the draw as `want` floats per vertex into out: Draco's
 * decoded values where its stream has them, else the accessor's. */
static int read_attribute(fill *f, const gltf_draw *d, int k, uint32_t acc, int want, float *out,
                          const char *what)
{
    const sl_draco_mesh *dm = d->decoded;
    if (dm && d->slot[k] >= 0) {
        const sl_draco_attribute *a = &dm->attributes[d->slot[k]];
        uint32_t comp = component_of(a->type);
        gltf_convert(a->data, comp, f->g->accessors[acc].normalized, a->components,
                     (uint64_t)a->components * gltf_component_size(comp), dm->vertex_count,
                     want, out);
        return 0;
    }
    if (dm && (f->g->accessors[acc].view == GLTF_NONE ||
               f->g->accessors[acc].count != dm->vertex_count))
        return gltf_error(f->g, SL_E_BADINPUT, "a Draco primitive's %s is neither in its stream "
                          "nor in a bufferView of its decoded vertex count", what);
    return gltf_read_floats(f->g, acc, want, out, what);
}

static int read_colors(fill *f, const gltf_draw *d)
{
    uint64_t n = d->vertices;
    float *rgba = malloc(n * 4 * sizeof *rgba + 1);
    if (!rgba)
        return sl_error_nomem(f->g->s->err, f->g->s->name, "out of memory for colours");
    int vec3 = f->g->accessors[d->color].components == 3;
    int rc = read_attribute(f, d, ATTR_COLOR, d->color, 4, rgba, "COLOR_0");
    uint8_t *out = f->m->colors + 4 * f->v0;
    for (uint64_t i = 0; !rc && i < n; i++) {
        for (int c = 0; c < 3; c++)
            out[4 * i + c] = srgb_byte(rgba[4 * i + c]);
        double a = vec3 ? 1.0 : rgba[4 * i + 3];
        out[4 * i + 3] = (uint8_t)lround((a < 0 ? 0 : a > 1 ? 1 : a) * 255.0);
    }
    free(rgba);
    return rc;
}

static int read_vertices(fill *f, const gltf_draw *d)
{
    sl_mesh *m = f->m;
    int rc = read_attribute(f, d, ATTR_POSITION, d->position, 3, m->positions + 3 * f->v0,
                            "POSITION");
    if (!rc)
        transform(d->world, m->positions + 3 * f->v0, d->vertices);
    if (!rc && f->keep[ATTR_NORMAL] &&
        !(rc = read_attribute(f, d, ATTR_NORMAL, d->normal, 3, m->normals + 3 * f->v0, "NORMAL")))
        transform_normals(d->world, m->normals + 3 * f->v0, d->vertices);
    if (!rc && f->keep[ATTR_COLOR])
        rc = read_colors(f, d);
    if (rc || !f->keep[ATTR_TEXCOORD])
        return rc;
    float *uv = m->texcoords + 2 * f->v0;
    if (d->texcoord == GLTF_NONE ||
        (f->g->texture_image != GLTF_NONE && d->material != f->g->texture_material)) {
        for (uint64_t i = 0; i < 2 * d->vertices; i++)
            uv[i] = NAN;
        return 0;
    }
    rc = read_attribute(f, d, ATTR_TEXCOORD, d->texcoord, 2, uv, "TEXCOORD");
    const double *t = f->g->uv_transform;
    int transform = f->g->uv_transform_set && d->material == f->g->texture_material;
    for (uint64_t i = 0; !rc && i < d->vertices; i++) {
        double u = uv[2 * i], v = uv[2 * i + 1];
        if (transform) /* KHR_texture_transform, in glTF's own uv space */
            u = t[0] * uv[2 * i] + t[2] * v + t[4], v = t[1] * uv[2 * i] + t[3] * v + t[5];
        uv[2 * i] = (float)u;
        uv[2 * i + 1] = (float)(1.0 - v); /* glTF: v down from the top */
    }
    return rc;
}

/* The draw's triangles from its `n` indices (idx NULL: 0, 1, 2, ...) by its mode. */
static void emit_triangles(fill *f, const gltf_draw *d, const uint32_t *idx, uint64_t n, int mode)
{
    sl_mesh *m = f->m;
    uint64_t count = mode == 4 ? n / 3 : mode == 5 || mode == 6 ? (n >= 3 ? n - 2 : 0) : 0;
    int flip = det3(d->world) < 0;
    for (uint64_t t = 0; t < count; t++) {
        uint64_t c[3] = {3 * t, 3 * t + 1, 3 * t + 2};
        if (mode == 5) /* strip: every other triangle turned to keep one winding */
            c[0] = t, c[1] = t + 1 + t % 2, c[2] = t + 2 - t % 2;
        else if (mode == 6) /* fan */
            c[0] = t + 1, c[1] = t + 2, c[2] = 0;
        uint32_t *out = m->triangles + 3 * m->triangle_count++;
        for (int k = 0; k < 3; k++)
            out[flip && k ? 3 - k : k] = (uint32_t)(f->v0 + (idx ? idx[c[k]] : c[k]));
    }
}

static int draw_plain(fill *f, const gltf_draw *d)
{
    uint32_t *idx = NULL;
    uint64_t n = d->indices != GLTF_NONE ? f->g->accessors[d->indices].count : d->vertices;
    int rc = read_vertices(f, d);
    if (!rc && d->indices != GLTF_NONE) {
        if (!(idx = malloc(n * sizeof *idx + 1)))
            return sl_error_nomem(f->g->s->err, f->g->s->name, "out of memory for indices");
        rc = gltf_read_indices(f->g, d->indices, d->vertices, idx);
    }
    if (!rc)
        emit_triangles(f, d, idx, n, d->mode);
    free(idx);
    return rc;
}

static int draw_draco(fill *f, const gltf_draw *d)
{
    int rc = read_vertices(f, d);
    if (!rc)
        emit_triangles(f, d, d->decoded->triangles, 3 * d->decoded->triangle_count, 4);
    return rc;
}

/* ---- Draco, decoded before the mesh is allocated: its counts are the stream's ---- */

/* The stream's attribute ids for every attribute the draw has. */
static int draco_request(gltf_doc *g, gltf_draw *d, sl_draco_mesh *dm)
{
    static const char *const names[ATTR_COUNT] = {"POSITION", "NORMAL", "COLOR_0", NULL};
    const uint32_t accessors[ATTR_COUNT] = {d->position, d->normal, d->color, d->texcoord};
    const sl_jdoc *j = &g->j;
    uint32_t attrs = sl_jdoc_get(j, d->draco, "attributes");
    char texcoord[16];
    snprintf(texcoord, sizeof texcoord, "TEXCOORD_%d",
             d->material == g->texture_material ? g->texcoord_set : 0);
    for (int k = 0; k < ATTR_COUNT; k++) {
        uint64_t id;
        d->slot[k] = -1;
        if (accessors[k] == GLTF_NONE ||
            sl_jdoc_index(j, sl_jdoc_get(j, attrs, names[k] ? names[k] : texcoord), 1u << 30,
                          &id) != 1)
            continue;
        d->slot[k] = dm->attribute_count;
        dm->attributes[dm->attribute_count++] =
            (sl_draco_attribute){.unique_id = (int)id, .type = SL_DRACO_ANY};
    }
    if (d->slot[ATTR_POSITION] < 0)
        return gltf_error(g, SL_E_BADINPUT, "a Draco primitive names no POSITION attribute");
    return 0;
}

/* The decoded counts become the draw's (real files differ from their accessors by a few
 * vertices: Draco splits some); indices are checked against them. */
static int draco_counts(gltf_doc *g, gltf_draw *d, const sl_draco_mesh *dm)
{
    for (uint64_t i = 0; i < 3 * dm->triangle_count; i++)
        if (dm->triangles[i] >= dm->vertex_count)
            return gltf_error(g, SL_E_BADINPUT, "a Draco stream's triangle names vertex %u of "
                              "%llu", dm->triangles[i], (unsigned long long)dm->vertex_count);
    if (dm->vertex_count != d->vertices || dm->triangle_count != d->triangles)
        gltf_warn(g, "a Draco stream decodes to %llu vertices and %llu triangles where its "
                  "accessors say %llu and %llu", (unsigned long long)dm->vertex_count,
                  (unsigned long long)dm->triangle_count, (unsigned long long)d->vertices,
                  (unsigned long long)d->triangles);
    d->vertices = dm->vertex_count;
    d->triangles = dm->triangle_count;
    return 0;
}

static int draco_decode(gltf_doc *g, gltf_draw *d)
{
    uint32_t view;
    const unsigned char *bytes;
    uint64_t size;
    int got = gltf_index(g, d->draco, "bufferView", g->view_count, "KHR_draco_mesh_compression",
                         &view), rc;
    if (got <= 0)
        return got < 0 ? got : gltf_error(g, SL_E_BADINPUT, "a Draco primitive has no bufferView");
    if (d->mode != 4)
        return gltf_error(g, SL_E_UNSUPPORTED, "a Draco primitive of mode %d (only triangles)",
                          d->mode);
    if (!(d->decoded = calloc(1, sizeof *d->decoded)))
        return sl_error_nomem(g->s->err, g->s->name, "out of memory for a Draco mesh");
    if ((rc = draco_request(g, d, d->decoded)) || (rc = gltf_view_bytes(g, view, &bytes, &size)))
        return rc;
    sl_error e;
    sl_error_init(&e);
    if (sl_draco_decode(bytes, (size_t)size, d->decoded, &e))
        return gltf_error(g, e.code == SL_E_NOMEM ? SL_E_NOMEM : SL_E_BADINPUT,
                          "bufferViews[%u]: %s", view, e.message);
    return draco_counts(g, d, d->decoded);
}

/* Nodes may draw one mesh many times: what a small file can ask for is bounded by its
 * bytes (and its buffers'), so a hostile scene cannot multiply a mesh into gigabytes. */
static int check_expansion(const gltf_doc *g, uint64_t vertices, uint64_t triangles)
{
    uint64_t bytes = g->s->size;
    for (uint32_t i = 0; i < g->buffer_count; i++)
        bytes += g->buffers[i].map_size;
    if (vertices / GLTF_MAX_EXPANSION <= bytes && triangles / GLTF_MAX_EXPANSION <= bytes)
        return 0;
    return gltf_error(g, SL_E_LIMIT, "the scene draws %llu vertices and %llu triangles from "
                      "%llu bytes (more than %d per byte: instancing)", (unsigned long long)vertices,
                      (unsigned long long)triangles, (unsigned long long)bytes, GLTF_MAX_EXPANSION);
}

/* The accessors a plain draw reads, checked against their data before any allocation
 * from their counts. */
static int check_draw(gltf_doc *g, const gltf_draw *d)
{
    const uint32_t acc[5] = {d->position, d->normal, d->color, d->texcoord, d->indices};
    static const char *const what[5] = {"POSITION", "NORMAL", "COLOR_0", "TEXCOORD",
                                        "indices"};
    int rc = 0;
    for (int k = 0; !rc && k < 5; k++)
        if (acc[k] != GLTF_NONE)
            rc = gltf_check_accessor(g, acc[k], what[k]);
    return rc;
}

/* Every Draco draw decoded, every other one's accessors checked; the scene's counts
 * against the limits again. */
static int prepare_draws(gltf_doc *g, uint64_t *vertices, uint64_t *triangles)
{
    int rc = 0;
    *vertices = *triangles = 0;
    for (uint64_t i = 0; !rc && i < g->draw_count; i++) {
        gltf_draw *d = &g->draws[i];
        rc = d->draco ? draco_decode(g, d) : check_draw(g, d);
        if (!rc && (__builtin_add_overflow(*vertices, d->vertices, vertices) ||
                    __builtin_add_overflow(*triangles, d->triangles, triangles)))
            rc = gltf_error(g, SL_E_LIMIT, "the scene's counts overflow");
    }
    if (!rc)
        rc = scan_check_limit(g->s, "vertices", *vertices, g->s->lim->max_vertices);
    if (!rc)
        rc = scan_check_limit(g->s, "triangles", *triangles, g->s->lim->max_faces);
    return rc ? rc : check_expansion(g, *vertices, *triangles);
}

/* Which arrays the mesh gets (see the file comment), warning about partial ones. */
static int alloc_mesh(fill *f, uint64_t vertices, uint64_t triangles)
{
    gltf_doc *g = f->g;
    sl_mesh *m = f->m;
    uint64_t with[ATTR_COUNT] = {0};
    for (uint64_t i = 0; i < g->draw_count; i++) {
        with[ATTR_NORMAL] += g->draws[i].normal != GLTF_NONE;
        with[ATTR_COLOR] += g->draws[i].color != GLTF_NONE;
        with[ATTR_TEXCOORD] += g->draws[i].texcoord != GLTF_NONE;
    }
    f->keep[ATTR_NORMAL] = g->draw_count && with[ATTR_NORMAL] == g->draw_count;
    f->keep[ATTR_COLOR] = g->draw_count && with[ATTR_COLOR] == g->draw_count;
    f->keep[ATTR_TEXCOORD] = with[ATTR_TEXCOORD] > 0;
    if (with[ATTR_COLOR] && !f->keep[ATTR_COLOR])
        gltf_warn(g, "COLOR_0 on %llu of %llu primitives: not used",
                  (unsigned long long)with[ATTR_COLOR], (unsigned long long)g->draw_count);
    int rc = 0;
    m->positions = scan_alloc(g->s, vertices, 3 * sizeof(float), &rc);
    m->triangles = scan_alloc(g->s, triangles, 3 * sizeof(uint32_t), &rc);
    if (f->keep[ATTR_NORMAL])
        m->normals = scan_alloc(g->s, vertices, 3 * sizeof(float), &rc);
    if (f->keep[ATTR_COLOR])
        m->colors = scan_alloc(g->s, vertices, 4, &rc);
    if (f->keep[ATTR_TEXCOORD])
        m->texcoords = scan_alloc(g->s, vertices, 2 * sizeof(float), &rc);
    return rc;
}

int gltf_fill(gltf_doc *g, sl_mesh *m)
{
    fill f = {.g = g, .m = m};
    uint64_t vertices, triangles;
    int rc = prepare_draws(g, &vertices, &triangles);
    if (!rc)
        rc = alloc_mesh(&f, vertices, triangles);
    for (uint64_t i = 0; !rc && i < g->draw_count; i++) {
        const gltf_draw *d = &g->draws[i];
        rc = d->draco ? draw_draco(&f, d) : draw_plain(&f, d);
        f.v0 += d->vertices;
        if (!rc)
            rc = scan_tick(g->s, g->s->data + (g->s->size * (i + 1)) / g->draw_count);
    }
    m->vertex_count = rc ? 0 : vertices;
    return rc;
}

/* ---- the texture ---- */

static void texture_file(gltf_doc *g, sl_mesh *m, uint32_t uri)
{
    char name[1024], path[4096];
    gltf_uri_name(g, uri, name, sizeof name);
    if (strlen(name) >= sizeof m->texture_file || sl_scan_sibling_path(".", name, path, 8) == -1) {
        gltf_warn(g, "texture '%.200s': not a name inside the file's folder; not used", name);
        return;
    }
    snprintf(m->texture_file, sizeof m->texture_file, "%.255s", name); /* fits: checked */
    if (g->s->dir && sl_scan_sibling_path(g->s->dir, name, path, sizeof path) == 0 &&
        access(path, R_OK) != 0)
        gltf_warn(g, "%s: missing", name);
}

/* The embedded image of images[i] (a bufferView or a data: URI) into the mesh. */
static int texture_bytes(gltf_doc *g, sl_mesh *m, uint32_t img, uint32_t uri)
{
    const unsigned char *bytes = NULL;
    unsigned char *owned = NULL;
    uint64_t size = 0;
    uint32_t view;
    char mime[64] = "";
    int rc;
    if (uri) {
        rc = gltf_data_uri(g, uri, &owned, &size, mime, sizeof mime, "the texture image");
        bytes = owned;
    } else if ((rc = gltf_index(g, img, "bufferView", g->view_count, "images", &view)) > 0) {
        sl_jdoc_string(&g->j, sl_jdoc_get(&g->j, img, "mimeType"), mime, sizeof mime);
        rc = gltf_view_bytes(g, view, &bytes, &size);
    } else if (rc == 0) {
        rc = gltf_error(g, SL_E_BADINPUT, "the texture image has neither uri nor bufferView");
    }
    if (!rc && (m->texture_data = malloc(size ? size : 1))) {
        memcpy(m->texture_data, bytes, size);
        m->texture_size = size;
        snprintf(m->texture_mime, sizeof m->texture_mime, "%.31s", mime);
    } else if (!rc) {
        rc = sl_error_nomem(g->s->err, g->s->name, "out of memory for the texture image");
    }
    free(owned);
    return rc;
}

/* The texture: a broken image is a warning, as a missing one is (the geometry stands). */
static int set_texture(gltf_doc *g, sl_mesh *m)
{
    if (g->texture_image == GLTF_NONE)
        return 0;
    uint32_t img = g->image_tok[g->texture_image], uri = sl_jdoc_get(&g->j, img, "uri");
    if (uri && sl_jdoc_type(&g->j, uri) == SL_JDOC_STRING && !gltf_is_data_uri(g, uri)) {
        texture_file(g, m, uri);
        return 0;
    }
    sl_error e; /* an image's own error stays a warning */
    sl_error_init(&e);
    scan_src local = *g->s;
    local.err = &e;
    const scan_src *keep = g->s;
    g->s = &local;
    int rc = texture_bytes(g, m, img, uri && sl_jdoc_type(&g->j, uri) == SL_JDOC_STRING ? uri : 0);
    g->s = keep;
    if (rc == SL_E_NOMEM || rc == SL_E_INTERRUPTED) {
        sl_error_merge(g->s->err, &e);
        return rc;
    }
    if (rc)
        gltf_warn(g, "images[%u]: %s; no texture", g->texture_image, e.message);
    return 0;
}

/* ---- entry points ---- */

static void fill_info(const gltf_doc *g, sl_scan_info *info)
{
    char generator[64] = "";
    uint64_t vertices = 0, triangles = 0, normals = 0, colors = 0, uvs = 0, draco = 0;
    for (uint64_t i = 0; i < g->draw_count; i++) {
        const gltf_draw *d = &g->draws[i];
        vertices += d->vertices, triangles += d->triangles, draco += d->draco != 0;
        normals += d->normal != GLTF_NONE, colors += d->color != GLTF_NONE;
        uvs += d->texcoord != GLTF_NONE;
    }
    sl_jdoc_string(&g->j, sl_jdoc_get(&g->j, sl_jdoc_get(&g->j, 0, "asset"), "generator"),
                   generator, sizeof generator);
    snprintf(info->format, sizeof info->format, "%s", g->glb ? "glb" : "gltf");
    snprintf(info->detail, sizeof info->detail, "glTF 2.0%s, generator '%s', %u meshes, %llu "
             "primitives drawn (%llu Draco), %u images", g->glb ? " binary (GLB)" : "", generator,
             g->mesh_count, (unsigned long long)g->draw_count, (unsigned long long)draco,
             g->image_count);
    info->declared_vertices = vertices;
    info->declared_faces = triangles;
    info->has_normals = g->draw_count && normals == g->draw_count;
    info->has_colors = g->draw_count && colors == g->draw_count;
    info->has_texcoords = uvs > 0;
}

int sl_gltf_info_source(const scan_src *s, sl_scan_info *info)
{
    gltf_doc g;
    int rc = gltf_open(&g, s, NULL);
    if (!rc && !(rc = gltf_plan(&g)))
        fill_info(&g, info);
    gltf_close(&g);
    return rc;
}

int sl_gltf_read_source(const scan_src *s, sl_mesh *out, sl_scan_info *info)
{
    gltf_doc g;
    int rc = gltf_open(&g, s, out);
    if (!rc && !(rc = gltf_plan(&g)) && info)
        fill_info(&g, info);
    if (!rc && !(rc = gltf_fill(&g, out)))
        rc = set_texture(&g, out);
    if (!rc) { /* glTF 2.0, 3.4: "units for all linear distances are meters", +Y up */
        snprintf(out->units, sizeof out->units, "m");
        out->up_axis = 'y';
    }
    gltf_close(&g);
    return rc;
}
