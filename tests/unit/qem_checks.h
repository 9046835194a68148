/* Measures and meshes for the quadric simplifier's test (test_qem_simplify.c): topology
 * after welding, flipped triangles, compactness, RMS distance, texture-space area, and
 * meshes with texture seams. Include after tests/check.h and analytic_meshes.h. */
#ifndef SCANLOD_TESTS_UNIT_QEM_CHECKS_H
#define SCANLOD_TESTS_UNIT_QEM_CHECKS_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_adjacency.h"
#include "geometry/mesh_distance.h"
#include "geometry/qem_simplify.h"
#include "geometry/triangle_bvh.h"
#include "geometry/vec3.h"

/* Topology after welding by position: what a simplification must keep. */
typedef struct shape {
    sl_mesh_topology topo;
    int64_t euler;
    uint64_t loops, pinched; /* boundary loops; vertices with two fans */
} shape;

static inline shape shape_of(uint64_t nv, float *pos, uint64_t nt, uint32_t *tri)
{
    shape s;
    memset(&s, 0, sizeof s);
    sl_error err;
    sl_error_init(&err);
    sl_mesh view = sl_mesh_view(nv, pos, NULL, NULL, nt, tri);
    CHECK(sl_mesh_topology_compute(&view, &s.topo, &err) == 0);
    uint32_t *weld = malloc((nv + 1) * sizeof *weld), *welded = malloc((3 * nt + 1) * sizeof *welded);
    int64_t ids = sl_mesh_weld_positions(&view, weld);
    for (uint64_t i = 0; i < 3 * nt; i++)
        welded[i] = weld[tri[i]];
    sl_mesh_adjacency adj;
    CHECK(sl_mesh_adjacency_build(welded, nt, (uint64_t)(ids > 0 ? ids : 1), NULL, 0, &adj, &err) == 0);
    s.euler = adj.report.euler_characteristic;
    s.loops = adj.report.boundary_loops;
    s.pinched = adj.report.nonmanifold_vertices;
    sl_mesh_adjacency_release(&adj);
    free(weld);
    free(welded);
    return s;
}

static inline void normal_of(const float *pos, const uint32_t *t, double n[3])
{
    double e[3], f[3];
    for (int i = 0; i < 3; i++) {
        e[i] = pos[3 * t[1] + i] - pos[3 * t[0] + i];
        f[i] = pos[3 * t[2] + i] - pos[3 * t[0] + i];
    }
    sl_cross3(e, f, n);
}

/* A mesh as the simplifier's borrowed input. */
static inline sl_qem_mesh view_of(sl_mesh *m)
{
    sl_qem_mesh q = {m->vertex_count, m->positions, m->colors, m->texcoords, m->triangle_count,
                     m->triangles, NULL};
    return q;
}

/* The same vertices (positions and sources) and triangles, byte for byte. */
static inline int same_mesh(const sl_qem_mesh *a, const sl_qem_mesh *b)
{
    return a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
           !memcmp(a->positions, b->positions, 12 * a->vertex_count) &&
           !memcmp(a->source, b->source, 4 * a->vertex_count) &&
           !memcmp(a->triangles, b->triangles, 12 * a->triangle_count);
}

/* Locks of a slab across the model (x within 3 % of the box's width of its middle), like
 * a brick border: malloc'd, *count set. */
static inline uint8_t *slab_locks(const sl_mesh *m, uint64_t *count)
{
    uint8_t *locked = calloc(m->vertex_count + 1, 1);
    double lo = INFINITY, hi = -INFINITY;
    for (uint64_t v = 0; v < m->vertex_count; v++) {
        lo = fmin(lo, m->positions[3 * v]);
        hi = fmax(hi, m->positions[3 * v]);
    }
    *count = 0;
    for (uint64_t v = 0; v < m->vertex_count; v++)
        *count += locked[v] = fabs(m->positions[3 * v] - (lo + hi) / 2) < 0.03 * (hi - lo);
    return locked;
}

/* Output vertices descending from a locked input vertex (*kept) and of them those not at
 * its position exactly (*moved). */
static inline void locks_kept(const sl_qem_mesh *out, const float *in_positions,
                              const uint8_t *locked, uint64_t *kept, uint64_t *moved)
{
    *kept = *moved = 0;
    for (uint64_t v = 0; v < out->vertex_count; v++) {
        uint32_t s = out->source[v];
        if (!locked[s])
            continue;
        ++*kept;
        *moved += memcmp(out->positions + 3 * v, in_positions + 3 * (uint64_t)s, 12) != 0;
    }
}

/* The tree of the input's triangles (a failure is a failed check). */
static inline void build_bvh(const sl_qem_mesh *in, sl_triangle_bvh *bvh)
{
    sl_error err;
    sl_error_init(&err);
    sl_mesh view = sl_mesh_view(in->vertex_count, in->positions, NULL, NULL, in->triangle_count,
                                in->triangles);
    CHECK(sl_triangle_bvh_build(bvh, &view, &err) == 0);
}

/* Output triangles facing away from the input surface under their centroid (judged by
 * the closest input triangle: sound where parts are thicker than the level's error; on a
 * thin part, the cow's ears, the closest triangle can be on the far side). */
