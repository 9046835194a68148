/* sl_mesh lifecycle (see mesh.h). */
#include "geometry/mesh.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sl_mesh_init(sl_mesh *m)
{
    memset(m, 0, sizeof *m);
}

void sl_mesh_release(sl_mesh *m)
{
    free(m->positions);
    free(m->normals);
    free(m->colors);
    free(m->texcoords);
    free(m->triangles);
    free(m->face_texcoords);
    free(m->grid_index);
    free(m->texture_data);
    sl_mesh_init(m);
}

void sl_mesh_warn(sl_mesh *m, const char *fmt, ...)
{
    size_t size = sizeof m->warnings, len = strlen(m->warnings);
    if (m->warning_count++ && len + 2 < size) {
        memcpy(m->warnings + len, "; ", 3);
        len += 2;
    }
    if (len + 1 >= size)
        return;
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(m->warnings + len, size - len, fmt, ap);
    va_end(ap);
    if (n >= 0 && (size_t)n >= size - len) /* mark the cut */
        memcpy(m->warnings + size - 4, "...", 4);
}

sl_mesh sl_mesh_view(uint64_t vertex_count, float *positions, float *normals, uint8_t *colors,
                     uint64_t triangle_count, uint32_t *triangles)
{
    sl_mesh v;
    sl_mesh_init(&v);
    v.vertex_count = vertex_count;
    v.positions = positions;
    v.normals = normals;
    v.colors = colors;
    v.triangle_count = triangle_count;
    v.triangles = triangles;
    return v;
}

int sl_mesh_check_writable(const sl_mesh *m, const char *path, sl_error *err)
{
    if (m->vertex_count == 0 || m->triangle_count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, path,
                            "nothing to write: the mesh has %llu vertices and %llu triangles",
                            (unsigned long long)m->vertex_count,
                            (unsigned long long)m->triangle_count);
    if (!m->positions || !m->triangles)
        return sl_error_set(err, SL_E_INTERNAL, 0, path, "mesh without positions or triangles");
    for (uint64_t i = 0; i < 3 * m->vertex_count; i++)
        if (!isfinite(m->positions[i]))
            return sl_error_set(err, SL_E_BADINPUT, 0, path,
                                "vertex %llu has a non-finite position",
                                (unsigned long long)(i / 3));
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count)
            return sl_error_set(err, SL_E_INTERNAL, 0, path,
                                "triangle %llu has vertex index %u (%llu vertices)",
                                (unsigned long long)(i / 3), m->triangles[i],
                                (unsigned long long)m->vertex_count);
    return 0;
}

void sl_mesh_vertex_normals(const float *positions, uint64_t vertex_count,
                            const uint32_t *triangles, uint64_t triangle_count, float *normals)
{
    double *sum = calloc(3 * (vertex_count ? vertex_count : 1), sizeof *sum);
    if (!sum) { /* no room for the sums: the float array itself carries them */
        memset(normals, 0, 3 * vertex_count * sizeof *normals);
    }
    for (uint64_t t = 0; t < triangle_count; t++) {
        const uint32_t *c = triangles + 3 * t;
        const float *a = positions + 3 * (uint64_t)c[0], *b = positions + 3 * (uint64_t)c[1],
                    *d = positions + 3 * (uint64_t)c[2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                       u[0] * w[1] - u[1] * w[0]}; /* |n| = twice the area */
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++) {
                if (sum)
                    sum[3 * (uint64_t)c[k] + j] += n[j];
                else
                    normals[3 * (uint64_t)c[k] + j] += (float)n[j];
            }
    }
    for (uint64_t v = 0; v < vertex_count; v++) {
        double n[3];
        for (int j = 0; j < 3; j++)
            n[j] = sum ? sum[3 * v + j] : normals[3 * v + j];
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int j = 0; j < 3; j++)
            normals[3 * v + j] = len > 0 ? (float)(n[j] / len) : 0.0f;
    }
    free(sum);
}
