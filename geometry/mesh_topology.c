/* Edge topology: weld equal positions, then count how many triangles share each edge.
 *
 * Welding uses an open-addressing hash of the three coordinates' bit patterns (after
 * -0 -> +0), so it is O(n) and exact: positions merge only when they are equal. Edges
 * are bucketed by their lower welded endpoint (a CSR array: counts, prefix sums, fill),
 * then each small bucket is sorted and its runs counted -- O(n) memory of 4 bytes per
 * edge end instead of sorting 64-bit edge keys. Connected parts: union-find over the
 * welded ids (path halving, union by index), then each triangle's area summed into its
 * part's root.
 */
#include "geometry/mesh_distance.h"
#include "geometry/key_table.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

static uint32_t coordinate_bits(float x)
{
    uint32_t u;
    if (x == 0.0f)
        x = 0.0f; /* -0 and +0 are the same position */
    memcpy(&u, &x, sizeof u);
    return u;
}

static uint64_t position_hash(const uint32_t k[3])
{
    uint64_t h = k[0] * 0x9e3779b97f4a7c15ull;
    h ^= (h >> 29) ^ k[1] * 0xbf58476d1ce4e5b9ull;
    h ^= (h >> 31) ^ k[2] * 0x94d049bb133111ebull;
    return h ^ (h >> 32);
}

static void position_key(const sl_mesh *m, uint32_t v, uint32_t k[3])
{
    for (int a = 0; a < 3; a++)
        k[a] = coordinate_bits(m->positions[3 * (uint64_t)v + a]);
}

/* Below this many triangles or ids the topology's loops run on one thread: a parallel
 * region costs more than it saves. */
#define PARALLEL_MIN 65536

/* Fixed slices of the vertices for the numbering (sl_slice_begin). */
#define WELD_SLICES 64

/* The slot of v's position, returned: the first empty one on its probe sequence is
 * claimed for v (compare-and-swap: two positions racing for one slot, the loser probes
 * on), and a slot already holding the position is lowered to v if v is lower (atomic
 * minimum). Once every vertex is in, a position's slot holds its lowest vertex, on any
 * thread count. */
static uint64_t weld_insert(_Atomic uint32_t *table, uint64_t mask, const sl_mesh *m,
                            uint32_t v)
{
    uint32_t key[3], other[3];
    position_key(m, v, key);
    for (uint64_t slot = position_hash(key) & mask;; slot = (slot + 1) & mask) {
        uint32_t held = atomic_load_explicit(&table[slot], memory_order_relaxed);
        if (held == NONE && atomic_compare_exchange_strong_explicit(
                                &table[slot], &held, v, memory_order_relaxed, memory_order_relaxed))
            return slot;
        position_key(m, held, other); /* held: the slot's vertex, read or lost to */
        if (memcmp(key, other, sizeof key) != 0)
            continue;
        while (v < held && !atomic_compare_exchange_weak_explicit(&table[slot], &held, v,
                                                                  memory_order_relaxed,
                                                                  memory_order_relaxed))
            ;
        return slot;
    }
}

/* The lowest vertex at v's position (v was inserted). */
static uint32_t weld_lookup(_Atomic uint32_t *table, uint64_t mask, const sl_mesh *m, uint32_t v)
{
    uint32_t key[3], other[3];
    position_key(m, v, key);
    for (uint64_t slot = position_hash(key) & mask;; slot = (slot + 1) & mask) {
        uint32_t held = atomic_load_explicit(&table[slot], memory_order_relaxed);
        position_key(m, held, other);
        if (memcmp(key, other, sizeof key) == 0)
            return held;
    }
}

/* Declared in mesh_distance.h (the topology's welding, shared with the simplifier). Ids in
 * the order of each position's first used vertex. In parallel: the used vertices marked,
 * inserted into the table and read back by all threads; a vertex is its position's first
 * when its slot gives itself back; the firsts numbered in fixed slices. */
