/* The checks every reader makes once a model's tables are loaded, and what generation
 * derives from them (lod_io.h: sl_lod_model_derive), shared by the level-order reader
 * (lod_io.c) and format 5's (lod_order_read.c). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "runtime/lod_io.h"
#include "runtime/lod_model.h"

int sl_lod_corrupt(sl_error *err, const char *path, const char *what)
{
    return sl_error_corrupt(err, path, "invalid LOD model: %s", what);
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
            rc = sl_lod_corrupt(err, path, "the LOD array is not an expansion order");
        else
            seen[node] = 1;
    }
    free(seen);
    /* A frontier after k expansions has at most 1 + 7k cells: the sizes generation
     * allocates from this table stay bounded whatever the file says. */
    for (uint32_t i = 0; i <= m->expansion_count && !rc; i++)
        if (m->accumulation[i] > (uint64_t)SL_MC_MAX_TRIANGLES * (1 + 7 * (uint64_t)i))
            rc = sl_lod_corrupt(err, path, "accumulation table out of range");
    /* Records must not overlap: loading rewrites their crossing ids in place, and one
     * record's ids read as another's header would change its length. */
    uint8_t *used = calloc(m->transitions.count ? m->transitions.count : 1, 1);
    if (!used && !rc)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, path, "out of memory");
    for (uint32_t i = 0; i < n && !rc; i++) {
        uint32_t mask = m->neighbours.mask[i];
        if (mask >> 27 || (mask >> 13 & 1) ||
            (uint64_t)m->neighbours.base[i] + (uint64_t)__builtin_popcount(mask) > m->neighbours.count)
            rc = sl_lod_corrupt(err, path, "neighbour table out of range");
        uint32_t tb = m->transitions.base[i];
        if (!rc && tb != SL_OCTREE_NONE) {
            if ((uint64_t)tb + 3 > m->transitions.count)
                rc = sl_lod_corrupt(err, path, "transition record out of range");
            else {
                const uint32_t *w = m->transitions.words + tb;
                uint64_t ids = (uint64_t)__builtin_popcount(w[1] & 0xffffff) +
                               (uint64_t)__builtin_popcount(w[2] & 0xffffff);
                if ((uint64_t)tb + 3 + ids > m->transitions.count)
                    rc = sl_lod_corrupt(err, path, "transition record out of range");
                for (uint64_t j = 0; !rc && j < ids; j++)
                    if (w[3 + j] >= t->crossing_count)
                        rc = sl_lod_corrupt(err, path, "transition crossing out of range");
                for (uint64_t j = 0; !rc && j < 3 + ids; j++)
                    if (used[tb + j]++)
                        rc = sl_lod_corrupt(err, path, "transition records overlap");
            }
        } else if (!rc && t->nodes[i].level > 0) {
            rc = sl_lod_corrupt(err, path, "internal node without a transition record");
        }
    }
    free(used);
    for (uint64_t i = 0; i < m->neighbours.count && !rc; i++)
        if (m->neighbours.index[i] >= n)
            rc = sl_lod_corrupt(err, path, "neighbour index out of range");
    for (uint32_t i = 0; i <= m->expansion_count && !rc; i++)
        if (!isfinite(m->error_after[i]))
            rc = sl_lod_corrupt(err, path, "non-finite error");
    return rc;
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
            return sl_lod_corrupt(err, path, "neighbour count differs from the octree's");
        if (declared == UINT64_MAX)
            declared = all;
    }
    m->neighbour_links = declared;
    return validate(m, path, err);
}

/* The checks and what generation derives from the tables (after the body is gone). */
int sl_lod_model_derive(sl_lod_model *out, int stored, uint64_t declared, const char *name,
                        sl_error *err)
{
    int rc = check_lod(out, stored, declared, name, err);
    if (rc)
        return rc;
    if (sl_lod_model_localize(out) || sl_lod_model_prepare(out))
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    return 0;
}
