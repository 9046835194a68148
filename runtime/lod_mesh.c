/* Welding cells' triangles into an indexed mesh (see lod_mesh.h). */
#include "runtime/lod_mesh.h"

#include "runtime/lod_dual.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void sl_lod_mesh_release(sl_lod_mesh *m)
{
    free(m->positions);
    free(m->normals);
    free(m->colors);
    free(m->indices);
    memset(m, 0, sizeof *m);
}

int sl_mesh_scratch_init(sl_mesh_scratch *s, const sl_octree *tree)
{
    memset(s, 0, sizeof *s);
    size_t n = tree->crossing_count ? tree->crossing_count : 1;
    s->vertex_of_crossing = malloc(n * sizeof *s->vertex_of_crossing);
    if (!s->vertex_of_crossing)
        return -1;
    memset(s->vertex_of_crossing, 0xff, n * sizeof *s->vertex_of_crossing);
    return 0;
}

void sl_mesh_scratch_release(sl_mesh_scratch *s)
{
    sl_mesh_scratch_shrink(s);
    free(s->vertex_of_crossing);
    free(s->vertex_of_dual);
    memset(s, 0, sizeof *s);
}

void sl_mesh_scratch_shrink(sl_mesh_scratch *s)
{
    free(s->used);
    free(s->slots);
    free(s->touched);
    free(s->edge_keys);
    free(s->polygons);
    s->used = NULL;
    s->slots = NULL;
    s->touched = NULL;
    s->edge_keys = NULL;
    s->polygons = NULL;
    s->used_capacity = s->slot_capacity = s->touched_capacity = 0;
    s->edge_capacity = s->polygon_capacity = 0;
    s->slot_count = s->touched_count = 0;
}

int sl_mesh_builder_init(sl_mesh_builder *b, const sl_octree *tree, sl_mesh_scratch *scratch)
{
    memset(b, 0, sizeof *b);
    b->tree = tree;
    if (!scratch) {
        if (sl_mesh_scratch_init(&b->own_scratch, tree))
            return -1;
        scratch = &b->own_scratch;
    }
    b->scratch = scratch;
    return 0;
}

void sl_mesh_builder_use_buffers(sl_mesh_builder *b, const sl_lod_mesh *buffers,
                                 uint64_t vertex_capacity, uint64_t triangle_capacity)
{
    b->mesh = *buffers;
    b->mesh.vertex_count = b->mesh.triangle_count = 0;
    if (!b->tree->crossing_color)
        b->mesh.colors = NULL;
    b->vertex_capacity = vertex_capacity;
    b->triangle_capacity = triangle_capacity;
    b->caller_buffers = 1;
}

/* Capacity for `need` elements: exactly that many when `exact`, else doubling. */
static int grow(void **p, uint64_t *cap, uint64_t need, size_t elem, int exact)
{
    if (need <= *cap)
        return 0;
    if (need > SIZE_MAX / elem) /* no size_t product that wraps into a short block */
        return -1;
    uint64_t n = exact ? need : *cap ? *cap : 1024;
    while (n < need)
        n = n > SIZE_MAX / elem / 2 ? need : 2 * n;
    void *q = realloc(*p, (size_t)n * elem);
    if (!q)
        return -1;
    *p = q;
    *cap = n;
    return 0;
}

static int reserve_vertices(sl_mesh_builder *b, uint64_t need, int exact)
{
    sl_lod_mesh *m = &b->mesh;
    sl_mesh_scratch *s = b->scratch;
    if (grow((void **)&s->used, &s->used_capacity, need, sizeof(uint32_t), exact))
        return -1;
    if (b->caller_buffers) {
        if (need > b->vertex_capacity)
            return -1;
    } else {
        uint64_t cap = b->vertex_capacity, c1 = cap, c2 = cap, c3 = cap;
        if (grow((void **)&m->positions, &c1, need, 3 * sizeof(float), exact) ||
            grow((void **)&m->normals, &c2, need, 3 * sizeof(float), exact) ||
            (b->tree->crossing_color && grow((void **)&m->colors, &c3, need, 4, exact)))
            return -1;
        b->vertex_capacity = c1;
    }
    b->vertex_room = b->vertex_capacity < s->used_capacity ? b->vertex_capacity : s->used_capacity;
    return 0;
}

