/* Where a pass's bricks are and what each must lock (qem_bricks_internal.h): the Morton
 * cut, the locks on the bricks' borders and the rings around them, and the strips a later
 * pass works on. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "geometry/key_table.h"
#include "geometry/mesh.h"
#include "geometry/mesh_distance.h"
#include "geometry/qem_bricks_internal.h"

#define MORTON_BITS 20        /* per axis, before the shift */
#define STRIP_RINGS 6         /* a later pass works on the triangles at least this many
                                 rings around the last pass's brick borders (its excess) */
#define STRIP_ROOM 8          /* ... and at least this many times the excess */

void qem_brick_cut_release(brick_cut *c)
{
    free(c->order);
    free(c->first);
    memset(c, 0, sizeof *c);
}

/* The Morton interleave of three 21-bit coordinates (runtime/octree.h's sl_morton3 has 20
 * bits, one short of the shifted grid, and lives above geometry/). */
static uint64_t spread3(uint64_t x)
{
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

/* The box of the corners of m's triangles (NaN coordinates ignored). */
void qem_mesh_box(const sl_qem_mesh *m, double lo[3], double hi[3])
{
    for (int a = 0; a < 3; a++)
        lo[a] = INFINITY, hi[a] = -INFINITY;
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        for (int a = 0; a < 3; a++) {
            double x = m->positions[3 * (uint64_t)m->triangles[i] + a];
            lo[a] = fmin(lo[a], x);
            hi[a] = fmax(hi[a], x);
        }
}

/* Bricks of at most `brick_triangles`, consecutive in the Morton order of the centroids
 * on a grid shifted by `shift` (a fraction of the cell of the octree level where cells
 * are about as many as bricks). */
int qem_cut_bricks(const sl_qem_mesh *m, const uint8_t *active, uint64_t brick_triangles,
                      double shift, brick_cut *out)
{
    memset(out, 0, sizeof *out);
    uint64_t n = 0; /* the active triangles */
    for (uint64_t t = 0; t < m->triangle_count; t++)
        n += !active || active[t];
    double lo[3], hi[3];
    qem_mesh_box(m, lo, hi); /* the whole's box */
    double extent = 0;
    for (int a = 0; a < 3; a++)
        extent = fmax(extent, hi[a] - lo[a]);
    uint64_t bricks = n ? (n + brick_triangles - 1) / brick_triangles : 0;
    int level = 0; /* 8^level cells at least as many as the bricks */
    while (level < MORTON_BITS && (uint64_t)1 << (3 * level) < bricks)
        level++;
    double grid = (double)((uint64_t)1 << MORTON_BITS);
    double offset = shift * (double)((uint64_t)1 << (MORTON_BITS - level));
    double scale = extent > 0 ? (grid - 1) / extent : 0;
    sl_key_pair *pairs = malloc((n ? n : 1) * sizeof *pairs);
    out->order = malloc((n ? n : 1) * sizeof *out->order);
    out->first = malloc((bricks + 1) * sizeof *out->first);
    if (!pairs || !out->order || !out->first) {
        free(pairs);
        qem_brick_cut_release(out);
        return -1;
    }
    uint64_t *which = active ? malloc((n ? n : 1) * sizeof *which) : NULL;
    if (active && !which) {
        free(pairs);
        qem_brick_cut_release(out);
        return -1;
    }
    for (uint64_t t = 0, i = 0; active && t < m->triangle_count; t++)
        if (active[t])
            which[i++] = t;
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < n; i++) {
        uint64_t t = which ? which[i] : i, q[3];
        for (int a = 0; a < 3; a++) {
            double c = 0;
            for (int k = 0; k < 3; k++)
                c += m->positions[3 * (uint64_t)m->triangles[3 * t + k] + a];
            double g = (c / 3 - lo[a]) * scale + offset;
            q[a] = g > 0 ? (uint64_t)fmin(g, 2 * grid - 1) : 0; /* NaN: 0 */
        }
        pairs[i].key = spread3(q[0]) | spread3(q[1]) << 1 | spread3(q[2]) << 2;
        pairs[i].value = t;
    }
    free(which);
    if (sl_sort_pairs(pairs, n, 3 * (MORTON_BITS + 1)) != 0) {
        free(pairs);
        qem_brick_cut_release(out);
        return -1;
    }
    for (uint64_t t = 0; t < n; t++)
        out->order[t] = (uint32_t)pairs[t].value;
    free(pairs);
    out->count = bricks;
    for (uint64_t b = 0; b <= bricks; b++) /* equal shares */
        out->first[b] = bricks ? n * b / bricks : 0; /* (no active triangle: none) */
    return 0;
}

/* Per vertex, the LOCK_ bits; *border_triangles: the active triangles with a corner on a
 * border. NULL when out of memory. */
