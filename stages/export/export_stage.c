/* export stage entry: levels, files, fidelity and the summary row (export.h). */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/atomicfile.h"
#include "geometry/mesh_distance.h"
#include "geometry/ply.h"
#include "runtime/lod_io.h"
#include "stages/crack/crack.h"
#include "stages/export/export_internal.h"

/* 4: report.json gives each level's connected parts and the largest one's share of the area. */
#define EXPORT_STAGE_VERSION 4u

static const sl_option export_options[] = {
    {"export", "lod_percents", SL_OPT_LIST, "20,40,60,80,100", 0, 100, NULL,
     "Levels by LOD percent, as in the paper's Table 1: P% of the LOD array's expansions "
     "of nodes with surface below them are done (empty band cells change nothing and are "
     "not counted; 100 = the finest level). Empty for none."},
    {"export", "budgets", SL_OPT_LIST, "thumb:2000,low:20000,medium:100000,high:500000", 0, 0,
     NULL,
     "Named triangle budgets (name:triangles), as museum web viewers use: the largest level "
     "within each budget. A budget above the finest level gives the finest (\"clamped\" in "
     "the report). A name becomes the level's file names: letters, digits, '.', '_' and '-', "
     "starting with a letter or digit, and no two levels (budgets or lodP percents) alike. "
     "Empty for none."},
    {"export", "formats", SL_OPT_LIST, "ply,glb", 0, 0, "ply|glb|obj",
     "Mesh files written per level: any of ply, glb, obj (empty: none, only thumbnails and "
     "the report)."},
    {"export", "thumbnail_size", SL_OPT_INT, "256", 0, 4096, NULL,
     "Edge of the square PNG thumbnail rendered per level, in pixels; 0 = none."},
    {"export", "fidelity", SL_OPT_BOOL, "true", 0, 0, NULL,
     "Measure every level against the input surface (symmetric Hausdorff and RMS distance, "
     "fractions of the input's bounding-box diagonal). Inputs without faces are not "
     "measured."},
    {"export", "fidelity_samples", SL_OPT_INT, "200000", 1000, 100000000, NULL,
     "Area samples per surface for the fidelity measurement."},
    SL_OPTION_END,
};

static int export_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_export_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    int rc = sl_export_parse_levels(sl_config_string(cfg, "export", "lod_percents"),
                                    sl_config_string(cfg, "export", "budgets"), c, err);
    /* The config checked every element against ply|glb|obj; the canonical list is
     * "a,b,c", so a name is in it when it is a whole element. */
    char formats[64];
    snprintf(formats, sizeof formats, ",%s,", sl_config_string(cfg, "export", "formats"));
    c->write_ply = strstr(formats, ",ply,") != NULL;
    c->write_glb = strstr(formats, ",glb,") != NULL;
    c->write_obj = strstr(formats, ",obj,") != NULL;
    c->thumbnail_size = (int)sl_config_int(cfg, "export", "thumbnail_size");
    c->fidelity = sl_config_bool(cfg, "export", "fidelity");
    c->fidelity_samples = (uint64_t)sl_config_int(cfg, "export", "fidelity_samples");
    if (rc) {
        free(c);
        return rc;
    }
    *out = c;
    return 0;
}

sl_export_config sl_export_default_config(void)
{
    sl_export_config c;
    sl_stage_default_config(&sl_export_stage, &c, sizeof c);
    return c;
}

static int export_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const sl_export_config *c = config;
    char model_path[PATH_MAX], published[PATH_MAX];
    sl_lod_model model;
    int rc = sl_stage_path(model_path, io->in_dir, SL_MODEL_FILE, err);
    if (rc == 0)
        rc = sl_stage_path(published, io->out_dir, SL_MODEL_FILE, err);
    if (rc == 0)
        rc = sl_lod_model_read(model_path, &model, err);
    if (rc)
        return rc;
    sl_mesh input;
    sl_mesh_init(&input);
    int measure = c->fidelity;
    if (measure) {
        sl_error ierr;
        sl_error_init(&ierr);
        /* The range stage already validated the input; a point cloud has nothing to
         * compare surfaces with. */
        if (sl_ply_read(io->source_path, NULL, &input, NULL, NULL, &ierr) != 0 ||
            input.triangle_count == 0 || sl_mesh_check_surface(&input, NULL, &ierr) != 0)
            measure = 0;
    }
    rc = sl_link_or_copy(model_path, published, err);
    if (rc == 0)
        rc = sl_export_levels(c, &model, measure ? &input : NULL, io, err);
    sl_mesh_release(&input);
    sl_lod_model_release(&model);
    return rc;
}

const sl_stage sl_export_stage = {
    .name = "export",
    .methods = SL_METHODS_ALL,
    .description = "LOD model -> meshes (PLY, GLB), thumbnails, fidelity report (paper 1 3)",
    .version = EXPORT_STAGE_VERSION,
    .options = export_options,
    .configure = export_configure,
    .release_config = free,
    .run = export_run,
    .publish = 1,
};
