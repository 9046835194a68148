/* The prepared mesh of the segment method (segment_internal.h): adjacency, segmentation
 * (paper 3, section 3.1), loops and corners, per-segment frames and fitness, and the
 * chains that boundary trimming works on.
 *
 * A segment's frame: its area-weighted normal n and an orthonormal u, v. Equation 1 makes
 * every triangle of a segment lie within delta_seg < 90 degrees of every other, so within
 * delta_seg of n (n lies in the convex hull of their normals): none turns over when
 * projected along n. That is why the patch is projected along n and not along the
 * least-squares plane's normal, which on a curved patch can lean away from some of its
 * triangles (the least-squares plane is still where equations 3-8 measure distances).
 *
 * Chains: a segment's loops split at fixed vertices (corners, and anchors added so that
 * every loop keeps at least three vertices); the two-segment vertices between are what
 * trimming may remove. Each chain is registered once, by the lower of its two segments.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/cdt.h"
#include "geometry/predicates.h"
#include "geometry/vec3.h"
#include "stages/segment/segment_internal.h"

void seg_sub(const float *a, const float *b, double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = (double)a[k] - (double)b[k];
}

static double dist2(const float *a, const float *b)
{
    double d[3];
    seg_sub(a, b, d);
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

void sl_segment_model_free(sl_segment_model *m)
{
    if (!m)
        return;
    if (!m->borrowed_adjacency)
        sl_mesh_adjacency_release(&m->adj);
    else
        m->vertex_normal = NULL; /* the base's */
    sl_segmentation_release(&m->seg);
    sl_segment_loops_release(&m->loops);
    free(m->seg_tri_start);
    free(m->seg_tris);
    free(m->by_size);
    free(m->frame);
    free(m->unfit);
    free(m->fixed);
    free(m->vertex_normal);
    free(m->chain_start);
    free(m->chain_vertices);
    free(m->chain_segments);
    free(m->seg_chain_start);
    free(m->seg_chains);
    free(m);
}

const uint32_t *sl_segment_model_map(const sl_segment_model *m, uint32_t *segment_count)
{
    if (segment_count)
        *segment_count = m->seg.segment_count;
    return m->seg.segment;
}

static int check_input(const sl_segment_input *in, double *diagonal, sl_error *err)
{
    if (in->triangle_count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "the mesh has no triangle to simplify");
    if (in->vertex_count >= UINT32_MAX || in->triangle_count > SL_ADJACENCY_MAX_TRIANGLES)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "%llu vertices and %llu triangles: the segment method takes at "
                            "most 2^32 - 2 vertices and %u triangles",
                            (unsigned long long)in->vertex_count,
                            (unsigned long long)in->triangle_count, SL_ADJACENCY_MAX_TRIANGLES);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < 3 * in->triangle_count; i++) {
        uint32_t v = in->triangles[i];
        if (v >= in->vertex_count)
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "triangle %llu names vertex %u, but there are %llu vertices",
                                (unsigned long long)(i / 3), v,
                                (unsigned long long)in->vertex_count);
        const float *p = in->positions + 3 * (uint64_t)v;
        for (int k = 0; k < 3; k++) {
            if (!isfinite(p[k]))
                return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                    "vertex %u has a non-finite coordinate", v);
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = p[k] > hi[k] ? p[k] : hi[k];
        }
    }
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    *diagonal = sqrt(d2);
    if (!(*diagonal > 0.0) || !isfinite(*diagonal))
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "every vertex of the mesh is at one point: nothing to simplify");
    return SL_OK;
}

/* Triangles by segment (stable counting sort). */
static int bucket_triangles(sl_segment_model *m)
{
    uint32_t ns = m->seg.segment_count;
    m->seg_tri_start = calloc((size_t)ns + 2, sizeof *m->seg_tri_start);
    m->seg_tris = malloc((size_t)m->triangle_count * sizeof *m->seg_tris);
    if (!m->seg_tri_start || !m->seg_tris)
        return -1;
    for (uint32_t t = 0; t < m->triangle_count; t++)
        m->seg_tri_start[m->seg.segment[t] + 2]++;
    for (uint32_t k = 0; k < ns; k++)
        m->seg_tri_start[k + 2] += m->seg_tri_start[k + 1];
    for (uint32_t t = 0; t < m->triangle_count; t++)
        m->seg_tris[m->seg_tri_start[m->seg.segment[t] + 1]++] = t;
    return 0;
}

