/* glb_check LEVEL.glb LEVEL.ply TO_METRES UP BOUND
 *
 * A published level's GLB against the PLY of the same level (the input's units and axes,
 * sRGB colour bytes): decodes the GLB with the tests' reader (any encoding), maps the PLY
 * into glTF's frame (x TO_METRES; UP z: (x, y, z) -> (x, z, -y)) and checks that every
 * GLB vertex lies within BOUND metres of a PLY vertex, that the triangle counts agree,
 * that the colours of the nearest PLY vertex come back within 1/255 after linear -> sRGB,
 * and that the two bounding boxes agree within BOUND. Prints one line of figures; exit 0
 * when all hold, 1 otherwise, 2 on a file that cannot be read.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/kdtree.h"
#include "formats/ply.h"
#include "../unit/glb_reader.h"

int main(int argc, char **argv)
{
    if (argc != 6) {
        fprintf(stderr, "usage: glb_check LEVEL.glb LEVEL.ply TO_METRES y|z BOUND\n");
        return 2;
    }
    double to_m = atof(argv[3]), bound = atof(argv[5]);
    int z_up = argv[4][0] == 'z';
    glb_decoded g;
    char why[512];
    if (glb_decode(argv[1], &g, why, sizeof why)) {
        fprintf(stderr, "glb_check: %s: %s\n", argv[1], why);
        return 2;
    }
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    if (sl_ply_read(argv[2], NULL, &m, NULL, NULL, &err)) {
        fprintf(stderr, "glb_check: %s: %s\n", argv[2], err.message);
        return 2;
    }
    for (uint64_t i = 0; i < m.vertex_count; i++) {
        float *p = m.positions + 3 * i;
        double x = p[0] * to_m, y = p[1] * to_m, z = p[2] * to_m;
        p[0] = (float)x, p[1] = (float)(z_up ? z : y), p[2] = (float)(z_up ? -y : z);
    }
    sl_kdtree *tree = NULL;
    if (sl_kdtree_build(&tree, m.positions, m.vertex_count, &err))
        return 2;
    double worst = 0, color_worst = 0, lo[2][3], hi[2][3];
    for (int k = 0; k < 3; k++)
        lo[0][k] = lo[1][k] = INFINITY, hi[0][k] = hi[1][k] = -INFINITY;
    for (uint64_t i = 0; i < g.vertex_count; i++) {
        const double *p = g.positions + 3 * i;
        float q[3] = {(float)p[0], (float)p[1], (float)p[2]}, d2;
        uint32_t j = sl_kdtree_nearest(tree, q, &d2);
        worst = fmax(worst, sqrt(d2));
        for (int k = 0; g.colors && m.colors && k < 3; k++)
            color_worst = fmax(color_worst, fabs(255 * glb_reader_linear_to_srgb(g.colors[4 * i + k]) -
                                                 m.colors[4 * (uint64_t)j + k]));
        for (int k = 0; k < 3; k++)
            lo[0][k] = fmin(lo[0][k], p[k]), hi[0][k] = fmax(hi[0][k], p[k]);
    }
    for (uint64_t i = 0; i < m.vertex_count; i++)
        for (int k = 0; k < 3; k++)
            lo[1][k] = fmin(lo[1][k], m.positions[3 * i + k]),
            hi[1][k] = fmax(hi[1][k], m.positions[3 * i + k]);
    double box = 0;
    for (int k = 0; k < 3; k++)
        box = fmax(box, fmax(fabs(lo[0][k] - lo[1][k]), fabs(hi[0][k] - hi[1][k])));
    int ok = worst <= bound && box <= bound && g.triangle_count == m.triangle_count &&
             (!m.colors || (g.colors && color_worst <= 1.0)) && (m.colors != NULL) == (g.colors != NULL);
    printf("%s: compression %d, %llu vertices, %llu triangles (PLY %llu), vertex error %.3g m "
           "(bound %.3g), box error %.3g m, colour error %.3g/255, height (y) %.4g m%s\n",
           argv[1], g.compression, (unsigned long long)g.vertex_count,
           (unsigned long long)g.triangle_count, (unsigned long long)m.triangle_count, worst,
           bound, box, g.colors ? color_worst : 0.0, hi[0][1] - lo[0][1], ok ? "" : "  FAILED");
    sl_kdtree_free(tree);
    sl_mesh_release(&m);
    glb_decoded_free(&g);
    return ok ? 0 : 1;
}
