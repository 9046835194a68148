/* Levels from a level list (export_internal.h): the cluster stage's levels and intermediate
 * models, or the segment stage's levels (stages/cluster/cluster.h, levels.sllev) written, measured and reported like the
 * octree's levels. Normals and colours come from the range stage's points (each level
 * vertex names the point it is, or was moved from): the input's shading on every level.
 * Thumbnails are rendered for the levels, not for the intermediate models; atlases are
 * baked for both when the input is textured. Identical meshes are published once (under
 * a level's name before an intermediate's). The manifest (scene.svx.json) and the pages
 * cover the levels; the intermediate models are in the report, summary.md and the files. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/atomicfile.h"
#include "core/json.h"
#include "core/markdown.h"
#include "stages/cluster/cluster.h"
#include "stages/export/export_internal.h"
#include "stages/range/range.h"

/* A list mesh as an sl_lod_mesh; normals and colours gathered from the points. */
static int view_of(const sl_cluster_list_mesh *m, const sl_pointset *ps, sl_lod_mesh *out)
{
    memset(out, 0, sizeof *out);
    size_t nv = m->vertex_count ? (size_t)m->vertex_count : 1;
    out->vertex_count = m->vertex_count;
    out->triangle_count = m->triangle_count;
    out->positions = m->positions;
    out->indices = m->triangles;
    out->normals = malloc(3 * nv * sizeof *out->normals);
    out->colors = ps->colors ? malloc(4 * nv) : NULL;
    if (!out->normals || (ps->colors && !out->colors))
        return -1;
    for (uint64_t v = 0; v < m->vertex_count; v++) {
        memcpy(out->normals + 3 * v, ps->normals + 3 * (uint64_t)m->source[v], 3 * sizeof(float));
        if (out->colors)
            memcpy(out->colors + 4 * v, ps->colors + 4 * (uint64_t)m->source[v], 4);
    }
    return 0;
}

/* The cluster method's bounds are proven (checked here against the measure); the segment
 * method's levels carry none. */
static int proven(const char *method)
{
    return strcmp(method, "cluster") == 0;
}

static void report_mesh(const sl_cluster_list_mesh *m, const char *method, sl_json *r)
{
    sl_json_string(r, "name", m->name);
    sl_json_bool(r, "intermediate", m->intermediate);
    sl_json_string(r, "from", m->from[0] ? m->from : NULL);
    if (!m->intermediate) {
        if (m->by_percent)
            sl_json_double(r, "lod_percent", m->percent);
        sl_json_u64(r, "budget", m->budget);
        sl_json_bool(r, "clamped", m->clamped);
        sl_json_bool(r, "reached", m->reached);
    }
    sl_json_u64(r, "triangles", m->triangle_count);
    sl_json_u64(r, "vertices", m->vertex_count);
    if (proven(method)) {
        sl_json_double(r, "bound", m->bound_fraction);
        sl_json_double(r, "bound_world", m->bound);
    }
}

