/* Transition records: the precomputed crack compensation (paper 1, section 2.4; crack.h;
 * the record's format: runtime/lod_model.h, docs/lod.md).
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
#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "stages/crack/crack.h"

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

/* The finer cell at offset (ox, oy, oz), each -1..2, from node i's first child's corner:
 * a child of i or of one of its same-level neighbours (a finer node exists only under its
 * parent), found through the neighbour table when i has its links (an internal node), else
 * by a search of the finer level's Morton order. */
static uint32_t finer_cell(const sl_octree *t, const sl_neighbours *nb, uint32_t i, int ox,
                           int oy, int oz)
{
    const sl_octree_node *n = &t->nodes[i];
    if (!nb || !n->child_mask)
        return sl_octree_find(t, n->level - 1u, 2 * (int64_t)n->x + ox, 2 * (int64_t)n->y + oy,
                              2 * (int64_t)n->z + oz);
    /* -1 -> the neighbour below, 0 and 1 -> i's own column, 2 -> the neighbour above */
    int dx = (ox + 2) / 2 - 1, dy = (oy + 2) / 2 - 1, dz = (oz + 2) / 2 - 1;
    uint32_t m = dx || dy || dz ? sl_neighbour(nb, i, sl_direction(dx, dy, dz)) : i;
    if (m == SL_OCTREE_NONE)
        return SL_OCTREE_NONE;
    const sl_octree_node *parent = &t->nodes[m];
    unsigned octant = (unsigned)(ox & 1) | (unsigned)(oy & 1) << 1 | (unsigned)(oz & 1) << 2;
    if (!(parent->child_mask >> octant & 1))
        return SL_OCTREE_NONE;
    uint32_t fi = parent->first_child + (uint32_t)__builtin_popcount(parent->child_mask & ((1u << octant) - 1u));
    assert(fi == sl_octree_find(t, n->level - 1u, 2 * (int64_t)n->x + ox, 2 * (int64_t)n->y + oy,
                                2 * (int64_t)n->z + oz));
    return fi;
}

static void gather(const sl_octree *t, const sl_neighbours *nb, uint32_t i, transition *tr)
{
    memset(tr, 0, sizeof *tr);
    for (int k = 0; k < 24; k++)
        tr->half[k] = tr->spoke[k] = SL_OCTREE_NONE;
    for (int cell = 0; cell < 64; cell++) {
        int ox = cell % 4 - 1, oy = cell / 4 % 4 - 1, oz = cell / 16 - 1;
        uint32_t fi = finer_cell(t, nb, i, ox, oy, oz);
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

int sl_transitions_build(const sl_octree *t, const sl_neighbours *nb, sl_transitions *out,
                         uint64_t *unresolved)
{
    memset(out, 0, sizeof *out);
    *unresolved = 0;
    uint32_t n = t->node_count, internal = 0;
    /* Leaves have no record: the gathered records are held for the internal nodes alone
     * (a sixth of the nodes; each record is 200 bytes), at slot[i]. */
    uint32_t *slot = malloc((n ? n : 1) * sizeof *slot);
    out->base = malloc((n ? n : 1) * sizeof *out->base);
    if (!slot || !out->base) {
        free(slot);
        sl_transitions_release(out);
        return -1;
    }
    for (uint32_t i = 0; i < n; i++)
        slot[i] = t->nodes[i].level == 0 ? SL_OCTREE_NONE : internal++;
    transition *all = malloc((internal ? internal : 1) * sizeof *all);
    if (!all) {
        free(slot);
        sl_transitions_release(out);
        return -1;
    }
    uint64_t missing = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : missing)
    for (uint32_t i = 0; i < n; i++) {
        if (slot[i] == SL_OCTREE_NONE)
            continue;
        transition *tr = &all[slot[i]];
        gather(t, nb, i, tr);
        missing += (uint64_t)(12 - __builtin_popcount(tr->mid_known)) +
                   (uint64_t)(6 - __builtin_popcount(tr->centre_known));
    }
    *unresolved = missing;
    for (uint32_t i = 0; i < n; i++) {
        if (slot[i] == SL_OCTREE_NONE) {
            out->base[i] = SL_OCTREE_NONE;
            continue;
        }
        const transition *tr = &all[slot[i]];
        out->base[i] = (uint32_t)out->count;
        out->count += 3;
        for (int k = 0; k < 24; k++)
            out->count += (tr->half[k] != SL_OCTREE_NONE) + (tr->spoke[k] != SL_OCTREE_NONE);
    }
    out->words = malloc((out->count ? out->count : 1) * sizeof *out->words);
    if (!out->words) {
        free(all);
        free(slot);
        sl_transitions_release(out);
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (uint32_t i = 0; i < n; i++) {
        if (out->base[i] == SL_OCTREE_NONE)
            continue;
        const transition *tr = &all[slot[i]];
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
    free(slot);
    return 0;
}
