/* Bottom-up construction of the marching-cube octree (paper 1, section 2.2; merge.h).
 *
 * Each level keeps three sorted tables: its vertices (with signs), its edges whose ends
 * differ in sign (with their crossing ids), and its nodes (Morton order, so a parent's
 * children are contiguous). Level l + 1 is derived from level l only:
 *   nodes    parents of the level-l nodes;
 *   signs    per parent corner u, the level-l vertex 2u (case A), else the majority of the
 *            defined level-l vertices at 2u + one unit step along 1 (B), 2 (C) or 3 (D)
 *            axes -- the adjacent, diagonal and centre vertices of the paper's Figure 2,
 *            looked up globally so every parent sharing u agrees;
 *   crossings on a parent edge (u, a) with a sign change: the crossing of the level-l
 *            half-edge where the sign flips, found through the midpoint 2u + e_a (ratio
 *            extension: the same crossing id, hence the same point); without one, a new
 *            crossing at the middle of that half (a counted fallback).
 * All per-element work runs in OpenMP loops writing to disjoint slots; anything that
 * appends (fallback crossings) happens afterwards in key order, so the result does not
 * depend on the thread count.
 */
#include "stages/merge/merge.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/mc_cube.h"
#include "runtime/octree_io.h"
#include "geometry/key_table.h"
#include "stages/merge/merge_internal.h"


static void level_release(level_tables *l)
{
    free(l->vkeys);
    free(l->vinside);
    free(l->ekeys);
    free(l->ecrossing);
    free(l->nodes);
    free(l->ncross);
    memset(l, 0, sizeof *l);
}

static int build_parent_nodes(build_state *b, const level_tables *child, level_tables *l)
{
    l->level = child->level + 1;
    l->nodes = calloc(child->ncount ? child->ncount : 1, sizeof *l->nodes);
    if (!l->nodes)
        return nomem(b);
    size_t k = 0;
    for (size_t i = 0; i < child->ncount; i++) { /* children in Morton order: parents too */
        const sl_octree_node *c = &child->nodes[i];
        int32_t x = c->x >> 1, y = c->y >> 1, z = c->z >> 1;
        if (k == 0 || l->nodes[k - 1].x != x || l->nodes[k - 1].y != y || l->nodes[k - 1].z != z) {
            l->nodes[k].x = x;
            l->nodes[k].y = y;
            l->nodes[k].z = z;
            l->nodes[k].level = (uint8_t)l->level;
            k++;
        }
        int octant = (c->x & 1) | (c->y & 1) << 1 | (c->z & 1) << 2;
        l->nodes[k - 1].child_mask |= (uint8_t)(1u << octant);
    }
    l->ncount = k;
    return 0;
}

static int build_parent_vertices(build_state *b, level_tables *l)
{
    uint64_t *keys = malloc((l->ncount ? l->ncount : 1) * 8 * sizeof *keys);
    if (!keys)
        return nomem(b);
    for (size_t i = 0; i < l->ncount; i++)
        for (int c = 0; c < 8; c++)
            keys[8 * i + (size_t)c] =
                sl_vertex_key((uint32_t)(l->nodes[i].x + corner_offset(c, 0)),
                              (uint32_t)(l->nodes[i].y + corner_offset(c, 1)),
                              (uint32_t)(l->nodes[i].z + corner_offset(c, 2)));
    if (sl_sort_keys(keys, 8 * l->ncount, 3 * SL_COORD_BITS) != 0) {
        free(keys);
        return nomem(b);
    }
    l->vcount = sl_unique_keys(keys, 8 * l->ncount);
    l->vkeys = keys;
    l->vinside = malloc(l->vcount ? l->vcount : 1);
    return l->vinside ? 0 : nomem(b);
}

/* Sign of parent vertex u from the child level (paper Figure 2, cases A-D): returns the
 * case (0..3) and sets *inside; -1 if no child vertex is near (cannot happen for a
 * corner of a parent that has children). */