void sl_mesh_builder_reserve(sl_mesh_builder *b, uint64_t triangles)
{
    /* A closed surface has about half as many vertices as triangles; an open scan's
     * boundary and loop centroids add a few: estimate, the builder grows past it. */
    uint64_t vertices = triangles / 2 + triangles / 16 + 64;
    if (b->caller_buffers) {
        reserve_vertices(b, vertices < b->vertex_capacity ? vertices : b->vertex_capacity, 0);
        return;
    }
    uint64_t cap = b->triangle_capacity;
    if (grow((void **)&b->mesh.indices, &cap, triangles, 3 * sizeof(uint32_t), 1) == 0)
        b->triangle_capacity = cap;
    reserve_vertices(b, vertices, 1);
}

/* A new vertex's normal sum starts at zero here rather than in a pass over the array
 * before the normals: no second pass, and no call into libc's memset, whose code a small
 * cut from cold caches would fetch. */
static inline void zero_normal(sl_lod_mesh *m, uint64_t v)
{
    if (m->normals)
        m->normals[3 * v] = m->normals[3 * v + 1] = m->normals[3 * v + 2] = 0.0f;
}

/* Vertex index of a crossing, mapping it on first use. */
static inline uint32_t vertex_of(sl_mesh_builder *b, uint32_t crossing)
{
    uint32_t v = b->scratch->vertex_of_crossing[crossing];
    if (v != SL_OCTREE_NONE)
        return v;
    sl_lod_mesh *m = &b->mesh;
    if (m->vertex_count >= b->vertex_room && reserve_vertices(b, m->vertex_count + 1, 0)) {
        b->failed = 1;
        return 0;
    }
    v = (uint32_t)m->vertex_count++;
    const float *p = b->tree->crossing_position + 3 * (size_t)crossing;
    float *q = m->positions + 3 * (size_t)v;
    q[0] = p[0];
    q[1] = p[1];
    q[2] = p[2];
    zero_normal(m, v);
    if (m->colors)
        memcpy(m->colors + 4 * (size_t)v, b->tree->crossing_color + 4 * (size_t)crossing, 4);
    b->scratch->used[v] = crossing;
    b->scratch->vertex_of_crossing[crossing] = v;
    return v;
}

/* A cell's own vertex at the mean of a loop (not in the crossing table). */
static uint32_t centroid_vertex(sl_mesh_builder *b, const sl_mc_triangles *tri, int loop,
                                const uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    sl_lod_mesh *m = &b->mesh;
    if (reserve_vertices(b, m->vertex_count + 1, 0)) {
        b->failed = 1;
        return 0;
    }
    uint32_t v = (uint32_t)m->vertex_count++;
    double sum[3] = {0, 0, 0}, col[4] = {0, 0, 0, 0};
    int n = tri->loop_sizes[loop];
    for (int i = 0; i < n; i++) {
        uint32_t c = point_crossing[tri->loop_points[loop][i]];
        for (int a = 0; a < 3; a++)
            sum[a] += b->tree->crossing_position[3 * (size_t)c + a];
        if (m->colors)
            for (int k = 0; k < 4; k++)
                col[k] += b->tree->crossing_color[4 * (size_t)c + k];
    }
    for (int a = 0; a < 3; a++)
        m->positions[3 * (size_t)v + a] = (float)(sum[a] / n);
    zero_normal(m, v);
    if (m->colors)
        for (int k = 0; k < 4; k++)
            m->colors[4 * (size_t)v + k] = (uint8_t)lround(col[k] / n);
    b->scratch->used[v] = SL_OCTREE_NONE;
    return v;
}

/* Room for `count` more triangles; 0, or -1 (and failed) when out of memory or past the
 * caller's capacity. */
static int reserve_triangles(sl_mesh_builder *b, int count)
{
    sl_lod_mesh *m = &b->mesh;
    if (m->triangle_count + (uint64_t)count <= b->triangle_capacity)
        return 0;
    uint64_t cap = b->triangle_capacity;
    if (b->caller_buffers || grow((void **)&m->indices, &cap, m->triangle_count + (uint64_t)count,
                                  3 * sizeof(uint32_t), 0)) {
        b->failed = 1;
        return -1;
    }
    b->triangle_capacity = cap;
    return 0;
}

/* Where the next `count` triangles' indices go, or NULL when there is nothing to add or
 * no room (the builder is then failed). The caller fills them and counts them in. */
static inline uint32_t *triangle_slots(sl_mesh_builder *b, int count)
{
    if (b->failed || count == 0 || reserve_triangles(b, count))
        return NULL;
    return b->mesh.indices + 3 * (size_t)b->mesh.triangle_count;
}

uint32_t *sl_mesh_builder_triangle_slots(sl_mesh_builder *b, int count)
{
    return triangle_slots(b, count);
}

int sl_mesh_grow(void **p, uint64_t *cap, uint64_t need, size_t elem)
{
    return grow(p, cap, need, elem, 0);
}

