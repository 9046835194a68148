/* The item's manifest: scene.svx.json, a Smithsonian Voyager scene document (the format
 * of dpo-voyager's source/client/schema/: document, model and common schemas and their
 * TypeScript twins) holding one model whose Web3D derivatives are the item's GLBs, and
 * the same facts in the report (docs/formats.md, "scene.svx.json").
 *
 * Qualities by triangle count: Voyager picks a derivative by quality (Thumb, Low,
 * Medium, High, Highest; it starts at Thumb and moves up with the model's share of the
 * screen), scanlod cuts levels by percent and by budget. Each quality has a triangle
 * target (the [export] budget of the same name, any case, else 2000, 20000, 100000,
 * 500000, and no limit for Highest) and gets the published level with the most triangles
 * within it (ties: the earlier level), or the coarsest level when none fits. Qualities
 * whose targets lie above the finest level therefore all name the finest level's one
 * file: the manifest lists them all with the same asset.
 */
#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "core/atomicfile.h"
#include "core/json.h"
#include "stages/export/export_internal.h"

const char *const sl_export_quality_names[SL_EXPORT_QUALITIES] = {"Thumb", "Low", "Medium",
                                                                  "High", "Highest"};
static const uint64_t default_target[SL_EXPORT_QUALITIES] = {2000, 20000, 100000, 500000,
                                                             UINT64_MAX};

#define SVX_UNITS "m" /* what glTF says a GLB's coordinates are (spec 3.4) */

static uint64_t quality_target(const sl_export_config *c, int q)
{
    for (int i = 0; i < c->level_count; i++)
        if (!c->levels[i].by_percent && !strcasecmp(c->levels[i].name, sl_export_quality_names[q]))
            return c->levels[i].budget;
    return default_target[q];
}

void sl_export_map_qualities(const sl_export_config *c, const sl_export_result *results,
                             int level_of_quality[SL_EXPORT_QUALITIES])
{
    for (int q = 0; q < SL_EXPORT_QUALITIES; q++) {
        uint64_t target = quality_target(c, q);
        int within = -1, coarsest = -1;
        for (int i = 0; c->write_glb && i < c->level_count; i++) {
            if (results[i].file != i)
                continue; /* no triangles, or published under an earlier level's name */
            uint64_t t = results[i].triangles;
            if (t <= target && (within < 0 || t > results[within].triangles))
                within = i;
            if (coarsest < 0 || t < results[coarsest].triangles)
                coarsest = i;
        }
        level_of_quality[q] = within >= 0 ? within : coarsest;
    }
}

uint64_t sl_export_file_bytes(const sl_stage_io *io, const char *name, const char *ext)
{
    char file[64], path[PATH_MAX];
    struct stat st;
    sl_error err;
    sl_error_init(&err);
    snprintf(file, sizeof file, "%s.%s", name, ext);
    if (sl_stage_path(path, io->out_dir, file, &err) || stat(path, &st) || !S_ISREG(st.st_mode))
        return 0;
    return (uint64_t)st.st_size;
}

/* A derivative with one asset, up to the asset's own fields: Voyager's form
 * ({usage, quality, assets: [{...}]}), or the report's (`report`: {usage, quality, level,
 * ...}, the asset's fields in the derivative, naming its level). */
static void derivative_begin(sl_json *j, const char *usage, const char *quality,
                             const char *level, int report)
{
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "usage", usage);
    sl_json_string(j, "quality", quality);
    if (report) {
        sl_json_string(j, "level", level);
    } else {
        sl_json_array_begin(j, "assets");
        sl_json_object_begin(j, NULL);
    }
}

static void derivative_end(sl_json *j, int report)
{
    if (!report) {
        sl_json_object_end(j);
        sl_json_array_end(j);
    }
    sl_json_object_end(j);
}

/* Quality q's derivative, served by level i's GLB: Voyager's fields in its schema's order. */
static void derivative(sl_json *j, const sl_export_config *c, const sl_export_result *results,
                       const sl_stage_io *io, int q, int i, int report)
{
    const char *name = c->levels[i].name;
    char uri[64];
    snprintf(uri, sizeof uri, "%s.glb", name);
    uint64_t bytes = sl_export_file_bytes(io, name, "glb");
    derivative_begin(j, "Web3D", sl_export_quality_names[q], name, report);
    sl_json_string(j, "uri", uri);
    sl_json_string(j, "type", "Model");
    sl_json_string(j, "mimeType", "model/gltf-binary");
    /* Voyager's schema wants both >= 1 (and its Asset.ts leaves them out otherwise). */
    if (bytes)
        sl_json_u64(j, "byteSize", bytes);
    if (results[i].triangles)
        sl_json_u64(j, "numFaces", results[i].triangles);
    derivative_end(j, report);
}

