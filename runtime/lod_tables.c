/* Precomputed tables of the LOD model: same-level neighbours and transition records
 * (crack compensation; see lod_model.h and docs/lod.md).
 *
 * A transition record holds what a coarse cell needs to be drawn against a finer
 * neighbour: the finer level's signs at its edge midpoints and face centres, and the
 * finer crossings on its half-edges and face spokes. These are global values of the
 * finer level (every fine cell that has the vertex or edge agrees), so they are harvested
 * from whichever of the 64 finer cells around the node exist: its own children and its
 * neighbours' children. Drawing a coarse cell with exactly the points its finer neighbour
 * uses on their shared face is what closes the crack (Shekhar et al. move the fine points
 * onto the coarse segment instead; here the coarse side adopts the fine points).
 */
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_model.h"

/* sl_mc_uniform_table() as constant data, so that generation needs no start-up work
 * (building that table takes longer than cutting a small level). Row c: the triangle
 * count of corner configuration c, then 3 edge ids per triangle. tests/unit/test_lod_cells.c
 * checks it against sl_mc_uniform_table() and prints the rows afresh when they differ. */
const uint8_t sl_lod_uniform_cells[256][SL_LOD_UNIFORM_ROW] = {
    {0}, {1,0,4,8}, {1,0,9,6}, {2,4,9,6,4,8,9}, {1,1,10,4}, {2,0,10,8,0,1,10}, {2,0,9,6,1,10,4},
    {3,1,9,6,1,8,9,1,10,8}, {1,1,6,11}, {2,0,4,8,1,6,11}, {2,0,11,1,0,9,11},
    {3,1,9,11,1,8,9,1,4,8}, {2,4,11,10,4,6,11}, {3,0,10,8,0,11,10,0,6,11},
    {3,0,10,4,0,11,10,0,9,11}, {2,8,11,10,8,9,11}, {1,2,8,5}, {2,0,5,2,0,4,5}, {2,0,9,6,2,8,5},
    {3,2,4,5,2,6,4,2,9,6}, {2,1,10,4,2,8,5}, {3,0,5,2,0,10,5,0,1,10}, {3,0,9,6,1,10,4,2,8,5},
    {4,1,9,6,1,2,9,1,5,2,1,10,5}, {2,1,6,11,2,8,5}, {3,0,5,2,0,4,5,1,6,11},
    {3,0,11,1,0,9,11,2,8,5}, {4,1,9,11,1,2,9,1,5,2,1,4,5}, {3,2,8,5,4,11,10,4,6,11},
    {4,0,5,2,0,10,5,0,11,10,0,6,11}, {4,0,10,4,0,11,10,0,9,11,2,8,5}, {3,2,10,5,2,11,10,2,9,11},
    {1,2,7,9}, {2,0,4,8,2,7,9}, {2,0,7,6,0,2,7}, {3,2,4,8,2,6,4,2,7,6}, {2,1,10,4,2,7,9},
    {3,0,10,8,0,1,10,2,7,9}, {3,0,7,6,0,2,7,1,10,4}, {4,1,7,6,1,2,7,1,8,2,1,10,8},
    {2,1,6,11,2,7,9}, {3,0,4,8,1,6,11,2,7,9}, {3,0,11,1,0,7,11,0,2,7},
    {4,1,7,11,1,2,7,1,8,2,1,4,8}, {3,2,7,9,4,11,10,4,6,11}, {4,0,10,8,0,11,10,0,6,11,2,7,9},
    {4,0,10,4,0,11,10,0,7,11,0,2,7}, {3,2,10,8,2,11,10,2,7,11}, {2,5,9,8,5,7,9},
    {3,0,7,9,0,5,7,0,4,5}, {3,0,7,6,0,5,7,0,8,5}, {2,4,7,6,4,5,7}, {3,1,10,4,5,9,8,5,7,9},
    {4,0,7,9,0,5,7,0,10,5,0,1,10}, {4,0,7,6,0,5,7,0,8,5,1,10,4}, {3,1,7,6,1,5,7,1,10,5},
    {3,1,6,11,5,9,8,5,7,9}, {4,0,7,9,0,5,7,0,4,5,1,6,11}, {4,0,11,1,0,7,11,0,5,7,0,8,5},
    {3,1,7,11,1,5,7,1,4,5}, {4,4,11,10,4,6,11,5,9,8,5,7,9},
    {5,0,7,9,0,5,7,0,10,5,0,11,10,0,6,11}, {5,0,10,4,0,11,10,0,7,11,0,5,7,0,8,5},
    {2,5,11,10,5,7,11}, {1,3,5,10}, {2,0,4,8,3,5,10}, {2,0,9,6,3,5,10}, {3,3,5,10,4,9,6,4,8,9},
    {2,1,5,4,1,3,5}, {3,0,5,8,0,3,5,0,1,3}, {3,0,9,6,1,5,4,1,3,5}, {4,1,9,6,1,8,9,1,5,8,1,3,5},
    {2,1,6,11,3,5,10}, {3,0,4,8,1,6,11,3,5,10}, {3,0,11,1,0,9,11,3,5,10},
    {4,1,9,11,1,8,9,1,4,8,3,5,10}, {3,3,6,11,3,4,6,3,5,4}, {4,0,5,8,0,3,5,0,11,3,0,6,11},
    {4,0,5,4,0,3,5,0,11,3,0,9,11}, {3,3,9,11,3,8,9,3,5,8}, {2,2,10,3,2,8,10},
    {3,0,3,2,0,10,3,0,4,10}, {3,0,9,6,2,10,3,2,8,10}, {4,2,10,3,2,4,10,2,6,4,2,9,6},
    {3,1,8,4,1,2,8,1,3,2}, {2,0,3,2,0,1,3}, {4,0,9,6,1,8,4,1,2,8,1,3,2}, {3,1,9,6,1,2,9,1,3,2},
    {3,1,6,11,2,10,3,2,8,10}, {4,0,3,2,0,10,3,0,4,10,1,6,11}, {4,0,11,1,0,9,11,2,10,3,2,8,10},
    {5,9,3,2,9,10,3,9,4,10,9,1,4,9,11,1}, {4,2,11,3,2,6,11,2,4,6,2,8,4},
    {3,0,3,2,0,11,3,0,6,11}, {5,4,2,8,4,3,2,4,11,3,4,9,11,4,0,9}, {2,2,11,3,2,9,11},
    {2,2,7,9,3,5,10}, {3,0,4,8,2,7,9,3,5,10}, {3,0,7,6,0,2,7,3,5,10},
    {4,2,4,8,2,6,4,2,7,6,3,5,10}, {3,1,5,4,1,3,5,2,7,9}, {4,0,5,8,0,3,5,0,1,3,2,7,9},
    {4,0,7,6,0,2,7,1,5,4,1,3,5}, {5,1,7,6,1,2,7,1,8,2,1,5,8,1,3,5}, {3,1,6,11,2,7,9,3,5,10},
    {4,0,4,8,1,6,11,2,7,9,3,5,10}, {4,0,11,1,0,7,11,0,2,7,3,5,10},
    {5,1,7,11,1,2,7,1,8,2,1,4,8,3,5,10}, {4,2,7,9,3,6,11,3,4,6,3,5,4},
    {5,0,5,8,0,3,5,0,11,3,0,6,11,2,7,9}, {5,0,5,4,0,3,5,0,11,3,0,7,11,0,2,7},
    {4,8,3,5,8,11,3,8,7,11,8,2,7}, {3,3,8,10,3,9,8,3,7,9}, {4,0,7,9,0,3,7,0,10,3,0,4,10},
    {4,0,7,6,0,3,7,0,10,3,0,8,10}, {3,3,4,10,3,6,4,3,7,6}, {4,1,8,4,1,9,8,1,7,9,1,3,7},
    {3,0,7,9,0,3,7,0,1,3}, {5,7,1,3,7,4,1,7,8,4,7,0,8,7,6,0}, {2,1,7,6,1,3,7},
    {4,1,6,11,3,8,10,3,9,8,3,7,9}, {5,0,7,9,0,3,7,0,10,3,0,4,10,1,6,11},
    {5,0,11,1,0,7,11,0,3,7,0,10,3,0,8,10}, {4,7,10,3,7,4,10,7,1,4,7,11,1},
    {5,3,6,11,3,4,6,3,8,4,3,9,8,3,7,9}, {4,0,7,9,0,3,7,0,11,3,0,6,11}, {2,0,8,4,3,7,11},
    {1,3,7,11}, {1,3,11,7}, {2,0,4,8,3,11,7}, {2,0,9,6,3,11,7}, {3,3,11,7,4,9,6,4,8,9},
    {2,1,10,4,3,11,7}, {3,0,10,8,0,1,10,3,11,7}, {3,0,9,6,1,10,4,3,11,7},
    {4,1,9,6,1,8,9,1,10,8,3,11,7}, {2,1,7,3,1,6,7}, {3,0,4,8,1,7,3,1,6,7},
    {3,0,3,1,0,7,3,0,9,7}, {4,1,7,3,1,9,7,1,8,9,1,4,8}, {3,3,6,7,3,4,6,3,10,4},
    {4,0,10,8,0,3,10,0,7,3,0,6,7}, {4,0,10,4,0,3,10,0,7,3,0,9,7}, {3,3,9,7,3,8,9,3,10,8},
    {2,2,8,5,3,11,7}, {3,0,5,2,0,4,5,3,11,7}, {3,0,9,6,2,8,5,3,11,7},
    {4,2,4,5,2,6,4,2,9,6,3,11,7}, {3,1,10,4,2,8,5,3,11,7}, {4,0,5,2,0,10,5,0,1,10,3,11,7},
    {4,0,9,6,1,10,4,2,8,5,3,11,7}, {5,1,9,6,1,2,9,1,5,2,1,10,5,3,11,7}, {3,1,7,3,1,6,7,2,8,5},
    {4,0,5,2,0,4,5,1,7,3,1,6,7}, {4,0,3,1,0,7,3,0,9,7,2,8,5}, {5,1,7,3,1,9,7,1,2,9,1,5,2,1,4,5},
    {4,2,8,5,3,6,7,3,4,6,3,10,4}, {5,0,5,2,0,10,5,0,3,10,0,7,3,0,6,7},
    {5,0,10,4,0,3,10,0,7,3,0,9,7,2,8,5}, {4,10,7,3,10,9,7,10,2,9,10,5,2}, {2,2,11,9,2,3,11},
    {3,0,4,8,2,11,9,2,3,11}, {3,0,11,6,0,3,11,0,2,3}, {4,2,4,8,2,6,4,2,11,6,2,3,11},
    {3,1,10,4,2,11,9,2,3,11}, {4,0,10,8,0,1,10,2,11,9,2,3,11}, {4,0,11,6,0,3,11,0,2,3,1,10,4},
    {5,6,3,11,6,2,3,6,8,2,6,10,8,6,1,10}, {3,1,2,3,1,9,2,1,6,9}, {4,0,4,8,1,2,3,1,9,2,1,6,9},
    {2,0,3,1,0,2,3}, {3,1,2,3,1,8,2,1,4,8}, {4,2,6,9,2,4,6,2,10,4,2,3,10},
    {5,10,2,3,10,9,2,10,6,9,10,0,6,10,8,0}, {3,0,10,4,0,3,10,0,2,3}, {2,2,10,8,2,3,10},
    {3,3,8,5,3,9,8,3,11,9}, {4,0,11,9,0,3,11,0,5,3,0,4,5}, {4,0,11,6,0,3,11,0,5,3,0,8,5},
    {3,3,4,5,3,6,4,3,11,6}, {4,1,10,4,3,8,5,3,9,8,3,11,9},
    {5,0,11,9,0,3,11,0,5,3,0,10,5,0,1,10}, {5,0,11,6,0,3,11,0,5,3,0,8,5,1,10,4},
    {4,6,3,11,6,5,3,6,10,5,6,1,10}, {4,1,5,3,1,8,5,1,9,8,1,6,9},
    {5,9,1,6,9,3,1,9,5,3,9,4,5,9,0,4}, {3,0,3,1,0,5,3,0,8,5}, {2,1,5,3,1,4,5},
    {5,3,8,5,3,9,8,3,6,9,3,4,6,3,10,4}, {2,0,6,9,3,10,5}, {4,0,10,4,0,3,10,0,5,3,0,8,5},
    {1,3,10,5}, {2,5,11,7,5,10,11}, {3,0,4,8,5,11,7,5,10,11}, {3,0,9,6,5,11,7,5,10,11},
    {4,4,9,6,4,8,9,5,11,7,5,10,11}, {3,1,5,4,1,7,5,1,11,7}, {4,0,5,8,0,7,5,0,11,7,0,1,11},
    {4,0,9,6,1,5,4,1,7,5,1,11,7}, {5,1,9,6,1,8,9,1,5,8,1,7,5,1,11,7}, {3,1,5,10,1,7,5,1,6,7},
    {4,0,4,8,1,5,10,1,7,5,1,6,7}, {4,0,10,1,0,5,10,0,7,5,0,9,7},
    {5,1,5,10,1,7,5,1,9,7,1,8,9,1,4,8}, {2,4,7,5,4,6,7}, {3,0,5,8,0,7,5,0,6,7},
    {3,0,5,4,0,7,5,0,9,7}, {2,5,9,7,5,8,9}, {3,2,11,7,2,10,11,2,8,10},
    {4,0,7,2,0,11,7,0,10,11,0,4,10}, {4,0,9,6,2,11,7,2,10,11,2,8,10},
    {5,2,11,7,2,10,11,2,4,10,2,6,4,2,9,6}, {4,1,8,4,1,2,8,1,7,2,1,11,7},
    {3,0,7,2,0,11,7,0,1,11}, {5,0,9,6,1,8,4,1,2,8,1,7,2,1,11,7}, {4,1,9,6,1,2,9,1,7,2,1,11,7},
    {4,1,8,10,1,2,8,1,7,2,1,6,7}, {5,2,6,7,2,1,6,2,10,1,2,4,10,2,0,4},
    {5,1,8,10,1,2,8,1,7,2,1,9,7,1,0,9}, {2,1,4,10,2,9,7}, {3,2,6,7,2,4,6,2,8,4},
    {2,0,7,2,0,6,7}, {4,4,2,8,4,7,2,4,9,7,4,0,9}, {1,2,9,7}, {3,2,11,9,2,10,11,2,5,10},
    {4,0,4,8,2,11,9,2,10,11,2,5,10}, {4,0,11,6,0,10,11,0,5,10,0,2,5},
    {5,2,4,8,2,6,4,2,11,6,2,10,11,2,5,10}, {4,1,5,4,1,2,5,1,9,2,1,11,9},
    {5,5,9,2,5,11,9,5,1,11,5,0,1,5,8,0}, {5,11,4,1,11,5,4,11,2,5,11,0,2,11,6,0},
    {2,1,11,6,2,5,8}, {4,1,5,10,1,2,5,1,9,2,1,6,9}, {5,0,4,8,1,5,10,1,2,5,1,9,2,1,6,9},
    {3,0,10,1,0,5,10,0,2,5}, {4,1,5,10,1,2,5,1,8,2,1,4,8}, {3,2,6,9,2,4,6,2,5,4},
    {4,5,9,2,5,6,9,5,0,6,5,8,0}, {2,0,5,4,0,2,5}, {1,2,5,8}, {2,8,11,9,8,10,11},
    {3,0,11,9,0,10,11,0,4,10}, {3,0,11,6,0,10,11,0,8,10}, {2,4,11,6,4,10,11},
    {3,1,8,4,1,9,8,1,11,9}, {2,0,11,9,0,1,11}, {4,11,4,1,11,8,4,11,0,8,11,6,0}, {1,1,11,6},
    {3,1,8,10,1,9,8,1,6,9}, {4,9,1,6,9,10,1,9,4,10,9,0,4}, {2,0,10,1,0,8,10}, {1,1,4,10},
    {2,4,9,8,4,6,9}, {1,0,6,9}, {1,0,8,4}, {0}
};