/* Do segment k's loops, projected in its frame, bound a region the triangulation
 * accepts (no crossing, winding 0 or 1)? With no triangle turned over this makes the
 * projection one-to-one (docs/mesh-toolkit.md, "Folds"). Out of memory: no. */
static int cmp_pair(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y;
    return a[0] != b[0] ? (a[0] > b[0]) - (a[0] < b[0]) : (a[1] > b[1]) - (a[1] < b[1]);
}

static int loops_embed(const sl_segment_model *m, uint32_t k)
{
    const seg_frame *f = &m->frame[k];
    uint32_t l0 = m->loops.segment_loop_start[k], l1 = m->loops.segment_loop_start[k + 1];
    uint32_t b = m->loops.loop_start[l0], e = m->loops.loop_start[l1], n = e - b;
    double *pts = malloc(2 * (size_t)(n ? n : 1) * sizeof *pts);
    uint32_t *start = malloc(((size_t)(l1 - l0) + 1) * sizeof *start);
    uint32_t *idx = malloc((size_t)(n ? n : 1) * sizeof *idx);
    uint32_t (*by_vertex)[2] = malloc((size_t)(n ? n : 1) * sizeof *by_vertex);
    int ok = 0;
    if (pts && start && idx && by_vertex) {
        /* one point per distinct vertex (a loop may pass a vertex twice) */
        for (uint32_t i = 0; i < n; i++) {
            by_vertex[i][0] = m->adj.triangles[m->loops.halfedges[b + i]];
            by_vertex[i][1] = i;
        }
        qsort(by_vertex, n, sizeof *by_vertex, cmp_pair);
        uint32_t points = 0;
        for (uint32_t i = 0; i < n; i++) {
            if (i == 0 || by_vertex[i][0] != by_vertex[i - 1][0]) {
                const float *q = m->positions + 3 * (uint64_t)by_vertex[i][0];
                double d[3] = {(double)q[0] - f->origin[0], (double)q[1] - f->origin[1],
                               (double)q[2] - f->origin[2]};
                pts[2 * points] = d[0] * f->u[0] + d[1] * f->u[1] + d[2] * f->u[2];
                pts[2 * points + 1] = d[0] * f->v[0] + d[1] * f->v[1] + d[2] * f->v[2];
                points++;
            }
            idx[by_vertex[i][1]] = points - 1;
        }
        for (uint32_t l = l0; l <= l1; l++)
            start[l - l0] = m->loops.loop_start[l] - b;
        sl_cdt_input in = {points, pts, l1 - l0, start, idx};
        sl_cdt_result *res = NULL;
        sl_error scratch;
        sl_error_init(&scratch);
        ok = sl_cdt_triangulate(&in, 0, &res, NULL, &scratch) == SL_OK && res->split_edges == 0;
        sl_cdt_free(res);
    }
    free(pts);
    free(start);
    free(idx);
    free(by_vertex);
    return ok;
}

/* Frame and fitness of segment k; `stamp` is per-thread scratch (vertex_count, holds
 * values != k + 1 on entry). */
