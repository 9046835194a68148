/* Small analytic triangle meshes for the mesh toolkit's tests (adjacency, region growing,
 * loops, the segment method): counter-clockwise seen from outside, welded. */
#ifndef SCANLOD_TESTS_UNIT_ANALYTIC_MESHES_H
#define SCANLOD_TESTS_UNIT_ANALYTIC_MESHES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct test_mesh {
    uint32_t vertex_count, triangle_count, vertex_cap, triangle_cap;
    float *positions;
    uint32_t *triangles;
} test_mesh;

static inline void tm_free(test_mesh *m)
{
    free(m->positions);
    free(m->triangles);
    memset(m, 0, sizeof *m);
}

static inline uint32_t tm_vertex(test_mesh *m, double x, double y, double z)
{
    if (m->vertex_count == m->vertex_cap) {
        m->vertex_cap = m->vertex_cap ? 2 * m->vertex_cap : 64;
        m->positions = realloc(m->positions, 3 * (size_t)m->vertex_cap * sizeof *m->positions);
    }
    float *p = m->positions + 3 * (size_t)m->vertex_count;
    p[0] = (float)x;
    p[1] = (float)y;
    p[2] = (float)z;
    return m->vertex_count++;
}

static inline void tm_triangle(test_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    if (m->triangle_count == m->triangle_cap) {
        m->triangle_cap = m->triangle_cap ? 2 * m->triangle_cap : 64;
        m->triangles = realloc(m->triangles, 3 * (size_t)m->triangle_cap * sizeof *m->triangles);
    }
    uint32_t *t = m->triangles + 3 * (size_t)m->triangle_count++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
}

/* A quad a b c d (counter-clockwise) as two triangles, split along a-c. */
static inline void tm_quad(test_mesh *m, uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    tm_triangle(m, a, b, c);
    tm_triangle(m, a, c, d);
}

/* An n x n grid of quads on [0, 1]^2 at height z(x, y), facing +z (open). */
static inline test_mesh tm_grid(uint32_t n, double (*height)(double, double))
{
    test_mesh m;
    memset(&m, 0, sizeof m);
    for (uint32_t j = 0; j <= n; j++)
        for (uint32_t i = 0; i <= n; i++) {
            double x = (double)i / n, y = (double)j / n;
            tm_vertex(&m, x, y, height ? height(x, y) : 0.0);
        }
    for (uint32_t j = 0; j < n; j++)
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = j * (n + 1) + i;
            tm_quad(&m, a, a + 1, a + n + 2, a + n + 1);
        }
    return m;
}

/* The surface of the cube [0, n]^3 in unit quads (6 n^2 quads, watertight), outwards. */
static inline test_mesh tm_cube(uint32_t n)
{
    test_mesh m;
    memset(&m, 0, sizeof m);
    uint32_t side = n + 1;
    uint32_t *id = malloc((size_t)side * side * side * sizeof *id);
    memset(id, 0xff, (size_t)side * side * side * sizeof *id);
#define TM_ID(x, y, z) (id[((size_t)(z) * side + (y)) * side + (x)] == UINT32_MAX                 \
                            ? (id[((size_t)(z) * side + (y)) * side + (x)] =                       \
                                   tm_vertex(&m, (x), (y), (z)))                                   \
                            : id[((size_t)(z) * side + (y)) * side + (x)])
    for (int axis = 0; axis < 3; axis++)
        for (int s = 0; s < 2; s++)
            for (uint32_t i = 0; i < n; i++)
                for (uint32_t j = 0; j < n; j++) {
                    uint32_t c[4][3]; /* the quad's corners in (a, b) = (axis+1, axis+2) */
                    uint32_t ab[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
                    uint32_t v[4];
                    for (int k = 0; k < 4; k++) {
                        c[k][axis] = s ? n : 0;
                        c[k][(axis + 1) % 3] = ab[k][0];
                        c[k][(axis + 2) % 3] = ab[k][1];
                        v[k] = TM_ID(c[k][0], c[k][1], c[k][2]);
                    }
                    /* (a, b, axis) is right-handed: counter-clockwise in (a, b) faces +axis */
                    if (s)
                        tm_quad(&m, v[0], v[1], v[2], v[3]);
                    else
                        tm_quad(&m, v[0], v[3], v[2], v[1]);
                }
#undef TM_ID
    free(id);
    return m;
}

