/* What a glTF file's default scene draws (gltf_internal.h): its nodes walked from the
 * roots with their transforms composed, one draw per primitive per node that shows a mesh,
 * the counts of each checked against the limits, and the texture the mesh carries.
 *
 * The default scene is `scene`, else scenes[0]; a file without scenes draws the nodes no
 * other node names as a child, and a file without nodes draws each mesh once as it is.
 * Nodes must form trees (glTF 2.0, 5.25: a node has at most one parent, no cycles): a
 * node reached twice is refused, so a hostile file cannot multiply its instances. The
 * texture: the baseColorTexture of the first drawn primitive's material that has one
 * (its image through `source`, or an extension's source: KHR_texture_basisu,
 * EXT_texture_webp, EXT_texture_avif), with its KHR_texture_transform (gltfpack writes one
 * for the quantised texture coordinates it makes).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/gltf_internal.h"

typedef struct walk {
    gltf_doc *g;
    uint8_t *seen;        /* per node */
    uint64_t cap;         /* of g->draws */
    uint64_t vertices, triangles;
    int lines_skipped;
} walk;

static void mat_identity(double m[16])
{
    memset(m, 0, 16 * sizeof *m);
    m[0] = m[5] = m[10] = m[15] = 1;
}

static void mat_mul(const double a[16], const double b[16], double out[16])
{
    double r[16];
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            double v = 0;
            for (int k = 0; k < 4; k++)
                v += a[k * 4 + row] * b[c * 4 + k];
            r[c * 4 + row] = v;
        }
    memcpy(out, r, sizeof r);
}

/* `n` numbers of array member `key` into v (left as they are when absent). */
static int numbers(const gltf_doc *g, uint32_t node, const char *key, int n, double *v)
{
    uint32_t t = sl_jdoc_get(&g->j, node, key);
    if (!t)
        return 0;
    if (sl_jdoc_type(&g->j, t) != SL_JDOC_ARRAY || g->j.tokens[t].count != (uint32_t)n)
        return gltf_error(g, SL_E_BADINPUT, "a node's %s is not %d numbers", key, n);
    for (int k = 0; k < n; k++)
        if (!sl_jdoc_number(&g->j, sl_jdoc_item(&g->j, t, (uint32_t)k), &v[k]))
            return gltf_error(g, SL_E_BADINPUT, "a node's %s is not %d numbers", key, n);
    return 0;
}

/* The node's local transform: `matrix`, or translation * rotation * scale. */
static int local_matrix(const gltf_doc *g, uint32_t node, double m[16])
{
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    int rc;
    mat_identity(m);
    if (sl_jdoc_get(&g->j, node, "matrix"))
        return numbers(g, node, "matrix", 16, m);
    if ((rc = numbers(g, node, "translation", 3, t)) || (rc = numbers(g, node, "rotation", 4, q)) ||
        (rc = numbers(g, node, "scale", 3, s)))
        return rc;
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                   2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                   2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++)
        for (int row = 0; row < 3; row++)
            m[c * 4 + row] = r[c * 3 + row] * s[c];
    m[12] = t[0], m[13] = t[1], m[14] = t[2];
    return 0;
}

/* An attribute accessor of the primitive: its index, or GLTF_NONE. */
static int attribute(const gltf_doc *g, uint32_t attrs, const char *name, uint64_t vertices,
                     uint32_t *out)
{
    uint32_t a = GLTF_NONE;
    int got = gltf_index(g, attrs, name, g->accessor_count, "attributes", &a);
    *out = got > 0 ? a : GLTF_NONE;
    if (got > 0 && g->accessors[a].count != vertices)
        return gltf_error(g, SL_E_BADINPUT, "a primitive's %s has %llu elements, its POSITION "
                          "%llu", name, (unsigned long long)g->accessors[a].count,
                          (unsigned long long)vertices);
    return got < 0 ? got : 0;
}

static uint64_t triangles_of(int mode, uint64_t n)
{
    return mode == 4 ? n / 3 : (mode == 5 || mode == 6) && n >= 3 ? n - 2 : 0;
}