/* The item's section of OUTPUT/summary.md: a row per level and intermediate model. */
static int write_summary(const sl_cluster_list *list, const char *method,
                         const sl_export_result *rows, int thumbnails, const sl_stage_io *io,
                         sl_error *err)
{
    char *text = NULL;
    size_t size = 0;
    FILE *md = open_memstream(&text, &size);
    if (!md)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    fputs("### ", md);
    sl_md_text(md, io->item);
    fprintf(md, "\n\n%s; input: %llu triangles.\n\n"
                "| level | triangles | vertices | bound | RMS | Hausdorff | watertight | files |\n"
                "|---|---:|---:|---:|---:|---:|---|---|\n",
            proven(method) ? "Clustering levels with bounded error (paper 2)"
                           : "Segmentation levels, planes kept exact (paper 3)",
            (unsigned long long)list->input_triangles);
    for (uint32_t i = 0; i < list->count; i++) {
        const sl_cluster_list_mesh *m = &list->meshes[i];
        fputs("| ", md);
        sl_md_text(md, m->name);
        fprintf(md, " | %llu | %llu |", (unsigned long long)m->triangle_count,
                (unsigned long long)m->vertex_count);
        if (proven(method))
            fprintf(md, " %.3f %% |", 100 * m->bound_fraction);
        else
            fputs(" – |", md);
        if (rows[i].measured)
            fprintf(md, " %.3f %% | %.3f %% |", 100 * rows[i].rms, 100 * rows[i].hausdorff);
        else
            fputs(" – | – |", md);
        fprintf(md, " %s | ", rows[i].watertight ? "yes" : "no");
        if (rows[i].file >= 0)
            sl_md_text(md, list->meshes[rows[i].file].name);
        else
            fputs("–", md);
        fputs(" |\n", md);
    }
    fputc('\n', md);
    for (uint32_t i = 0, n = 0; thumbnails && i < list->count; i++)
        if (rows[i].file == (int)i && !list->meshes[i].intermediate) {
            sl_export_md_thumbnail(md, io->item, list->meshes[i].name, n++ == 0);
        }
    if (thumbnails)
        fputs("\n\n", md);
    fclose(md);
    return sl_export_write_summary_item(io, text, size, err);
}

/* Of two list meshes with one mesh, the one whose name the files take: a level before an
 * intermediate model, a percent level before a budget, the larger percent, else the earlier. */
static int names_files_before(const sl_cluster_list *list, int a, int b)
{
    const sl_cluster_list_mesh *x = &list->meshes[a], *y = &list->meshes[b];
    if (x->intermediate != y->intermediate)
        return !x->intermediate;
    if (x->by_percent != y->by_percent)
        return x->by_percent;
    if (x->by_percent && x->percent != y->percent)
        return x->percent > y->percent;
    return a < b;
}

/* Which meshes are the same (rows[i].file, -1 without triangles). */
static int plan_meshes(const sl_cluster_list *list, const sl_pointset *ps,
                       sl_export_result *rows, sl_error *err)
{
    sl_export_digest *digests = calloc(list->count ? list->count : 1, sizeof *digests);
    if (!digests)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    for (uint32_t i = 0; i < list->count; i++) {
        sl_lod_mesh mesh;
        int bad = view_of(&list->meshes[i], ps, &mesh);
        if (!bad)
            digests[i] = sl_export_digest_mesh(&mesh);
        free(mesh.normals);
        free(mesh.colors);
        if (bad) {
            free(digests);
            return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "level %s", list->meshes[i].name);
        }
        rows[i].triangles = list->meshes[i].triangle_count;
        rows[i].vertices = list->meshes[i].vertex_count;
    }
    for (uint32_t i = 0; i < list->count; i++) {
        rows[i].file = rows[i].triangles ? (int)i : -1;
        for (uint32_t j = 0; j < list->count && rows[i].triangles; j++)
            if (!memcmp(&digests[j], &digests[i], sizeof *digests) &&
                names_files_before(list, (int)j, rows[i].file))
                rows[i].file = (int)j;
    }
    free(digests);
    return 0;
}

/* [export] morph: the published level (not an intermediate model) next coarser than
 * published level i, the one with the most triangles below i's; else -1. The paper's
 * intermediate models are their own morph and get none. */
static int morph_coarser(const sl_export_config *c, const sl_cluster_list *list,
                         const sl_export_result *rows, uint32_t i)
{
    if (!c->morph || !c->write_glb || list->meshes[i].intermediate || rows[i].file != (int)i)
        return -1;
    int best = -1;
    for (uint32_t j = 0; j < list->count; j++)
        if (!list->meshes[j].intermediate && rows[j].file == (int)j && rows[j].triangles &&
            rows[j].triangles < rows[i].triangles &&
            (best < 0 || rows[j].triangles > rows[best].triangles))
            best = (int)j;
    return best;
}

