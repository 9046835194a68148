/* Texture coordinates for a level from the input's own (docs/glb.md "Textures"): a level
 * whose vertices are not the input's (a collapsed, fitted or octree level) takes, at each
 * corner, the input's texture coordinate where the corner lies on the input surface, and
 * embeds the input's image as it is, instead of baking an atlas of its own.
 *
 * The input's image is an atlas of charts (photogrammetry writes hundreds): its texture
 * coordinates jump where two charts meet (a seam). A level triangle takes the chart of the
 * input triangle nearest to its centre; a corner that lies on that chart takes the
 * coordinate there, one that lies across a seam takes the coordinate the chart's nearest
 * triangle would give it, continued past its edge (the triangle's affine map), so that
 * the level triangle reads one chart and no triangle spans the atlas. Corners of one level
 * vertex with different coordinates become separate vertices (the seams of the level).
 * Every step is per triangle or per corner: parallel, and the same on any thread count. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/export/export_internal.h"

void sl_export_input_uv(const sl_mesh *in, uint32_t tri, int k, double uv[2])
{
    if (in->face_texcoords) {
        uv[0] = in->face_texcoords[6 * (uint64_t)tri + 2 * k];
        uv[1] = in->face_texcoords[6 * (uint64_t)tri + 2 * k + 1];
    } else {
        uint32_t v = in->triangles[3 * (uint64_t)tri + k];
        uv[0] = in->texcoords[2 * (uint64_t)v], uv[1] = in->texcoords[2 * (uint64_t)v + 1];
    }
}

static uint32_t find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
    return x;
}

typedef struct edge_ref {
    uint64_t key;  /* the two vertices, lower first */
    uint32_t tri;
    uint8_t corner; /* the edge runs from this corner to the next */
} edge_ref;

static int by_key(const void *a, const void *b)
{
    const edge_ref *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->tri < y->tri ? -1 : x->tri > y->tri;
}

/* Whether triangles a and b, sharing the edge of vertices (p, q), give p and q the same
 * texture coordinates on both sides: the edge is inside a chart, not a seam. */
static int same_uv(const sl_mesh *in, uint32_t a, uint32_t b, uint32_t p, uint32_t q)
{
    for (int side = 0; side < 2; side++) {
        uint32_t v = side ? q : p;
        double ua[2] = {NAN, NAN}, ub[2] = {NAN, NAN};
        for (int k = 0; k < 3; k++) {
            if (in->triangles[3 * (uint64_t)a + k] == v)
                sl_export_input_uv(in, a, k, ua);
            if (in->triangles[3 * (uint64_t)b + k] == v)
                sl_export_input_uv(in, b, k, ub);
        }
        if (!(ua[0] == ub[0] && ua[1] == ub[1]))
            return 0;
    }
    return 1;
}

