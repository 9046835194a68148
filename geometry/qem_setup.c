/* The simplifier's set-up: checks, welding, classification, the initial quadrics and the
 * initial queue.
 *
 * Welding is exact (sl_mesh_weld_positions). The welded triangles' half-edge adjacency
 * (geometry/mesh_adjacency.h, lenient) classifies the points: on a boundary, on a cut
 * edge (3+ triangles, or two running it the same way) or with two fans; the last two are
 * locked, as are the caller's locked vertices and points where more than QEM_MAX_WEDGES
 * wedges meet. Triangles with two corners at one point are dropped.
 *
 * Quadrics (Garland and Heckbert 1997, section 5): every triangle's plane, weighted by its
 * area, goes to its three points; every border edge adds the plane through it
 * perpendicular to its triangle, weighted border_weight * length^2 (area units, so the
 * weight does not depend on the scale), and every attribute seam edge the same at half
 * that weight on each side. Each point sums over its own corner list in list order, so
 * the sums are the same on any thread count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/alloc.h"
#include "geometry/mesh_adjacency.h"
#include "geometry/mesh_distance.h"
#include "geometry/qem_internal.h"
#include "geometry/vec3.h"

int qem_check_input(const sl_qem_mesh *in, const sl_qem_config *cfg, sl_error *err)
{
    if (cfg->allow_topology_change < SL_QEM_TOPOLOGY_KEEP ||
        cfg->allow_topology_change > SL_QEM_TOPOLOGY_RELAX)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "simplify: allow_topology_change %d is not an sl_qem_topology",
                            cfg->allow_topology_change);
    if (!(cfg->border_weight >= 0 && cfg->border_weight < 1e12) ||
        !(cfg->attribute_weight >= 0 && cfg->attribute_weight < 1e12) ||
        !(cfg->max_error >= 0 && isfinite(cfg->max_error)) ||
        !(cfg->diagonal >= 0 && isfinite(cfg->diagonal)))
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "simplify: border_weight, attribute_weight, max_error and diagonal "
                            "must be finite and >= 0");
    if (in->vertex_count > UINT32_MAX - 1 || in->triangle_count > SL_ADJACENCY_MAX_TRIANGLES)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "simplify: %llu vertices, %llu triangles: at most 2^32 - 2 and %u",
                            (unsigned long long)in->vertex_count,
                            (unsigned long long)in->triangle_count, SL_ADJACENCY_MAX_TRIANGLES);
    if (in->triangle_count && (!in->triangles || !in->positions))
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "simplify: no triangle or position array");
    for (uint64_t i = 0; i < 3 * in->triangle_count; i++)
        if (in->triangles[i] >= in->vertex_count)
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "simplify: triangle %llu uses vertex %u of %llu",
                                (unsigned long long)(i / 3), in->triangles[i],
                                (unsigned long long)in->vertex_count);
    for (uint64_t i = 0; i < 3 * in->triangle_count; i++) {
        const float *p = in->positions + 3 * (uint64_t)in->triangles[i];
        const float *uv = in->texcoords ? in->texcoords + 2 * (uint64_t)in->triangles[i] : NULL;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]) ||
            (uv && (!isfinite(uv[0]) || !isfinite(uv[1]))))
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "simplify: vertex %u (of triangle %llu) has a non-finite "
                                "coordinate", in->triangles[i], (unsigned long long)(i / 3));
    }
    return 0;
}

static int allocate(qem_state *st, sl_error *err)
{
    uint64_t v = st->vertex_count ? st->vertex_count : 1, t = st->triangle_count ? st->triangle_count : 1;
    st->wedge_point = malloc(v * sizeof *st->wedge_point);
    st->corner_wedge = malloc(3 * t * sizeof *st->corner_wedge);
    st->corner_next = malloc(3 * t * sizeof *st->corner_next);
    if (!st->wedge_point || !st->corner_wedge || !st->corner_next)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: %llu triangles",
                            (unsigned long long)st->triangle_count);
    return 0;
}

static int allocate_points(qem_state *st, sl_error *err)
{
    uint64_t p = st->point_count ? st->point_count : 1;
    st->point = aligned_alloc(64, p * sizeof *st->point);
    if (!st->point)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: %llu points",
                            (unsigned long long)st->point_count);
    memset(st->point, 0, p * sizeof *st->point);
    st->generation = 1;
    return 0;
}

/* Corner lists (triangles in order, each prepended), dropping degenerate triangles. */
static void link_corners(qem_state *st, const uint8_t *degenerate)
{
    for (uint32_t p = 0; p < st->point_count; p++)
        st->point[p].head = QEM_NONE;
    if (st->triangle_count) /* (an empty mesh may have no array at all) */
        memcpy(st->corner_wedge, st->in->triangles,
               3 * (size_t)st->triangle_count * sizeof *st->corner_wedge);
    st->live_triangles = 0;
    for (uint32_t t = 0; t < st->triangle_count; t++) {
        if (degenerate[t]) {
            st->corner_wedge[3 * t] = QEM_NONE;
            st->stats.degenerate_triangles++;
            continue;
        }
        st->live_triangles++;
        for (uint32_t c = 3 * t; c < 3 * t + 3; c++) {
            uint32_t p = st->wedge_point[st->corner_wedge[c]];
            st->corner_next[c] = st->point[p].head;
            st->point[p].head = c;
        }
    }
}

