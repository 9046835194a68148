/* Levels as artifacts (level.h; docs/formats.md "Levels").
 *
 * levels.sllst: envelope magic "SLLEVLST", format 1. Body, little-endian:
 *   u64 input_triangles, u64 input_points, f64 diagonal, u32 model_expansions, u32 count,
 *   u64 model_triangles                                                    (40 bytes)
 *   count records of 192 bytes:
 *     char name[32], char from[32], char method[16] (NUL-padded), u32 flags,
 *     u32 rung kind, char rung name[32], f64 rung percent, u64 rung triangles, u64 budget,
 *     f64 bound, f64 bound_fraction, u32 expansions, u32 unpatched_cells,
 *     u64 vertex_count, u64 triangle_count, 8 bytes 0
 * NAME.sllvl: envelope magic "SLLEVMSH", format 1. Body, little-endian:
 *   u64 V, u64 T, u32 attributes (1 colours, 2 texture coordinates, 4 sources), u32 0,
 *   f32 positions[3 V], [u8 colors[4 V]], [f32 texcoords[2 V]], [u32 source[V]],
 *   u32 triangles[3 T]
 */
#include "levels/level.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/artifact.h"

#define LIST_MAGIC "SLLEVLST"
#define MESH_MAGIC "SLLEVMSH"
#define FORMAT 1u
#define LIST_HEAD 40u
#define RECORD 192u
#define MESH_HEAD 24u
#define MAX_BODY (UINT64_C(1) << 40)

enum { HAS_COLORS = 1, HAS_TEXCOORDS = 2, HAS_SOURCE = 4 };

void sl_level_release_mesh(sl_level *lv)
{
    free(lv->positions);
    free(lv->colors);
    free(lv->texcoords);
    free(lv->source);
    free(lv->triangles);
    lv->positions = NULL;
    lv->colors = NULL;
    lv->texcoords = NULL;
    lv->source = NULL;
    lv->triangles = NULL;
}

void sl_level_list_release(sl_level_list *list)
{
    for (uint32_t i = 0; list->levels && i < list->count; i++)
        sl_level_release_mesh(&list->levels[i]);
    free(list->levels);
    memset(list, 0, sizeof *list);
}

void sl_level_copy_record(sl_level *to, const sl_level *from)
{
    *to = *from;
    to->positions = NULL;
    to->colors = NULL;
    to->texcoords = NULL;
    to->source = NULL;
    to->triangles = NULL;
}

static int path_of(char path[PATH_MAX], const char *dir, const char *name, const char *suffix,
                   sl_error *err)
{
    int n = snprintf(path, PATH_MAX, "%s/%s%s", dir, name, suffix);
    if (n < 0 || n >= PATH_MAX)
        return sl_error_set(err, SL_E_STORAGE, ENAMETOOLONG, dir, "path too long for '%s'",
                            name);
    return 0;
}

/* --- one level's mesh ------------------------------------------------------------------ */

