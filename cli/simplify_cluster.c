/* `scanlod simplify --method cluster` (paper 2; docs/clustering.md): the cluster method's
 * options and its run (cli/simplify.h). */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/simplify.h"
#include "stages/cluster/cluster.h"

static sl_cluster_config cluster_opts;
static uint32_t cluster_intermediates;

static void cluster_reset(void)
{
    cluster_opts = sl_cluster_default_config();
    cluster_intermediates = 0;
}

static int cluster_parse(int argc, char **argv, int *i)
{
    const char *arg = argv[*i];
    double v;
    if (!strcmp(arg, "--passes")) {
        if (sl_simplify_parse_count(argc, argv, i, 1, SL_CLUSTER_MAX_PASSES, &v))
            return -1;
        cluster_opts.passes = (uint32_t)v;
    } else if (!strcmp(arg, "--intermediates")) {
        if (sl_simplify_parse_count(argc, argv, i, 1, SL_CLUSTER_MAX_INTERMEDIATES, &v))
            return -1;
        cluster_intermediates = (uint32_t)v;
    } else if (!strcmp(arg, "--max-angle") || !strcmp(arg, "--slab-share")) {
        int angle = arg[2] == 'm';
        if (*i + 1 >= argc || sl_simplify_parse_double(argv[++*i], &v) ||
            !(angle ? v > 0 && v <= SL_CLUSTER_MAX_ANGLE : v > 0 && v <= 1)) {
            fprintf(stderr, "scanlod simplify: %s needs a number in %s\n", arg,
                    angle ? "(0, 89] (degrees)" : "(0, 1]");
            return -1;
        }
        *(angle ? &cluster_opts.max_angle : &cluster_opts.slab_share) = v;
    } else {
        return 0;
    }
    return 1;
}

static void cluster_figures(sl_json *j, const sl_cluster_level *l)
{
    sl_json_double(j, "bound", l->bound_fraction);
    sl_json_double(j, "bound_world", l->bound);
    sl_json_double(j, "diagonal", l->diagonal);
    sl_json_bool(j, "reached", l->reached);
    sl_json_u64(j, "search_steps", l->search_steps);
    sl_json_u64(j, "boundary_edges", l->boundary_edges);
    sl_json_u64(j, "nonmanifold_edges", l->nonmanifold_edges);
    sl_json_u64(j, "nonmanifold_vertices", l->nonmanifold_vertices);
    sl_json_array_begin(j, "passes");
    for (uint32_t p = 0; p < l->pass_count; p++) {
        const sl_cluster_pass_stats *s = &l->pass[p];
        sl_json_object_begin(j, NULL);
        sl_json_double(j, "tolerance", s->tolerance / l->diagonal);
        sl_json_double(j, "bound", s->bound / l->diagonal);
        sl_json_double(j, "max_slab", s->max_slab / l->diagonal);
        sl_json_double(j, "max_deviation", s->max_deviation / l->diagonal);
        sl_json_u64(j, "clusters", s->clusters);
        sl_json_u64(j, "clusters_kept", s->clusters_kept);
        sl_json_u64(j, "corners", s->corners);
        sl_json_u64(j, "borders", s->borders);
        sl_json_u64(j, "borders_reverted", s->borders_reverted);
        sl_json_u64(j, "forced_splits", s->forced_splits);
        sl_json_u64(j, "triangulation_failures", s->triangulation_failures);
        sl_json_u64(j, "regrowths", s->regrowths);
        sl_json_u64(j, "removed_interior", s->removed_interior);
        sl_json_u64(j, "removed_border", s->removed_border);
        sl_json_u64(j, "triangles_in", s->triangles_in);
        sl_json_u64(j, "triangles_out", s->triangles_out);
        sl_json_object_end(j);
    }
    sl_json_array_end(j);
    sl_json_array_begin(j, "intermediates");
    for (uint32_t k = 0; k < l->intermediate_count; k++) {
        sl_json_object_begin(j, NULL);
        sl_json_u64(j, "triangles", l->intermediates[k].triangle_count);
        sl_json_double(j, "bound", l->intermediates[k].bound / l->diagonal);
        sl_json_object_end(j);
    }
    sl_json_array_end(j);
}

static int cluster_check(const simplify_job *job)
{
    if (cluster_intermediates && !job->has_output) {
        fputs("scanlod simplify: --intermediates needs -o OUT.ply (they are written beside it)\n",
              stderr);
        return -1;
    }
    return 0;
}

static int cluster_run(const simplify_job *job, simplify_output *out, sl_progress *progress,
                       sl_error *err)
{
    sl_cluster_level *l = calloc(1, sizeof *l);
    if (!l)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory");
    sl_cluster_input in = {job->mesh->count, job->mesh->positions, job->mesh->triangle_count,
                           job->mesh->triangles, 0.0, 0.0, job->strict ? SL_CLUSTER_STRICT : 0};
    sl_cluster_target target = {job->max_error, job->triangles, cluster_intermediates};
    if (job->ratio > 0) /* at most R x the input's triangles */
        target.triangles = (uint64_t)fmax(1, floor(job->ratio * (double)job->mesh->triangle_count));
    if (!target.max_error && !target.triangles)
        target.max_error = 0.01;
    int rc = sl_cluster_simplify(&cluster_opts, &in, &target, l, progress, err);
    out->state = l;
    if (rc)
        return rc;
    out->triangle_count = l->triangle_count;
    out->triangles = l->triangles;
    out->extras = calloc(l->intermediate_count ? l->intermediate_count : 1, sizeof *out->extras);
    if (!out->extras)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory");
    out->extra_count = l->intermediate_count;
    for (uint32_t k = 0; k < l->intermediate_count; k++) {
        const sl_cluster_intermediate *m = &l->intermediates[k];
        out->extras[k] = (simplify_extra){m->vertex_count, m->triangle_count, m->positions,
                                          m->source, m->triangles};
    }
    cluster_figures(&out->figures, l);
    if (l->boundary_edges || l->nonmanifold_edges || l->nonmanifold_vertices)
        fprintf(stderr, "scanlod simplify: note: kept %" PRIu64 " boundary edges (straightened "
                "within the bound), %" PRIu64 " non-manifold edges and %" PRIu64 " non-manifold "
                "vertices (unchanged); --strict refuses them\n", l->boundary_edges,
                l->nonmanifold_edges, l->nonmanifold_vertices);
    return 0;
}

static void cluster_release(simplify_output *out)
{
    if (out->state)
        sl_cluster_level_release(out->state);
    free(out->state);
    free(out->extras);
}

const simplify_method sl_simplify_cluster = {
    "cluster",
    "  cluster (paper 2; docs/clustering.md): --max-error bounds the symmetric Hausdorff\n"
    "  distance to the input (proven; measure it with `scanlod compare`)\n"
    "    --passes P          clustering passes, each on the previous one's output (1)\n"
    "    --intermediates M   also write M intermediate models OUT_1 .. OUT_M (morphing)\n"
    "    --max-angle D       a face's normal within D degrees of its cluster's (60)\n"
    "    --slab-share S      share of each pass tolerance for cluster thickness (0.7)\n",
    cluster_reset, cluster_parse, cluster_check, cluster_run, cluster_release,
};
