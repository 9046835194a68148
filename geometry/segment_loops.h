/* Boundary loops and corners of a segmentation (paper 3, sections 3.2 and 3.4): what
 * boundary trimming walks and what retriangulation takes as the polygon of a segment.
 *
 * A segment's boundary half-edges are those of its triangles whose twin is missing (mesh
 * boundary, cut edge) or in another segment. Each runs with the segment on its left; the
 * successor of one is found by turning around its target inside the segment
 * (sl_halfedge_next_boundary restricted to the segment), which is well defined on a
 * manifold vertex even where a segment touches itself there. Loops are traced from the
 * lowest unvisited half-edge of the segment, so their order and start are canonical.
 *
 * Outer loop and holes: a loop's vector area, 1/2 sum p_i x p_i+1, dotted with the
 * segment's area-weighted normal, is its signed area seen from outside: the outer loop
 * is the one with the largest positive area, the others are holes (a patch that projects
 * onto its plane without folding has exactly one positive loop). A segment with no
 * positive loop (a closed or strongly curved patch) has outer = NONE.
 *
 * Vertex kinds, from the segment labels around each vertex's fan:
 *  - interior: every triangle around it is in one segment;
 *  - two-segment boundary: the labels around it change exactly twice, so it lies on
 *    exactly two segments and on one stretch of the boundary between them (the vertices
 *    boundary trimming may remove, paper equation 2);
 *  - corner: on three or more segments, or on one segment twice (the labels change three
 *    or more times), or on the mesh boundary or a cut edge, or a non-manifold vertex.
 *
 * Thread safety: the build runs its own OpenMP loops; the result is read-only.
 * Determinism: independent of the thread count. Cost: O(n), 4 bytes per boundary
 * half-edge and 2 per vertex.
 */
#ifndef SCANLOD_GEOMETRY_SEGMENT_LOOPS_H
#define SCANLOD_GEOMETRY_SEGMENT_LOOPS_H

#include <stdint.h>

#include "core/error.h"
#include "geometry/mesh_adjacency.h"

enum sl_segment_vertex_kind {
    SL_SEGMENT_VERTEX_UNUSED = 0,
    SL_SEGMENT_VERTEX_INTERIOR = 1,
    SL_SEGMENT_VERTEX_TWO_SEGMENT = 2, /* on the boundary between exactly two segments, once */
    SL_SEGMENT_VERTEX_CORNER = 3
};

typedef struct sl_segment_loops {
    uint32_t segment_count;
    uint32_t loop_count;
    uint32_t *segment_loop_start; /* segment_count + 1: segment k's loops are
                                     [segment_loop_start[k], segment_loop_start[k + 1]) */
    uint32_t *loop_start;         /* loop_count + 1: loop l is halfedges[loop_start[l] ..
                                     loop_start[l + 1]), in order, closed */
    uint32_t *halfedges;          /* boundary half-edges (each loop's vertices are their
                                     origins), the segment on their left */
    double *loop_area;            /* loop_count: signed area along the segment's normal */
    uint32_t *outer;              /* segment_count: the outer loop, or NONE */
    uint8_t *vertex_kind;         /* vertex_count: enum sl_segment_vertex_kind */
    uint8_t *vertex_changes;      /* vertex_count: label changes around the fan (capped at
                                     255; a boundary fan counts as open) */
    uint64_t corners, two_segment_vertices;
} sl_segment_loops;

/* Loops and vertex kinds of the segmentation `segment` (one id < segment_count per
 * triangle of adj; a degenerate triangle's label is ignored). `positions`: 3 floats per
 * vertex (the areas). OUT: *out (release with sl_segment_loops_release). Returns 0,
 * SL_E_BADINPUT (a label out of range), SL_E_NOMEM. */
int sl_segment_loops_build(const sl_mesh_adjacency *adj, const float *positions,
                           const uint32_t *segment, uint32_t segment_count,
                           sl_segment_loops *out, sl_error *err);

void sl_segment_loops_release(sl_segment_loops *loops);

/* Is half-edge h on its segment's boundary? */
static inline int sl_segment_is_boundary(const sl_mesh_adjacency *adj, const uint32_t *segment,
                                         uint32_t h)
{
    uint32_t t = adj->twin[h];
    return t == SL_HALFEDGE_NONE || segment[sl_halfedge_face(t)] != segment[sl_halfedge_face(h)];
}

/* The boundary half-edge of the same segment that follows boundary half-edge h. */
static inline uint32_t sl_segment_next_boundary(const sl_mesh_adjacency *adj,
                                                const uint32_t *segment, uint32_t h)
{
    uint32_t g = sl_halfedge_next(h);
    while (!sl_segment_is_boundary(adj, segment, g))
        g = sl_halfedge_next(adj->twin[g]);
    return g;
}

#endif