uint8_t *qem_brick_locks(const sl_qem_mesh *m, const brick_cut *cut, const uint8_t *active,
                              const uint8_t *locked, uint64_t *border_triangles)
{
    uint64_t nv = m->vertex_count;
    uint32_t *point = malloc((nv ? nv : 1) * sizeof *point);
    uint8_t *out = calloc(nv ? nv : 1, 1);
    uint32_t *owner = NULL;
    uint8_t *outside = NULL;
    if (!point || !out)
        goto fail;
    sl_mesh view = sl_mesh_view(nv, m->positions, NULL, NULL, m->triangle_count, m->triangles);
    int64_t points = sl_mesh_weld_positions(&view, point);
    if (points < 0)
        goto fail;
    uint64_t np = (uint64_t)points ? (uint64_t)points : 1;
    owner = malloc(np * sizeof *owner); /* the brick that first used point p, or SHARED */
    outside = calloc(np, 1);            /* a triangle the pass leaves alone uses it */
    if (!owner || !outside)
        goto fail;
    const uint32_t unseen = UINT32_MAX, shared = UINT32_MAX - 1;
    memset(owner, 0xff, np * sizeof *owner);
    for (uint64_t t = 0; active && t < m->triangle_count; t++)
        if (!active[t])
            for (int k = 0; k < 3; k++)
                outside[point[m->triangles[3 * t + k]]] = 1;
    for (uint64_t b = 0; b < cut->count; b++)
        for (uint64_t i = cut->first[b]; i < cut->first[b + 1]; i++)
            for (int k = 0; k < 3; k++) {
                uint32_t p = point[m->triangles[3 * (uint64_t)cut->order[i] + k]];
                if (owner[p] == unseen)
                    owner[p] = (uint32_t)b;
                else if (owner[p] != (uint32_t)b)
                    owner[p] = shared;
            }
    for (uint64_t v = 0; v < nv; v++) {
        uint32_t p = point[v];
        if (p != UINT32_MAX && owner[p] != unseen)
            out[v] = (uint8_t)((owner[p] == shared ? LOCK_BORDER : 0) |
                               (outside[p] ? LOCK_OUTSIDE : 0));
        if (locked && locked[v])
            out[v] |= LOCK_CALLER;
    }
    /* The ring around them locked too. Why: a brick sees only its own triangles, so its
     * link condition cannot see an edge between two border points that lies in another
     * brick, and a collapse of a point next to both could give that edge a third triangle
     * (eight spheres, test_qem_bricked). With the ring locked nothing collapses into a
     * border point: their stars do not change in any brick. The next pass's strips take
     * the ring down with the borders. */
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *c = m->triangles + 3 * t;
        if ((out[c[0]] | out[c[1]] | out[c[2]]) & (LOCK_BORDER | LOCK_OUTSIDE))
            for (int k = 0; k < 3; k++)
                out[c[k]] |= LOCK_RING;
    }
    *border_triangles = 0;
    for (uint64_t t = 0; t < m->triangle_count; t++)
        if (!active || active[t])
            *border_triangles += ((out[m->triangles[3 * t]] | out[m->triangles[3 * t + 1]] |
                                   out[m->triangles[3 * t + 2]]) & (LOCK_BORDER | LOCK_RING)) != 0;
    free(owner);
    free(outside);
    free(point);
    return out;
fail:
    free(owner);
    free(outside);
    free(point);
    free(out);
    return NULL;
}

/* One brick's part in a pass: its error curve and how far its first run went, its count,
 * its simplified mesh with `source` naming the pass input's vertices, its figures, and its
 * error. */
/* The triangles within some rings of the marked vertices (the last pass's borders, where
 * its excess is): at least STRIP_RINGS rings, and as many more as it takes to hold
 * STRIP_ROOM times `excess` triangles, so the excess is taken from a band, not a line.
 * What the next pass works on. NULL when out of memory; *count set. */
uint8_t *qem_brick_strip(const sl_qem_mesh *m, const uint8_t *marked, uint64_t excess,
                             uint64_t *count)
{
    uint8_t *vert = malloc(m->vertex_count + 1), *tri = calloc(m->triangle_count + 1, 1);
    if (!vert || !tri) {
        free(vert);
        free(tri);
        return NULL;
    }
    memcpy(vert, marked, m->vertex_count);
    *count = 0;
    for (int ring = 0; ring < STRIP_RINGS || *count < STRIP_ROOM * excess; ring++) {
        uint64_t before = *count;
        for (uint64_t t = 0; t < m->triangle_count; t++)
            if (!tri[t] && (vert[m->triangles[3 * t]] | vert[m->triangles[3 * t + 1]] |
                            vert[m->triangles[3 * t + 2]])) {
                tri[t] = 1;
                ++*count;
            }
        if (*count == before || *count == m->triangle_count)
            break;
        for (uint64_t t = 0; t < m->triangle_count; t++)
            if (tri[t])
                for (int k = 0; k < 3; k++)
                    vert[m->triangles[3 * t + k]] = 1;
    }
    free(vert);
    return tri;
}