int sl_neighbours_build(const sl_octree *t, sl_neighbours *out)
{
    memset(out, 0, sizeof *out);
    out->mask = calloc(t->node_count ? t->node_count : 1, sizeof *out->mask);
    out->base = calloc(t->node_count ? t->node_count : 1, sizeof *out->base);
    if (!out->mask || !out->base)
        goto nomem;
#pragma omp parallel for schedule(dynamic, 256)
    for (uint32_t i = 0; i < t->node_count; i++) {
        const sl_octree_node *n = &t->nodes[i];
        uint32_t mask = 0;
        for (int d = 0; d < 27; d++) {
            if (d == 13)
                continue;
            int dx = d % 3 - 1, dy = d / 3 % 3 - 1, dz = d / 9 - 1;
            if (sl_octree_find(t, n->level, (int64_t)n->x + dx, (int64_t)n->y + dy,
                               (int64_t)n->z + dz) != SL_OCTREE_NONE)
                mask |= 1u << d;
        }
        out->mask[i] = mask;
    }
    for (uint32_t i = 0; i < t->node_count; i++) {
        out->base[i] = (uint32_t)out->count;
        out->count += (uint64_t)__builtin_popcount(out->mask[i]);
    }
    out->index = malloc((out->count ? out->count : 1) * sizeof *out->index);
    if (!out->index)
        goto nomem;
#pragma omp parallel for schedule(dynamic, 256)
    for (uint32_t i = 0; i < t->node_count; i++) {
        const sl_octree_node *n = &t->nodes[i];
        uint32_t k = out->base[i];
        for (int d = 0; d < 27; d++)
            if (out->mask[i] >> d & 1)
                out->index[k++] = sl_octree_find(t, n->level, (int64_t)n->x + d % 3 - 1,
                                                 (int64_t)n->y + d / 3 % 3 - 1,
                                                 (int64_t)n->z + d / 9 - 1);
    }
    return 0;
nomem:
    sl_neighbours_release(out);
    return -1;
}