/* Writes and measures one distinct list mesh; its GLB morphs to list mesh `to` (>= 0). */
static int one_mesh(const sl_export_config *c, const sl_cluster_list *list, uint32_t i, int to,
                    const char *method, const sl_pointset *ps, const sl_mesh *input, const sl_export_frame *frame,
                    const sl_export_texture *texture, const sl_stage_io *io,
                    sl_export_result *row, sl_error *err)
{
    const sl_cluster_list_mesh *m = &list->meshes[i];
    sl_lod_mesh mesh, coarser;
    memset(&coarser, 0, sizeof coarser);
    int bad = view_of(m, ps, &mesh);
    if (!bad && to >= 0)
        bad = view_of(&list->meshes[to], ps, &coarser);
    if (bad) {
        free(mesh.normals), free(mesh.colors);
        free(coarser.normals), free(coarser.colors);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "level %s", m->name);
    }
    row->morph_to = to;
    sl_export_config files = *c; /* intermediates: meshes, no thumbnails */
    if (m->intermediate)
        files.thumbnail_size = 0;
    sl_export_level lv;
    memset(&lv, 0, sizeof lv);
    memcpy(lv.name, m->name, sizeof lv.name); /* both 32 bytes, NUL-terminated */
    char extras[256];
    if (proven(method))
        snprintf(extras, sizeof extras,
                 "{\"scanlod\":{\"level\":\"%s\",\"method\":\"%s\",\"bound\":%.9g}}",
                 lv.name, method, m->bound_fraction);
    else
        snprintf(extras, sizeof extras, "{\"scanlod\":{\"level\":\"%s\",\"method\":\"%s\"}}",
                 lv.name, method);
    int rc = sl_export_write_level(&files, &lv, &mesh, to >= 0 ? &coarser : NULL, extras, input,
                                   frame, texture, io, row, err);
    free(mesh.normals), free(mesh.colors);
    free(coarser.normals), free(coarser.colors);
    return rc;
}

static void report_meshes(const sl_export_config *c, const char *method,
                          const sl_cluster_list *list, const sl_export_result *rows,
                          const sl_export_frame *frame, sl_json *r)
{
    sl_json_array_begin(r, "levels");
    for (uint32_t i = 0; i < list->count; i++) {
        const sl_cluster_list_mesh *m = &list->meshes[i];
        sl_json_object_begin(r, NULL);
        report_mesh(m, method, r);
        sl_export_report_result(c, frame, &rows[i],
                                rows[i].file >= 0 ? list->meshes[rows[i].file].name : NULL,
                                m->bound, r);
        if (rows[i].morph_to >= 0)
            sl_json_string(r, "morph_to", list->meshes[rows[i].morph_to].name);
        if (rows[i].measured && proven(method)) /* the proven bound, checked by the measure (whose own closest
                                 points round at 1e-16 of the diagonal) */
            sl_json_bool(r, "bound_holds", rows[i].hausdorff <= m->bound_fraction + 1e-12);
        sl_json_object_end(r);
    }
    sl_json_array_end(r);
}

/* The manifest and the pages, over the levels (not the intermediate models): an export
 * configuration whose levels are the list's, as asked, and their results. */
