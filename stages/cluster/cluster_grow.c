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
 *   - its normal is within max_angle of n (n . m >= cos(max_angle); a triangle of a cluster
 *     whose polygon folded in an earlier try has a smaller angle, see cluster_pass.c),
 *   - the cluster's vertices with its corners stay in a slab of width <= `slab` across n
 *     (also per triangle: smaller where an earlier try folded),
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
    const double *normals, *area;
    const double *slab_limit;        /* per triangle: the widest slab its cluster may have */
    const double *cos_limit;         /* per triangle: the cosine its angle to n must reach */
    double seed_cos, seed_slab;      /* the current attempt's seed's */
    uint32_t *of_triangle, *stamp, attempt;
    heap_entry *heap;
    uint32_t heap_size, seq;
    uint32_t *members, member_count; /* the current attempt's triangles */
    uint32_t *best, best_count;      /* the best attempt's */
    double *frame, *lo, *hi;
    uint8_t *kept;
    uint32_t *seed;                  /* per cluster */
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
    uint32_t *seed = realloc(g->seed, (size_t)cap * sizeof *seed);
    if (seed)
        g->seed = seed;
    if (!frame || !lo || !hi || !kept || !seed)
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

static void push_neighbours(grower *g, uint32_t t, const double *frame, double mid)
{
    for (int c = 0; c < 3; c++) {
        uint32_t tw = g->adj->twin[3 * (uint64_t)t + c];
        if (tw == SL_HALFEDGE_NONE)
            continue;
        uint32_t f = sl_halfedge_face(tw);
        if (g->of_triangle[f] != CL_NONE || g->stamp[f] == g->attempt)
            continue;
        g->stamp[f] = g->attempt;
        double key = 0.0;
        for (int i = 0; i < 3; i++) {
            double d = fabs(cl_height(frame, g->positions +
                                                 3 * (uint64_t)g->adj->triangles[3 * (uint64_t)f + i]) -
                            mid);
            key = d > key ? d : key;
        }
        heap_push(g->heap, &g->heap_size, (heap_entry){key, g->seq++, f});
    }
}

/* One attempt at cluster k from seed s with direction n (unit): its triangles in
 * g->members, its frame and slab in k's slots. Returns its area (0 if the seed itself
 * does not fit). */
static double attempt(grower *g, uint32_t s, uint32_t k, const double n[3])
{
    double *frame = g->frame + 12 * (uint64_t)k;
    make_frame(n, g->positions + 3 * (uint64_t)g->adj->triangles[3 * (uint64_t)s], frame);
    g->attempt++;
    g->member_count = 0;
    g->seed_cos = g->cos_limit[s];
    g->seed_slab = g->slab_limit[s];
    g->seed[k] = s;
    double h[3];
    int ccw = corner_heights(g, frame, s, h);
    double lo = fmin(h[0], fmin(h[1], h[2])), hi = fmax(h[0], fmax(h[1], h[2]));
    g->lo[k] = lo;
    g->hi[k] = hi;
    if (!ccw || hi - lo > g->seed_slab)
        return 0.0;
    g->of_triangle[s] = k;
    g->stamp[s] = g->attempt;
    g->members[g->member_count++] = s;
    double area = g->area[s], mid = 0.5 * (lo + hi);
    g->heap_size = 0;
    push_neighbours(g, s, frame, mid);
    while (g->heap_size) {
        uint32_t t = heap_pop(g->heap, &g->heap_size).tri;
        const double *m = g->normals + 3 * (uint64_t)t;
        if (n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < fmax(g->seed_cos, g->cos_limit[t]))
            continue;
        if (!corner_heights(g, frame, t, h))
            continue;
        double nlo = fmin(lo, fmin(h[0], fmin(h[1], h[2])));
        double nhi = fmax(hi, fmax(h[0], fmax(h[1], h[2])));
        if (nhi - nlo > fmin(g->seed_slab, g->slab_limit[t]))
            continue;
        lo = nlo;
        hi = nhi;
        g->of_triangle[t] = k;
        g->members[g->member_count++] = t;
        area += g->area[t];
        push_neighbours(g, t, frame, mid);
    }
    g->lo[k] = lo;
    g->hi[k] = hi;
    return area;
}

static void assign(grower *g, const uint32_t *tris, uint32_t count, uint32_t k)
{
    for (uint32_t i = 0; i < count; i++)
        g->of_triangle[tris[i]] = k;
}

/* Grows cluster k from seed s: first with the seed's normal, then again with the
 * area-weighted mean normal of what grew (its slab is thinner along it, so the regrown
 * cluster can reach further), kept while it covers more area. */
