/* Half-edge adjacency (mesh_adjacency.h).
 *
 * Method: every half-edge of a non-degenerate triangle is put in the bucket of its lower
 * vertex (counting sort: counts, prefix sums, fill in half-edge order), each bucket is
 * sorted by (upper vertex, half-edge id), and each run of equal upper vertices is one
 * undirected edge: a run of two half-edges running opposite ways are twins, anything else
 * is a boundary (one), inconsistent (two the same way) or non-manifold (three or more)
 * edge. Then each vertex walks its fan from its stored half-edge; a walk that sees fewer
 * corners than the vertex has means more than one fan.
 */
#include "geometry/mesh_adjacency.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NONE SL_HALFEDGE_NONE

typedef struct bucket_entry {
    uint32_t upper, halfedge;
} bucket_entry;

static int entry_less(const bucket_entry *a, const bucket_entry *b)
{
    return a->upper < b->upper || (a->upper == b->upper && a->halfedge < b->halfedge);
}

static void sort_bucket(bucket_entry *e, uint64_t n)
{
    /* Insertion sort for the usual 3-8 entries; a shell sort for a huge fan. */
    uint64_t gap = 1;
    while (n > 16 && gap < n / 3)
        gap = 3 * gap + 1;
    for (; gap >= 1; gap = (gap - 1) / 3) {
        for (uint64_t i = gap; i < n; i++) {
            bucket_entry x = e[i];
            uint64_t j = i;
            for (; j >= gap && entry_less(&x, &e[j - gap]); j -= gap)
                e[j] = e[j - gap];
            e[j] = x;
        }
        if (gap == 1)
            break;
    }
}

static void note_problem(sl_adjacency_report *r, int problem, uint32_t v0, uint32_t v1,
                         uint32_t t0, uint32_t t1, uint32_t t2, uint32_t count)
{
    if (r->problem != SL_ADJACENCY_OK)
        return;
    r->problem = problem;
    r->v[0] = v0;
    r->v[1] = v1;
    r->t[0] = t0;
    r->t[1] = t1;
    r->t[2] = t2;
    r->edge_triangles = count;
}

/* Pairs twins inside one sorted bucket of lower vertex `lo`; counts into r. */
static void pair_bucket(const uint32_t *tri, uint32_t lo, const bucket_entry *e, uint64_t n,
                        uint32_t *twin, uint8_t *vflags, sl_adjacency_report *r)
{
    for (uint64_t i = 0; i < n;) {
        uint64_t j = i + 1;
        while (j < n && e[j].upper == e[i].upper)
            j++;
        uint32_t h0 = e[i].halfedge, hi = e[i].upper;
        r->edges++;
        if (j - i == 1) {
            r->boundary_edges++;
        } else if (j - i == 2 && tri[h0] != tri[e[i + 1].halfedge]) {
            twin[h0] = e[i + 1].halfedge;
            twin[e[i + 1].halfedge] = h0;
        } else {
            uint32_t t1 = sl_halfedge_face(e[i + 1].halfedge);
            uint32_t t2 = j - i > 2 ? sl_halfedge_face(e[i + 2].halfedge) : UINT32_MAX;
            if (j - i == 2) {
                r->inconsistent_edges++;
                note_problem(r, SL_ADJACENCY_INCONSISTENT_EDGE, tri[h0], tri[sl_halfedge_next(h0)],
                             sl_halfedge_face(h0), t1, UINT32_MAX, 2);
            } else {
                r->nonmanifold_edges++;
                note_problem(r, SL_ADJACENCY_NONMANIFOLD_EDGE, lo, hi, sl_halfedge_face(h0), t1,
                             t2, (uint32_t)(j - i));
            }
            /* hi's bucket may be another thread's: the flags are shared */
#pragma omp atomic update
            vflags[lo] |= (uint8_t)SL_VERTEX_CUT;
#pragma omp atomic update
            vflags[hi] |= (uint8_t)SL_VERTEX_CUT;
        }
        i = j;
    }
}