static int parent_sign(const level_tables *child, const uint32_t u[3], uint8_t *inside)
{
    int64_t w[3] = {2 * (int64_t)u[0], 2 * (int64_t)u[1], 2 * (int64_t)u[2]};
    for (int steps = 0; steps <= 3; steps++) {
        int in = 0, out = 0, first = -1;
        for (int dx = -1; dx <= 1; dx++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dz = -1; dz <= 1; dz++) {
                    if ((dx != 0) + (dy != 0) + (dz != 0) != steps)
                        continue;
                    int64_t p[3] = {w[0] + dx, w[1] + dy, w[2] + dz};
                    if (p[0] < 0 || p[1] < 0 || p[2] < 0)
                        continue;
                    int64_t v = vertex_index(child, (uint32_t)p[0], (uint32_t)p[1], (uint32_t)p[2]);
                    if (v < 0)
                        continue;
                    if (first < 0)
                        first = child->vinside[v];
                    if (child->vinside[v])
                        in++;
                    else
                        out++;
                }
        if (in + out > 0) {
            *inside = (uint8_t)(in > out ? 1 : in < out ? 0 : first);
            return steps;
        }
    }
    return -1;
}

static int parent_signs(build_state *b, const level_tables *child, level_tables *l)
{
    uint64_t cases[4] = {0, 0, 0, 0};
    int missing = 0;
#pragma omp parallel for schedule(static) reduction(+ : missing)
    for (size_t i = 0; i < l->vcount; i++) {
        uint32_t u[3];
        sl_vertex_unpack(l->vkeys[i], u);
        int which = parent_sign(child, u, &l->vinside[i]);
        if (which < 0) {
            l->vinside[i] = 0;
            missing++;
        } else {
#pragma omp atomic
            cases[which]++;
        }
    }
    for (int c = 0; c < 4; c++)
        b->stats.sign_case[c] += cases[c];
    if (missing)
        return sl_error_set(b->err, SL_E_INTERNAL, 0, NULL,
                            "%d parent corners without any child vertex", missing);
    return 0;
}

/* Parent edge crossings: the child's crossing on the half-edge where the sign flips. */
static int parent_crossings(build_state *b, const level_tables *child, level_tables *l)
{
    uint8_t *fallback_half = malloc(l->ecount ? l->ecount : 1); /* 0 none, 1/2 half, 3 whole */
    if (!fallback_half)
        return nomem(b);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < l->ecount; i++) {
        uint64_t vu = l->ekeys[i] >> 2;
        int axis = (int)(l->ekeys[i] & 3);
        uint32_t u[3];
        sl_vertex_unpack(vu, u);
        uint8_t inside_u = l->vinside[sl_find_key(l->vkeys, l->vcount, vu)];
        uint32_t w[3] = {2 * u[0], 2 * u[1], 2 * u[2]}, m[3] = {w[0], w[1], w[2]};
        m[axis]++;
        int64_t mid = vertex_index(child, m[0], m[1], m[2]);
        l->ecrossing[i] = SL_OCTREE_NONE;
        fallback_half[i] = 3;
        if (mid < 0)
            continue;
        int first_half = child->vinside[mid] != inside_u;
        const uint32_t *start = first_half ? w : m;
        int64_t e = sl_find_key(child->ekeys, child->ecount,
                                sl_edge_key(sl_vertex_key(start[0], start[1], start[2]), axis));
        if (e >= 0) {
            l->ecrossing[i] = child->ecrossing[e];
            fallback_half[i] = 0;
        } else {
            fallback_half[i] = first_half ? 1 : 2;
        }
    }
    size_t fallbacks = 0;
    for (size_t i = 0; i < l->ecount; i++)
        fallbacks += fallback_half[i] != 0;
    int rc = sl_merge_crossings_reserve(b, (uint32_t)fallbacks);
    if (rc) {
        free(fallback_half);
        return rc;
    }
    crossing_table *ct = &b->crossings;
    double size = b->samples->leaf_size * (double)(1u << l->level);
    for (size_t i = 0; i < l->ecount; i++) { /* appended in key order: deterministic */
        if (!fallback_half[i])
            continue;
        uint32_t u[3];
        sl_vertex_unpack(l->ekeys[i] >> 2, u);
        int axis = (int)(l->ekeys[i] & 3);
        double t = fallback_half[i] == 1 ? 0.25 : fallback_half[i] == 2 ? 0.75 : 0.5;
        uint32_t id = ct->count++;
        for (int a = 0; a < 3; a++)
            ct->position[3 * (size_t)id + a] =
                (float)(b->origin[a] + ((double)u[a] + (a == axis ? t : 0.0)) * size);
        if (ct->color)
            memset(ct->color + 4 * (size_t)id, 160, 4);
        l->ecrossing[i] = id;
    }
    b->stats.fallback_crossings += fallbacks;
    b->stats.inherited_crossings += l->ecount - fallbacks;
    free(fallback_half);
    return 0;
}

