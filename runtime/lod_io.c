/* .slod reading and writing (see lod_io.h). */
#include "runtime/lod_io.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "runtime/lod_order.h"
#include "runtime/lod_pack.h"
#include "runtime/octree_io.h"

#define LOD_HEADER_SIZE 24
/* The largest plain body a packed one may declare (the envelope's own limit). */
#define PLAIN_LIMIT ((uint64_t)1 << 40)

int sl_lod_model_write(const char *path, const sl_lod_model *m, uint32_t stage_version,
                       sl_error *err)
{
    void *packed = NULL;
    size_t packed_size = 0;
    if (m->cuts_only)
        return sl_error_set(err, SL_E_INTERNAL, 0, path,
                            "a model opened for cutting only cannot be written");
    if (sl_lod_order_pack(m, SL_LOD_ORDER_PIECE, &packed, &packed_size))
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory packing the model");
    sl_artifact_part body = {packed, packed_size};
    int rc = sl_artifact_write(path, SL_LOD_MAGIC, SL_LOD_FORMAT_VERSION, stage_version, &body,
                               1, err);
    free(packed);
    return rc;
}

static int corrupt(sl_error *err, const char *path, const char *what)
{
    return sl_error_set(err, SL_E_CORRUPT, 0, path, "invalid LOD model: %s", what);
}

static void *take(const unsigned char **at, uint64_t bytes)
{
    void *p = malloc(bytes ? bytes : 1);
    if (p && bytes)
        memcpy(p, *at, bytes);
    *at += bytes;
    return p;
}

/* The LOD array must be a valid expansion order, the tables in range. */
static int validate(const sl_lod_model *m, const char *path, sl_error *err)
{
    const sl_octree *t = &m->tree;
    uint32_t n = t->node_count;
    uint8_t *seen = calloc(n ? n : 1, 1);
    if (!seen)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    int rc = 0;
    for (uint32_t i = 0; i < m->expansion_count && !rc; i++) {
        uint32_t node = m->lod_array[i];
        if (node >= n || seen[node] || !t->nodes[node].child_mask ||
            (t->nodes[node].parent != SL_OCTREE_NONE && !seen[t->nodes[node].parent]))
            rc = corrupt(err, path, "the LOD array is not an expansion order");
        else
            seen[node] = 1;
    }
    free(seen);
    /* A frontier after k expansions has at most 1 + 7k cells: the sizes generation
     * allocates from this table stay bounded whatever the file says. */
    for (uint32_t i = 0; i <= m->expansion_count && !rc; i++)
        if (m->accumulation[i] > (uint64_t)SL_MC_MAX_TRIANGLES * (1 + 7 * (uint64_t)i))
            rc = corrupt(err, path, "accumulation table out of range");
    /* Records must not overlap: loading rewrites their crossing ids in place, and one
     * record's ids read as another's header would change its length. */
    uint8_t *used = calloc(m->transitions.count ? m->transitions.count : 1, 1);
    if (!used && !rc)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    for (uint32_t i = 0; i < n && !rc; i++) {
        uint32_t mask = m->neighbours.mask[i];
        if (mask >> 27 || (mask >> 13 & 1) ||
            (uint64_t)m->neighbours.base[i] + (uint64_t)__builtin_popcount(mask) > m->neighbours.count)
            rc = corrupt(err, path, "neighbour table out of range");
        uint32_t tb = m->transitions.base[i];
        if (!rc && tb != SL_OCTREE_NONE) {
            if ((uint64_t)tb + 3 > m->transitions.count)
                rc = corrupt(err, path, "transition record out of range");
            else {
                const uint32_t *w = m->transitions.words + tb;
                uint64_t ids = (uint64_t)__builtin_popcount(w[1] & 0xffffff) +
                               (uint64_t)__builtin_popcount(w[2] & 0xffffff);
                if ((uint64_t)tb + 3 + ids > m->transitions.count)
                    rc = corrupt(err, path, "transition record out of range");
                for (uint64_t j = 0; !rc && j < ids; j++)
                    if (w[3 + j] >= t->crossing_count)
                        rc = corrupt(err, path, "transition crossing out of range");
                for (uint64_t j = 0; !rc && j < 3 + ids; j++)
                    if (used[tb + j]++)
                        rc = corrupt(err, path, "transition records overlap");
            }
        } else if (!rc && t->nodes[i].level > 0) {
            rc = corrupt(err, path, "internal node without a transition record");
        }
    }
    free(used);
    for (uint64_t i = 0; i < m->neighbours.count && !rc; i++)
        if (m->neighbours.index[i] >= n)
            rc = corrupt(err, path, "neighbour index out of range");
    for (uint32_t i = 0; i <= m->expansion_count && !rc; i++)
        if (!isfinite(m->error_after[i]))
            rc = corrupt(err, path, "non-finite error");
    return rc;
}

