/* Mesh checks shared by the octree and LOD tests. */
#ifndef SCANLOD_TESTS_UNIT_MESH_CHECKS_H
#define SCANLOD_TESTS_UNIT_MESH_CHECKS_H

#include <stdint.h>
#include <stdlib.h>

#include "runtime/lod_mesh.h"

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* How many edges of an indexed mesh are not in exactly two triangles (0 = watertight). */
static uint64_t bad_edges(const sl_lod_mesh *m)
{
    uint64_t n = 3 * m->triangle_count, bad = 0;
    uint64_t *e = malloc((n ? n : 1) * sizeof *e);
    for (uint64_t t = 0; t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            uint64_t a = m->indices[3 * t + k], b = m->indices[3 * t + (k + 1) % 3];
            e[3 * t + k] = a < b ? a << 32 | b : b << 32 | a;
        }
    qsort(e, n, sizeof *e, cmp_u64);
    for (uint64_t i = 0; i < n;) {
        uint64_t j = i;
        while (j < n && e[j] == e[i])
            j++;
        bad += (j - i) != 2;
        i = j;
    }
    free(e);
    return bad;
}

#endif