uint32_t sl_mesh_builder_dual_vertex(sl_mesh_builder *b, uint32_t id)
{
    sl_mesh_scratch *s = b->scratch;
    uint32_t v = s->vertex_of_dual[id];
    if (v != SL_OCTREE_NONE)
        return v;
    sl_lod_mesh *m = &b->mesh;
    if (m->vertex_count >= b->vertex_room && reserve_vertices(b, m->vertex_count + 1, 0)) {
        b->failed = 1;
        return 0;
    }
    v = (uint32_t)m->vertex_count++;
    memcpy(m->positions + 3 * (size_t)v, b->dual_position + 3 * (size_t)id, 3 * sizeof(float));
    zero_normal(m, v);
    if (m->colors)
        memcpy(m->colors + 4 * (size_t)v, b->dual_color + 4 * (size_t)id, 4);
    s->used[v] = id;
    s->vertex_of_dual[id] = v;
    return v;
}

void sl_mesh_builder_add_triangles(sl_mesh_builder *b, int count, const uint8_t *points,
                                   const uint32_t *point_crossing)
{
    uint32_t *out = triangle_slots(b, count);
    if (!out)
        return;
    for (int i = 0; i < 3 * count; i++)
        out[i] = vertex_of(b, point_crossing[points[i]]);
    b->mesh.triangle_count += (uint64_t)count;
}

void sl_mesh_builder_add_crossing_triangles(sl_mesh_builder *b, int count,
                                            const uint32_t *crossings)
{
    uint32_t *out = triangle_slots(b, count);
    if (!out)
        return;
    for (int i = 0; i < 3 * count; i++)
        out[i] = vertex_of(b, crossings[i]);
    b->mesh.triangle_count += (uint64_t)count;
}

void sl_mesh_builder_add_cell(sl_mesh_builder *b, const sl_mc_triangles *tri,
                              const uint32_t point_crossing[SL_MC_MAX_POINTS])
{
    if (b->failed || tri->count == 0)
        return;
    if (!tri->centroids) { /* every point is a crossing */
        sl_mesh_builder_add_triangles(b, tri->count, &tri->points[0][0], point_crossing);
        return;
    }
    uint32_t centroid[SL_MC_MAX_LOOPS];
    for (int l = 0; l < tri->loops; l++)
        if (tri->centroids >> l & 1)
            centroid[l] = centroid_vertex(b, tri, l, point_crossing);
    uint32_t *out = triangle_slots(b, tri->count);
    if (!out)
        return;
    for (int t = 0; t < tri->count; t++, out += 3)
        for (int k = 0; k < 3; k++) {
            int p = tri->points[t][k];
            out[k] = p >= SL_MC_MAX_POINTS ? centroid[p - SL_MC_MAX_POINTS]
                                           : vertex_of(b, point_crossing[p]);
        }
    b->mesh.triangle_count += tri->count;
}

/* The power of two that brings a cut's edges below a few units, so the normal sums stay
 * finite however many triangles meet at a vertex: 2^-e for S = 2 (R + 4 FLT_EPSILON F) in
 * [2^e, 2^(e+1)), with R the root cube's edge and F the largest coordinate of its corners.
 * The readers keep every crossing within a leaf and float rounding (2 FLT_EPSILON of the
 * coordinate) of that cube, so an edge spans at most 3 R + 4 FLT_EPSILON F <= 1.5 S: a
 * scaled edge is under 3. The rounding term matters only for a cube far smaller than its
 * distance from zero, where R alone would overflow the products. Computed from the bits:
 * ldexp and ilogb are calls into libm, whose code a small cut from cold caches would fetch
 * for this one number. */
static float normal_scale(const sl_octree *tree)
{
    double root = tree->leaf_size * (double)(1u << tree->depth), far = 0, lo[3], hi[3];
    sl_octree_corner_world(tree, &tree->nodes[0], 0, lo);
    sl_octree_corner_world(tree, &tree->nodes[0], 7, hi);
    for (int a = 0; a < 3; a++) {
        double c = fabs(lo[a]) > fabs(hi[a]) ? fabs(lo[a]) : fabs(hi[a]);
        far = c > far ? c : far;
    }
    double bound = 2 * (root + 4 * FLT_EPSILON * far);
    uint64_t bits;
    memcpy(&bits, &bound, sizeof bits);
    int e = (int)(bits >> 52 & 0x7ff) - 1023; /* a subnormal bound reads as tiny: clamped */
    e = e > 126 ? 126 : e < -126 ? -126 : e;
    uint32_t fbits = (uint32_t)(127 - e) << 23;
    float scale;
    memcpy(&scale, &fbits, sizeof scale);
    return scale;
}

