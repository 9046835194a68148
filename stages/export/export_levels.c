/* Per-level work of the export stage: cut, write, measure, report (export.h). */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "core/atomicfile.h"
#include "core/markdown.h"
#include "geometry/mesh_distance.h"
#include "stages/export/export_internal.h"

/* A level's name becomes its file names (NAME.ply, NAME.png) in the item's folder: letters,
 * digits, '.', '_' and '-', starting with a letter or digit, so that no name can reach
 * outside the folder, hide a file or need quoting. */
static int good_level_name(const char *name)
{
    if (!isalnum((unsigned char)name[0]))
        return 0;
    for (const char *p = name; *p; p++)
        if (!isalnum((unsigned char)*p) && !strchr("._-", *p))
            return 0;
    return 1;
}

int sl_export_parse_levels(const char *percents, const char *budgets, sl_export_config *c,
                           sl_error *err)
{
    const char *lists[2] = {percents, budgets};
    for (int l = 0; l < 2; l++) {
        const char *p = lists[l];
        while (p && *p) {
            char word[64];
            size_t n = strcspn(p, ",");
            snprintf(word, sizeof word, "%.*s", (int)(n < sizeof word ? n : sizeof word - 1), p);
            p += n + (p[n] == ',');
            if (!word[0])
                continue;
            if (c->level_count == SL_EXPORT_MAX_LEVELS)
                return sl_error_set(err, SL_E_CONFIG, 0, "[export]", "more than %d levels",
                                    SL_EXPORT_MAX_LEVELS);
            sl_export_level *lv = &c->levels[c->level_count];
            char *end;
            if (l == 0) {
                lv->by_percent = 1;
                lv->percent = strtod(word, &end);
                if (*end || lv->percent < 0 || lv->percent > 100)
                    return sl_error_set(err, SL_E_CONFIG, 0, "[export] lod_percents",
                                        "'%s' is not a percent in [0, 100]", word);
                snprintf(lv->name, sizeof lv->name, "lod%g", lv->percent);
            } else {
                char *colon = strchr(word, ':');
                if (!colon || colon == word || colon - word >= (long)sizeof lv->name)
                    return sl_error_set(err, SL_E_CONFIG, 0, "[export] budgets",
                                        "'%s' is not name:triangles", word);
                *colon = '\0';
                long long v = strtoll(colon + 1, &end, 10);
                if (*end || v < 1)
                    return sl_error_set(err, SL_E_CONFIG, 0, "[export] budgets",
                                        "'%s': the budget must be a whole number >= 1", word);
                snprintf(lv->name, sizeof lv->name, "%.31s", word);
                lv->budget = (uint64_t)v;
                if (!good_level_name(lv->name))
                    return sl_error_set(err, SL_E_CONFIG, 0, "[export] budgets",
                                        "'%s': a level name is letters, digits, '.', '_' "
                                        "and '-', starting with a letter or digit", lv->name);
            }
            for (int j = 0; j < c->level_count; j++)
                if (!strcmp(c->levels[j].name, lv->name))
                    return sl_error_set(err, SL_E_CONFIG, 0,
                                        l ? "[export] budgets" : "[export] lod_percents",
                                        "two levels are named '%s' (their files would overwrite "
                                        "each other)", lv->name);
            c->level_count++;
        }
    }
    return 0;
}

/* The level's GLB geometry: the level itself, or with a baked atlas its per-triangle
 * charts (three vertices per triangle) with texture coordinates and the image. */
static sl_lod_mesh glb_geometry(const sl_lod_mesh *mesh, const sl_export_baked *baked,
                                sl_export_glb *glb)
{
    if (!baked || !baked->image)
        return *mesh;
    glb->texcoords = baked->texcoords;
    glb->options.image = baked->image;
    glb->options.image_size = baked->image_size;
    glb->options.image_mime_type = baked->mime_type;
    sl_lod_mesh g = {baked->vertex_count, baked->triangle_count, baked->positions,
                     baked->normals, NULL, baked->triangles};
    return g; /* vertex colours would multiply the texture: left out */
}