static void merge_report(sl_adjacency_report *dst, const sl_adjacency_report *src)
{
    dst->edges += src->edges;
    dst->boundary_edges += src->boundary_edges;
    dst->nonmanifold_edges += src->nonmanifold_edges;
    dst->inconsistent_edges += src->inconsistent_edges;
    if (dst->problem == SL_ADJACENCY_OK && src->problem != SL_ADJACENCY_OK) {
        dst->problem = src->problem;
        memcpy(dst->v, src->v, sizeof dst->v);
        memcpy(dst->t, src->t, sizeof dst->t);
        dst->edge_triangles = src->edge_triangles;
    }
}

/* The twins, by buckets of the lower vertex. Returns 0 or SL_E_NOMEM. */
static int build_twins(sl_mesh_adjacency *adj, sl_adjacency_report *r, sl_error *err)
{
    const uint32_t *tri = adj->triangles;
    uint64_t nv = adj->vertex_count, nh = 3 * (uint64_t)adj->triangle_count;
    uint64_t *start = calloc(nv + 2, sizeof *start);
    bucket_entry *entries = malloc((nh ? nh : 1) * sizeof *entries);
    if (!start || !entries) {
        free(start);
        free(entries);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "adjacency of %u triangles",
                            adj->triangle_count);
    }
    for (uint64_t h = 0; h < nh; h++) {
        if (adj->degenerate[h / 3])
            continue;
        uint32_t a = tri[h], b = tri[sl_halfedge_next((uint32_t)h)];
        start[(a < b ? a : b) + 2]++;
    }
    for (uint64_t v = 0; v < nv; v++)
        start[v + 2] += start[v + 1];
    for (uint64_t h = 0; h < nh; h++) {
        if (adj->degenerate[h / 3])
            continue;
        uint32_t a = tri[h], b = tri[sl_halfedge_next((uint32_t)h)];
        bucket_entry e = {a < b ? b : a, (uint32_t)h};
        entries[start[(a < b ? a : b) + 1]++] = e;
    }
    /* start[v] .. start[v + 1] is now bucket v. Buckets are disjoint, so they are sorted
     * and paired in parallel; each thread's static chunk is ascending, so the first
     * problem overall is the one with the lowest bucket among the threads' first ones. */
    int64_t nvi = (int64_t)nv;
    uint64_t first_vertex = UINT64_MAX;
    sl_adjacency_report edge_problem;
    memset(&edge_problem, 0, sizeof edge_problem);
#pragma omp parallel
    {
        sl_adjacency_report mine;
        memset(&mine, 0, sizeof mine);
        uint64_t mine_first = UINT64_MAX;
#pragma omp for schedule(static)
        for (int64_t v = 0; v < nvi; v++) {
            uint64_t n = start[v + 1] - start[v];
            if (!n)
                continue;
            sort_bucket(entries + start[v], n);
            int had = mine.problem;
            pair_bucket(tri, (uint32_t)v, entries + start[v], n, adj->twin, adj->vertex_flags,
                        &mine);
            if (!had && mine.problem)
                mine_first = (uint64_t)v;
        }
#pragma omp critical(sl_adjacency_merge)
        {
            if (mine_first < first_vertex) {
                first_vertex = mine_first;
                edge_problem = mine;
                edge_problem.edges = edge_problem.boundary_edges = 0;
                edge_problem.nonmanifold_edges = edge_problem.inconsistent_edges = 0;
            }
            mine.problem = SL_ADJACENCY_OK;
            merge_report(r, &mine);
        }
    }
    if (first_vertex != UINT64_MAX)
        merge_report(r, &edge_problem);
    free(start);
    free(entries);
    return SL_OK;
}

/* Outgoing half-edges per vertex, the fans, boundary and non-manifold flags. */
static int build_vertices(sl_mesh_adjacency *adj, sl_adjacency_report *r, sl_error *err)
{
    uint64_t nv = adj->vertex_count, nh = 3 * (uint64_t)adj->triangle_count;
    uint32_t *corners = calloc(nv ? nv : 1, sizeof *corners);
    if (!corners)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "adjacency of %u vertices",
                            adj->vertex_count);
    for (uint64_t h = 0; h < nh; h++) {
        if (adj->degenerate[h / 3])
            continue;
        uint32_t v = adj->triangles[h];
        corners[v]++;
        adj->vertex_flags[v] |= SL_VERTEX_USED;
        if (adj->twin[h] == NONE) {
            adj->vertex_flags[v] |= SL_VERTEX_BOUNDARY;
            adj->vertex_flags[adj->triangles[sl_halfedge_next((uint32_t)h)]] |= SL_VERTEX_BOUNDARY;
            if (adj->vertex_halfedge[v] == NONE || adj->twin[adj->vertex_halfedge[v]] != NONE)
                adj->vertex_halfedge[v] = (uint32_t)h;
        } else if (adj->vertex_halfedge[v] == NONE) {
            adj->vertex_halfedge[v] = (uint32_t)h;
        }
    }
    uint64_t nonmanifold = 0, used = 0;
    int64_t nvi = (int64_t)nv;
