/* The published levels (export_internal.h): every level of the refine stage's level list
 * (levels/level.h) written, measured and reported, whichever method made it. Normals are
 * the area-weighted normals of each level's own faces; colours are the level's. Thumbnails
 * are rendered for the levels, not for the intermediate models; atlases are baked for both
 * when the input is textured. Identical meshes are published once (under a level's name
 * before an intermediate's). The manifest (scene.svx.json) and the pages cover the levels;
 * the intermediate models are in the report, summary.md and the files. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/hash.h"
#include "core/json.h"
#include "core/markdown.h"
#include "stages/export/export_internal.h"

/* A level as the writers take it: its arrays, and normals drawn from its faces (the
 * caller frees `normals`). */
static int view_of(const sl_level *lv, sl_lod_mesh *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    out->vertex_count = lv->vertex_count;
    out->triangle_count = lv->triangle_count;
    out->positions = lv->positions;
    out->indices = lv->triangles;
    out->colors = lv->colors;
    out->normals = malloc(3 * (lv->vertex_count ? lv->vertex_count : 1) * sizeof *out->normals);
    if (!out->normals)
        return sl_error_nomem(err, NULL, "level %s", lv->name);
    sl_mesh_vertex_normals(lv->positions, lv->vertex_count, lv->triangles, lv->triangle_count,
                           out->normals);
    return 0;
}

static int intermediate(const sl_level *lv)
{
    return (lv->flags & SL_LEVEL_INTERMEDIATE) != 0;
}

static int proven(const sl_level *lv)
{
    return (lv->flags & SL_LEVEL_PROVEN) != 0;
}

sl_export_digest sl_export_digest_mesh(const sl_lod_mesh *m)
{
    sl_export_digest d;
    memset(&d, 0, sizeof d); /* no padding bytes left undefined: digests are compared whole */
    d.vertices = m->vertex_count;
    d.triangles = m->triangle_count;
    size_t v = (size_t)m->vertex_count, t = (size_t)m->triangle_count;
    d.positions = sl_hash_bytes(m->positions, v * 3 * sizeof *m->positions);
    d.normals = m->normals ? sl_hash_bytes(m->normals, v * 3 * sizeof *m->normals) : d.normals;
    d.colors = m->colors ? sl_hash_bytes(m->colors, v * 4) : d.colors;
    d.indices = sl_hash_bytes(m->indices, t * 3 * sizeof *m->indices);
    return d;
}

static void report_rung(const sl_level *m, sl_json *r)
{
    if (m->rung.kind == SL_RUNG_SHARE)
        sl_json_double(r, "lod_percent", m->rung.percent);
    if (m->rung.kind == SL_RUNG_EXPANSIONS)
        sl_json_double(r, "expansion_percent", m->rung.percent);
    sl_json_u64(r, "budget", m->budget);
    sl_json_bool(r, "clamped", (m->flags & SL_LEVEL_CLAMPED) != 0);
    sl_json_bool(r, "reached", (m->flags & SL_LEVEL_REACHED) != 0);
}

static void report_mesh(const sl_level *m, sl_json *r)
{
    sl_json_string(r, "name", m->name);
    sl_json_string(r, "method", m->method);
    sl_json_bool(r, "intermediate", intermediate(m));
    sl_json_string(r, "from", m->from[0] ? m->from : NULL);
    if (!intermediate(m))
        report_rung(m, r);
    sl_json_bool(r, "scan", (m->flags & SL_LEVEL_SCAN) != 0);
    sl_json_bool(r, "refined", (m->flags & SL_LEVEL_REFINED) != 0);
    sl_json_u64(r, "triangles", m->triangle_count);
    sl_json_u64(r, "vertices", m->vertex_count);
    if (!strcmp(m->method, "octree")) {
        sl_json_u64(r, "expansions", m->expansions);
        sl_json_double(r, "max_error", m->bound);
        sl_json_u64(r, "unpatched_cells", m->unpatched_cells);
    }
    if (proven(m)) {
        sl_json_double(r, "bound", m->bound_fraction);
        sl_json_double(r, "bound_world", m->bound);
    }
}

