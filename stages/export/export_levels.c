/* Per-level work of the export stage: cut, write, measure, report (export.h). */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

static int write_files(const sl_export_config *c, const sl_export_level *lv,
                       const sl_lod_mesh *mesh, const char *extras, const sl_stage_io *io,
                       sl_error *err)
{
    static const char *const exts[4] = {"ply", "glb", "obj", "png"};
    const int wanted[4] = {c->write_ply, c->write_glb, c->write_obj, c->thumbnail_size > 0};
    int rc = 0;
    for (int i = 0; i < 4 && rc == 0; i++) {
        if (!wanted[i])
            continue;
        char file[sizeof lv->name + 8], path[PATH_MAX];
        snprintf(file, sizeof file, "%s.%s", lv->name, exts[i]);
        rc = sl_stage_path(path, io->out_dir, file, err);
        if (rc == 0)
            rc = i < 3 ? sl_export_write_mesh(path, mesh, extras, err)
                       : sl_export_thumbnail(path, mesh, c->thumbnail_size, err);
    }
    return rc;
}

/* One level's line of the collection summary. */
typedef struct level_row {
    uint32_t k;
    uint64_t triangles, vertices;
    int watertight, measured, thumbnail;
    double rms, hausdorff; /* fractions of the input's diagonal, when measured */
} level_row;

static int measure_level(const sl_export_config *c, const sl_mesh *input, const sl_lod_mesh *mesh,
                         const sl_stage_io *io, sl_json *r, level_row *row, sl_error *err)
{
    sl_mesh view = sl_export_mesh_view(mesh);
    sl_mesh_topology topo;
    int rc = sl_mesh_topology_compute(&view, &topo, err);
    if (rc)
        return rc;
    sl_json_u64(r, "boundary_edges", topo.boundary_edges);
    sl_json_u64(r, "nonmanifold_edges", topo.nonmanifold_edges);
    sl_json_bool(r, "watertight", topo.watertight);
    sl_json_u64(r, "components", topo.components);
    sl_json_double(r, "largest_component_area_fraction",
                   topo.area > 0 ? topo.largest_component_area / topo.area : 0);
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
        sl_json_double(r, "rms", d.fraction.rms);
        sl_json_double(r, "hausdorff", d.fraction.hausdorff);
        sl_json_double(r, "mean", d.fraction.mean);
        row->measured = 1;
        row->rms = d.fraction.rms;
        row->hausdorff = d.fraction.hausdorff;
    }
    return 0;
}

/* The item's section of OUTPUT/summary.md: paper Table 1 for this item (a row per level)
 * and its thumbnails, linked relative to OUTPUT/. The engine concatenates the sections. */
static int write_summary_section(const sl_export_config *c, const sl_lod_model *model,
                                 const sl_mesh *input, const level_row *rows,
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
    fprintf(md, ".\n\n| level | k | triangles | vertices | RMS | Hausdorff | watertight |\n"
                "|---|---:|---:|---:|---:|---:|---|\n");
    for (int i = 0; i < c->level_count; i++) {
        const level_row *w = &rows[i];
        fputs("| ", md);
        sl_md_text(md, c->levels[i].name);
        fprintf(md, " | %u | %llu | %llu |", w->k, (unsigned long long)w->triangles,
                (unsigned long long)w->vertices);
        if (w->measured)
            fprintf(md, " %.3f %% | %.3f %% |", 100 * w->rms, 100 * w->hausdorff);
        else
            fputs(" – | – |", md);
        fprintf(md, " %s |\n", w->watertight ? "yes" : "no");
    }
    fputc('\n', md);
    int thumbnails = 0;
    for (int i = 0; i < c->level_count; i++)
        if (rows[i].thumbnail) {
            fputs(thumbnails++ ? " ![" : "![", md);
            sl_md_text(md, io->item);
            fputc(' ', md);
            sl_md_text(md, c->levels[i].name);
            fputs("](<", md);
            sl_md_link(md, io->item);
            fputc('/', md);
            sl_md_link(md, c->levels[i].name);
            fputs(".png>)", md);
        }
    if (thumbnails)
        fputs("\n\n", md);
    fclose(md);
    char path[PATH_MAX];
    int rc = text ? sl_stage_path(path, io->out_dir, "summary-item.md", err)
                  : sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = sl_write_file_atomic(path, text, size, err);
    free(text);
    return rc;
}

int sl_export_levels(const sl_export_config *c, sl_lod_model *model, const sl_mesh *input,
                     const sl_stage_io *io, sl_error *err)
{
    sl_json *r = io->report;
    uint64_t finest = model->accumulation[model->expansion_count];
    sl_json_u64(r, "expansions", model->expansion_count);
    sl_json_u64(r, "triangles_finest", finest);
    sl_json_bool(r, "fidelity_measured", input != NULL);
    sl_json_array_begin(r, "levels");
    level_row *rows = calloc((size_t)c->level_count + 1, sizeof *rows);
    if (!rows)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    int rc = 0;
    for (int i = 0; i < c->level_count && rc == 0; i++) {
        const sl_export_level *lv = &c->levels[i];
        uint32_t k = lv->by_percent ? sl_lod_expansions_for_percent(model, lv->percent)
                                    : sl_lod_expansions_for_triangles(model, lv->budget);
        if ((rc = sl_stage_step(io, "export", (double)i / c->level_count, err)))
            break;
        sl_lod_mesh mesh;
        uint64_t cracks = 0;
        if (sl_lod_generate(model, k, &mesh, &cracks)) {
            rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
            break;
        }
        char extras[256];
        snprintf(extras, sizeof extras,
                 "{\"scanlod\":{\"level\":\"%s\",\"expansions\":%u,\"of\":%u}}", lv->name, k,
                 model->expansion_count);
        sl_json_object_begin(r, NULL);
        sl_json_string(r, "name", lv->name);
        if (lv->by_percent)
            sl_json_double(r, "lod_percent", lv->percent);
        else {
            sl_json_u64(r, "budget", lv->budget);
            sl_json_bool(r, "clamped", lv->budget >= finest);
        }
        sl_json_u64(r, "expansions", k);
        sl_json_u64(r, "triangles", mesh.triangle_count);
        sl_json_u64(r, "vertices", mesh.vertex_count);
        sl_json_double(r, "max_error", model->error_after[k]);
        sl_json_u64(r, "unpatched_cells", cracks);
        level_row *row = &rows[i];
        row->k = k;
        row->triangles = mesh.triangle_count;
        row->vertices = mesh.vertex_count;
        row->thumbnail = mesh.triangle_count && c->thumbnail_size > 0;
        rc = mesh.triangle_count ? write_files(c, lv, &mesh, extras, io, err) : 0;
        if (rc == 0)
            rc = measure_level(c, input, &mesh, io, r, row, err);
        sl_json_object_end(r);
        sl_lod_mesh_release(&mesh);
    }
    sl_json_array_end(r);
    if (rc == 0)
        rc = write_summary_section(c, model, input, rows, io, err);
    free(rows);
    return rc;
}