static int add_draw(walk *w, const gltf_draw *d)
{
    gltf_doc *g = w->g;
    int rc = 0;
    if (g->draw_count == GLTF_MAX_DRAWS)
        return gltf_error(g, SL_E_LIMIT, "more than %u primitives drawn", GLTF_MAX_DRAWS);
    if ((rc = scan_reserve(g->s, (void **)&g->draws, &w->cap, g->draw_count + 1, sizeof *d)))
        return rc;
    g->draws[g->draw_count++] = *d;
    if (__builtin_add_overflow(w->vertices, d->vertices, &w->vertices) ||
        __builtin_add_overflow(w->triangles, d->triangles, &w->triangles))
        return gltf_error(g, SL_E_LIMIT, "the scene's counts overflow");
    if ((rc = scan_check_limit(g->s, "vertices", w->vertices, g->s->lim->max_vertices)))
        return rc;
    return scan_check_limit(g->s, "triangles", w->triangles, g->s->lim->max_faces);
}

/* The attributes, indices, mode and material of primitive token p into d. */
static int describe_primitive(walk *w, uint32_t p, gltf_draw *d)
{
    gltf_doc *g = w->g;
    uint32_t attrs = sl_jdoc_get(&g->j, p, "attributes");
    uint64_t mode = 4;
    int rc, got;
    d->primitive = p;
    d->material = d->indices = GLTF_NONE;
    if ((got = gltf_index(g, attrs, "POSITION", g->accessor_count, "attributes",
                          &d->position)) <= 0)
        return got < 0 ? got : 1; /* nothing to draw */
    d->vertices = g->accessors[d->position].count;
    if (sl_jdoc_index(&g->j, sl_jdoc_get(&g->j, p, "mode"), 7, &mode) < 0)
        return gltf_error(g, SL_E_BADINPUT, "a primitive's mode is not 0..6");
    if ((rc = gltf_index(g, p, "indices", g->accessor_count, "indices", &d->indices)) < 0 ||
        (rc = gltf_index(g, p, "material", g->material_count, "material", &d->material)) < 0)
        return rc;
    d->mode = (int)mode;
    if (mode >= 1 && mode <= 3) {
        w->lines_skipped++;
        return 1;
    }
    d->triangles = triangles_of(d->mode, d->indices != GLTF_NONE ? g->accessors[d->indices].count
                                                                 : d->vertices);
    d->draco = sl_jdoc_get(&g->j, sl_jdoc_get(&g->j, p, "extensions"),
                           "KHR_draco_mesh_compression");
    if ((rc = attribute(g, attrs, "NORMAL", d->vertices, &d->normal)) ||
        (rc = attribute(g, attrs, "COLOR_0", d->vertices, &d->color)))
        return rc;
    d->texcoord = GLTF_NONE; /* chosen once the texture is known (gltf_plan) */
    return 0;
}

static int draw_mesh(walk *w, uint32_t mesh, const double world[16])
{
    gltf_doc *g = w->g;
    uint32_t prims = sl_jdoc_get(&g->j, g->mesh_tok[mesh], "primitives");
    if (sl_jdoc_type(&g->j, prims) != SL_JDOC_ARRAY)
        return gltf_error(g, SL_E_BADINPUT, "meshes[%u] has no primitives array", mesh);
    uint32_t n = g->j.tokens[prims].count;
    for (uint32_t i = 0, p = prims + 1; i < n; i++, p = g->j.tokens[p].next) {
        gltf_draw d;
        memset(&d, 0, sizeof d);
        memcpy(d.world, world, sizeof d.world);
        int rc = describe_primitive(w, p, &d);
        if (rc < 0 || (rc == 0 && (rc = add_draw(w, &d))))
            return rc;
    }
    return 0;
}

static int walk_node(walk *w, uint32_t node, const double parent[16], int depth);

