/* The clustering method's entry (cluster.h): checks, passes chained to a bound, and the
 * search for a triangle budget.
 *
 * Passes and their tolerances: a level asked to be within E (world, what is left after
 * the input's own bound) runs P passes, each on the previous one's output. Pass p gets
 * eps_p = R_p / (2^(P-p+1) - 1) of what is left, R_p = E - (bounds proven so far), so the
 * tolerances double from pass to pass (the paper's hierarchy: coarser and coarser levels)
 * and what a pass does not use goes to the next ones. The level's bound is the sum of the
 * passes' proven bounds: the symmetric Hausdorff distance obeys the triangle inequality.
 *
 * A budget of N triangles: a search of E (search_budget) for the smallest whose level has
 * at most N triangles; the count is nearly, not strictly, monotone in E, so the result is
 * the smallest E seen within the budget, always within it unless even E = 1 diagonal is
 * not ("not reached": the coarsest level seen is returned).
 *
 * Threads: below SERIAL_BELOW triangles the whole call runs on one thread. A pass is a
 * dozen short parallel regions (several of them the toolkit's); on meshes this small each
 * region's fork and barrier cost more than its work, and on the shared 2-core machine with
 * a load of 14 two threads made cow's Table 1 run 0.85 s instead of 0.12 s.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "stages/cluster/cluster_internal.h"

#define SERIAL_BELOW 50000

int sl_cluster_check_config(const sl_cluster_config *c, sl_error *err)
{
    if (c->passes < 1 || c->passes > SL_CLUSTER_MAX_PASSES)
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "passes: %u is not in [1, %d]", c->passes,
                            SL_CLUSTER_MAX_PASSES);
    if (c->intermediates > SL_CLUSTER_MAX_INTERMEDIATES)
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "intermediates: %u is not in [0, %d]",
                            c->intermediates, SL_CLUSTER_MAX_INTERMEDIATES);
    if (!(c->max_angle > 0.0 && c->max_angle <= SL_CLUSTER_MAX_ANGLE))
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "max_angle: %g degrees is not in (0, %g] (a cluster must project "
                            "onto its plane)", c->max_angle, SL_CLUSTER_MAX_ANGLE);
    if (!(c->slab_share > 0.0 && c->slab_share <= 1.0))
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "slab_share: %g is not in (0, 1]",
                            c->slab_share);
    if (c->search_steps < 1 || c->search_steps > 64)
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "search_steps: %u is not in [1, 64]",
                            c->search_steps);
    return 0;
}

int sl_cluster_check_target(const sl_cluster_target *t, sl_error *err)
{
    int by_error = t->max_error != 0.0, by_count = t->triangles != 0;
    if (by_error == by_count)
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "give either a bound (max error) or a triangle budget");
    if (by_error && !(t->max_error > 0.0 && t->max_error <= 1.0))
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "the bound %g is not a fraction of the diagonal in (0, 1]",
                            t->max_error);
    if (t->intermediates > SL_CLUSTER_MAX_INTERMEDIATES)
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "%u intermediate models: at most %d", t->intermediates,
                            SL_CLUSTER_MAX_INTERMEDIATES);
    return 0;
}

void sl_cluster_level_release(sl_cluster_level *level)
{
    free(level->triangles);
    for (uint32_t j = 0; j < level->intermediate_count; j++)
        cl_intermediate_release(&level->intermediates[j]);
    free(level->intermediates);
    memset(level, 0, sizeof *level);
}

/* What the checks found: the diagonal, the rounding margin, the triangles to work on. */
typedef struct prepared {
    double diagonal, margin;
    uint32_t triangle_count;
    uint32_t *triangles;      /* the input's, without triangles repeating a corner */
} prepared;

