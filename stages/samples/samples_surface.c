/* samples stage: the signed distance from a grid vertex to the input's triangles
 * ([samples] closest = triangles, the default for meshes).
 *
 * The paper's sample (section 2.1) is sign((v - p) . n_p) * |v - p| with p the closest
 * input *point*. On a mesh the points are only the corners of the surface: beside a large
 * triangle, or beside a part thinner than a leaf, the closest corner can lie far from the
 * closest surface point, or on the far side of the part, and then the sign is wrong and
 * the surface tears (docs/samples-stage.md has the measurements). Here p is the closest
 * point of the triangles themselves and n_p the pseudonormal of the face, edge or vertex
 * p lies on (Baerentzen and Aanaes 2005): the face normal inside a face, the sum of the
 * unit normals of the faces sharing an edge, the angle-weighted sum of the unit normals
 * around a vertex. For a closed, consistently wound mesh that sign is exactly inside /
 * outside, and |v - p| is the exact distance, so the samples are the mesh's signed
 * distance field: the paper's formula applied to the continuous surface instead of its
 * corners.
 *
 * Determinism: the incidence lists are in ascending triangle order and the vertex
 * pseudonormals are summed in that order; the BVH's layout does not depend on the thread
 * count (geometry/triangle_bvh.h); a query's hint comes from the previous vertex of the
 * same fixed-size block, never from another thread.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/samples/samples_internal.h"

/* Unit normal of triangle (a, b, c) in its winding; zero for a degenerate one. */
static void face_normal(const float *a, const float *b, const float *c, double n[3])
{
    double ab[3], ac[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = (double)b[k] - a[k];
        ac[k] = (double)c[k] - a[k];
    }
    n[0] = ab[1] * ac[2] - ab[2] * ac[1];
    n[1] = ab[2] * ac[0] - ab[0] * ac[2];
    n[2] = ab[0] * ac[1] - ab[1] * ac[0];
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++)
        n[k] = len > 0 ? n[k] / len : 0.0;
}

static const float *corner(const sl_pointset *ps, uint64_t t, int k)
{
    return ps->positions + 3 * (uint64_t)ps->triangles[3 * t + (uint64_t)k];
}

/* The interior angle of triangle t at its corner k. */
static double corner_angle(const sl_pointset *ps, uint64_t t, int k)
{
    const float *o = corner(ps, t, k), *p = corner(ps, t, (k + 1) % 3), *q = corner(ps, t, (k + 2) % 3);
    double u[3], v[3];
    for (int a = 0; a < 3; a++) {
        u[a] = (double)p[a] - o[a];
        v[a] = (double)q[a] - o[a];
    }
    double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                 u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
}

/* Triangles around every point (counting sort by corner: ascending triangle order). */
static int build_incidence(samples_surface *s, sl_error *err)
{
    const sl_pointset *ps = s->ps;
    uint64_t n = ps->count, t_count = ps->triangle_count;
    s->incident_first = calloc(n + 1, sizeof *s->incident_first);
    s->incident = malloc(3 * t_count * sizeof *s->incident + 1);
    if (!s->incident_first || !s->incident)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for the incidence of "
                            "%llu triangles", (unsigned long long)t_count);
    for (uint64_t i = 0; i < 3 * t_count; i++)
        s->incident_first[ps->triangles[i] + 1]++;
    for (uint64_t v = 0; v < n; v++)
        s->incident_first[v + 1] += s->incident_first[v];
    uint64_t *fill = malloc(n * sizeof *fill + 1);
    if (!fill)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for the incidence");
    memcpy(fill, s->incident_first, n * sizeof *fill);
    for (uint64_t i = 0; i < 3 * t_count; i++)
        s->incident[fill[ps->triangles[i]]++] = (uint32_t)(i / 3);
    free(fill);
    return SL_OK;
}