const char *sl_export_title(const sl_stage_io *io)
{
    return io->metadata && io->metadata->title[0] ? io->metadata->title : io->item;
}

/* The thumbnail Voyager shows for the scene: the finest published level's (what Highest
 * serves), or -1 without thumbnails. */
static int scene_image_level(const sl_export_item *it)
{
    int i = it->quality[SL_EXPORT_QUALITIES - 1];
    return i >= 0 && sl_export_file_bytes(it->io, it->c->levels[i].name, "png") ? i : -1;
}

/* That thumbnail as an Image2D derivative (the form of Voyager's own captures,
 * CVCaptureTask: type Image, mimeType, byteSize, imageSize). */
static void image_derivative(sl_json *j, const sl_export_item *it, int i, int report)
{
    const char *name = it->c->levels[i].name;
    char uri[64];
    snprintf(uri, sizeof uri, "%s.png", name);
    derivative_begin(j, "Image2D", "Thumb", name, report);
    sl_json_string(j, "uri", uri);
    sl_json_string(j, "type", "Image");
    sl_json_string(j, "mimeType", "image/png");
    sl_json_u64(j, "byteSize", sl_export_file_bytes(it->io, name, "png"));
    sl_json_u64(j, "imageSize", (uint64_t)it->c->thumbnail_size);
    derivative_end(j, report);
}

/* "credit; licence", either alone, or NULL: the document's copyright line (malloc'd). */
static char *copyright(const sl_item_metadata *m)
{
    if (!m || (!m->credit[0] && !m->licence[0]))
        return NULL;
    size_t n = strlen(m->credit) + strlen(m->licence) + 3;
    char *text = malloc(n);
    if (text)
        snprintf(text, n, "%s%s%s", m->credit, m->credit[0] && m->licence[0] ? "; " : "",
                 m->licence);
    return text;
}

/* metas[0]: the collection record Voyager shows (CVMeta, CVDocument: "titles" and
 * "intros" by language, its collection panel every other field) and the scene's image. */
static void meta(sl_json *j, const sl_export_item *it)
{
    const sl_item_metadata *m = it->io->metadata;
    sl_json_array_begin(j, "metas");
    sl_json_object_begin(j, NULL);
    sl_json_object_begin(j, "collection");
    sl_json_object_begin(j, "titles");
    sl_json_string(j, "EN", sl_export_title(it->io)); /* the manifest has no language */
    sl_json_object_end(j);
    if (m && m->description[0]) {
        sl_json_object_begin(j, "intros");
        sl_json_string(j, "EN", m->description);
        sl_json_object_end(j);
    }
    static const char *const keys[] = {"accession", "credit", "licence"};
    const char *values[] = {m ? m->accession : "", m ? m->credit : "", m ? m->licence : ""};
    for (int k = 0; k < 3; k++)
        if (values[k][0])
            sl_json_string(j, keys[k], values[k]);
    sl_json_string(j, "item", it->io->item);
    sl_json_object_end(j);
    int i = scene_image_level(it);
    if (i >= 0) {
        char uri[64];
        snprintf(uri, sizeof uri, "%s.png", it->c->levels[i].name);
        sl_json_array_begin(j, "images");
        sl_json_object_begin(j, NULL);
        sl_json_string(j, "uri", uri);
        sl_json_string(j, "quality", "Thumb");
        sl_json_u64(j, "byteSize", sl_export_file_bytes(it->io, it->c->levels[i].name, "png"));
        sl_json_u64(j, "width", (uint64_t)it->c->thumbnail_size);
        sl_json_u64(j, "height", (uint64_t)it->c->thumbnail_size);
        sl_json_object_end(j);
        sl_json_array_end(j);
    }
    sl_json_object_end(j);
    sl_json_array_end(j);
}