static int manifest_and_pages(const sl_export_config *c, const sl_cluster_list *list,
                              const sl_export_result *rows, const sl_mesh *input,
                              const sl_stage_io *io, sl_error *err)
{
    sl_export_config *lc = malloc(sizeof *lc);
    sl_export_result *lr = calloc(SL_EXPORT_MAX_LEVELS, sizeof *lr);
    int at[SL_EXPORT_MAX_LEVELS];
    int rc = lc && lr ? 0 : sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0) {
        *lc = *c;
        lc->level_count = 0;
    }
    for (uint32_t i = 0; rc == 0 && i < list->count; i++) {
        const sl_cluster_list_mesh *m = &list->meshes[i];
        if (m->intermediate)
            continue;
        if (lc->level_count == SL_EXPORT_MAX_LEVELS) {
            rc = sl_error_set(err, SL_E_CORRUPT, 0, SL_CLUSTER_LEVELS_FILE,
                              "more than %d levels", SL_EXPORT_MAX_LEVELS);
            break;
        }
        sl_export_level *lv = &lc->levels[lc->level_count];
        memset(lv, 0, sizeof *lv);
        memcpy(lv->name, m->name, sizeof lv->name);
        lv->by_percent = m->by_percent;
        lv->percent = m->percent;
        lv->budget = m->budget;
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
    if (rc == 0) {
        sl_export_map_qualities(lc, lr, level_of_quality);
        rc = sl_export_manifest(lc, lr, level_of_quality, io, err);
    }
    if (rc == 0)
        rc = sl_export_html(lc, NULL, input, lr, level_of_quality, io, err);
    free(lr);
    free(lc);
    return rc;
}

int sl_export_level_list(const sl_export_config *c, const char *method, const char *list_dir,
                         const char *range_dir, const sl_mesh *input,
                         const sl_export_frame *frame, const sl_export_texture *texture,
                         const sl_stage_io *io, sl_error *err)
{
    char list_path[PATH_MAX], points_path[PATH_MAX];
    if (!range_dir)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "a level list needs the range stage");
    int rc = sl_stage_path(list_path, list_dir, SL_CLUSTER_LEVELS_FILE, err);
    if (rc == 0)
        rc = sl_stage_path(points_path, range_dir, SL_POINTSET_FILE, err);
    sl_cluster_list list;
    sl_pointset ps;
    memset(&list, 0, sizeof list);
    memset(&ps, 0, sizeof ps);
    if (rc == 0)
        rc = sl_cluster_list_read(list_path, &list, err);
    if (rc == 0)
        rc = sl_pointset_read(points_path, &ps, err);
    for (uint32_t i = 0; rc == 0 && i < list.count; i++)
        for (uint64_t v = 0; v < list.meshes[i].vertex_count; v++)
            if (list.meshes[i].source[v] >= ps.count) {
                rc = sl_error_set(err, SL_E_CORRUPT, 0, list_path,
                                  "level %s names point %u of %llu", list.meshes[i].name,
                                  list.meshes[i].source[v], (unsigned long long)ps.count);
                break;
            }
    sl_export_result *rows = rc == 0 ? calloc(list.count ? list.count : 1, sizeof *rows) : NULL;
    if (rc == 0 && !rows)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = plan_meshes(&list, &ps, rows, err);
    /* Each distinct mesh: its files and its measures, once. */
    for (uint32_t i = 0; i < list.count && rc == 0; i++)
        rows[i].morph_to = -1;
    for (uint32_t i = 0; i < list.count && rc == 0; i++) {
        rc = sl_stage_step(io, "export", (double)i / list.count, err);
        if (rc == 0 && rows[i].file == (int)i)
            rc = one_mesh(c, &list, i, morph_coarser(c, &list, rows, i), method, &ps, input,
                          frame, texture, io, &rows[i], err);
    }
    for (uint32_t i = 0; i < list.count && rc == 0; i++)
        if (rows[i].file >= 0 && rows[i].file != (int)i)
            rows[i] = rows[rows[i].file]; /* the same mesh: the same files and measures */
    if (rc == 0) {
        sl_json *r = io->report;
        sl_json_string(r, "method", method);
        sl_json_u64(r, "input_triangles", list.input_triangles);
        sl_json_bool(r, "fidelity_measured", input != NULL);
        report_meshes(c, method, &list, rows, frame, r);
        rc = write_summary(&list, method, rows, c->thumbnail_size > 0, io, err);
    }
    if (rc == 0)
        rc = manifest_and_pages(c, &list, rows, input, io, err);
    free(rows);
    sl_pointset_release(&ps);
    sl_cluster_list_release(&list);
    return rc;
}