static int build_parent(build_state *b, const level_tables *child, level_tables *l)
{
    int rc = build_parent_nodes(b, child, l);
    if (rc == 0)
        rc = build_parent_vertices(b, l);
    if (rc == 0)
        rc = parent_signs(b, child, l);
    if (rc == 0) {
        sl_merge_node_signs(l);
        rc = sl_merge_collect_edges(b, l);
    }
    if (rc == 0)
        rc = parent_crossings(b, child, l);
    if (rc == 0)
        rc = sl_merge_node_crossings(b, l);
    return rc;
}

/* ---- assembly: levels root-first into one node array ------------------------------ */

/* Level l's node i as the octree's node `at`, its crossings from `cross` on. */
static uint64_t place_node(sl_octree *out, const level_tables *lt, uint32_t l, size_t i,
                           uint32_t at, uint64_t cross)
{
    sl_octree_node *n = &out->nodes[at];
    *n = lt->nodes[i];
    n->level = (uint8_t)l;
    n->parent = SL_OCTREE_NONE;
    n->first_child = SL_OCTREE_NONE;
    n->crossing_base = (uint32_t)cross;
    for (int e = 0; e < 12; e++)
        if (n->edge_mask >> e & 1)
            out->node_crossings[cross++] = lt->ncross[12 * i + (size_t)e];
    return cross;
}

/* The levels into one octree, the root's level first. The leaves, three quarters of the
 * nodes, become the tail of the node and crossing arrays in place: their tables are grown
 * into the octree's (realloc, then moved up) instead of copied beside them, which was the
 * merge's peak (every level's tables and the whole octree at once). */