/* `stored`: the section holds the neighbour table (format 2); else it is rebuilt from the
 * octree and must have the count the header declares. */
static int parse_lod(sl_lod_model *m, const unsigned char *p, uint64_t size, int stored,
                     const char *path, sl_error *err)
{
    if (size < LOD_HEADER_SIZE)
        return corrupt(err, path, "truncated LOD header");
    uint64_t e = sl_get_u32(p), n = sl_get_u32(p + 4);
    uint64_t neighbours = sl_get_u64(p + 8);
    m->transitions.count = sl_get_u64(p + 16);
    if (n != m->tree.node_count || e > n || neighbours > 26 * n ||
        m->transitions.count > 51 * n ||
        size != LOD_HEADER_SIZE + 4 * e + 8 * (e + 1) + 4 * (e + 1) + 4 * n +
                    (stored ? 8 * n + 4 * neighbours : 0) + 4 * m->transitions.count)
        return corrupt(err, path, "LOD section sizes do not match the file");
    m->expansion_count = (uint32_t)e;
    const unsigned char *at = p + LOD_HEADER_SIZE;
    m->lod_array = take(&at, 4 * e);
    m->accumulation = take(&at, 8 * (e + 1));
    m->error_after = take(&at, 4 * (e + 1));
    m->neighbours.count = neighbours; /* format 3: what the rebuilt table must have */
    if (stored) {
        m->neighbours.mask = take(&at, 4 * n);
        m->neighbours.base = take(&at, 4 * n);
        m->neighbours.index = take(&at, 4 * neighbours);
    }
    m->transitions.base = take(&at, 4 * n);
    m->transitions.words = take(&at, 4 * m->transitions.count);
    if (!m->lod_array || !m->accumulation || !m->error_after || !m->transitions.base ||
        !m->transitions.words ||
        (stored && (!m->neighbours.mask || !m->neighbours.base || !m->neighbours.index)))
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    return 0;
}

/* After the body is freed: format 3's neighbour table rebuilt from the octree (the count
 * the header declared must match), then every table checked. */
static int check_lod(sl_lod_model *m, int stored, uint64_t declared, const char *path,
                     sl_error *err)
{
    uint64_t all = 0;
    if (stored) {
        declared = m->neighbours.count;
    } else {
        if (m->cuts_only ? sl_neighbours_build_internal(&m->tree, &m->neighbours, &all)
                         : sl_neighbours_build(&m->tree, &m->neighbours))
            return sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
        if (!m->cuts_only)
            all = m->neighbours.count;
        if (declared != UINT64_MAX && all != declared)
            return corrupt(err, path, "neighbour count differs from the octree's");
        if (declared == UINT64_MAX)
            declared = all;
    }
    m->neighbour_links = declared;
    return validate(m, path, err);
}

/* The octree and LOD sections of a plain body: with the neighbour table (format 2) or
 * without it (format 3, unpacked). Everything is copied out of `body`. */