/* The item's section of OUTPUT/summary.md: a row per level and intermediate model. */
static int write_summary(const sl_level_list *list, const sl_export_result *rows,
                         int thumbnails, const sl_stage_io *io, sl_error *err)
{
    char *text = NULL;
    size_t size = 0;
    FILE *md = open_memstream(&text, &size);
    if (!md)
        return sl_error_nomem(err, NULL, "out of memory");
    fputs("### ", md);
    sl_md_text(md, io->item);
    fprintf(md, "\n\nInput: %llu triangles", (unsigned long long)list->input_triangles);
    if (list->model_expansions)
        fprintf(md, "; LOD model: %u expansions, %llu triangles at the finest level",
                list->model_expansions, (unsigned long long)list->model_triangles);
    fputs(".\n\n| level | made by | triangles | vertices | bound | RMS | Hausdorff | watertight "
          "| files |\n|---|---|---:|---:|---:|---:|---:|---|---|\n", md);
    for (uint32_t i = 0; i < list->count; i++) {
        const sl_level *m = &list->levels[i];
        fputs("| ", md);
        sl_md_text(md, m->name);
        fputs(" | ", md);
        sl_md_text(md, m->method);
        fprintf(md, " | %llu | %llu |", (unsigned long long)m->triangle_count,
                (unsigned long long)m->vertex_count);
        if (proven(m))
            fprintf(md, " %.3f %% |", 100 * m->bound_fraction);
        else
            fputs(" – |", md);
        if (rows[i].measured)
            fprintf(md, " %.3f %% | %.3f %% |", 100 * rows[i].rms, 100 * rows[i].hausdorff);
        else
            fputs(" – | – |", md);
        fprintf(md, " %s | ", rows[i].watertight ? "yes" : "no");
        if (rows[i].file >= 0)
            sl_md_text(md, list->levels[rows[i].file].name);
        else
            fputs("–", md);
        fputs(" |\n", md);
    }
    fputc('\n', md);
    for (uint32_t i = 0, n = 0; thumbnails && i < list->count; i++)
        if (rows[i].file == (int)i && !intermediate(&list->levels[i]))
            sl_export_md_thumbnail(md, io->item, list->levels[i].name, n++ == 0);
    if (thumbnails)
        fputs("\n\n", md);
    fclose(md);
    return sl_export_write_summary_item(io, text, size, err);
}

/* Of two levels with one mesh, the one whose name the files take: a level before an
 * intermediate model, a share (lodP, kP) before a count, the larger share, else the
 * earlier. */
static int names_files_before(const sl_level_list *list, int a, int b)
{
    const sl_level *x = &list->levels[a], *y = &list->levels[b];
    if (intermediate(x) != intermediate(y))
        return !intermediate(x);
    int xs = x->rung.kind != SL_RUNG_TRIANGLES, ys = y->rung.kind != SL_RUNG_TRIANGLES;
    if (xs != ys)
        return xs;
    if (xs && x->rung.percent != y->rung.percent)
        return x->rung.percent > y->rung.percent;
    return a < b;
}

/* Which levels are the same mesh (rows[i].file, -1 without triangles): each read once. */
static int plan_meshes(const sl_level_list *list, const char *dir, sl_export_result *rows,
                       sl_error *err)
{
    sl_export_digest *digests = calloc(list->count ? list->count : 1, sizeof *digests);
    if (!digests)
        return sl_error_nomem(err, NULL, "out of memory");
    int rc = 0;
    for (uint32_t i = 0; i < list->count && rc == 0; i++) {
        sl_level lv;
        sl_level_copy_record(&lv, &list->levels[i]);
        sl_lod_mesh mesh;
        rc = sl_level_read_mesh(dir, &lv, list->input_points, err);
        if (rc == 0 && (rc = view_of(&lv, &mesh, err)) == 0) {
            digests[i] = sl_export_digest_mesh(&mesh);
            free(mesh.normals);
        }
        rows[i].triangles = lv.triangle_count;
        rows[i].vertices = lv.vertex_count;
        sl_level_release_mesh(&lv);
    }
    for (uint32_t i = 0; i < list->count && rc == 0; i++) {
        rows[i].file = rows[i].triangles ? (int)i : -1;
        for (uint32_t j = 0; j < list->count && rows[i].triangles; j++)
            if (!memcmp(&digests[j], &digests[i], sizeof *digests) &&
                names_files_before(list, (int)j, rows[i].file))
                rows[i].file = (int)j;
    }
    free(digests);
    return rc;
}

/* [export] morph: the published level (not an intermediate model) next coarser than
 * published level i, the one with the most triangles below i's; else -1. The paper's
 * intermediate models are their own morph and get none. */
static int morph_coarser(const sl_export_config *c, const sl_level_list *list,
                         const sl_export_result *rows, uint32_t i)
{
    if (!c->morph || !c->write_glb || intermediate(&list->levels[i]) || rows[i].file != (int)i)
        return -1;
    int best = -1;
    for (uint32_t j = 0; j < list->count; j++)
        if (!intermediate(&list->levels[j]) && rows[j].file == (int)j && rows[j].triangles &&
            rows[j].triangles < rows[i].triangles &&
            (best < 0 || rows[j].triangles > rows[best].triangles))
            best = (int)j;
    return best;
}