int sl_level_write_mesh(const char *dir, const sl_level *lv, sl_error *err)
{
    char path[PATH_MAX];
    int rc = path_of(path, dir, lv->name, SL_LEVEL_MESH_SUFFIX, err);
    if (rc)
        return rc;
    uint64_t v = lv->vertex_count, t = lv->triangle_count;
    uint32_t attrs = (lv->colors ? HAS_COLORS : 0) | (lv->texcoords ? HAS_TEXCOORDS : 0) |
                     (lv->source ? HAS_SOURCE : 0);
    uint64_t size = MESH_HEAD + 12 * v + 12 * t + (attrs & HAS_COLORS ? 4 * v : 0) +
                    (attrs & HAS_TEXCOORDS ? 8 * v : 0) + (attrs & HAS_SOURCE ? 4 * v : 0);
    unsigned char *body = size <= MAX_BODY ? malloc(size) : NULL;
    if (!body)
        return sl_error_nomem(err, path, "level %s: %llu bytes", lv->name,
                              (unsigned long long)size);
    unsigned char *p = body;
    sl_put_u64(p, v);
    sl_put_u64(p + 8, t);
    sl_put_u32(p + 16, attrs);
    sl_put_u32(p + 20, 0);
    p += MESH_HEAD;
    for (uint64_t k = 0; k < 3 * v; k++, p += 4)
        sl_put_f32(p, lv->positions[k]);
    if (attrs & HAS_COLORS) {
        memcpy(p, lv->colors, 4 * v);
        p += 4 * v;
    }
    for (uint64_t k = 0; (attrs & HAS_TEXCOORDS) && k < 2 * v; k++, p += 4)
        sl_put_f32(p, lv->texcoords[k]);
    for (uint64_t k = 0; (attrs & HAS_SOURCE) && k < v; k++, p += 4)
        sl_put_u32(p, lv->source[k]);
    for (uint64_t k = 0; k < 3 * t; k++, p += 4)
        sl_put_u32(p, lv->triangles[k]);
    sl_artifact_part part = {body, (size_t)size};
    rc = sl_artifact_write(path, MESH_MAGIC, FORMAT, 1, &part, 1, err);
    free(body);
    return rc;
}

/* The arrays of a mesh of v vertices and t triangles with `attrs`, allocated. */
static int alloc_mesh(sl_level *lv, uint64_t v, uint64_t t, uint32_t attrs)
{
    size_t nv = v ? (size_t)v : 1, nt = t ? (size_t)t : 1;
    lv->positions = malloc(3 * nv * sizeof *lv->positions);
    lv->colors = attrs & HAS_COLORS ? malloc(4 * nv) : NULL;
    lv->texcoords = attrs & HAS_TEXCOORDS ? malloc(2 * nv * sizeof *lv->texcoords) : NULL;
    lv->source = attrs & HAS_SOURCE ? malloc(nv * sizeof *lv->source) : NULL;
    lv->triangles = malloc(3 * nt * sizeof *lv->triangles);
    return lv->positions && lv->triangles && (lv->colors || !(attrs & HAS_COLORS)) &&
           (lv->texcoords || !(attrs & HAS_TEXCOORDS)) && (lv->source || !(attrs & HAS_SOURCE));
}

static int decode_mesh(const unsigned char *p, uint64_t size, sl_level *lv, uint64_t max_source,
                       const char *path, sl_error *err)
{
    if (size < MESH_HEAD)
        return sl_error_corrupt(err, path, "level mesh: shorter than its head");
    uint64_t v = sl_get_u64(p), t = sl_get_u64(p + 8);
    uint32_t attrs = sl_get_u32(p + 16);
    uint64_t per_vertex = 12 + (attrs & HAS_COLORS ? 4 : 0) + (attrs & HAS_TEXCOORDS ? 8 : 0) +
                          (attrs & HAS_SOURCE ? 4 : 0);
    uint64_t left = size - MESH_HEAD;
    if (attrs > 7 || v > left / per_vertex || t > (left - v * per_vertex) / 12 ||
        v * per_vertex + 12 * t != left)
        return sl_error_corrupt(err, path, "level mesh: its counts disagree with its size");
    if ((lv->vertex_count && lv->vertex_count != v) ||
        (lv->triangle_count && lv->triangle_count != t))
        return sl_error_corrupt(err, path, "level mesh: its counts disagree with the list's");
    if (!alloc_mesh(lv, v, t, attrs)) {
        sl_level_release_mesh(lv);
        return sl_error_nomem(err, path, "level %s of %llu triangles", lv->name,
                              (unsigned long long)t);
    }
    lv->vertex_count = v;
    lv->triangle_count = t;
    p += MESH_HEAD;
    int bad = 0;
    for (uint64_t k = 0; k < 3 * v; k++, p += 4)
        bad |= !isfinite(lv->positions[k] = sl_get_f32(p));
    if (attrs & HAS_COLORS) {
        memcpy(lv->colors, p, 4 * v);
        p += 4 * v;
    }
    for (uint64_t k = 0; (attrs & HAS_TEXCOORDS) && k < 2 * v; k++, p += 4)
        bad |= !isfinite(lv->texcoords[k] = sl_get_f32(p));
    for (uint64_t k = 0; (attrs & HAS_SOURCE) && k < v; k++, p += 4)
        bad |= max_source && (lv->source[k] = sl_get_u32(p)) >= max_source;
    for (uint64_t k = 0; k < 3 * t; k++, p += 4)
        bad |= (lv->triangles[k] = sl_get_u32(p)) >= v;
    if (bad) {
        sl_level_release_mesh(lv);
        return sl_error_corrupt(err, path, "level mesh: a non-finite value or an index out of "
                                           "range");
    }
    return 0;
}

