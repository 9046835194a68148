/* Octrees of analytic surfaces for the tests: a signed distance function sampled on the
 * integer grid [-n, n]^3 wherever it is within `band` of the surface (as the samples
 * stage's band keeps every cube the surface crosses fully sampled), optionally coloured by
 * position, merged by sl_octree_build with leaf size `leaf` at origin (1, 2, 3). */
#ifndef SCANLOD_TESTS_UNIT_SDF_OCTREE_H
#define SCANLOD_TESTS_UNIT_SDF_OCTREE_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/merge/merge.h"

typedef double (*sdf_fn)(const double p[3]);

static int sdf_octree(sdf_fn sdf, int n, double band, double leaf, int coloured, sl_octree *out)
{
    size_t cap = 4096, count = 0;
    int32_t *coords = malloc(cap * 3 * sizeof *coords);
    float *dist = malloc(cap * sizeof *dist);
    uint8_t *colors = coloured ? malloc(cap * 4) : NULL;
    for (int x = -n; x <= n; x++)
        for (int y = -n; y <= n; y++)
            for (int z = -n; z <= n; z++) {
                double p[3] = {x, y, z}, d = sdf(p);
                if (fabs(d) > band)
                    continue;
                if (count == cap) {
                    cap *= 2;
                    coords = realloc(coords, cap * 3 * sizeof *coords);
                    dist = realloc(dist, cap * sizeof *dist);
                    if (colors)
                        colors = realloc(colors, cap * 4);
                }
                coords[3 * count] = x;
                coords[3 * count + 1] = y;
                coords[3 * count + 2] = z;
                if (colors) {
                    uint8_t rgba[4] = {(uint8_t)(x + 64), (uint8_t)(y + 64), (uint8_t)(z + 64), 255};
                    memcpy(colors + 4 * count, rgba, 4);
                }
                dist[count++] = (float)d;
            }
    sl_sample_grid g = {count, coords, dist, colors, leaf, {1, 2, 3}};
    sl_error err;
    sl_error_init(&err);
    int rc = sl_octree_build(&g, out, NULL, &err);
    free(coords);
    free(dist);
    free(colors);
    return rc;
}

#endif
