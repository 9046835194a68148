/* Normals of point clouds without faces: Hoppe, DeRose, Duchamp, McDonald & Stuetzle,
 * "Surface Reconstruction from Unorganized Points", SIGGRAPH 1992 (paper 1's reference
 * [13]): section 3.2 (tangent plane = PCA of the k nearest neighbours, normal = the
 * eigenvector of the smallest eigenvalue of their covariance) and section 3.3 (consistent
 * orientation by propagation along a minimum spanning tree of the neighbour graph with
 * edge cost 1 - |n_i . n_j|, flipping n_j when n_i . n_j < 0; we add a penalty for edges
 * that leave the tangent planes, see edge_cost).
 *
 * Where the file states the scanner position, each normal simply faces it (a scanner only
 * sees surfaces that face it). Otherwise, after propagation each connected component of
 * the kNN graph gets its sign from the normals at its convex-hull extremes, which must
 * point outwards (Hoppe roots each tree at the highest point with normal +z, the same
 * idea with one direction). "Away from the centroid on average" was the first rule
 * tried: it is right for closed clouds but balances on single-view scans (it got 80% of
 * dragon_rangescan backwards; the hull vote gets 98.7% right; docs/range-stage.md).
 *
 * Determinism: the neighbour search and PCA are per point (parallel, independent); the
 * MST walk is serial, seeded at the lowest unvisited index, with ties broken by the
 * lower point, then the lower parent index.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/range/range_internal.h"

/* Eigenvector of the smallest eigenvalue of symmetric `a` (cyclic Jacobi rotations). */
static void smallest_eigenvector(double a[3][3], double out[3])
{
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int sweep = 0; sweep < 32; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double scale = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (off <= 1e-15 * scale || off == 0.0)
            break;
        for (int p = 0; p < 2; p++)
            for (int q = p + 1; q < 3; q++) {
                if (a[p][q] == 0.0)
                    continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; k++) { /* A <- A J */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) { /* A <- J^T A */
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    int m = 0;
    for (int k = 1; k < 3; k++)
        if (a[k][k] < a[m][m])
            m = k;
    for (int k = 0; k < 3; k++)
        out[k] = v[k][m];
}

static void pca_normal(const float *positions, const uint32_t *nb, uint32_t count, float *n)
{
    double mean[3] = {0, 0, 0}, cov[3][3] = {{0}}, e[3];
    for (uint32_t i = 0; i < count; i++)
        for (int k = 0; k < 3; k++)
            mean[k] += positions[3 * (uint64_t)nb[i] + k];
    for (int k = 0; k < 3; k++)
        mean[k] /= count;
    for (uint32_t i = 0; i < count; i++) {
        double d[3];
        for (int k = 0; k < 3; k++)
            d[k] = positions[3 * (uint64_t)nb[i] + k] - mean[k];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                cov[r][c] += d[r] * d[c];
    }
    smallest_eigenvector(cov, e);
    double len = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    for (int k = 0; k < 3; k++)
        n[k] = (float)(len > 0 ? e[k] / len : (k == 2));
}

static double dot3f(const float *a, const float *b)
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

static void flip(float *n)
{
    n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
}

/* ---- MST propagation: Prim with an indexed binary heap (decrease-key), so memory is
 * O(points) however many edges the kNN graph has ---- */

typedef struct prim_heap {
    uint32_t *items;  /* heap of points, ordered by (key, point) */
    uint32_t *slot;   /* point -> position in items, or RANGE_NONE */
    double *key;      /* point -> cheapest edge to the tree so far */
    uint32_t *parent; /* point -> the tree point at the other end of that edge */
    uint64_t size;
} prim_heap;

static int heap_before(const prim_heap *h, uint32_t a, uint32_t b)
{
    return h->key[a] != h->key[b] ? h->key[a] < h->key[b] : a < b;
}

static void heap_place(prim_heap *h, uint64_t i, uint32_t point)
{
    h->items[i] = point;
    h->slot[point] = (uint32_t)i;
}

static void heap_sift_up(prim_heap *h, uint64_t i)
{
    uint32_t x = h->items[i];
    while (i > 0 && heap_before(h, x, h->items[(i - 1) / 2])) {
        heap_place(h, i, h->items[(i - 1) / 2]);
        i = (i - 1) / 2;
    }
    heap_place(h, i, x);
}

static uint32_t heap_pop(prim_heap *h)
{
    uint32_t top = h->items[0], last = h->items[--h->size];
    h->slot[top] = RANGE_NONE;
    if (h->size == 0)
        return top;
    uint64_t i = 0;
    for (;;) {
        uint64_t c = 2 * i + 1;
        if (c >= h->size)
            break;
        if (c + 1 < h->size && heap_before(h, h->items[c + 1], h->items[c]))
            c++;
        if (!heap_before(h, h->items[c], last))
            break;
        heap_place(h, i, h->items[c]);
        i = c;
    }
    heap_place(h, i, last);
    return top;
}

/* Offers the edge (parent p -> q) of `cost`; keeps the cheaper, then lower-parent one. */
static void heap_offer(prim_heap *h, uint32_t q, double cost, uint32_t p)
{
    uint32_t at = h->slot[q];
    if (at == RANGE_NONE) {
        h->key[q] = cost, h->parent[q] = p;
        h->items[h->size] = q;
        heap_sift_up(h, h->size++);
    } else if (cost < h->key[q] || (cost == h->key[q] && p < h->parent[q])) {
        h->key[q] = cost, h->parent[q] = p;
        heap_sift_up(h, at);
    }
}

typedef struct graph {
    const uint32_t *knn;  /* n * k forward neighbours (self and padding = RANGE_NONE) */
    uint32_t k;
    uint64_t *rstart;     /* reverse edges, CSR */
    uint32_t *rev;
    const float *positions;
} graph;

static int build_reverse(graph *g, uint64_t n, sl_error *err)
{
    g->rstart = calloc(n + 1, sizeof *g->rstart);
    g->rev = malloc((n * g->k + 1) * sizeof *g->rev);
    uint64_t *fill = malloc((n + 1) * sizeof *fill);
    if (!g->rstart || !g->rev || !fill) {
        free(fill);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals: out of memory (kNN graph)");
    }
    for (uint64_t i = 0; i < n * g->k; i++)
        if (g->knn[i] != RANGE_NONE)
            g->rstart[g->knn[i] + 1]++;
    for (uint64_t i = 0; i < n; i++)
        g->rstart[i + 1] += g->rstart[i];
    memcpy(fill, g->rstart, (n + 1) * sizeof *fill);
    for (uint64_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < g->k; j++) {
            uint32_t t = g->knn[i * g->k + j];
            if (t != RANGE_NONE)
                g->rev[fill[t]++] = (uint32_t)i;
        }
    free(fill);
    return SL_OK;
}

/* Hoppe's 1 - |n_p . n_q|, plus TANGENT_WEIGHT x how far the edge leaves the two tangent
 * planes. Without the second term the tree happily jumps between facing sheets (two
 * sides of a thin part, or of a narrow gap), where "flip if n_p . n_q < 0" is right for
 * one and wrong for the other; with it, propagation runs along the surface. Measured on
 * meshes read as bare vertices (sign agreement with their face normals, k = 12): fandisk
 * 0.77 -> 1.00, cow 0.85 -> 0.91, lucy 0.970 -> 0.986, happy_buddha 0.981 -> 0.994. */
#define TANGENT_WEIGHT 0.5

static double edge_cost(const graph *g, const float *normals, uint32_t p, uint32_t q)
{
    const float *np = normals + 3 * (uint64_t)p, *nq = normals + 3 * (uint64_t)q;
    const float *pp = g->positions + 3 * (uint64_t)p, *pq = g->positions + 3 * (uint64_t)q;
    double e[3] = {(double)pq[0] - pp[0], (double)pq[1] - pp[1], (double)pq[2] - pp[2]};
    double len = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    double cost = 1.0 - fabs(dot3f(np, nq));
    if (len > 0)
        cost += TANGENT_WEIGHT * (fabs(np[0] * e[0] + np[1] * e[1] + np[2] * e[2]) +
                                  fabs(nq[0] * e[0] + nq[1] * e[1] + nq[2] * e[2])) / len;
    return cost;
}

static void offer_neighbours(prim_heap *h, const graph *g, const uint8_t *visited,
                             const float *normals, uint32_t p)
{
    const uint32_t *fwd = g->knn + (uint64_t)p * g->k;
    for (uint64_t i = 0; i < g->k + (g->rstart[p + 1] - g->rstart[p]); i++) {
        uint32_t q = i < g->k ? fwd[i] : g->rev[g->rstart[p] + (i - g->k)];
        if (q != RANGE_NONE && !visited[q])
            heap_offer(h, q, edge_cost(g, normals, p, q), p);
    }
}

/* The sign rule for a component: at a point of the component that is extreme in a
 * direction d (a vertex of its convex hull), an outward normal has n . d > 0, for a
 * closed surface and for the visible side of a single scan alike. Sum n . d over the
 * extreme points of the 26 directions of a 3x3x3 stencil (ties: lower index). */
static double hull_vote(const float *positions, const float *normals, const uint32_t *members,
                        uint64_t count)
{
    double dir[26][3], best[26];
    uint32_t arg[26];
    int nd = 0;
    for (int x = -1; x <= 1; x++)
        for (int y = -1; y <= 1; y++)
            for (int z = -1; z <= 1; z++) {
                if (!x && !y && !z)
                    continue;
                double len = sqrt((double)(x * x + y * y + z * z));
                dir[nd][0] = x / len, dir[nd][1] = y / len, dir[nd][2] = z / len;
                best[nd] = -HUGE_VAL, arg[nd] = RANGE_NONE;
                nd++;
            }
    for (uint64_t i = 0; i < count; i++) {
        uint32_t m = members[i];
        const float *p = positions + 3 * (uint64_t)m;
        for (int d = 0; d < 26; d++) {
            double s = p[0] * dir[d][0] + p[1] * dir[d][1] + p[2] * dir[d][2];
            if (s > best[d] || (s == best[d] && m < arg[d]))
                best[d] = s, arg[d] = m;
        }
    }
    double vote = 0;
    for (int d = 0; d < 26; d++) {
        const float *n = normals + 3 * (uint64_t)arg[d];
        vote += n[0] * dir[d][0] + n[1] * dir[d][1] + n[2] * dir[d][2];
    }
    return vote;
}

/* Orients each connected component by propagation, then by the hull vote. */
static int propagate(const graph *g, const float *positions, uint64_t n, float *normals,
                     uint64_t *components, sl_progress *progress, sl_error *err)
{
    uint64_t size = n ? n : 1;
    uint8_t *visited = calloc(size, 1);
    uint32_t *members = malloc(size * sizeof *members);
    prim_heap h = {malloc(size * sizeof(uint32_t)), malloc(size * sizeof(uint32_t)),
                   malloc(size * sizeof(double)), malloc(size * sizeof(uint32_t)), 0};
    int rc = SL_OK;
    if (!visited || !members || !h.items || !h.slot || !h.key || !h.parent) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals: out of memory (propagation)");
        goto done;
    }
    for (uint64_t i = 0; i < n; i++)
        h.slot[i] = RANGE_NONE;
    uint64_t done_count = 0;
    *components = 0;
    for (uint64_t seed = 0; seed < n; seed++) {
        if (visited[seed])
            continue;
        (*components)++;
        uint64_t member_count = 0;
        heap_offer(&h, (uint32_t)seed, 0.0, RANGE_NONE);
        while (h.size) {
            uint32_t p = heap_pop(&h);
            visited[p] = 1;
            members[member_count++] = p;
            float *np = normals + 3 * (uint64_t)p;
            if (h.parent[p] != RANGE_NONE && dot3f(normals + 3 * (uint64_t)h.parent[p], np) < 0)
                flip(np);
            offer_neighbours(&h, g, visited, normals, p);
            if ((++done_count & 0xffff) == 0 &&
                sl_progress_step(progress, "orient normals", (double)done_count / n)) {
                rc = SL_E_INTERRUPTED;
                goto done;
            }
        }
        double outward = hull_vote(positions, normals, members, member_count);
        if (outward < 0)
            for (uint64_t i = 0; i < member_count; i++)
                flip(normals + 3 * (uint64_t)members[i]);
    }
done:
    free(visited), free(members);
    free(h.items), free(h.slot), free(h.key), free(h.parent);
    return rc;
}

