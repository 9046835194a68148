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
 * MST walk is serial, seeded at the lowest unvisited index, with heap ties broken by
 * (cost, point, parent).
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

/* ---- MST propagation (Prim with a lazy binary heap) ---- */

typedef struct heap_entry {
    double cost;
    uint32_t point, parent;
} heap_entry;

typedef struct heap {
    heap_entry *e;
    uint64_t size, cap;
} heap;

static int entry_less(const heap_entry *a, const heap_entry *b)
{
    if (a->cost != b->cost)
        return a->cost < b->cost;
    if (a->point != b->point)
        return a->point < b->point;
    return a->parent < b->parent;
}

static int heap_push(heap *h, heap_entry x)
{
    if (h->size == h->cap) {
        uint64_t cap = h->cap ? 2 * h->cap : 1024;
        heap_entry *e = realloc(h->e, cap * sizeof *e);
        if (!e)
            return SL_E_NOMEM;
        h->e = e, h->cap = cap;
    }
    uint64_t i = h->size++;
    while (i > 0 && entry_less(&x, &h->e[(i - 1) / 2])) {
        h->e[i] = h->e[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h->e[i] = x;
    return SL_OK;
}

static heap_entry heap_pop(heap *h)
{
    heap_entry top = h->e[0], last = h->e[--h->size];
    uint64_t i = 0;
    for (;;) {
        uint64_t c = 2 * i + 1;
        if (c >= h->size)
            break;
        if (c + 1 < h->size && entry_less(&h->e[c + 1], &h->e[c]))
            c++;
        if (!entry_less(&h->e[c], &last))
            break;
        h->e[i] = h->e[c];
        i = c;
    }
    if (h->size)
        h->e[i] = last;
    return top;
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

static int push_neighbours(heap *h, const graph *g, const uint8_t *visited, const float *normals,
                           uint32_t p)
{
    const uint32_t *fwd = g->knn + (uint64_t)p * g->k;
    for (uint64_t i = 0; i < g->k + (g->rstart[p + 1] - g->rstart[p]); i++) {
        uint32_t q = i < g->k ? fwd[i] : g->rev[g->rstart[p] + (i - g->k)];
        if (q == RANGE_NONE || visited[q])
            continue;
        if (heap_push(h, (heap_entry){edge_cost(g, normals, p, q), q, p}) != SL_OK)
            return SL_E_NOMEM;
    }
    return SL_OK;
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
    uint8_t *visited = calloc(n ? n : 1, 1);
    uint32_t *members = malloc((n ? n : 1) * sizeof *members);
    heap h = {NULL, 0, 0};
    int rc = SL_OK;
    if (!visited || !members) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals: out of memory (propagation)");
        goto done;
    }
    uint64_t done_count = 0;
    *components = 0;
    for (uint64_t seed = 0; seed < n; seed++) {
        if (visited[seed])
            continue;
        (*components)++;
        uint64_t member_count = 0;
        h.size = 0;
        if ((rc = heap_push(&h, (heap_entry){0.0, (uint32_t)seed, RANGE_NONE})) != SL_OK)
            goto nomem;
        while (h.size) {
            heap_entry x = heap_pop(&h);
            if (visited[x.point])
                continue;
            visited[x.point] = 1;
            members[member_count++] = x.point;
            float *np = normals + 3 * (uint64_t)x.point;
            if (x.parent != RANGE_NONE && dot3f(normals + 3 * (uint64_t)x.parent, np) < 0)
                flip(np);
            if ((rc = push_neighbours(&h, g, visited, normals, x.point)) != SL_OK)
                goto nomem;
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
    goto done;
nomem:
    rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals: out of memory (propagation heap)");
done:
    free(visited), free(members), free(h.e);
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
