/* The samples stage's registry entry: options of [octree] and [samples], configure, run,
 * report. The work itself: samples_plan.c (grid), samples_cubes.c (which vertices),
 * samples_distance.c (the signed samples), shim/vdb_shim.cpp (the .vdb file).
 *
 * The report holds only deterministic counts (it is part of the stage's committed
 * outputs); the seconds per phase go to the log and to `_phases.json` in the artifact
 * directory, which the commit record ignores like the engine's own `_stats.json`.
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/atomicfile.h"
#include "core/log.h"
#include "stages/samples/samples_internal.h"

#define STRING_(x) #x
#define STRING(x) STRING_(x)

static const sl_option samples_options[] = {
    {"octree", "leaf_size", SL_OPT_DOUBLE, "0", 0, 1e30, NULL,
     "Edge length of the finest (leaf) marching cubes, in the input's world units. "
     "0 = derived from [octree] depth, or else from the point spacing (spacing_factor)."},
    {"octree", "depth", SL_OPT_INT, "0", 0, SL_SAMPLES_MAX_DEPTH, NULL,
     "Octree depth when leaf_size is 0: the bounding box's longest side plus the band on "
     "both sides is cut into 2^depth leaf cubes. 0 = leaf size from the point spacing."},
    {"octree", "spacing_factor", SL_OPT_DOUBLE, "1.5", 0.5, 64, NULL,
     "Automatic leaf size = this x the mean nearest-neighbour spacing of the points, at "
     "most the bounding box's diagonal / " STRING(SL_SAMPLES_DIAGONAL_LEAVES) " (a mesh of "
     "a few large triangles) "
     "(docs/samples-stage.md has the measurements behind the default)."},
    {"octree", "max_depth", SL_OPT_INT, "16", 1, SL_SAMPLES_MAX_DEPTH, NULL,
     "Items whose leaf size needs a deeper octree are refused (limit error, quarantined): "
     "it bounds memory on a huge extent with tiny features."},
    {"samples", "closest", SL_OPT_ENUM, "triangles", 0, 0, "triangles|points",
     "Where a grid vertex's closest point comes from. 'triangles' (meshes; point clouds "
     "always use their points): the nearest point of the input's triangles, signed by the "
     "pseudonormal of the face, edge or vertex it lies on, sample = the exact signed "
     "distance; every cube the surface passes through is sampled, so a closed mesh gives a "
     "closed surface. 'points': the nearest input point (paper 1 section 2.1), with "
     "[samples] distance and sign_neighbours."},
    {"samples", "distance", SL_OPT_ENUM, "tangent", 0, 0, "euclidean|tangent",
     "closest = points only. Sample magnitude at a grid vertex v with closest point p: "
     "'euclidean' = |v - p| "
     "(paper 1 section 2.1); 'tangent' = |(v - p) . n_p|, the distance to p's tangent plane. "
     "Measured in docs/samples-stage.md."},
    {"samples", "band", SL_OPT_INT, "1", 0, SL_SAMPLES_MAX_BAND, NULL,
     "Cubes holding points are dilated by this many cubes (26-neighbourhood) and every "
     "vertex of the dilated set is sampled; 0 = only the cubes holding points (paper)."},
    {"samples", "max_samples", SL_OPT_INT, "2147483648", 1, 1099511627776.0, NULL,
     "Items needing more samples (grid vertices) are refused (limit error, quarantined) "
     "before the memory is allocated."},
    {"samples", "sign_neighbours", SL_OPT_INT, "1", 1, 64, NULL,
     "closest = points only. 1 = the sign of a sample comes from its closest point's "
     "normal (paper); k > 1 = a "
     "vote of the k nearest points' normals weighted by inverse distance."},
    SL_OPTION_END,
};

static const char *const samples_sections[] = {"samples", "octree", NULL};

static int samples_configure(const sl_config *cfg, void **stage_config, sl_error *err)
{
    sl_samples_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory");
    c->leaf_size = sl_config_double(cfg, "octree", "leaf_size");
    c->depth = (int)sl_config_int(cfg, "octree", "depth");
    c->spacing_factor = sl_config_double(cfg, "octree", "spacing_factor");
    c->max_depth = (int)sl_config_int(cfg, "octree", "max_depth");
    c->distance = strcmp(sl_config_string(cfg, "samples", "distance"), "euclidean") == 0
                      ? SL_SAMPLES_EUCLIDEAN
                      : SL_SAMPLES_TANGENT;
    c->closest = strcmp(sl_config_string(cfg, "samples", "closest"), "points") == 0
                     ? SL_SAMPLES_CLOSEST_POINTS
                     : SL_SAMPLES_CLOSEST_TRIANGLES;
    c->band = (int)sl_config_int(cfg, "samples", "band");
    c->max_samples = (uint64_t)sl_config_int(cfg, "samples", "max_samples");
    c->sign_neighbours = (int)sl_config_int(cfg, "samples", "sign_neighbours");
    const char *file = sl_config_path(cfg);
    if (c->depth > c->max_depth || (c->depth > 0 && (1 << c->depth) <= 2 * c->band)) {
        sl_error_set(err, SL_E_CONFIG, 0, file[0] ? file : NULL,
                     "[octree] depth %d needs max_depth >= depth and 2^depth > 2 x [samples] "
                     "band (max_depth %d, band %d)", c->depth, c->max_depth, c->band);
        free(c);
        return SL_E_CONFIG;
    }
    *stage_config = c;
    return SL_OK;
}

sl_samples_config sl_samples_default_config(void)
{
    sl_samples_config c;
    sl_stage_default_config(&sl_samples_stage, &c, sizeof c);
    return c;
}

static void report_counts(sl_json *j, const sl_samples_config *cfg, const sl_samples_counts *c,
                          int colors)
{
    const sl_samples_plan *p = &c->plan;
    sl_json_double(j, "leaf_size", p->leaf_size);
    sl_json_u64(j, "depth", (uint64_t)p->depth);
    sl_json_array_begin(j, "origin");
    for (int k = 0; k < 3; k++)
        sl_json_double(j, NULL, p->origin[k]);
    sl_json_array_end(j);
    sl_json_array_begin(j, "cells");
    for (int k = 0; k < 3; k++)
        sl_json_u64(j, NULL, p->cells[k]);
    sl_json_array_end(j);
    sl_json_u64(j, "band", (uint64_t)p->band);
    sl_json_string(j, "closest", c->triangles ? "triangles" : "points");
    sl_json_u64(j, "triangles", c->triangles);
    sl_json_u64(j, "triangle_cube_keys", c->triangle_keys);
    sl_json_string(j, "distance", c->triangles ? "exact"
                                  : cfg->distance == SL_SAMPLES_TANGENT ? "tangent"
                                                                        : "euclidean");
    sl_json_u64(j, "sign_neighbours", (uint64_t)cfg->sign_neighbours);
    sl_json_u64(j, "points", c->points);
    sl_json_u64(j, "occupied_cubes", c->occupied_cubes);
    sl_json_u64(j, "band_cubes", c->band_cubes);
    sl_json_u64(j, "samples", c->samples);
    sl_json_u64(j, "inside", c->inside);
    sl_json_u64(j, "outside", c->outside);
    sl_json_u64(j, "sign_flips", c->sign_flips);
    sl_json_bool(j, "closed_surface", c->closed_surface);
    sl_json_u64(j, "sign_repairs", c->sign_repairs);
    sl_json_bool(j, "colors", colors);
}

/* Seconds per phase: the log and `_phases.json` (not in the report: see the top). */
static void record_phases(const sl_stage_io *io, const sl_samples_counts *c, double write_s)
{
    char text[256], path[PATH_MAX];
    int n = snprintf(text, sizeof text,
                     "{\"plan_s\":%.3f,\"cubes_s\":%.3f,\"tree_s\":%.3f,\"samples_s\":%.3f,"
                     "\"write_s\":%.3f}\n", c->seconds_plan, c->seconds_cubes, c->seconds_tree,
                     c->seconds_samples, write_s);
    SL_LOG(SL_LOG_INFO, "samples", io->item,
           "%llu samples (leaf %g, depth %d): plan %.3f s, cubes %.3f s, tree %.3f s, "
           "samples %.3f s, write %.3f s", (unsigned long long)c->samples, c->plan.leaf_size,
           c->plan.depth, c->seconds_plan, c->seconds_cubes, c->seconds_tree, c->seconds_samples,
           write_s);
    sl_error ignored;
    sl_error_init(&ignored);
    if (n > 0 && (size_t)n < sizeof text &&
        sl_stage_path(path, io->out_dir, "_phases.json", &ignored) == SL_OK)
        sl_write_file_atomic(path, text, (size_t)n, &ignored); /* best effort: diagnostics */
}

