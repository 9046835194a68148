/* Wavefront OBJ writer (see formats/glb.h for the contract).
 *
 * OBJ has no binary form and no standard colour: vertex colours use the widespread
 * `v x y z r g b` extension (floats in [0, 1]; alpha is dropped). Numbers are printed with
 * %.9g, which round-trips a float; a decimal comma that a library's setlocale() could
 * cause is turned back into a point so the file parses everywhere.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/atomicfile.h"
#include "formats/glb.h"

/* Appends " %.*g" of each value to `line` at `*len`. */
static void put_numbers(char *line, size_t *len, size_t cap, const float *v, int n, int digits)
{
    for (int k = 0; k < n; k++) {
        char *start = line + *len;
        int w = snprintf(start, cap - *len, " %.*g", digits, (double)v[k]);
        for (char *c = start; c < start + w; c++)
            if (*c == ',')
                *c = '.';
        *len += (size_t)w;
    }
}

static int write_vertices(sl_atomic_file *f, const sl_mesh *m, sl_error *err)
{
    int rc = 0;
    for (uint64_t i = 0; i < m->vertex_count && !rc; i++) {
        char line[160] = "v";
        size_t len = 1;
        put_numbers(line, &len, sizeof line, m->positions + 3 * i, 3, 9);
        if (m->colors) {
            float rgb[3];
            for (int k = 0; k < 3; k++)
                rgb[k] = m->colors[4 * i + k] / 255.0f;
            put_numbers(line, &len, sizeof line, rgb, 3, 6);
        }
        line[len++] = '\n';
        rc = sl_atomic_write(f, line, len, err);
    }
    for (uint64_t i = 0; m->normals && i < m->vertex_count && !rc; i++) {
        char line[128] = "vn";
        size_t len = 2;
        const float *n = m->normals + 3 * i;
        float unit[3] = {0, 0, 1};
        double l = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        for (int k = 0; k < 3 && l > 1e-30 && isfinite(l); k++)
            unit[k] = (float)(n[k] / l);
        put_numbers(line, &len, sizeof line, unit, 3, 9);
        line[len++] = '\n';
        rc = sl_atomic_write(f, line, len, err);
    }
    return rc;
}

static int write_faces(sl_atomic_file *f, const sl_mesh *m, sl_error *err)
{
    int rc = 0;
    for (uint64_t t = 0; t < m->triangle_count && !rc; t++) {
        unsigned long long a = m->triangles[3 * t] + 1ull, b = m->triangles[3 * t + 1] + 1ull,
                           c = m->triangles[3 * t + 2] + 1ull;
        if (m->normals)
            rc = sl_atomic_printf(f, err, "f %llu//%llu %llu//%llu %llu//%llu\n", a, a, b, b, c, c);
        else
            rc = sl_atomic_printf(f, err, "f %llu %llu %llu\n", a, b, c);
    }
    return rc;
}

int sl_obj_write(const char *path, const sl_mesh *m, const char *extras_json, sl_error *err)
{
    int rc = sl_mesh_check_writable(m, path, err);
    if (rc)
        return rc;
    sl_atomic_file f;
    if ((rc = sl_atomic_open(&f, path, err)))
        return rc;
    rc = sl_atomic_printf(&f, err, "# scanlod\n# %llu vertices, %llu triangles\n",
                          (unsigned long long)m->vertex_count,
                          (unsigned long long)m->triangle_count);
    if (!rc && extras_json && !strpbrk(extras_json, "\r\n"))
        rc = sl_atomic_printf(&f, err, "# extras %s\n", extras_json);
    rc = rc ? rc : write_vertices(&f, m, err);
    rc = rc ? rc : write_faces(&f, m, err);
    rc = rc ? rc : sl_atomic_commit(&f, err);
    if (rc)
        sl_atomic_abort(&f);
    return rc;
}