static void classify(qem_state *st, const sl_mesh_adjacency *adj)
{
    const uint8_t *locked = st->cfg.locked;
    for (uint32_t w = st->vertex_count; w-- > 0;) { /* each point's first wedge last */
        uint32_t p = st->wedge_point[w];
        if (p == QEM_NONE)
            continue;
        if (locked && locked[w])
            st->point[p].flags |= QEM_LOCKED;
        st->point[p].wedge = w;
    }
    for (uint32_t p = 0; p < st->point_count; p++) {
        uint8_t vf = adj->vertex_flags[p];
        if (vf & (SL_VERTEX_CUT | SL_VERTEX_NONMANIFOLD)) {
            if (!(st->point[p].flags & QEM_LOCKED)) /* locked for this alone */
                st->point[p].flags |= QEM_COMPLEX;
            st->point[p].flags |= QEM_LOCKED;
            st->stats.nonmanifold_points++;
        } else if (vf & SL_VERTEX_BOUNDARY) {
            st->point[p].flags |= QEM_BORDER;
            st->stats.border_points++;
        }
        uint32_t wedges[QEM_MAX_WEDGES + 1];
        int n = qem_point_wedges(st, p, wedges);
        if (n > 1) {
            st->point[p].flags |= QEM_SEAM;
            st->stats.seam_points++;
        }
        if (n > QEM_MAX_WEDGES) {
            st->point[p].flags |= QEM_LOCKED;
            st->point[p].flags &= (uint8_t)~QEM_COMPLEX; /* locked for good */
        }
        st->stats.locked_points += (st->point[p].flags & QEM_LOCKED) != 0;
    }
}

/* Origin at the centre of the used vertices' box (small numbers in the quadrics). */
static void place_points(qem_state *st)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t p = 0; p < st->point_count; p++)
        for (int i = 0; i < 3; i++) {
            double x = st->in->positions[3 * (uint64_t)st->point[p].wedge + i];
            lo[i] = fmin(lo[i], x);
            hi[i] = fmax(hi[i], x);
        }
    double d2 = 0;
    for (int i = 0; i < 3; i++) {
        st->origin[i] = st->point_count ? (lo[i] + hi[i]) / 2 : 0;
        d2 += st->point_count ? (hi[i] - lo[i]) * (hi[i] - lo[i]) : 0;
    }
    if (st->cfg.diagonal > 0) /* a brick of a larger mesh: the whole's scale */
        d2 = st->cfg.diagonal * st->cfg.diagonal;
    st->diagonal = sqrt(d2);
    st->key_scale = d2 > 0 ? 1 / (d2 * sqrt(d2)) : 1;
    for (uint32_t p = 0; p < st->point_count; p++)
        for (int i = 0; i < 3; i++)
            st->point[p].position[i] =
                st->in->positions[3 * (uint64_t)st->point[p].wedge + i] - st->origin[i];
}

