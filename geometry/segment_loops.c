/* Boundary loops and corners of a segmentation (segment_loops.h).
 *
 * Boundary half-edges are gathered per segment by a stable counting sort (so each
 * segment's slice is in half-edge order), then each segment traces its loops inside its
 * own slice in parallel (a half-edge belongs to exactly one segment, so the visited marks
 * never race). Vertex kinds come from one walk around each vertex's fan.
 */
#include "geometry/segment_loops.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NONE SL_HALFEDGE_NONE

void sl_segment_loops_release(sl_segment_loops *l)
{
    free(l->segment_loop_start);
    free(l->loop_start);
    free(l->halfedges);
    free(l->loop_area);
    free(l->outer);
    free(l->vertex_kind);
    free(l->vertex_changes);
    memset(l, 0, sizeof *l);
}

static void cross_sub(const float *o, const float *a, const float *b, double out[3])
{
    double u[3], v[3];
    for (int k = 0; k < 3; k++) {
        u[k] = (double)a[k] - o[k];
        v[k] = (double)b[k] - o[k];
    }
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
}

/* Traces segment k's loops over its slice halfedges[begin, end) (sorted); writes them in
 * loop order into traced[begin, end) and each loop's length into lens[begin + i]. Returns
 * the number of loops. */
static uint32_t trace_segment(const sl_mesh_adjacency *adj, const uint32_t *segment,
                              const uint32_t *slice, uint32_t begin, uint32_t end,
                              uint8_t *visited, uint32_t *traced, uint32_t *lens)
{
    uint32_t loops = 0, at = begin;
    for (uint32_t i = begin; i < end; i++) {
        uint32_t h = slice[i];
        if (visited[h])
            continue;
        uint32_t len = 0;
        for (uint32_t g = h; !visited[g]; g = sl_segment_next_boundary(adj, segment, g)) {
            visited[g] = 1;
            traced[at++] = g;
            len++;
        }
        lens[begin + loops++] = len;
    }
    return loops;
}

/* Label changes around vertex v's fan (cyclic for an interior fan), capped at 255. */
static uint8_t fan_changes(const sl_mesh_adjacency *adj, const uint32_t *segment, uint32_t v)
{
    uint32_t h0 = adj->vertex_halfedge[v], h = h0, changes = 0, steps = 0;
    uint32_t first = segment[sl_halfedge_face(h0)], last = first;
    for (;;) {
        uint32_t next = sl_halfedge_rotate(adj, h);
        if (next == NONE || next == h0 || ++steps > 3 * adj->triangle_count)
            break;
        uint32_t l = segment[sl_halfedge_face(next)];
        changes += l != last;
        last = l;
        h = next;
    }
    if (sl_halfedge_rotate(adj, h) == h0) /* closed fan: the step back to the start */
        changes += last != first;
    return (uint8_t)(changes > 255 ? 255 : changes);
}

static void vertex_kinds(const sl_mesh_adjacency *adj, const uint32_t *segment,
                         sl_segment_loops *out)
{
    int64_t nv = adj->vertex_count;
    uint64_t corners = 0, two = 0;
#pragma omp parallel for schedule(static) reduction(+ : corners, two)
    for (int64_t v = 0; v < nv; v++) {
        uint8_t f = adj->vertex_flags[v];
        if (!(f & SL_VERTEX_USED)) {
            out->vertex_kind[v] = SL_SEGMENT_VERTEX_UNUSED;
            out->vertex_changes[v] = 0;
            continue;
        }
        uint8_t c = fan_changes(adj, segment, (uint32_t)v);
        out->vertex_changes[v] = c;
        uint8_t kind;
        if (f & (SL_VERTEX_BOUNDARY | SL_VERTEX_CUT | SL_VERTEX_NONMANIFOLD) || c >= 3)
            kind = SL_SEGMENT_VERTEX_CORNER;
        else
            kind = c == 0 ? SL_SEGMENT_VERTEX_INTERIOR : SL_SEGMENT_VERTEX_TWO_SEGMENT;
        out->vertex_kind[v] = kind;
        corners += kind == SL_SEGMENT_VERTEX_CORNER;
        two += kind == SL_SEGMENT_VERTEX_TWO_SEGMENT;
    }
    out->corners = corners;
    out->two_segment_vertices = two;
}

