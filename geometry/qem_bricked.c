/* Quadric edge collapse by bricks (qem_simplify.h; docs/simplify.md "By bricks").
 *
 * Why: the simplifier holds about 180 bytes per input triangle and runs one greedy queue on
 * one thread; the refine stage's first collapse takes the whole scan (20 M triangles: 4 GB).
 * Here the mesh is cut into bricks of at most `brick_triangles` triangles, consecutive in
 * the Morton order of their centroids; each brick is simplified alone with the points it
 * shares with another brick (and the ring around them) locked, so the bricks stitch back
 * without a crack whatever each did, and the bricks run in parallel. Their counts follow one error, as one greedy
 * queue over the whole would: a sample of the bricks records its error curves, and every
 * brick stops at the error that brings the sample to the count. The locked borders stay
 * at full density; the next passes take them down on strips around them, cut into bricks
 * elsewhere; once the mesh fits one brick the last pass is the whole simplifier.
 *
 * Determinism: bricks, the sample, the error and the stitching depend on the mesh alone;
 * each brick's simplifier is deterministic; results are joined in brick order. The output
 * bytes do not depend on the thread count. */
#include <assert.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "geometry/key_table.h"
#include "geometry/mesh.h"
#include "geometry/mesh_distance.h"
#include "geometry/qem_internal.h"

#define BRICK_MAX_PASSES 24   /* a pass that cannot reach its target leaves the rest to
                                 the next; this many and the count is out of reach */
#define BRICK_FIRST_DEPTH 4   /* in the first pass a brick's first run goes to this
                                 fraction of its share of the pass's count, and no further
                                 than twice its share's collapses: how far below its share
                                 the sharing by error may put it. Later passes (what the
                                 borders kept) run to the share: one run, not two */
#define MORTON_BITS 20        /* per axis, before the shift */
#define STRIP_RINGS 6         /* a later pass works on the triangles at least this many
                                 rings around the last pass's brick borders (its excess) */
#define STRIP_ROOM 8          /* ... and at least this many times the excess */
#define BRICK_SAMPLE 4        /* the first pass prices every this-many-th brick (a curve
                                 run) and stops the others at the error the sample gives */
#define BRICK_SAMPLE_MARGIN 200 /* ... aiming 1/this of the triangles above the count, for
                                   the strips to take (the sample misjudges by less) */

/* The Morton interleave of three 21-bit coordinates (runtime/octree.h's sl_morton3 has 20
 * bits, one short of the shifted grid, and lives above geometry/). */
static uint64_t spread3(uint64_t x)
{
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

/* One pass's bricks: triangle indices in brick order, brick b = order[first[b] ..
 * first[b + 1]). */
typedef struct brick_cut {
    uint32_t *order;
    uint64_t *first;
    uint64_t count;
} brick_cut;

static void brick_cut_release(brick_cut *c)
{
    free(c->order);
    free(c->first);
    memset(c, 0, sizeof *c);
}

/* Bricks of at most `brick_triangles`, consecutive in the Morton order of the centroids
 * on a grid shifted by `shift` (a fraction of the cell of the octree level where cells
 * are about as many as bricks). */
static int cut_bricks(const sl_qem_mesh *m, const uint8_t *active, uint64_t brick_triangles,
                      double shift, brick_cut *out)
{
    memset(out, 0, sizeof *out);
    uint64_t n = 0; /* the active triangles */
    for (uint64_t t = 0; t < m->triangle_count; t++)
        n += !active || active[t];
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++) /* the whole's box */
        for (int a = 0; a < 3; a++) {
            double x = m->positions[3 * (uint64_t)m->triangles[i] + a];
            lo[a] = fmin(lo[a], x);
            hi[a] = fmax(hi[a], x);
        }
    double extent = 0;
    for (int a = 0; a < 3; a++)
        extent = fmax(extent, hi[a] - lo[a]);
    uint64_t bricks = n ? (n + brick_triangles - 1) / brick_triangles : 0;
    int level = 0; /* 8^level cells at least as many as the bricks */
    while (level < MORTON_BITS && (uint64_t)1 << (3 * level) < bricks)
        level++;
    double grid = (double)((uint64_t)1 << MORTON_BITS);
    double offset = shift * (double)((uint64_t)1 << (MORTON_BITS - level));
    double scale = extent > 0 ? (grid - 1) / extent : 0;
    sl_key_pair *pairs = malloc((n ? n : 1) * sizeof *pairs);
    out->order = malloc((n ? n : 1) * sizeof *out->order);
    out->first = malloc((bricks + 1) * sizeof *out->first);
    if (!pairs || !out->order || !out->first) {
        free(pairs);
        brick_cut_release(out);
        return -1;
    }
    uint64_t *which = active ? malloc((n ? n : 1) * sizeof *which) : NULL;
    if (active && !which) {
        free(pairs);
        brick_cut_release(out);
        return -1;
    }
    for (uint64_t t = 0, i = 0; active && t < m->triangle_count; t++)
        if (active[t])
            which[i++] = t;
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < n; i++) {
        uint64_t t = which ? which[i] : i, q[3];
        for (int a = 0; a < 3; a++) {
            double c = 0;
            for (int k = 0; k < 3; k++)
                c += m->positions[3 * (uint64_t)m->triangles[3 * t + k] + a];
            double g = (c / 3 - lo[a]) * scale + offset;
            q[a] = g > 0 ? (uint64_t)fmin(g, 2 * grid - 1) : 0; /* NaN: 0 */
        }
        pairs[i].key = spread3(q[0]) | spread3(q[1]) << 1 | spread3(q[2]) << 2;
        pairs[i].value = t;
    }
    free(which);
    if (sl_sort_pairs(pairs, n, 3 * (MORTON_BITS + 1)) != 0) {
        free(pairs);
        brick_cut_release(out);
        return -1;
    }
    for (uint64_t t = 0; t < n; t++)
        out->order[t] = (uint32_t)pairs[t].value;
    free(pairs);
    out->count = bricks;
    for (uint64_t b = 0; b <= bricks; b++) /* equal shares */
        out->first[b] = bricks ? n * b / bricks : 0; /* (no active triangle: none) */
    return 0;
}

