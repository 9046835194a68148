/* Triangulation of the cluster polygons (paper 2, section 3: "triangulation"; the mesh
 * toolkit's constrained Delaunay triangulation, geometry/cdt.h).
 *
 * A cluster's polygon is its loops, each the vertices its borders keep, in the loop's
 * order (the cluster on the left), projected into the cluster's frame; no interior point.
 * The triangulation tiles exactly the points the loops wind once around and refuses loops
 * that cross, overlap or wind twice: what the proof of the bound takes as given
 * (docs/clustering.md). A polygon is also refused here when the triangulation had to split
 * a loop edge at a point lying on it or merge coincident points: the cluster across that
 * edge would not split it, and the mesh would get a crack. Refused polygons keep their
 * previous triangles; the pass then undoes straightening around them.
 */
#include <stdlib.h>
#include <string.h>

#include "geometry/cdt.h"
#include "geometry/predicates.h"
#include "stages/cluster/cluster_internal.h"

int cl_triangulation_init(cl_triangulation *t, uint32_t clusters)
{
    t->count = calloc(clusters ? clusters : 1, sizeof *t->count);
    t->tri = calloc(clusters ? clusters : 1, sizeof *t->tri);
    return t->count && t->tri ? 0 : -1;
}

void cl_triangulation_release(cl_triangulation *t, uint32_t clusters)
{
    if (t->tri)
        for (uint32_t k = 0; k < clusters; k++)
            free(t->tri[k]);
    free(t->tri);
    free(t->count);
    memset(t, 0, sizeof *t);
}

int cl_keep_input(const cl_clusters *c, const uint32_t *triangles, uint32_t k,
                  cl_triangulation *t)
{
    uint32_t n = c->tri_start[k + 1] - c->tri_start[k];
    uint32_t *tri = malloc(3 * (size_t)(n ? n : 1) * sizeof *tri);
    if (!tri)
        return -1;
    for (uint32_t i = 0; i < n; i++)
        memcpy(tri + 3 * (size_t)i, triangles + 3 * (uint64_t)c->tris[c->tri_start[k] + i],
               3 * sizeof *tri);
    free(t->tri[k]);
    t->tri[k] = tri;
    t->count[k] = n;
    return 0;
}

/* Per-thread scratch: the polygon being built. */
typedef struct scratch {
    uint32_t *local;        /* vertex -> local point index, CL_NONE between uses */
    uint32_t *global;       /* local -> vertex */
    double *uv;
    uint32_t *loop_start, *loop_points;
    uint32_t points, points_cap, loops, loops_cap, entries, entries_cap;
} scratch;

static int grow(void **p, uint32_t need, uint32_t *cap, size_t size)
{
    if (need <= *cap)
        return 0;
    uint32_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    void *q = realloc(*p, (size_t)c * size);
    if (!q)
        return -1;
    *p = q;
    *cap = c;
    return 0;
}

static int add_point(scratch *s, const double *frame, const float *positions, uint32_t v)
{
    if (s->local[v] == CL_NONE) {
        uint32_t cap = s->points_cap;
        if (grow((void **)&s->global, s->points + 1, &cap, sizeof *s->global))
            return -1;
        cap = s->points_cap;
        if (grow((void **)&s->uv, s->points + 1, &cap, 2 * sizeof *s->uv))
            return -1;
        s->points_cap = cap;
        s->global[s->points] = v;
        cl_project(frame, positions + 3 * (uint64_t)v, s->uv + 2 * (size_t)s->points, NULL);
        s->local[v] = s->points++;
    }
    if (grow((void **)&s->loop_points, s->entries + 1, &s->entries_cap, sizeof *s->loop_points))
        return -1;
    s->loop_points[s->entries++] = s->local[v];
    return 0;
}

/* Builds cluster k's polygon into s. */
static int build_polygon(const cl_clusters *c, const cl_borders *b, const float *positions,
                         const uint8_t *keep, uint32_t k, scratch *s)
{
    const double *frame = c->frame + 12 * (uint64_t)k;
    s->points = s->loops = s->entries = 0;
    for (uint32_t l = b->cluster_loop[k]; l < b->cluster_loop[k + 1]; l++) {
        if (grow((void **)&s->loop_start, s->loops + 2, &s->loops_cap, sizeof *s->loop_start))
            return -1;
        s->loop_start[s->loops++] = s->entries;
        for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++) {
            uint32_t br = b->pieces[p] >> 1, rev = b->pieces[p] & 1u;
            uint32_t first = b->start[br], last = b->start[br + 1] - 1;
            for (uint32_t i = 0; i < last - first; i++) { /* the last entry starts the next piece */
                uint32_t e = rev ? last - i : first + i;
                if (keep[e] && add_point(s, frame, positions, b->verts[e]))
                    return -1;
            }
        }
    }
    s->loop_start[s->loops] = s->entries;
    return 0;
}