int64_t sl_mesh_weld_positions(const sl_mesh *m, uint32_t *weld)
{
    uint64_t n = m->vertex_count, corners = 3 * m->triangle_count;
    const int wide = m->triangle_count >= PARALLEL_MIN;
#pragma omp parallel for schedule(static) if (wide)
    for (uint64_t v = 0; v < n; v++)
        weld[v] = NONE;
#pragma omp parallel for schedule(static) if (wide)
    for (uint64_t i = 0; i < corners; i++) {
        uint32_t *mark = &weld[m->triangles[i]];
#pragma omp atomic write
        *mark = 0; /* used (every writer writes the same 0) */
    }
    uint64_t used = 0;
#pragma omp parallel for schedule(static) reduction(+ : used) if (wide)
    for (uint64_t v = 0; v < n; v++)
        used += weld[v] == 0;
    uint64_t cap = 16;
    while (cap < 2 * used)
        cap *= 2;
    _Atomic uint32_t *table = malloc(cap * sizeof *table); /* lowest vertex per slot */
    if (!table)
        return -1;
#pragma omp parallel for schedule(static) if (wide)
    for (uint64_t i = 0; i < cap; i++)
        atomic_init(&table[i], NONE);
    /* A used vertex keeps its slot where the slots fit below NONE (fewer than 2^30 used
     * vertices), so its first vertex is read back without hashing again. */
    const int keep_slot = cap <= (uint64_t)1 << 31;
#pragma omp parallel for schedule(dynamic, 4096) if (wide)
    for (uint64_t v = 0; v < n; v++)
        if (weld[v] == 0) {
            uint64_t slot = weld_insert(table, cap - 1, m, (uint32_t)v);
            if (keep_slot)
                weld[v] = (uint32_t)slot;
        }
    /* weld[v] = the first vertex at v's position, for the used ones */
#pragma omp parallel for schedule(static) if (wide)
    for (uint64_t v = 0; v < n; v++)
        if (weld[v] != NONE)
            weld[v] = keep_slot ? atomic_load_explicit(&table[weld[v]], memory_order_relaxed)
                                : weld_lookup(table, cap - 1, m, (uint32_t)v);
    free(table);
    uint32_t *id = malloc((n ? n : 1) * sizeof *id); /* per first vertex: its id */
    if (!id)
        return -1;
    uint64_t first[WELD_SLICES + 1];
    first[0] = 0;
#pragma omp parallel for schedule(static) if (wide)
    for (int s = 0; s < WELD_SLICES; s++) {
        uint64_t c = 0;
        for (uint64_t v = sl_slice_begin(n, s, WELD_SLICES); v < sl_slice_begin(n, s + 1, WELD_SLICES); v++)
            c += weld[v] == v;
        first[s + 1] = c;
    }
    for (int s = 0; s < WELD_SLICES; s++)
        first[s + 1] += first[s];
#pragma omp parallel for schedule(static) if (wide)
    for (int s = 0; s < WELD_SLICES; s++) {
        uint32_t next = (uint32_t)first[s];
        for (uint64_t v = sl_slice_begin(n, s, WELD_SLICES); v < sl_slice_begin(n, s + 1, WELD_SLICES); v++)
            if (weld[v] == v)
                id[v] = next++;
    }
#pragma omp parallel for schedule(static) if (wide)
    for (uint64_t v = 0; v < n; v++)
        if (weld[v] != NONE)
            weld[v] = id[weld[v]];
    free(id);
    return (int64_t)first[WELD_SLICES];
}

/* Welded corners of triangle t; returns 0 if two coincide (degenerate). */
static int welded_triangle(const sl_mesh *m, const uint32_t *weld, uint64_t t, uint32_t w[3])
{
    for (int c = 0; c < 3; c++)
        w[c] = weld[m->triangles[3 * t + c]];
    return w[0] != w[1] && w[1] != w[2] && w[2] != w[0];
}

/* Each bucket's ends sorted and their runs counted: an edge per run, a border edge for a
 * run of one, a non-manifold edge for a run of three or more. Buckets are independent. */
static void count_edge_runs(uint32_t *ends, const uint64_t *start, uint64_t ids,
                            sl_mesh_topology *out)
{
    uint64_t edges = 0, boundary = 0, nonmanifold = 0;
#pragma omp parallel for schedule(dynamic, 4096) reduction(+ : edges, boundary, nonmanifold) \
    if (ids >= PARALLEL_MIN)
    for (uint64_t lo = 0; lo < ids; lo++) {
        uint64_t n = start[lo + 1] - start[lo];
        uint32_t *v = ends + start[lo];
        sl_sort_run_u32(v, n);
        for (uint64_t i = 0; i < n;) {
            uint64_t j = i + 1;
            while (j < n && v[j] == v[i])
                j++;
            edges++;
            if (j - i == 1)
                boundary++;
            else if (j - i > 2)
                nonmanifold++;
            i = j;
        }
    }
    out->edges += edges;
    out->boundary_edges += boundary;
    out->nonmanifold_edges += nonmanifold;
}