/* What locks a vertex in a pass (bits of shared_points' array). */
enum {
    LOCK_CALLER = 1,  /* the caller's */
    LOCK_BORDER = 2,  /* its position is used by triangles of two bricks */
    LOCK_OUTSIDE = 4, /* ... by a brick's and a triangle the pass leaves alone */
    LOCK_RING = 8     /* shares a triangle with such a point (below) */
};

/* Per vertex, the LOCK_ bits; *border_triangles: the active triangles with a corner on a
 * border. NULL when out of memory. */
static uint8_t *shared_points(const sl_qem_mesh *m, const brick_cut *cut, const uint8_t *active,
                              const uint8_t *locked, uint64_t *border_triangles)
{
    uint64_t nv = m->vertex_count;
    uint32_t *point = malloc((nv ? nv : 1) * sizeof *point);
    uint8_t *out = calloc(nv ? nv : 1, 1);
    uint32_t *owner = NULL;
    uint8_t *outside = NULL;
    if (!point || !out)
        goto fail;
    sl_mesh view = sl_mesh_view(nv, m->positions, NULL, NULL, m->triangle_count, m->triangles);
    int64_t points = sl_mesh_weld_positions(&view, point);
    if (points < 0)
        goto fail;
    uint64_t np = (uint64_t)points ? (uint64_t)points : 1;
    owner = malloc(np * sizeof *owner); /* the brick that first used point p, or SHARED */
    outside = calloc(np, 1);            /* a triangle the pass leaves alone uses it */
    if (!owner || !outside)
        goto fail;
    const uint32_t unseen = UINT32_MAX, shared = UINT32_MAX - 1;
    memset(owner, 0xff, np * sizeof *owner);
    for (uint64_t t = 0; active && t < m->triangle_count; t++)
        if (!active[t])
            for (int k = 0; k < 3; k++)
                outside[point[m->triangles[3 * t + k]]] = 1;
    for (uint64_t b = 0; b < cut->count; b++)
        for (uint64_t i = cut->first[b]; i < cut->first[b + 1]; i++)
            for (int k = 0; k < 3; k++) {
                uint32_t p = point[m->triangles[3 * (uint64_t)cut->order[i] + k]];
                if (owner[p] == unseen)
                    owner[p] = (uint32_t)b;
                else if (owner[p] != (uint32_t)b)
                    owner[p] = shared;
            }
    for (uint64_t v = 0; v < nv; v++) {
        uint32_t p = point[v];
        if (p != UINT32_MAX && owner[p] != unseen)
            out[v] = (uint8_t)((owner[p] == shared ? LOCK_BORDER : 0) |
                               (outside[p] ? LOCK_OUTSIDE : 0));
        if (locked && locked[v])
            out[v] |= LOCK_CALLER;
    }
    /* The ring around them locked too. Why: a brick sees only its own triangles, so its
     * link condition cannot see an edge between two border points that lies in another
     * brick, and a collapse of a point next to both could give that edge a third triangle
     * (eight spheres, test_qem_bricked). With the ring locked nothing collapses into a
     * border point: their stars do not change in any brick. The next pass's strips take
     * the ring down with the borders. */
    for (uint64_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *c = m->triangles + 3 * t;
        if ((out[c[0]] | out[c[1]] | out[c[2]]) & (LOCK_BORDER | LOCK_OUTSIDE))
            for (int k = 0; k < 3; k++)
                out[c[k]] |= LOCK_RING;
    }
    *border_triangles = 0;
    for (uint64_t t = 0; t < m->triangle_count; t++)
        if (!active || active[t])
            *border_triangles += ((out[m->triangles[3 * t]] | out[m->triangles[3 * t + 1]] |
                                   out[m->triangles[3 * t + 2]]) & (LOCK_BORDER | LOCK_RING)) != 0;
    free(owner);
    free(outside);
    free(point);
    return out;
fail:
    free(owner);
    free(outside);
    free(point);
    free(out);
    return NULL;
}