#pragma omp parallel for schedule(static) reduction(+ : nonmanifold, used)
    for (int64_t v = 0; v < nvi; v++) {
        uint32_t h0 = adj->vertex_halfedge[v];
        if (h0 == NONE)
            continue;
        used++;
        uint32_t seen = 0, h = h0;
        do {
            seen++;
            h = sl_halfedge_rotate(adj, h);
        } while (h != NONE && h != h0 && seen <= corners[v]);
        if (seen != corners[v]) {
            adj->vertex_flags[v] |= SL_VERTEX_NONMANIFOLD;
            nonmanifold++;
        }
    }
    r->nonmanifold_vertices = nonmanifold;
    r->used_vertices = used;
    if (nonmanifold && r->problem == SL_ADJACENCY_OK)
        for (uint64_t v = 0; v < nv; v++)
            if (adj->vertex_flags[v] & SL_VERTEX_NONMANIFOLD) {
                note_problem(r, SL_ADJACENCY_NONMANIFOLD_VERTEX, (uint32_t)v, UINT32_MAX,
                             sl_halfedge_face(adj->vertex_halfedge[v]), UINT32_MAX, UINT32_MAX, 0);
                break;
            }
    free(corners);
    return SL_OK;
}

/* Cycles of twin-less half-edges under sl_halfedge_next_boundary. */
static int count_boundary_loops(const sl_mesh_adjacency *adj, sl_adjacency_report *r,
                                sl_error *err)
{
    uint64_t nh = 3 * (uint64_t)adj->triangle_count;
    if (!r->boundary_edges && !r->nonmanifold_edges && !r->inconsistent_edges)
        return SL_OK;
    uint8_t *seen = calloc(nh ? nh : 1, 1);
    if (!seen)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "boundary loops");
    for (uint64_t h = 0; h < nh; h++) {
        if (seen[h] || adj->degenerate[h / 3] || adj->twin[h] != NONE)
            continue;
        r->boundary_loops++;
        for (uint32_t g = (uint32_t)h; !seen[g]; g = sl_halfedge_next_boundary(adj, g))
            seen[g] = 1;
    }
    free(seen);
    return SL_OK;
}

const char *sl_adjacency_problem_text(const sl_adjacency_report *r, const float *positions,
                                      char *buf, unsigned size)
{
    char where[160] = "";
    if (positions && r->v[0] != UINT32_MAX) {
        const float *p = positions + 3 * (uint64_t)r->v[0];
        snprintf(where, sizeof where, " (at %.9g %.9g %.9g)", p[0], p[1], p[2]);
    }
    switch (r->problem) {
    case SL_ADJACENCY_DEGENERATE:
        snprintf(buf, size, "triangle %u repeats vertex %u%s: a degenerate triangle", r->t[0],
                 r->v[0], where);
        break;
    case SL_ADJACENCY_NONMANIFOLD_EDGE:
        snprintf(buf, size,
                 "the edge between vertices %u and %u%s is shared by %u triangles (%u, %u, %u, "
                 "...): a non-manifold edge", r->v[0], r->v[1], where, r->edge_triangles,
                 r->t[0], r->t[1], r->t[2]);
        break;
    case SL_ADJACENCY_INCONSISTENT_EDGE:
        snprintf(buf, size,
                 "triangles %u and %u both run the edge from vertex %u to %u%s: their "
                 "orientations disagree", r->t[0], r->t[1], r->v[0], r->v[1], where);
        break;
    case SL_ADJACENCY_NONMANIFOLD_VERTEX:
        snprintf(buf, size,
                 "the triangles around vertex %u%s form more than one fan: a non-manifold "
                 "vertex", r->v[0], where);
        break;
    default:
        if (size)
            buf[0] = '\0';
    }
    return buf;
}