/* Each node of index array `list` (its tokens followed in order: O(n)). */
static int walk_list(walk *w, uint32_t list, const double parent[16], int depth,
                     const char *where)
{
    gltf_doc *g = w->g;
    uint32_t n = sl_jdoc_type(&g->j, list) == SL_JDOC_ARRAY ? g->j.tokens[list].count : 0;
    for (uint32_t i = 0, k = list + 1; i < n; i++, k = g->j.tokens[k].next) {
        uint64_t node;
        if (sl_jdoc_index(&g->j, k, g->node_count, &node) != 1)
            return gltf_error(g, SL_E_BADINPUT, "%s: not a node index", where);
        int rc = walk_node(w, (uint32_t)node, parent, depth);
        if (rc)
            return rc;
    }
    return 0;
}

static int walk_node(walk *w, uint32_t node, const double parent[16], int depth)
{
    gltf_doc *g = w->g;
    uint32_t t = g->node_tok[node], mesh;
    double local[16], world[16];
    int rc;
    if (depth > GLTF_MAX_DEPTH || w->seen[node]++)
        return gltf_error(g, SL_E_BADINPUT, "nodes[%u] is reached twice or nested deeper than "
                          "%d: the nodes are not trees", node, GLTF_MAX_DEPTH);
    if ((rc = local_matrix(g, t, local)))
        return rc;
    mat_mul(parent, local, world);
    if ((rc = gltf_index(g, t, "mesh", g->mesh_count, "node.mesh", &mesh)) < 0 ||
        (rc > 0 && (rc = draw_mesh(w, mesh, world))))
        return rc;
    char where[48];
    snprintf(where, sizeof where, "nodes[%u].children", node);
    return walk_list(w, sl_jdoc_get(&g->j, t, "children"), world, depth + 1, where);
}

/* The default scene's root nodes (`scene`, else scenes[0]). */
static int walk_roots(walk *w)
{
    gltf_doc *g = w->g;
    double id[16];
    mat_identity(id);
    uint64_t scene = 0;
    if (sl_jdoc_index(&g->j, sl_jdoc_get(&g->j, 0, "scene"), 1u << 31, &scene) < 0)
        return gltf_error(g, SL_E_BADINPUT, "'scene' is not an index");
    uint32_t st = sl_jdoc_item(&g->j, g->scenes, (uint32_t)scene);
    if (!st)
        return g->j.tokens[g->scenes].count ? gltf_error(g, SL_E_BADINPUT, "scene %llu does not "
                                                         "exist", (unsigned long long)scene) : 0;
    return walk_list(w, sl_jdoc_get(&g->j, st, "nodes"), id, 0, "scenes[].nodes");
}

/* No scenes: the nodes that are nobody's child; no nodes: every mesh once. */
static int walk_sceneless(walk *w)
{
    gltf_doc *g = w->g;
    double id[16];
    mat_identity(id);
    int rc = 0;
    if (!g->node_count) {
        for (uint32_t m = 0; !rc && m < g->mesh_count; m++)
            rc = draw_mesh(w, m, id);
        return rc;
    }
    uint8_t *child = calloc(g->node_count, 1);
    if (!child)
        return sl_error_nomem(g->s->err, g->s->name, "out of memory for the nodes");
    for (uint32_t n = 0; n < g->node_count; n++) {
        uint32_t kids = sl_jdoc_get(&g->j, g->node_tok[n], "children"), count;
        uint64_t c;
        count = sl_jdoc_type(&g->j, kids) == SL_JDOC_ARRAY ? g->j.tokens[kids].count : 0;
        for (uint32_t i = 0, k = kids + 1; i < count; i++, k = g->j.tokens[k].next)
            if (sl_jdoc_index(&g->j, k, g->node_count, &c) == 1)
                child[c] = 1;
    }
    for (uint32_t n = 0; !rc && n < g->node_count; n++)
        if (!child[n])
            rc = walk_node(w, n, id, 0);
    free(child);
    return rc;
}