static int assemble(build_state *b, level_tables *levels, uint32_t depth, sl_octree *out)
{
    uint64_t total = 0, crossings = 0, leaf_crossings = 0;
    for (uint32_t l = 0; l <= depth; l++) {
        total += levels[l].ncount;
        for (size_t i = 0; i < levels[l].ncount; i++)
            crossings += (uint64_t)__builtin_popcount(levels[l].nodes[i].edge_mask);
    }
    if (total >= UINT32_MAX)
        return sl_error_set(b->err, SL_E_LIMIT, 0, NULL, "more than 2^32 octree nodes");
    level_tables *leaves = &levels[0];
    /* The leaves' crossings packed to the front of their own table (each node's edges in
     * order: a write never passes the read), then the table grown to hold every level's. */
    for (size_t i = 0; i < leaves->ncount; i++)
        for (int e = 0; e < 12; e++)
            if (leaves->nodes[i].edge_mask >> e & 1)
                leaves->ncross[leaf_crossings++] = leaves->ncross[12 * i + (size_t)e];
    uint32_t n0 = (uint32_t)leaves->ncount;
    uint64_t upper = total - n0, upper_crossings = crossings - leaf_crossings;
    sl_octree_node *nodes = realloc(leaves->nodes, (size_t)(total ? total : 1) * sizeof *nodes);
    if (nodes)
        leaves->nodes = nodes;
    uint32_t *node_crossings =
        realloc(leaves->ncross, (size_t)(crossings ? crossings : 1) * sizeof *node_crossings);
    if (node_crossings)
        leaves->ncross = node_crossings;
    if (!nodes || !node_crossings)
        return nomem(b);
    memmove(nodes + upper, nodes, (size_t)n0 * sizeof *nodes);
    memmove(node_crossings + upper_crossings, node_crossings,
            (size_t)leaf_crossings * sizeof *node_crossings);
    leaves->nodes = NULL; /* the octree's now */
    leaves->ncross = NULL;
    out->nodes = nodes;
    out->node_crossings = node_crossings;
    out->node_count = (uint32_t)total;
    out->node_crossing_count = crossings;
    out->depth = depth;
    uint32_t next = 0;
    uint64_t cross = 0;
    for (int32_t l = (int32_t)depth; l >= 1; l--) {
        level_tables *lt = &levels[l];
        out->level_first[l] = next;
        out->level_count[l] = (uint32_t)lt->ncount;
        for (size_t i = 0; i < lt->ncount; i++)
            cross = place_node(out, lt, (uint32_t)l, i, next + (uint32_t)i, cross);
        next += (uint32_t)lt->ncount;
        free(lt->nodes);
        free(lt->ncross);
        lt->nodes = NULL;
        lt->ncross = NULL;
    }
    out->level_first[0] = next;
    out->level_count[0] = n0;
    for (uint32_t i = 0; i < n0; i++) { /* the leaves, in place */
        sl_octree_node *n = &out->nodes[next + i];
        n->level = 0;
        n->parent = SL_OCTREE_NONE;
        n->first_child = SL_OCTREE_NONE;
        n->crossing_base = (uint32_t)cross;
        cross += (uint64_t)__builtin_popcount(n->edge_mask);
    }
    /* Children of level l + 1 nodes are the level-l nodes, in the same Morton order. */
    for (uint32_t l = 1; l <= depth; l++) {
        uint32_t child = out->level_first[l - 1];
        for (uint32_t i = 0; i < out->level_count[l]; i++) {
            uint32_t p = out->level_first[l] + i;
            out->nodes[p].first_child = child;
            int count = __builtin_popcount(out->nodes[p].child_mask);
            for (int k = 0; k < count; k++)
                out->nodes[child + (uint32_t)k].parent = p;
            child += (uint32_t)count;
        }
    }
    out->crossing_count = b->crossings.count;
    out->crossing_position = b->crossings.position;
    out->crossing_color = b->crossings.color;
    b->crossings.position = NULL;
    b->crossings.color = NULL;
    out->leaf_size = b->samples->leaf_size;
    memcpy(out->origin, b->origin, sizeof out->origin);
    out->stats = b->stats;
    return sl_octree_index(out) ? nomem(b) : 0;
}

static int check_samples(build_state *b)
{
    const sl_sample_grid *s = b->samples;
    if (s->count == 0)
        return sl_error_set(b->err, SL_E_BADINPUT, 0, NULL, "no samples: nothing to mesh");
    if (!(s->leaf_size > 0) || !isfinite(s->leaf_size))
        return sl_error_set(b->err, SL_E_CORRUPT, 0, NULL, "leaf size %g is not positive",
                            s->leaf_size);
    int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
    for (uint64_t i = 0; i < s->count; i++)
        for (int a = 0; a < 3; a++) {
            int64_t c = s->coords[3 * i + a];
            lo[a] = c < lo[a] ? c : lo[a];
            hi[a] = c > hi[a] ? c : hi[a];
        }
    for (int a = 0; a < 3; a++) {
        if (hi[a] - lo[a] >= (int64_t)SL_COORD_LIMIT / 2)
            return sl_error_set(b->err, SL_E_LIMIT, 0, NULL,
                                "samples span %lld leaf cells, more than the octree's %u",
                                (long long)(hi[a] - lo[a]), SL_COORD_LIMIT / 2);
        b->shift[a] = -lo[a]; /* the octree grid starts at the lowest sample */
        b->origin[a] = s->origin[a] - (double)b->shift[a] * s->leaf_size;
    }
    return 0;
}