static void fit_segment(sl_segment_model *m, uint32_t k, uint32_t *stamp)
{
    seg_frame *f = &m->frame[k];
    memset(f, 0, sizeof *f);
    uint32_t b = m->seg_tri_start[k], e = m->seg_tri_start[k + 1];
    double area_sum = 0, centroid[3] = {0, 0, 0};
    for (uint32_t i = b; i < e; i++) {
        const uint32_t *c = m->triangles + 3 * (uint64_t)m->seg_tris[i];
        double x[3], u[3], w[3];
        seg_sub(m->positions + 3 * (uint64_t)c[1], m->positions + 3 * (uint64_t)c[0], u);
        seg_sub(m->positions + 3 * (uint64_t)c[2], m->positions + 3 * (uint64_t)c[0], w);
        sl_cross3(u, w, x);
        double a = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        area_sum += a;
        for (int j = 0; j < 3; j++) {
            f->normal[j] += x[j];
            for (int q = 0; q < 3; q++)
                centroid[j] += a * m->positions[3 * (uint64_t)c[q] + j] / 3.0;
        }
    }
    double len = sqrt(f->normal[0] * f->normal[0] + f->normal[1] * f->normal[1] +
                      f->normal[2] * f->normal[2]);
    if (m->adj.degenerate[m->seg_tris[b]] || !(len > 0.0) || !(area_sum > 0.0)) {
        m->unfit[k] = SEG_UNFIT_NO_NORMAL;
        return;
    }
    for (int j = 0; j < 3; j++) {
        f->normal[j] /= len;
        f->origin[j] = centroid[j] / area_sum;
    }
    const double *n = f->normal;
    double ax[3] = {0, 0, 0};
    ax[fabs(n[0]) <= fabs(n[1]) && fabs(n[0]) <= fabs(n[2]) ? 0 : fabs(n[1]) <= fabs(n[2]) ? 1 : 2] = 1;
    sl_cross3(n, ax, f->u);
    double ul = sqrt(f->u[0] * f->u[0] + f->u[1] * f->u[1] + f->u[2] * f->u[2]);
    for (int j = 0; j < 3; j++)
        f->u[j] /= ul;
    sl_cross3(n, f->u, f->v);
    if (m->loops.outer[k] == SEG_NONE) {
        m->unfit[k] = SEG_UNFIT_NO_OUTER;
        return;
    }
    /* Euler characteristic of the patch: a disc with L - 1 holes has 2 - L */
    uint64_t vertices = 0, boundary = 0;
    for (uint32_t i = b; i < e; i++)
        for (int c = 0; c < 3; c++) {
            uint32_t v = m->triangles[3 * (uint64_t)m->seg_tris[i] + c];
            if (stamp[v] != k + 1) {
                stamp[v] = k + 1;
                vertices++;
            }
        }
    uint32_t l0 = m->loops.segment_loop_start[k], l1 = m->loops.segment_loop_start[k + 1];
    boundary = m->loops.loop_start[l1] - m->loops.loop_start[l0];
    int64_t faces = e - b, edges = (int64_t)(3 * (uint64_t)faces + boundary) / 2;
    /* A loop vertex visited twice (the boundary touches itself, or a hole touches the
     * outer loop) joins two boundary points: one less than the disc with holes has. */
    int64_t touches = 0;
    for (uint32_t i = m->loops.loop_start[l0]; i < m->loops.loop_start[l1]; i++) {
        uint32_t v = m->adj.triangles[m->loops.halfedges[i]];
        if (stamp[v] == k + 1)
            stamp[v] = k + 1 + UINT32_MAX / 2; /* first visit */
        else
            touches++;
    }
    if ((int64_t)vertices - edges + faces + touches != 2 - (int64_t)(l1 - l0)) {
        m->unfit[k] = SEG_UNFIT_TOPOLOGY;
        return;
    }
    for (uint32_t i = b; i < e; i++) { /* no triangle turns over in the frame (exact) */
        const uint32_t *c = m->triangles + 3 * (uint64_t)m->seg_tris[i];
        double uv[3][2];
        for (int q = 0; q < 3; q++) {
            double d[3];
            const float *p = m->positions + 3 * (uint64_t)c[q];
            for (int j = 0; j < 3; j++)
                d[j] = (double)p[j] - f->origin[j];
            uv[q][0] = d[0] * f->u[0] + d[1] * f->u[1] + d[2] * f->u[2];
            uv[q][1] = d[0] * f->v[0] + d[1] * f->v[1] + d[2] * f->v[2];
        }
        if (sl_orient2d(uv[0], uv[1], uv[2]) <= 0) {
            m->unfit[k] = SEG_UNFIT_FOLD;
            return;
        }
    }
    m->unfit[k] = loops_embed(m, k) ? SEG_FIT : SEG_UNFIT_OVERLAP;
}

/* Loop l's vertices (origins of its half-edges). */
static uint32_t loop_vertex(const sl_segment_model *m, uint32_t i)
{
    return m->adj.triangles[m->loops.halfedges[i]];
}

/* Makes every loop hold at least three fixed vertices (serial: a fixed order): the
 * lowest vertex, the farthest from it, the farthest from both. */
