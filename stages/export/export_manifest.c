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

/* Quality q's derivative, served by level i's GLB: Voyager's fields in its schema's order.
 * The report's form (`report`) names the level and holds the asset's fields itself. */
static void derivative(sl_json *j, const sl_export_config *c, const sl_export_result *results,
                       const sl_stage_io *io, int q, int i, int report)
{
    const char *name = c->levels[i].name;
    char uri[64];
    snprintf(uri, sizeof uri, "%s.glb", name);
    uint64_t bytes = sl_export_file_bytes(io, name, "glb");
    sl_json_object_begin(j, NULL);
    sl_json_string(j, "usage", "Web3D");
    sl_json_string(j, "quality", sl_export_quality_names[q]);
    if (report) {
        sl_json_string(j, "level", name);
    } else {
        sl_json_array_begin(j, "assets");
        sl_json_object_begin(j, NULL);
    }
    sl_json_string(j, "uri", uri);
    sl_json_string(j, "type", "Model");
    sl_json_string(j, "mimeType", "model/gltf-binary");
    /* Voyager's schema wants both >= 1 (and its Asset.ts leaves them out otherwise). */
    if (bytes)
        sl_json_u64(j, "byteSize", bytes);
    if (results[i].triangles)
        sl_json_u64(j, "numFaces", results[i].triangles);
    if (!report) {
        sl_json_object_end(j);
        sl_json_array_end(j);
    }
    sl_json_object_end(j);
}

static int write_svx(const sl_export_config *c, const sl_export_result *results,
                     const int level_of_quality[SL_EXPORT_QUALITIES], const sl_stage_io *io,
                     sl_error *err)
{
    sl_json j;
    sl_json_init(&j, 1);
    sl_json_object_begin(&j, NULL);
    sl_json_object_begin(&j, "asset");
    sl_json_string(&j, "type", "application/si-dpo-3d.document+json");
    sl_json_string(&j, "version", "1.0"); /* CVDocument.version */
    sl_json_string(&j, "generator", "scanlod");
    sl_json_object_end(&j);
    sl_json_u64(&j, "scene", 0);
    sl_json_array_begin(&j, "scenes");
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "name", io->item);
    /* Voyager's scene reader takes a missing unit for mm. */
    sl_json_string(&j, "units", SVX_UNITS);
    sl_json_array_begin(&j, "nodes");
    sl_json_u64(&j, NULL, 0);
    sl_json_array_end(&j);
    sl_json_u64(&j, "setup", 0);
    sl_json_object_end(&j);
    sl_json_array_end(&j);
    sl_json_array_begin(&j, "nodes");
    sl_json_object_begin(&j, NULL);
    sl_json_string(&j, "name", io->item);
    sl_json_u64(&j, "model", 0);
    sl_json_object_end(&j);
    sl_json_array_end(&j);
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
        derivative(&j, c, results, io, q, level_of_quality[q], 0);
    sl_json_array_end(&j);
    sl_json_object_end(&j);
    sl_json_array_end(&j);
    sl_json_object_end(&j);
    char path[PATH_MAX];
    int rc = j.failed ? sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory") : 0;
    if (rc == 0)
        rc = sl_stage_path(path, io->out_dir, "scene.svx.json", err);
    if (rc == 0)
        rc = sl_write_file_atomic(path, j.buf, j.len, err);
    sl_json_release(&j);
    return rc;
}

int sl_export_manifest(const sl_export_config *c, const sl_export_result *results,
                       const int level_of_quality[SL_EXPORT_QUALITIES], const sl_stage_io *io,
                       sl_error *err)
{
    static const char *const exts[4] = {"ply", "glb", "obj", "png"};
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
    sl_json_array_begin(r, "derivatives");
    for (int q = 0; q < SL_EXPORT_QUALITIES; q++)
        derivative(r, c, results, io, q, level_of_quality[q], 1);
    sl_json_array_end(r);
    sl_json_object_end(r);
    return write_svx(c, results, level_of_quality, io, err);
}