int sl_level_read_mesh(const char *dir, sl_level *lv, uint64_t max_source, sl_error *err)
{
    char path[PATH_MAX];
    int rc = path_of(path, dir, lv->name, SL_LEVEL_MESH_SUFFIX, err);
    void *body = NULL;
    uint64_t size = 0;
    if (rc == 0)
        rc = sl_artifact_read(path, MESH_MAGIC, FORMAT, MAX_BODY, &body, &size, NULL, err);
    if (rc == 0)
        rc = decode_mesh(body, size, lv, max_source, path, err);
    free(body);
    return rc;
}

/* --- the list ----------------------------------------------------------------------------- */

static void put_name(unsigned char *p, const char *name, size_t size)
{
    memset(p, 0, size);
    memcpy(p, name, strnlen(name, size - 1));
}

static void put_record(unsigned char *p, const sl_level *lv)
{
    put_name(p, lv->name, 32);
    put_name(p + 32, lv->from, 32);
    put_name(p + 64, lv->method, 16);
    sl_put_u32(p + 80, lv->flags);
    sl_put_u32(p + 84, (uint32_t)lv->rung.kind);
    put_name(p + 88, lv->rung.name, 32);
    sl_put_f64(p + 120, lv->rung.percent);
    sl_put_u64(p + 128, lv->rung.triangles);
    sl_put_u64(p + 136, lv->budget);
    sl_put_f64(p + 144, lv->bound);
    sl_put_f64(p + 152, lv->bound_fraction);
    sl_put_u32(p + 160, lv->expansions);
    sl_put_u32(p + 164, lv->unpatched_cells);
    sl_put_u64(p + 168, lv->vertex_count);
    sl_put_u64(p + 176, lv->triangle_count);
    sl_put_u64(p + 184, 0);
}

int sl_level_list_write(const char *dir, const sl_level_list *list, sl_error *err)
{
    char path[PATH_MAX];
    int rc = path_of(path, dir, SL_LEVEL_LIST_FILE, "", err);
    if (rc)
        return rc;
    size_t size = LIST_HEAD + (size_t)list->count * RECORD;
    unsigned char *body = calloc(1, size);
    if (!body)
        return sl_error_nomem(err, path, "%u level records", list->count);
    sl_put_u64(body, list->input_triangles);
    sl_put_u64(body + 8, list->input_points);
    sl_put_f64(body + 16, list->diagonal);
    sl_put_u32(body + 24, list->model_expansions);
    sl_put_u32(body + 28, list->count);
    sl_put_u64(body + 32, list->model_triangles);
    for (uint32_t i = 0; i < list->count; i++)
        put_record(body + LIST_HEAD + (size_t)i * RECORD, &list->levels[i]);
    sl_artifact_part part = {body, size};
    rc = sl_artifact_write(path, LIST_MAGIC, FORMAT, 1, &part, 1, err);
    free(body);
    return rc;
}

/* A NUL-terminated name of at most size - 1 characters at p, a file stem (or "" when
 * `empty_ok`). */
static int get_name(char *out, const unsigned char *p, size_t size, int empty_ok)
{
    memcpy(out, p, size);
    if (!memchr(out, 0, size))
        return -1;
    return out[0] ? !sl_level_name_ok(out) * -1 : (empty_ok ? 0 : -1);
}