/* One brick's part in a pass: its error curve and how far its first run went, its count,
 * its simplified mesh with `source` naming the pass input's vertices, its figures, and its
 * error. */
enum brick_task {
    TASK_NONE = 0,       /* nothing (this round) */
    TASK_CURVE,          /* a run to `want` recording its error curve */
    TASK_FINAL           /* the run to `want`, or to `max_error` first when that is set */
};

typedef struct brick_result {
    int task;            /* enum brick_task, this round */
    uint64_t want;       /* the count the run stops at */
    double max_error;    /* ... or the error it stops before (0: none) */
    float *curve;        /* the curve run's error_curve, triangles + 1 entries */
    uint64_t triangles;  /* the brick's */
    uint64_t share;      /* its share of the pass's count, in proportion to its triangles */
    uint64_t reached;    /* the curve run's count */
    sl_qem_mesh mesh;
    sl_qem_stats stats;
    int rc;
    sl_error err;
} brick_result;

/* A brick gathered into a mesh of its own, with its locks and each vertex's index in the
 * pass input. */
typedef struct brick_mesh {
    sl_qem_mesh mesh;
    uint8_t *lock;
    uint32_t *verts;
} brick_mesh;

static void brick_mesh_release(brick_mesh *g)
{
    free(g->mesh.positions);
    free(g->mesh.colors);
    free(g->mesh.texcoords);
    free(g->mesh.triangles);
    free(g->lock);
    free(g->verts);
    memset(g, 0, sizeof *g);
}

/* `map`: per pass input vertex, UINT32_MAX (this thread's; left so again). */
static int gather_brick(const sl_qem_mesh *m, const brick_cut *cut, uint64_t b,
                        const uint8_t *locked, uint32_t *map, brick_mesh *g)
{
    memset(g, 0, sizeof *g);
    uint64_t t0 = cut->first[b], nt = cut->first[b + 1] - t0;
    uint32_t *verts = g->verts = malloc((3 * nt + 1) * sizeof *verts);
    uint32_t *tris = g->mesh.triangles = malloc((3 * nt + 1) * sizeof *tris);
    if (!verts || !tris)
        return -1;
    uint64_t nv = 0; /* vertices in the order the brick's triangles first use them */
    for (uint64_t i = 0; i < nt; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = m->triangles[3 * (uint64_t)cut->order[t0 + i] + k];
            if (map[v] == UINT32_MAX) {
                map[v] = (uint32_t)nv;
                verts[nv++] = v;
            }
            tris[3 * i + k] = map[v];
        }
    for (uint64_t i = 0; i < nv; i++)
        map[verts[i]] = UINT32_MAX;
    sl_qem_mesh *in = &g->mesh;
    in->vertex_count = nv;
    in->triangle_count = nt;
    in->positions = malloc((3 * nv + 1) * sizeof *in->positions);
    in->colors = m->colors ? malloc(4 * nv + 1) : NULL;
    in->texcoords = m->texcoords ? malloc((2 * nv + 1) * sizeof *in->texcoords) : NULL;
    g->lock = malloc(nv + 1);
    if (!in->positions || (m->colors && !in->colors) || (m->texcoords && !in->texcoords) ||
        !g->lock)
        return -1;
    for (uint64_t i = 0; i < nv; i++) {
        uint64_t v = verts[i];
        memcpy(in->positions + 3 * i, m->positions + 3 * v, 3 * sizeof *in->positions);
        if (in->colors)
            memcpy(in->colors + 4 * i, m->colors + 4 * v, 4);
        if (in->texcoords)
            memcpy(in->texcoords + 2 * i, m->texcoords + 2 * v, 2 * sizeof *in->texcoords);
        g->lock[i] = locked[v] != 0;
    }
    return 0;
}

/* Brick b simplified as r->task asks. Its mesh's `source` names the pass input's
 * vertices. */