void sl_mesh_adjacency_release(sl_mesh_adjacency *adj)
{
    free(adj->twin);
    free(adj->vertex_halfedge);
    free(adj->vertex_flags);
    free(adj->degenerate);
    memset(adj, 0, sizeof *adj);
}

static int check_input(const uint32_t *tri, uint64_t triangle_count, uint64_t vertex_count,
                       sl_error *err)
{
    if (triangle_count > SL_ADJACENCY_MAX_TRIANGLES)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "%llu triangles: the adjacency holds at most %u",
                            (unsigned long long)triangle_count, SL_ADJACENCY_MAX_TRIANGLES);
    if (vertex_count >= UINT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "%llu vertices: the adjacency holds at most 2^32 - 2",
                            (unsigned long long)vertex_count);
    for (uint64_t i = 0; i < 3 * triangle_count; i++)
        if (tri[i] >= vertex_count)
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "triangle %llu names vertex %u, but there are %llu vertices",
                                (unsigned long long)(i / 3), tri[i],
                                (unsigned long long)vertex_count);
    return SL_OK;
}

int sl_mesh_adjacency_build(const uint32_t *triangles, uint64_t triangle_count,
                            uint64_t vertex_count, const float *positions, uint32_t flags,
                            sl_mesh_adjacency *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    int rc = check_input(triangles, triangle_count, vertex_count, err);
    if (rc)
        return rc;
    sl_mesh_adjacency a;
    memset(&a, 0, sizeof a);
    a.vertex_count = (uint32_t)vertex_count;
    a.triangle_count = (uint32_t)triangle_count;
    a.triangles = triangles;
    uint64_t nh = 3 * triangle_count;
    a.twin = malloc((nh ? nh : 1) * sizeof *a.twin);
    a.vertex_halfedge = malloc((vertex_count ? vertex_count : 1) * sizeof *a.vertex_halfedge);
    a.vertex_flags = calloc(vertex_count ? vertex_count : 1, 1);
    a.degenerate = calloc(triangle_count ? triangle_count : 1, 1);
    if (!a.twin || !a.vertex_halfedge || !a.vertex_flags || !a.degenerate) {
        sl_mesh_adjacency_release(&a);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "adjacency of %llu triangles",
                            (unsigned long long)triangle_count);
    }
    memset(a.twin, 0xff, (nh ? nh : 1) * sizeof *a.twin);
    memset(a.vertex_halfedge, 0xff, (vertex_count ? vertex_count : 1) * sizeof *a.vertex_halfedge);
    sl_adjacency_report *r = &a.report;
    memset(r->v, 0xff, sizeof r->v);
    memset(r->t, 0xff, sizeof r->t);
    for (uint64_t t = 0; t < triangle_count; t++) {
        const uint32_t *c = triangles + 3 * t;
        if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) {
            a.degenerate[t] = 1;
            r->degenerate_triangles++;
            note_problem(r, SL_ADJACENCY_DEGENERATE, c[0] == c[1] || c[0] == c[2] ? c[0] : c[1],
                         UINT32_MAX, (uint32_t)t, UINT32_MAX, UINT32_MAX, 0);
        }
    }
    rc = build_twins(&a, r, err);
    if (!rc)
        rc = build_vertices(&a, r, err);
    if (!rc)
        rc = count_boundary_loops(&a, r, err);
    if (!rc && (flags & SL_ADJACENCY_STRICT) && r->problem != SL_ADJACENCY_OK) {
        char text[400];
        rc = sl_error_set(err, SL_E_BADINPUT, 0, NULL, "%s",
                          sl_adjacency_problem_text(r, positions, text, sizeof text));
    }
    if (rc) {
        sl_mesh_adjacency_release(&a);
        return rc;
    }
    r->euler_characteristic = (int64_t)r->used_vertices - (int64_t)r->edges +
                              (int64_t)(triangle_count - r->degenerate_triangles);
    *out = a;
    return SL_OK;
}