static void scene_head(sl_json *j, const sl_export_item *it)
{
    char *c = copyright(it->io->metadata); /* NULL also when out of memory: no line */
    sl_json_object_begin(j, "asset");
    sl_json_string(j, "type", "application/si-dpo-3d.document+json");
    sl_json_string(j, "version", "1.0"); /* CVDocument.version */
    if (c)
        sl_json_string(j, "copyright", c);
    free(c);
    sl_json_string(j, "generator", "scanlod");
    sl_json_object_end(j);
    sl_json_u64(j, "scene", 0);
    sl_json_array_begin(j, "scenes");
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "name", it->io->item);
    /* Voyager's scene reader takes a missing unit for mm. */
    sl_json_string(j, "units", SVX_UNITS);
    sl_json_array_begin(j, "nodes");
    sl_json_u64(j, NULL, 0);
    sl_json_array_end(j);
    sl_json_u64(j, "setup", 0);
    sl_json_u64(j, "meta", 0); /* the scene's meta is the document's title (CVDocument) */
    sl_json_object_end(j);
    sl_json_array_end(j);
}

static int write_svx(const sl_export_item *it, sl_error *err)
{
    sl_json j;
    sl_json_init(&j, 1);
    sl_json_object_begin(&j, NULL);
    scene_head(&j, it);
    sl_json_array_begin(&j, "nodes");
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "name", it->io->item);
    sl_json_u64(&j, "model", 0);
    sl_json_object_end(&j);
    sl_json_array_end(&j);
    meta(&j, it);
    sl_json_array_begin(&j, "setups");
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "units", SVX_UNITS);
    sl_json_object_end(&j);
    sl_json_array_end(&j);
    sl_json_array_begin(&j, "models");
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "units", SVX_UNITS);
    sl_json_array_begin(&j, "derivatives");
    for (int q = 0; q < SL_EXPORT_QUALITIES; q++)
        derivative(&j, it->c, it->results, it->io, q, it->quality[q], 0);
    if (scene_image_level(it) >= 0)
        image_derivative(&j, it, scene_image_level(it), 0);
    sl_json_array_end(&j);
    sl_json_object_end(&j);
    sl_json_array_end(&j);
    sl_json_object_end(&j);
    char path[PATH_MAX];
    int rc = j.failed ? sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory") : 0;
    if (rc == 0)
        rc = sl_stage_path(path, it->io->out_dir, "scene.svx.json", err);
    if (rc == 0)
        rc = sl_write_file_atomic(path, j.buf, j.len, err);
    sl_json_release(&j);
    return rc;
}

int sl_export_manifest(const sl_export_item *it, sl_error *err)
{
    static const char *const exts[4] = {"ply", "glb", "obj", "png"};
    const sl_export_config *c = it->c;
    const sl_export_result *results = it->results;
    const int *level_of_quality = it->quality;
    const sl_stage_io *io = it->io;
    sl_json *r = io->report;
    /* Every published mesh once, with every level and quality it serves. */
    sl_json_array_begin(r, "files");
    for (int i = 0; i < c->level_count; i++) {
        if (results[i].file != i)
            continue;
        sl_json_object_begin(r, NULL);
        sl_json_string(r, "name", c->levels[i].name);
        sl_json_u64(r, "triangles", results[i].triangles);
        sl_json_array_begin(r, "levels");
        for (int l = 0; l < c->level_count; l++)
            if (results[l].file == i)
                sl_json_string(r, NULL, c->levels[l].name);
        sl_json_array_end(r);
        sl_json_array_begin(r, "qualities");
        for (int q = 0; q < SL_EXPORT_QUALITIES; q++)
            if (level_of_quality[q] == i)
                sl_json_string(r, NULL, sl_export_quality_names[q]);
        sl_json_array_end(r);
        sl_json_object_begin(r, "bytes");
        for (int e = 0; e < 4; e++) {
            uint64_t n = sl_export_file_bytes(io, c->levels[i].name, exts[e]);
            if (n)
                sl_json_u64(r, exts[e], n);
        }
        sl_json_object_end(r);
        sl_json_object_end(r);
    }
    sl_json_array_end(r);
    if (level_of_quality[0] < 0)
        return 0; /* no GLB: nothing for Voyager to show */
    sl_json_object_begin(r, "manifest");
    sl_json_string(r, "file", "scene.svx.json");
    sl_json_string(r, "units", SVX_UNITS);
    sl_json_string(r, "title", sl_export_title(io));
    sl_json_array_begin(r, "derivatives");
    for (int q = 0; q < SL_EXPORT_QUALITIES; q++)
        derivative(r, c, results, io, q, level_of_quality[q], 1);
    if (scene_image_level(it) >= 0)
        image_derivative(r, it, scene_image_level(it), 1);
    sl_json_array_end(r);
    sl_json_object_end(r);
    return write_svx(it, err);
}