static int parse_tables(const void *body, uint64_t size, int stored, const char *name,
                        sl_lod_model *out, sl_error *err)
{
    uint64_t used = 0;
    int rc = sl_octree_parse(body, size, name, &out->tree, &used, err);
    if (rc == 0) {
        sl_octree_drop_node_metrics(&out->tree); /* a format 2 or 3 model's: unread */
        rc = parse_lod(out, (const unsigned char *)body + used, size - used, stored, name, err);
    }
    return rc;
}

/* The checks and what generation derives from the tables (after the body is gone). */
static int derive(sl_lod_model *out, int stored, uint64_t declared, const char *name,
                  sl_error *err)
{
    int rc = check_lod(out, stored, declared, name, err);
    if (rc)
        return rc;
    if (sl_lod_model_localize(out) || sl_lod_model_prepare(out))
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    return 0;
}

int sl_lod_model_derive(sl_lod_model *m, uint64_t links, const char *name, sl_error *err)
{
    return derive(m, 0, links, name, err);
}

/* Parses a body (packed or plain) into `out`. `owned` (may be NULL) is the caller's copy of
 * the body to free: it goes, with the unpacked copy, as soon as the tables are copied out,
 * before the neighbour table and the derived tables are made. On failure `out` holds
 * nothing. */
static int parse_body(const void *body, uint64_t size, void *owned, const char *name,
                      sl_lod_model *out, sl_error *err)
{
    int rc, stored = !sl_pack_is_packed(body, size);
    int ordered = !stored && sl_get_u32(body) == SL_PACK_MAGIC_CHECKED; /* format 5 */
    if (!stored) {
        void *plain = NULL;
        uint64_t plain_size = 0;
        rc = sl_unpack(body, size, PLAIN_LIMIT, name, &plain, &plain_size, err);
        free(owned);
        owned = NULL;
        if (rc == 0 && ordered)
            rc = sl_lod_order_parse(plain, plain_size, out->cuts_only, name, out, err);
        else if (rc == 0)
            rc = parse_tables(plain, plain_size, 0, name, out, err);
        free(plain);
        if (ordered)
            return rc; /* built and checked, or released */
    } else {
        rc = parse_tables(body, size, 1, name, out, err);
    }
    free(owned);
    if (rc == 0)
        rc = derive(out, stored, out->neighbours.count, name, err);
    if (rc)
        sl_lod_model_release(out);
    return rc;
}

int sl_lod_model_parse(const void *body, uint64_t size, const char *name, sl_lod_model *out,
                       sl_error *err)
{
    sl_lod_model_init(out);
    return parse_body(body, size, NULL, name, out, err);
}

static int read_model(const char *path, int cuts_only, sl_lod_model *out, sl_error *err)
{
    sl_lod_model_init(out);
    void *body = NULL;
    uint64_t size = 0;
    uint32_t version = 0;
    int rc = sl_artifact_read_versions(path, SL_LOD_MAGIC, SL_LOD_OLDEST_VERSION,
                                       SL_LOD_FORMAT_VERSION, PLAIN_LIMIT, &body, &size, NULL,
                                       &version, err);
    int packed = rc == 0 && sl_pack_is_packed(body, size);
    if (rc == 0 && packed != (version >= 3))
        rc = corrupt(err, path, version >= 3 ? "format 3 without packed parts"
                                             : "packed parts in a format 2 file");
    else if (rc == 0 && packed && (sl_get_u32(body) == SL_PACK_MAGIC_CHECKED) != (version >= 5))
        rc = corrupt(err, path, version >= 5 ? "format 5 without checked pieces"
                                             : "checked pieces in a format 3 or 4 file");
    out->cuts_only = cuts_only;
    if (rc == 0)
        return parse_body(body, size, body, path, out, err);
    free(body);
    return rc;
}

int sl_lod_model_read(const char *path, sl_lod_model *out, sl_error *err)
{
    return read_model(path, 0, out, err);
}

int sl_lod_model_open(const char *path, sl_lod_model *out, sl_error *err)
{
    return read_model(path, 1, out, err);
}
