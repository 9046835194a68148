/* cluster method internals (cluster.h): one pass = clusters (cluster_grow.c) -> borders
 * and their straightening (cluster_borders.c) -> polygons triangulated
 * (cluster_polygons.c) -> intermediate models (cluster_morph.c); cluster_pass.c runs
 * them, cluster_simplify.c chains passes and searches budgets. */
#ifndef SCANLOD_STAGES_CLUSTER_INTERNAL_H
#define SCANLOD_STAGES_CLUSTER_INTERNAL_H

#include <stdint.h>

#include "core/error.h"
#include "geometry/mesh_adjacency.h"
#include "geometry/segment_loops.h"
#include "stages/cluster/cluster.h"

#define CL_NONE UINT32_MAX
#define CL_KEPT_REFUSED 3

/* The clusters of one pass, each with the frame the whole pass measures it in. */
typedef struct cl_clusters {
    uint32_t count;
    uint32_t *of_triangle;   /* triangle -> cluster */
    double *frame;           /* 12 per cluster: normal n, u, v (u x v = n), origin o */
    double *lo, *hi;         /* the slab: min and max of n . (p - o) over its vertices */
    uint32_t *tri_start;     /* count + 1: cluster k's triangles are tris[tri_start[k]..) */
    uint32_t *tris;
    uint8_t *kept;           /* nonzero: keeps its input triangles (its borders stay as they
                                are); CL_KEPT_REFUSED: because its polygon was refused */
} cl_clusters;

/* Grows the clusters of `adj` (positions: 3 floats per vertex; normals: 3 doubles per
 * triangle, zero for none). A triangle joins a cluster when the cluster's slab stays within
 * its own slab_limit and the seed's, the cosine of its normal's angle to the cluster's
 * direction is at least its own cos_limit and the seed's, and it is strictly
 * counter-clockwise in the cluster's frame (exact test). Serial, ordered by indices. */
int cl_grow(const sl_mesh_adjacency *adj, const float *positions, const double *normals,
            const double *slab_limit, const double *cos_limit, cl_clusters *out, sl_error *err);
void cl_clusters_release(cl_clusters *c);

/* Projection of a point into cluster k's frame: (u, v) and height n . (p - o). */
static inline void cl_project(const double *frame, const float *p, double uv[2], double *height)
{
    double d[3] = {(double)p[0] - frame[9], (double)p[1] - frame[10], (double)p[2] - frame[11]};
    uv[0] = d[0] * frame[3] + d[1] * frame[4] + d[2] * frame[5];
    uv[1] = d[0] * frame[6] + d[1] * frame[7] + d[2] * frame[8];
    if (height)
        *height = d[0] * frame[0] + d[1] * frame[1] + d[2] * frame[2];
}

/* The height n . (p - o) alone. */
static inline double cl_height(const double *frame, const float *p)
{
    return ((double)p[0] - frame[9]) * frame[0] + ((double)p[1] - frame[10]) * frame[1] +
           ((double)p[2] - frame[11]) * frame[2];
}

enum cl_border_flags {
    CL_BORDER_CLOSED = 1u << 0,   /* starts and ends at the same vertex (one or no corner) */
    CL_BORDER_FROZEN = 1u << 1,   /* never straightened (a kept cluster's, an input edge) */
    CL_BORDER_REVERTED = 1u << 2  /* straightening undone: every vertex kept */
};

/* The borders of one pass: maximal runs of boundary half-edges of a cluster between
 * corner vertices, each stored once (as its lower cluster traced it), and every cluster
 * loop as a cycle of borders. */
typedef struct cl_borders {
    uint32_t count;
    uint32_t *start;         /* count + 1: border b's vertices are verts[start[b]..start[b+1]) */
    uint32_t *verts;         /* in order, first and last the corners (equal when closed) */
    uint32_t *left, *right;  /* the clusters on each side (right CL_NONE: mesh boundary) */
    uint8_t *flags;          /* enum cl_border_flags */
    uint8_t *keep;           /* per entry of verts: kept by the straightening */
    double *tolerance;       /* per border: straightening tolerance, world */
    double *deviation;       /* per border: largest distance of a removed vertex to its
                                segment (0 when nothing was removed) */
    /* Loops: cluster k's loops are [cluster_loop[k], cluster_loop[k + 1]); loop l is the
     * cycle of pieces[loop_piece[l] .. loop_piece[l + 1]), each (border << 1 | reversed). */
    uint32_t loop_count;
    uint32_t *cluster_loop;
    uint32_t *loop_piece;
    uint32_t *pieces;
    uint64_t corners;
} cl_borders;