int sl_export_texture_charts(const sl_mesh *in, uint32_t **chart)
{
    uint64_t tn = in->triangle_count;
    uint32_t *parent = malloc((tn + 1) * sizeof *parent);
    edge_ref *edges = in->face_texcoords ? malloc((3 * tn + 1) * sizeof *edges) : NULL;
    if (!parent || (in->face_texcoords && !edges)) {
        free(parent), free(edges);
        return -1;
    }
    for (uint64_t t = 0; t < tn; t++)
        parent[t] = (uint32_t)t;
    if (!in->face_texcoords) {
        /* one coordinate per vertex (glTF, a split OBJ): a seam is where the file has two
         * vertices, so a chart is a region of triangles joined by shared vertices */
        uint32_t *first = malloc((in->vertex_count + 1) * sizeof *first);
        if (!first) {
            free(parent);
            return -1;
        }
        memset(first, 0xff, (in->vertex_count + 1) * sizeof *first);
        for (uint64_t t = 0; t < tn; t++)
            for (int k = 0; k < 3; k++) {
                uint32_t v = in->triangles[3 * t + k];
                if (first[v] == UINT32_MAX) {
                    first[v] = (uint32_t)t;
                    continue;
                }
                uint32_t ra = find(parent, first[v]), rb = find(parent, (uint32_t)t);
                parent[ra > rb ? ra : rb] = ra < rb ? ra : rb;
            }
        free(first);
        for (uint64_t t = 0; t < tn; t++)
            parent[t] = find(parent, (uint32_t)t);
        *chart = parent;
        return 0;
    }
    for (uint64_t t = 0; t < tn; t++)
        for (int k = 0; k < 3; k++) {
            uint64_t p = in->triangles[3 * t + k], q = in->triangles[3 * t + (k + 1) % 3];
            uint64_t key = p < q ? p << 32 | q : q << 32 | p;
            edges[3 * t + k] = (edge_ref){key, (uint32_t)t, (uint8_t)k};
        }
    qsort(edges, 3 * tn, sizeof *edges, by_key);
    for (uint64_t i = 0; i < 3 * tn;) {
        uint64_t j = i + 1;
        while (j < 3 * tn && edges[j].key == edges[i].key)
            j++;
        uint32_t p = (uint32_t)(edges[i].key >> 32), q = (uint32_t)edges[i].key;
        for (uint64_t a = i; a < j; a++) /* every pair of the edge's triangles (2 on a manifold) */
            for (uint64_t b = a + 1; b < j; b++)
                if (same_uv(in, edges[a].tri, edges[b].tri, p, q)) {
                    uint32_t ra = find(parent, edges[a].tri), rb = find(parent, edges[b].tri);
                    parent[ra > rb ? ra : rb] = ra < rb ? ra : rb;
                }
        i = j;
    }
    for (uint64_t t = 0; t < tn; t++)
        parent[t] = find(parent, (uint32_t)t);
    free(edges);
    *chart = parent;
    return 0;
}

void sl_export_plane_weights(const double p[3], const double a[3], const double b[3],
                             const double c[3], double w[3])
{
    double e0[3], e1[3], d[3], d00 = 0, d01 = 0, d11 = 0, d20 = 0, d21 = 0;
    for (int k = 0; k < 3; k++)
        e0[k] = b[k] - a[k], e1[k] = c[k] - a[k], d[k] = p[k] - a[k];
    for (int k = 0; k < 3; k++) {
        d00 += e0[k] * e0[k], d01 += e0[k] * e1[k], d11 += e1[k] * e1[k];
        d20 += d[k] * e0[k], d21 += d[k] * e1[k];
    }
    double den = d00 * d11 - d01 * d01;
    if (!(fabs(den) > 0)) {
        w[0] = w[1] = w[2] = 1.0 / 3;
        return;
    }
    w[1] = (d11 * d20 - d01 * d21) / den;
    w[2] = (d00 * d21 - d01 * d20) / den;
    w[0] = 1 - w[1] - w[2];
}

/* The texture coordinate input triangle `tri` (tree order `leaf`) gives point p. */
static void uv_at(const sl_export_texture *src, uint32_t leaf, const double p[3], float uv[2])
{
    const float *c = src->bvh.corners + 9 * (uint64_t)leaf;
    double a[3] = {c[0], c[1], c[2]}, b[3] = {c[3], c[4], c[5]}, cc[3] = {c[6], c[7], c[8]};
    double w[3], out[2] = {0, 0};
    sl_export_plane_weights(p, a, b, cc, w);
    uint32_t tri = src->bvh.source[leaf];
    for (int k = 0; k < 3; k++) {
        double t[2];
        sl_export_input_uv(src->input, tri, k, t);
        out[0] += w[k] * t[0], out[1] += w[k] * t[1];
    }
    for (int k = 0; k < 2; k++) /* the GLB stores them normalised (CLAMP_TO_EDGE) */
        uv[k] = (float)(out[k] < 0 ? 0 : out[k] > 1 ? 1 : out[k]);
}

