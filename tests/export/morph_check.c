/* morph_check COARSER.ply MESH.ply
 * morph_check COARSER.ply LEVEL.glb WEIGHT [OUT.ply]
 *
 * How far a morphed level lies from the coarser level it morphs to (docs/morphing.md):
 * the largest distance from a vertex of MESH (a PLY written by `scanlod extract
 * --morph-to`, or LEVEL.glb decoded by the tests' own reader with its morph target at
 * WEIGHT, as a viewer blends it) to the surface of COARSER, exact closest points on its
 * triangles. The GLB is compared in glTF's frame: run with +Y-up inputs in metres.
 * Prints "vertices N max_distance D diagonal G ratio D/G" (G: COARSER's bounding-box
 * diagonal). With OUT.ply the decoded GLB at WEIGHT (its triangles too) is written there,
 * so `scanlod compare COARSER.ply OUT.ply` can measure the *surface* at that weight by area
 * sampling (b_to_a: the one-sided Hausdorff from it to COARSER).
 * Exit 0, 2 on a file that cannot be read or a GLB without a morph target.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "formats/ply.h"
#include "geometry/triangle_bvh.h"
#include "../unit/glb_reader.h"

/* The reader's colour helper is not needed here. */
#define MORPH_CHECK_UNUSED(f) ((void)(f))

static double diagonal(const sl_mesh *m)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < m->vertex_count; i++)
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], m->positions[3 * i + k]), hi[k] = fmax(hi[k], m->positions[3 * i + k]);
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/* The decoded mesh at the weight asked for, as a float PLY. */
static int write_weighted(const char *path, const double *points, uint64_t n,
                          uint32_t *triangles, uint64_t triangle_count)
{
    float *p = malloc(12 * (n ? n : 1));
    if (!p)
        return 1;
    for (uint64_t i = 0; i < 3 * n; i++)
        p[i] = (float)points[i];
    sl_mesh m = sl_mesh_view(n, p, NULL, NULL, triangle_count, triangles);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_write(path, &m, &err);
    if (rc)
        fprintf(stderr, "morph_check: %s: %s\n", path, err.message);
    free(p);
    return rc != 0;
}

int main(int argc, char **argv)
{
    if (argc < 3 || argc > 5) {
        fprintf(stderr, "usage: morph_check COARSER.ply (MESH.ply | LEVEL.glb WEIGHT [OUT.ply])\n");
        return 2;
    }
    MORPH_CHECK_UNUSED(glb_reader_linear_to_srgb);
    sl_error err;
    sl_error_init(&err);
    sl_mesh coarse, mesh;
    if (sl_ply_read(argv[1], NULL, &coarse, NULL, NULL, &err)) {
        fprintf(stderr, "morph_check: %s: %s\n", argv[1], err.message);
        return 2;
    }
    uint64_t n = 0;
    double *points = NULL;
    if (argc == 3) {
        if (sl_ply_read(argv[2], NULL, &mesh, NULL, NULL, &err)) {
            fprintf(stderr, "morph_check: %s: %s\n", argv[2], err.message);
            return 2;
        }
        n = mesh.vertex_count;
        points = malloc(24 * (n ? n : 1));
        for (uint64_t i = 0; i < 3 * n; i++)
            points[i] = mesh.positions[i];
        sl_mesh_release(&mesh);
    } else {
        glb_decoded g;
        char why[512];
        double w = atof(argv[3]);
        if (glb_decode(argv[2], &g, why, sizeof why)) {
            fprintf(stderr, "morph_check: %s: %s\n", argv[2], why);
            return 2;
        }
        if (!g.morph) {
            fprintf(stderr, "morph_check: %s: no morph target\n", argv[2]);
            return 2;
        }
        n = g.vertex_count;
        points = malloc(24 * (n ? n : 1));
        for (uint64_t i = 0; i < 3 * n; i++)
            points[i] = g.positions[i] + w * g.morph[i];
        if (argc == 5 && write_weighted(argv[4], points, n, g.triangles, g.triangle_count)) {
            glb_decoded_free(&g);
            return 2;
        }
        glb_decoded_free(&g);
    }
    sl_triangle_bvh bvh;
    if (sl_triangle_bvh_build(&bvh, &coarse, &err))
        return 2;
    double worst = 0;
    for (uint64_t i = 0; i < n; i++) {
        sl_closest c;
        sl_triangle_bvh_closest(&bvh, points + 3 * i, UINT32_MAX, &c);
        worst = fmax(worst, sqrt(c.distance_sq));
    }
    double g = diagonal(&coarse);
    printf("vertices %llu max_distance %.9g diagonal %.9g ratio %.3g\n", (unsigned long long)n,
           worst, g, worst / g);
    sl_triangle_bvh_release(&bvh);
    sl_mesh_release(&coarse);
    free(points);
    return 0;
}
