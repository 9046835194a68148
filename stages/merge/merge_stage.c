/* merge stage entry: samples.vdb -> octree.slot (paper 1, section 2.2; merge.h). */
#include <errno.h>
#include <limits.h>
#include <stdlib.h>

#include "runtime/octree_io.h"
#include "shim/vdb_shim.h"
#include "stages/merge/merge.h"
#include "stages/samples/samples.h"

/* 2: refuses an octree whose grid its readers would refuse (SL_OCTREE_MAX_EXTENT), so a
 * work folder holding such an octree from version 1 rebuilds it and quarantines the item
 * instead of failing at the next stage on every run.
 * 3: refuses samples whose finest level has no triangle (issue 16: such items were
 * published as a success with empty levels); a work folder from version 2 rebuilds. */
#define MERGE_STAGE_VERSION 3u

static const sl_option merge_options[] = {
    {"merge", "max_samples", SL_OPT_INT, "2147483647", 1, 4294967295.0, NULL,
     "Refuse sample grids with more samples than this (memory guard: about 60 bytes per "
     "sample while the octree is built)."},
    SL_OPTION_END,
};

static int merge_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_merge_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    c->max_samples = (uint64_t)sl_config_int(cfg, "merge", "max_samples");
    *out = c;
    return 0;
}

sl_merge_config sl_merge_default_config(void)
{
    sl_merge_config c;
    sl_stage_default_config(&sl_merge_stage, &c, sizeof c);
    return c;
}

static void report_octree(sl_json *r, const sl_octree *t)
{
    sl_json_double(r, "leaf_size", t->leaf_size);
    sl_json_u64(r, "depth", t->depth);
    sl_json_u64(r, "nodes", t->node_count);
    sl_json_array_begin(r, "nodes_per_level");
    for (uint32_t l = 0; l <= t->depth; l++)
        sl_json_u64(r, NULL, t->level_count[l]);
    sl_json_array_end(r);
    sl_json_u64(r, "crossings", t->crossing_count);
    sl_json_u64(r, "inherited_crossings", t->stats.inherited_crossings);
    sl_json_u64(r, "fallback_crossings", t->stats.fallback_crossings);
    sl_json_object_begin(r, "parent_sign_cases");
    sl_json_u64(r, "A_corresponding", t->stats.sign_case[0]);
    sl_json_u64(r, "B_adjacent", t->stats.sign_case[1]);
    sl_json_u64(r, "C_diagonal", t->stats.sign_case[2]);
    sl_json_u64(r, "D_centre", t->stats.sign_case[3]);
    sl_json_object_end(r);
    sl_json_bool(r, "colors", t->crossing_color != NULL);
}

static int merge_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const sl_merge_config *c = config;
    char in_path[PATH_MAX], out_path[PATH_MAX];
    int rc = sl_stage_path(in_path, io->in_dir, SL_SAMPLES_FILE, err);
    if (rc == 0)
        rc = sl_stage_path(out_path, io->out_dir, SL_OCTREE_FILE, err);
    sl_vdb_samples samples;
    sl_vdb_set_threads(io->threads); /* OpenVDB's TBB pool reads the grids: cap it */
    if (rc == 0)
        rc = sl_vdb_samples_read(in_path, c->max_samples, &samples, err);
    if (rc)
        return rc;
    sl_sample_grid grid = {samples.count, samples.coords, samples.distance, samples.colors,
                           samples.voxel_size,
                           {samples.origin[0], samples.origin[1], samples.origin[2]}};
    sl_octree tree;
    rc = sl_octree_build(&grid, &tree, io->progress, err);
    sl_vdb_samples_release(&samples);
    if (rc)
        return rc;
    rc = sl_octree_write(out_path, &tree, MERGE_STAGE_VERSION, err);
    if (rc == 0)
        report_octree(io->report, &tree);
    sl_octree_release(&tree);
    return rc;
}

const sl_stage sl_merge_stage = {
    .name = "merge",
    .methods = SL_METHOD_OCTREE,
    .description = "signed samples -> marching-cube octree (paper 1 section 2.2)",
    .version = MERGE_STAGE_VERSION,
    .options = merge_options,
    .configure = merge_configure,
    .release_config = free,
    .run = merge_run,
};
