/* samples stage: the signed sample at each grid vertex (paper 1 section 2.1).
 *
 *   p_n = the point closest to v_n        d_n = |v_n - p_n|  (or |(v_n - p_n) . n_p|)
 *   s_n = sign((v_n - p_n) . n_p)         sample = s_n * d_n  (> 0 outside, < 0 inside)
 *
 * The paper restricts p_n to the cube C; we take the closest point of the whole set, so
 * that a vertex shared by several cubes has one sample (docs/samples-stage.md, "Method") and the
 * band cubes, which hold no points, get samples too. Closest points are exact (k-d tree,
 * geometry/kdtree.h), ties to the lower point index. With sign_neighbours = k > 1 the sign
 * is instead a vote of the k nearest points, each weighted by 1 / (distance + leaf/16):
 * on noisy scans one point with a flipped normal then cannot flip a vertex alone.
 *
 * Meshes ([samples] closest = triangles, the default) take p from the triangles instead:
 * samples_surface.c.
 *
 * Parallelism: the vertices are sorted before this phase (samples_cubes.c); blocks of
 * them are evaluated in parallel into arrays indexed by vertex position, and the counts
 * are integer sums, so the result is identical for any thread count.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/kdtree.h"
#include "stages/samples/samples_internal.h"

enum { BLOCK = 4096, MAX_SIGN_NEIGHBOURS = 64 };

typedef struct eval_ctx {
    const sl_samples_config *cfg;
    const sl_samples_plan *plan;
    const sl_pointset *ps;
    const sl_kdtree *tree;          /* closest = points */
    const samples_surface *surface; /* closest = triangles */
    const uint64_t *keys;
    sl_vdb_samples *out;
} eval_ctx;

static double dot_to(const sl_pointset *ps, uint32_t i, const double v[3], double *dist2)
{
    double d[3], dot = 0;
    for (int k = 0; k < 3; k++) {
        d[k] = v[k] - ps->positions[3 * i + k];
        dot += d[k] * ps->normals[3 * i + k];
    }
    if (dist2)
        *dist2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    return dot;
}

/* The sign vote of the k nearest points; returns +1 or -1 (0 -> +). Each point votes
 * with weight |cos(v - p, n_p)| / (|v - p| + leaf/16): near points count more, and so do
 * points that see v along their normal -- a point that sees v edge-on (|cos| ~ 0: v lies
 * beyond the rim of its surface patch, the case of thin parts and sharp edges) hardly
 * votes. So the weighted vote is sum of dot / (|v - p| (|v - p| + leaf/16)). */
static int vote_sign(const eval_ctx *c, const float q[3], const double v[3])
{
    uint32_t idx[MAX_SIGN_NEIGHBOURS];
    float d2[MAX_SIGN_NEIGHBOURS];
    uint32_t found = sl_kdtree_knn(c->tree, q, (uint32_t)c->cfg->sign_neighbours, idx, d2);
    double vote = 0, soft = c->plan->leaf_size / 16;
    for (uint32_t j = 0; j < found; j++) {
        double dist2 = 0, dot = dot_to(c->ps, idx[j], v, &dist2), d = sqrt(dist2);
        if (d > 0)
            vote += dot / (d * (d + soft));
    }
    return vote >= 0 ? 1 : -1;
}

static void store(sl_vdb_samples *out, uint64_t i, double value)
{
    out->distance[i] = (float)value;
    if (out->distance[i] == 0)
        out->distance[i] = 0.0f; /* no -0: "0 -> +" and identical bytes */
}

/* Evaluates vertex i; returns 1 when a vote overruled the closest point's sign. *hint:
 * the previous vertex's closest triangle (closest = triangles). */
