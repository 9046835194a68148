/* The LOD model: the marching-cube octree plus what makes any level of detail cheap to cut
 * (paper 1, sections 2.3-3; docs/lod.md).
 *
 *   lod_array        node index of the k-th expansion, k = 0 .. expansion_count - 1 (paper:
 *                    "priority number"); expanding a node replaces it by its children;
 *   expansion_index  per node, its position in lod_array (SL_OCTREE_NONE: never expanded);
 *   accumulation     triangles of the mesh after k expansions, k = 0 .. expansion_count;
 *   error_after      the largest geometric error of any node still unexpanded after k
 *                    expansions (world units), non-increasing in k;
 *   neighbours       per node, its same-level neighbours in the 26 directions;
 *   transitions      per node, the finer level's samples on its boundary (edge midpoint and
 *                    face centre signs, half-edge and spoke crossings): the precomputed crack
 *                    compensation, so a coarse cell next to a finer one is drawn with the
 *                    finer one's points on their shared face and no crack opens.
 *
 * The mesh after k expansions has as cells the frontier nodes: children of the first k
 * expanded nodes that are not themselves among them (the root for k = 0). Generating it
 * costs O(k + m): every frontier cell is found from the LOD array and drawn from its own
 * record and its neighbours' expansion indices, with no search.
 */
#ifndef SCANLOD_RUNTIME_LOD_MODEL_H
#define SCANLOD_RUNTIME_LOD_MODEL_H

#include <stdint.h>

#include "core/error.h"
#include "runtime/lod_mesh.h"
#include "runtime/mc_cube.h"
#include "runtime/octree.h"

/* Direction index of a neighbour offset (dx, dy, dz) in {-1, 0, 1}^3, 13 = self. */
static inline int sl_direction(int dx, int dy, int dz)
{
    return (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1);
}

typedef struct sl_neighbours {
    uint32_t *mask;   /* per node: bit d set when the neighbour in direction d exists */
    uint32_t *base;   /* per node: index of its first neighbour in `index` */
    uint64_t count;
    uint32_t *index;  /* node indices, per node in direction order */
} sl_neighbours;

/* Per node transition record, compact: words[base] = mid_known | mid_inside << 12 |
 * centre_known << 24; words[base + 1] = half_mask | centre_inside << 24; words[base + 2] =
 * spoke_mask; then one crossing id per set bit of half_mask (bit 2e + h: half h of edge e)
 * and of spoke_mask (bit 4f + k: spoke k of face f). */
typedef struct sl_transitions {
    uint32_t *base;   /* per node, SL_OCTREE_NONE for leaves */
    uint64_t count;
    uint32_t *words;
} sl_transitions;

/* Words of the transition record starting at w: the three heads and one id per mask bit. */
static inline uint32_t sl_transition_record_words(const uint32_t *w)
{
    return 3u + (uint32_t)__builtin_popcount(w[1] & 0xffffff) +
           (uint32_t)__builtin_popcount(w[2] & 0xffffff);
}

/* A node as generation reads it, in LOD order. */
typedef struct sl_lod_cell_ref {
    uint32_t expansion;     /* its expansion_index (SL_OCTREE_NONE: never expanded) */
    uint32_t crossing_base; /* as the node's */
    uint32_t splits;        /* offset of its split list in split_words, or SL_OCTREE_NONE
                               when no cut splits it (a leaf never meets a finer cell) */
    uint16_t edge_mask;
    uint8_t inside;
    uint8_t draws;          /* 0: draws nothing whatever its neighbours */
} sl_lod_cell_ref;

/* A split list (split_words at sl_lod_cell_ref.splits): which faces and edges of a cell
 * meet a finer cell, and how the cell is drawn then, for every k at which it is on the
 * frontier. Word 0: the node's transition record base; word 1: the splits when the cell
 * appears (faces in bits 0-5, edges in bits 6-17) | event count << 24; word 2: the offset
 * of that state's drawing in split_drawings; then per event, in increasing order, the
 * expansion index s of a same-level neighbour, the splits its expansion adds (for k > s)
 * and the drawing of the new state. Only neighbours expanding while the cell is on the
 * frontier make events, so a cell reads a few words after the previous cell's.
 *
 * A drawing is the transition cell's triangles as crossing ids, worked out at load from
 * the transition record (the crack compensation points) and the face-rule triangulation:
 * word 0 = triangle count | 1 << 8 when a split lacked data (a crack the report counts),
 * then 3 crossing ids per triangle. Offset SL_OCTREE_NONE: no split, or a configuration
 * with centroid vertices or more than 18 triangles (drawn the general way). In a dual
 * model (lod_dual.h) a drawing is the cell's drawn loops instead: word 0 = loop count |
 * crack << 8, then per loop its size n, its vertex (an id of dual_position) and its n
 * crossing ids; every state has one. */
#define SL_LOD_SPLIT_DIRS 18 /* 6 face and 12 edge neighbours: those that split a cell */
#define SL_LOD_SPLIT_FACES(w) ((w) & 0x3fu)
#define SL_LOD_SPLIT_EDGES(w) ((w) >> 6 & 0xfffu)