/* A level's mesh read, with its normals; release with drop(). */
static int load(const sl_level_list *list, const char *dir, uint32_t i, sl_level *lv,
                sl_lod_mesh *mesh, sl_error *err)
{
    sl_level_copy_record(lv, &list->levels[i]);
    memset(mesh, 0, sizeof *mesh);
    int rc = sl_level_read_mesh(dir, lv, list->input_points, err);
    if (rc == 0)
        rc = view_of(lv, mesh, err);
    return rc;
}

static void drop(sl_level *lv, sl_lod_mesh *mesh)
{
    free(mesh->normals);
    memset(mesh, 0, sizeof *mesh);
    sl_level_release_mesh(lv);
}

/* Writes and measures one distinct mesh; its GLB morphs to level `to` (>= 0). */
static int one_mesh(const sl_export_config *c, const sl_level_list *list, const char *dir,
                    uint32_t i, int to, const sl_distance_reference *fidelity,
                    const sl_export_frame *frame,
                    const sl_export_texture *texture, const sl_stage_io *io,
                    sl_export_result *row, sl_error *err)
{
    sl_level lv, coarser_lv;
    sl_lod_mesh mesh, coarser;
    memset(&coarser_lv, 0, sizeof coarser_lv);
    memset(&coarser, 0, sizeof coarser);
    int rc = load(list, dir, i, &lv, &mesh, err);
    if (rc == 0 && to >= 0)
        rc = load(list, dir, (uint32_t)to, &coarser_lv, &coarser, err);
    row->morph_to = to;
    row->k = lv.expansions;
    sl_export_config files = *c; /* intermediates: meshes, no thumbnails */
    if (intermediate(&lv))
        files.thumbnail_size = 0;
    sl_export_level name;
    memset(&name, 0, sizeof name);
    memcpy(name.name, lv.name, sizeof name.name); /* both 32 bytes, NUL-terminated */
    char extras[256];
    if (proven(&lv))
        snprintf(extras, sizeof extras,
                 "{\"scanlod\":{\"level\":\"%s\",\"method\":\"%s\",\"bound\":%.9g}}", lv.name,
                 lv.method, lv.bound_fraction);
    else
        snprintf(extras, sizeof extras, "{\"scanlod\":{\"level\":\"%s\",\"method\":\"%s\"}}",
                 lv.name, lv.method);
    if (rc == 0) /* the files and the measures, after the level's read (its own phase) */
        rc = sl_stage_step(io, "export: write levels", (double)i / list->count, err);
    if (rc == 0)
        rc = sl_export_write_level(&files, &name, &mesh, lv.texcoords,
                                   to >= 0 ? &coarser : NULL, extras, fidelity, frame, texture, io,
                                   row, err);
    drop(&lv, &mesh);
    drop(&coarser_lv, &coarser);
    return rc;
}

static void report_meshes(const sl_export_config *c, const sl_level_list *list,
                          const sl_export_result *rows, const sl_export_frame *frame, sl_json *r)
{
    sl_json_array_begin(r, "levels");
    for (uint32_t i = 0; i < list->count; i++) {
        const sl_level *m = &list->levels[i];
        sl_json_object_begin(r, NULL);
        report_mesh(m, r);
        sl_export_report_result(c, frame, &rows[i],
                                rows[i].file >= 0 ? list->levels[rows[i].file].name : NULL,
                                m->bound, r);
        if (rows[i].morph_to >= 0)
            sl_json_string(r, "morph_to", list->levels[rows[i].morph_to].name);
        if (rows[i].measured && proven(m)) /* the proven bound, checked by the measure (whose
                                              own closest points round at 1e-16 of the
                                              diagonal) */
            sl_json_bool(r, "bound_holds", rows[i].hausdorff <= m->bound_fraction + 1e-12);
        sl_json_object_end(r);
    }
    sl_json_array_end(r);
}

/* The manifest and the pages, over the levels (not the intermediate models): the export
 * configuration with the list's levels, and their results. */