/* No leaf edge changes sign: the finest level would have no triangle. That is bad input
 * (a leaf too coarse for the surface, or samples of one sign), never an empty success. */
static int no_surface(const build_state *b, const level_tables *leaves)
{
    size_t inside = 0;
    for (size_t i = 0; i < leaves->vcount; i++)
        inside += leaves->vinside[i];
    return sl_error_set(b->err, SL_E_BADINPUT, 0, NULL,
                        "the surface produced no triangles at leaf size %g: no leaf cube has "
                        "corners on both sides of it (%zu of %zu samples inside); set a "
                        "smaller [octree] leaf_size or a larger [octree] depth",
                        b->samples->leaf_size, inside, leaves->vcount);
}

int sl_octree_build(const sl_sample_grid *samples, sl_octree *out, sl_progress *progress,
                    sl_error *err)
{
    return sl_octree_build_releasing(samples, NULL, NULL, out, progress, err);
}

int sl_octree_build_releasing(const sl_sample_grid *samples, void (*release)(void *owner),
                              void *owner, sl_octree *out, sl_progress *progress, sl_error *err)
{
    sl_octree_init(out);
    build_state b;
    memset(&b, 0, sizeof b);
    b.samples = samples;
    b.coloured = samples->colors != NULL;
    b.err = err;
    level_tables levels[SL_OCTREE_MAX_LEVELS];
    memset(levels, 0, sizeof levels);
    int rc = check_samples(&b);
    if (rc == 0)
        rc = sl_merge_build_leaves(&b, &levels[0]);
    if (release) /* the parents read only the level below them */
        release(owner);
    if (rc == 0 && levels[0].ncount == 0)
        rc = sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                          "no leaf cube has all 8 corners sampled: the samples are too sparse");
    if (rc == 0 && levels[0].ecount == 0)
        rc = no_surface(&b, &levels[0]);
    uint32_t depth = 0;
    while (rc == 0 && levels[depth].ncount > 1) {
        if (depth + 1 >= SL_OCTREE_MAX_LEVELS) {
            rc = sl_error_set(err, SL_E_LIMIT, 0, NULL, "octree deeper than %d levels",
                              SL_OCTREE_MAX_LEVELS);
            break;
        }
        if (sl_progress_step(progress, "merge", (double)depth / 16.0)) {
            rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "interrupted");
            break;
        }
        rc = build_parent(&b, &levels[depth], &levels[depth + 1]);
        depth++;
        /* The child level's vertex and edge tables are no longer needed. */
        free(levels[depth - 1].vkeys);
        free(levels[depth - 1].vinside);
        free(levels[depth - 1].ekeys);
        free(levels[depth - 1].ecrossing);
        levels[depth - 1].vkeys = NULL;
        levels[depth - 1].vinside = NULL;
        levels[depth - 1].ekeys = NULL;
        levels[depth - 1].ecrossing = NULL;
    }
    if (rc == 0)
        rc = assemble(&b, levels, depth, out);
    if (rc == 0 && !sl_octree_grid_ok(out))
        rc = sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                          "the octree's grid (leaf %g, %u levels, origin %g %g %g) reaches "
                          "beyond %g units, which readers refuse: rescale the scan, move it "
                          "nearer the origin or choose a smaller leaf",
                          out->leaf_size, depth + 1, out->origin[0], out->origin[1],
                          out->origin[2], SL_OCTREE_MAX_EXTENT);
    for (uint32_t l = 0; l < SL_OCTREE_MAX_LEVELS; l++)
        level_release(&levels[l]);
    free(b.crossings.position);
    free(b.crossings.color);
    if (rc)
        sl_octree_release(out);
    return rc;
}
