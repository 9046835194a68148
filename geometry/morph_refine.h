/* A finer level cut along the coarser level's edges, for its morph target
 * (docs/morphing.md, "The surface at weight 1").
 *
 * With closest-point targets alone every vertex lands on the coarser level at weight 1,
 * but a triangle whose corners land on different coarser faces becomes a chord across the
 * coarser edges between them. The refinement splits such triangles until the three
 * targets of every triangle lie in one coarser triangle (its inside, an edge or a corner),
 * so at weight 1 every triangle is inside one coarser triangle: the surface, not only the
 * vertices, lies on the coarser level.
 *
 * Method (a common refinement built by local splits, in rounds):
 *  1. an edge whose two targets share no coarser triangle is split where its weight-1
 *     chord crosses the plane halving the dihedral angle at an edge of the coarser
 *     triangle its first (or else its last) target lies in: the new vertex's target is
 *     that point of the coarser edge (in both triangles of the edge), its weight-0
 *     position the point of the finer edge nearest to it. Where the chord crosses no
 *     coarser edge from either end (a gap of the closest-point map: a fold, a thin part),
 *     the split goes to the next vertex of the shortest path along coarser edges.
 *     Triangles with split edges are re-triangulated by the 2-, 3- and 4-triangle
 *     templates (no T-junctions). The second edge round in a row without a new fewest
 *     failing edges splits nothing;
 *  2. a triangle whose targets share no coarser triangle but reach over a coarser vertex
 *     gets a vertex targeting it (weight-0 position: the point of the triangle nearest
 *     to the coarser vertex) and becomes a fan of three. Rounds alternate 2, 1;
 *  3. where the rounds stop with triangles still failing (a fold of the closest-point
 *     map), retargeting: a corner whose target is not in the coarser triangle holding
 *     most of its triangle's targets takes the point of that triangle nearest to it as
 *     its target, for all its triangles, when fewer of those then fail (serial passes, in
 *     triangle order);
 *  4. with SL_MORPH_REFINE_TEAR, what is left is torn: such a corner gets a copy (same
 *     bytes at weight 0) targeting the point nearest to it of the coarser triangle its
 *     corners travel least to; at weight 1 the surface lies on the coarser level, in
 *     between the tear opens a crack (`tear_max` at weight 1). Without it (the default)
 *     what is left stays whole, its corners on their closest points: at weight 1 such a
 *     triangle is a chord of the coarser surface (`unresolved`, `unresolved_max`).
 * No new or retargeted vertex travels farther than the level is from the coarser level
 * (the farthest of its triangles' corners, edge midpoints and centres; a split that
 * would is not made, a retarget that would is not taken): a triangle moving into one
 * coarser triangle is, at weight w, within (1 - w) times that distance of the coarser
 * surface, so the blend never strays farther than weight 0 and comes closer as w grows
 * (the unresolved triangles, and with tears the copies, are not bound by it).
 * Every added vertex lies on the finer level's triangle it was made in: its weight-0
 * position is a convex combination of that triangle's corners (kept as up to three
 * source vertices and weights, so normals, colours and texture coordinates interpolate
 * too), so the weight-0 surface is the level's (to float rounding of the new vertices).
 * The level's own vertices come first, in order, with their exact bytes and their
 * closest-point targets (sl_morph_closest_points), except those step 3 retargets.
 *
 * "Lies in a coarser triangle" is a distance below SL_MORPH_REFINE_EPS of the coarser
 * bounding-box diagonal. Rounds stop at SL_MORPH_REFINE_ROUNDS, when two in a row change
 * nothing, or when the triangle count reaches SL_MORPH_REFINE_GROWTH times the level's;
 * triangles whose targets still share no coarser triangle after the tears are counted in
 * `unresolved` (docs/morphing.md has the figures).
 *
 * Thread safety: reentrant. The closest-point queries and each round's tests run in
 * parallel (OpenMP), the splits serially in a fixed order: the result depends only on the
 * inputs, not on the thread count.
 */
#ifndef SCANLOD_GEOMETRY_MORPH_REFINE_H
#define SCANLOD_GEOMETRY_MORPH_REFINE_H

#include <stdint.h>

#include "core/error.h"
#include "geometry/mesh.h"

#define SL_MORPH_REFINE_EPS 1e-6
#define SL_MORPH_REFINE_ROUNDS 48
#define SL_MORPH_REFINE_GROWTH 16
/* sl_morph_refine's flag: tear what no split mends (step 4). */
#define SL_MORPH_REFINE_TEAR 1u

typedef struct sl_morph_refined {
    uint64_t vertex_count;   /* the level's vertices, then the added ones */
    uint64_t triangle_count;
    float *positions;        /* 3 * vertex_count, world: weight 0 */
    float *targets;          /* 3 * vertex_count, world: weight 1, on the coarser level */
    uint32_t *triangles;     /* 3 * triangle_count */
    uint32_t *source;        /* 3 * vertex_count: level vertices a vertex is made of */
    float *weight;           /* 3 * vertex_count: their weights (sum 1; a level vertex: 1, 0, 0) */
    uint64_t level_vertices, level_triangles; /* the level's counts */
    uint64_t torn_triangles; /* triangles with a torn corner (see sl_morph_refine) */
    uint64_t torn_vertices;  /* copies made for them */
    double tear_max;         /* the largest distance between a copy's target and its
                                vertex's: the widest crack at weight 1, world */
    uint64_t unresolved;     /* triangles whose targets still share no coarser triangle */
    double unresolved_max;   /* the farthest such a triangle is from the coarser surface
                                at weight 1 (corners, edge midpoints, centre), world */
    double max_move;         /* the largest distance a level vertex moves, world (its
                                closest point, or where step 3 put it) */
} sl_morph_refined;

/* Refines `level` against `coarser` (both need finite positions; `coarser` at least one
 * triangle); flags: 0 or SL_MORPH_REFINE_TEAR. OUT: *out (release with sl_morph_refined_release; zeroed on failure).
 * Returns 0, SL_E_NOMEM, SL_E_LIMIT (more than 2^32 - 1 vertices) or SL_E_BADINPUT
 * (a coarser mesh without triangles). */
int sl_morph_refine(const sl_mesh *coarser, const sl_mesh *level, unsigned flags,
                    sl_morph_refined *out, sl_error *err);
void sl_morph_refined_release(sl_morph_refined *r);

/* A per-vertex attribute of the level (`comps` floats a vertex) for every refined vertex
 * (OUT: comps * r->vertex_count floats): the weighted sum of its sources'. */
void sl_morph_refined_interpolate(const sl_morph_refined *r, const float *level_attr, int comps,
                                  float *out);
/* Unit normals: the level's interpolated and normalised (zero stays zero). */
void sl_morph_refined_normals(const sl_morph_refined *r, const float *level_normals, float *out);
/* The same for 8-bit RGBA colours (4 a vertex), rounded. */
void sl_morph_refined_interpolate_rgba(const sl_morph_refined *r, const uint8_t *level_rgba,
                                       uint8_t *out);

#endif
