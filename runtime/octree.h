/* The marching-cube octree (paper 1, section 2.2; docs/octree.md).
 *
 * Nodes are cubes of the level's grid: a level-l node has edge length leaf_size * 2^l and
 * integer coordinates (x, y, z) in level-l cells, so its world corner is
 * origin + (x, y, z) * leaf_size * 2^l. Each node holds the paper's marching-cube node
 * data: 8 vertex signs, and for every edge whose ends differ in sign, the crossing point
 * ("edge ratio"). Crossings are shared: a crossing is one entry of the crossing table, and
 * a parent's crossing on an edge *is* the child's crossing on the half-edge it came from
 * (the ratio extension of section 2.2), so meshes of any mix of levels share vertices.
 *
 * Layout: nodes sorted by level, root (level `depth`) first, leaves (level 0) last; within
 * a level in Morton order, so the children of a node are contiguous, in octant order
 * (octant o = child at (2x + (o & 1), 2y + (o >> 1 & 1), 2z + (o >> 2))).
 *
 * Vertices ([octree] vertices = qef; docs/lod.md "Vertices from quadrics"): optionally each
 * node also carries one vertex per closed loop of its own (uniform) marching-cube
 * configuration, placed where the quadric of the input surface inside the cell that the
 * loop stands for is least, and a mesh is then drawn as the dual of the marching-cube
 * surface: a vertex per loop, a polygon per crossing. Node n's vertices are
 * vertex_first[n] .. vertex_first[n + 1] - 1, in the order of the uniform table's loops
 * (sl_mc_uniform_table()[inside]); their count is the loop count, or 0 when the cell holds
 * no input surface and the input is open (its loops are trimmed: no surface is grown
 * across a scan's holes), or 1 for a node without loops whose cell holds surface (the
 * vertex a transition loop of that cell takes).
 */
#ifndef SCANLOD_RUNTIME_OCTREE_H
#define SCANLOD_RUNTIME_OCTREE_H

#include <stddef.h>
#include <stdint.h>

#define SL_OCTREE_MAX_LEVELS 21 /* coordinates are packed in 20 bits */
#define SL_OCTREE_NONE UINT32_MAX

typedef struct sl_octree_node {
    int32_t x, y, z;        /* cube position in this level's cells */
    uint8_t level;          /* 0 = leaf */
    uint8_t inside;         /* bit i: corner i inside (paper: s_n = true) */
    uint8_t child_mask;     /* bit o: child in octant o exists */
    uint8_t flags;          /* SL_NODE_* */
    uint32_t parent;        /* SL_OCTREE_NONE for the root */
    uint32_t first_child;   /* children are nodes [first_child, first_child + popcount) */
    uint32_t crossing_base; /* this node's crossings: node_crossings[crossing_base + rank] */
    uint16_t edge_mask;     /* bit e: edge e has a crossing (its ends differ in sign) */
    uint16_t reserved;
} sl_octree_node;

typedef struct sl_octree_stats {
    uint64_t sign_case[4];      /* parent corners by paper case A (corresponding), B
                                   (adjacent), C (diagonal), D (centre) */
    uint64_t inherited_crossings;
    uint64_t fallback_crossings; /* parent crossing with no child crossing to extend */
} sl_octree_stats;

typedef struct sl_octree {
    double leaf_size;    /* world units */
    double origin[3];    /* world position of leaf-grid vertex (0, 0, 0) */
    uint32_t depth;      /* the root's level */
    uint32_t node_count;
    sl_octree_node *nodes;
    uint32_t level_first[SL_OCTREE_MAX_LEVELS]; /* first node of each level */
    uint32_t level_count[SL_OCTREE_MAX_LEVELS];
    uint32_t crossing_count;
    float *crossing_position;  /* 3 * crossing_count, world */
    uint8_t *crossing_color;   /* 4 * crossing_count RGBA, or NULL */
    uint64_t node_crossing_count;
    uint32_t *node_crossings;  /* crossing ids, per node in edge order */
    sl_octree_stats stats;
    uint64_t *morton;          /* per node Morton key, derived (not stored): lookups */
    /* Dual vertices, or all NULL/0 (paper 1's marching-cube triangles). */
    uint32_t vertex_count;
    uint32_t *vertex_first;    /* node_count + 1 entries, non-decreasing, last = vertex_count */
    float *vertex_position;    /* 3 * vertex_count, world, inside the node's cube */
    uint8_t *vertex_color;     /* 4 * vertex_count RGBA, iff crossing_color */
    float *node_error;         /* per node: the quadric error of its vertices, summed, plus
                                  (cell edge / 2)^2 per unit of area of surface it draws no
                                  loop for (world units^4: area x squared distance) */
    float *node_area;          /* per node: area of input surface in its cell (world^2) */
                               /* Both NULL in an LOD model's octree (model format 4):
                                  only the priority stage reads them, from octree.slot. */
} sl_octree;

#define SL_OCTREE_MAX_NODE_VERTICES 4 /* loops of a uniform configuration, at most */

/* Whether the tree has dual vertices (drawn as the dual of its marching-cube surface). */
static inline int sl_octree_dual(const sl_octree *t)
{
    return t->vertex_first != NULL;
}

void sl_octree_init(sl_octree *t);
void sl_octree_release(sl_octree *t);
/* Frees the per-node errors and areas (NULL after): what an LOD model's octree goes without
 * (model format 4); the priority stage, which orders by them, reads octree.slot. */
void sl_octree_drop_node_metrics(sl_octree *t);

/* The box of every crossing: lo[3], hi[3] (FLT_MAX and -FLT_MAX when there are none). */
void sl_octree_crossing_bounds(const sl_octree *t, float lo[3], float hi[3]);

/* The crossings renumbered by the permutation new_id (crossing i goes to new_id[i]):
 * fresh arrays in *position and, when the tree has colours, *color (else NULL). 0, or -1
 * when out of memory (nothing allocated). The model's layout and its writer both need it. */
int sl_octree_permuted_crossings(const sl_octree *t, const uint32_t *new_id, float **position,
                                 uint8_t **color);

/* Crossing id of edge e of node n (edge_mask must have bit e). */
static inline uint32_t sl_octree_crossing(const sl_octree *t, const sl_octree_node *n, int e)
{
    unsigned below = (unsigned)n->edge_mask & ((1u << e) - 1u);
    return t->node_crossings[n->crossing_base + (uint32_t)__builtin_popcount(below)];
}

/* World position of a node's corner c. */
void sl_octree_corner_world(const sl_octree *t, const sl_octree_node *n, int c, double out[3]);

/* Index of the node at (level, x, y, z), or SL_OCTREE_NONE. Binary search in the level's
 * Morton order: O(log n). */
uint32_t sl_octree_find(const sl_octree *t, uint32_t level, int64_t x, int64_t y, int64_t z);

/* Index of the node with Morton key `key` among nodes [lo, hi) of one level, or
 * SL_OCTREE_NONE: the binary search behind sl_octree_find, for a run of a level (a brick). */
uint32_t sl_octree_search(const sl_octree *t, uint32_t lo, uint32_t hi, uint64_t key);

/* Derives the per-node Morton keys that make sl_octree_find fast (called by the
 * builder and the readers; -1 when out of memory). */
int sl_octree_index(sl_octree *t);

/* Morton code of 20-bit coordinates (x in the lowest interleaved bit). */
uint64_t sl_morton3(uint32_t x, uint32_t y, uint32_t z);

#endif
