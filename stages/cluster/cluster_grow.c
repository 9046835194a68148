/* Clustering (paper 2, section 1; Tseng and Cheng's first step; docs/clustering.md).
 *
 * Greedy region growing, one cluster at a time. Seeds are taken flattest first (the
 * largest 1 - cos to an edge neighbour, in 1024 bins, then triangle index), as the mesh
 * toolkit's region growing does. The seed's unit normal n is the cluster's direction and
 * fixes its frame (u, v, n) and origin o for the rest of the pass. Candidates across
 * edges are taken nearest the seed's tangent plane first (the largest |n . (p - o) - h0|
 * over a candidate's corners, then the order they were found), so a cluster on a curved
 * surface grows as a cap around its seed, the shape that covers most area for a slab.
 * A candidate joins when
 *   - its normal is within max_angle of n (n . m >= cos_angle),
 *   - the cluster's vertices with its corners stay in a slab of width <= `slab` across n,
 *   - it projects strictly counter-clockwise into the (u, v) plane (exact orientation).
 * The last makes every cluster's projection orientation-preserving, what the proof of the
 * bound needs; the first only keeps clusters from bending around edges. A rejected
 * candidate is never retried for that cluster: the slab only widens, n is fixed.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/predicates.h"
#include "stages/cluster/cluster_internal.h"

void cl_clusters_release(cl_clusters *c)
{
    free(c->of_triangle);
    free(c->frame);
    free(c->lo);
    free(c->hi);
    free(c->tri_start);
    free(c->tris);
    free(c->kept);
    memset(c, 0, sizeof *c);
}

/* The frame of direction n: u, v with u x v = n, origin o. */
static void make_frame(const double n[3], const float *origin, double *frame)
{
    int axis = 0; /* the axis least aligned with n */
    for (int k = 1; k < 3; k++)
        if (fabs(n[k]) < fabs(n[axis]))
            axis = k;
    double e[3] = {0, 0, 0};
    e[axis] = 1.0;
    double u[3] = {e[1] * n[2] - e[2] * n[1], e[2] * n[0] - e[0] * n[2], e[0] * n[1] - e[1] * n[0]};
    double len = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int k = 0; k < 3; k++)
        u[k] /= len;
    double v[3] = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};
    for (int k = 0; k < 3; k++) {
        frame[k] = n[k];
        frame[3 + k] = u[k];
        frame[6 + k] = v[k];
        frame[9 + k] = origin[k];
    }
}

typedef struct heap_entry {
    double key;
    uint32_t seq, tri;
} heap_entry;

static int entry_less(const heap_entry *a, const heap_entry *b)
{
    return a->key < b->key || (a->key == b->key && a->seq < b->seq);
}

static void heap_push(heap_entry *h, uint32_t *size, heap_entry e)
{
    uint32_t i = (*size)++;
    while (i > 0) {
        uint32_t p = (i - 1) / 2;
        if (!entry_less(&e, &h[p]))
            break;
        h[i] = h[p];
        i = p;
    }
    h[i] = e;
}

static heap_entry heap_pop(heap_entry *h, uint32_t *size)
{
    heap_entry top = h[0], last = h[--*size];
    uint32_t i = 0, n = *size;
    for (;;) {
        uint32_t c = 2 * i + 1;
        if (c >= n)
            break;
        if (c + 1 < n && entry_less(&h[c + 1], &h[c]))
            c++;
        if (!entry_less(&h[c], &last))
            break;
        h[i] = h[c];
        i = c;
    }
    if (n)
        h[i] = last;
    return top;
}

/* Seeds flattest first: a stable counting sort on 1024 bins of the largest 1 - cos to an
 * edge neighbour. */
