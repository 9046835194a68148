/* 2D constrained Delaunay triangulation of a polygon with holes: the retriangulation step
 * of the segmentation method (paper 3, section 3.4) and the clustering method's
 * triangulation (paper 2, section 3). docs/mesh-toolkit.md has the algorithm.
 *
 * Input: points (x, y) and closed loops of point indices: an outer boundary, its holes,
 * islands inside holes, ... Points on no loop are interior vertices to keep (points that
 * fall outside the polygon or in a hole are left out of the output).
 *
 * Output: triangles, as counter-clockwise index triples into the input points, that
 *  - tile exactly the polygon's interior (outside and holes removed);
 *  - contain every loop edge; a loop edge with input points on it is split at them;
 *  - are constrained Delaunay: no triangle's circumcircle strictly contains a point that
 *    is visible from the triangle's interior (loop edges block visibility);
 *  - are canonical: each triple starts at its lowest index and the triples are sorted,
 *    so the same input gives the same array (the computation is serial and exact).
 *
 * Interior: by default loops are oriented, the interior on their left (outer boundary
 * counter-clockwise, holes clockwise), and every point must be wound 0 or 1 times; more
 * (loops overlap: a projection that folds, or a hole running the wrong way) or -1 (a
 * clockwise outer loop: a mirrored projection) is refused as SL_CDT_FOLD. With
 * SL_CDT_EVEN_ODD, orientation is ignored and a point is inside when it is enclosed by an
 * odd number of loops.
 *
 * Refused input (returns SL_E_BADINPUT, `report` says which points): a loop edge crossing
 * another, two loop edges sharing a segment (a loop edge used twice, or collinear loop
 * edges overlapping), folds, points that coincide (unless SL_CDT_MERGE_DUPLICATES),
 * non-finite or huge coordinates, indices out of range. Loops may touch at points (a loop
 * vertex on another loop's edge splits that edge). Consecutive equal indices in a loop are
 * skipped. A caller that triangulates many patches passes a scratch sl_error and, on
 * SL_E_BADINPUT, leaves that patch as it was (as CGAL does for a patch it cannot project).
 *
 * Limits: at most SL_CDT_MAX_POINTS points and SL_CDT_MAX_LOOP_POINTS loop entries
 * (SL_E_LIMIT above), |x|, |y| <= SL_CDT_MAX_COORDINATE.
 * Cost: O(n log n) expected for point insertion (spatial sort, walk, Lawson flips), plus
 * O(k^2) per loop edge crossing k triangles; about 100 bytes per point.
 * Thread safety: no shared state; concurrent calls on different data are fine.
 */
#ifndef SCANLOD_GEOMETRY_CDT_H
#define SCANLOD_GEOMETRY_CDT_H

#include <stdint.h>

#include "core/error.h"

#define SL_CDT_MAX_POINTS (1u << 28)
#define SL_CDT_MAX_LOOP_POINTS (1u << 30)
#define SL_CDT_MAX_COORDINATE 0x1p500

enum sl_cdt_flags {
    SL_CDT_EVEN_ODD = 1u << 0,         /* loops unoriented: inside = enclosed an odd number of times */
    SL_CDT_MERGE_DUPLICATES = 1u << 1, /* coincident points: keep the lowest index, map the others to it */
};

typedef struct sl_cdt_input {
    uint32_t point_count;
    const double *points;       /* 2 * point_count: x, y */
    uint32_t loop_count;
    const uint32_t *loop_start; /* loop_count + 1 offsets into loop_points, ascending, [0] = 0 */
    const uint32_t *loop_points; /* loop l: loop_points[loop_start[l] .. loop_start[l + 1]),
                                    closed: its last point joins its first */
} sl_cdt_input;

/* Why an input was refused; v[] are input point indices (unused entries UINT32_MAX). */
enum sl_cdt_problem {
    SL_CDT_PROBLEM_NONE = 0,
    SL_CDT_NONFINITE,       /* v[0]'s coordinates are NaN, infinite or beyond the limit */
    SL_CDT_BAD_INDEX,       /* loop v[0] names point v[1] >= point_count, or loop_start is bad */
    SL_CDT_DUPLICATE_POINT, /* v[0] and v[1] (v[0] < v[1]) have the same coordinates */
    SL_CDT_CROSSING,        /* loop edge v[0]-v[1] crosses loop edge v[2]-v[3] */
    SL_CDT_OVERLAP,         /* the segment v[0]-v[1] belongs to two loop edges */
    SL_CDT_FOLD             /* triangle v[0] v[1] v[2] is wound `winding` times */
};

typedef struct sl_cdt_report {
    int problem;     /* enum sl_cdt_problem */
    uint32_t v[4];
    int winding;     /* SL_CDT_FOLD only */
} sl_cdt_report;

typedef struct sl_cdt_result {
    uint64_t triangle_count;
    uint32_t *triangles;     /* 3 * triangle_count point indices (merged points: the lowest) */
    uint64_t split_edges;    /* loop edge pieces created at points lying on loop edges */
    uint64_t merged_points;  /* points mapped to an equal lower-index point */
    uint64_t unused_points;  /* points in no output triangle: outside, in holes, or merged */
} sl_cdt_result;

/* Triangulates `in`; `flags` from enum sl_cdt_flags. OUT: *out, a new result to release
 * with sl_cdt_free (NULL on failure); *report (may be NULL) is filled on every call.
 * Returns 0, SL_E_BADINPUT (refused input, see above), SL_E_LIMIT, SL_E_NOMEM, or
 * SL_E_INTERNAL (an internal consistency check failed: a bug). */
int sl_cdt_triangulate(const sl_cdt_input *in, uint32_t flags, sl_cdt_result **out,
                       sl_cdt_report *report, sl_error *err);

void sl_cdt_free(sl_cdt_result *result); /* NULL is fine */

#endif