static int write_files(const sl_export_config *c, const sl_export_level *lv,
                       const sl_lod_mesh *mesh, const sl_export_baked *baked, const char *extras,
                       const sl_export_glb *level_glb, sl_glb_stats *stats,
                       const sl_stage_io *io, sl_error *err)
{
    sl_export_glb glb = *level_glb;
    sl_lod_mesh textured = glb_geometry(mesh, baked, &glb);
    static const char *const exts[4] = {"ply", "glb", "obj", "png"};
    const int wanted[4] = {c->write_ply, c->write_glb, c->write_obj, c->thumbnail_size > 0};
    int rcs[4] = {0};
    sl_error errs[4];
    /* The four files are independent (each its own bytes, the GLB's stats its own), so they
     * are written as tasks: the GLB's vertex-cache order and the thumbnail were the
     * export's serial path (a one-thread main loop while the cut ahead ran beside it).
     * The first failure in file order is reported, whatever finished first. */
#pragma omp parallel num_threads(omp_in_parallel() ? 1 : omp_get_max_threads())
#pragma omp single
    for (int i = 0; i < 4; i++) {
        sl_error_init(&errs[i]);
        if (!wanted[i])
            continue;
#pragma omp task firstprivate(i)
        {
            char file[sizeof lv->name + 8], path[PATH_MAX];
            snprintf(file, sizeof file, "%s.%s", lv->name, exts[i]);
            sl_error *e = &errs[i];
            int r = sl_stage_path(path, io->out_dir, file, e);
            if (r == 0)
                r = i == 1 ? sl_export_write_mesh(path, &textured, extras, &glb, stats, e)
                    : i < 3 ? sl_export_write_mesh(path, mesh, extras, &glb, NULL, e)
                            : sl_export_thumbnail(path, mesh, c->thumbnail_size, glb.z_up, e);
            rcs[i] = r;
        }
    }
    for (int i = 0; i < 4; i++)
        if (rcs[i]) {
            *err = errs[i];
            return rcs[i];
        }
    return 0;
}

/* The GLB's encoding and what quantisation did to it, in the input's units and as
 * fractions of the input's diagonal (0 when not measured): the bound is added to the
 * level's errors, since no point of the published surface is further than it from the
 * point of the unquantised level it came from. */
static void report_glb(sl_json *r, const sl_export_config *c, const sl_glb_stats *g,
                       double to_metres, double max_error, double diagonal,
                       double hausdorff, int measured)
{
    static const char *const names[] = {"none", "meshopt", "draco"};
    double bound = g->position_bound / to_metres, worst = g->position_error_max / to_metres;
    sl_json_object_begin(r, "glb");
    sl_json_string(r, "compression", names[c->glb.compression]);
    sl_json_bool(r, "quantized", c->glb.quantize || c->glb.compression == SL_GLB_DRACO);
    sl_json_u64(r, "vertices", g->vertices);
    sl_json_u64(r, "triangles", g->triangles);
    sl_json_double(r, "position_step_world", g->position_step / to_metres);
    sl_json_double(r, "quantization_bound_world", bound);
    sl_json_double(r, "quantization_error_world", worst);
    sl_json_double(r, "quantization_rms_world", g->position_error_rms / to_metres);
    if (diagonal > 0) {
        sl_json_double(r, "quantization_bound", bound / diagonal);
        sl_json_double(r, "quantization_error", worst / diagonal);
    }
    sl_json_double(r, "normal_error_deg", g->normal_error_max_deg);
    sl_json_double(r, "color_error_srgb_steps", g->color_error_max);
    sl_json_double(r, "max_error", max_error + bound);
    if (g->morph) { /* how far weight 1 lands from the coarser level's surface point */
        sl_json_double(r, "morph_error_world", g->morph_error_max / to_metres);
        sl_json_u64(r, "morph_added_triangles", g->morph_added_triangles);
        sl_json_u64(r, "morph_unresolved_triangles", g->morph_unresolved);
        sl_json_u64(r, "morph_torn_triangles", g->morph_torn_triangles);
        sl_json_double(r, "morph_tear_world", g->morph_tear_max / to_metres);
    }
    if (measured)
        sl_json_double(r, "hausdorff", hausdorff + bound / diagonal);
    sl_json_object_end(r);
}

