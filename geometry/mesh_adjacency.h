/* Half-edge adjacency over an indexed triangle mesh: the connectivity the segmentation
 * (paper 3) and clustering (paper 2) methods walk. docs/mesh-toolkit.md has the method.
 *
 * Half-edges are implicit: half-edge h = 3 t + c of triangle t runs from corner c to
 * corner (c + 1) % 3, so next, prev and face are arithmetic; only the twin (the half-edge
 * running the other way in the triangle across) and one outgoing half-edge per vertex are
 * stored. Triangles are the caller's (borrowed, not copied).
 *
 * Problems are found, counted and cut, never guessed around:
 *  - an edge in three or more triangles (non-manifold), or in two that run it the same
 *    way (inconsistent orientation), is cut: none of its half-edges gets a twin, so it
 *    behaves like a boundary and walks never cross it;
 *  - a vertex whose triangles form more than one fan once those edges are cut (two cones
 *    touching at a tip, a "bow tie") is flagged non-manifold; its outgoing half-edge is
 *    in one of the fans;
 *  - a triangle with a repeated corner index is degenerate: left out of the adjacency
 *    (no twins, nobody's twin, no vertex refers to it).
 * With SL_ADJACENCY_STRICT any of them is refused instead: SL_E_BADINPUT with a message
 * naming the first one (indices, and coordinates when positions are given).
 *
 * Orientation: for counter-clockwise triangles, sl_halfedge_rotate() turns an outgoing
 * half-edge counter-clockwise around its origin. A boundary vertex's stored half-edge is
 * the outgoing boundary one (no twin), so rotating from it visits its whole fan.
 *
 * Limits: at most SL_ADJACENCY_MAX_TRIANGLES triangles (half-edge ids fit in 32 bits)
 * and 2^32 - 2 vertices (SL_E_LIMIT above); every index < vertex_count (SL_E_BADINPUT).
 * Cost: O(n) time (edges bucketed by their lower vertex, buckets sorted in parallel),
 * 4 bytes per half-edge, 5 bytes per vertex, plus 8 bytes per half-edge while building.
 * Determinism: the result depends only on the input, not on the thread count.
 * Thread safety: building runs its own OpenMP loops; a built adjacency is read-only.
 */
#ifndef SCANLOD_GEOMETRY_MESH_ADJACENCY_H
#define SCANLOD_GEOMETRY_MESH_ADJACENCY_H

#include <stdint.h>

#include "core/error.h"

#define SL_HALFEDGE_NONE UINT32_MAX
#define SL_ADJACENCY_MAX_TRIANGLES ((UINT32_MAX - 1u) / 3u)

enum sl_adjacency_flags {
    SL_ADJACENCY_STRICT = 1u << 0 /* refuse non-manifold, inconsistent and degenerate input */
};

/* Per-vertex flags (sl_mesh_adjacency.vertex_flags). */
enum sl_vertex_flags {
    SL_VERTEX_USED = 1u << 0,        /* some non-degenerate triangle uses it */
    SL_VERTEX_BOUNDARY = 1u << 1,    /* on a half-edge without twin (a boundary or cut edge) */
    SL_VERTEX_CUT = 1u << 2,         /* on a cut (non-manifold or inconsistent) edge */
    SL_VERTEX_NONMANIFOLD = 1u << 3  /* its triangles form more than one fan */
};

enum sl_adjacency_problem {
    SL_ADJACENCY_OK = 0,
    SL_ADJACENCY_DEGENERATE,        /* triangle t[0] repeats vertex v[0] */
    SL_ADJACENCY_NONMANIFOLD_EDGE,  /* edge v[0]-v[1] is in `edge_triangles` triangles, t[0..2] the first */
    SL_ADJACENCY_INCONSISTENT_EDGE, /* triangles t[0] and t[1] both run v[0] -> v[1] */
    SL_ADJACENCY_NONMANIFOLD_VERTEX /* vertex v[0]'s triangles form more than one fan; t[0] is in one */
};