static int prepare(const sl_cluster_input *in, prepared *pr, sl_cluster_level *level,
                   sl_error *err)
{
    if (in->triangle_count == 0 || !in->triangles || !in->positions)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "no triangle to simplify");
    if (in->triangle_count > SL_ADJACENCY_MAX_TRIANGLES || in->triangle_count > INT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "%llu triangles: at most %d",
                            (unsigned long long)in->triangle_count, INT32_MAX);
    if (in->vertex_count >= UINT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "%llu vertices: at most %u",
                            (unsigned long long)in->vertex_count, UINT32_MAX - 1);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double big = 0.0;
    pr->triangles = malloc(3 * in->triangle_count * sizeof *pr->triangles);
    if (!pr->triangles)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "%llu triangles",
                            (unsigned long long)in->triangle_count);
    uint32_t kept = 0;
    for (uint64_t t = 0; t < in->triangle_count; t++) {
        const uint32_t *c = in->triangles + 3 * t;
        for (int i = 0; i < 3; i++) {
            if (c[i] >= in->vertex_count)
                return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                    "triangle %llu names vertex %u of %llu",
                                    (unsigned long long)t, c[i],
                                    (unsigned long long)in->vertex_count);
            const float *p = in->positions + 3 * (uint64_t)c[i];
            for (int k = 0; k < 3; k++) {
                if (!isfinite(p[k]))
                    return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                        "vertex %u has a non-finite coordinate", c[i]);
                lo[k] = fmin(lo[k], p[k]);
                hi[k] = fmax(hi[k], p[k]);
                big = fmax(big, fabs(p[k]));
            }
        }
        if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) {
            level->degenerate_triangles++;
            continue;
        }
        memcpy(pr->triangles + 3 * (uint64_t)kept++, c, 3 * sizeof *c);
    }
    pr->triangle_count = kept;
    double d = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                    (hi[2] - lo[2]) * (hi[2] - lo[2]));
    pr->diagonal = in->diagonal > 0.0 ? in->diagonal : d;
    if (!(d > 0.0) || !isfinite(pr->diagonal) || kept == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            kept ? "the mesh has a zero-size bounding box"
                                 : "every triangle repeats a corner: nothing to simplify");
    /* Float rounding of a coordinate of magnitude <= big is <= big 2^-24; the margin covers
     * that for the moved vertices of intermediates and every double evaluation. */
    pr->margin = ldexp(big, -20);
    return 0;
}

/* Topology of the input: counted, and refused in strict mode. */
static int topology(const sl_cluster_input *in, const prepared *pr, sl_cluster_level *level,
                    sl_error *err)
{
    int strict = (in->flags & SL_CLUSTER_STRICT) != 0;
    if (strict && level->degenerate_triangles)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "%llu triangles repeat a corner (degenerate faces)",
                            (unsigned long long)level->degenerate_triangles);
    sl_mesh_adjacency adj;
    int rc = sl_mesh_adjacency_build(pr->triangles, pr->triangle_count, in->vertex_count,
                                     in->positions, strict ? SL_ADJACENCY_STRICT : 0, &adj, err);
    if (rc)
        return rc;
    level->boundary_edges = adj.report.boundary_edges;
    level->nonmanifold_edges = adj.report.nonmanifold_edges + adj.report.inconsistent_edges;
    level->nonmanifold_vertices = adj.report.nonmanifold_vertices;
    if (strict && adj.report.boundary_edges) {
        uint32_t h = 0;
        while (adj.twin[h] != SL_HALFEDGE_NONE)
            h++;
        uint32_t a = sl_halfedge_origin(&adj, h), b = sl_halfedge_target(&adj, h);
        const float *p = in->positions + 3 * (uint64_t)a;
        rc = sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                          "the surface is open: %llu boundary edges in %llu loops (the first "
                          "between vertices %u and %u, at %g %g %g)",
                          (unsigned long long)adj.report.boundary_edges,
                          (unsigned long long)adj.report.boundary_loops, a, b, p[0], p[1], p[2]);
    }
    sl_mesh_adjacency_release(&adj);
    return rc;
}

/* P passes from `pr`'s triangles within the budget `budget` (world). */
static int run_passes(const sl_cluster_config *cfg, const sl_cluster_input *in,
                      const prepared *pr, double budget, uint32_t intermediates,
                      sl_cluster_level *out, sl_progress *progress, sl_error *err)
{
    uint32_t count = pr->triangle_count;
    uint32_t *tri = malloc(3 * (size_t)count * sizeof *tri);
    if (!tri)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "%u triangles", count);
    memcpy(tri, pr->triangles, 3 * (size_t)count * sizeof *tri);
    double spent = 0.0;
    int rc = 0;
    out->pass_count = 0;
    for (uint32_t p = 1; p <= cfg->passes && rc == 0; p++) {
        uint32_t left = cfg->passes - p + 1;
        double eps = (budget - spent - left * pr->margin) / (ldexp(1.0, (int)left) - 1.0);
        if (!(eps > 0.0))
            break;
        cl_pass_input pin = {in->vertex_count, in->positions, count, tri, eps, pr->margin,
                             in->base_bound + spent, p == cfg->passes ? intermediates : 0, cfg};
        cl_pass_output pout;
        rc = cl_pass_run(&pin, &pout, progress, err);
        if (rc)
            break;
        out->pass[out->pass_count++] = pout.stats;
        spent += pout.stats.bound;
        free(tri);
        tri = pout.triangles;
        count = pout.triangle_count;
        pout.triangles = NULL;
        if (pout.intermediate_count) {
            out->intermediates = pout.intermediates;
            out->intermediate_count = pout.intermediate_count;
            pout.intermediates = NULL;
            pout.intermediate_count = 0;
        }
        cl_pass_output_release(&pout);
    }
    if (rc) {
        free(tri);
        return rc;
    }
    out->triangles = tri;
    out->triangle_count = count;
    out->bound = in->base_bound + spent;
    out->bound_fraction = out->bound / pr->diagonal;
    out->diagonal = pr->diagonal;
    return 0;
}