static int eval_vertex(const eval_ctx *c, uint64_t i, uint32_t *hint)
{
    const sl_samples_plan *plan = c->plan;
    uint32_t g[3];
    double v[3];
    float q[3];
    sl_vertex_unpack(c->keys[i], g);
    for (int k = 0; k < 3; k++) {
        c->out->coords[3 * i + k] = (int32_t)g[k];
        v[k] = plan->origin[k] + plan->leaf_size * g[k];
        q[k] = (float)v[k];
    }
    if (c->surface) {
        uint8_t *rgba = c->out->colors ? c->out->colors + 4 * i : NULL;
        store(c->out, i, samples_surface_signed_distance(c->surface, v, hint, rgba));
        return 0;
    }
    uint32_t p = sl_kdtree_nearest(c->tree, q, NULL);
    double dist2 = 0, dot = dot_to(c->ps, p, v, &dist2);
    int sign = dot >= 0 ? 1 : -1, flipped = 0;
    if (c->cfg->sign_neighbours > 1) {
        int voted = vote_sign(c, q, v);
        flipped = voted != sign;
        sign = voted;
    }
    double d = c->cfg->distance == SL_SAMPLES_TANGENT ? fabs(dot) : sqrt(dist2);
    store(c->out, i, sign * d);
    if (c->out->colors)
        memcpy(c->out->colors + 4 * i, c->ps->colors + 4 * (uint64_t)p, 4);
    return flipped;
}

/* The parallel phase; returns SL_E_INTERRUPTED if asked to stop. */
void sl_samples_part_range(uint64_t n, int part, int parts, uint64_t *first, uint64_t *end)
{
    uint64_t blocks = (n + BLOCK - 1) / BLOCK;
    uint64_t b0 = blocks * (uint64_t)part / (uint64_t)parts;
    uint64_t b1 = blocks * (uint64_t)(part + 1) / (uint64_t)parts;
    *first = b0 * BLOCK < n ? b0 * BLOCK : n;
    *end = b1 * BLOCK < n ? b1 * BLOCK : n;
}

/* Vertices [first, end) (block-aligned: a block's closest-triangle hint starts afresh, so a
 * part evaluates exactly what the whole pass does there). */
static int eval_all(const eval_ctx *c, uint64_t first, uint64_t n, sl_progress *progress,
                    uint64_t *flips)
{
    int64_t b0 = (int64_t)(first / BLOCK), blocks = (int64_t)((n + BLOCK - 1) / BLOCK);
    int stop = 0;
    uint64_t flipped = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : flipped) if (blocks - b0 > 1)
    for (int64_t b = b0; b < blocks; b++) {
        int stopped;
#pragma omp atomic read
        stopped = stop;
        if (stopped)
            continue;
        if (sl_progress_step(progress, "samples", (double)(b - b0) / (double)(blocks - b0))) {
#pragma omp atomic write
            stop = 1;
        }
        uint64_t end = (uint64_t)(b + 1) * BLOCK < n ? (uint64_t)(b + 1) * BLOCK : n;
        uint32_t hint = UINT32_MAX; /* per block: the same for any thread count */
        for (uint64_t i = (uint64_t)b * BLOCK; i < end; i++)
            flipped += (uint64_t)eval_vertex(c, i, &hint);
    }
    *flips = flipped;
    return stop || sl_progress_interrupted(progress) ? SL_E_INTERRUPTED : SL_OK;
}

static int alloc_samples(sl_vdb_samples *out, uint64_t n, int colors, sl_error *err)
{
    out->count = n;
    out->coords = malloc(3 * n * sizeof *out->coords + 1);
    out->distance = malloc(n * sizeof *out->distance + 1);
    out->colors = colors ? malloc(4 * n + 1) : NULL;
    if (out->coords && out->distance && (!colors || out->colors))
        return SL_OK;
    sl_vdb_samples_release(out);
    return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory for %llu samples",
                        (unsigned long long)n);
}

/* The join of a split: every vertex's grid position, the values from the parts. */
static int join_parts(const sl_samples_split *split, const samples_keys *vertices,
                      sl_vdb_samples *out, int *closed, uint64_t *flips, sl_error *err)
{
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < vertices->count; i++) {
        uint32_t g[3];
        sl_vertex_unpack(vertices->keys[i], g);
        for (int k = 0; k < 3; k++)
            out->coords[3 * i + k] = (int32_t)g[k];
    }
    return split->fill(split->ctx, out, closed, flips, err);
}