static inline uint64_t flipped_triangles(const sl_qem_mesh *in, const sl_qem_mesh *out)
{
    sl_triangle_bvh bvh;
    build_bvh(in, &bvh);
    uint64_t flipped = 0;
    for (uint64_t t = 0; t < out->triangle_count; t++) {
        const uint32_t *tri = out->triangles + 3 * t;
        double c[3] = {0, 0, 0}, n[3], m[3];
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++)
                c[i] += out->positions[3 * tri[k] + i] / 3.0;
        sl_closest hit;
        sl_triangle_bvh_closest(&bvh, c, UINT32_MAX, &hit);
        normal_of(out->positions, tri, n);
        normal_of(in->positions, in->triangles + 3 * (uint64_t)bvh.source[hit.triangle], m);
        flipped += sl_dot3(n, m) < 0;
    }
    sl_triangle_bvh_release(&bvh);
    return flipped;
}

static inline double min_compactness(const float *pos, const uint32_t *tri, uint64_t nt)
{
    double worst = 1;
    for (uint64_t t = 0; t < nt; t++) {
        double n[3], sum = 0;
        normal_of(pos, tri + 3 * t, n);
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++) {
                double d = pos[3 * tri[3 * t + (k + 1) % 3] + i] - pos[3 * tri[3 * t + k] + i];
                sum += d * d;
            }
        double c = sum > 0 ? 2 * sqrt(3.0) * sqrt(sl_dot3(n, n)) / sum : 0;
        worst = c < worst ? c : worst;
    }
    return worst;
}

static inline double rms_distance(const sl_qem_mesh *a, const sl_qem_mesh *b)
{
    sl_error err;
    sl_error_init(&err);
    sl_mesh va = sl_mesh_view(a->vertex_count, a->positions, NULL, NULL, a->triangle_count, a->triangles);
    sl_mesh vb = sl_mesh_view(b->vertex_count, b->positions, NULL, NULL, b->triangle_count, b->triangles);
    sl_mesh_distance_config cfg = sl_mesh_distance_default_config();
    cfg.samples = 20000;
    sl_mesh_distance d;
    CHECK(sl_mesh_distance_compute(&va, &vb, &cfg, &d, NULL, &err) == 0);
    return d.fraction.rms;
}

/* A UV sphere whose texture wraps once around: the meridian at angle 0 is a seam (its
 * vertices twice, at u = 0 and u = 1), the poles one vertex each. */
static inline test_mesh seam_sphere(uint32_t around, uint32_t rows, float **uv)
{
    test_mesh m;
    memset(&m, 0, sizeof m);
    *uv = malloc(2 * (size_t)((rows - 1) * (around + 1) + 2) * sizeof **uv);
    uint32_t south = tm_vertex(&m, 0, 0, -1);
    (*uv)[0] = 0.5f, (*uv)[1] = 0;
    for (uint32_t r = 1; r < rows; r++)
        for (uint32_t a = 0; a <= around; a++) {
            double phi = M_PI * r / rows - M_PI / 2, t = 2 * M_PI * (a % around) / around;
            uint32_t v = tm_vertex(&m, cos(phi) * cos(t), cos(phi) * sin(t), sin(phi));
            (*uv)[2 * v] = (float)a / around;
            (*uv)[2 * v + 1] = (float)r / rows;
        }
    uint32_t north = tm_vertex(&m, 0, 0, 1), ring = around + 1;
    (*uv)[2 * north] = 0.5f, (*uv)[2 * north + 1] = 1;
    uint32_t top = 1 + (rows - 2) * ring;
    for (uint32_t a = 0; a < around; a++) {
        tm_triangle(&m, south, 1 + a + 1, 1 + a);
        tm_triangle(&m, top + a, top + a + 1, north);
    }
    for (uint32_t r = 0; r + 2 < rows; r++)
        for (uint32_t a = 0; a < around; a++) {
            uint32_t p = 1 + r * ring;
            tm_quad(&m, p + a, p + a + 1, p + ring + a + 1, p + ring + a);
        }
    return m;
}

static inline double uv_area(const float *uv, const uint32_t *tri, uint64_t nt, uint64_t *turned)
{
    double sum = 0;
    for (uint64_t t = 0; t < nt; t++) {
        const float *a = uv + 2 * tri[3 * t], *b = uv + 2 * tri[3 * t + 1], *c = uv + 2 * tri[3 * t + 2];
        double area = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2;
        *turned += area <= 0;
        sum += fabs(area);
    }
    return sum;
}

/* A wavy open grid cut into one-column charts: strip k (columns k, k + 1) has wedges of
 * its own, at u = 2k and 2k + 1, so every inner column is a seam and the edges across a
 * strip join two seam points through a chart (what the seam rule must refuse). */
static inline test_mesh chart_grid(uint32_t n, float **uv)
{
    test_mesh m;
    memset(&m, 0, sizeof m);
    *uv = malloc(2 * (size_t)n * 2 * (n + 1) * sizeof **uv);
    for (uint32_t k = 0; k < n; k++)
        for (uint32_t j = 0; j <= n; j++)
            for (uint32_t c = 0; c < 2; c++) {
                double x = (double)(k + c) / n, y = (double)j / n;
                uint32_t v = tm_vertex(&m, x, y, 0.05 * sin(7 * x) * cos(5 * y));
                (*uv)[2 * v] = (float)(2 * k + c);
                (*uv)[2 * v + 1] = (float)y;
            }
    for (uint32_t k = 0; k < n; k++)
        for (uint32_t j = 0; j < n; j++) {
            uint32_t a = 2 * (k * (n + 1) + j); /* (k, j); +1 = (k + 1, j); +2 = (k, j + 1) */
            tm_quad(&m, a, a + 1, a + 3, a + 2);
        }
    return m;
}

/* A bump in the middle of the unit square (a height for tm_grid). */
static inline double bump(double x, double y)
{
    return 0.2 * exp(-20 * ((x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5)));
}
#endif
