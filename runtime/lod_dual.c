/* The dual of a cut's marching-cube surface (lod_dual.h). */
#include "runtime/lod_dual.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

static sl_mc_triangles dual_uniform[256];
static uint8_t uniform_loops[256][SL_DUAL_UNIFORM_ROW];
static pthread_once_t loops_once = PTHREAD_ONCE_INIT;
static atomic_int loops_ready; /* set once built: later calls skip pthread_once */

void sl_dual_loops(const sl_mc_cell *cell, sl_mc_triangles *out)
{
    sl_mc_triangulate(cell, out);
    sl_mc_split_double_passes(cell, out);
}

static void build_uniform_loops(void)
{
    for (int c = 0; c < 256; c++) {
        sl_mc_cell cell;
        memset(&cell, 0, sizeof cell);
        cell.inside = (uint8_t)c;
        sl_dual_loops(&cell, &dual_uniform[c]);
        const sl_mc_triangles *u = &dual_uniform[c];
        uint8_t *row = uniform_loops[c];
        int at = 5;
        row[0] = u->loops;
        for (int l = 0; l < u->loops && l < 4; l++) {
            row[1 + l] = u->loop_sizes[l];
            for (int j = 0; j < u->loop_sizes[l] && at < SL_DUAL_UNIFORM_ROW; j++)
                row[at++] = (uint8_t)u->loop_points[l][j];
        }
    }
    atomic_store_explicit(&loops_ready, 1, memory_order_release);
}

const uint8_t (*sl_dual_uniform_loops(void))[SL_DUAL_UNIFORM_ROW]
{
    if (!atomic_load_explicit(&loops_ready, memory_order_acquire))
        pthread_once(&loops_once, build_uniform_loops);
    return (const uint8_t(*)[SL_DUAL_UNIFORM_ROW])uniform_loops;
}

const sl_mc_triangles *sl_dual_uniform_table(void)
{
    if (!atomic_load_explicit(&loops_ready, memory_order_acquire))
        pthread_once(&loops_once, build_uniform_loops);
    return dual_uniform;
}

void sl_dual_loop_vertices(const sl_octree *t, uint32_t n, const sl_mc_triangles *tri,
                           const uint32_t point_crossing[SL_MC_MAX_POINTS],
                           uint32_t vertex[SL_MC_MAX_LOOPS])
{
    const sl_octree_node *node = &t->nodes[n];
    uint32_t first = t->vertex_first[n], count = t->vertex_first[n + 1] - first;
    const uint8_t *row = sl_dual_uniform_loops()[node->inside];
    uint32_t own[SL_OCTREE_MAX_NODE_VERTICES][12];
    int own_size[SL_OCTREE_MAX_NODE_VERTICES], taken = 0, at = 5;
    for (int u = 0; u < row[0] && u < SL_OCTREE_MAX_NODE_VERTICES; u++) {
        own_size[u] = row[1 + u];
        for (int j = 0; j < own_size[u]; j++)
            own[u][j] = sl_octree_crossing(t, node, row[at++]);
    }
    for (int l = 0; l < tri->loops; l++) {
        vertex[l] = SL_DUAL_NOT_DRAWN;
        if (tri->loop_sizes[l] < 3 || count == 0)
            continue;
        int best = -1, best_shared = 0;
        for (uint32_t u = 0; u < (uint32_t)row[0] && u < count; u++) {
            if (taken >> u & 1)
                continue;
            int shared = 0;
            for (int i = 0; i < tri->loop_sizes[l]; i++) {
                uint32_t c = point_crossing[tri->loop_points[l][i]];
                for (int j = 0; j < own_size[u]; j++)
                    shared += own[u][j] == c;
            }
            if (shared > best_shared) {
                best_shared = shared;
                best = (int)u;
            }
        }
        if (best < 0 && row[0] == 0 && !(taken & 1))
            best = 0; /* the vertex of a cell without loops of its own */
        if (best >= 0) {
            taken |= 1 << best;
            vertex[l] = first + (uint32_t)best;
        } else {
            vertex[l] = SL_DUAL_EXTRA;
        }
    }
}

int sl_mesh_builder_dual(sl_mesh_builder *b, const float *positions, const uint8_t *colors,
                         uint32_t count)
{
    sl_mesh_scratch *s = b->scratch;
    b->dual_position = positions;
    b->dual_color = colors;
    if (s->vertex_of_dual && s->dual_count == count)
        return 0;
    free(s->vertex_of_dual);
    s->vertex_of_dual = malloc((count ? count : 1) * sizeof *s->vertex_of_dual);
    s->dual_count = s->vertex_of_dual ? count : 0;
    if (!s->vertex_of_dual) {
        b->failed = 1;
        return -1;
    }
    memset(s->vertex_of_dual, 0xff, (size_t)count * sizeof *s->vertex_of_dual);
    return 0;
}