static int measure_level(const sl_export_config *c, const sl_mesh *input, const sl_lod_mesh *mesh,
                         const sl_stage_io *io, sl_export_result *row, sl_error *err)
{
    sl_mesh view = sl_export_mesh_view(mesh);
    sl_mesh_topology topo;
    int rc = sl_mesh_topology_compute(&view, &topo, err);
    if (rc)
        return rc;
    row->boundary_edges = topo.boundary_edges;
    row->nonmanifold_edges = topo.nonmanifold_edges;
    row->components = topo.components;
    row->largest_area_fraction = topo.area > 0 ? topo.largest_component_area / topo.area : 0;
    row->watertight = topo.watertight;
    if (!input || mesh->triangle_count == 0)
        return 0;
    sl_mesh_distance_config dc = sl_mesh_distance_default_config();
    dc.samples = c->fidelity_samples;
    sl_mesh_distance d;
    sl_error derr;
    sl_error_init(&derr);
    rc = sl_mesh_distance_compute(input, &view, &dc, &d, io->progress, &derr);
    if (rc == SL_E_INTERRUPTED || rc == SL_E_NOMEM) {
        sl_error_merge(err, &derr);
        return rc;
    }
    if (rc == 0) {
        row->measured = 1;
        row->rms = d.fraction.rms;
        row->hausdorff = d.fraction.hausdorff;
        row->mean = d.fraction.mean;
        row->diagonal = d.diagonal;
    }
    return 0;
}

/* The item's section of OUTPUT/summary.md: paper Table 1 for this item (a row per level)
 * and its thumbnails, linked relative to OUTPUT/. The engine concatenates the sections. */
static int write_summary_section(const sl_export_config *c, const sl_lod_model *model,
                                 const sl_mesh *input, const sl_export_result *rows,
                                 const sl_stage_io *io, sl_error *err)
{
    char *text = NULL;
    size_t size = 0;
    FILE *md = open_memstream(&text, &size);
    if (!md)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    fputs("### ", md);
    sl_md_text(md, io->item);
    fprintf(md, "\n\nLOD model: %u expansions, %llu triangles at the finest level",
            model->expansion_count,
            (unsigned long long)model->accumulation[model->expansion_count]);
    if (input)
        fprintf(md, "; input: %llu triangles", (unsigned long long)input->triangle_count);
    fprintf(md, ".\n\n| level | k | triangles | vertices | RMS | Hausdorff | watertight | files |\n"
                "|---|---:|---:|---:|---:|---:|---|---|\n");
    for (int i = 0; i < c->level_count; i++) {
        const sl_export_result *w = &rows[i];
        fputs("| ", md);
        sl_md_text(md, c->levels[i].name);
        fprintf(md, " | %u | %llu | %llu |", w->k, (unsigned long long)w->triangles,
                (unsigned long long)w->vertices);
        if (w->measured)
            fprintf(md, " %.3f %% | %.3f %% |", 100 * w->rms, 100 * w->hausdorff);
        else
            fputs(" – | – |", md);
        fprintf(md, " %s | ", w->watertight ? "yes" : "no");
        if (w->file >= 0)
            sl_md_text(md, c->levels[w->file].name);
        else
            fputs("–", md);
        fputs(" |\n", md);
    }
    fputc('\n', md);
    int thumbnails = 0;
    for (int i = 0; i < c->level_count; i++)
        if (rows[i].file == i && c->thumbnail_size > 0) {
            sl_export_md_thumbnail(md, io->item, c->levels[i].name, thumbnails++ == 0);
        }
    if (thumbnails)
        fputs("\n\n", md);
    fclose(md);
    return sl_export_write_summary_item(io, text, size, err);
}

void sl_export_md_thumbnail(FILE *md, const char *item, const char *name, int first)
{
    fputs(first ? "![" : " ![", md);
    sl_md_text(md, item);
    fputc(' ', md);
    sl_md_text(md, name);
    fputs("](<", md);
    sl_md_link(md, item);
    fputc('/', md);
    sl_md_link(md, name);
    fputs(".png>)", md);
}