void sl_neighbours_release(sl_neighbours *nb)
{
    free(nb->mask);
    free(nb->base);
    free(nb->index);
    memset(nb, 0, sizeof *nb);
}

/* A full transition record while it is gathered. */
typedef struct transition {
    uint16_t mid_known, mid_inside;
    uint8_t centre_known, centre_inside;
    uint32_t half[24], spoke[24];
} transition;

/* Which of the node's boundary samples a fine vertex (local coords in 0..2) is. */
static void note_vertex(transition *tr, const int v[3], int inside)
{
    int ones = (v[0] == 1) + (v[1] == 1) + (v[2] == 1);
    if (ones == 1) { /* an edge midpoint */
        int a = v[0] == 1 ? 0 : v[1] == 1 ? 1 : 2, c0 = 0;
        for (int b = 0; b < 3; b++)
            if (b != a)
                c0 |= (v[b] / 2) << b;
        int e = sl_mc_edge_of(a, c0);
        tr->mid_known |= (uint16_t)(1u << e);
        if (inside)
            tr->mid_inside |= (uint16_t)(1u << e);
    } else if (ones == 2) { /* a face centre */
        int a = v[0] != 1 ? 0 : v[1] != 1 ? 1 : 2, f = 2 * a + v[a] / 2;
        tr->centre_known |= (uint8_t)(1u << f);
        if (inside)
            tr->centre_inside |= (uint8_t)(1u << f);
    }
}