void sl_mesh_builder_add_loop(sl_mesh_builder *b, uint32_t vertex, const uint32_t *crossings,
                              int n)
{
    sl_mesh_scratch *s = b->scratch;
    if (b->failed || n < 3)
        return;
    if (sl_mesh_grow((void **)&s->slots, &s->slot_capacity, s->slot_count + (uint64_t)n,
                     sizeof *s->slots) ||
        sl_mesh_grow((void **)&s->touched, &s->touched_capacity, s->touched_count + (uint64_t)n,
                     sizeof *s->touched)) {
        b->failed = 1;
        return;
    }
    for (int j = 0; j < n; j++) {
        uint32_t c = crossings[j];
        uint32_t head = s->vertex_of_crossing[c];
        if (head == SL_OCTREE_NONE)
            s->touched[s->touched_count++] = c;
        s->slots[s->slot_count] = (sl_dual_slot){vertex, crossings[j ? j - 1 : n - 1],
                                                 crossings[j + 1 < n ? j + 1 : 0], head};
        s->vertex_of_crossing[c] = (uint32_t)s->slot_count++;
    }
}

#define MAX_DEGREE SL_DUAL_MAX_DEGREE


/* The loops around one crossing in their order around it: each next loop is the one
 * across the segment the previous one leaves the crossing by (its `prev` is the
 * previous loop's `next`). Starts at a loop no other leads to (an open fan), else at the
 * first added. Loops that fit no chain (a broken surface) follow in order. */
static int chain(const sl_dual_slot *slots, const uint32_t *ids, int k, uint32_t order[])
{
    int start = 0, used[MAX_DEGREE] = {0};
    for (int a = 0; a < k; a++) {
        int led = 0;
        for (int c = 0; c < k && !led; c++)
            led = c != a && slots[ids[c]].next == slots[ids[a]].prev;
        if (!led) {
            start = a;
            break;
        }
    }
    int cur = start;
    for (int n = 0; n < k; n++) {
        used[cur] = 1;
        order[n] = ids[cur];
        int next = -1;
        for (int c = 0; c < k && next < 0; c++)
            if (!used[c] && slots[ids[c]].prev == slots[ids[cur]].next)
                next = c;
        for (int c = 0; c < k && next < 0; c++)
            if (!used[c])
                next = c;
        cur = next;
    }
    return k;
}

/* The dual edges made so far (polygon sides and diagonals), for triangulating a polygon
 * without drawing an edge two polygons already have: where levels meet, two loops
 * opposite around one crossing can be neighbours around another, and a diagonal between
 * them would be an edge of four triangles. Open addressing over 64-bit pair keys. */
typedef struct edge_set {
    uint64_t *keys; /* 0: empty */
    uint64_t mask;
} edge_set;

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32 | b) + 1 : ((uint64_t)b << 32 | a) + 1;
}

static uint64_t *edge_slot(const edge_set *e, uint64_t key)
{
    uint64_t i = (key * 0x9E3779B97F4A7C15ull) >> 20 & e->mask;
    while (e->keys[i] && e->keys[i] != key)
        i = (i + 1) & e->mask;
    return &e->keys[i];
}

static int has_edge(const edge_set *e, uint32_t a, uint32_t b)
{
    return *edge_slot(e, edge_key(a, b)) != 0;
}

static void add_edge(edge_set *e, uint32_t a, uint32_t b)
{
    uint64_t key = edge_key(a, b);
    *edge_slot(e, key) = key;
}

/* Squared distance from point x to the segment between vertices a and b. */
static float segment_distance2(const float *positions, const float x[3], uint32_t a, uint32_t b)
{
    const float *p = positions + 3 * (size_t)a, *q = positions + 3 * (size_t)b;
    float d[3], w[3], dd = 0, dw = 0;
    for (int i = 0; i < 3; i++) {
        d[i] = q[i] - p[i];
        w[i] = x[i] - p[i];
        dd += d[i] * d[i];
        dw += d[i] * w[i];
    }
    float s = dd > 0 ? dw / dd : 0, r = 0;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    for (int i = 0; i < 3; i++) {
        float e = w[i] - s * d[i];
        r += e * e;
    }
    return r;
}

/* Triangles of the polygon p[0..k) (counter-clockwise) around crossing point x into tri,
 * 3 dual vertex ids each: ears are cut one at a time, the one whose new diagonal passes
 * nearest the crossing (a point of the surface the polygon stands for) among those no
 * polygon has yet (among all when every one has). Returns k - 2. */
