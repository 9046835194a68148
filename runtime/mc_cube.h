/* Marching-cube cell polygonization, consistent between face neighbours and across one
 * level of octree refinement (paper 1, sections 2.1-2.2 and 2.4; docs/marching-cubes.md).
 *
 * Numbering (used by every file of the octree):
 *   corner i      at offset (i & 1, (i >> 1) & 1, (i >> 2) & 1) in the cube;
 *   edge e        along axis a = e / 4; k = e % 4 gives the other two axes' bits:
 *                 b = (a + 1) % 3 gets bit k & 1, c = (a + 2) % 3 gets bit k >> 1; its first
 *                 corner c0 has bit a = 0, its second c1 = c0 | (1 << a). Ratios run c0 -> c1;
 *   face f        axis f / 2, side f % 2 (0 = the low side, 1 = the high side).
 * "Inside" is the paper's s_n = true (negative signed distance).
 *
 * The surface in a cell is built face by face, not from a hand-written table: on each face
 * the crossings are paired by one rule that depends only on that face's samples ("every
 * inside run along the face boundary is cut off by its own segment"), so two cells that share
 * a face always draw the same segments on it, and the segments of one cell close into loops.
 * The classic 256-configuration table is this rule applied to whole faces
 * (sl_mc_uniform_table); the same rule on subdivided edges and faces gives the transition
 * cells that meet a finer neighbour without cracks.
 *
 * Thread safety: everything here is pure; the uniform table is built once (pthread_once).
 */
#ifndef SCANLOD_RUNTIME_MC_CUBE_H
#define SCANLOD_RUNTIME_MC_CUBE_H

#include <stdint.h>

#define SL_MC_MAX_POINTS 60 /* distinct crossing point ids below */
#define SL_MC_MAX_TRIANGLES 64
#define SL_MC_MAX_LOOPS 8

/* Point ids: where a crossing lies on the cell. */
#define SL_MC_EDGE_POINT(e) (e)                     /* whole edge e: 0..11 */
#define SL_MC_HALF_POINT(e, h) (12 + 2 * (e) + (h)) /* half h of split edge e (0 = at c0) */
#define SL_MC_SPOKE_POINT(f, k) (36 + 4 * (f) + (k)) /* split face f: centre -> midpoint of
                                                        the face's k-th boundary edge */
#define SL_MC_CENTROID_POINT(l) (60 + (l)) /* mean of loop l's points (a cell's own vertex) */

/* One cell: corner signs, and for transitions the samples of split edges and faces. */
typedef struct sl_mc_cell {
    uint8_t inside;         /* bit i: corner i inside */
    uint16_t split_edges;   /* bit e: edge e is split at its midpoint */
    uint16_t mid_inside;    /* bit e: the midpoint of split edge e is inside */
    uint8_t split_faces;    /* bit f: face f is split into 2x2 (its 4 edges must be split) */
    uint8_t centre_inside;  /* bit f: the centre of split face f is inside */
} sl_mc_cell;

typedef struct sl_mc_triangles {
    uint8_t count;
    uint8_t points[SL_MC_MAX_TRIANGLES][3]; /* point ids, counter-clockwise seen from outside */
    uint8_t loops;                          /* closed crossing loops in the cell */
    uint8_t loop_sizes[SL_MC_MAX_LOOPS];
    int loop_points[SL_MC_MAX_LOOPS][12 + 24];
    uint8_t centroids;                      /* bit l: loop l is fanned from its centroid */
} sl_mc_triangles;

/* Loops of point ids (each closed), triangulated; triangles face outwards. Only the parts of
 * *out up to count, loops and loop_sizes are written. */
void sl_mc_triangulate(const sl_mc_cell *cell, sl_mc_triangles *out);

/* The 256 whole-face configurations (points are edge indices 0..11). */
const sl_mc_triangles *sl_mc_uniform_table(void);

/* For the dual of the surface (runtime/lod_dual.h): splits every loop that has two
 * segments on one face (or one sub-face of a split face) into two, along a chord between
 * the ends of those segments, until none has (a segment joining the two halves of a split
 * edge is on the face whose walk drew it, though both its points lie on two faces). Two cells sharing a face both drawing one
 * loop through it twice would otherwise share two edges, and their two dual vertices two
 * edges: an edge of four triangles once vertices name edges. Only loop_sizes, loop_points
 * and loops change (up to SL_MC_MAX_LOOPS; the triangles are left as they were). */
void sl_mc_split_double_passes(const sl_mc_cell *cell, sl_mc_triangles *tri);

/* Edge/face geometry helpers. */
static inline int sl_mc_edge_axis(int e) { return e / 4; }
static inline int sl_mc_edge_c0(int e)
{
    int a = e / 4, k = e % 4, b = (a + 1) % 3, c = (a + 2) % 3;
    return ((k & 1) << b) | ((k >> 1) << c);
}
static inline int sl_mc_edge_c1(int e) { return sl_mc_edge_c0(e) | (1 << (e / 4)); }
/* Edge index of the edge along axis a starting at corner c0 (bit a of c0 clear). */
static inline int sl_mc_edge_of(int a, int c0)
{
    int b = (a + 1) % 3, c = (a + 2) % 3;
    return a * 4 + ((c0 >> b) & 1) + 2 * ((c0 >> c) & 1);
}
/* The 4 corners of face f in counter-clockwise order seen from outside the cube, and its
 * 4 boundary edges: edge k joins corner k and corner k + 1 (mod 4). */
void sl_mc_face_corners(int f, int corners[4]);
void sl_mc_face_edges(int f, int edges[4]);

#endif