typedef struct sl_lod_model {
    sl_octree tree;
    uint32_t expansion_count;
    uint32_t *lod_array;
    uint32_t *expansion_index;
    uint64_t *accumulation;  /* expansion_count + 1 entries */
    float *error_after;      /* expansion_count + 1 entries */
    /* Same-level neighbours: the priority and crack stages' and the cells' layout's. A
     * model opened for cutting (sl_lod_model_open) holds none after loading: generation
     * never reads them, and they are the largest table in memory (about 20 links a
     * node, most of them the leaves'). */
    sl_neighbours neighbours;
    sl_transitions transitions;
    sl_mesh_scratch scratch; /* the builder's, kept between extractions */
    int cuts_only; /* sl_lod_model_open: only the internal nodes' neighbours are built,
                      and sl_lod_model_prepare drops them once it has laid out the cells,
                      with what else generation never reads: tree.nodes keeps the root
                      alone (node_count stays), and tree.morton, expansion_index and
                      transitions.base go. Such a model is for cutting only: the writer
                      refuses it, and sl_lod_frontier and sl_lod_cell need a whole one. */
    uint64_t neighbour_links; /* the whole table's count (the file header's), what the
                                 writer stores when the table is not held */
    /* Derived at load (sl_lod_model_prepare, runtime/lod_layout.c), for generation: the
     * nodes in LOD order (the root, then the children of lod_array[0], of lod_array[1],
     * ...), so the frontier after k expansions is the part of cells[0 .. frontier_end[k])
     * whose expansion is not below k, drawn in that order by streaming one prefix. */
    uint32_t *frontier_end;  /* expansion_count + 1 entries */
    sl_lod_cell_ref *cells;  /* frontier_end[expansion_count] entries */
    uint32_t *split_words;   /* the cells' split lists, in LOD order */
    uint32_t *split_drawings; /* their states' drawings, in LOD order */
    uint64_t split_drawing_words;
    /* Derived at load: surface_before[k] = how many of the first k expansions are of a
     * node with surface below it (a crossing on an edge of it or of a descendant);
     * expansion_count + 1 entries. The others (empty band cells) change no mesh, so LOD
     * percents count these alone. */
    uint32_t *surface_before;
    /* Derived at load, dual models only (lod_dual.h): the node of each cell in LOD order,
     * and the vertex table generation copies from: the tree's vertices, then one per
     * transition loop that none of its node's vertices fits (at its crossings' centroid). */
    uint32_t *cell_node;
    uint32_t dual_count;
    float *dual_position;
    uint8_t *dual_color;
} sl_lod_model;

void sl_lod_model_init(sl_lod_model *m);
/* Derives what generation needs besides the file's tables: expansion_index, the
 * extraction scratch, the cells in LOD order and their split rows. Needs the tree,
 * lod_array, neighbours and transitions.
 * Returns -1 when out of memory. */
int sl_lod_model_prepare(sl_lod_model *m);
/* The checks and derived tables of a model whose tables are loaded (lod_derive.c):
 * `stored`, the neighbour table was in the file (format 2); else it is rebuilt and must
 * have `links` links, the count the file declares (UINT64_MAX for a prefix, which has no
 * count to check). Then sl_lod_model_localize and sl_lod_model_prepare. Returns 0 or an
 * error naming `name`. */
int sl_lod_model_derive(sl_lod_model *m, int stored, uint64_t links, const char *name,
                        sl_error *err);

/* Renumbers the crossings in the order the LOD array first reaches them (then the rest),
 * so a coarse level's vertices are read from one compact stretch of the crossing table
 * rather than from all over it, and lays out the per-node crossing ids and transition
 * records in LOD order. Generated meshes do not change (vertices are numbered by first
 * use, not by crossing id). Call before sl_lod_model_prepare. Returns -1 when out of
 * memory. */
int sl_lod_model_localize(sl_lod_model *m);
/* The nodes in LOD order (lod_layout.c): order[pos] = node, the root, then the children of
 * lod_array[0], of lod_array[1], ..., then the children of the nodes never expanded,
 * breadth first in this order (model format 5's node order, lod_order.h). Returns NULL
 * when out of memory. */
uint32_t *sl_lod_order(const sl_lod_model *m);
/* new_id[crossing]: the crossings numbered in the order the nodes in `order` first name
 * them (their own, then their transition record's), then those no node names. NULL when
 * out of memory. */
uint32_t *sl_lod_crossing_numbers(const sl_lod_model *m, const uint32_t *order);
/* surface_before from the tree and the LOD array into out (expansion_count + 1 entries):
 * sl_lod_model_prepare's, and what the format 5 writer stores. Returns -1 when out of
 * memory. */
int sl_lod_surface_counts(const sl_lod_model *m, uint32_t *out);
void sl_lod_model_release(sl_lod_model *m);
/* Frees what sl_lod_model_prepare derived (the cell layout, split lists and their
 * drawings, the dual vertex table, the expansion index, the builder's scratch): what the
 * writer never reads. The crack stage's model, prepared for its triangle counts, goes
 * without them while it is packed; a model needs sl_lod_model_prepare again to be cut. */