/* A closed cylinder of radius 1 and height h along z: `around` segments, `rings` side
 * rows, each cap `cap_rings` concentric rings around a centre vertex. */
static inline test_mesh tm_cylinder(uint32_t around, uint32_t rings, uint32_t cap_rings, double h)
{
    test_mesh m;
    memset(&m, 0, sizeof m);
    /* side vertices: ring r (0 = bottom) */
    uint32_t side0 = 0;
    for (uint32_t r = 0; r <= rings; r++)
        for (uint32_t a = 0; a < around; a++) {
            double t = 2 * M_PI * a / around;
            tm_vertex(&m, cos(t), sin(t), h * r / rings);
        }
    for (uint32_t r = 0; r < rings; r++)
        for (uint32_t a = 0; a < around; a++) {
            uint32_t b = (a + 1) % around;
            uint32_t p = side0 + r * around;
            tm_quad(&m, p + a, p + b, p + around + b, p + around + a);
        }
    for (int top = 0; top < 2; top++) {
        double z = top ? h : 0.0;
        uint32_t outer = side0 + (top ? rings * around : 0);
        uint32_t prev = outer; /* ring rc has radius 1 - rc / cap_rings */
        for (uint32_t rc = 1; rc < cap_rings; rc++) {
            uint32_t ring = m.vertex_count;
            double radius = 1.0 - (double)rc / cap_rings;
            for (uint32_t a = 0; a < around; a++) {
                double t = 2 * M_PI * a / around;
                tm_vertex(&m, radius * cos(t), radius * sin(t), z);
            }
            for (uint32_t a = 0; a < around; a++) {
                uint32_t b = (a + 1) % around;
                if (top)
                    tm_quad(&m, prev + a, prev + b, ring + b, ring + a);
                else
                    tm_quad(&m, prev + b, prev + a, ring + a, ring + b);
            }
            prev = ring;
        }
        uint32_t centre = tm_vertex(&m, 0, 0, z);
        for (uint32_t a = 0; a < around; a++) {
            uint32_t b = (a + 1) % around;
            if (top)
                tm_triangle(&m, prev + a, prev + b, centre);
            else
                tm_triangle(&m, prev + b, prev + a, centre);
        }
    }
    return m;
}

/* A torus (major radius R, minor r), u x v quads, watertight, genus 1. */
static inline test_mesh tm_torus(uint32_t nu, uint32_t nv, double R, double r)
{
    test_mesh m;
    memset(&m, 0, sizeof m);
    for (uint32_t i = 0; i < nu; i++)
        for (uint32_t j = 0; j < nv; j++) {
            double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
            tm_vertex(&m, (R + r * cos(v)) * cos(u), (R + r * cos(v)) * sin(u), r * sin(v));
        }
    for (uint32_t i = 0; i < nu; i++)
        for (uint32_t j = 0; j < nv; j++) {
            uint32_t i1 = (i + 1) % nu, j1 = (j + 1) % nv;
            tm_quad(&m, i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1);
        }
    return m;
}

/* A UV sphere of radius 1: `around` x `rows`, poles as fans. Watertight. */
static inline test_mesh tm_sphere(uint32_t around, uint32_t rows)
{
    test_mesh m;
    memset(&m, 0, sizeof m);
    uint32_t south = tm_vertex(&m, 0, 0, -1);
    for (uint32_t r = 1; r < rows; r++)
        for (uint32_t a = 0; a < around; a++) {
            double phi = M_PI * r / rows - M_PI / 2, t = 2 * M_PI * a / around;
            tm_vertex(&m, cos(phi) * cos(t), cos(phi) * sin(t), sin(phi));
        }
    uint32_t north = tm_vertex(&m, 0, 0, 1);
    for (uint32_t a = 0; a < around; a++) {
        uint32_t b = (a + 1) % around;
        tm_triangle(&m, south, 1 + b, 1 + a);
        uint32_t top = 1 + (rows - 2) * around;
        tm_triangle(&m, top + a, top + b, north);
    }
    for (uint32_t r = 0; r + 2 < rows; r++)
        for (uint32_t a = 0; a < around; a++) {
            uint32_t b = (a + 1) % around, p = 1 + r * around;
            tm_quad(&m, p + a, p + b, p + around + b, p + around + a);
        }
    return m;
}

#endif
