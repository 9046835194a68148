/* crack stage entry (crack.h). */
#include <assert.h>
#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_io.h"
#include "runtime/octree_io.h"
#include "stages/crack/crack.h"
#include "stages/merge/merge.h"
#include "stages/priority/priority.h"

/* 2: dual models (runtime/lod_dual.h): their accumulation table counts dual triangles;
 * model format 2.
 * 3: model format 3 (packed parts, no neighbour table).
 * 4: a dual model's transition cells split a loop that runs along a split edge and
 * crosses the same face again (sl_mc_split_double_passes): more triangles in those cuts,
 * so an older table no longer equals what is generated.
 * 5: model format 4 (no node errors and areas), pieces packed at zstd level 6 (was 9).
 * 6: model format 5 (LOD order, checked pieces: a cut reads a prefix, lod_prefix.h).
 * 7: format 5's node crossing ids may name the parent's transition record's (a smaller
 * model; the first format 5 readers refuse such a file as corrupt).
 * (Unchanged by priority.slpri format 3: the same model from the same inputs.) */
#define CRACK_STAGE_VERSION 7u

static int crack_configure(const sl_config *cfg, void **out, sl_error *err)
{
    (void)cfg;
    *out = calloc(1, sizeof(sl_crack_config));
    return *out ? 0 : sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
}

sl_crack_config sl_crack_default_config(void)
{
    sl_crack_config c;
    sl_stage_default_config(&sl_crack_stage, &c, sizeof c);
    return c;
}

#ifndef NDEBUG
/* The accumulation table counts exactly the triangles generation draws (both use the
 * runtime's cell rule): checked in Debug builds on the coarsest, a middle and the finest
 * cut of every model the stage makes. A model read from a file is not trusted this way
 * (its table is only checked for range): this is where the invariant is made. */
static void check_accumulation(sl_lod_model *m)
{
    if (sl_lod_model_prepare(m)) /* laid out for generating, as a reader would */
        return;
    uint32_t ks[3] = {0, m->expansion_count / 2, m->expansion_count};
    for (int i = 0; i < 3; i++) {
        sl_lod_mesh mesh;
        if (sl_lod_generate(m, ks[i], &mesh, NULL) == 0) {
            assert(mesh.triangle_count == m->accumulation[ks[i]]);
            sl_lod_mesh_release(&mesh);
        }
    }
}
#endif

static int crack_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    (void)config;
    const char *merge_dir = sl_stage_dir(io, "merge");
    if (!merge_dir)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "crack stage needs the merge stage");
    char octree_path[PATH_MAX], priority_path[PATH_MAX], out_path[PATH_MAX];
    sl_lod_model model;
    sl_lod_model_init(&model);
    sl_priority p;
    memset(&p, 0, sizeof p);
    int rc = sl_stage_path(octree_path, merge_dir, SL_OCTREE_FILE, err);
    if (rc == 0)
        rc = sl_stage_path(priority_path, io->in_dir, SL_PRIORITY_FILE, err);
    if (rc == 0)
        rc = sl_stage_path(out_path, io->out_dir, SL_MODEL_FILE, err);
    if (rc == 0)
        rc = sl_octree_read(octree_path, &model.tree, err);
    if (rc == 0)
        rc = sl_priority_read(priority_path, &model.tree, &p, err);
    /* The node errors and areas ordered the expansions (the priority file has its own);
     * no reader of the model asks for them (model format 4: 21-23 % of a model's bytes). */
    sl_octree_drop_node_metrics(&model.tree);
    uint64_t unresolved = 0;
    if (rc == 0)
        rc = sl_stage_step(io, "crack: transitions", 0.1, err);
    if (rc == 0 && sl_transitions_build(&model.tree, &p.neighbours, &model.transitions, &unresolved))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0) {
        /* The model takes over the priority stage's arrays. */
        model.expansion_count = p.expansion_count;
        model.lod_array = p.lod_array;
        model.neighbours = p.neighbours;
        p.lod_array = NULL;
        memset(&p.neighbours, 0, sizeof p.neighbours);
        rc = sl_stage_step(io, "crack: accumulation", 0.5, err);
    }
    if (rc == 0)
        rc = sl_lod_model_finish(&model, p.expansion_error, err);
#ifndef NDEBUG
    if (rc == 0)
        check_accumulation(&model);
#endif
    if (rc == 0) { /* what writing does not read goes before it packs the model */
        model.neighbour_links = p.neighbour_links;
        sl_priority_release(&p);
        sl_neighbours_release(&model.neighbours);
        /* The expansion indices the tables were drawn with (and, in Debug builds, the
         * layout check_accumulation made): the writer reads the tree, the records and the
         * tables, not these. */
        sl_lod_model_drop_layout(&model);
        rc = sl_stage_step(io, "crack: write", 0.8, err);
        if (rc == 0)
            rc = sl_lod_model_write(out_path, &model, CRACK_STAGE_VERSION, err);
    }
    if (rc == 0) {
        sl_json_u64(io->report, "transition_words", model.transitions.count);
        sl_json_u64(io->report, "finer_samples_missing", unresolved);
        sl_json_u64(io->report, "triangles_coarsest", model.accumulation[0]);
        sl_json_u64(io->report, "triangles_finest", model.accumulation[model.expansion_count]);
    }
    sl_priority_release(&p);
    sl_lod_model_release(&model);
    return rc;
}

const sl_stage sl_crack_stage = {
    .name = "crack",
    .methods = SL_METHOD_OCTREE,
    .description = "LOD array -> crack compensation records and the LOD model (paper 1 2.4)",
    .version = CRACK_STAGE_VERSION,
    .options = NULL,
    .configure = crack_configure,
    .release_config = free,
    .run = crack_run,
};