static void simplify_brick(const sl_qem_mesh *m, const brick_cut *cut, uint64_t b,
                           const uint8_t *locked, uint32_t *map, const sl_qem_config *cfg,
                           brick_result *r)
{
    brick_mesh g;
    sl_error_init(&r->err);
    r->triangles = cut->first[b + 1] - cut->first[b];
    if (gather_brick(m, cut, b, locked, map, &g) != 0) {
        brick_mesh_release(&g);
        r->rc = sl_error_set(&r->err, SL_E_NOMEM, 0, NULL, "simplify: brick of %llu triangles",
                             (unsigned long long)r->triangles);
        return;
    }
    sl_qem_config c = *cfg;
    c.target_triangles = r->want;
    c.max_error = cfg->max_error; /* the pass's error, within the caller's */
    if (r->task == TASK_FINAL && r->max_error > 0)
        c.max_error = cfg->max_error > 0 ? fmin(cfg->max_error, r->max_error) : r->max_error;
    c.locked = g.lock;
    c.error_curve = NULL;
    if (r->task == TASK_CURVE) {
        r->curve = malloc((r->triangles + 1) * sizeof *r->curve);
        c.error_curve = r->curve;
        if (!r->curve) {
            brick_mesh_release(&g);
            r->rc = sl_error_set(&r->err, SL_E_NOMEM, 0, NULL, "simplify: error curve");
            return;
        }
    }
    sl_qem_mesh_release(&r->mesh);
    r->rc = sl_qem_simplify(&g.mesh, &c, &r->mesh, &r->stats, NULL, &r->err);
    if (r->rc == 0)
        for (uint64_t i = 0; i < r->mesh.vertex_count; i++)
            r->mesh.source[i] = g.verts[r->mesh.source[i]];
    if (c.error_curve)
        r->reached = r->rc == 0 ? r->mesh.triangle_count : r->triangles;
    brick_mesh_release(&g);
}