/* Connected parts by a union-find shared by all threads: a root is linked under another
 * only by a compare-and-swap that finds it still a root, always the larger under the
 * smaller, so a set's root is its lowest id whatever the order of the unions (the serial
 * loop's rule, and its result); finding halves the path with stores of an ancestor,
 * which any thread may overwrite with another ancestor. */
static uint32_t find_root(_Atomic uint32_t *parent, uint32_t x)
{
    for (;;) {
        uint32_t up = atomic_load_explicit(&parent[x], memory_order_relaxed);
        if (up == x)
            return x;
        uint32_t above = atomic_load_explicit(&parent[up], memory_order_relaxed);
        if (above != up)
            atomic_store_explicit(&parent[x], above, memory_order_relaxed);
        x = above;
    }
}

static void unite(_Atomic uint32_t *parent, uint32_t a, uint32_t b)
{
    for (;;) {
        a = find_root(parent, a), b = find_root(parent, b);
        if (a == b)
            return;
        uint32_t low = a < b ? a : b, high = a < b ? b : a;
        if (atomic_compare_exchange_strong_explicit(&parent[high], &high, low,
                                                    memory_order_relaxed, memory_order_relaxed))
            return;
    }
}

/* parent[] over `ids` ids, every triangle's welded corners joined (the degenerate ones
 * too unless `skip_degenerate`), then every id pointing at its root. NULL when out of
 * memory. */
static _Atomic uint32_t *join_parts(const sl_mesh *m, const uint32_t *weld, uint64_t ids,
                                    int skip_degenerate)
{
    _Atomic uint32_t *parent = malloc((ids ? ids : 1) * sizeof *parent);
    if (!parent)
        return NULL;
    const int wide = m->triangle_count >= PARALLEL_MIN;
#pragma omp parallel for schedule(static) if (wide)
    for (uint64_t i = 0; i < ids; i++)
        atomic_init(&parent[i], (uint32_t)i);
#pragma omp parallel for schedule(dynamic, 4096) if (wide)
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        uint32_t w[3];
        if (!welded_triangle(m, weld, t, w) && skip_degenerate)
            continue;
        unite(parent, w[0], w[1]);
        unite(parent, w[0], w[2]);
    }
#pragma omp parallel for schedule(static) if (wide)
    for (uint64_t i = 0; i < ids; i++)
        atomic_store_explicit(&parent[i], find_root(parent, (uint32_t)i), memory_order_relaxed);
    return parent;
}

static uint32_t root_of(_Atomic uint32_t *parent, uint32_t id)
{
    return atomic_load_explicit(&parent[id], memory_order_relaxed);
}

static double triangle_area(const sl_mesh *m, uint64_t t)
{
    const float *p[3];
    for (int c = 0; c < 3; c++)
        p[c] = m->positions + 3 * (uint64_t)m->triangles[3 * t + c];
    double u[3], v[3];
    for (int a = 0; a < 3; a++) {
        u[a] = (double)p[1][a] - p[0][a];
        v[a] = (double)p[2][a] - p[0][a];
    }
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* Parts connected through shared welded vertices and their areas; `ids` welded ids.
 * Returns -1 when out of memory. */
static int count_components(const sl_mesh *m, const uint32_t *weld, uint64_t ids,
                            sl_mesh_topology *out)
{
    _Atomic uint32_t *parent = join_parts(m, weld, ids, 1);
    double *area = calloc(ids ? ids : 1, sizeof *area);
    if (!parent || !area) {
        free(parent);
        free(area);
        return -1;
    }
    /* The areas summed in triangle order, on one thread: the same bits as ever. */
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        uint32_t w[3];
        if (!welded_triangle(m, weld, t, w))
            continue;
        double a = triangle_area(m, t);
        area[root_of(parent, w[0])] += a;
        out->area += a;
    }
    uint64_t used = 0;
    for (uint64_t i = 0; i < ids; i++)
        if (root_of(parent, (uint32_t)i) == i && area[i] > 0) {
            used++;
            if (area[i] > out->largest_component_area)
                out->largest_component_area = area[i];
        }
    out->components = used;
    free(parent);
    free(area);
    return 0;
}