/* Angle-weighted pseudonormal of every point. */
static int build_vertex_normals(samples_surface *s, sl_error *err)
{
    const sl_pointset *ps = s->ps;
    s->vertex_normals = malloc(3 * ps->count * sizeof *s->vertex_normals + 1);
    if (!s->vertex_normals)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for vertex pseudonormals");
#pragma omp parallel for schedule(static) if (ps->count > 65536)
    for (int64_t v = 0; v < (int64_t)ps->count; v++) {
        double sum[3] = {0, 0, 0};
        for (uint64_t i = s->incident_first[v]; i < s->incident_first[v + 1]; i++) {
            uint64_t t = s->incident[i];
            int k = ps->triangles[3 * t] == (uint32_t)v ? 0 : ps->triangles[3 * t + 1] == (uint32_t)v ? 1 : 2;
            double n[3], w = corner_angle(ps, t, k);
            face_normal(corner(ps, t, 0), corner(ps, t, 1), corner(ps, t, 2), n);
            for (int a = 0; a < 3; a++)
                sum[a] += w * n[a];
        }
        for (int a = 0; a < 3; a++)
            s->vertex_normals[3 * v + a] = sum[a];
    }
    return SL_OK;
}

/* Closed and consistently wound: every edge is used by as many triangles in one direction
 * as in the other (a closed oriented surface, the boundary of a volume; non-manifold
 * edges with two sheets each way, as in happy_buddha_100kf, are fine). */
static int is_closed(const samples_surface *s)
{
    const sl_pointset *ps = s->ps;
    int closed = 1;
#pragma omp parallel for schedule(static) reduction(&& : closed) if (ps->triangle_count > 65536)
    for (int64_t t = 0; t < (int64_t)ps->triangle_count; t++)
        for (int k = 0; k < 3 && closed; k++) {
            uint32_t i = ps->triangles[3 * t + k], j = ps->triangles[3 * t + (k + 1) % 3];
            int forward = 0, backward = 0;
            for (uint64_t m = s->incident_first[i]; m < s->incident_first[i + 1]; m++) {
                const uint32_t *c = ps->triangles + 3 * (uint64_t)s->incident[m];
                for (int e = 0; e < 3; e++) {
                    forward += c[e] == i && c[(e + 1) % 3] == j;
                    backward += c[e] == j && c[(e + 1) % 3] == i;
                }
            }
            closed = forward == backward;
        }
    return closed;
}

int samples_surface_build(samples_surface *s, const sl_pointset *ps, sl_error *err)
{
    memset(s, 0, sizeof *s);
    s->ps = ps;
    sl_mesh view = sl_mesh_view(ps->count, ps->positions, NULL, NULL, ps->triangle_count,
                                ps->triangles);
    int rc = sl_triangle_bvh_build(&s->bvh, &view, err);
    if (rc == SL_OK)
        rc = build_incidence(s, err);
    if (rc == SL_OK)
        rc = build_vertex_normals(s, err);
    if (rc == SL_OK)
        s->closed = is_closed(s);
    if (rc != SL_OK)
        samples_surface_release(s);
    return rc;
}

void samples_surface_release(samples_surface *s)
{
    sl_triangle_bvh_release(&s->bvh);
    free(s->vertex_normals);
    free(s->incident_first);
    free(s->incident);
    memset(s, 0, sizeof *s);
}

/* Sum of the unit normals of the triangles that have both points i and j as corners. */
static void edge_normal(const samples_surface *s, uint32_t i, uint32_t j, double out[3])
{
    const sl_pointset *ps = s->ps;
    out[0] = out[1] = out[2] = 0;
    for (uint64_t k = s->incident_first[i]; k < s->incident_first[i + 1]; k++) {
        uint64_t t = s->incident[k];
        const uint32_t *c = ps->triangles + 3 * t;
        if (c[0] != j && c[1] != j && c[2] != j)
            continue;
        double n[3];
        face_normal(corner(ps, t, 0), corner(ps, t, 1), corner(ps, t, 2), n);
        for (int a = 0; a < 3; a++)
            out[a] += n[a];
    }
}