int sl_export_write_summary_item(const sl_stage_io *io, char *text, size_t size, sl_error *err)
{
    char path[PATH_MAX];
    int rc = text ? sl_stage_path(path, io->out_dir, "summary-item.md", err)
                  : sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = sl_write_file_atomic(path, text, size, err);
    free(text);
    return rc;
}

/* Of two levels with one mesh, the one whose name the files take: a percent level before
 * a budget (lod100 is the finest level's name whatever the budgets), the larger percent
 * first, else the earlier budget. */
static int names_files_before(const sl_export_config *c, int a, int b)
{
    const sl_export_level *x = &c->levels[a], *y = &c->levels[b];
    if (x->by_percent != y->by_percent)
        return x->by_percent;
    if (x->by_percent && x->percent != y->percent)
        return x->percent > y->percent;
    return a < b;
}

/* With morph targets (each level needs to know its coarser published level before it is
 * written): every level's k, counts and mesh digest first; then which levels share a mesh
 * and whose name their files take (rows[i].file). Each level is then cut twice. */
static int plan_levels(const sl_export_config *c, sl_export_cutter *cutter, const sl_stage_io *io,
                       sl_export_result *rows, uint64_t *cracks, sl_error *err)
{
    sl_export_digest *digests = calloc((size_t)c->level_count + 1, sizeof *digests);
    if (!digests)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    for (int i = 0; i < c->level_count; i++) {
        const sl_export_level *lv = &c->levels[i];
        int rc = sl_stage_step(io, "export", 0, err);
        if (rc) {
            free(digests);
            return rc;
        }
        sl_export_level_k(cutter, lv, &rows[i]);
        sl_lod_mesh mesh;
        if ((rc = sl_export_cut_row(cutter, lv, &rows[i], &mesh, &cracks[i], err))) {
            free(digests);
            return rc;
        }
        rows[i].triangles = mesh.triangle_count;
        rows[i].vertices = mesh.vertex_count;
        digests[i] = sl_export_digest_mesh(&mesh);
        sl_lod_mesh_release(&mesh);
    }
    for (int i = 0; i < c->level_count; i++) {
        rows[i].file = rows[i].triangles ? i : -1;
        for (int j = 0; j < c->level_count && rows[i].triangles; j++)
            if (!memcmp(&digests[j], &digests[i], sizeof *digests) &&
                names_files_before(c, j, rows[i].file))
                rows[i].file = j;
    }
    free(digests);
    return 0;
}

/* Bakes the level's atlas when the input has a texture (and GLBs are written); reports
 * what it made in the row. 0, or SL_E_NOMEM/SL_E_INTERNAL. */
static int bake_level(const sl_export_config *c, const sl_export_texture *texture,
                      const sl_export_level *lv, const sl_lod_mesh *mesh, sl_export_result *row,
                      sl_export_baked *baked, sl_error *err)
{
    memset(baked, 0, sizeof *baked);
    if (!texture || !c->write_glb || mesh->triangle_count == 0)
        return 0;
    int wanted = sl_export_texture_size(c, lv->name);
    int rc = sl_export_bake(texture, mesh, wanted, c->texture_png, c->texture_quality, baked, err);
    if (rc < 0)
        return rc;
    row->texture = rc == 1 ? -1 : 1;
    if (rc == 0) {
        row->texture_size = baked->size;
        row->texture_mime = baked->mime_type;
        row->texture_bytes = baked->image_size;
        row->texture_cell = baked->cell;
        row->texel_efficiency = baked->texel_efficiency;
    }
    return 0;
}

/* The level's atlas, as bake_level left it in the row. */
static void report_texture(const sl_export_result *row, sl_json *r)
{
    sl_json_object_begin(r, "texture");
    if (row->texture < 0) {
        sl_json_string(r, "warning", "too many triangles for the atlas: vertex colours only");
    } else {
        sl_json_u64(r, "size", (uint64_t)row->texture_size);
        sl_json_string(r, "mime_type", row->texture_mime);
        sl_json_u64(r, "image_bytes", row->texture_bytes);
        sl_json_u64(r, "cell_texels", (uint64_t)row->texture_cell);
        sl_json_double(r, "texel_efficiency", row->texel_efficiency);
    }
    sl_json_object_end(r);
}