typedef struct corner_key {
    uint32_t vertex;
    float u, v;
    uint32_t corner;
} corner_key;

static int by_vertex_uv(const void *a, const void *b)
{
    const corner_key *x = a, *y = b;
    if (x->vertex != y->vertex)
        return x->vertex < y->vertex ? -1 : 1;
    if (x->u != y->u)
        return x->u < y->u ? -1 : 1;
    if (x->v != y->v)
        return x->v < y->v ? -1 : 1;
    return x->corner < y->corner ? -1 : x->corner > y->corner;
}

int sl_export_project_uvs(const sl_export_texture *src, const sl_lod_mesh *level,
                          sl_export_baked *out, uint64_t *continued, sl_error *err)
{
    memset(out, 0, sizeof *out);
    uint64_t tn = level->triangle_count, cn = 3 * tn, beyond = 0;
    corner_key *keys = malloc((cn + 1) * sizeof *keys);
    uint32_t *index = malloc((cn + 1) * sizeof *index);
    if (!keys || !index) {
        free(keys), free(index);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory for texture coordinates");
    }
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : beyond)
    for (int64_t t = 0; t < (int64_t)tn; t++) {
        double p[3][3], centre[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++) {
                p[k][d] = level->positions[3 * (uint64_t)level->indices[3 * t + k] + d];
                centre[d] += p[k][d] / 3;
            }
        sl_closest home;
        sl_triangle_bvh_closest(&src->bvh, centre, UINT32_MAX, &home);
        uint32_t chart = src->chart[src->bvh.source[home.triangle]];
        for (int k = 0; k < 3; k++) {
            sl_closest hit;
            sl_triangle_bvh_closest(&src->bvh, p[k], home.triangle, &hit);
            int across = src->chart[src->bvh.source[hit.triangle]] != chart;
            float uv[2];
            uv_at(src, across ? home.triangle : hit.triangle, across ? p[k] : hit.point, uv);
            beyond += (uint64_t)across;
            uint64_t corner = 3 * (uint64_t)t + (uint64_t)k;
            keys[corner] = (corner_key){level->indices[corner], uv[0], uv[1], (uint32_t)corner};
        }
    }
    qsort(keys, cn, sizeof *keys, by_vertex_uv);
    uint64_t vn = 0;
    for (uint64_t i = 0; i < cn; i++) {
        if (i == 0 || keys[i].vertex != keys[i - 1].vertex || keys[i].u != keys[i - 1].u ||
            keys[i].v != keys[i - 1].v)
            vn++;
        index[keys[i].corner] = (uint32_t)(vn - 1);
    }
    out->positions = malloc((vn + 1) * 3 * sizeof(float));
    out->normals = level->normals ? malloc((vn + 1) * 3 * sizeof(float)) : NULL;
    out->texcoords = malloc((vn + 1) * 2 * sizeof(float));
    out->triangles = malloc((cn + 1) * sizeof(uint32_t));
    if (!out->positions || (level->normals && !out->normals) || !out->texcoords ||
        !out->triangles) {
        free(keys), free(index);
        sl_export_baked_release(out);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory for texture coordinates");
    }
    for (uint64_t i = 0; i < cn; i++) {
        uint64_t o = index[keys[i].corner], v = keys[i].vertex;
        memcpy(out->positions + 3 * o, level->positions + 3 * v, 3 * sizeof(float));
        if (out->normals)
            memcpy(out->normals + 3 * o, level->normals + 3 * v, 3 * sizeof(float));
        out->texcoords[2 * o] = keys[i].u, out->texcoords[2 * o + 1] = keys[i].v;
    }
    memcpy(out->triangles, index, cn * sizeof *index);
    out->vertex_count = vn;
    out->triangle_count = tn;
    *continued = beyond;
    free(keys), free(index);
    return 0;
}