/* Barycentric weights of q (a point of triangle t) for its corners, clamped to it. */
static void barycentric(const sl_pointset *ps, uint64_t t, const double q[3], double w[3])
{
    const float *a = corner(ps, t, 0), *b = corner(ps, t, 1), *c = corner(ps, t, 2);
    double v0[3], v1[3], v2[3];
    for (int k = 0; k < 3; k++) {
        v0[k] = (double)b[k] - a[k];
        v1[k] = (double)c[k] - a[k];
        v2[k] = q[k] - a[k];
    }
    double d00 = v0[0] * v0[0] + v0[1] * v0[1] + v0[2] * v0[2];
    double d01 = v0[0] * v1[0] + v0[1] * v1[1] + v0[2] * v1[2];
    double d11 = v1[0] * v1[0] + v1[1] * v1[1] + v1[2] * v1[2];
    double d20 = v2[0] * v0[0] + v2[1] * v0[1] + v2[2] * v0[2];
    double d21 = v2[0] * v1[0] + v2[1] * v1[1] + v2[2] * v1[2];
    double den = d00 * d11 - d01 * d01;
    w[0] = 1, w[1] = w[2] = 0;
    if (!(den > 0))
        return; /* a sliver: its first corner */
    w[1] = (d11 * d20 - d01 * d21) / den;
    w[2] = (d00 * d21 - d01 * d20) / den;
    for (int k = 1; k < 3; k++)
        w[k] = w[k] < 0 ? 0 : w[k] > 1 ? 1 : w[k];
    w[0] = 1 - w[1] - w[2];
    if (w[0] < 0) { /* rounding at the edge bc */
        w[1] /= w[1] + w[2];
        w[2] = 1 - w[1];
        w[0] = 0;
    }
}

/* The closest point's colour: barycentric blend of its triangle's corner colours. */
static void blend_color(const sl_pointset *ps, uint64_t t, const double w[3], uint8_t rgba[4])
{
    for (int ch = 0; ch < 4; ch++) {
        double sum = 0;
        for (int k = 0; k < 3; k++)
            sum += w[k] * ps->colors[4 * (uint64_t)ps->triangles[3 * t + (uint64_t)k] + (uint64_t)ch];
        rgba[ch] = (uint8_t)(sum < 0 ? 0 : sum > 255 ? 255 : lrint(sum));
    }
}

double samples_surface_signed_distance(const samples_surface *s, const double v[3],
                                       uint32_t *hint, uint8_t rgba[4])
{
    sl_closest c;
    sl_triangle_bvh_closest(&s->bvh, v, *hint, &c);
    *hint = c.triangle;
    const sl_pointset *ps = s->ps;
    uint64_t t = s->bvh.source[c.triangle];
    const uint32_t *tri = ps->triangles + 3 * t;
    double n[3];
    switch (c.feature) {
    case SL_FEATURE_VERTEX_A:
    case SL_FEATURE_VERTEX_B:
    case SL_FEATURE_VERTEX_C:
        for (int a = 0; a < 3; a++)
            n[a] = s->vertex_normals[3 * (uint64_t)tri[c.feature - SL_FEATURE_VERTEX_A] + (uint64_t)a];
        break;
    case SL_FEATURE_EDGE_AB:
    case SL_FEATURE_EDGE_BC:
    case SL_FEATURE_EDGE_CA: {
        int k = c.feature - SL_FEATURE_EDGE_AB;
        edge_normal(s, tri[k], tri[(k + 1) % 3], n);
        break;
    }
    default:
        face_normal(corner(ps, t, 0), corner(ps, t, 1), corner(ps, t, 2), n);
    }
    double dot = 0, w[3];
    for (int a = 0; a < 3; a++)
        dot += (v[a] - c.point[a]) * n[a];
    if (rgba && ps->colors) {
        barycentric(ps, t, c.point, w);
        blend_color(ps, t, w, rgba);
    }
    double d = sqrt(c.distance_sq);
    return dot >= 0 ? d : -d;
}