static void anchor_loops(sl_segment_model *m)
{
    for (uint32_t l = 0; l < m->loops.loop_count; l++) {
        uint32_t b = m->loops.loop_start[l], e = m->loops.loop_start[l + 1], fixed[3], nf = 0;
        for (uint32_t i = b; i < e && nf < 3; i++)
            if (m->fixed[loop_vertex(m, i)])
                fixed[nf++] = loop_vertex(m, i);
        while (nf < 3) {
            uint32_t best = SEG_NONE;
            double best_d = -1;
            for (uint32_t i = b; i < e; i++) {
                uint32_t v = loop_vertex(m, i);
                if (m->fixed[v])
                    continue;
                double d = nf ? INFINITY : -(double)v; /* none fixed yet: the lowest index */
                for (uint32_t j = 0; j < nf; j++) {
                    double dd = dist2(m->positions + 3 * (uint64_t)v,
                                      m->positions + 3 * (uint64_t)fixed[j]);
                    d = dd < d ? dd : d;
                }
                if (best == SEG_NONE || d > best_d) {
                    best = v;
                    best_d = d;
                }
            }
            if (best == SEG_NONE)
                break; /* a loop of fewer than three distinct vertices */
            m->fixed[best] = 1;
            fixed[nf++] = best;
        }
    }
}

/* The chains, registered by the lower segment. Two passes: count, fill. */
static int build_chains(sl_segment_model *m)
{
    const sl_segment_loops *L = &m->loops;
    uint64_t count = 0, verts = 0;
    for (int fill = 0; fill < 2; fill++) {
        count = verts = 0;
        for (uint32_t k = 0; k < L->segment_count; k++)
            for (uint32_t l = L->segment_loop_start[k]; l < L->segment_loop_start[k + 1]; l++) {
                uint32_t b = L->loop_start[l], e = L->loop_start[l + 1], n = e - b, start = SEG_NONE;
                for (uint32_t i = 0; i < n && start == SEG_NONE; i++)
                    if (m->fixed[loop_vertex(m, b + i)])
                        start = i;
                if (start == SEG_NONE)
                    continue; /* cannot happen after anchor_loops */
                for (uint32_t i = 0; i < n;) { /* a chain from fixed vertex start + i */
                    uint32_t j = i + 1;
                    while (j < n && !m->fixed[loop_vertex(m, b + (start + j) % n)])
                        j++;
                    uint32_t h = L->halfedges[b + (start + i) % n], tw = m->adj.twin[h];
                    uint32_t other = tw == SEG_NONE ? SEG_NONE : m->seg.segment[sl_halfedge_face(tw)];
                    if (j - i >= 2 && other != SEG_NONE && k < other) {
                        if (fill) {
                            m->chain_start[count] = (uint32_t)verts;
                            m->chain_segments[count][0] = k;
                            m->chain_segments[count][1] = other;
                            for (uint32_t q = i; q <= j; q++)
                                m->chain_vertices[verts + q - i] = loop_vertex(m, b + (start + q) % n);
                        }
                        count++;
                        verts += j - i + 1;
                    }
                    i = j;
                }
            }
        if (!fill) {
            m->chain_start = malloc((count + 1) * sizeof *m->chain_start);
            m->chain_vertices = malloc((verts ? verts : 1) * sizeof *m->chain_vertices);
            m->chain_segments = malloc((count ? count : 1) * sizeof *m->chain_segments);
            if (!m->chain_start || !m->chain_vertices || !m->chain_segments)
                return -1;
        }
    }
    m->chain_count = (uint32_t)count;
    m->chain_start[count] = (uint32_t)verts;
    /* each segment's chains (a chain under both its segments), ascending */
    uint32_t ns = L->segment_count;
    m->seg_chain_start = calloc((size_t)ns + 2, sizeof *m->seg_chain_start);
    m->seg_chains = malloc(2 * (count ? count : 1) * sizeof *m->seg_chains);
    if (!m->seg_chain_start || !m->seg_chains)
        return -1;
    for (uint32_t c = 0; c < count; c++) {
        m->seg_chain_start[m->chain_segments[c][0] + 2]++;
        m->seg_chain_start[m->chain_segments[c][1] + 2]++;
    }
    for (uint32_t k = 0; k < ns; k++)
        m->seg_chain_start[k + 2] += m->seg_chain_start[k + 1];
    for (uint32_t c = 0; c < count; c++)
        for (int side = 0; side < 2; side++)
            m->seg_chains[m->seg_chain_start[m->chain_segments[c][side] + 1]++] = c;
    return 0;
}

