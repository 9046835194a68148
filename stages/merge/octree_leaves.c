/* Level 0 of the marching-cube octree (paper 1, section 2.2): the leaf cubes are the
 * leaf-grid cubes whose 8 corners all carry a sample; vertex signs are the samples' signs
 * and edge ratios come from "simple divide" of the two distances (merge.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/mc_cube.h"
#include "stages/merge/merge_internal.h"

#define RATIO_MIN 1e-3 /* keeps crossings off the corners: no zero-length edges */

static int leaf_vertices(build_state *b, level_tables *l, uint32_t **sample_of)
{
    const sl_sample_grid *s = b->samples;
    sl_key_pair *pairs = malloc(s->count * sizeof *pairs);
    if (!pairs)
        return nomem(b);
    for (uint64_t i = 0; i < s->count; i++) {
        uint32_t p[3];
        for (int a = 0; a < 3; a++)
            p[a] = (uint32_t)(s->coords[3 * i + a] + b->shift[a]);
        pairs[i].key = sl_vertex_key(p[0], p[1], p[2]);
        pairs[i].value = i;
    }
    if (sl_sort_pairs(pairs, s->count, 3 * SL_COORD_BITS) != 0) {
        free(pairs);
        return nomem(b);
    }
    l->vcount = s->count;
    l->vkeys = malloc(s->count * sizeof *l->vkeys);
    l->vinside = malloc(s->count);
    *sample_of = malloc(s->count * sizeof **sample_of);
    if (!l->vkeys || !l->vinside || !*sample_of) {
        free(pairs);
        return nomem(b);
    }
    for (uint64_t i = 0; i < s->count; i++) {
        if (i > 0 && pairs[i].key == pairs[i - 1].key) {
            free(pairs);
            return sl_error_set(b->err, SL_E_CORRUPT, 0, NULL, "two samples at one grid vertex");
        }
        l->vkeys[i] = pairs[i].key;
        (*sample_of)[i] = (uint32_t)pairs[i].value;
        l->vinside[i] = s->distance[pairs[i].value] < 0;
    }
    free(pairs);
    return 0;
}

int sl_merge_build_leaves(build_state *b, level_tables *l)
{
    const sl_sample_grid *s = b->samples;
    uint32_t *sample_of = NULL;
    int rc = leaf_vertices(b, l, &sample_of);
    uint8_t *is_leaf = rc ? NULL : calloc(l->vcount ? l->vcount : 1, 1);
    if (rc == 0 && !is_leaf)
        rc = nomem(b);
    if (rc) {
        free(sample_of);
        return rc;
    }
    /* A leaf cube is a cube whose 8 corners all carry a sample. */
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < l->vcount; i++) {
        uint32_t p[3];
        sl_vertex_unpack(l->vkeys[i], p);
        int all = 1;
        for (int c = 1; c < 8 && all; c++)
            all = vertex_index(l, p[0] + (uint32_t)corner_offset(c, 0),
                               p[1] + (uint32_t)corner_offset(c, 1),
                               p[2] + (uint32_t)corner_offset(c, 2)) >= 0;
        is_leaf[i] = (uint8_t)all;
    }
    for (size_t i = 0; i < l->vcount; i++)
        l->ncount += is_leaf[i];
    l->nodes = calloc(l->ncount ? l->ncount : 1, sizeof *l->nodes);
    if (!l->nodes) {
        free(is_leaf);
        free(sample_of);
        return nomem(b);
    }
    for (size_t i = 0, k = 0; i < l->vcount; i++) {
        if (!is_leaf[i])
            continue;
        uint32_t p[3];
        sl_vertex_unpack(l->vkeys[i], p);
        l->nodes[k].x = (int32_t)p[0];
        l->nodes[k].y = (int32_t)p[1];
        l->nodes[k].z = (int32_t)p[2];
        k++;
    }
    free(is_leaf);
    rc = sl_merge_sort_nodes_morton(b, l->nodes, l->ncount);
    if (rc == 0) {
        sl_merge_node_signs(l);
        rc = sl_merge_collect_edges(b, l);
    }
    if (rc == 0)
        rc = sl_merge_crossings_reserve(b, (uint32_t)l->ecount);
    if (rc) {
        free(sample_of);
        return rc;
    }
    /* Leaf crossings: "simple divide" of the two distances along the edge. */
    crossing_table *ct = &b->crossings;
    uint32_t base = ct->count;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < l->ecount; i++) {
        uint64_t v0 = l->ekeys[i] >> 2;
        int axis = (int)(l->ekeys[i] & 3);
        uint32_t p[3];
        sl_vertex_unpack(v0, p);
        int64_t i0 = sl_find_key(l->vkeys, l->vcount, v0);
        uint32_t q[3] = {p[0], p[1], p[2]};
        q[axis]++;
        int64_t i1 = vertex_index(l, q[0], q[1], q[2]);
        double d0 = s->distance[sample_of[i0]], d1 = s->distance[sample_of[i1]];
        double t = d0 / (d0 - d1);
        if (!(t >= RATIO_MIN))
            t = RATIO_MIN;
        if (t > 1 - RATIO_MIN)
            t = 1 - RATIO_MIN;
        uint32_t id = base + (uint32_t)i;
        for (int a = 0; a < 3; a++)
            ct->position[3 * (size_t)id + a] =
                (float)(b->origin[a] + ((double)p[a] + (a == axis ? t : 0.0)) * s->leaf_size);
        if (ct->color)
            for (int k = 0; k < 4; k++)
                ct->color[4 * (size_t)id + k] = (uint8_t)lround(
                    (1 - t) * s->colors[4 * (size_t)sample_of[i0] + k] +
                    t * s->colors[4 * (size_t)sample_of[i1] + k]);
        l->ecrossing[i] = id;
    }
    ct->count += (uint32_t)l->ecount;
    free(sample_of);
    return sl_merge_node_crossings(b, l);
}