/* Signed areas along each segment's area-weighted normal, and the outer loops. */
static int loop_areas(const sl_mesh_adjacency *adj, const float *positions,
                      const uint32_t *segment, sl_segment_loops *out)
{
    uint32_t ns = out->segment_count;
    double *normal = calloc(3 * (size_t)(ns ? ns : 1), sizeof *normal);
    if (!normal)
        return -1;
    for (uint32_t t = 0; t < adj->triangle_count; t++) { /* serial: a fixed summation order */
        if (adj->degenerate[t])
            continue;
        const uint32_t *c = adj->triangles + 3 * (uint64_t)t;
        double x[3];
        cross_sub(positions + 3 * (uint64_t)c[0], positions + 3 * (uint64_t)c[1],
                  positions + 3 * (uint64_t)c[2], x);
        for (int k = 0; k < 3; k++)
            normal[3 * (uint64_t)segment[t] + k] += x[k];
    }
    int64_t nsi = ns;
#pragma omp parallel for schedule(dynamic, 64)
    for (int64_t k = 0; k < nsi; k++) {
        uint32_t best = NONE;
        for (uint32_t l = out->segment_loop_start[k]; l < out->segment_loop_start[k + 1]; l++) {
            const uint32_t *h = out->halfedges + out->loop_start[l];
            uint32_t n = out->loop_start[l + 1] - out->loop_start[l];
            const float *o = positions + 3 * (uint64_t)adj->triangles[h[0]];
            double sum[3] = {0, 0, 0};
            for (uint32_t i = 1; i + 1 < n; i++) {
                double x[3];
                cross_sub(o, positions + 3 * (uint64_t)adj->triangles[h[i]],
                          positions + 3 * (uint64_t)adj->triangles[h[i + 1]], x);
                for (int j = 0; j < 3; j++)
                    sum[j] += x[j];
            }
            const double *m = normal + 3 * k;
            double len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
            double d = sum[0] * m[0] + sum[1] * m[1] + sum[2] * m[2];
            out->loop_area[l] = len > 0.0 ? 0.5 * d / len : 0.0;
            if (out->loop_area[l] > 0.0 && (best == NONE || out->loop_area[l] > out->loop_area[best]))
                best = l;
        }
        out->outer[k] = best;
    }
    free(normal);
    return 0;
}

/* The loops themselves: boundary half-edges per segment, traced. */
static int trace_loops(const sl_mesh_adjacency *adj, const uint32_t *segment,
                       sl_segment_loops *out)
{
    uint64_t nh = 3 * (uint64_t)adj->triangle_count;
    uint32_t ns = out->segment_count;
    uint32_t *seg_start = calloc((size_t)ns + 2, sizeof *seg_start);
    uint8_t *visited = calloc(nh ? nh : 1, 1);
    if (!seg_start || !visited) {
        free(seg_start);
        free(visited);
        return -1;
    }
    for (uint64_t h = 0; h < nh; h++)
        if (!adj->degenerate[h / 3] && sl_segment_is_boundary(adj, segment, (uint32_t)h))
            seg_start[segment[h / 3] + 2]++;
    for (uint32_t k = 0; k < ns; k++)
        seg_start[k + 2] += seg_start[k + 1];
    uint32_t total = seg_start[ns + 1];
    uint32_t *slice = malloc((total ? total : 1) * sizeof *slice);
    uint32_t *lens = malloc((total ? total : 1) * sizeof *lens);
    uint32_t *loops_of = malloc((ns ? ns : 1) * sizeof *loops_of);
    out->halfedges = malloc((total ? total : 1) * sizeof *out->halfedges);
    int ok = slice && lens && loops_of && out->halfedges;
    if (ok) {
        for (uint64_t h = 0; h < nh; h++)
            if (!adj->degenerate[h / 3] && sl_segment_is_boundary(adj, segment, (uint32_t)h))
                slice[seg_start[segment[h / 3] + 1]++] = (uint32_t)h;
        int64_t nsi = ns;
#pragma omp parallel for schedule(dynamic, 64)
        for (int64_t k = 0; k < nsi; k++)
            loops_of[k] = trace_segment(adj, segment, slice, seg_start[k], seg_start[k + 1],
                                        visited, out->halfedges, lens);
        uint64_t loop_count = 0;
        for (uint32_t k = 0; k < ns; k++)
            loop_count += loops_of[k];
        out->loop_count = (uint32_t)loop_count;
        out->segment_loop_start = malloc(((size_t)ns + 1) * sizeof *out->segment_loop_start);
        out->loop_start = malloc(((size_t)loop_count + 1) * sizeof *out->loop_start);
        ok = out->segment_loop_start && out->loop_start;
        if (ok) {
            uint32_t l = 0, at = 0;
            for (uint32_t k = 0; k < ns; k++) {
                out->segment_loop_start[k] = l;
                for (uint32_t i = 0; i < loops_of[k]; i++) {
                    out->loop_start[l++] = at;
                    at += lens[seg_start[k] + i];
                }
            }
            out->segment_loop_start[ns] = l;
            out->loop_start[l] = at;
        }
    }
    free(seg_start);
    free(visited);
    free(slice);
    free(lens);
    free(loops_of);
    return ok ? 0 : -1;
}

int sl_segment_loops_build(const sl_mesh_adjacency *adj, const float *positions,
                           const uint32_t *segment, uint32_t segment_count,
                           sl_segment_loops *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    for (uint32_t t = 0; t < adj->triangle_count; t++)
        if (!adj->degenerate[t] && segment[t] >= segment_count)
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "triangle %u is in segment %u, but there are %u segments", t,
                                segment[t], segment_count);
    out->segment_count = segment_count;
    size_t nv = adj->vertex_count ? adj->vertex_count : 1;
    out->vertex_kind = malloc(nv);
    out->vertex_changes = malloc(nv);
    out->outer = malloc((segment_count ? segment_count : 1) * sizeof *out->outer);
    int ok = out->vertex_kind && out->vertex_changes && out->outer &&
             trace_loops(adj, segment, out) == 0;
    if (ok) {
        out->loop_area = malloc((out->loop_count ? out->loop_count : 1) * sizeof *out->loop_area);
        ok = out->loop_area && loop_areas(adj, positions, segment, out) == 0;
    }
    if (!ok) {
        sl_segment_loops_release(out);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "segment loops of %u triangles",
                            adj->triangle_count);
    }
    vertex_kinds(adj, segment, out);
    return SL_OK;
}