static int triangulate_polygon(const float *positions, const float x[3], edge_set *edges,
                               uint32_t *p, int k, uint32_t *tri)
{
    int count = 0;
    while (k > 3) {
        int best = -1, best_free = 0;
        float best_d = 0;
        for (int i = 0; i < k; i++) {
            uint32_t a = p[(i + k - 1) % k], c = p[(i + 1) % k];
            int is_free = !has_edge(edges, a, c);
            float d = segment_distance2(positions, x, a, c);
            if (best < 0 || is_free > best_free || (is_free == best_free && d < best_d)) {
                best = i;
                best_free = is_free;
                best_d = d;
            }
        }
        uint32_t a = p[(best + k - 1) % k], b = p[best], c = p[(best + 1) % k];
        tri[3 * count] = a;
        tri[3 * count + 1] = b;
        tri[3 * count + 2] = c;
        count++;
        add_edge(edges, a, c);
        memmove(p + best, p + best + 1, (size_t)(k - best - 1) * sizeof *p);
        k--;
    }
    tri[3 * count] = p[0];
    tri[3 * count + 1] = p[1];
    tri[3 * count + 2] = p[2];
    return count + 1;
}

/* The polygon around crossing c (its loops' vertices, counter-clockwise) into poly;
 * returns its size (0 when under 3). Clears the crossing's list. */
static int polygon_of(sl_mesh_scratch *s, uint32_t c, uint32_t *poly)
{
    uint32_t ids[MAX_DEGREE], order[MAX_DEGREE];
    int k = 0;
    for (uint32_t slot = s->vertex_of_crossing[c]; slot != SL_OCTREE_NONE; slot = s->slots[slot].link)
        if (k < MAX_DEGREE)
            ids[k++] = slot;
    s->vertex_of_crossing[c] = SL_OCTREE_NONE;
    if (k < 3)
        return 0;
    for (int a = 0, z = k - 1; a < z; a++, z--) { /* the list runs newest first */
        uint32_t x = ids[a];
        ids[a] = ids[z];
        ids[z] = x;
    }
    chain(s->slots, ids, k, order);
    /* Loops run with the inside on their left (clockwise seen from outside), so the
     * chain turns counter-clockwise: the polygon faces out. */
    for (int j = 0; j < k; j++)
        poly[j] = s->slots[order[j]].vertex;
    return k;
}

void sl_mesh_builder_dual_polygons(sl_mesh_builder *b)
{
    sl_mesh_scratch *s = b->scratch;
    /* The polygons (size, crossing, then vertices; at most one word per slot and two per
     * crossing), their sides into the edge set, then their triangles. */
    /* The set holds each polygon side once (a side is two polygons', so slot_count / 2 of
     * them) and k - 3 diagonals per k-gon: under 1.5 slot_count keys, about 0.75 for
     * quads. Twice slot_count slots keeps its load under 0.75, typically 0.2-0.4. */
    uint64_t need = 1;
    while (need < 2 * s->slot_count + 64)
        need *= 2;
    if (sl_mesh_grow((void **)&s->edge_keys, &s->edge_capacity, need, sizeof *s->edge_keys) ||
        sl_mesh_grow((void **)&s->polygons, &s->polygon_capacity,
                     s->slot_count + 2 * s->touched_count + 1, sizeof *s->polygons)) {
        b->failed = 1;
        return;
    }
    memset(s->edge_keys, 0, need * sizeof *s->edge_keys);
    edge_set edges = {s->edge_keys, need - 1};
    uint32_t *polys = s->polygons;
    uint64_t at = 0, count = 0;
    for (uint64_t i = 0; i < s->touched_count; i++) {
        uint32_t poly[MAX_DEGREE];
        int k = polygon_of(s, s->touched[i], poly);
        if (k == 0)
            continue;
        polys[at++] = (uint32_t)k;
        polys[at++] = s->touched[i];
        for (int j = 0; j < k; j++) {
            polys[at++] = poly[j];
            add_edge(&edges, poly[j], poly[(j + 1) % k]);
        }
        count++;
    }
    for (uint64_t i = 0, from = 0; i < count && !b->failed; i++) {
        int k = (int)polys[from];
        const float *x = b->tree->crossing_position + 3 * (size_t)polys[from + 1];
        uint32_t poly[MAX_DEGREE], tri[3 * (MAX_DEGREE - 2)];
        memcpy(poly, polys + from + 2, (size_t)k * sizeof *poly);
        from += 2 + (uint64_t)k;
        int n = triangulate_polygon(b->dual_position, x, &edges, poly, k, tri);
        uint32_t *out = sl_mesh_builder_triangle_slots(b, n);
        if (!out)
            break;
        for (int j = 0; j < 3 * n; j++)
            out[j] = sl_mesh_builder_dual_vertex(b, tri[j]);
        b->mesh.triangle_count += (uint64_t)n;
    }
    for (uint64_t i = 0; i < s->touched_count; i++)
        s->vertex_of_crossing[s->touched[i]] = SL_OCTREE_NONE;
    s->touched_count = s->slot_count = 0;
}