static void reset_local(scratch *s)
{
    for (uint32_t i = 0; i < s->points; i++)
        s->local[s->global[i]] = CL_NONE;
}

/* Triangulates cluster k: 1 refused, 0 done (t->tri[k] replaced), negative on an error. */
static int triangulate_one(const cl_clusters *c, const cl_borders *b, const float *positions,
                           const uint8_t *keep, uint32_t k, scratch *s, cl_triangulation *t,
                           sl_error *err)
{
    if (build_polygon(c, b, positions, keep, k, s)) {
        reset_local(s);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "polygon of cluster %u", k);
    }
    if (s->loops == 1 && s->entries == 3 && s->points == 3) { /* a triangle: no search */
        const double *uv = s->uv;
        int ccw = sl_orient2d(uv, uv + 2, uv + 4) > 0;
        uint32_t *tri = ccw ? malloc(3 * sizeof *tri) : NULL;
        if (ccw && !tri) {
            reset_local(s);
            return sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangles of cluster %u", k);
        }
        if (ccw) {
            for (int i = 0; i < 3; i++)
                tri[i] = s->global[s->loop_points[i]];
            free(t->tri[k]);
            t->tri[k] = tri;
            t->count[k] = 1;
        }
        reset_local(s);
        return !ccw;
    }
    sl_cdt_input in = {s->points, s->uv, s->loops, s->loop_start, s->loop_points};
    sl_cdt_result *res = NULL;
    sl_error scratch_err;
    sl_error_init(&scratch_err);
    int rc = sl_cdt_triangulate(&in, 0, &res, NULL, &scratch_err);
    int refused = rc != 0 || res->split_edges || res->merged_points || res->unused_points ||
                  res->triangle_count == 0;
    if (rc == SL_E_NOMEM) {
        sl_error_merge(err, &scratch_err);
        reset_local(s);
        return rc;
    }
    if (!refused) {
        uint32_t *tri = malloc(3 * res->triangle_count * sizeof *tri);
        if (!tri) {
            sl_cdt_free(res);
            reset_local(s);
            return sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangles of cluster %u", k);
        }
        for (uint64_t i = 0; i < 3 * res->triangle_count; i++)
            tri[i] = s->global[res->triangles[i]];
        free(t->tri[k]);
        t->tri[k] = tri;
        t->count[k] = (uint32_t)res->triangle_count;
    }
    sl_cdt_free(res);
    reset_local(s);
    return refused;
}

int cl_triangulate(const cl_clusters *c, const cl_borders *b, const float *positions,
                   const uint8_t *keep, const uint8_t *dirty, uint8_t *failed,
                   cl_triangulation *t, sl_error *err, uint64_t vertex_count)
{
    int64_t nc = c->count;
    int rc = 0;
#pragma omp parallel
    {
        scratch s;
        memset(&s, 0, sizeof s);
        s.local = malloc((vertex_count ? vertex_count : 1) * sizeof *s.local);
        sl_error terr;
        sl_error_init(&terr);
        int trc = s.local ? 0 : sl_error_set(&terr, SL_E_NOMEM, 0, NULL, "triangulation scratch");
        if (s.local)
            memset(s.local, 0xff, vertex_count * sizeof *s.local);
#pragma omp for schedule(dynamic, 16)
        for (int64_t k = 0; k < nc; k++) {
            if (trc || !dirty[k] || c->kept[k])
                continue;
            int r = triangulate_one(c, b, positions, keep, (uint32_t)k, &s, t, &terr);
            if (r < 0)
                trc = r;
            else
                failed[k] = (uint8_t)r;
        }
#pragma omp critical(cluster_triangulate)
        if (trc && !rc) {
            rc = trc;
            sl_error_merge(err, &terr);
        }
        free(s.local);
        free(s.global);
        free(s.uv);
        free(s.loop_start);
        free(s.loop_points);
    }
    return rc;
}

/* One segment of a cluster's polygon: its two vertices, their projections and the border
 * it lies on. */
typedef struct poly_segment {
    uint32_t v[2], border;
    double a[2], b[2];
    double lo[2], hi[2];
} poly_segment;

