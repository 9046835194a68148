/* Mesh and LOD-model checks shared by the octree and LOD tests (and tests/e2e/lod_check.c). */
#ifndef SCANLOD_TESTS_UNIT_MESH_CHECKS_H
#define SCANLOD_TESTS_UNIT_MESH_CHECKS_H

#include <stdint.h>
#include <stdlib.h>

#include "runtime/lod_model.h"
#include "runtime/lod_mesh.h"

static inline int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* How many edges of an indexed mesh are not in exactly two triangles (the return value)
 * and how many are in three or more (*crowded, when not NULL). */
static inline uint64_t edge_census(const sl_lod_mesh *m, uint64_t *crowded)
{
    uint64_t n = 3 * m->triangle_count, bad = 0, over = 0;
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
        over += (j - i) > 2;
        i = j;
    }
    free(e);
    if (crowded)
        *crowded = over;
    return bad;
}

/* How many edges of an indexed mesh are not in exactly two triangles (0 = watertight). */
static inline uint64_t bad_edges(const sl_lod_mesh *m) { return edge_census(m, NULL); }

/* Volume enclosed by a closed mesh, positive when its triangles face outwards. */
static inline double signed_volume(const sl_lod_mesh *m)
{
    double v = 0;
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        const float *a = m->positions + 3 * (size_t)m->indices[3 * t];
        const float *b = m->positions + 3 * (size_t)m->indices[3 * t + 1];
        const float *c = m->positions + 3 * (size_t)m->indices[3 * t + 2];
        v += ((double)a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) -
              (double)a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
              (double)a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) / 6;
    }
    return v;
}

/* Does some frontier cell touch a frontier cell 2 or more levels coarser? For each of the 26
 * positions around frontier cell a (at a's level), walk up from level a + 1 to the first
 * node that exists over the position: if it is expanded, what covers the position is finer
 * than it (or nothing: an empty octant); if not, the frontier cell there is that node or an
 * ancestor, and a gap when that is 2 or more levels above a. */
static inline int level_gap(const sl_lod_model *m, uint32_t k)
{
    uint32_t *cells = malloc(sl_lod_frontier_bound(m, k) * sizeof *cells);
    uint64_t count = sl_lod_frontier(m, k, cells);
    int gap = 0;
    const sl_octree *t = &m->tree;
    for (uint64_t i = 0; i < count && !gap; i++) {
        const sl_octree_node *a = &t->nodes[cells[i]];
        for (int d = 0; d < 27 && !gap; d++) {
            int64_t q[3] = {a->x + d % 3 - 1, a->y + d / 3 % 3 - 1, a->z + d / 9 - 1};
            if (d == 13 || q[0] < 0 || q[1] < 0 || q[2] < 0)
                continue;
            for (uint32_t level = a->level + 1u; level <= t->depth; level++) {
                int shift = (int)(level - a->level);
                uint32_t c = sl_octree_find(t, level, q[0] >> shift, q[1] >> shift, q[2] >> shift);
                if (c == SL_OCTREE_NONE)
                    continue;
                if (m->expansion_index[c] >= k) { /* unexpanded: it or an ancestor is drawn */
                    uint32_t parent = t->nodes[c].parent;
                    gap = level >= a->level + 2u ||
                          (parent != SL_OCTREE_NONE && m->expansion_index[parent] >= k);
                }
                break;
            }
        }
    }
    free(cells);
    return gap;
}

#endif