/* Moves the passes' results of `from` into `to`, keeping `to`'s input counts. */
static void take_result(sl_cluster_level *to, sl_cluster_level *from)
{
    sl_cluster_level keep = *to;
    free(to->triangles);
    for (uint32_t j = 0; j < to->intermediate_count; j++)
        cl_intermediate_release(&to->intermediates[j]);
    free(to->intermediates);
    *to = *from;
    to->boundary_edges = keep.boundary_edges;
    to->nonmanifold_edges = keep.nonmanifold_edges;
    to->nonmanifold_vertices = keep.nonmanifold_vertices;
    to->degenerate_triangles = keep.degenerate_triangles;
    to->search_steps = keep.search_steps;
    memset(from, 0, sizeof *from);
}

/* A search's state: the best level within the budget seen so far (at budget `hi`) and
 * the largest budget seen over it (`lo`, its count `lo_count`). */
typedef struct search {
    const sl_cluster_config *cfg;
    const sl_cluster_input *in;
    const prepared *pr;
    uint64_t target;
    sl_cluster_level best;
    double lo, hi;
    uint64_t lo_count, hi_count;
    uint32_t steps;
    sl_progress *progress;
} search;

/* Runs the passes at `budget` and files the result; 1 within the target, 0 over. */
static int probe(search *s, double budget, sl_error *err)
{
    sl_cluster_level trial;
    memset(&trial, 0, sizeof trial);
    int rc = run_passes(s->cfg, s->in, s->pr, budget, 0, &trial, s->progress, err);
    s->steps++;
    if (rc == 0 && sl_progress_step(s->progress, "cluster: budget search",
                                    (double)s->steps / (s->cfg->search_steps + 8)))
        rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "interrupted");
    if (rc) {
        sl_cluster_level_release(&trial);
        return rc;
    }
    if (trial.triangle_count <= s->target) {
        sl_cluster_level_release(&s->best);
        s->best = trial;
        s->hi = budget;
        s->hi_count = trial.triangle_count;
        return 1;
    }
    s->lo = budget;
    s->lo_count = trial.triangle_count;
    sl_cluster_level_release(&trial);
    return 0;
}

/* The smallest bound whose level has at most `target` triangles. The count falls about
 * as a power of the bound, so the next probe is the regula falsi on log count against log
 * bound (Illinois: a side kept twice has its count pulled halfway to the target), from a
 * bracket found by factors of 4 from 1 % of the diagonal (upwards only while the count
 * still falls: past a few % of the diagonal, clusters limited by max_angle alone start to
 * fold over protrusions and are kept whole, so counts rise again). Stops at search_steps probes,
 * when the bracket is within 0.1 %, or when the level is within 1 % under the target. */