/* The fewest triangles brick r has after collapses of error at most e (its curve). */
static uint64_t count_within(const brick_result *r, double e)
{
    uint64_t lo = r->reached, hi = r->triangles; /* curve[hi] = 0 <= e */
    while (lo < hi) {
        uint64_t mid = lo + (hi - lo) / 2;
        if (r->curve[mid] <= e)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* Each brick's count: the bricks' collapses taken in one order of error, as one greedy
 * queue over the whole would take them, up to the pass's target (locked borders aside):
 * the least error e at which the bricks together are within `target`, each brick then
 * where its curve is within e. A brick its first run took no lower stays there. */
static void share_by_error(brick_result *r, uint64_t bricks, uint64_t target)
{
    double hi = 0;
    uint64_t deepest = 0;
    for (uint64_t b = 0; b < bricks; b++) {
        deepest += r[b].reached;
        if (r[b].reached < r[b].triangles)
            hi = fmax(hi, r[b].curve[r[b].reached]);
    }
    if (deepest >= target) { /* out of reach this pass: as deep as each went */
        for (uint64_t b = 0; b < bricks; b++)
            r[b].want = r[b].reached;
        return;
    }
    double lo = 0; /* the bricks above the target at lo, within it at hi */
    for (int i = 0; i < 64 && lo < hi; i++) {
        double mid = lo + (hi - lo) / 2;
        uint64_t total = 0;
        for (uint64_t b = 0; b < bricks; b++)
            total += count_within(&r[b], mid);
        if (total <= target)
            hi = mid;
        else
            lo = mid;
    }
    /* The running maximum has plateaus, so hi can overshoot: the bricks in order are given
     * back triangles towards their counts at lo until the target is met. */
    uint64_t total = 0;
    for (uint64_t b = 0; b < bricks; b++)
        total += r[b].want = count_within(&r[b], hi);
    for (uint64_t b = 0; b < bricks && total < target; b++) {
        uint64_t more = count_within(&r[b], lo) - r[b].want;
        more = more < target - total ? more : target - total;
        r[b].want += more;
        total += more;
    }
}

/* The error at which the bricks together come to `target`, judged from the curves of
 * every `stride`-th brick (their counts scaled to all): what the others stop at. */
static double sampled_error(const brick_result *r, uint64_t bricks, uint64_t stride,
                            uint64_t target)
{
    uint64_t sampled = 0, all = 0;
    double hi = 0;
    for (uint64_t b = 0; b < bricks; b++) {
        all += r[b].triangles;
        if (b % stride == 0) {
            sampled += r[b].triangles;
            if (r[b].reached < r[b].triangles)
                hi = fmax(hi, r[b].curve[r[b].reached]);
        }
    }
    double scale = sampled ? (double)all / (double)sampled : 1, lo = 0;
    for (int i = 0; i < 64 && lo < hi; i++) {
        double mid = lo + (hi - lo) / 2, total = 0;
        for (uint64_t b = 0; b < bricks; b += stride)
            total += (double)count_within(&r[b], mid);
        if (total * scale <= (double)target)
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

/* The bricks' meshes joined: a vertex per pass input vertex some brick kept (the shared
 * ones, locked, kept alike by each brick that has them), in the input's order; triangles
 * brick by brick. `source` names the pass input's vertices. */
static int stitch(const sl_qem_mesh *m, const uint8_t *active, brick_result *r, uint64_t bricks,
                  sl_qem_mesh *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t *index = malloc((m->vertex_count + 1) * sizeof *index);
    if (!index)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: joining the bricks");
    memset(index, 0xff, m->vertex_count * sizeof *index);
    uint64_t nt = 0;
    for (uint64_t b = 0; b < bricks; b++) {
        for (uint64_t i = 0; i < r[b].mesh.vertex_count; i++)
            index[r[b].mesh.source[i]] = 0;
        nt += r[b].mesh.triangle_count;
    }
    for (uint64_t t = 0; active && t < m->triangle_count; t++) /* left alone: as they were */
        if (!active[t]) {
            for (int k = 0; k < 3; k++)
                index[m->triangles[3 * t + k]] = 0;
            nt++;
        }
    uint64_t nv = 0;
    for (uint64_t v = 0; v < m->vertex_count; v++)
        if (index[v] != QEM_NONE)
            index[v] = (uint32_t)nv++;
    out->positions = malloc((3 * nv + 1) * sizeof *out->positions);
    out->source = malloc((nv + 1) * sizeof *out->source);
    out->triangles = malloc((3 * nt + 1) * sizeof *out->triangles);
    out->colors = m->colors ? malloc(4 * nv + 1) : NULL;
    out->texcoords = m->texcoords ? malloc((2 * nv + 1) * sizeof *out->texcoords) : NULL;
    if (!out->positions || !out->source || !out->triangles || (m->colors && !out->colors) ||
        (m->texcoords && !out->texcoords)) {
        free(index);
        sl_qem_mesh_release(out);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: joining %llu triangles",
                            (unsigned long long)nt);
    }
    out->vertex_count = nv;
    out->triangle_count = nt;
    uint64_t k = 0;
    for (uint64_t t = 0; active && t < m->triangle_count; t++)
        if (!active[t])
            for (int c = 0; c < 3; c++) {
                uint32_t v = m->triangles[3 * t + c];
                uint64_t o = index[v];
                memcpy(out->positions + 3 * o, m->positions + 3 * (uint64_t)v,
                       3 * sizeof *out->positions);
                if (out->colors)
                    memcpy(out->colors + 4 * o, m->colors + 4 * (uint64_t)v, 4);
                if (out->texcoords)
                    memcpy(out->texcoords + 2 * o, m->texcoords + 2 * (uint64_t)v,
                           2 * sizeof *out->texcoords);
                out->source[o] = v;
                out->triangles[k++] = (uint32_t)o;
            }
    for (uint64_t b = 0; b < bricks; b++) {
        const sl_qem_mesh *bm = &r[b].mesh;
        for (uint64_t i = 0; i < bm->vertex_count; i++) {
            uint64_t o = index[bm->source[i]];
            memcpy(out->positions + 3 * o, bm->positions + 3 * i, 3 * sizeof *out->positions);
            if (out->colors)
                memcpy(out->colors + 4 * o, bm->colors + 4 * i, 4);
            if (out->texcoords)
                memcpy(out->texcoords + 2 * o, bm->texcoords + 2 * i, 2 * sizeof *out->texcoords);
            out->source[o] = bm->source[i];
        }
        for (uint64_t i = 0; i < 3 * bm->triangle_count; i++)
            out->triangles[k++] = index[bm->source[bm->triangles[i]]];
        sl_qem_mesh_release(&r[b].mesh);
    }
    assert(k == 3 * nt);
    free(index);
    return 0;
}

/* Adds a brick's or a pass's figures to the total. */
static void add_stats(sl_qem_stats *sum, const sl_qem_stats *s)
{
    sum->degenerate_triangles += s->degenerate_triangles;
    sum->points += s->points;
    sum->seam_points += s->seam_points;
    sum->border_points += s->border_points;
    sum->locked_points += s->locked_points;
    sum->nonmanifold_points += s->nonmanifold_points;
    sum->collapses += s->collapses;
    sum->relaxed_collapses += s->relaxed_collapses;
    sum->cancelled_triangles += s->cancelled_triangles;
    sum->queued += s->queued;
    sum->rejected_topology += s->rejected_topology;
    sum->rejected_flip += s->rejected_flip;
    sum->rejected_shape += s->rejected_shape;
    sum->last_error = fmax(sum->last_error, s->last_error);
    if (s->stop == SL_QEM_STOP_MAX_ERROR || sum->stop == SL_QEM_STOP_MAX_ERROR)
        sum->stop = SL_QEM_STOP_MAX_ERROR;
    else if (s->stop == SL_QEM_STOP_TOPOLOGY)
        sum->stop = SL_QEM_STOP_TOPOLOGY;
}

/* Runs each brick's task in parallel (round 0 or 1, for the progress); 0, or the first
 * error in brick order (an interrupt reported as the progress asks). */
static int run_bricks(const sl_qem_mesh *m, const brick_cut *cut, const uint8_t *locked,
                      const sl_qem_config *cfg, brick_result *r, int round,
                      sl_progress *progress, sl_error *err)
{
    uint64_t done = 0;
    int stop = 0, nomem = 0;
#pragma omp parallel
    {
        uint32_t *map = malloc((m->vertex_count + 1) * sizeof *map); /* gather_brick's */
        if (map)
            memset(map, 0xff, (m->vertex_count + 1) * sizeof *map);
#pragma omp for schedule(dynamic, 1)
        for (uint64_t b = 0; b < cut->count; b++) {
            int skip;
#pragma omp atomic read
            skip = stop;
            if (skip)
                continue;
            if (!map) {
#pragma omp atomic write
                nomem = 1;
                continue;
            }
            if (r[b].task != TASK_NONE)
                simplify_brick(m, cut, b, locked, map, cfg, &r[b]);
            uint64_t finished;
#pragma omp atomic capture
            finished = ++done;
            if (sl_progress_step(progress, "simplify",
                                 (round + (double)finished / (double)cut->count) / 2)) {
#pragma omp atomic write
                stop = 1;
            }
        }
        free(map);
    }
    if (nomem)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: brick vertex map");
    for (uint64_t b = 0; b < cut->count; b++) /* the first error in brick order */
        if (r[b].rc) {
            sl_error_merge(err, &r[b].err);
            return r[b].rc;
        }
    if (stop)
        return sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "simplify: interrupted");
    return 0;
}

/* One pass over the `active` triangles (NULL: all; the others are kept as they are): cut
 * into bricks; in the first pass (`deep`) each brick run once as deep as BRICK_FIRST_DEPTH
 * asks, recording its error curve, the counts shared out by error, and each run again to
 * its count (unless the first stopped there); in a later one each run once to its share;
 * the bricks joined. *border (when given): per vertex of `out`, 1 on a border between two
 * bricks, malloc'd. */
static int brick_pass(const sl_qem_mesh *m, const uint8_t *active, const sl_qem_config *cfg,
                      uint64_t brick_triangles, double shift, int deep, int exact,
                      uint64_t target,
                      sl_qem_mesh *out, uint8_t **border_out, sl_qem_stats *stats,
                      sl_progress *progress, sl_error *err)
{
    brick_cut cut;
    if (cut_bricks(m, active, brick_triangles, shift, &cut) != 0)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: cutting %llu triangles into "
                            "bricks", (unsigned long long)m->triangle_count);
    uint64_t border = 0, n = cut.count ? cut.first[cut.count] : 0;
    uint64_t alone = m->triangle_count - n; /* left as they are */
    uint8_t *locked = shared_points(m, &cut, active, cfg->locked, &border);
    brick_result *r = calloc(cut.count + 1, sizeof *r);
    if (!locked || !r) {
        free(locked);
        free(r);
        brick_cut_release(&cut);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: brick borders");
    }
    /* The bricks' part of the target; the locked borders keep their triangles this pass,
     * so the count it aims at leaves them what the target would have taken of them, for
     * the next pass (elsewhere) to take. */
    uint64_t part = target > alone ? target - alone : 0;
    double kept = n ? 1 - (double)part / (double)n : 0;
    uint64_t aim = part + (uint64_t)((double)border * kept);
    aim = aim < n ? aim : n;
    for (uint64_t b = 0; b < cut.count; b++) { /* the rounding of the running sum, so the
                                                   shares add up */
        r[b].triangles = cut.first[b + 1] - cut.first[b];
        r[b].share = (uint64_t)((double)aim * (double)cut.first[b + 1] / (double)n + 0.5) -
                     (uint64_t)((double)aim * (double)cut.first[b] / (double)n + 0.5);
    }
    /* How far a curve run goes: BRICK_FIRST_DEPTH below its share, no more than twice its
     * share's collapses. */
    uint64_t stride = exact ? 1 : BRICK_SAMPLE;
    deep = deep && aim < n; /* (nothing to take: each brick copied) */
    for (uint64_t b = 0; b < cut.count; b++) {
        uint64_t nb = r[b].triangles, share = r[b].share, floor = share / BRICK_FIRST_DEPTH;
        if (nb > 2 * (nb - share) && nb - 2 * (nb - share) > floor)
            floor = nb - 2 * (nb - share);
        r[b].task = !deep ? TASK_FINAL : b % stride == 0 ? TASK_CURVE : TASK_NONE;
        r[b].want = deep ? floor : share;
    }
    int rc = run_bricks(m, &cut, locked, cfg, r, 0, progress, err);
    if (rc == 0 && deep) {
        if (exact) { /* every brick's curve: the counts exactly */
            share_by_error(r, cut.count, aim);
        } else { /* the sample's error for all; a little above the aim, for the strips */
            double e = sampled_error(r, cut.count, stride, aim + n / BRICK_SAMPLE_MARGIN);
            for (uint64_t b = 0; b < cut.count; b++) {
                if (b % stride == 0) {
                    r[b].want = count_within(&r[b], e);
                } else {
                    r[b].max_error = e > 0 ? e : DBL_MIN; /* 0 would be no limit */
                }
            }
        }
        for (uint64_t b = 0; b < cut.count; b++) {
            r[b].task = r[b].curve && r[b].want == r[b].reached ? TASK_NONE : TASK_FINAL;
            free(r[b].curve); /* (its mesh is the count's when the task is none) */
            r[b].curve = NULL;
        }
        rc = run_bricks(m, &cut, locked, cfg, r, 1, progress, err);
    }
    for (uint64_t b = 0; b < cut.count && rc == 0; b++)
        add_stats(stats, &r[b].stats);
    if (rc == 0)
        rc = stitch(m, active, r, cut.count, out, err);
    if (rc == 0 && border_out) {
        *border_out = malloc(out->vertex_count + 1);
        if (!*border_out) {
            sl_qem_mesh_release(out);
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: brick borders");
        }
        for (uint64_t v = 0; rc == 0 && v < out->vertex_count; v++)
            (*border_out)[v] = (locked[out->source[v]] & (LOCK_BORDER | LOCK_RING)) != 0;
    }
    free(locked);
    for (uint64_t b = 0; b < cut.count; b++) {
        free(r[b].curve);
        sl_qem_mesh_release(&r[b].mesh);
    }
    free(r);
    brick_cut_release(&cut);
    return rc;
}

/* The triangles within some rings of the marked vertices (the last pass's borders, where
 * its excess is): at least STRIP_RINGS rings, and as many more as it takes to hold
 * STRIP_ROOM times `excess` triangles, so the excess is taken from a band, not a line.
 * What the next pass works on. NULL when out of memory; *count set. */
static uint8_t *strip_around(const sl_qem_mesh *m, const uint8_t *marked, uint64_t excess,
                             uint64_t *count)
{
    uint8_t *vert = malloc(m->vertex_count + 1), *tri = calloc(m->triangle_count + 1, 1);
    if (!vert || !tri) {
        free(vert);
        free(tri);
        return NULL;
    }
    memcpy(vert, marked, m->vertex_count);
    *count = 0;
    for (int ring = 0; ring < STRIP_RINGS || *count < STRIP_ROOM * excess; ring++) {
        uint64_t before = *count;
        for (uint64_t t = 0; t < m->triangle_count; t++)
            if (!tri[t] && (vert[m->triangles[3 * t]] | vert[m->triangles[3 * t + 1]] |
                            vert[m->triangles[3 * t + 2]])) {
                tri[t] = 1;
                ++*count;
            }
        if (*count == before || *count == m->triangle_count)
            break;
        for (uint64_t t = 0; t < m->triangle_count; t++)
            if (tri[t])
                for (int k = 0; k < 3; k++)
                    vert[m->triangles[3 * t + k]] = 1;
    }
    free(vert);
    return tri;
}

/* `source` of `next` made to name the original input's vertices through `prev`'s. */
static void compose_source(sl_qem_mesh *next, const uint32_t *prev_source)
{
    if (prev_source)
        for (uint64_t v = 0; v < next->vertex_count; v++)
            next->source[v] = prev_source[next->source[v]];
}

/* The caller's locks carried to a pass's mesh (its `source` names the input's vertices):
 * *out NULL when there are none. -1 when out of memory. */
static int carry_locks(const uint8_t *locked, const sl_qem_mesh *cur, uint8_t **out)
{
    *out = NULL;
    if (!locked || !cur->source)
        return 0;
    *out = malloc(cur->vertex_count + 1);
    if (!*out)
        return -1;
    for (uint64_t v = 0; v < cur->vertex_count; v++)
        (*out)[v] = locked[cur->source[v]];
    return 0;
}

int sl_qem_simplify_bricked(const sl_qem_mesh *in, const sl_qem_config *cfg,
                            uint64_t brick_triangles, sl_qem_mesh *out, sl_qem_stats *stats,
                            sl_progress *progress, sl_error *err)
{
    sl_qem_config defaults = sl_qem_default_config();
    if (!cfg)
        cfg = &defaults;
    if (brick_triangles == 0 || in->triangle_count <= brick_triangles)
        return sl_qem_simplify(in, cfg, out, stats, progress, err);
    memset(out, 0, sizeof *out);
    sl_qem_stats sum;
    memset(&sum, 0, sizeof sum);
    sum.input_triangles = in->triangle_count;
    int rc = qem_check_input(in, cfg, err);
    sl_qem_config c = *cfg;
    if (rc == 0 && c.diagonal == 0) { /* the whole's, so every brick prices alike */
        double lo[3] = {INFINITY, INFINITY, INFINITY};
        double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint64_t i = 0; i < 3 * in->triangle_count; i++)
            for (int a = 0; a < 3; a++) {
                double x = in->positions[3 * (uint64_t)in->triangles[i] + a];
                lo[a] = fmin(lo[a], x);
                hi[a] = fmax(hi[a], x);
            }
        for (int a = 0; a < 3; a++)
            c.diagonal += (hi[a] - lo[a]) * (hi[a] - lo[a]);
        c.diagonal = sqrt(c.diagonal);
    }
    uint64_t target = cfg->target_triangles;
    sl_qem_mesh cur = *in; /* borrowed until the first pass */
    cur.source = NULL;
    uint8_t *border = NULL; /* per vertex of cur: on the last pass's brick borders */
    int owned = 0, max_error = 0, whole = 0, full = 1;
    uint64_t brick = brick_triangles; /* doubled when a pass could take nothing (below) */
    for (int pass = 0; rc == 0; pass++) {
        int last = owned && cur.triangle_count <= brick;
        if (owned && (cur.triangle_count <= target || whole || pass == BRICK_MAX_PASSES))
            break;
        uint8_t *locks = NULL, *active = NULL;
        uint64_t strip = 0;
        if (carry_locks(cfg->locked, &cur, &locks) != 0 ||
            (!last && !full &&
             !(active = strip_around(&cur, border, cur.triangle_count - target, &strip)))) {
            free(locks);
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: locks");
            break;
        }
        c.locked = owned ? locks : cfg->locked;
        sl_qem_mesh next;
        sl_qem_stats s;
        memset(&s, 0, sizeof s);
        uint8_t *next_border = NULL;
        if (last) { /* the mesh fits one brick: the whole, nothing but the caller's locked */
            c.target_triangles = target;
            rc = sl_qem_simplify(&cur, &c, &next, &s, progress, err);
            whole = 1;
        } else { /* (a first pass at or below the target only copies, as the whole would) */
            /* the golden-ratio sequence: each pass's grid off the earlier ones' */
            double shift = fmod(pass * 0.6180339887498949, 1.0);
            /* after the first pass, aim up to half the 1 % the count allows below it: the
             * borders' last triangles sit beside locked ones, and an exact aim takes them
             * a few at a time, pass after pass */
            uint64_t aim = pass == 0 ? target : target - target / 200;
            rc = brick_pass(&cur, active, &c, brick, shift, pass == 0, 0, aim, &next,
                            &next_border, &s, progress, err);
            if (rc == 0 && pass == 0 && next.triangle_count < target - target / 100) {
                /* the sample misjudged the error below the count: every brick priced */
                sl_qem_mesh_release(&next);
                free(next_border);
                next_border = NULL;
                memset(&s, 0, sizeof s);
                rc = brick_pass(&cur, active, &c, brick, shift, 1, 1, target, &next,
                                &next_border, &s, progress, err);
            }
        }
        free(locks);
        free(active);
        if (rc)
            break;
        add_stats(&sum, &s);
        max_error |= cfg->max_error > 0 && s.stop == SL_QEM_STOP_MAX_ERROR; /* the caller's */
        /* The next pass on strips around these borders, unless this one (on strips) took
         * less than half of what was left to take: then on all of it; and when a pass on
         * all of it took nothing (bricks so small that their locked borders and rings are
         * most of them), on bricks twice as large, up to the whole. */
        uint64_t excess = cur.triangle_count > target ? cur.triangle_count - target : 0;
        uint64_t taken = cur.triangle_count - next.triangle_count;
        if (full && pass > 0 && 2 * taken < excess)
            brick = brick > UINT64_MAX / 2 ? UINT64_MAX : 2 * brick;
        full = !full && 2 * taken < excess;
        compose_source(&next, cur.source);
        if (owned)
            sl_qem_mesh_release(&cur);
        free(border);
        border = next_border;
        cur = next;
        owned = 1;
    }
    free(border);
    if (rc == 0) {
        *out = cur;
        sum.stop = cur.triangle_count <= target ? SL_QEM_STOP_TARGET
                   : max_error                  ? SL_QEM_STOP_MAX_ERROR
                                                : SL_QEM_STOP_TOPOLOGY;
        sum.output_triangles = out->triangle_count;
        sum.output_vertices = out->vertex_count;
    } else if (owned) {
        sl_qem_mesh_release(&cur);
    }
    if (stats)
        *stats = sum;
    return rc;
}
