/* Median splits along one axis, for the spatial trees that split at the median of their
 * widest axis (geometry/kdtree.c over points, geometry/triangle_bvh.c over triangle
 * centroids).
 *
 * A record is a position and the caller's index. Along an axis the records are ordered by
 * (coordinate, index): a strict total order when the indices are distinct, so which
 * records fall on each side of a split, and hence the tree, is a pure function of the
 * input, whatever order the records arrive in.
 */
#ifndef SCANLOD_GEOMETRY_AXIS_SELECT_H
#define SCANLOD_GEOMETRY_AXIS_SELECT_H

#include <stdint.h>

typedef struct sl_axis_record {
    float p[3];     /* world position: a point, a triangle's centroid */
    uint32_t index; /* the caller's index of the point or triangle; breaks ties */
} sl_axis_record;

/* Rearranges r[0..n) so that r[k] is the record of rank k along `axis` (0..2), the
 * records before it smaller and those after it larger (Hoare's selection with a
 * median-of-three pivot: expected O(n), deterministic). Needs k < n. */
void sl_axis_select(sl_axis_record *r, uint64_t n, uint64_t k, int axis);

/* The axis along which r[0..n) spread widest (the lowest such axis on a tie); n >= 1 and
 * the positions finite. */
int sl_axis_widest(const sl_axis_record *r, uint64_t n);

#endif