/* The borders of clusters `c` over `loops` (sl_segment_loops_build of the clusters):
 * corners are vertices on three or more clusters, on one cluster twice, on a mesh boundary
 * where two clusters meet, on a cut edge or non-manifold; a loop without a corner is
 * anchored at its lowest vertex. */
int cl_borders_build(const sl_mesh_adjacency *adj, const sl_segment_loops *loops,
                     const cl_clusters *c, cl_borders *out, sl_error *err);
void cl_borders_release(cl_borders *b);

/* Douglas-Peucker on every border that is neither frozen nor reverted, with its own
 * tolerance; then splits segments so every loop keeps three vertices and no two borders
 * share a segment. Returns the number of forced splits. */
uint64_t cl_borders_straighten(cl_borders *b, const float *positions);
/* Splits the segment of border `b` around entry `i` (an index into verts) at its farthest
 * removed vertex; 0 when it has none (the segment is an input edge). */
int cl_border_split(cl_borders *b, const float *positions, uint32_t border, uint32_t entry);
/* Recomputes border `b`'s deviation from its keep flags. */
void cl_border_deviation(cl_borders *b, const float *positions, uint32_t border);

/* Distance from p to the segment [a, b] in 3D; *closest (may be NULL) the nearest point. */
double cl_segment_distance(const double p[3], const double a[3], const double b[3],
                           double closest[3]);

/* Triangles of every cluster, in the shared vertex indices. */
typedef struct cl_triangulation {
    uint32_t *count;         /* per cluster */
    uint32_t **tri;          /* per cluster: 3 * count vertex indices (malloc'd, may be NULL) */
} cl_triangulation;

int cl_triangulation_init(cl_triangulation *t, uint32_t clusters);
void cl_triangulation_release(cl_triangulation *t, uint32_t clusters);

/* Triangulates the polygons of the clusters with dirty[k] = 1 (in parallel): each loop is
 * the vertices its borders keep (`keep`, one flag per border entry), at `positions` (the
 * input's, or an intermediate's with moved border vertices), projected into the cluster's
 * frame. A polygon the triangulation refuses, or that it could only triangulate by
 * splitting a loop edge or merging points, sets failed[k] = 1 and keeps tri[k] as it was.
 * Returns 0 or SL_E_NOMEM / SL_E_INTERNAL. */
int cl_triangulate(const cl_clusters *c, const cl_borders *b, const float *positions,
                   const uint8_t *keep, const uint8_t *dirty, uint8_t *failed,
                   cl_triangulation *t, sl_error *err, uint64_t vertex_count);
/* The borders of cluster k's polygon (as cl_triangulate builds it) whose segments cross,
 * touch or overlap another of its segments, each once, into out (room for every border;
 * marked: zero per border, used and left zero). Returns how many (0: none, or the polygon
 * is too large to scan), or -1 out of memory. */
int cl_polygon_crossings(const cl_clusters *c, const cl_borders *b, const float *positions,
                         const uint8_t *keep, uint32_t k, uint8_t *marked, uint32_t *out);
/* Cluster k's input triangles as its triangulation (a kept cluster); -1 out of memory. */
int cl_keep_input(const cl_clusters *c, const uint32_t *triangles, uint32_t k,
                  cl_triangulation *t);

/* One pass over a mesh whose triangles index the shared vertex array. */
typedef struct cl_pass_input {
    uint64_t vertex_count;
    const float *positions;
    uint32_t triangle_count;
    const uint32_t *triangles;
    double tolerance;        /* eps, world */
    double margin;           /* added to the bound: float rounding of coordinates */
    double base_bound;       /* the bound of the pass's input (intermediates add to it) */
    uint32_t intermediates;  /* m (this pass makes them) */
    const sl_cluster_config *cfg;
} cl_pass_input;

typedef struct cl_pass_output {
    uint32_t triangle_count;
    uint32_t *triangles;     /* into the shared vertex array */
    sl_cluster_pass_stats stats;
    uint32_t intermediate_count;
    sl_cluster_intermediate *intermediates;
} cl_pass_output;

int cl_pass_run(const cl_pass_input *in, cl_pass_output *out, sl_progress *progress,
                sl_error *err);
void cl_pass_output_release(cl_pass_output *out);

/* The m intermediate models of a pass whose borders and triangulation are final. */
typedef struct cl_morph_input {
    const cl_clusters *clusters;
    const cl_borders *borders;
    const float *positions;
    uint64_t vertex_count;
    const cl_triangulation *destination; /* kept clusters are copied from it */
    uint32_t m;
    double base_bound, margin;
} cl_morph_input;

int cl_morph(const cl_morph_input *in, sl_cluster_intermediate *out, sl_progress *progress,
             sl_error *err);
void cl_intermediate_release(sl_cluster_intermediate *m);

#endif