/* Which half-edge or spoke a fine edge (start s in local coords, axis a) is. */
static void note_edge(transition *tr, const int s[3], int a, uint32_t crossing)
{
    int b = (a + 1) % 3, c = (a + 2) % 3;
    int b_on = s[b] != 1, c_on = s[c] != 1;
    if (b_on && c_on) { /* along one of the node's edges */
        int c0 = (s[b] / 2) << b | (s[c] / 2) << c;
        tr->half[2 * sl_mc_edge_of(a, c0) + s[a]] = crossing;
        return;
    }
    if (b_on == c_on)
        return; /* through the node's inside */
    int fa = b_on ? b : c, f = 2 * fa + s[fa] / 2;
    /* One end is the face centre (coordinate 1 along a), the other an edge midpoint of
     * the face (0 or 2 along a). */
    int m[3] = {s[0], s[1], s[2]};
    if (s[a] == 1)
        m[a] = 2;
    int edges[4];
    sl_mc_face_edges(f, edges);
    for (int k = 0; k < 4; k++) {
        int e = edges[k], ea = sl_mc_edge_axis(e), c0 = sl_mc_edge_c0(e);
        int mid[3] = {2 * (c0 & 1), 2 * (c0 >> 1 & 1), 2 * (c0 >> 2 & 1)};
        mid[ea] = 1;
        if (mid[0] == m[0] && mid[1] == m[1] && mid[2] == m[2])
            tr->spoke[4 * f + k] = crossing;
    }
}

