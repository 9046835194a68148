/* cluster stage entry (cluster.h): the range stage's welded mesh -> the export ladder's
 * levels, each from the next finer one, with their bounds. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/cluster/cluster.h"

#define CLUSTER_STAGE_VERSION 1u

static const sl_option cluster_options[] = {
    {"cluster", "passes", SL_OPT_INT, "1", 1, SL_CLUSTER_MAX_PASSES, NULL,
     "Clustering passes per level (paper 2): each clusters, straightens and triangulates "
     "the previous one's output; their bounds add up. Tolerances double from pass to pass."},
    {"cluster", "intermediates", SL_OPT_INT, "0", 0, SL_CLUSTER_MAX_INTERMEDIATES, NULL,
     "Intermediate models (paper 2, section 4) written between each level and the next "
     "finer one: border vertices moved part of the way to their straightened segments, "
     "straightened and triangulated again. 0 = none."},
    {"cluster", "max_angle", SL_OPT_DOUBLE, "60", 1, SL_CLUSTER_MAX_ANGLE, NULL,
     "Degrees: a face joins a cluster only when its normal is within this angle of the "
     "cluster's direction (the seed face's normal)."},
    {"cluster", "slab_share", SL_OPT_DOUBLE, "0.7", 0.01, 1, NULL,
     "Share of a pass's tolerance eps that a cluster's thickness (the slab of its vertices "
     "across its direction) may take; its borders are straightened within "
     "sqrt(eps^2 - thickness^2), so that the pass's bound is at most eps."},
    {"cluster", "search_steps", SL_OPT_INT, "16", 1, 64, NULL,
     "Bisection steps of the bound when a level is asked as a triangle budget."},
    SL_OPTION_END,
};

static int cluster_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_cluster_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    c->passes = (uint32_t)sl_config_int(cfg, "cluster", "passes");
    c->intermediates = (uint32_t)sl_config_int(cfg, "cluster", "intermediates");
    c->max_angle = sl_config_double(cfg, "cluster", "max_angle");
    c->slab_share = sl_config_double(cfg, "cluster", "slab_share");
    c->search_steps = (uint32_t)sl_config_int(cfg, "cluster", "search_steps");
    *out = c;
    return 0;
}

sl_cluster_config sl_cluster_default_config(void)
{
    sl_cluster_config c;
    sl_stage_default_config(&sl_cluster_stage, &c, sizeof c);
    return c;
}

static int cluster_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    (void)config;
    (void)io;
    return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "cluster stage: not written yet");
}

const sl_stage sl_cluster_stage = {
    .name = "cluster",
    .methods = SL_METHOD_CLUSTER,
    .description = "welded mesh -> levels by clustering with bounded error (paper 2)",
    .version = CLUSTER_STAGE_VERSION,
    .options = cluster_options,
    .configure = cluster_configure,
    .release_config = free,
    .run = cluster_run,
    .publish = 0,
};
