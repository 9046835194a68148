/* Closest-point morph targets (morph_target.h): one BVH over the coarser level
 * (geometry/triangle_bvh.h), one exact closest-point query per vertex. Consecutive
 * vertices of a level are mostly neighbours, so each query starts from the triangle the
 * previous one found in the same chunk. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "geometry/morph_target.h"
#include "geometry/triangle_bvh.h"

#define MORPH_CHUNK 1024 /* vertices per parallel task: hints stay within one */

int sl_morph_closest_points(const sl_mesh *coarser, const float *positions, uint64_t count,
                            float *out, double *max_move, sl_error *err)
{
    if (coarser->triangle_count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "morph target: the coarser level has no triangles");
    sl_triangle_bvh bvh;
    int rc = sl_triangle_bvh_build(&bvh, coarser, err);
    if (rc)
        return rc;
    int64_t chunks = (int64_t)((count + MORPH_CHUNK - 1) / MORPH_CHUNK);
    double worst2 = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(max : worst2)
    for (int64_t c = 0; c < chunks; c++) {
        uint64_t end = (uint64_t)(c + 1) * MORPH_CHUNK;
        uint32_t hint = UINT32_MAX;
        for (uint64_t i = (uint64_t)c * MORPH_CHUNK; i < end && i < count; i++) {
            const float *p = positions + 3 * i;
            double q[3] = {p[0], p[1], p[2]};
            sl_closest hit;
            sl_triangle_bvh_closest(&bvh, q, hint, &hit);
            hint = hit.triangle;
            for (int k = 0; k < 3; k++)
                out[3 * i + k] = (float)hit.point[k];
            worst2 = hit.distance_sq > worst2 ? hit.distance_sq : worst2;
        }
    }
    sl_triangle_bvh_release(&bvh);
    if (max_move)
        *max_move = sqrt(worst2);
    return 0;
}

void sl_morph_blend(const float *positions, const float *targets, uint64_t count, double w,
                    float *out)
{
    if (w == 0) {
        memmove(out, positions, 3 * count * sizeof *out);
        return;
    }
    if (w == 1) {
        memmove(out, targets, 3 * count * sizeof *out);
        return;
    }
    for (uint64_t i = 0; i < 3 * count; i++)
        out[i] = (float)(positions[i] + w * ((double)targets[i] - positions[i]));
}
