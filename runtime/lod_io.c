/* .slod reading and writing (see lod_io.h). */
#include "runtime/lod_io.h"

#include <errno.h>
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

static void *take(const unsigned char **at, uint64_t bytes)
{
    void *p = malloc(bytes ? bytes : 1);
    if (p && bytes)
        memcpy(p, *at, bytes);
    *at += bytes;
    return p;
}

/* `stored`: the section holds the neighbour table (format 2); else it is rebuilt from the
 * octree and must have the count the header declares. */
static int parse_lod(sl_lod_model *m, const unsigned char *p, uint64_t size, int stored,
                     const char *path, sl_error *err)
{
    if (size < LOD_HEADER_SIZE)
        return sl_lod_corrupt(err, path, "truncated LOD header");
    uint64_t e = sl_get_u32(p), n = sl_get_u32(p + 4);
    uint64_t neighbours = sl_get_u64(p + 8);
    m->transitions.count = sl_get_u64(p + 16);
    if (n != m->tree.node_count || e > n || neighbours > 26 * n ||
        m->transitions.count > 51 * n ||
        size != LOD_HEADER_SIZE + 4 * e + 8 * (e + 1) + 4 * (e + 1) + 4 * n +
                    (stored ? 8 * n + 4 * neighbours : 0) + 4 * m->transitions.count)
        return sl_lod_corrupt(err, path, "LOD section sizes do not match the file");
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
        rc = sl_lod_model_derive(out, stored, out->neighbours.count, name, err);
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
        rc = sl_lod_corrupt(err, path, version >= 3 ? "format 3 without packed parts"
                                             : "packed parts in a format 2 file");
    else if (rc == 0 && packed && (sl_get_u32(body) == SL_PACK_MAGIC_CHECKED) != (version >= 5))
        rc = sl_lod_corrupt(err, path, version >= 5 ? "format 5 without checked pieces"
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