/* Segments with nothing to remove: no interior vertex, every loop vertex fixed. */
static void mark_trivial(sl_segment_model *m)
{
    uint8_t *has = calloc(m->seg.segment_count ? m->seg.segment_count : 1, 1);
    if (!has)
        return; /* only an optimisation */
    for (uint32_t v = 0; v < m->vertex_count; v++)
        if (m->loops.vertex_kind[v] == SL_SEGMENT_VERTEX_INTERIOR && !m->fixed[v])
            has[m->seg.segment[sl_halfedge_face(m->adj.vertex_halfedge[v])]] = 1;
    for (uint32_t c = 0; c < m->chain_count; c++) {
        has[m->chain_segments[c][0]] = 1;
        has[m->chain_segments[c][1]] = 1;
    }
    for (uint32_t k = 0; k < m->seg.segment_count; k++)
        if (!has[k] && m->unfit[k] == SEG_FIT)
            m->unfit[k] = SEG_UNFIT_TRIVIAL;
    free(has);
}

/* Area-weighted unit vertex normals of the input (serial sums: a fixed order). */
static int vertex_normals(sl_segment_model *m)
{
    m->vertex_normal = calloc(3 * (size_t)(m->vertex_count ? m->vertex_count : 1), sizeof(double));
    if (!m->vertex_normal)
        return -1;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        if (m->adj.degenerate[t])
            continue;
        const uint32_t *c = m->triangles + 3 * (uint64_t)t;
        double u[3], w[3], x[3];
        seg_sub(m->positions + 3 * (uint64_t)c[1], m->positions + 3 * (uint64_t)c[0], u);
        seg_sub(m->positions + 3 * (uint64_t)c[2], m->positions + 3 * (uint64_t)c[0], w);
        sl_cross3(u, w, x);
        for (int q = 0; q < 3; q++)
            for (int j = 0; j < 3; j++)
                m->vertex_normal[3 * (size_t)c[q] + j] += x[j];
    }
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        double *n = m->vertex_normal + 3 * (size_t)v;
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int j = 0; j < 3; j++)
            n[j] = len > 0 ? n[j] / len : 0;
    }
    return 0;
}

/* The adjacency and the segmentation of equation 1. */
static int build_base(sl_segment_model *m, const sl_segment_config *cfg, sl_error *err)
{
    int rc = sl_mesh_adjacency_build(m->triangles, m->triangle_count, m->vertex_count,
                                     m->positions, 0, &m->adj, err);
    if (rc)
        return rc;
    const sl_adjacency_report *r = &m->adj.report;
    m->used_vertices = r->used_vertices;
    m->input_boundary_edges = r->boundary_edges;
    m->input_nonmanifold_edges = r->nonmanifold_edges;
    m->input_inconsistent_edges = r->inconsistent_edges;
    m->input_nonmanifold_vertices = r->nonmanifold_vertices;
    m->input_euler = r->euler_characteristic;
    sl_region_grow_config g = sl_region_grow_default_config();
    g.delta_seg = cfg->delta_seg;
    g.target_segments = cfg->target_segments;
    return sl_region_grow(&m->adj, m->positions, &g, &m->seg, err);
}

