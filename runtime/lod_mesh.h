/* Meshes cut from the octree: triangles given as crossing ids are welded into an indexed
 * mesh (a crossing shared by several cells, at whatever level, becomes one vertex), with
 * colours from the crossings and area-weighted vertex normals. Cost is linear in the
 * output: the crossing -> vertex map is a scratch array the builder resets entry by entry.
 */
#ifndef SCANLOD_RUNTIME_LOD_MESH_H
#define SCANLOD_RUNTIME_LOD_MESH_H

#include <stdint.h>

#include "runtime/mc_cube.h"
#include "runtime/octree.h"

typedef struct sl_lod_mesh {
    uint64_t vertex_count;
    uint64_t triangle_count;
    float *positions;  /* 3 * vertex_count, world */
    float *normals;    /* 3 * vertex_count, unit (zero for isolated vertices) */
    uint8_t *colors;   /* 4 * vertex_count RGBA, or NULL when the octree has none */
    uint32_t *indices; /* 3 * triangle_count */
} sl_lod_mesh;

void sl_lod_mesh_release(sl_lod_mesh *m);

/* What a builder needs besides its output, kept between extractions so that repeated
 * ones stay O(m): the crossing -> vertex map (crossing_count entries, all SL_OCTREE_NONE
 * between uses) and the crossing of each vertex made (to reset the map entry by entry). */
typedef struct sl_dual_slot {
    uint32_t vertex, prev, next; /* a drawn loop through a crossing: its vertex and the
                                    crossings before and after this one in it */
    uint32_t link;               /* the crossing's next slot, or SL_OCTREE_NONE */
} sl_dual_slot;

typedef struct sl_mesh_scratch {
    uint32_t *vertex_of_crossing; /* dual mode: the crossing's first slot */
    uint32_t *used;               /* dual mode: the dual vertex of each vertex made */
    uint64_t used_capacity;
    /* Dual mode only (lod_dual.h): */
    sl_dual_slot *slots;
    uint64_t slot_count, slot_capacity;
    uint32_t *touched;            /* the crossings with slots, in order of first touch */
    uint64_t touched_count, touched_capacity;
    uint32_t *vertex_of_dual;     /* per dual vertex: the vertex made of it, or NONE */
    uint32_t dual_count;
    uint64_t *edge_keys;          /* the dual edges made (lod_dual.c) */
    uint64_t edge_capacity;
    uint32_t *polygons;           /* the polygons around the crossings */
    uint64_t polygon_capacity;
} sl_mesh_scratch;

int sl_mesh_scratch_init(sl_mesh_scratch *s, const sl_octree *tree);
void sl_mesh_scratch_release(sl_mesh_scratch *s);
/* Frees what the scratch grew to for the largest extraction so far (a few tens of bytes
 * per triangle of it), keeping what it was made with: the next extraction grows it
 * again. For a reader that cuts a few large levels and keeps them (the export stage). */
void sl_mesh_scratch_shrink(sl_mesh_scratch *s);

typedef struct sl_mesh_builder {
    const sl_octree *tree;
    sl_mesh_scratch *scratch;
    sl_mesh_scratch own_scratch;  /* when the caller gave none */
    sl_lod_mesh mesh;
    uint64_t vertex_capacity, triangle_capacity;
    uint64_t vertex_room;         /* vertices that fit both the output and scratch->used */
    int caller_buffers;           /* mesh arrays belong to the caller: never grown or freed */
    int failed;                   /* out of memory, or past the caller's capacity */
    const float *dual_position;   /* dual mode (lod_dual.h): the vertex table, else NULL */
    const uint8_t *dual_color;
} sl_mesh_builder;

/* `scratch` may be NULL (allocated here, O(crossings)) or a caller-kept one. */
int sl_mesh_builder_init(sl_mesh_builder *b, const sl_octree *tree, sl_mesh_scratch *scratch);
/* Sizes the output for about `triangles` triangles (a hint: the builder grows past it). */
void sl_mesh_builder_reserve(sl_mesh_builder *b, uint64_t triangles);
/* Writes into the caller's arrays instead (normals may be NULL; colors are written only
 * when both the array and the octree's colours exist): nothing is allocated for the
 * output, and a mesh larger than the capacities fails rather than grows. */
void sl_mesh_builder_use_buffers(sl_mesh_builder *b, const sl_lod_mesh *buffers,
                                 uint64_t vertex_capacity, uint64_t triangle_capacity);
/* Adds the triangles of one cell: `point_id` maps the cell's point ids to crossing ids;
 * centroid points (SL_MC_CENTROID_POINT) become new vertices at their loop's mean. */
void sl_mesh_builder_add_cell(sl_mesh_builder *b, const sl_mc_triangles *tri,
                              const uint32_t point_crossing[SL_MC_MAX_POINTS]);
/* Adds `count` triangles whose corners are crossings: points[3 t + i] is a point id that
 * `point_crossing` maps to a crossing id (a cell without centroid vertices). */
void sl_mesh_builder_add_triangles(sl_mesh_builder *b, int count, const uint8_t *points,
                                   const uint32_t *point_crossing);
/* Adds `count` triangles given as 3 crossing ids each. */
void sl_mesh_builder_add_crossing_triangles(sl_mesh_builder *b, int count,
                                            const uint32_t *crossings);
/* Finishes normals, resets the scratch, moves the mesh to *out (with caller buffers: their
 * pointers and the counts). Returns -1 when out of memory or past the capacities. */
int sl_mesh_builder_finish(sl_mesh_builder *b, sl_lod_mesh *out);
void sl_mesh_builder_abort(sl_mesh_builder *b);

/* For lod_dual.c: the vertex made of dual vertex `id` (made on first use), and room for
 * `count` more triangles (NULL when failed; the caller fills them and counts them in). */
uint32_t sl_mesh_builder_dual_vertex(sl_mesh_builder *b, uint32_t id);
uint32_t *sl_mesh_builder_triangle_slots(sl_mesh_builder *b, int count);
/* Capacity for `need` elements of size `elem` (doubling); -1 when out of memory. */
int sl_mesh_grow(void **p, uint64_t *cap, uint64_t need, size_t elem);

/* The uniform mesh of one level (all level-L nodes with the 256-case table). */
int sl_octree_level_mesh(const sl_octree *tree, uint32_t level, sl_lod_mesh *out);

#endif