/* What the build saw. Edges are undirected vertex pairs of non-degenerate triangles. */
typedef struct sl_adjacency_report {
    uint64_t edges;                /* distinct edges */
    uint64_t boundary_edges;       /* in exactly one triangle */
    uint64_t nonmanifold_edges;    /* in three or more triangles: cut */
    uint64_t inconsistent_edges;   /* in two triangles running it the same way: cut */
    uint64_t nonmanifold_vertices; /* more than one fan after cutting */
    uint64_t degenerate_triangles; /* a repeated corner: left out */
    uint64_t used_vertices;        /* vertices of non-degenerate triangles */
    uint64_t boundary_loops;       /* cycles of half-edges without twin (boundary and cut
                                      edges), followed around each vertex's fan */
    int64_t euler_characteristic;  /* used_vertices - edges + non-degenerate triangles */
    int problem;                   /* enum sl_adjacency_problem: the first one found */
    uint32_t v[2], t[3];           /* where (unused entries UINT32_MAX) */
    uint32_t edge_triangles;       /* SL_ADJACENCY_NONMANIFOLD_EDGE: how many */
} sl_adjacency_report;

typedef struct sl_mesh_adjacency {
    uint32_t vertex_count;
    uint32_t triangle_count;
    const uint32_t *triangles;  /* borrowed: 3 * triangle_count vertex indices */
    uint32_t *twin;             /* 3 * triangle_count: the opposite half-edge, or NONE */
    uint32_t *vertex_halfedge;  /* vertex_count: an outgoing half-edge (on a boundary: the
                                   outgoing one without twin), NONE if unused */
    uint8_t *vertex_flags;      /* vertex_count: enum sl_vertex_flags */
    uint8_t *degenerate;        /* triangle_count: 1 for a left-out triangle */
    sl_adjacency_report report;
} sl_mesh_adjacency;

/* Builds the adjacency of `triangle_count` triangles over `vertex_count` vertices.
 * `positions` (3 floats per vertex, may be NULL) only make messages name coordinates;
 * `flags` from enum sl_adjacency_flags. OUT: *out (release with
 * sl_mesh_adjacency_release; zeroed on failure). Returns 0, SL_E_BADINPUT (an index out
 * of range; in strict mode also the problems above), SL_E_LIMIT or SL_E_NOMEM. */
int sl_mesh_adjacency_build(const uint32_t *triangles, uint64_t triangle_count,
                            uint64_t vertex_count, const float *positions, uint32_t flags,
                            sl_mesh_adjacency *out, sl_error *err);

void sl_mesh_adjacency_release(sl_mesh_adjacency *adj);

/* One line describing report->problem into buf ("" when none); `positions` may be NULL. */
const char *sl_adjacency_problem_text(const sl_adjacency_report *report, const float *positions,
                                      char *buf, unsigned size);

static inline uint32_t sl_halfedge_face(uint32_t h) { return h / 3u; }
static inline uint32_t sl_halfedge_next(uint32_t h) { return h % 3u == 2u ? h - 2u : h + 1u; }
static inline uint32_t sl_halfedge_prev(uint32_t h) { return h % 3u == 0u ? h + 2u : h - 1u; }

static inline uint32_t sl_halfedge_origin(const sl_mesh_adjacency *adj, uint32_t h)
{
    return adj->triangles[h];
}
static inline uint32_t sl_halfedge_target(const sl_mesh_adjacency *adj, uint32_t h)
{
    return adj->triangles[sl_halfedge_next(h)];
}

/* The next outgoing half-edge around h's origin, counter-clockwise (twin of prev), or
 * NONE at a boundary. */
static inline uint32_t sl_halfedge_rotate(const sl_mesh_adjacency *adj, uint32_t h)
{
    return adj->twin[sl_halfedge_prev(h)];
}

/* The boundary half-edge (no twin) that follows boundary half-edge h, found by turning
 * around h's target inside h's fan: the boundary loops' successor. */
static inline uint32_t sl_halfedge_next_boundary(const sl_mesh_adjacency *adj, uint32_t h)
{
    uint32_t g = sl_halfedge_next(h);
    while (adj->twin[g] != SL_HALFEDGE_NONE)
        g = sl_halfedge_next(adj->twin[g]);
    return g;
}

#endif