static int get_record(const unsigned char *p, sl_level *lv)
{
    memset(lv, 0, sizeof *lv);
    int bad = get_name(lv->name, p, 32, 0) | get_name(lv->from, p + 32, 32, 1) |
              get_name(lv->rung.name, p + 88, 32, 1);
    memcpy(lv->method, p + 64, 16);
    bad |= memchr(lv->method, 0, 16) == NULL ? -1 : 0;
    lv->flags = sl_get_u32(p + 80);
    lv->rung.kind = (int)sl_get_u32(p + 84);
    lv->rung.percent = sl_get_f64(p + 120);
    lv->rung.triangles = sl_get_u64(p + 128);
    lv->budget = sl_get_u64(p + 136);
    lv->bound = sl_get_f64(p + 144);
    lv->bound_fraction = sl_get_f64(p + 152);
    lv->expansions = sl_get_u32(p + 160);
    lv->unpatched_cells = sl_get_u32(p + 164);
    lv->vertex_count = sl_get_u64(p + 168);
    lv->triangle_count = sl_get_u64(p + 176);
    if (lv->flags > 63u || (unsigned)lv->rung.kind > SL_RUNG_EXPANSIONS ||
        !(lv->rung.percent >= 0 && lv->rung.percent <= 100) || !(lv->bound >= 0) ||
        !isfinite(lv->bound) || !isfinite(lv->bound_fraction) || lv->vertex_count > MAX_BODY ||
        lv->triangle_count > MAX_BODY)
        bad = -1;
    return bad;
}

int sl_level_list_read(const char *dir, sl_level_list *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    char path[PATH_MAX];
    void *data = NULL;
    uint64_t size = 0;
    int rc = path_of(path, dir, SL_LEVEL_LIST_FILE, "", err);
    if (rc == 0)
        rc = sl_artifact_read(path, LIST_MAGIC, FORMAT, MAX_BODY, &data, &size, NULL, err);
    if (rc)
        return rc;
    const unsigned char *p = data;
    uint32_t count = size >= LIST_HEAD ? sl_get_u32(p + 28) : 0;
    if (size < LIST_HEAD || (size - LIST_HEAD) / RECORD != count ||
        (size - LIST_HEAD) % RECORD != 0) {
        free(data);
        return sl_error_corrupt(err, path, "level list: its count disagrees with its size");
    }
    out->input_triangles = sl_get_u64(p);
    out->input_points = sl_get_u64(p + 8);
    out->diagonal = sl_get_f64(p + 16);
    out->model_expansions = sl_get_u32(p + 24);
    out->model_triangles = sl_get_u64(p + 32);
    out->levels = calloc(count ? count : 1, sizeof *out->levels);
    if (!out->levels) {
        free(data);
        return sl_error_nomem(err, path, "%u level records", count);
    }
    out->count = count;
    for (uint32_t i = 0; i < count && rc == 0; i++) {
        if (get_record(p + LIST_HEAD + (size_t)i * RECORD, &out->levels[i]))
            rc = sl_error_corrupt(err, path, "level list: record %u is not a level", i);
        for (uint32_t j = 0; j < i && rc == 0; j++)
            if (!strcmp(out->levels[j].name, out->levels[i].name))
                rc = sl_error_corrupt(err, path, "level list: two levels named %s",
                                      out->levels[i].name);
    }
    if (rc == 0 && !isfinite(out->diagonal))
        rc = sl_error_corrupt(err, path, "level list: a non-finite diagonal");
    free(data);
    if (rc)
        sl_level_list_release(out);
    return rc;
}

int sl_level_list_present(const char *dir)
{
    char path[PATH_MAX];
    int n = snprintf(path, sizeof path, "%s/%s", dir, SL_LEVEL_LIST_FILE);
    return n > 0 && n < (int)sizeof path && access(path, F_OK) == 0;
}