void sl_lod_model_drop_layout(sl_lod_model *m);
/* Works out the drawing of every state of every split list (each distinct configuration
 * triangulated once); part of sl_lod_model_prepare. Returns -1 when out of memory. */
int sl_lod_draw_states(sl_lod_model *m);

/* The first k at which the cell at LOD-order position pos (pos < frontier_end[E]) is on
 * the frontier: one past its parent's expansion (cells [frontier_end[i],
 * frontier_end[i + 1]) are the children of lod_array[i]); 0 for the root. */
static inline uint32_t sl_lod_first_frontier(const sl_lod_model *m, uint32_t pos)
{
    uint32_t lo = 0, hi = m->expansion_count; /* largest i with frontier_end[i] <= pos */
    if (pos == 0)
        return 0;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo + 1) / 2;
        if (m->frontier_end[mid] <= pos)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo + 1;
}

/* Neighbour in direction d of node n, or SL_OCTREE_NONE. */
static inline uint32_t sl_neighbour(const sl_neighbours *nb, uint32_t n, int d)
{
    uint32_t mask = nb->mask[n];
    if (!(mask >> d & 1))
        return SL_OCTREE_NONE;
    return nb->index[nb->base[n] + (uint32_t)__builtin_popcount(mask & ((1u << d) - 1u))];
}

/* The uniform cell table (sl_mc_uniform_table) as constant data: row c holds the triangle
 * count of corner configuration c, then 3 edge ids per triangle (at most 5 triangles). */
#define SL_LOD_UNIFORM_ROW 16
extern const uint8_t sl_lod_uniform_cells[256][SL_LOD_UNIFORM_ROW];

/* The same-level neighbour table of every node (lod_neighbours.c; O(n log n) lookups,
 * OpenMP over nodes): built by the priority stage and when a model is read. Returns -1
 * on OOM. The transition records are built by the crack stage (sl_transitions_build:
 * stages/crack/crack.h) and read here. */
int sl_neighbours_build(const sl_octree *t, sl_neighbours *out);
/* The same for the internal nodes alone (what the cells' layout reads): the leaves'
 * links are counted into *all_links (the whole table's count) but not kept, and their
 * masks are 0. Returns -1 on OOM. */
int sl_neighbours_build_internal(const sl_octree *t, sl_neighbours *out, uint64_t *all_links);
void sl_neighbours_release(sl_neighbours *nb);
void sl_transitions_release(sl_transitions *tr);

/* The cell of frontier node n when the nodes with expansion_index < k are expanded:
 * corner signs plus the splits its expanded neighbours require; `point_crossing` maps the
 * cell's point ids to crossing ids. Returns 0, or -1 when a split lacks data (a crack the
 * report counts; the cell is then drawn unsplit there). */
int sl_lod_cell(const sl_octree *t, const sl_neighbours *nb, const sl_transitions *tr,
                const uint32_t *expansion_index, uint32_t k, uint32_t n, sl_mc_cell *cell,
                uint32_t point_crossing[SL_MC_MAX_POINTS]);

/* Frontier after k expansions, in a deterministic order; *cells must hold
 * sl_lod_frontier_bound(m, k) entries. Returns the count. */
uint64_t sl_lod_frontier_bound(const sl_lod_model *m, uint32_t k);
uint64_t sl_lod_frontier(const sl_lod_model *m, uint32_t k, uint32_t *cells);

/* The mesh after k expansions (k <= expansion_count). `cracks` (may be NULL) gets the
 * count of cells drawn without a split they needed. Returns 0 or -1 on OOM. */
int sl_lod_generate(sl_lod_model *m, uint32_t k, sl_lod_mesh *out, uint64_t *cracks);
/* The same mesh written into the caller's arrays (positions, indices; normals and colors
 * may be NULL; colors stay unwritten when the octree has none): nothing is allocated for
 * the output. On return *buffers holds the counts. Returns -1 when the mesh does not fit
 * the capacities (then the arrays hold a partial mesh) or scratch cannot grow. */
int sl_lod_generate_into(sl_lod_model *m, uint32_t k, sl_lod_mesh *buffers,
                         uint64_t vertex_capacity, uint64_t triangle_capacity, uint64_t *cracks);

/* k for a triangle budget (largest k whose accumulation <= budget; at least 0), a LOD
 * percent (paper Table 1: the smallest k whose first k expansions include
 * round(percent / 100 * S) of the S expansions of nodes with surface below them, so
 * 100 % is the finest mesh, reached as early as the LOD array reaches it) and a maximum
 * error (smallest k whose error_after <= max_error). */
uint32_t sl_lod_expansions_for_triangles(const sl_lod_model *m, uint64_t budget);
uint32_t sl_lod_expansions_for_percent(const sl_lod_model *m, double percent);
uint32_t sl_lod_expansions_for_error(const sl_lod_model *m, double max_error);

#endif