/* The whole stage (io->parts = 0), a part of it (io->part >= 0) or the join of its parts;
 * the samples in `samples`, the counts in `counts`. */
static int compute(const sl_samples_config *cfg, const sl_stage_io *io, char path[PATH_MAX],
                   sl_vdb_samples *samples, sl_samples_counts *counts, int *colors,
                   sl_error *err)
{
    memset(samples, 0, sizeof *samples); /* released by the caller whatever happens */
    sl_vdb_set_threads(io->threads); /* OpenVDB's TBB pool next to our OpenMP threads */
    const char *range_dir = sl_stage_dir(io, "range"); /* the range stage's artifacts */
    if (!range_dir)
        range_dir = io->in_dir ? io->in_dir : ".";
    sl_pointset ps;
    int rc = sl_stage_path(path, range_dir, SL_POINTSET_FILE, err);
    if (rc == SL_OK)
        rc = sl_pointset_read(path, &ps, err);
    if (rc != SL_OK)
        return rc;
    samples_parts parts = {io->part_dirs, io->parts};
    sl_samples_split split = {io->part, io->parts, NULL, NULL};
    if (io->parts > 1 && io->part < 0) {
        split.fill = samples_parts_fill;
        split.ctx = &parts;
    }
    rc = sl_samples_compute_split(cfg, &ps, io->parts > 1 ? &split : NULL, samples, counts,
                                  io->progress, err);
    if (rc != SL_OK && !err->file[0]) { /* the failure is about the points file */
        size_t n = strlen(path) < sizeof err->file ? strlen(path) : sizeof err->file - 1;
        memcpy(err->file, path, n);
        err->file[n] = '\0';
    }
    *colors = ps.colors != NULL;
    sl_pointset_release(&ps);
    return rc;
}