static int search_budget(const sl_cluster_config *cfg, const sl_cluster_input *in,
                         const prepared *pr, const sl_cluster_target *target,
                         sl_cluster_level *level, sl_progress *progress, sl_error *err)
{
    search s = {cfg, in, pr, target->triangles, {0}, 0.0, 0.0, 0, 0, 0, progress};
    double d = pr->diagonal, budget = 0.01 * d, floor_budget = ldexp(d, -30);
    int rc = probe(&s, budget, err);
    uint64_t fewest = s.lo_count;
    double fewest_budget = budget;
    while (rc == 0 && budget < d) { /* over the target: grow the bound */
        budget = fmin(d, 4.0 * budget);
        rc = probe(&s, budget, err);
        if (rc == 0 && s.lo_count >= fewest)
            break; /* past the coarsest: larger clusters only fold (docs/clustering.md) */
        if (rc == 0) {
            fewest = s.lo_count;
            fewest_budget = budget;
        }
    }
    while (rc == 1 && s.lo == 0.0 && budget > floor_budget) { /* within: shrink it */
        budget = fmax(floor_budget, 0.25 * budget);
        rc = probe(&s, budget, err);
    }
    int reached = s.hi > 0.0;
    double pull_lo = 1.0, pull_hi = 1.0; /* Illinois weights */
    int last = 0;
    while (rc >= 0 && reached && s.lo > 0.0 && s.steps < cfg->search_steps &&
           s.hi > s.lo * 1.001 && 100 * s.hi_count < 99 * s.target) {
        double t = log((double)s.target);
        double fl = (log((double)s.lo_count) - t) * pull_lo, fh = (log((double)s.hi_count) - t) * pull_hi;
        double x = log(s.lo) + (log(s.hi) - log(s.lo)) * (fl / (fl - fh));
        double lo_x = log(s.lo) + 0.02 * (log(s.hi) - log(s.lo)), hi_x = log(s.hi) - 0.02 * (log(s.hi) - log(s.lo));
        x = !(x > lo_x) ? lo_x : x > hi_x ? hi_x : x; /* strictly inside the bracket */
        rc = probe(&s, exp(x), err);
        if (rc >= 0) {
            pull_lo = rc == 1 && last == 1 ? 0.5 * pull_lo : 1.0;
            pull_hi = rc == 0 && last == 0 ? 0.5 * pull_hi : 1.0;
            last = rc;
        }
    }
    if (rc >= 0 && !reached) { /* out of reach: the coarsest level seen */
        s.hi = fewest_budget;
        rc = run_passes(cfg, in, pr, s.hi, 0, &s.best, progress, err);
    }
    if (rc >= 0 && target->intermediates) { /* the chosen level once more, with its morph */
        sl_cluster_level_release(&s.best);
        rc = run_passes(cfg, in, pr, s.hi, target->intermediates, &s.best, progress, err);
    }
    if (rc < 0) {
        sl_cluster_level_release(&s.best);
        return rc;
    }
    level->search_steps = s.steps;
    take_result(level, &s.best);
    level->reached = reached;
    return 0;
}

int sl_cluster_simplify(const sl_cluster_config *cfg, const sl_cluster_input *in,
                        const sl_cluster_target *target, sl_cluster_level *level,
                        sl_progress *progress, sl_error *err)
{
    memset(level, 0, sizeof *level);
    int rc = sl_cluster_check_config(cfg, err);
    if (rc == 0)
        rc = sl_cluster_check_target(target, err);
    if (rc == 0 && !(in->base_bound >= 0.0 && isfinite(in->base_bound)))
        rc = sl_error_set(err, SL_E_USAGE, 0, NULL, "the input's bound %g is not >= 0",
                          in->base_bound);
    prepared pr;
    memset(&pr, 0, sizeof pr);
    if (rc == 0)
        rc = prepare(in, &pr, level, err);
    int threads = omp_get_max_threads();
    if (rc == 0 && pr.triangle_count < SERIAL_BELOW)
        omp_set_num_threads(1);
    if (rc == 0)
        rc = topology(in, &pr, level, err);
    if (rc == 0) {
        double budget = target->max_error * pr.diagonal - in->base_bound;
        int unchanged = target->triangles ? pr.triangle_count <= target->triangles
                                          : !(budget > cfg->passes * pr.margin);
        if (unchanged) { /* the input meets the target, or has no bound left to spend */
            level->triangles = pr.triangles;
            level->triangle_count = pr.triangle_count;
            pr.triangles = NULL;
            level->bound = in->base_bound;
            level->bound_fraction = in->base_bound / pr.diagonal;
            level->diagonal = pr.diagonal;
            level->reached = target->triangles || in->base_bound <= target->max_error * pr.diagonal;
        } else if (target->triangles) {
            rc = search_budget(cfg, in, &pr, target, level, progress, err);
        } else {
            sl_cluster_level res;
            memset(&res, 0, sizeof res);
            rc = run_passes(cfg, in, &pr, budget, target->intermediates, &res, progress, err);
            if (rc == 0) {
                take_result(level, &res);
                level->reached = 1;
            }
        }
    }
    omp_set_num_threads(threads);
    free(pr.triangles);
    if (rc) {
        sl_error level_err = *err;
        sl_cluster_level_release(level);
        *err = level_err;
    }
    return rc;
}
