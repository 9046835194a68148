/* Test meshes for the GLB, OBJ and thumbnail tests: a UV sphere, a cube with per-face
 * vertices (sharp normals), a height-field grid of any size, area-weighted vertex normals,
 * and a reader for the bundled scans. Each builder fills an sl_mesh the caller releases
 * with sl_mesh_release().
 */
#ifndef SCANLOD_TESTS_GLB_MESHES_H
#define SCANLOD_TESTS_GLB_MESHES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh.h"
#include "formats/ply.h"

static inline void meshes_alloc_(sl_mesh *m, uint64_t vertices, uint64_t triangles, int normals,
                          int colors)
{
    sl_mesh_init(m);
    m->vertex_count = vertices;
    m->triangle_count = triangles;
    m->positions = calloc(3 * vertices, sizeof(float));
    m->normals = normals ? calloc(3 * vertices, sizeof(float)) : NULL;
    m->colors = colors ? calloc(4 * vertices, 1) : NULL;
    m->triangles = calloc(3 * triangles, sizeof(uint32_t));
}

/* Unit sphere at `center`, `rings` x `segments` quads (poles fanned), outward normals,
 * colours from the normal direction when `colors`. Counter-clockwise from outside. */
static inline void meshes_sphere(sl_mesh *m, int rings, int segments, const float center[3],
                          int colors)
{
    uint64_t v = (uint64_t)(rings + 1) * (uint64_t)(segments + 1);
    meshes_alloc_(m, v, 2 * (uint64_t)rings * (uint64_t)segments, 1, colors);
    const double pi = 3.14159265358979323846;
    for (int r = 0; r <= rings; r++)
        for (int s = 0; s <= segments; s++) {
            uint64_t i = (uint64_t)r * (uint64_t)(segments + 1) + (uint64_t)s;
            double th = pi * r / rings, ph = 2 * pi * s / segments;
            double n[3] = {sin(th) * cos(ph), cos(th), -sin(th) * sin(ph)};
            for (int k = 0; k < 3; k++) {
                m->positions[3 * i + k] = (float)(center[k] + n[k]);
                m->normals[3 * i + k] = (float)n[k];
                if (colors)
                    m->colors[4 * i + k] = (uint8_t)(127.5 + 127.5 * n[k]);
            }
            if (colors)
                m->colors[4 * i + 3] = 255;
        }
    uint64_t t = 0;
    for (int r = 0; r < rings; r++)
        for (int s = 0; s < segments; s++) {
            uint32_t a = (uint32_t)(r * (segments + 1) + s), b = a + 1;
            uint32_t c = a + (uint32_t)(segments + 1), d = c + 1;
            uint32_t quad[6] = {a, c, b, b, c, d};
            memcpy(m->triangles + 3 * t, quad, sizeof quad);
            t += 2;
        }
}

/* Axis-aligned cube [lo, hi]^3 with 4 vertices per face (24) so normals stay sharp. */
static inline void meshes_cube(sl_mesh *m, float lo, float hi, int normals, int colors)
{
    meshes_alloc_(m, 24, 12, normals, colors);
    for (int f = 0; f < 6; f++) {
        int axis = f / 2, sign = f % 2 ? 1 : -1, u = (axis + 1) % 3, w = (axis + 2) % 3;
        for (int c = 0; c < 4; c++) {
            uint64_t i = (uint64_t)(4 * f + c);
            float *p = m->positions + 3 * i;
            p[axis] = sign > 0 ? hi : lo;
            p[u] = (c == 1 || c == 2) ? hi : lo;
            p[w] = (c >= 2) ? hi : lo;
            if (normals)
                m->normals[3 * i + axis] = (float)sign;
            if (colors) {
                m->colors[4 * i + axis] = 200;
                m->colors[4 * i + 3] = 255;
            }
        }
        /* Corners go round the face: counter-clockwise from outside for sign > 0. */
        uint32_t b = (uint32_t)(4 * f);
        uint32_t pos[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
        uint32_t neg[6] = {b, b + 2, b + 1, b, b + 3, b + 2};
        memcpy(m->triangles + 6 * (uint64_t)f, sign > 0 ? pos : neg, sizeof pos);
    }
}

/* n x n vertices on z = 0.1 sin(x) cos(y) over [0, 1]^2, 2 (n-1)^2 triangles. */
static inline void meshes_grid(sl_mesh *m, uint32_t n, int normals, int colors)
{
    meshes_alloc_(m, (uint64_t)n * n, 2 * (uint64_t)(n - 1) * (n - 1), normals, colors);
    for (uint32_t y = 0; y < n; y++)
        for (uint32_t x = 0; x < n; x++) {
            uint64_t i = (uint64_t)y * n + x;
            double fx = (double)x / (n - 1), fy = (double)y / (n - 1);
            m->positions[3 * i] = (float)fx;
            m->positions[3 * i + 1] = (float)fy;
            m->positions[3 * i + 2] = (float)(0.1 * sin(12 * fx) * cos(9 * fy));
            if (normals)
                m->normals[3 * i + 2] = 2.0f; /* not unit on purpose: the writer normalises */
            if (colors) {
                m->colors[4 * i] = (uint8_t)(255 * fx);
                m->colors[4 * i + 1] = (uint8_t)(255 * fy);
                m->colors[4 * i + 3] = 255;
            }
        }
    uint64_t t = 0;
    for (uint32_t y = 0; y + 1 < n; y++)
        for (uint32_t x = 0; x + 1 < n; x++) {
            uint32_t a = y * n + x, b = a + 1, c = a + n, d = c + 1;
            uint32_t quad[6] = {a, b, d, a, d, c};
            memcpy(m->triangles + 3 * t, quad, sizeof quad);
            t += 2;
        }
}

/* Area-weighted vertex normals (the cross products summed unnormalised), unit length. */
static inline void meshes_vertex_normals(sl_mesh *m)
{
    free(m->normals);
    m->normals = calloc(3 * m->vertex_count, sizeof(float));
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *v = m->triangles + 3 * t;
        const float *a = m->positions + 3 * (uint64_t)v[0], *b = m->positions + 3 * (uint64_t)v[1];
        const float *c = m->positions + 3 * (uint64_t)v[2];
        float e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        float f[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float n[3] = {e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2],
                      e[0] * f[1] - e[1] * f[0]};
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                m->normals[3 * (uint64_t)v[i] + k] += n[k];
    }
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        float *n = m->normals + 3 * i;
        float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3 && l > 0; k++)
            n[k] /= l;
    }
}

/* Reads tests/data/scans/NAME.ply; returns 0 on success. */
static inline int meshes_read_scan(const char *name, sl_mesh *m)
{
    const char *root = getenv("SCANLOD_SOURCE_DIR");
    char path[1024];
    snprintf(path, sizeof path, "%s/tests/data/scans/%s.ply", root ? root : ".", name);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_read(path, NULL, m, NULL, NULL, &err);
    if (rc) {
        char msg[1400];
        fprintf(stderr, "%s\n", sl_error_format(&err, msg, sizeof msg));
    }
    return rc;
}

#endif