/* The stage's run (is_part 0: the whole stage, or the join of its parts) and run_part
 * (is_part 1: one part's run of vertices into samples.part, docs/engine.md "Parts"). */
static int run_samples(const void *stage_config, const sl_stage_io *io, int is_part,
                       sl_error *err)
{
    const sl_samples_config *cfg = stage_config;
    char path[PATH_MAX];
    sl_vdb_samples samples;
    sl_samples_counts counts;
    int colors = 0;
    int rc = compute(cfg, io, path, &samples, &counts, &colors, err);
    if (rc == SL_OK)
        rc = sl_stage_step(io, "write", 0.95, err);
    double t0 = omp_get_wtime();
    if (rc == SL_OK)
        rc = sl_stage_path(path, io->out_dir, is_part ? SL_SAMPLES_PART_FILE : SL_SAMPLES_FILE,
                           err);
    if (rc == SL_OK)
        rc = is_part ? samples_part_write(path, &samples, io->part, io->parts,
                                          counts.closed_surface, counts.sign_flips, err)
                     : sl_vdb_samples_write(path, &samples, err);
    uint64_t first = 0, end = 0;
    if (is_part)
        sl_samples_part_range(samples.count, io->part, io->parts, &first, &end);
    sl_vdb_samples_release(&samples);
    if (rc != SL_OK)
        return rc;
    if (is_part) {
        sl_json_u64(io->report, "part", (uint64_t)io->part);
        sl_json_u64(io->report, "parts", (uint64_t)io->parts);
        sl_json_u64(io->report, "samples", counts.samples);
        sl_json_u64(io->report, "first", first);
        sl_json_u64(io->report, "count", end - first);
        return SL_OK;
    }
    report_counts(io->report, cfg, &counts, colors);
    record_phases(io, &counts, omp_get_wtime() - t0);
    return SL_OK;
}

static int samples_run(const void *stage_config, const sl_stage_io *io, sl_error *err)
{
    return run_samples(stage_config, io, 0, err);
}

static int samples_run_part(const void *stage_config, const sl_stage_io *io, sl_error *err)
{
    return run_samples(stage_config, io, 1, err);
}

const sl_stage sl_samples_stage = {
    .name = "samples",
    .methods = SL_METHOD_OCTREE,
    .description = "oriented points -> signed samples at leaf-cube vertices, OpenVDB grids "
                   "(paper 1 section 2.1)",
    .version = 3, /* 3: automatic leaf at most the diagonal / SL_SAMPLES_DIAGONAL_LEAVES */
    .options = samples_options,
    .sections = samples_sections,
    .configure = samples_configure,
    .release_config = free,
    .run = samples_run,
    .run_part = samples_run_part,
};