static void gather(const sl_octree *t, uint32_t i, transition *tr)
{
    const sl_octree_node *n = &t->nodes[i];
    memset(tr, 0, sizeof *tr);
    for (int k = 0; k < 24; k++)
        tr->half[k] = tr->spoke[k] = SL_OCTREE_NONE;
    int64_t fx = 2 * (int64_t)n->x, fy = 2 * (int64_t)n->y, fz = 2 * (int64_t)n->z;
    for (int cell = 0; cell < 64; cell++) {
        int ox = cell % 4 - 1, oy = cell / 4 % 4 - 1, oz = cell / 16 - 1;
        uint32_t fi = sl_octree_find(t, n->level - 1u, fx + ox, fy + oy, fz + oz);
        if (fi == SL_OCTREE_NONE)
            continue;
        const sl_octree_node *fine = &t->nodes[fi];
        for (int c = 0; c < 8; c++) {
            int v[3] = {ox + (c & 1), oy + (c >> 1 & 1), oz + (c >> 2 & 1)};
            if (v[0] >= 0 && v[0] <= 2 && v[1] >= 0 && v[1] <= 2 && v[2] >= 0 && v[2] <= 2)
                note_vertex(tr, v, fine->inside >> c & 1);
        }
        for (int e = 0; e < 12; e++) {
            if (!(fine->edge_mask >> e & 1))
                continue;
            int c0 = sl_mc_edge_c0(e), a = sl_mc_edge_axis(e);
            int s[3] = {ox + (c0 & 1), oy + (c0 >> 1 & 1), oz + (c0 >> 2 & 1)};
            int end = s[a] + 1;
            if (s[0] < 0 || s[1] < 0 || s[2] < 0 || s[0] > 2 || s[1] > 2 || s[2] > 2 || end > 2)
                continue;
            note_edge(tr, s, a, sl_octree_crossing(t, fine, e));
        }
    }
}