static int cmp_key(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* m->by_size: the segments by triangle count, descending, ties by id. 0 or -1 (memory). */
static int order_by_size(sl_segment_model *m)
{
    uint32_t ns = m->seg.segment_count;
    uint64_t *key = malloc((ns ? ns : 1) * sizeof *key);
    m->by_size = malloc((ns ? ns : 1) * sizeof *m->by_size);
    if (!key || !m->by_size) {
        free(key);
        return -1;
    }
    for (uint32_t k = 0; k < ns; k++)
        key[k] = (uint64_t)(UINT32_MAX - (m->seg_tri_start[k + 1] - m->seg_tri_start[k])) << 32 | k;
    qsort(key, ns, sizeof *key, cmp_key);
    for (uint32_t i = 0; i < ns; i++)
        m->by_size[i] = (uint32_t)key[i];
    free(key);
    return 0;
}

/* Everything that follows from the labels: loops, frames, fitness, fixed vertices,
 * chains. Returns 0, SL_E_NOMEM, SL_E_BADINPUT (a label out of range). */
static int build_labelled(sl_segment_model *m, sl_error *err)
{
    int rc = sl_segment_loops_build(&m->adj, m->positions, m->seg.segment, m->seg.segment_count,
                                    &m->loops, err);
    if (rc)
        return rc;
    uint32_t ns = m->seg.segment_count;
    m->frame = malloc((ns ? ns : 1) * sizeof *m->frame);
    m->unfit = calloc(ns ? ns : 1, 1);
    m->fixed = malloc(m->vertex_count ? m->vertex_count : 1);
    int ok = m->frame && m->unfit && m->fixed && bucket_triangles(m) == 0 &&
             order_by_size(m) == 0;
    if (ok) {
        int64_t nsi = ns;
#pragma omp parallel
        {
            uint32_t *stamp = calloc(m->vertex_count ? m->vertex_count : 1, sizeof *stamp);
            if (!stamp) {
#pragma omp atomic write
                ok = 0;
            }
#pragma omp for schedule(dynamic, 16)
            for (int64_t i = 0; i < nsi; i++)
                if (stamp)
                    fit_segment(m, m->by_size[i], stamp);
            free(stamp);
        }
    }
    if (ok) {
        for (uint32_t v = 0; v < m->vertex_count; v++)
            m->fixed[v] = m->loops.vertex_kind[v] == SL_SEGMENT_VERTEX_CORNER ||
                          m->loops.vertex_kind[v] == SL_SEGMENT_VERTEX_UNUSED;
        anchor_loops(m);
        ok = build_chains(m) == 0;
    }
    if (!ok)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "segment model of %u triangles",
                            m->triangle_count);
    mark_trivial(m);
    return SL_OK;
}

int sl_segment_model_build(const sl_segment_config *cfg, const sl_segment_input *in,
                           sl_segment_model **out, sl_progress *progress, sl_error *err)
{
    *out = NULL;
    double diagonal = 0;
    int rc = sl_segment_check_config(cfg, err);
    if (!rc)
        rc = check_input(in, &diagonal, err);
    if (rc)
        return rc;
    sl_segment_model *m = calloc(1, sizeof *m);
    if (!m)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "segment model");
    m->vertex_count = (uint32_t)in->vertex_count;
    m->triangle_count = (uint32_t)in->triangle_count;
    m->positions = in->positions;
    m->triangles = in->triangles;
    m->diagonal = diagonal;
    rc = build_base(m, cfg, err);
    if (!rc && vertex_normals(m))
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "vertex normals of %u vertices", m->vertex_count);
    if (!rc && sl_progress_step(progress, "segment", 0.2))
        rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "segmentation interrupted");
    if (!rc)
        rc = build_labelled(m, err);
    if (rc) {
        sl_segment_model_free(m);
        return rc;
    }
    *out = m;
    return SL_OK;
}

int seg_model_relabel(const sl_segment_model *base, uint32_t *labels, uint32_t count,
                      sl_segment_model **out, sl_error *err)
{
    *out = NULL;
    sl_segment_model *m = calloc(1, sizeof *m);
    if (!m) {
        free(labels);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "segment model");
    }
    m->vertex_count = base->vertex_count;
    m->triangle_count = base->triangle_count;
    m->positions = base->positions;
    m->triangles = base->triangles;
    m->diagonal = base->diagonal;
    m->adj = base->adj;
    m->borrowed_adjacency = 1;
    m->vertex_normal = base->vertex_normal; /* borrowed too */
    m->used_vertices = base->used_vertices;
    m->input_boundary_edges = base->input_boundary_edges;
    m->input_nonmanifold_edges = base->input_nonmanifold_edges;
    m->input_inconsistent_edges = base->input_inconsistent_edges;
    m->input_nonmanifold_vertices = base->input_nonmanifold_vertices;
    m->input_euler = base->input_euler;
    m->seg.triangle_count = base->triangle_count;
    m->seg.segment_count = count;
    m->seg.segment = labels;
    m->seg.delta_seg = base->seg.delta_seg;
    m->seg.without_normal = base->seg.without_normal;
    int rc = build_labelled(m, err);
    if (rc) {
        sl_segment_model_free(m);
        return rc;
    }
    *out = m;
    return SL_OK;
}