static int compute_samples(const sl_samples_config *cfg, const sl_pointset *ps,
                           const samples_keys *vertices, const sl_samples_split *split,
                           sl_vdb_samples *out, sl_samples_counts *counts,
                           sl_progress *progress, sl_error *err)
{
    sl_kdtree *tree = NULL;
    samples_surface surface, *use_surface = NULL;
    int closed = 0, joining = split && split->fill;
    double t0 = omp_get_wtime();
    int rc = SL_OK;
    if (joining) {
        /* the parts hold the values and whether the surface is closed */
    } else if (counts->triangles) {
        rc = samples_surface_build(&surface, ps, err);
        use_surface = rc == SL_OK ? &surface : NULL;
        closed = use_surface && surface.closed;
    } else {
        rc = sl_kdtree_build(&tree, ps->positions, ps->count, err);
    }
    counts->seconds_tree = omp_get_wtime() - t0;
    if (rc == SL_OK)
        rc = alloc_samples(out, vertices->count, ps->colors != NULL, err);
    if (rc == SL_OK) {
        eval_ctx c = {cfg, &counts->plan, ps, tree, use_surface, vertices->keys, out};
        out->leaf_size = counts->plan.leaf_size;
        memcpy(out->origin, counts->plan.origin, sizeof out->origin);
        uint64_t first = 0, end = vertices->count;
        if (split && !joining)
            sl_samples_part_range(vertices->count, split->part, split->parts, &first, &end);
        rc = joining ? join_parts(split, vertices, out, &closed, &counts->sign_flips, err)
                     : eval_all(&c, first, end, progress, &counts->sign_flips);
    }
    sl_kdtree_free(tree);
    if (use_surface)
        samples_surface_release(use_surface);
    counts->closed_surface = closed;
    if (split && !joining)
        return rc; /* a part: the signs are repaired and counted by the join */
    if (rc == SL_OK && closed) /* open scans have no inside: nothing to repair against */
        rc = samples_repair_signs(vertices->keys, out, counts->plan.leaf_size,
                                  &counts->sign_repairs, err);
    if (rc != SL_OK)
        return rc;
    for (uint64_t i = 0; i < out->count; i++)
        counts->inside += out->distance[i] < 0;
    counts->outside = out->count - counts->inside;
    return SL_OK;
}

int sl_samples_compute(const sl_samples_config *cfg, const sl_pointset *ps, sl_vdb_samples *out,
                       sl_samples_counts *counts, sl_progress *progress, sl_error *err)
{
    return sl_samples_compute_split(cfg, ps, NULL, out, counts, progress, err);
}

int sl_samples_compute_split(const sl_samples_config *cfg, const sl_pointset *ps,
                             const sl_samples_split *split, sl_vdb_samples *out,
                             sl_samples_counts *counts, sl_progress *progress, sl_error *err)
{
    memset(out, 0, sizeof *out);
    memset(counts, 0, sizeof *counts);
    counts->points = ps->count;
    if (cfg->closest == SL_SAMPLES_CLOSEST_TRIANGLES)
        counts->triangles = ps->triangle_count;
    if (cfg->sign_neighbours < 1 || cfg->sign_neighbours > MAX_SIGN_NEIGHBOURS ||
        cfg->band < 0 || cfg->band > SL_SAMPLES_MAX_BAND || cfg->max_depth > SL_SAMPLES_MAX_DEPTH)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "samples config out of range");
    double t0 = omp_get_wtime();
    int rc = sl_samples_plan_make(cfg, ps, &counts->plan, err);
    if (rc != SL_OK)
        return rc;
    double t1 = omp_get_wtime();
    counts->seconds_plan = t1 - t0;
    if (sl_progress_step(progress, "cubes", 0.0))
        return SL_E_INTERRUPTED;
    samples_keys keys;
    if ((rc = samples_occupied_cubes(&counts->plan, ps, counts->triangles > 0, cfg->max_samples,
                                     &keys, &counts->triangle_keys, err)) != SL_OK)
        return rc;
    counts->occupied_cubes = keys.count;
    rc = samples_band_vertices(&counts->plan, &keys, cfg->max_samples, &counts->band_cubes, err);
    counts->samples = rc == SL_OK ? keys.count : 0;
    double t2 = omp_get_wtime();
    counts->seconds_cubes = t2 - t1;
    if (rc == SL_OK && sl_progress_step(progress, "samples", 0.0))
        rc = SL_E_INTERRUPTED;
    if (rc == SL_OK)
        rc = compute_samples(cfg, ps, &keys, split, out, counts, progress, err);
    samples_keys_release(&keys);
    if (rc != SL_OK)
        sl_vdb_samples_release(out);
    counts->seconds_samples = omp_get_wtime() - t2 - counts->seconds_tree;
    return rc;
}
