/* A pass's bricks simplified in parallel, the count shared out by error, and the bricks
 * joined (qem_bricks_internal.h). */
#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "geometry/qem_bricks_internal.h"
#include "geometry/qem_internal.h"

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
uint64_t qem_count_within(const brick_result *r, double e)
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
void qem_share_by_error(brick_result *r, uint64_t bricks, uint64_t target)
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
            total += qem_count_within(&r[b], mid);
        if (total <= target)
            hi = mid;
        else
            lo = mid;
    }
    /* The running maximum has plateaus, so hi can overshoot: the bricks in order are given
     * back triangles towards their counts at lo until the target is met. */
    uint64_t total = 0;
    for (uint64_t b = 0; b < bricks; b++)
        total += r[b].want = qem_count_within(&r[b], hi);
    for (uint64_t b = 0; b < bricks && total < target; b++) {
        uint64_t more = qem_count_within(&r[b], lo) - r[b].want;
        more = more < target - total ? more : target - total;
        r[b].want += more;
        total += more;
    }
}

/* The error at which the bricks together come to `target`, judged from the curves of
 * every `stride`-th brick (their counts scaled to all): what the others stop at. */
double qem_sampled_error(const brick_result *r, uint64_t bricks, uint64_t stride,
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
            total += (double)qem_count_within(&r[b], mid);
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
int qem_stitch_bricks(const sl_qem_mesh *m, const uint8_t *active, brick_result *r, uint64_t bricks,
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

/* Runs each brick's task in parallel (round 0 or 1, for the progress); 0, or the first
 * error in brick order (an interrupt reported as the progress asks). */
int qem_run_bricks(const sl_qem_mesh *m, const brick_cut *cut, const uint8_t *locked,
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

