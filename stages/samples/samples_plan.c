/* samples stage: the grid of leaf cubes (paper 1 section 2.1 leaves the cube size open;
 * docs/samples-stage.md, "The grid": "leaf size defaults from point spacing").
 *
 * The leaf size comes from, in order: [octree] leaf_size; [octree] depth (the longest
 * side of the bounding box plus the band on both sides fills the 2^depth cubes of the
 * root); spacing_factor x the points' mean nearest-neighbour spacing, at most the
 * bounding box's diagonal / SL_SAMPLES_DIAGONAL_LEAVES (a few far-apart vertices say
 * nothing about how fine the surface between them is). Everything that
 * could make the later phases allocate without bound is refused here, before any
 * allocation: a depth beyond max_depth (also the case of a huge extent with tiny
 * features), and clouds from which no size can be derived.
 */
#include <math.h>
#include <string.h>

#include "stages/samples/samples_internal.h"

/* Bounding box of the positions in double; refuses non-finite coordinates. */
static int point_bbox(const sl_pointset *ps, double lo[3], double hi[3], sl_error *err)
{
    for (int k = 0; k < 3; k++)
        lo[k] = INFINITY, hi[k] = -INFINITY;
    for (uint64_t i = 0; i < ps->count; i++)
        for (int k = 0; k < 3; k++) {
            double v = ps->positions[3 * i + k];
            if (!isfinite(v))
                return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                    "point %llu has a non-finite coordinate",
                                    (unsigned long long)i);
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    return SL_OK;
}

static int longest_axis(const double extent[3])
{
    int a = 0;
    for (int k = 1; k < 3; k++)
        if (extent[k] > extent[a])
            a = k;
    return a;
}

static double diagonal_of(const double extent[3])
{
    return sqrt(extent[0] * extent[0] + extent[1] * extent[1] + extent[2] * extent[2]);
}

static int choose_leaf(const sl_samples_config *cfg, const sl_pointset *ps,
                       const double extent[3], double *leaf, sl_error *err)
{
    double longest = extent[longest_axis(extent)];
    if (cfg->leaf_size > 0) {
        *leaf = cfg->leaf_size;
    } else if (cfg->depth > 0) {
        if (!(longest > 0))
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "all %llu point(s) coincide: [octree] depth needs an extent; "
                                "set [octree] leaf_size", (unsigned long long)ps->count);
        *leaf = longest / (ldexp(1.0, cfg->depth) - 2.0 * cfg->band);
    } else {
        if (!(ps->mean_spacing > 0) || !isfinite(ps->mean_spacing))
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "mean point spacing is %g with %llu point(s): no leaf size can "
                                "be derived; set [octree] leaf_size or [octree] depth",
                                ps->mean_spacing, (unsigned long long)ps->count);
        *leaf = cfg->spacing_factor * ps->mean_spacing;
        double bound = diagonal_of(extent) / SL_SAMPLES_DIAGONAL_LEAVES;
        if (bound > 0 && *leaf > bound)
            *leaf = bound;
    }
    if (!(*leaf > 0) || !isfinite(*leaf))
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "leaf size %g is not usable", *leaf);
    return SL_OK;
}

static int too_deep(const sl_samples_config *cfg, double leaf, double longest, double span,
                    sl_error *err)
{
    double need = ceil(log2(span));
    return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                        "leaf size %g on a bounding box of longest side %g needs %.4g cubes per "
                        "side, an octree of depth %.0f > [octree] max_depth %d; set a larger "
                        "[octree] leaf_size or a smaller [octree] depth, or raise max_depth",
                        leaf, longest, span, need, cfg->max_depth);
}

int sl_samples_plan_make(const sl_samples_config *cfg, const sl_pointset *ps,
                         sl_samples_plan *plan, sl_error *err)
{
    memset(plan, 0, sizeof *plan);
    if (ps->count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "the point set is empty");
    int rc = point_bbox(ps, plan->bbox_min, plan->bbox_max, err);
    if (rc != SL_OK)
        return rc;
    double extent[3];
    for (int k = 0; k < 3; k++)
        extent[k] = plan->bbox_max[k] - plan->bbox_min[k];
    int axis = longest_axis(extent);
    double leaf = 0;
    if ((rc = choose_leaf(cfg, ps, extent, &leaf, err)) != SL_OK)
        return rc;
    double max_cells = ldexp(1.0, cfg->max_depth) - 2.0 * cfg->band, span = 0;
    for (int k = 0; k < 3; k++) {
        double c = ceil(extent[k] / leaf);
        if (c < 1)
            c = 1;
        if (c > max_cells)
            return too_deep(cfg, leaf, extent[axis], ceil(extent[axis] / leaf) + 2.0 * cfg->band,
                            err);
        if (c > 1 && (c - 1) * leaf >= extent[k]) /* extent / leaf rounded up by one ulp */
            c -= 1;
        plan->cells[k] = (uint32_t)c;
    }
    if (cfg->leaf_size <= 0 && cfg->depth > 0 && extent[axis] > 0)
        plan->cells[axis] = (uint32_t)(ldexp(1.0, cfg->depth) - 2.0 * cfg->band);
    for (int k = 0; k < 3; k++)
        span = plan->cells[k] + 2.0 * cfg->band > span ? plan->cells[k] + 2.0 * cfg->band : span;
    int depth = 1;
    while (ldexp(1.0, depth) < span)
        depth++;
    if (depth > cfg->max_depth)
        return too_deep(cfg, leaf, extent[axis], span, err);
    plan->leaf_size = leaf;
    plan->depth = depth;
    plan->band = cfg->band;
    for (int k = 0; k < 3; k++)
        plan->origin[k] = plan->bbox_min[k] - cfg->band * leaf;
    return SL_OK;
}
