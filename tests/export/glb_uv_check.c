/* glb_uv_check LEVEL.glb INPUT.ply TO_METRES UP TOLERANCE
 *
 * A published level's texture coordinates against the textured input's: decodes the GLB
 * with the tests' reader (any encoding), maps the input into glTF's frame (x TO_METRES;
 * UP z: (x, y, z) -> (x, z, -y)) and, for every GLB vertex, takes the input vertex
 * nearest to it. Checks that the GLB has TEXCOORD_0, that every coordinate lies in
 * [0, 1], and that each one is within TOLERANCE of its nearest input vertex's (glTF's v
 * is the input's 1 - v). Prints one line of figures; exit 0 when all hold, 1 otherwise,
 * 2 on a file that cannot be read.
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
        fprintf(stderr, "usage: glb_uv_check LEVEL.glb INPUT.ply TO_METRES y|z TOLERANCE\n");
        return 2;
    }
    (void)glb_reader_linear_to_srgb; /* the reader's, not needed here */
    double to_m = atof(argv[3]), tolerance = atof(argv[5]);
    int z_up = argv[4][0] == 'z';
    glb_decoded g;
    char why[512];
    if (glb_decode(argv[1], &g, why, sizeof why)) {
        fprintf(stderr, "glb_uv_check: %s: %s\n", argv[1], why);
        return 2;
    }
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    if (sl_ply_read(argv[2], NULL, &m, NULL, NULL, &err) || !m.texcoords) {
        fprintf(stderr, "glb_uv_check: %s: %s\n", argv[2],
                err.message[0] ? err.message : "no per-vertex texture coordinates");
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
    double lo = INFINITY, hi = -INFINITY, worst = 0, sum = 0;
    for (uint64_t i = 0; g.texcoords && i < g.vertex_count; i++) {
        const double *p = g.positions + 3 * i, *uv = g.texcoords + 2 * i;
        float q[3] = {(float)p[0], (float)p[1], (float)p[2]}, d2;
        uint32_t j = sl_kdtree_nearest(tree, q, &d2);
        double du = fabs(uv[0] - m.texcoords[2 * (uint64_t)j]);
        double dv = fabs(1.0 - uv[1] - m.texcoords[2 * (uint64_t)j + 1]);
        worst = fmax(worst, fmax(du, dv));
        sum += fmax(du, dv);
        lo = fmin(lo, fmin(uv[0], uv[1])), hi = fmax(hi, fmax(uv[0], uv[1]));
    }
    int ok = g.texcoords && g.vertex_count && lo >= 0 && hi <= 1 && worst <= tolerance;
    printf("%s: %llu vertices, texcoords %s in [%.6g, %.6g], off the nearest input vertex's "
           "by at most %.4g (mean %.4g, tolerance %.4g)%s\n",
           argv[1], (unsigned long long)g.vertex_count, g.texcoords ? "yes" : "none", lo, hi,
           worst, g.vertex_count ? sum / (double)g.vertex_count : 0.0, tolerance,
           ok ? "" : "  FAILED");
    sl_kdtree_free(tree);
    sl_mesh_release(&m);
    glb_decoded_free(&g);
    return ok ? 0 : 1;
}