/* The image of texture `tex`: `source`, or an image extension's. */
static int texture_source(const gltf_doc *g, uint32_t tex, uint32_t *image)
{
    static const char *const exts[] = {"KHR_texture_basisu", "EXT_texture_webp",
                                       "EXT_texture_avif"};
    uint32_t t = g->texture_tok[tex];
    int got = gltf_index(g, t, "source", g->image_count, "textures.source", image);
    uint32_t ext = sl_jdoc_get(&g->j, t, "extensions");
    for (size_t i = 0; !got && i < sizeof exts / sizeof exts[0]; i++)
        got = gltf_index(g, sl_jdoc_get(&g->j, ext, exts[i]), "source", g->image_count,
                         exts[i], image);
    return got;
}

/* KHR_texture_transform on the texture's textureInfo (its README: the matrix is
 * translation * rotation * scale on (u, v, 1)); its texCoord replaces the info's. */
static int texture_transform(gltf_doc *g, uint32_t info, uint32_t *set)
{
    uint32_t t = sl_jdoc_get(&g->j, sl_jdoc_get(&g->j, info, "extensions"),
                             "KHR_texture_transform");
    double offset[2] = {0, 0}, scale[2] = {1, 1}, r = 0;
    int rc;
    if (!t)
        return 0;
    if ((rc = numbers(g, t, "offset", 2, offset)) || (rc = numbers(g, t, "scale", 2, scale)) ||
        (rc = gltf_index(g, t, "texCoord", 8, "KHR_texture_transform", set)) < 0)
        return rc;
    sl_jdoc_number(&g->j, sl_jdoc_get(&g->j, t, "rotation"), &r);
    double c = cos(r), s = sin(r);
    double m[6] = {c * scale[0], s * scale[0], -s * scale[1], c * scale[1], offset[0], offset[1]};
    memcpy(g->uv_transform, m, sizeof m);
    g->uv_transform_set = 1;
    return 0;
}

/* The first drawn material with a baseColorTexture: g->texture_image and its set. */
static int choose_texture(gltf_doc *g)
{
    for (uint64_t i = 0; i < g->draw_count; i++) {
        uint32_t mat = g->draws[i].material, tex;
        if (mat == GLTF_NONE)
            continue;
        uint32_t pbr = sl_jdoc_get(&g->j, g->material_tok[mat], "pbrMetallicRoughness");
        uint32_t info = sl_jdoc_get(&g->j, pbr, "baseColorTexture");
        uint32_t set = 0;
        int got = gltf_index(g, info, "index", g->texture_count, "baseColorTexture", &tex), rc;
        if (got < 0 || (rc = gltf_index(g, info, "texCoord", 8, "baseColorTexture", &set)) < 0)
            return got < 0 ? got : rc;
        if (got && (rc = texture_source(g, tex, &g->texture_image)) != 0) {
            if (rc > 0)
                rc = texture_transform(g, info, &set);
            g->texcoord_set = (int)set;
            g->texture_material = mat;
            return rc < 0 ? rc : 0;
        }
    }
    return 0;
}

/* Each draw's texture coordinates: TEXCOORD_n of the texture for its material's draws,
 * TEXCOORD_0 for the others. */
static int choose_texcoords(gltf_doc *g)
{
    for (uint64_t i = 0; i < g->draw_count; i++) {
        gltf_draw *d = &g->draws[i];
        char name[16];
        int set = d->material == g->texture_material ? g->texcoord_set : 0;
        snprintf(name, sizeof name, "TEXCOORD_%d", set);
        uint32_t attrs = sl_jdoc_get(&g->j, d->primitive, "attributes");
        int rc = attribute(g, attrs, name, d->vertices, &d->texcoord);
        if (rc)
            return rc;
    }
    return 0;
}

int gltf_plan(gltf_doc *g)
{
    walk w = {.g = g};
    int rc = 0;
    if (g->node_count && !(w.seen = calloc(g->node_count, 1)))
        return sl_error_nomem(g->s->err, g->s->name, "out of memory for the nodes");
    rc = g->scenes ? walk_roots(&w) : walk_sceneless(&w);
    free(w.seen);
    if (!rc && w.lines_skipped)
        gltf_warn(g, "%d line primitives are not read", w.lines_skipped);
    if (!rc && (rc = choose_texture(g)) == 0)
        rc = choose_texcoords(g);
    return rc;
}