static void grow_one(grower *g, uint32_t s, uint32_t k)
{
    double n[3], frame[12], lo, hi;
    memcpy(n, g->normals + 3 * (uint64_t)s, sizeof n);
    double best = attempt(g, s, k, n);
    g->kept[k] = best == 0.0;
    if (g->kept[k]) {
        g->of_triangle[s] = k;
        return;
    }
    for (int refit = 0; refit < 2; refit++) {
        memcpy(g->best, g->members, g->member_count * sizeof *g->best);
        g->best_count = g->member_count;
        memcpy(frame, g->frame + 12 * (uint64_t)k, sizeof frame);
        lo = g->lo[k];
        hi = g->hi[k];
        double m[3] = {0, 0, 0};
        for (uint32_t i = 0; i < g->best_count; i++)
            for (int c = 0; c < 3; c++)
                m[c] += g->area[g->best[i]] * g->normals[3 * (uint64_t)g->best[i] + c];
        double len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (!(len > 0.0) || m[0] / len * n[0] + m[1] / len * n[1] + m[2] / len * n[2] > 1.0 - 1e-12)
            break;
        for (int c = 0; c < 3; c++)
            n[c] = m[c] / len;
        assign(g, g->best, g->best_count, CL_NONE);
        double area = attempt(g, s, k, n);
        if (area > best) {
            best = area;
            continue;
        }
        assign(g, g->members, g->member_count, CL_NONE); /* the earlier one was better */
        assign(g, g->best, g->best_count, k);
        memcpy(g->frame + 12 * (uint64_t)k, frame, sizeof frame);
        g->lo[k] = lo;
        g->hi[k] = hi;
        break;
    }
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

/* Each cluster's triangles as a linked list (head, next, tail), so merging is O(1). */
typedef struct lists {
    uint32_t *head, *tail, *next;
} lists;

static int make_lists(const grower *g, uint32_t n, lists *l)
{
    l->head = malloc(((size_t)g->count + 1) * sizeof *l->head);
    l->tail = malloc(((size_t)g->count + 1) * sizeof *l->tail);
    l->next = malloc((n ? n : 1) * sizeof *l->next);
    if (!l->head || !l->tail || !l->next)
        return -1;
    memset(l->head, 0xff, ((size_t)g->count + 1) * sizeof *l->head);
    for (uint32_t t = n; t-- > 0;) {
        uint32_t k = g->of_triangle[t];
        if (l->head[k] == CL_NONE)
            l->tail[k] = t;
        l->next[t] = l->head[k];
        l->head[k] = t;
    }
    return 0;
}

/* Whether every triangle of cluster from fits cluster k's frame; OUT: the widened slab. */
static int fits(const grower *g, const lists *l, uint32_t from, uint32_t k, double *lo,
                double *hi)
{
    const double *frame = g->frame + 12 * (uint64_t)k;
    double limit = fmax(g->cos_limit[g->seed[k]], g->cos_limit[g->seed[from]]);
    double slab = fmin(g->slab_limit[g->seed[k]], g->slab_limit[g->seed[from]]);
    *lo = g->lo[k];
    *hi = g->hi[k];
    for (uint32_t t = l->head[from]; t != CL_NONE; t = l->next[t]) {
        const double *m = g->normals + 3 * (uint64_t)t;
        double h[3];
        if (frame[0] * m[0] + frame[1] * m[1] + frame[2] * m[2] < fmax(limit, g->cos_limit[t]) ||
            !corner_heights(g, frame, t, h))
            return 0;
        *lo = fmin(*lo, fmin(h[0], fmin(h[1], h[2])));
        *hi = fmax(*hi, fmax(h[0], fmax(h[1], h[2])));
        if (*hi - *lo > fmin(slab, g->slab_limit[t]))
            return 0;
    }
    return 1;
}

typedef struct by_area {
    double area;
    uint32_t k;
} by_area;

static int area_cmp(const void *a, const void *b)
{
    const by_area *x = a, *y = b;
    if (x->area != y->area)
        return x->area < y->area ? -1 : 1;
    return x->k < y->k ? -1 : x->k > y->k;
}

/* The neighbour of cluster k that can hold it, across the most edges (ties: the lower
 * id), or CL_NONE; OUT: the slab it would have. `shared` (zero) and `near` are scratch. */
static uint32_t host_of(const grower *g, const lists *l, uint32_t k, uint32_t *shared,
                        uint32_t *near, double *lo, double *hi)
{
    uint32_t nn = 0, best = CL_NONE;
    for (uint32_t t = l->head[k]; t != CL_NONE; t = l->next[t])
        for (int c = 0; c < 3; c++) {
            uint32_t tw = g->adj->twin[3 * (uint64_t)t + c];
            if (tw == SL_HALFEDGE_NONE)
                continue;
            uint32_t r = g->of_triangle[sl_halfedge_face(tw)];
            if (r != k && !g->kept[r] && !shared[r]++)
                near[nn++] = r;
        }
    for (;;) {
        uint32_t pick = CL_NONE;
        for (uint32_t i = 0; i < nn; i++)
            if (shared[near[i]] && (pick == CL_NONE || shared[near[i]] > shared[pick] ||
                                    (shared[near[i]] == shared[pick] && near[i] < pick)))
                pick = near[i];
        if (pick == CL_NONE)
            break;
        shared[pick] = 0;
        if (fits(g, l, k, pick, lo, hi)) {
            best = pick;
            break;
        }
    }
    for (uint32_t i = 0; i < nn; i++)
        shared[near[i]] = 0;
    return best;
}

/* Merges clusters into neighbours that can hold them, smallest first: greedy growth
 * leaves small clusters in the gaps between large ones, and every cluster costs corners.
 * A merged cluster keeps the frame of the one it joined, so it meets the same criteria.
 * Then ids are made dense again, in their order. */
static int merge_small(grower *g, uint32_t n)
{
    lists l = {NULL, NULL, NULL};
    by_area *order = malloc(((size_t)g->count + 1) * sizeof *order);
    uint32_t *shared = calloc((size_t)g->count + 1, sizeof *shared);
    uint32_t *near = malloc(((size_t)g->count + 1) * sizeof *near);
    int ok = order && shared && near && make_lists(g, n, &l) == 0;
    for (uint32_t k = 0; ok && k < g->count; k++) {
        double a = 0.0;
        for (uint32_t t = l.head[k]; t != CL_NONE; t = l.next[t])
            a += g->area[t];
        order[k] = (by_area){a, k};
    }
    if (ok)
        qsort(order, g->count, sizeof *order, area_cmp);
    for (uint32_t o = 0; ok && o < g->count; o++) {
        uint32_t k = order[o].k;
        double lo, hi;
        uint32_t host = g->kept[k] ? CL_NONE : host_of(g, &l, k, shared, near, &lo, &hi);
        if (host == CL_NONE)
            continue;
        for (uint32_t t = l.head[k]; t != CL_NONE; t = l.next[t])
            g->of_triangle[t] = host;
        l.next[l.tail[host]] = l.head[k];
        l.tail[host] = l.tail[k];
        l.head[k] = CL_NONE;
        g->lo[host] = lo;
        g->hi[host] = hi;
        g->kept[k] = 2; /* gone */
    }
    uint32_t *id = near; /* the new id of each old cluster (ids only shrink: in place) */
    uint32_t count = 0;
    for (uint32_t k = 0; ok && k < g->count; k++) {
        if (g->kept[k] == 2)
            continue;
        id[k] = count;
        memmove(g->frame + 12 * (uint64_t)count, g->frame + 12 * (uint64_t)k, 12 * sizeof(double));
        g->lo[count] = g->lo[k];
        g->hi[count] = g->hi[k];
        g->kept[count] = g->kept[k];
        g->seed[count] = g->seed[k];
        count++;
    }
    for (uint32_t t = 0; ok && t < n; t++)
        g->of_triangle[t] = id[g->of_triangle[t]];
    if (ok)
        g->count = count;
    free(order);
    free(shared);
    free(near);
    free(l.head);
    free(l.tail);
    free(l.next);
    return ok ? 0 : -1;
}

/* Triangle areas (double). */
static double *areas(const sl_mesh_adjacency *adj, const float *positions)
{
    uint32_t n = adj->triangle_count;
    double *a = malloc((n ? n : 1) * sizeof *a);
    if (!a)
        return NULL;
    for (uint32_t t = 0; t < n; t++) {
        const uint32_t *c = adj->triangles + 3 * (uint64_t)t;
        double u[3], v[3];
        for (int k = 0; k < 3; k++) {
            u[k] = (double)positions[3 * (uint64_t)c[1] + k] - positions[3 * (uint64_t)c[0] + k];
            v[k] = (double)positions[3 * (uint64_t)c[2] + k] - positions[3 * (uint64_t)c[0] + k];
        }
        double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
               z = u[0] * v[1] - u[1] * v[0];
        a[t] = 0.5 * sqrt(x * x + y * y + z * z);
    }
    return a;
}

int cl_grow(const sl_mesh_adjacency *adj, const float *positions, const double *normals,
            const double *slab_limit, const double *cos_limit, cl_clusters *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t n = adj->triangle_count;
    grower g;
    memset(&g, 0, sizeof g);
    g.adj = adj;
    g.positions = positions;
    g.normals = normals;
    g.slab_limit = slab_limit;
    g.cos_limit = cos_limit;
    size_t words = n ? n : 1;
    uint32_t *order = malloc(words * sizeof *order);
    double *area = areas(adj, positions);
    g.area = area;
    g.of_triangle = malloc(words * sizeof *g.of_triangle);
    g.stamp = calloc(words, sizeof *g.stamp);
    g.heap = malloc(words * sizeof *g.heap);
    g.members = malloc(words * sizeof *g.members);
    g.best = malloc(words * sizeof *g.best);
    int ok = order && area && g.of_triangle && g.stamp && g.heap && g.members && g.best &&
             seed_order(adj, normals, order) == 0;
    if (ok) {
        memset(g.of_triangle, 0xff, (size_t)n * sizeof *g.of_triangle);
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
                g.seed[k] = s;
                memset(g.frame + 12 * (uint64_t)k, 0, 12 * sizeof(double));
                g.lo[k] = g.hi[k] = 0.0;
                continue;
            }
            grow_one(&g, s, k);
        }
    }
    if (ok && merge_small(&g, n))
        ok = 0;
    free(order);
    free(area);
    free(g.stamp);
    free(g.heap);
    free(g.members);
    free(g.best);
    free(g.seed);
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
