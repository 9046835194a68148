/* Internals of the morph refinement (morph_refine.h), the floor its files stand on: the
 * state its rounds share and the helpers on it (morph_refine_core.c), and the steps
 * above them: the sharing tests (morph_refine_flat.c), the splits (morph_refine_step.c),
 * retargeting and tears (morph_refine_tear.c); morph_refine.c runs the rounds. */
#ifndef SCANLOD_GEOMETRY_MORPH_REFINE_CORE_H
#define SCANLOD_GEOMETRY_MORPH_REFINE_CORE_H

#include <stdint.h>

#include "geometry/morph_refine.h"
#include "geometry/triangle_bvh.h"

#define NONE UINT32_MAX
#define MEMBERS_MAX 128 /* coarser triangles a target is tested against (< 256) */

typedef struct refine {
    const sl_mesh *c, *level;
    sl_triangle_bvh bvh;
    uint32_t *ring_start, *ring; /* coarser vertex -> its triangles */
    double eps2;                 /* "lies in": squared distance bound, world^2 */
    double travel2;              /* the farthest a new or retargeted vertex may travel
                                    between weights 0 and 1, squared (world^2) */
    int tear;                    /* SL_MORPH_REFINE_TEAR: tear what no split mends */
    int stale_rounds;            /* edge rounds in a row without a new fewest failing */
    sl_morph_refined *r;
    uint32_t *hint;              /* per vertex: a coarser triangle its target lies in */
    /* Per vertex, the coarser triangles its target lies in (mr_members), computed once
     * when the vertex is made (target and hint never change): members_at[v] >> 8 is its
     * first entry in members_pool, & 0xff how many. */
    uint64_t *members_at;
    uint32_t *members_pool;
    uint64_t members_n, members_cap;
    int failed;                  /* a vertex's members did not fit in memory */
    uint64_t vcap, tcap;
    double *dist;                /* path search, per coarser vertex: length, */
    uint32_t *prev, *stamp;      /* previous vertex, search it belongs to */
    uint32_t stamp_now;
    uint32_t *heap_v;
    double *heap_k;
    uint64_t heap_n, heap_cap;
} refine;

static inline void mr_corner(const sl_mesh *m, uint32_t t, int k, double out[3])
{
    const float *p = m->positions + 3 * (uint64_t)m->triangles[3 * (uint64_t)t + k];
    out[0] = p[0], out[1] = p[1], out[2] = p[2];
}

static inline void mr_target_of(const refine *R, uint32_t v, double out[3])
{
    const float *t = R->r->targets + 3 * (uint64_t)v;
    out[0] = t[0], out[1] = t[1], out[2] = t[2];
}

/* Vertex v's weight-0 position (world). */
static inline void mr_position_of(const refine *R, uint32_t v, double out[3])
{
    const float *p = R->r->positions + 3 * (uint64_t)v;
    out[0] = p[0], out[1] = p[1], out[2] = p[2];
}

static inline int mr_lies_in(const refine *R, const double p[3], uint32_t g)
{
    double a[3], b[3], c[3], q[3];
    mr_corner(R->c, g, 0, a), mr_corner(R->c, g, 1, b), mr_corner(R->c, g, 2, c);
    return sl_closest_point_triangle(p, a, b, c, q) <= R->eps2;
}

/* The coarser triangles (around the corners of v's hint) v's target lies in, into out
 * (MEMBERS_MAX); returns how many. */
static inline int mr_members(const refine *R, uint32_t v, uint32_t *out)
{
    uint64_t at = R->members_at[v];
    int n = (int)(at & 0xff);
    for (int i = 0; i < n; i++)
        out[i] = R->members_pool[(at >> 8) + i];
    return n;
}
/* Whether the targets of u and w lie in one coarser triangle (and of x too, x != NONE),
 * or in a flat pair of them (mr_flat_share); mr_share_one: in one coarser triangle only
 * (morph_refine_flat.c). */
int mr_share(const refine *R, uint32_t u, uint32_t w, uint32_t x);
int mr_share_one(const refine *R, uint32_t u, uint32_t w, uint32_t x);
/* Whether points p[0..count) (count 2 or 3; targets, the first in members[]) lie in a
 * pair of coplanar coarser triangles sharing an edge, one of them in members, with every
 * chord between the two crossing that edge: then the segment or triangle they span lies
 * on the coarser surface (morph_refine_flat.c). */
int mr_flat_share(const refine *R, const double (*p)[3], int count, const uint32_t *members,
                  int member_count);
/* morph_refine_core.c: adds the vertex sum_k f[k] * (vertex v[k]) with target t in
 * coarser triangle `hint` (room reserved by the caller); returns its index. */
uint32_t mr_add_vertex(refine *R, int count, const uint32_t *v, const double *f,
                       const double t[3], uint32_t hint);
/* Also morph_refine_core.c: the members (out: MEMBERS_MAX) of target p near coarser
 * triangle h; keeping them as v's for mr_members (0, or -1 out of memory); room for the
 * counts given; the out-of-memory error; a uint64_t comparator. */
int mr_members_of(const refine *R, const double p[3], uint32_t h, uint32_t *out);
int mr_members_keep(refine *R, uint32_t v, const uint32_t *m, int n);
int mr_reserve(refine *R, uint64_t vertices, uint64_t triangles, sl_error *err);
int mr_nomem(sl_error *err);
int mr_cmp_u64(const void *a, const void *b);
/* Each vertex's triangles: vertex v's are (*ring)[(*start)[v] .. (*start)[v + 1]), in
 * triangle order (OUT: both arrays, freed by the caller, also on failure). 0, or -1 out
 * of memory. */
int mr_vertex_rings(const uint32_t *triangles, uint64_t triangle_count, uint64_t vertex_count,
                    uint32_t **start, uint32_t **ring);
/* The coarser triangle holding the most of the targets of triangle v[0..2] (the first
 * such), *held a bit per corner whose target it holds (morph_refine_tear.c). */
uint32_t mr_best_face(const refine *R, const uint32_t *v, int *held);
/* Retargeting (morph_refine.h, step 3): a corner of a failing triangle whose target is
 * not in mr_best_face's triangle takes its closest point there, for every triangle
 * around it, when fewer of them then fail; in passes over the triangles (at most
 * MR_RETARGET_PASSES) until none moves. Updates max_move. 0 or SL_E_NOMEM. */
#define MR_RETARGET_PASSES 8
int mr_retarget(refine *R, sl_error *err);
/* Tears (step 4): what still fails gets copies of its corners (morph_refine.h). */
int mr_tear(refine *R, sl_error *err);
/* The vertex splitting failing edge (u, w), or NONE (morph_refine_step.c). */
uint32_t mr_split_edge(refine *R, uint32_t u, uint32_t w);
/* A vertex inside triangle (a, b, c) targeting the coarser vertex it spans, or NONE. */
uint32_t mr_split_triangle(refine *R, uint32_t a, uint32_t b, uint32_t c);

#endif
