/* The cluster stage's level list (cluster.h; docs/formats.md "levels.sllev").
 *
 * Envelope: core/artifact.h (magic "SLCLLEVS", format 1, checksum). Body, little-endian:
 *   u64 input_triangles, f64 diagonal, u32 count, u32 0
 *   count records, each:
 *     char name[32], char from[32] (NUL-padded), u32 flags (1 intermediate, 2 by_percent,
 *     4 reached, 8 clamped), u32 0, f64 percent, u64 budget, f64 bound, f64 bound_fraction,
 *     u64 vertex_count V, u64 triangle_count T, u64 0 (128 bytes), then
 *     f32 positions[3 V], u32 source[V], u32 triangles[3 T]
 * The reader checks every count against the bytes left before allocating, every index
 * against V, and every name (letters, digits, '.', '_', '-', from a letter or digit).
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "stages/cluster/cluster.h"

#define LIST_MAGIC "SLCLLEVS"
#define LIST_FORMAT 1u
#define HEAD_SIZE 24u
#define RECORD_SIZE 128u
#define MAX_BODY (UINT64_C(1) << 40)

static void put_f64(unsigned char *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    sl_put_u64(p, u);
}

static double get_f64(const unsigned char *p)
{
    uint64_t u = sl_get_u64(p);
    double v;
    memcpy(&v, &u, 8);
    return v;
}

static uint64_t mesh_bytes(const sl_cluster_list_mesh *m)
{
    return RECORD_SIZE + 16 * m->vertex_count + 12 * m->triangle_count;
}

void sl_cluster_list_release(sl_cluster_list *list)
{
    for (uint32_t i = 0; list->meshes && i < list->count; i++) {
        free(list->meshes[i].positions);
        free(list->meshes[i].source);
        free(list->meshes[i].triangles);
    }
    free(list->meshes);
    memset(list, 0, sizeof *list);
}

int sl_cluster_list_write(const char *path, const sl_cluster_list *list, sl_error *err)
{
    uint64_t size = HEAD_SIZE;
    for (uint32_t i = 0; i < list->count; i++)
        size += mesh_bytes(&list->meshes[i]);
    unsigned char *body = size <= MAX_BODY ? malloc(size) : NULL;
    if (!body)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "%llu bytes of levels",
                            (unsigned long long)size);
    unsigned char *p = body;
    sl_put_u64(p, list->input_triangles);
    put_f64(p + 8, list->diagonal);
    sl_put_u32(p + 16, list->count);
    sl_put_u32(p + 20, 0);
    p += HEAD_SIZE;
    for (uint32_t i = 0; i < list->count; i++) {
        const sl_cluster_list_mesh *m = &list->meshes[i];
        memset(p, 0, 64);
        memcpy(p, m->name, strnlen(m->name, sizeof m->name - 1));
        memcpy(p + 32, m->from, strnlen(m->from, sizeof m->from - 1));
        sl_put_u32(p + 64, (m->intermediate ? 1u : 0) | (m->by_percent ? 2u : 0) |
                               (m->reached ? 4u : 0) | (m->clamped ? 8u : 0));
        sl_put_u32(p + 68, 0);
        put_f64(p + 72, m->percent);
        sl_put_u64(p + 80, m->budget);
        put_f64(p + 88, m->bound);
        put_f64(p + 96, m->bound_fraction);
        sl_put_u64(p + 104, m->vertex_count);
        sl_put_u64(p + 112, m->triangle_count);
        sl_put_u64(p + 120, 0);
        p += RECORD_SIZE;
        for (uint64_t k = 0; k < 3 * m->vertex_count; k++, p += 4) {
            uint32_t u;
            memcpy(&u, &m->positions[k], 4);
            sl_put_u32(p, u);
        }
        for (uint64_t k = 0; k < m->vertex_count; k++, p += 4)
            sl_put_u32(p, m->source[k]);
        for (uint64_t k = 0; k < 3 * m->triangle_count; k++, p += 4)
            sl_put_u32(p, m->triangles[k]);
    }
    sl_artifact_part part = {body, (size_t)size};
    int rc = sl_artifact_write(path, LIST_MAGIC, LIST_FORMAT, 1, &part, 1, err);
    free(body);
    return rc;
}

static int corrupt(sl_error *err, const char *path, const char *what)
{
    return sl_error_set(err, SL_E_CORRUPT, 0, path, "level list: %s", what);
}

static int good_name(const char *name)
{
    if (!isalnum((unsigned char)name[0]))
        return 0;
    for (const char *p = name; *p; p++)
        if (!isalnum((unsigned char)*p) && !strchr("._-", *p))
            return 0;
    return 1;
}

/* One record at *p (with `left` bytes from it); advances *p. */
static int read_mesh(const unsigned char **p, uint64_t *left, sl_cluster_list_mesh *m,
                     const char *path, sl_error *err)
{
    const unsigned char *q = *p;
    if (*left < RECORD_SIZE)
        return corrupt(err, path, "a record is cut short");
    memcpy(m->name, q, 32);
    memcpy(m->from, q + 32, 32);
    if (memchr(q, 0, 32) == NULL || !good_name(m->name) || memchr(q + 32, 0, 32) == NULL ||
        (m->from[0] && !good_name(m->from)))
        return corrupt(err, path, "a level name is not a file stem");
    uint32_t flags = sl_get_u32(q + 64);
    m->intermediate = (flags & 1u) != 0;
    m->by_percent = (flags & 2u) != 0;
    m->reached = (flags & 4u) != 0;
    m->clamped = (flags & 8u) != 0;
    m->percent = get_f64(q + 72);
    m->budget = sl_get_u64(q + 80);
    m->bound = get_f64(q + 88);
    m->bound_fraction = get_f64(q + 96);
    m->vertex_count = sl_get_u64(q + 104);
    m->triangle_count = sl_get_u64(q + 112);
    *left -= RECORD_SIZE;
    q += RECORD_SIZE;
    uint64_t need;
    if (flags > 15u || !(m->bound >= 0.0) || !isfinite(m->bound) || m->vertex_count > *left / 16 ||
        m->triangle_count > *left / 12 ||
        __builtin_add_overflow(16 * m->vertex_count, 12 * m->triangle_count, &need) || need > *left)
        return corrupt(err, path, "a level's counts disagree with the file's size");
    size_t nv = m->vertex_count ? (size_t)m->vertex_count : 1;
    size_t nt = m->triangle_count ? (size_t)m->triangle_count : 1;
    m->positions = malloc(3 * nv * sizeof *m->positions);
    m->source = malloc(nv * sizeof *m->source);
    m->triangles = malloc(3 * nt * sizeof *m->triangles);
    if (!m->positions || !m->source || !m->triangles)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "a level of %llu triangles",
                            (unsigned long long)m->triangle_count);
    for (uint64_t k = 0; k < 3 * m->vertex_count; k++, q += 4) {
        uint32_t u = sl_get_u32(q);
        memcpy(&m->positions[k], &u, 4);
        if (!isfinite(m->positions[k]))
            return corrupt(err, path, "a non-finite position");
    }
    for (uint64_t k = 0; k < m->vertex_count; k++, q += 4)
        m->source[k] = sl_get_u32(q);
    for (uint64_t k = 0; k < 3 * m->triangle_count; k++, q += 4)
        if ((m->triangles[k] = sl_get_u32(q)) >= m->vertex_count)
            return corrupt(err, path, "a triangle names a vertex out of range");
    *left -= need;
    *p = q;
    return 0;
}