static void report_level(const sl_export_config *c, const sl_lod_model *model,
                         const sl_export_frame *frame, int i, const sl_export_result *row,
                         uint64_t cracks, sl_json *r)
{
    const sl_export_level *lv = &c->levels[i];
    sl_json_object_begin(r, NULL);
    sl_json_string(r, "name", lv->name);
    if (lv->by_percent)
        sl_json_double(r, "lod_percent", lv->percent);
    else {
        sl_json_u64(r, "budget", lv->budget);
        sl_json_bool(r, "clamped", lv->budget >= model->accumulation[model->expansion_count]);
    }
    sl_json_u64(r, "expansions", row->k);
    sl_json_bool(r, "capped", row->capped);
    sl_json_u64(r, "triangles", row->triangles);
    sl_json_u64(r, "vertices", row->vertices);
    sl_json_double(r, "max_error", model->error_after[row->k]);
    sl_json_u64(r, "unpatched_cells", cracks);
    if (c->min_part_area > 0) { /* shards left out (export_parts.c); the counts are after */
        sl_json_object_begin(r, "shards_dropped");
        sl_json_u64(r, "parts", row->dropped.parts);
        sl_json_u64(r, "triangles", row->dropped.triangles);
        sl_json_double(r, "area_fraction", row->dropped.area_fraction);
        sl_json_object_end(r);
    }
    sl_export_report_result(c, frame, row, row->file >= 0 ? c->levels[row->file].name : NULL,
                            model->error_after[row->k], r);
    if (row->morph_to >= 0)
        sl_json_string(r, "morph_to", c->levels[row->morph_to].name);
    sl_json_object_end(r);
}

void sl_export_report_result(const sl_export_config *c, const sl_export_frame *frame,
                             const sl_export_result *row, const char *file_name,
                             double max_error, sl_json *r)
{
    sl_json_u64(r, "boundary_edges", row->boundary_edges);
    sl_json_u64(r, "nonmanifold_edges", row->nonmanifold_edges);
    sl_json_bool(r, "watertight", row->watertight);
    sl_json_u64(r, "components", row->components);
    sl_json_double(r, "largest_component_area_fraction", row->largest_area_fraction);
    if (row->measured) {
        sl_json_double(r, "rms", row->rms);
        sl_json_double(r, "hausdorff", row->hausdorff);
        sl_json_double(r, "mean", row->mean);
    }
    /* The level whose files hold this mesh (docs/formats.md); null without triangles. */
    sl_json_string(r, "file", file_name);
    if (row->texture)
        report_texture(row, r);
    if (row->triangles && c->write_glb)
        report_glb(r, c, &row->glb, frame->to_metres, max_error, row->diagonal, row->hausdorff,
                   row->measured);
}

/* The levels in the order their files are named by (names_files_before): the first of
 * a set of levels with one mesh is the one whose name the files take. */
static void preference_order(const sl_export_config *c, int *order)
{
    for (int i = 0; i < c->level_count; i++) {
        int at = i;
        while (at > 0 && names_files_before(c, i, order[at - 1]))
            order[at] = order[at - 1], at--;
        order[at] = i;
    }
}

int sl_export_write_level(const sl_export_config *c, const sl_export_level *lv,
                          const sl_lod_mesh *mesh, const sl_lod_mesh *morph_to,
                          const char *extras, const sl_mesh *input,
                          const sl_export_frame *frame, const sl_export_texture *texture,
                          const sl_stage_io *io, sl_export_result *row, sl_error *err)
{
    sl_export_glb glb = {c->glb, frame->to_metres, frame->up == 'z', NULL, morph_to};
    row->triangles = mesh->triangle_count;
    row->vertices = mesh->vertex_count;
    sl_export_baked baked;
    int rc = bake_level(c, texture, lv, mesh, row, &baked, err);
    if (rc == 0 && mesh->triangle_count)
        rc = write_files(c, lv, mesh, &baked, extras, &glb, &row->glb, io, err);
    sl_export_baked_release(&baked);
    if (rc == 0)
        rc = measure_level(c, input, mesh, io, row, err);
    return rc;
}

