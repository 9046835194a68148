/* merge stage entry: samples.vdb -> octree.slot (paper 1, section 2.2; merge.h). */
#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_distance.h"
#include "runtime/octree_io.h"
#include "shim/vdb_shim.h"
#include "stages/merge/merge.h"
#include "stages/range/range.h"
#include "stages/samples/samples.h"

/* 2: refuses an octree whose grid its readers would refuse (SL_OCTREE_MAX_EXTENT), so a
 * work folder holding such an octree from version 1 rebuilds it and quarantines the item
 * instead of failing at the next stage on every run.
 * 3: refuses samples whose finest level has no triangle (issue 16: such items were
 * published as a success with empty levels); a work folder from version 2 rebuilds.
 * 4: octree format 2; optional dual vertices from quadrics of the input surface
 * ([octree] vertices = qef, the default since every cut of a qef model of a closed scan
 * is watertight; mc, paper 1's triangles, by config: docs/lod.md, Vertices from
 * quadrics). The default's change needs no new version: the config is part of the key. */
#define MERGE_STAGE_VERSION 4u

static const sl_option merge_options[] = {
    {"merge", "max_samples", SL_OPT_INT, "2147483647", 1, 4294967295.0, NULL,
     "Refuse sample grids with more samples than this (memory guard: about 60 bytes per "
     "sample while the octree is built)."},
    {"octree", "vertices", SL_OPT_ENUM, "qef", 0, 0, "mc|qef",
     "Where a level's vertices go. 'qef' (the default): one vertex per marching-cube loop "
     "of a cell, where the quadric of the input surface the loop stands for is least (dual "
     "contouring of the cell's surface: sharp edges and corners kept, vertices on the "
     "scan, an open scan trimmed at its border; docs/lod.md, Vertices from quadrics). "
     "'mc': paper 1's marching-cube triangles, vertices on the cell edges."},
    {"octree", "qef_tau", SL_OPT_DOUBLE, "0.02", 0.0001, 0.9, NULL,
     "qef: directions in which the quadric is flatter than this fraction of its steepest "
     "are left at the surface's mean point (keeps vertices of flat and smooth parts on "
     "their surface; smaller follows weaker features, and noise)."},
    SL_OPTION_END,
};

static const char *const merge_sections[] = {"merge", "octree", NULL};

static int merge_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_merge_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    c->max_samples = (uint64_t)sl_config_int(cfg, "merge", "max_samples");
    c->qef_vertices = !strcmp(sl_config_string(cfg, "octree", "vertices"), "qef");
    c->qef_tau = sl_config_double(cfg, "octree", "qef_tau");
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
    sl_json_string(r, "vertices", sl_octree_dual(t) ? "qef" : "mc");
    if (sl_octree_dual(t))
        sl_json_u64(r, "dual_vertices", t->vertex_count);
}

/* Whether the mesh has boundary edges (an open scan). */
static int surface_open(const sl_pointset *ps, sl_error *err, int *open)
{
    sl_mesh view = sl_mesh_view(ps->count, ps->positions, NULL, NULL, ps->triangle_count,
                                ps->triangles);
    sl_mesh_topology topo;
    int rc = sl_mesh_topology_compute(&view, &topo, err);
    *open = rc == 0 && topo.boundary_edges > 0;
    return rc;
}

/* The quadric vertices, from the range stage's points (and triangles). */
static int place_vertices(const sl_merge_config *c, const sl_stage_io *io, sl_octree *tree,
                          sl_error *err)
{
    const char *range_dir = sl_stage_dir(io, "range");
    if (!range_dir)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "merge needs the range stage's points");
    char path[PATH_MAX];
    sl_pointset ps;
    int rc = sl_stage_path(path, range_dir, SL_POINTSET_FILE, err);
    if (rc == 0)
        rc = sl_stage_step(io, "merge: read points", 0.7, err);
    if (rc == 0)
        rc = sl_pointset_read(path, &ps, err);
    if (rc)
        return rc;
    int open = 0;
    if (ps.triangle_count)
        rc = surface_open(&ps, err, &open);
    sl_surface s = {ps.count, ps.positions, ps.normals, ps.colors, ps.triangle_count,
                    ps.triangles, ps.mean_spacing * ps.mean_spacing, open};
    if (rc == 0)
        rc = sl_stage_step(io, "merge: vertices", 0.8, err);
    if (rc == 0)
        rc = sl_octree_vertices(tree, &s, c->qef_tau, SL_VERTEX_BRICK_LEVEL, err);
    if (rc == 0)
        sl_json_bool(io->report, "trimmed_open_surface", open);
    sl_pointset_release(&ps);
    return rc;
}

static void release_samples(void *samples)
{
    sl_vdb_samples_release(samples);
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
        rc = sl_stage_step(io, "merge: read samples", 0.0, err);
    if (rc == 0)
        rc = sl_vdb_samples_read(in_path, c->max_samples, &samples, err);
    if (rc)
        return rc;
    /* the leaves, until the build's first level step ("merge") */
    if ((rc = sl_stage_step(io, "merge: leaves", 0.05, err)) != 0) {
        sl_vdb_samples_release(&samples);
        return rc;
    }
    sl_sample_grid grid = {samples.count, samples.coords, samples.distance, samples.colors,
                           samples.leaf_size,
                           {samples.origin[0], samples.origin[1], samples.origin[2]}};
    sl_octree tree;
    rc = sl_octree_build_releasing(&grid, release_samples, &samples, &tree, io->progress, err);
    sl_vdb_samples_release(&samples);
    if (rc)
        return rc;
    if (c->qef_vertices)
        rc = place_vertices(c, io, &tree, err);
    if (rc == 0)
        rc = sl_stage_step(io, "merge: write", 0.95, err);
    if (rc == 0)
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
    .sections = merge_sections,
    .configure = merge_configure,
    .release_config = free,
    .run = merge_run,
};