static const double *corner_position(const qem_state *st, uint32_t c)
{
    return st->point[qem_corner_point(st, c)].position;
}


/* Corner c's triangle seen from c: the edges to the next and previous corners and their
 * cross product (twice the area along the normal); returns c's position. */
static const double *triangle_edges(const qem_state *st, uint32_t c, double e[3], double f[3],
                                    double n[3])
{
    const double *p0 = corner_position(st, c), *p1 = corner_position(st, qem_corner_after(c, 1));
    const double *p2 = corner_position(st, qem_corner_after(c, 2));
    for (int i = 0; i < 3; i++) {
        e[i] = p1[i] - p0[i];
        f[i] = p2[i] - p0[i];
    }
    sl_cross3(e, f, n);
    return p0;
}

/* The plane through edge (corner c -> the next corner), perpendicular to the triangle,
 * weighted `weight` * length^2, added to q. */
static void add_edge_plane(const qem_state *st, uint32_t c, double weight, sl_qef *q)
{
    double e[3], f[3], n[3], perp[3];
    const double *p0 = triangle_edges(st, c, e, f, n);
    sl_cross3(e, n, perp);
    double len = sqrt(sl_dot3(perp, perp)), e2 = sl_dot3(e, e);
    if (!(len > 0))
        return;
    for (int i = 0; i < 3; i++)
        perp[i] /= len;
    sl_qef_add_plane(q, perp, p0, weight * e2);
}

/* Is half-edge h an attribute seam (its twin's triangle has other wedges on it)? */
static int seam_edge(const qem_state *st, const sl_mesh_adjacency *adj, uint32_t h)
{
    uint32_t g = adj->twin[h];
    return g != SL_HALFEDGE_NONE && (st->corner_wedge[g] != st->corner_wedge[qem_corner_after(h, 1)] ||
                                     st->corner_wedge[qem_corner_after(g, 1)] != st->corner_wedge[h]);
}

/* Point p's quadric: its triangles' planes, and its border and seam edges' planes. */
static void point_quadric(qem_state *st, const sl_mesh_adjacency *adj, uint32_t p)
{
    sl_qef *q = &st->point[p].quadric;
    for (uint32_t c = st->point[p].head; c != QEM_NONE; c = st->corner_next[c]) {
        double e[3], f[3], n[3];
        const double *p0 = triangle_edges(st, c, e, f, n);
        double len = sqrt(sl_dot3(n, n));
        for (int i = 0; i < 3; i++)
            st->point[p].normal[i] += n[i] / 2;
        if (len > 0) {
            double unit[3] = {n[0] / len, n[1] / len, n[2] / len};
            sl_qef_add_plane(q, unit, p0, len / 2);
        }
        uint32_t in = qem_corner_after(c, 2); /* the half-edge arriving at p */
        double bw = st->cfg.border_weight;
        if (adj->twin[c] == SL_HALFEDGE_NONE || seam_edge(st, adj, c))
            add_edge_plane(st, c, adj->twin[c] == SL_HALFEDGE_NONE ? bw : bw / 2, q);
        if (adj->twin[in] == SL_HALFEDGE_NONE || seam_edge(st, adj, in))
            add_edge_plane(st, in, adj->twin[in] == SL_HALFEDGE_NONE ? bw : bw / 2, q);
    }
}

static void fill_quadrics(qem_state *st, const sl_mesh_adjacency *adj)
{
    int64_t n = st->point_count;
#pragma omp parallel for schedule(static)
    for (int64_t p = 0; p < n; p++)
        point_quadric(st, adj, (uint32_t)p);
}