int range_pca_normals(const sl_kdtree *tree, const float *positions, uint64_t point_count,
                      uint32_t k, const double *viewpoint, float *normals, uint32_t *source,
                      sl_range_counts *counts, sl_progress *progress, sl_error *err)
{
    uint64_t n = point_count;
    uint32_t kk = (uint64_t)k > n ? (uint32_t)n : k;
    uint32_t *knn = malloc((n * kk + 1) * sizeof *knn);
    if (!knn)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals: out of memory (%llu x %u)",
                            (unsigned long long)n, kk);
    int stop = 0;
#pragma omp parallel for schedule(dynamic, 1024)
    for (int64_t i = 0; i < (int64_t)n; i++) {
        int stopped;
#pragma omp atomic read
        stopped = stop;
        if (stopped)
            continue;
        if ((i & 4095) == 0 && sl_progress_step(progress, "pca normals", (double)i / n)) {
#pragma omp atomic write
            stop = 1;
        }
        uint32_t *nb = knn + (uint64_t)i * kk;
        uint32_t found = sl_kdtree_knn(tree, positions + 3 * i, kk, nb, NULL);
        for (uint32_t j = found; j < kk; j++)
            nb[j] = RANGE_NONE;
        pca_normal(positions, nb, found, normals + 3 * i);
        for (uint32_t j = 0; j < found; j++)
            if (nb[j] == (uint32_t)i)
                nb[j] = RANGE_NONE; /* no self edges in the graph */
    }
    if (stop) {
        free(knn);
        return SL_E_INTERRUPTED;
    }
    int rc = SL_OK;
    counts->pca_components = 0;
    if (viewpoint) {
        *source = SL_NORMALS_PCA_VIEWPOINT;
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < (int64_t)n; i++) {
            float *nn = normals + 3 * i;
            const float *p = positions + 3 * i;
            double toward = 0;
            for (int c = 0; c < 3; c++)
                toward += nn[c] * (viewpoint[c] - p[c]);
            if (toward < 0)
                flip(nn);
        }
    } else {
        *source = SL_NORMALS_PCA_PROPAGATED;
        graph g = {knn, kk, NULL, NULL, positions};
        rc = build_reverse(&g, n, err);
        if (rc == SL_OK)
            rc = propagate(&g, positions, n, normals, &counts->pca_components, progress, err);
        free(g.rstart), free(g.rev);
    }
    free(knn);
    return rc;
}
