/* The extreme normals of a set of unit normals: their convex hull in the gnomonic
 * projection onto the plane tangent to a chart direction s (every normal must face s:
 * n . s > 0). Great circles project to lines, so the hull's vertices are the extreme
 * normals in every such chart, and for a direction m with all normals within 90 degrees
 * of it, the largest angle between m and the set is taken at a hull vertex (the normals
 * within an angle below 90 degrees of m form a convex cone). Region growing (paper 3,
 * equation 1) and the segment method's merging keep each segment's normals this way.
 *
 * A new normal inside the hull changes nothing; one outside rebuilds it (Andrew's
 * monotone chain with exact orientation, geometry/predicates.h): O(h log h), h the
 * vertex count, typically 5-60 for a patch of a scan. Thread safety: one hull per thread.
 */
#ifndef SCANLOD_GEOMETRY_NORMAL_HULL_H
#define SCANLOD_GEOMETRY_NORMAL_HULL_H

#include <stdint.h>

typedef struct sl_normal_hull {
    double s[3], e1[3], e2[3]; /* chart direction and its tangent frame */
    uint32_t count, cap;
    double *p;                 /* 2 per vertex: gnomonic coordinates, counter-clockwise */
    double *n;                 /* 3 per vertex: the unit normals */
    uint32_t *id;              /* per vertex: the caller's id of the normal */
    double *scratch_p, *scratch_n;
    uint32_t *scratch_id, *order;
} sl_normal_hull;

void sl_normal_hull_init(sl_normal_hull *h);    /* empty, no memory */
void sl_normal_hull_release(sl_normal_hull *h);

/* Empties the hull and sets its chart to the unit direction s. */
void sl_normal_hull_start(sl_normal_hull *h, const double s[3]);

/* Adds unit normal n (n . s > 0) with the caller's id; returns 0 or -1 (out of memory). */
int sl_normal_hull_add(sl_normal_hull *h, const double n[3], uint32_t id);

/* The smallest n . m over the hull's vertices (1 for an empty hull): the cosine of the
 * largest angle between m and the normals added, when they are all within 90 degrees
 * of m. */
double sl_normal_hull_min_dot(const sl_normal_hull *h, const double m[3]);

#endif