/* The input's attributes of wedge w: rgba / 255, then uv. */
static void input_attributes(const qem_state *st, uint32_t w, double *out)
{
    int k = 0;
    if (st->in->colors)
        for (int i = 0; i < 4; i++)
            out[k++] = st->in->colors[4 * (uint64_t)w + i] / 255.0;
    if (st->in->texcoords)
        for (int i = 0; i < 2; i++)
            out[k++] = st->in->texcoords[2 * (uint64_t)w + i];
}

/* Adds the linear fields of corner c's triangle (area-weighted) to its wedge's sums. */
static void add_triangle_field(qem_state *st, uint32_t c)
{
    double e1[3], e2[3], n[3];
    const double *p0 = triangle_edges(st, c, e1, e2, n);
    double area = sqrt(sl_dot3(n, n)) / 2;
    double d00 = sl_dot3(e1, e1), d01 = sl_dot3(e1, e2), d11 = sl_dot3(e2, e2);
    double den = d00 * d11 - d01 * d01;
    int na = st->attribute_count;
    const double *a0 = st->attribute + (uint64_t)st->corner_wedge[c] * na;
    const double *a1 = st->attribute + (uint64_t)st->corner_wedge[qem_corner_after(c, 1)] * na;
    const double *a2 = st->attribute + (uint64_t)st->corner_wedge[qem_corner_after(c, 2)] * na;
    double *f = st->field + (uint64_t)st->corner_wedge[c] * (1 + 4 * na);
    f[0] += area;
    for (int k = 0; k < na; k++) {
        double g[3] = {0, 0, 0}, u = a1[k] - a0[k], v = a2[k] - a0[k];
        if (den > 0)
            for (int i = 0; i < 3; i++)
                g[i] = (u * (d11 * e1[i] - d01 * e2[i]) + v * (d00 * e2[i] - d01 * e1[i])) / den;
        double *fk = f + 1 + 4 * k;
        for (int i = 0; i < 3; i++)
            fk[i] += area * g[i];
        fk[3] += area * (a0[k] - sl_dot3(g, p0));
    }
}

static int fill_attributes(qem_state *st, sl_error *err)
{
    st->attribute_count = (st->in->colors ? 4 : 0) + (st->in->texcoords ? 2 : 0);
    if (!st->attribute_count)
        return 0;
    int na = st->attribute_count;
    uint64_t v = st->vertex_count ? st->vertex_count : 1;
    st->attribute = malloc(v * na * sizeof *st->attribute);
    st->field = sl_alloc_zeroed(v * (1 + 4 * na), sizeof *st->field);
    if (!st->attribute || !st->field)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: attributes of %llu vertices",
                            (unsigned long long)st->vertex_count);
    for (uint32_t w = 0; w < st->vertex_count; w++)
        input_attributes(st, w, st->attribute + (uint64_t)w * na);
    double scale = st->cfg.attribute_weight * st->diagonal;
    st->attribute_scale = scale * scale;
    int64_t n = st->point_count;
#pragma omp parallel for schedule(static)
    for (int64_t p = 0; p < n; p++) /* a wedge belongs to one point: no two threads share it */
        for (uint32_t c = st->point[p].head; c != QEM_NONE; c = st->corner_next[c])
            add_triangle_field(st, c);
    return 0;
}

/* Half-edge h stands for its edge: one side of an interior edge, a border edge. */
static int edge_leader(const qem_state *st, const sl_mesh_adjacency *adj, uint32_t h)
{
    return !qem_triangle_dead(st, h / 3) &&
           (adj->twin[h] == SL_HALFEDGE_NONE ||
            qem_corner_point(st, h) < qem_corner_point(st, qem_corner_after(h, 1)));
}

