/* Point normals from faces: paper 1 section 4 ("the normal vectors are calculated from
 * neighbor triangles' normal"), area weighted (docs/range-stage.md, "Decisions").
 *
 * The unnormalised cross product (b - a) x (c - a) of a triangle is its normal scaled by
 * twice its area, so summing it over a point's triangles is the area-weighted mean.
 * Determinism: no per-thread partial sums; a CSR point -> triangle table (counted and
 * filled by all threads, then each list sorted) lists each point's triangles in ascending
 * order and every point sums its own list in double, so the result is the same bits on
 * any thread count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/key_table.h"
#include "stages/range/range_internal.h"

static void triangle_normal(const float *positions, const uint32_t *tri, double n[3])
{
    const float *a = positions + 3 * (uint64_t)tri[0];
    const float *b = positions + 3 * (uint64_t)tri[1];
    const float *c = positions + 3 * (uint64_t)tri[2];
    double u[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = (double)b[k] - a[k];
        w[k] = (double)c[k] - a[k];
    }
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

/* Unit float normal from a double vector; returns 0 if it has no direction. */
static int store_unit(const double n[3], float *out)
{
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0) || !isfinite(len))
        return 0;
    for (int k = 0; k < 3; k++)
        out[k] = (float)(n[k] / len);
    return 1;
}

int range_face_normals(const float *positions, uint64_t point_count, const uint32_t *triangles,
                       uint64_t triangle_count, float *normals, sl_range_counts *counts,
                       sl_progress *progress, sl_error *err)
{
    uint64_t *start = calloc(point_count + 1, sizeof *start);
    uint64_t *fill = malloc((point_count ? point_count : 1) * sizeof *fill);
    uint64_t *adjacent = malloc((triangle_count ? 3 * triangle_count : 1) * sizeof *adjacent);
    if (!start || !fill || !adjacent) {
        free(start), free(fill), free(adjacent);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals: out of memory (%llu faces)",
                            (unsigned long long)triangle_count);
    }
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < 3 * triangle_count; i++) {
#pragma omp atomic update
        start[triangles[i] + 1]++;
    }
    for (uint64_t p = 0; p < point_count; p++)
        start[p + 1] += start[p];
    memcpy(fill, start, point_count * sizeof *fill);
    /* Filled in any order; each list is sorted before it is summed (below). */
#pragma omp parallel for schedule(static)
    for (uint64_t t = 0; t < triangle_count; t++)
        for (int c = 0; c < 3; c++) {
            uint64_t at;
#pragma omp atomic capture
            at = fill[triangles[3 * t + c]]++;
            adjacent[at] = t;
        }
    if (sl_progress_step(progress, "normals", 0.3)) {
        free(start), free(fill), free(adjacent);
        return SL_E_INTERRUPTED;
    }

    uint64_t fallbacks = 0;
#pragma omp parallel for schedule(static, 4096) reduction(+ : fallbacks)
    for (int64_t p = 0; p < (int64_t)point_count; p++) {
        double sum[3] = {0, 0, 0}, n[3];
        sl_sort_run_u64(adjacent + start[p], start[p + 1] - start[p]); /* ascending */
        for (uint64_t i = start[p]; i < start[p + 1]; i++) {
            triangle_normal(positions, triangles + 3 * adjacent[i], n);
            for (int k = 0; k < 3; k++)
                sum[k] += n[k];
        }
        if (store_unit(sum, normals + 3 * p))
            continue;
        /* Opposite faces cancel (a doubled fin): take the first face that has a direction. */
        fallbacks++;
        float *out = normals + 3 * p;
        out[0] = 0.0f, out[1] = 0.0f, out[2] = 1.0f;
        for (uint64_t i = start[p]; i < start[p + 1]; i++) {
            triangle_normal(positions, triangles + 3 * adjacent[i], n);
            if (store_unit(n, out))
                break;
        }
    }
    counts->normal_fallbacks += fallbacks;
    free(start), free(fill), free(adjacent);
    return SL_OK;
}

int range_file_normals(const sl_mesh *mesh, const range_clean *clean, float *normals,
                       uint8_t *valid, sl_error *err)
{
    uint64_t points = clean->point_count;
    memset(valid, 0, points);
    if (!mesh->normals)
        return SL_OK;
    double *sum = calloc(points ? 3 * points : 1, sizeof *sum);
    if (!sum)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals: out of memory (%llu points)",
                            (unsigned long long)points);
    /* Welded twins: mean of their unit file normals, in input order (deterministic). */
    for (uint64_t v = 0; v < mesh->vertex_count; v++) {
        uint32_t p = clean->vertex_point[v];
        if (p == RANGE_NONE)
            continue;
        const float *n = mesh->normals + 3 * v;
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        if (!(len > 0.0) || !isfinite(len))
            continue;
        for (int k = 0; k < 3; k++)
            sum[3 * (uint64_t)p + k] += n[k] / len;
    }
    for (uint64_t p = 0; p < points; p++)
        valid[p] = (uint8_t)store_unit(sum + 3 * p, normals + 3 * p);
    free(sum);
    return SL_OK;
}