int sl_mesh_topology_compute(const sl_mesh *m, sl_mesh_topology *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    if (m->vertex_count > (uint64_t)UINT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "%llu vertices: edge topology handles at most 2^32 - 1",
                            (unsigned long long)m->vertex_count);
    const int wide = m->triangle_count >= PARALLEL_MIN;
    uint32_t *weld = malloc((m->vertex_count ? m->vertex_count : 1) * sizeof *weld);
    int64_t ids = weld ? sl_mesh_weld_positions(m, weld) : -1;
    uint64_t *start = ids >= 0 ? calloc((uint64_t)ids + 2, sizeof *start) : NULL;
    uint32_t *ends = NULL;
    if (start) {
        /* start[lo + 2] counts edges with lower end lo, so that after the prefix sum
         * start[lo + 1] is the fill cursor and, once filled, bucket lo's end. */
        uint64_t degenerate = 0;
#pragma omp parallel for schedule(static) reduction(+ : degenerate) if (wide)
        for (uint64_t t = 0; t < m->triangle_count; t++) {
            uint32_t w[3];
            if (!welded_triangle(m, weld, t, w)) {
                degenerate++;
                continue;
            }
            for (int c = 0; c < 3; c++) {
                uint32_t a = w[c], b = w[(c + 1) % 3];
#pragma omp atomic update
                start[(a < b ? a : b) + 2]++;
            }
        }
        out->degenerate_triangles = degenerate;
        for (int64_t i = 0; i < ids; i++)
            start[i + 2] += start[i + 1];
        ends = malloc((start[ids + 1] ? start[ids + 1] : 1) * sizeof *ends);
    }
    if (!ends) {
        free(weld);
        free(start);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "edge topology of %llu triangles",
                            (unsigned long long)m->triangle_count);
    }
    /* Filled in any order (the buckets are sorted before they are counted). */
#pragma omp parallel for schedule(static) if (wide)
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        uint32_t w[3];
        if (!welded_triangle(m, weld, t, w))
            continue;
        for (int c = 0; c < 3; c++) {
            uint32_t a = w[c], b = w[(c + 1) % 3];
            uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
            uint64_t at;
#pragma omp atomic capture
            at = start[lo + 1]++;
            ends[at] = hi;
        }
    }
    out->welded_vertices = (uint64_t)ids;
    count_edge_runs(ends, start, (uint64_t)ids, out);
    out->watertight = out->edges > 0 && out->boundary_edges == 0 && out->nonmanifold_edges == 0;
    free(start);
    free(ends);
    int rc = count_components(m, weld, (uint64_t)ids, out);
    free(weld);
    if (rc)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "connected parts of %llu triangles",
                            (unsigned long long)m->triangle_count);
    return SL_OK;
}

int sl_mesh_parts(const sl_mesh *m, uint32_t *part_of_triangle, double **part_area,
                  uint64_t *part_count, sl_error *err)
{
    *part_area = NULL;
    *part_count = 0;
    if (m->vertex_count > (uint64_t)UINT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "%llu vertices: parts handle at most 2^32 - 1",
                            (unsigned long long)m->vertex_count);
    uint64_t n = m->vertex_count ? m->vertex_count : 1;
    uint32_t *weld = malloc(n * sizeof *weld), *dense = NULL;
    _Atomic uint32_t *parent = NULL;
    int64_t ids = weld ? sl_mesh_weld_positions(m, weld) : -1;
    if (ids >= 0) {
        /* Degenerate triangles join their corners too: they touch the part they lie in. */
        parent = join_parts(m, weld, (uint64_t)ids, 0);
        dense = malloc(((uint64_t)ids + 1) * sizeof *dense);
    }
    if (!parent || !dense) {
        free(weld);
        free(parent);
        free(dense);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "connected parts of %llu triangles",
                            (unsigned long long)m->triangle_count);
    }
    for (int64_t i = 0; i < ids; i++)
        dense[i] = NONE;
    uint64_t parts = 0;
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        uint32_t r = root_of(parent, weld[m->triangles[3 * t]]);
        if (dense[r] == NONE)
            dense[r] = (uint32_t)parts++;
        part_of_triangle[t] = dense[r];
    }
    double *area = calloc(parts ? parts : 1, sizeof *area);
    if (area)
        for (uint64_t t = 0; t < m->triangle_count; t++)
            area[part_of_triangle[t]] += triangle_area(m, t);
    free(weld);
    free(parent);
    free(dense);
    if (!area)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "connected parts of %llu triangles",
                            (unsigned long long)m->triangle_count);
    *part_area = area;
    *part_count = parts;
    return SL_OK;
}
