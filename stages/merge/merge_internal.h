/* Internals of the octree build, shared by stages/merge/octree_build.c (parents,
 * assembly), octree_leaves.c (level 0) and octree_levels.c (what every level does). Not
 * an interface: merge.h is. */
#ifndef SCANLOD_STAGES_MERGE_INTERNAL_H
#define SCANLOD_STAGES_MERGE_INTERNAL_H

#include <errno.h>
#include <stdint.h>

#include "geometry/key_table.h"
#include "stages/merge/merge.h"

typedef struct level_tables {
    uint32_t level;
    size_t vcount;
    uint64_t *vkeys;     /* sorted vertex keys */
    uint8_t *vinside;
    size_t ecount;
    uint64_t *ekeys;     /* sorted keys of edges with a crossing */
    uint32_t *ecrossing; /* crossing id per edge */
    size_t ncount;
    sl_octree_node *nodes;  /* Morton order; level, x, y, z, inside, child_mask, edge_mask */
    uint32_t *ncross;       /* 12 per node: crossing id per edge (or NONE) */
} level_tables;

typedef struct crossing_table {
    uint32_t count, capacity;
    float *position;
    uint8_t *color; /* NULL without colours */
} crossing_table;

typedef struct build_state {
    const sl_sample_grid *samples; /* its arrays are gone once the leaves are built */
    int coloured;                  /* the samples have colours */
    int64_t shift[3];     /* added to sample coords to make them >= 0 */
    double origin[3];     /* world of shifted vertex (0,0,0) */
    crossing_table crossings;
    sl_octree_stats stats;
    sl_error *err;
} build_state;

static inline int nomem(build_state *b)
{
    return sl_error_nomem(b->err, NULL, "out of memory building the octree");
}

static inline int64_t vertex_index(const level_tables *l, uint32_t x, uint32_t y, uint32_t z)
{
    if (x >= SL_COORD_LIMIT || y >= SL_COORD_LIMIT || z >= SL_COORD_LIMIT)
        return -1;
    return sl_find_key(l->vkeys, l->vcount, sl_vertex_key(x, y, z));
}

static inline int corner_offset(int c, int a)
{
    return (c >> a) & 1;
}

int sl_merge_crossings_reserve(build_state *b, uint32_t extra);
int sl_merge_sort_nodes_morton(build_state *b, sl_octree_node *nodes, size_t count);
void sl_merge_node_signs(level_tables *l);
int sl_merge_collect_edges(build_state *b, level_tables *l);
int sl_merge_node_crossings(build_state *b, level_tables *l);

/* Level 0: leaf cubes, their signs and "simple divide" crossings (octree_leaves.c). */
int sl_merge_build_leaves(build_state *b, level_tables *l);

#endif