/* 1 when collinear points p, q, r have r within the box of p and q. */
static int on_segment(const double p[2], const double q[2], const double r[2])
{
    return r[0] >= (p[0] < q[0] ? p[0] : q[0]) && r[0] <= (p[0] > q[0] ? p[0] : q[0]) &&
           r[1] >= (p[1] < q[1] ? p[1] : q[1]) && r[1] <= (p[1] > q[1] ? p[1] : q[1]);
}

/* 1 when segments s and t of one polygon meet anywhere except at a vertex they share as
 * loop neighbours (then only when they overlap along a line). */
static int segments_meet(const poly_segment *s, const poly_segment *t)
{
    for (int k = 0; k < 2; k++)
        if (s->hi[k] < t->lo[k] || t->hi[k] < s->lo[k])
            return 0;
    int shared = (s->v[0] == t->v[0]) + (s->v[0] == t->v[1]) + (s->v[1] == t->v[0]) +
                 (s->v[1] == t->v[1]);
    if (shared >= 2)
        return 1; /* the same segment twice */
    if (shared == 1) { /* meeting at the shared vertex is what a loop does: overlap only */
        const double *o = s->v[0] == t->v[0] || s->v[0] == t->v[1] ? s->a : s->b;
        const double *p = o == s->a ? s->b : s->a;
        const double *q = t->v[0] == s->v[0] || t->v[0] == s->v[1] ? t->b : t->a;
        if (sl_orient2d(o, p, q) != 0)
            return 0;
        return (p[0] - o[0]) * (q[0] - o[0]) + (p[1] - o[1]) * (q[1] - o[1]) > 0;
    }
    int o1 = sl_orient2d(s->a, s->b, t->a), o2 = sl_orient2d(s->a, s->b, t->b);
    int o3 = sl_orient2d(t->a, t->b, s->a), o4 = sl_orient2d(t->a, t->b, s->b);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return 1;
    return (o1 == 0 && on_segment(s->a, s->b, t->a)) || (o2 == 0 && on_segment(s->a, s->b, t->b)) ||
           (o3 == 0 && on_segment(t->a, t->b, s->a)) || (o4 == 0 && on_segment(t->a, t->b, s->b));
}

int cl_polygon_crossings(const cl_clusters *c, const cl_borders *b, const float *positions,
                         const uint8_t *keep, uint32_t k, uint8_t *marked, uint32_t *out)
{
    const double *frame = c->frame + 12 * (uint64_t)k;
    uint32_t count = 0, cap = 0;
    poly_segment *seg = NULL;
    int found = 0;
    for (uint32_t l = b->cluster_loop[k]; l < b->cluster_loop[k + 1]; l++) {
        uint32_t loop_first = count;
        for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++) {
            uint32_t br = b->pieces[p] >> 1, rev = b->pieces[p] & 1u;
            uint32_t s = b->start[br], e = b->start[br + 1] - 1;
            for (uint32_t i = 0; i < e - s; i++) { /* the last entry starts the next piece */
                uint32_t at = rev ? e - i : s + i;
                if (!keep[at])
                    continue;
                if (grow((void **)&seg, count + 1, &cap, sizeof *seg)) {
                    free(seg);
                    return -1;
                }
                seg[count].v[0] = b->verts[at]; /* the segment from here lies on border br */
                seg[count++].border = br;
            }
        }
        for (uint32_t i = loop_first; i < count; i++)
            seg[i].v[1] = seg[i + 1 < count ? i + 1 : loop_first].v[0];
    }
    /* a quadratic scan: refused polygons are few and small; larger ones are left to the
     * caller's undoing of every border */
    if (count > 4096) {
        free(seg);
        return 0;
    }
    for (uint32_t i = 0; i < count; i++) {
        poly_segment *s = seg + i;
        cl_project(frame, positions + 3 * (uint64_t)s->v[0], s->a, NULL);
        cl_project(frame, positions + 3 * (uint64_t)s->v[1], s->b, NULL);
        for (int d = 0; d < 2; d++)
            s->lo[d] = s->a[d] < s->b[d] ? s->a[d] : s->b[d],
            s->hi[d] = s->a[d] > s->b[d] ? s->a[d] : s->b[d];
    }
    for (uint32_t i = 0; i < count; i++)
        for (uint32_t j = i + 1; j < count; j++) {
            if (!segments_meet(seg + i, seg + j))
                continue;
            uint32_t bi = seg[i].border, bj = seg[j].border;
            if (!marked[bi])
                marked[bi] = 1, out[found++] = bi;
            if (!marked[bj])
                marked[bj] = 1, out[found++] = bj;
        }
    for (int i = 0; i < found; i++)
        marked[out[i]] = 0;
    free(seg);
    return found;
}