static int seed_order(const sl_mesh_adjacency *adj, const double *normals, uint32_t *order)
{
    uint32_t n = adj->triangle_count;
    uint16_t *bin = malloc((n ? n : 1) * sizeof *bin);
    uint32_t *count = calloc(1025, sizeof *count);
    if (!bin || !count) {
        free(bin);
        free(count);
        return -1;
    }
    for (uint32_t t = 0; t < n; t++) {
        const double *a = normals + 3 * (uint64_t)t;
        double worst = 0.0;
        for (int c = 0; c < 3; c++) {
            uint32_t g = adj->twin[3 * (uint64_t)t + c];
            if (g == SL_HALFEDGE_NONE)
                continue;
            const double *b = normals + 3 * (uint64_t)sl_halfedge_face(g);
            double d = 1.0 - (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
            worst = d > worst ? d : worst;
        }
        int q = (int)(worst * 512.0);
        bin[t] = (uint16_t)(q < 0 ? 0 : q > 1023 ? 1023 : q);
        count[bin[t] + 1]++;
    }
    for (int b = 0; b < 1024; b++)
        count[b + 1] += count[b];
    for (uint32_t t = 0; t < n; t++)
        order[count[bin[t]]++] = t;
    free(bin);
    free(count);
    return 0;
}

typedef struct grower {
    const sl_mesh_adjacency *adj;
    const float *positions;
    const double *normals;
    double slab, cos_angle;
    uint32_t *of_triangle, *stamp;
    heap_entry *heap;
    uint32_t heap_size, seq;
    double *frame, *lo, *hi;
    uint8_t *kept;
    uint32_t count, capacity;
} grower;

static int grow_room(grower *g)
{
    if (g->count < g->capacity)
        return 0;
    uint32_t cap = g->capacity ? 2 * g->capacity : 1024;
    double *frame = realloc(g->frame, (size_t)cap * 12 * sizeof *frame);
    if (frame)
        g->frame = frame;
    double *lo = realloc(g->lo, (size_t)cap * sizeof *lo);
    if (lo)
        g->lo = lo;
    double *hi = realloc(g->hi, (size_t)cap * sizeof *hi);
    if (hi)
        g->hi = hi;
    uint8_t *kept = realloc(g->kept, cap);
    if (kept)
        g->kept = kept;
    if (!frame || !lo || !hi || !kept)
        return -1;
    g->capacity = cap;
    return 0;
}

/* Heights of t's corners in `frame`, and whether t projects strictly counter-clockwise. */
static int corner_heights(const grower *g, const double *frame, uint32_t t, double h[3])
{
    double uv[3][2];
    for (int c = 0; c < 3; c++)
        cl_project(frame, g->positions + 3 * (uint64_t)g->adj->triangles[3 * (uint64_t)t + c],
                   uv[c], &h[c]);
    return sl_orient2d(uv[0], uv[1], uv[2]) > 0;
}

static void push_neighbours(grower *g, uint32_t t, uint32_t k, const double *frame, double mid)
{
    for (int c = 0; c < 3; c++) {
        uint32_t tw = g->adj->twin[3 * (uint64_t)t + c];
        if (tw == SL_HALFEDGE_NONE)
            continue;
        uint32_t f = sl_halfedge_face(tw);
        if (g->of_triangle[f] != CL_NONE || g->stamp[f] == k)
            continue;
        g->stamp[f] = k;
        double h[3], key = 0.0;
        for (int i = 0; i < 3; i++) {
            double uv[2];
            cl_project(frame, g->positions + 3 * (uint64_t)g->adj->triangles[3 * (uint64_t)f + i],
                       uv, &h[i]);
            double d = fabs(h[i] - mid);
            key = d > key ? d : key;
        }
        heap_push(g->heap, &g->heap_size, (heap_entry){key, g->seq++, f});
    }
}

/* Grows cluster k from seed s. */
static void grow_one(grower *g, uint32_t s, uint32_t k)
{
    const double *n = g->normals + 3 * (uint64_t)s;
    double *frame = g->frame + 12 * (uint64_t)k;
    make_frame(n, g->positions + 3 * (uint64_t)g->adj->triangles[3 * (uint64_t)s], frame);
    g->of_triangle[s] = k;
    g->stamp[s] = k;
    double h[3];
    int ccw = corner_heights(g, frame, s, h);
    double lo = fmin(h[0], fmin(h[1], h[2])), hi = fmax(h[0], fmax(h[1], h[2]));
    g->kept[k] = !ccw || hi - lo > g->slab;
    if (!g->kept[k]) {
        double mid = 0.5 * (lo + hi);
        g->heap_size = 0;
        push_neighbours(g, s, k, frame, mid);
        while (g->heap_size) {
            uint32_t t = heap_pop(g->heap, &g->heap_size).tri;
            const double *m = g->normals + 3 * (uint64_t)t;
            if (n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < g->cos_angle)
                continue;
            if (!corner_heights(g, frame, t, h))
                continue;
            double nlo = fmin(lo, fmin(h[0], fmin(h[1], h[2])));
            double nhi = fmax(hi, fmax(h[0], fmax(h[1], h[2])));
            if (nhi - nlo > g->slab)
                continue;
            lo = nlo;
            hi = nhi;
            g->of_triangle[t] = k;
            push_neighbours(g, t, k, frame, mid);
        }
    }
    g->lo[k] = lo;
    g->hi[k] = hi;
}

static int index_clusters(cl_clusters *out, uint32_t n)
{
    out->tri_start = calloc((size_t)out->count + 1, sizeof *out->tri_start);
    out->tris = malloc((n ? n : 1) * sizeof *out->tris);
    if (!out->tri_start || !out->tris)
        return -1;
    for (uint32_t t = 0; t < n; t++)
        out->tri_start[out->of_triangle[t] + 1]++;
    for (uint32_t k = 0; k < out->count; k++)
        out->tri_start[k + 1] += out->tri_start[k];
    uint32_t *at = malloc(((size_t)out->count + 1) * sizeof *at);
    if (!at)
        return -1;
    memcpy(at, out->tri_start, ((size_t)out->count + 1) * sizeof *at);
    for (uint32_t t = 0; t < n; t++)
        out->tris[at[out->of_triangle[t]]++] = t;
    free(at);
    return 0;
}

int cl_grow(const sl_mesh_adjacency *adj, const float *positions, const double *normals,
            double slab, double cos_angle, cl_clusters *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t n = adj->triangle_count;
    grower g = {adj, positions, normals, slab, cos_angle, NULL, NULL, NULL, 0, 0,
                NULL, NULL, NULL, NULL, 0, 0};
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    g.of_triangle = malloc((n ? n : 1) * sizeof *g.of_triangle);
    g.stamp = malloc((n ? n : 1) * sizeof *g.stamp);
    g.heap = malloc((n ? n : 1) * sizeof *g.heap);
    int ok = order && g.of_triangle && g.stamp && g.heap && seed_order(adj, normals, order) == 0;
    if (ok) {
        memset(g.of_triangle, 0xff, (size_t)n * sizeof *g.of_triangle);
        memset(g.stamp, 0xff, (size_t)n * sizeof *g.stamp);
        for (uint32_t i = 0; i < n && ok; i++) {
            uint32_t s = order[i];
            if (g.of_triangle[s] != CL_NONE)
                continue;
            if (grow_room(&g)) {
                ok = 0;
                break;
            }
            uint32_t k = g.count++;
            const double *ns = normals + 3 * (uint64_t)s;
            if (adj->degenerate[s] || (ns[0] == 0.0 && ns[1] == 0.0 && ns[2] == 0.0)) {
                /* left out of the adjacency, or no normal: a cluster kept as it is */
                g.of_triangle[s] = k;
                g.kept[k] = 1;
                memset(g.frame + 12 * (uint64_t)k, 0, 12 * sizeof(double));
                g.lo[k] = g.hi[k] = 0.0;
                continue;
            }
            grow_one(&g, s, k);
        }
    }
    free(order);
    free(g.stamp);
    free(g.heap);
    out->count = g.count;
    out->of_triangle = g.of_triangle;
    out->frame = g.frame;
    out->lo = g.lo;
    out->hi = g.hi;
    out->kept = g.kept;
    if (!ok || index_clusters(out, n)) {
        cl_clusters_release(out);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "clusters of %u triangles", n);
    }
    return SL_OK;
}