int sl_cluster_list_read(const char *path, sl_cluster_list *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    void *data = NULL;
    uint64_t size = 0;
    int rc = sl_artifact_read(path, LIST_MAGIC, LIST_FORMAT, MAX_BODY, &data, &size, NULL, err);
    if (rc)
        return rc;
    const unsigned char *p = data;
    if (size < HEAD_SIZE) {
        free(data);
        return corrupt(err, path, "shorter than its head");
    }
    out->input_triangles = sl_get_u64(p);
    out->diagonal = get_f64(p + 8);
    uint32_t count = sl_get_u32(p + 16);
    uint64_t left = size - HEAD_SIZE;
    p += HEAD_SIZE;
    if (count > left / RECORD_SIZE) {
        free(data);
        return corrupt(err, path, "more levels than the file holds");
    }
    out->meshes = calloc(count ? count : 1, sizeof *out->meshes);
    if (!out->meshes) {
        free(data);
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "%u levels", count);
    }
    for (uint32_t i = 0; i < count && rc == 0; i++) {
        out->count = i + 1;
        rc = read_mesh(&p, &left, &out->meshes[i], path, err);
    }
    if (rc == 0 && left)
        rc = corrupt(err, path, "bytes after the last level");
    free(data);
    if (rc)
        sl_cluster_list_release(out);
    return rc;
}