/* Area-weighted vertex normals. The edges are scaled by normal_scale's power of two,
 * which changes no bit of the result (every product and sum scales exactly) but keeps the
 * sums finite however many triangles meet at a vertex and however large the model's
 * coordinates (the octree readers bound them; a file can still make one crossing the
 * corner of millions of triangles). */
static void compute_normals(sl_lod_mesh *m, const sl_octree *tree)
{
    if (m->triangle_count == 0) /* every normal stays zero (zero_normal) */
        return;
    const float scale = normal_scale(tree); /* triangles: the tree has its root, nodes[0] */
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *i = m->indices + 3 * t;
        const float *p0 = m->positions + 3 * (size_t)i[0], *p1 = m->positions + 3 * (size_t)i[1],
                    *p2 = m->positions + 3 * (size_t)i[2];
        float u[3] = {(p1[0] - p0[0]) * scale, (p1[1] - p0[1]) * scale, (p1[2] - p0[2]) * scale};
        float v[3] = {(p2[0] - p0[0]) * scale, (p2[1] - p0[1]) * scale, (p2[2] - p0[2]) * scale};
        float n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++)
                m->normals[3 * (size_t)i[k] + a] += n[a]; /* area-weighted (|n| = 2 area) */
    }
    for (uint64_t v = 0; v < m->vertex_count; v++) {
        float *n = m->normals + 3 * v;
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        if (len > 0)
            for (int a = 0; a < 3; a++)
                n[a] = (float)(n[a] / len);
    }
}

static void reset_scratch(sl_mesh_builder *b)
{
    sl_mesh_scratch *s = b->scratch;
    if (!s)
        return;
    uint64_t made = b->mesh.vertex_count < s->used_capacity ? b->mesh.vertex_count
                                                            : s->used_capacity;
    uint32_t *map = b->dual_position ? s->vertex_of_dual : s->vertex_of_crossing;
    for (uint64_t v = 0; v < made; v++)
        if (s->used[v] != SL_OCTREE_NONE)
            map[s->used[v]] = SL_OCTREE_NONE;
    if (b->dual_position) { /* polygons not made (a failed build) keep their slots */
        for (uint64_t i = 0; i < s->touched_count; i++)
            s->vertex_of_crossing[s->touched[i]] = SL_OCTREE_NONE;
        s->touched_count = s->slot_count = 0;
    }
}

/* Resets the scratch and frees what the builder owns (the mesh too when `mesh_too`). */
static void builder_end(sl_mesh_builder *b, int mesh_too)
{
    reset_scratch(b);
    if (b->scratch == &b->own_scratch)
        sl_mesh_scratch_release(&b->own_scratch);
    b->scratch = NULL;
    if (mesh_too && !b->caller_buffers)
        sl_lod_mesh_release(&b->mesh);
}

int sl_mesh_builder_finish(sl_mesh_builder *b, sl_lod_mesh *out)
{
    sl_lod_mesh *m = &b->mesh;
    if (b->dual_position && !b->failed)
        sl_mesh_builder_dual_polygons(b);
    if (!b->failed && !b->caller_buffers && !m->normals) { /* no vertex was reserved */
        m->normals = malloc(3 * sizeof(float));
        if (!m->normals)
            b->failed = 1;
    }
    if (!b->failed && m->normals)
        compute_normals(m, b->tree);
    builder_end(b, b->failed);
    if (b->failed) {
        memset(m, 0, sizeof *m);
        return -1;
    }
    *out = *m;
    memset(m, 0, sizeof *m);
    return 0;
}

void sl_mesh_builder_abort(sl_mesh_builder *b)
{
    builder_end(b, 1);
    memset(b, 0, sizeof *b);
}

int sl_octree_level_mesh(const sl_octree *tree, uint32_t level, sl_lod_mesh *out)
{
    memset(out, 0, sizeof *out);
    if (level > tree->depth)
        return -1;
    sl_mesh_builder b;
    if (sl_mesh_builder_init(&b, tree, NULL))
        return -1;
    const sl_mc_triangles *table = sl_mc_uniform_table();
    uint32_t first = tree->level_first[level], count = tree->level_count[level];
    for (uint32_t i = 0; i < count; i++) {
        const sl_octree_node *n = &tree->nodes[first + i];
        uint32_t point_crossing[SL_MC_MAX_POINTS];
        for (int e = 0; e < 12; e++)
            point_crossing[e] = (n->edge_mask >> e & 1) ? sl_octree_crossing(tree, n, e) : 0;
        sl_mesh_builder_add_cell(&b, &table[n->inside], point_crossing);
    }
    return sl_mesh_builder_finish(&b, out);
}