static int manifest_and_pages(const sl_export_config *c, const sl_level_list *list,
                              const sl_export_result *rows, const sl_mesh *input,
                              const sl_export_frame *frame, const sl_stage_io *io,
                              sl_error *err)
{
    sl_export_config *lc = malloc(sizeof *lc);
    sl_export_result *lr = calloc(SL_EXPORT_MAX_LEVELS, sizeof *lr);
    int at[SL_EXPORT_MAX_LEVELS];
    int rc = lc && lr ? 0 : sl_error_nomem(err, NULL, "out of memory");
    if (rc == 0) {
        *lc = *c;
        lc->level_count = 0;
    }
    for (uint32_t i = 0; rc == 0 && i < list->count; i++) {
        const sl_level *m = &list->levels[i];
        if (intermediate(m))
            continue;
        if (lc->level_count == SL_EXPORT_MAX_LEVELS) {
            rc = sl_error_corrupt(err, SL_LEVEL_LIST_FILE, "more than %d levels",
                                  SL_EXPORT_MAX_LEVELS);
            break;
        }
        sl_export_level *lv = &lc->levels[lc->level_count];
        memset(lv, 0, sizeof *lv);
        memcpy(lv->name, m->name, sizeof lv->name);
        memcpy(lv->method, m->method, sizeof lv->method);
        lv->by_percent = m->rung.kind != SL_RUNG_TRIANGLES;
        lv->percent = m->rung.percent;
        lv->budget = m->budget;
        lv->scan = (m->flags & SL_LEVEL_SCAN) != 0;
        lr[lc->level_count] = rows[i];
        at[lc->level_count++] = (int)i;
    }
    /* file and morph_to: a list index -> a level index (both are always levels). */
    for (int l = 0; rc == 0 && l < lc->level_count; l++) {
        int f = lr[l].file, t = lr[l].morph_to;
        lr[l].file = lr[l].morph_to = -1;
        for (int k = 0; k < lc->level_count; k++) {
            if (f >= 0 && at[k] == f)
                lr[l].file = k;
            if (t >= 0 && at[k] == t)
                lr[l].morph_to = k;
        }
    }
    int level_of_quality[SL_EXPORT_QUALITIES];
    sl_export_item item = {lc, list, input, lr, level_of_quality, frame, io};
    if (rc == 0) {
        sl_export_map_qualities(lc, lr, level_of_quality);
        rc = sl_export_manifest(&item, err);
    }
    if (rc == 0)
        rc = sl_export_html(&item, err);
    free(lr);
    free(lc);
    return rc;
}

int sl_export_level_list(const sl_export_config *c, const char *list_dir, int model,
                         const sl_mesh *input, const sl_distance_reference *fidelity,
                         const sl_export_frame *frame,
                         const sl_export_texture *texture, const sl_stage_io *io, sl_error *err)
{
    sl_level_list list;
    int rc = sl_level_list_read(list_dir, &list, err);
    if (rc)
        return rc;
    if (!model) /* the pages say a model is there by its size */
        list.model_expansions = 0;
    sl_export_result *rows = calloc(list.count ? list.count : 1, sizeof *rows);
    if (!rows)
        rc = sl_error_nomem(err, NULL, "out of memory");
    if (rc == 0)
        rc = plan_meshes(&list, list_dir, rows, err);
    /* Each distinct mesh: its files and its measures, once. */
    for (uint32_t i = 0; i < list.count && rc == 0; i++)
        rows[i].morph_to = -1;
    for (uint32_t i = 0; i < list.count && rc == 0; i++) {
        rc = sl_stage_step(io, "export: read levels", (double)i / list.count, err);
        if (rc == 0 && rows[i].file == (int)i)
            rc = one_mesh(c, &list, list_dir, i, morph_coarser(c, &list, rows, i), fidelity, frame,
                          texture, io, &rows[i], err);
    }
    for (uint32_t i = 0; i < list.count && rc == 0; i++)
        if (rows[i].file >= 0 && rows[i].file != (int)i)
            rows[i] = rows[rows[i].file]; /* the same mesh: the same files and measures */
    if (rc == 0) {
        sl_json *r = io->report;
        sl_json_u64(r, "input_triangles", list.input_triangles);
        sl_json_double(r, "input_diagonal", list.diagonal); /* world: the input's units */
        if (list.model_expansions) {
            sl_json_u64(r, "expansions", list.model_expansions);
            sl_json_u64(r, "triangles_finest", list.model_triangles);
        }
        sl_json_bool(r, "fidelity_measured", input != NULL);
        report_meshes(c, &list, rows, frame, r);
        rc = sl_stage_step(io, "export: pages", 0.95, err);
        if (rc == 0)
            rc = write_summary(&list, rows, c->thumbnail_size > 0, io, err);
    }
    if (rc == 0)
        rc = manifest_and_pages(c, &list, rows, input, frame, io, err);
    free(rows);
    sl_level_list_release(&list);
    return rc;
}