int sl_export_levels(const sl_export_config *c, sl_lod_model *model, const sl_mesh *input,
                     uint64_t cap, const sl_export_frame *frame, const sl_export_texture *texture,
                     const sl_stage_io *io, sl_error *err)
{
    sl_json *r = io->report;
    sl_json_u64(r, "expansions", model->expansion_count);
    sl_json_u64(r, "triangles_finest", model->accumulation[model->expansion_count]);
    if (cap)
        sl_json_u64(r, "triangles_cap", cap);
    sl_json_bool(r, "fidelity_measured", input != NULL);
    sl_export_result *rows = calloc((size_t)c->level_count + 1, sizeof *rows);
    uint64_t *cracks = calloc((size_t)c->level_count + 1, sizeof *cracks);
    int rc = rows && cracks ? 0 : sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    int morph = c->morph && c->write_glb, order[SL_EXPORT_MAX_LEVELS];
    sl_export_digest *digests = calloc((size_t)c->level_count + 1, sizeof *digests);
    if (rc == 0 && !digests)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    sl_export_cutter cutter = {c, model, -1, cap};
    if (rc == 0 && morph)
        rc = plan_levels(c, &cutter, io, rows, cracks, err);
    for (int i = 0; i < c->level_count && rc == 0 && !morph; i++)
        sl_export_level_k(&cutter, &c->levels[i], &rows[i]);
    preference_order(c, order);
    for (int i = 0; i < c->level_count; i++) /* -1 unless the morph plan made the files */
        rows[i].morph_to = sl_export_morph_coarser(c, rows, i);
    /* Each distinct mesh: its files and its measures, once; the next one is cut while
     * this one is written (export_cuts.c). */
    sl_export_cut_job jobs[2] = {{.cutter = &cutter, .order = order, .rows = rows,
                                  .cracks = cracks, .digests = digests, .morph = morph,
                                  .threads = omp_get_max_threads()}};
    jobs[1] = jobs[0];
    if (rc == 0 && c->level_count > 0)
        sl_export_cut_job_start(&jobs[0], 0);
    for (int at = 0; at < c->level_count && rc == 0; at++) {
        sl_export_cut_job *job = &jobs[at & 1];
        if ((rc = sl_export_cut_job_finish(job, err)))
            break;
        if ((rc = sl_stage_step(io, "export", (double)at / c->level_count, err))) {
            sl_export_cut_job_release(job);
            break;
        }
        if (at + 1 < c->level_count)
            sl_export_cut_job_start(&jobs[(at + 1) & 1], at + 1);
        if (!job->own)
            continue;
        int i = order[at];
        char extras[256];
        snprintf(extras, sizeof extras,
                 "{\"scanlod\":{\"level\":\"%s\",\"expansions\":%u,\"of\":%u}}",
                 c->levels[i].name, rows[i].k, model->expansion_count);
        rc = sl_export_write_level(c, &c->levels[i], &job->mesh,
                                   rows[i].morph_to >= 0 ? &job->coarser : NULL, extras, input,
                                   frame, texture, io, &rows[i], err);
        sl_export_cut_job_release(job);
    }
    for (int j = 0; j < 2; j++) /* after a failed write: the cut ahead is dropped */
        sl_export_cut_job_cancel(&jobs[j]);
    free(digests);
    for (int i = 0; i < c->level_count && rc == 0; i++)
        if (rows[i].file >= 0 && rows[i].file != i) {
            sl_export_result own = rows[i];
            rows[i] = rows[own.file]; /* the same mesh: the same files and measures */
            rows[i].k = own.k;
        }
    sl_json_array_begin(r, "levels");
    for (int i = 0; i < c->level_count && rc == 0; i++)
        report_level(c, model, frame, i, &rows[i], cracks[i], r);
    sl_json_array_end(r);
    free(cracks);
    int level_of_quality[SL_EXPORT_QUALITIES];
    if (rc == 0) {
        sl_export_map_qualities(c, rows, level_of_quality);
        rc = write_summary_section(c, model, input, rows, io, err);
    }
    if (rc == 0)
        rc = sl_export_manifest(c, rows, level_of_quality, io, err);
    if (rc == 0)
        rc = sl_export_html(c, model, input, rows, level_of_quality, io, err);
    free(rows);
    return rc;
}
