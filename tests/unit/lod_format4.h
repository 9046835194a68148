/* Model format 4 as the crack stage wrote it before format 5 (levels order, one packed
 * body without piece checks): the tests write it to check that such files, which
 * museums keep, still read and cut the same, and to hand the level-order reader models
 * whose contents are hostile in ways format 5's writer cannot express (its reordering
 * presumes a tree). */
#ifndef SCANLOD_TESTS_LOD_FORMAT4_H
#define SCANLOD_TESTS_LOD_FORMAT4_H

#include <stdlib.h>

#include "core/artifact.h"
#include "runtime/lod_io.h"
#include "runtime/lod_pack.h"
#include "runtime/octree_io.h"

static uint16_t format4_record(const sl_octree *t, const sl_artifact_part *part, int index)
{
    if (index == 0)
        return 0; /* the header */
    if (part->data == (const void *)t->nodes)
        return sizeof *t->nodes;
    if (part->data == (const void *)t->crossing_position ||
        part->data == (const void *)t->vertex_position)
        return 12;
    return 4;
}

static int write_format4(const char *path, const sl_lod_model *m, sl_error *err)
{
    unsigned char octree_header[512], header[24];
    sl_artifact_part octree[SL_OCTREE_PARTS];
    sl_pack_part parts[SL_OCTREE_PARTS + 6];
    int count = sl_octree_parts(&m->tree, octree_header, octree, 0);
    for (int i = 0; i < count; i++)
        parts[i] = (sl_pack_part){octree[i].data, octree[i].size,
                                  format4_record(&m->tree, &octree[i], i)};
    uint32_t n = m->tree.node_count, e = m->expansion_count;
    sl_put_u32(header, e);
    sl_put_u32(header + 4, n);
    sl_put_u64(header + 8, m->neighbours.index ? m->neighbours.count : m->neighbour_links);
    sl_put_u64(header + 16, m->transitions.count);
    parts[count++] = (sl_pack_part){header, sizeof header, 0};
    parts[count++] = (sl_pack_part){m->lod_array, (size_t)e * 4, 4};
    parts[count++] = (sl_pack_part){m->accumulation, ((size_t)e + 1) * 8, 8};
    parts[count++] = (sl_pack_part){m->error_after, ((size_t)e + 1) * 4, 4};
    parts[count++] = (sl_pack_part){m->transitions.base, (size_t)n * 4, 4};
    parts[count++] = (sl_pack_part){m->transitions.words, (size_t)m->transitions.count * 4, 4};
    void *packed = NULL;
    size_t packed_size = 0;
    if (sl_pack(parts, count, &packed, &packed_size))
        return sl_error_set(err, SL_E_NOMEM, 0, path, "out of memory packing the model");
    sl_artifact_part body = {packed, packed_size};
    int rc = sl_artifact_write(path, SL_LOD_MAGIC, 4, 1, &body, 1, err);
    free(packed);
    return rc;
}

#endif