int sl_transitions_build(const sl_octree *t, sl_transitions *out, uint64_t *unresolved)
{
    memset(out, 0, sizeof *out);
    *unresolved = 0;
    uint32_t n = t->node_count;
    transition *all = malloc((n ? n : 1) * sizeof *all);
    out->base = malloc((n ? n : 1) * sizeof *out->base);
    if (!all || !out->base) {
        free(all);
        sl_transitions_release(out);
        return -1;
    }
    uint64_t missing = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : missing)
    for (uint32_t i = 0; i < n; i++) {
        if (t->nodes[i].level == 0)
            continue;
        gather(t, i, &all[i]);
        missing += (uint64_t)(12 - __builtin_popcount(all[i].mid_known)) +
                   (uint64_t)(6 - __builtin_popcount(all[i].centre_known));
    }
    *unresolved = missing;
    for (uint32_t i = 0; i < n; i++) {
        if (t->nodes[i].level == 0) {
            out->base[i] = SL_OCTREE_NONE;
            continue;
        }
        out->base[i] = (uint32_t)out->count;
        out->count += 3;
        for (int k = 0; k < 24; k++)
            out->count += (all[i].half[k] != SL_OCTREE_NONE) + (all[i].spoke[k] != SL_OCTREE_NONE);
    }
    out->words = malloc((out->count ? out->count : 1) * sizeof *out->words);
    if (!out->words) {
        free(all);
        sl_transitions_release(out);
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (uint32_t i = 0; i < n; i++) {
        if (out->base[i] == SL_OCTREE_NONE)
            continue;
        const transition *tr = &all[i];
        uint32_t *w = out->words + out->base[i], half_mask = 0, spoke_mask = 0, k = 3;
        for (int j = 0; j < 24; j++) {
            half_mask |= (uint32_t)(tr->half[j] != SL_OCTREE_NONE) << j;
            spoke_mask |= (uint32_t)(tr->spoke[j] != SL_OCTREE_NONE) << j;
        }
        w[0] = tr->mid_known | (uint32_t)tr->mid_inside << 12 | (uint32_t)tr->centre_known << 24;
        w[1] = half_mask | (uint32_t)tr->centre_inside << 24;
        w[2] = spoke_mask;
        for (int j = 0; j < 24; j++)
            if (tr->half[j] != SL_OCTREE_NONE)
                w[k++] = tr->half[j];
        for (int j = 0; j < 24; j++)
            if (tr->spoke[j] != SL_OCTREE_NONE)
                w[k++] = tr->spoke[j];
    }
    free(all);
    return 0;
}

void sl_transitions_release(sl_transitions *tr)
{
    free(tr->base);
    free(tr->words);
    memset(tr, 0, sizeof *tr);
}