/* Every edge's estimated cost, in parallel into fixed slots, then queued in edge order. */
static int fill_queue(qem_state *st, const sl_mesh_adjacency *adj, sl_error *err)
{
    uint64_t count = 0;
    for (uint32_t h = 0; h < 3 * st->triangle_count; h++)
        count += (uint64_t)edge_leader(st, adj, h);
    qem_entry *edges = malloc((count + 1) * sizeof *edges);
    if (!edges || qem_queue_init(&st->queue) != 0) {
        free(edges);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: queue of %llu edges",
                            (unsigned long long)count);
    }
    uint64_t slot = 0;
    for (uint32_t h = 0; h < 3 * st->triangle_count; h++)
        if (edge_leader(st, adj, h)) {
            uint32_t p = qem_corner_point(st, h), q = qem_corner_point(st, qem_corner_after(h, 1));
            edges[slot].a = p < q ? p : q;
            edges[slot++].b = p < q ? q : p;
        }
    int64_t n = (int64_t)count;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        double priority = qem_estimate(st, edges[i].a, edges[i].b);
        edges[i] = qem_make_entry(st, priority, edges[i].a, edges[i].b);
        edges[i].stamps = isfinite(priority) ? edges[i].stamps : UINT32_MAX; /* forbidden */
    }
    int rc = 0;
    for (uint64_t i = 0; i < count && !rc; i++)
        if (edges[i].stamps != UINT32_MAX) {
            rc = qem_queue_push(&st->queue, &edges[i]);
            st->stats.queued++;
        }
    free(edges);
    return rc ? sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: queue") : 0;
}

int qem_setup(qem_state *st, const sl_qem_mesh *in, const sl_qem_config *cfg, sl_error *err)
{
    memset(st, 0, sizeof *st);
    st->in = in;
    st->cfg = *cfg;
    int rc = qem_check_input(in, cfg, err);
    if (rc)
        return rc;
    st->vertex_count = (uint32_t)in->vertex_count;
    st->triangle_count = (uint32_t)in->triangle_count;
    st->stats.input_triangles = in->triangle_count;
    if ((rc = allocate(st, err)) != 0)
        return rc;
    sl_mesh view = sl_mesh_view(in->vertex_count, in->positions, NULL, NULL, in->triangle_count,
                                in->triangles);
    int64_t points = sl_mesh_weld_positions(&view, st->wedge_point);
    if (points < 0)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: welding");
    st->point_count = (uint32_t)points;
    st->stats.points = (uint64_t)points;
    if ((rc = allocate_points(st, err)) != 0)
        return rc;
    for (uint64_t i = 0; i < 3 * (uint64_t)st->triangle_count; i++)
        st->corner_next[i] = st->wedge_point[in->triangles[i]]; /* scratch: point triangles */
    sl_mesh_adjacency adj;
    rc = sl_mesh_adjacency_build(st->corner_next, st->triangle_count, st->point_count, NULL, 0,
                                 &adj, err);
    if (rc)
        return rc;
    link_corners(st, adj.degenerate);
    classify(st, &adj);
    place_points(st);
    if (cfg->allow_topology_change == SL_QEM_TOPOLOGY_RELAX)
        qem_relax_rules(st);
    fill_quadrics(st, &adj);
    rc = fill_attributes(st, err);
    if (!rc)
        rc = fill_queue(st, &adj, err);
    sl_mesh_adjacency_release(&adj);
    return rc;
}

void qem_release(qem_state *st)
{
    free(st->wedge_point);
    free(st->corner_wedge);
    free(st->corner_next);
    free(st->point);
    free(st->attribute);
    free(st->field);
    qem_queue_free(&st->queue);
    memset(st, 0, sizeof *st);
}

void qem_relax_rules(qem_state *st)
{
    st->relaxed = 1;
    for (uint32_t p = 0; p < st->point_count; p++) {
        st->point[p].flags &= (uint8_t)~QEM_BLOCKED;
        if (st->point[p].flags & QEM_COMPLEX)
            st->point[p].flags &= (uint8_t)~QEM_LOCKED;
    }
}
