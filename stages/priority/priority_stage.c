/* priority stage entry and its file, priority.slpri (priority.h; docs/formats.md). */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"
#include "runtime/octree_io.h"
#include "stages/merge/merge.h"
#include "stages/priority/priority.h"

#define PRIORITY_STAGE_VERSION 5u /* 2: error-driven order by default; 3: metric auto (qef
                                      on octrees with dual vertices) by default; 4: format 2;
                                      5: format 3 */
#define PRIORITY_MAGIC "SLPRIORI"
#define PRIORITY_FORMAT_VERSION 3u /* 2: the internal nodes' neighbour links alone, and the
                                      whole table's count; 3: the error per expansion, no
                                      per-node area difference or error (224 MB at 20 M) */
#define PRIORITY_HEADER 24

void sl_priority_release(sl_priority *p)
{
    free(p->lod_array);
    free(p->area_difference);
    free(p->node_error);
    free(p->expansion_error);
    sl_neighbours_release(&p->neighbours);
    memset(p, 0, sizeof *p);
}

int sl_priority_write(const char *path, const sl_priority *p, uint32_t stage_version,
                      sl_error *err)
{
    unsigned char header[PRIORITY_HEADER];
    sl_put_u32(header, p->node_count);
    sl_put_u32(header + 4, p->expansion_count);
    sl_put_u64(header + 8, p->neighbours.count);
    sl_put_u64(header + 16, p->neighbour_links);
    size_t n = p->node_count;
    sl_artifact_part parts[] = {
        {header, sizeof header},
        {p->lod_array, (size_t)p->expansion_count * 4},
        {p->expansion_error, (size_t)p->expansion_count * 4},
        {p->neighbours.mask, n * 4},
        {p->neighbours.base, n * 4},
        {p->neighbours.index, (size_t)p->neighbours.count * 4},
    };
    return sl_artifact_write(path, PRIORITY_MAGIC, PRIORITY_FORMAT_VERSION, stage_version, parts,
                             (int)(sizeof parts / sizeof parts[0]), err);
}

/* Every node's mask and base against the links held (the leaves' masks are 0), the
 * indices against the node count. */
static int validate(const sl_priority *p, const sl_octree *t, const char *path, sl_error *err)
{
    for (uint32_t i = 0; i < p->expansion_count; i++)
        if (p->lod_array[i] >= t->node_count || !t->nodes[p->lod_array[i]].child_mask)
            return sl_error_corrupt(err, path, "invalid priority file: LOD array entry is not an internal node");
    for (uint32_t i = 0; i < p->node_count; i++) {
        uint64_t count = (uint64_t)__builtin_popcount(p->neighbours.mask[i] & 0x7ffffff);
        if ((p->neighbours.mask[i] >> 13 & 1) || p->neighbours.mask[i] >> 27 ||
            (uint64_t)p->neighbours.base[i] + count > p->neighbours.count)
            return sl_error_corrupt(err, path, "invalid priority file: neighbour table out of range");
    }
    for (uint32_t i = 0; i < p->expansion_count; i++)
        if (!isfinite(p->expansion_error[i]))
            return sl_error_corrupt(err, path, "invalid priority file: non-finite error");
    for (uint64_t i = 0; i < p->neighbours.count; i++)
        if (p->neighbours.index[i] >= t->node_count)
            return sl_error_corrupt(err, path, "invalid priority file: neighbour index out of range");
    return 0;
}

/* Read in order straight into the arrays (sl_artifact_reader): the whole body beside them
 * was 836 MB more at 20 M triangles. The counts are checked against the body's size before
 * they size anything; the tables once the checksum is. */
int sl_priority_read(const char *path, const sl_octree *t, sl_priority *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    sl_artifact_reader reader;
    int rc = sl_artifact_reader_open(&reader, path, PRIORITY_MAGIC, PRIORITY_FORMAT_VERSION,
                                     PRIORITY_FORMAT_VERSION, (uint64_t)1 << 40, err);
    if (rc)
        return rc;
    uint64_t size = reader.info.body_size;
    unsigned char header[PRIORITY_HEADER];
    rc = size < PRIORITY_HEADER ? sl_error_corrupt(err, path, "invalid priority file: truncated header")
                                : sl_artifact_reader_take(&reader, header, sizeof header, err);
    if (rc == 0) {
        out->node_count = sl_get_u32(header);
        out->expansion_count = sl_get_u32(header + 4);
        out->neighbours.count = sl_get_u64(header + 8);
        out->neighbour_links = sl_get_u64(header + 16);
        uint64_t n = out->node_count;
        if (n != t->node_count || out->expansion_count > n || out->neighbour_links > 26 * n ||
            out->neighbours.count > out->neighbour_links ||
            size != PRIORITY_HEADER +
                        4 * (2 * (uint64_t)out->expansion_count + 2 * n + out->neighbours.count))
            rc = sl_error_corrupt(err, path, "invalid priority file: counts do not match the octree or the file size");
    }
    uint64_t n = out->node_count;
    if (rc == 0)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->lod_array, (uint64_t)out->expansion_count * 4, err);
    if (rc == 0)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->expansion_error, (uint64_t)out->expansion_count * 4, err);
    if (rc == 0)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->neighbours.mask, n * 4, err);
    if (rc == 0)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->neighbours.base, n * 4, err);
    if (rc == 0)
        rc = sl_artifact_reader_take_new(&reader, (void **)&out->neighbours.index, out->neighbours.count * 4, err);
    if (rc == 0)
        rc = sl_artifact_reader_finish(&reader, err);
    sl_artifact_reader_close(&reader);
    if (rc == 0)
        rc = validate(out, t, path, err);
    if (rc)
        sl_priority_release(out);
    return rc;
}

static const sl_option priority_options[] = {
    {"priority", "metric", SL_OPT_ENUM, "auto", 0, 0, "auto|qef|error|hausdorff|area",
     "What orders the node expansions, so what the levels between the coarsest and the "
     "finest look like. auto: qef when the octree has quadric vertices ([octree] vertices "
     "= qef), else error. qef: the quadric error (squared distance of the input surface to "
     "the vertices' tangent planes) an expansion removes, per triangle it adds. error: "
     "the squared distance to the finest surface that an "
     "expansion removes, per triangle it adds (lowest RMS at a triangle count); hausdorff: "
     "the largest distance to the finest surface anywhere below a node first; area: the "
     "paper's area difference M_r, in the paper's order (docs/lod.md, \"The priority "
     "metric\")."},
    SL_OPTION_END,
};

static int priority_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_priority_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    const char *name = sl_config_string(cfg, "priority", "metric");
    int metric = sl_priority_metric_parse(name);
    if (metric < 0) {
        free(c);
        return sl_error_set(err, SL_E_CONFIG, 0, "[priority] metric", "unknown metric '%s'", name);
    }
    c->metric = (sl_priority_metric)metric;
    *out = c;
    return 0;
}

sl_priority_config sl_priority_default_config(void)
{
    sl_priority_config c;
    sl_stage_default_config(&sl_priority_stage, &c, sizeof c);
    return c;
}

static int priority_run(const void *config, const sl_stage_io *io, sl_error *err)
{
    const sl_priority_config *c = config;
    char in_path[PATH_MAX], out_path[PATH_MAX];
    sl_octree tree;
    int rc = sl_stage_path(in_path, io->in_dir, SL_OCTREE_FILE, err);
    if (rc == 0)
        rc = sl_stage_path(out_path, io->out_dir, SL_PRIORITY_FILE, err);
    if (rc == 0)
        rc = sl_octree_read(in_path, &tree, err);
    if (rc)
        return rc;
    if (sl_octree_dual(&tree) && !tree.node_error) { /* an LOD model's octree, not the merge's */
        sl_octree_release(&tree);
        return sl_error_set(err, SL_E_CORRUPT, 0, in_path,
                            "invalid octree: quadric vertices without node errors and areas");
    }
    sl_priority_metric metric = c->metric;
    if (metric == SL_PRIORITY_AUTO)
        metric = sl_octree_dual(&tree) ? SL_PRIORITY_QEF : SL_PRIORITY_ERROR;
    if (metric == SL_PRIORITY_QEF && !sl_octree_dual(&tree)) {
        sl_octree_release(&tree);
        return sl_error_set(err, SL_E_CONFIG, 0, "[priority] metric",
                            "qef needs quadric vertices: set [octree] vertices = qef");
    }
    sl_priority p;
    memset(&p, 0, sizeof p);
    p.node_count = tree.node_count;
    p.lod_array = malloc(tree.node_count * sizeof *p.lod_array);
    p.area_difference = malloc(tree.node_count * sizeof *p.area_difference);
    p.node_error = malloc(tree.node_count * sizeof *p.node_error);
    if (!p.lod_array || !p.area_difference || !p.node_error)
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = sl_stage_step(io, "priority: metrics", 0.0, err);
    if (rc == 0 && sl_priority_metrics(&tree, p.area_difference, p.node_error))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = sl_stage_step(io, "priority: neighbours", 0.3, err);
    /* The order asks for the neighbours of parents only, and the crack stage for those of
     * internal nodes: a leaf's are counted (the model's header keeps the whole table's
     * count, which a reader that rebuilds the table checks), not kept. */
    if (rc == 0 && sl_neighbours_build_internal(&tree, &p.neighbours, &p.neighbour_links))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = sl_stage_step(io, "priority: keys", 0.4, err);
    float *key = rc == 0 ? malloc((tree.node_count ? tree.node_count : 1) * sizeof *key) : NULL;
    if (rc == 0 && (!key || sl_priority_keys(&tree, metric, p.area_difference, key)))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        rc = sl_stage_step(io, "priority: order", 0.8, err);
    if (rc == 0)
        rc = sl_priority_order(&tree, &p.neighbours, key, metric != SL_PRIORITY_AREA,
                               p.lod_array, &p.expansion_count, err);
    free(key);
    if (rc == 0 && !(p.expansion_error = malloc(((size_t)p.expansion_count + 1) * sizeof *p.expansion_error)))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory");
    if (rc == 0)
        for (uint32_t i = 0; i < p.expansion_count; i++)
            p.expansion_error[i] = p.node_error[p.lod_array[i]];
    if (rc == 0)
        rc = sl_stage_step(io, "priority: write", 0.95, err);
    if (rc == 0)
        rc = sl_priority_write(out_path, &p, PRIORITY_STAGE_VERSION, err);
    if (rc == 0) {
        double total = 0, top = 0;
        for (uint32_t i = 0; i < p.expansion_count; i++) {
            total += p.area_difference[p.lod_array[i]];
            top = fmax(top, p.area_difference[p.lod_array[i]]);
        }
        sl_json_string(io->report, "metric", sl_priority_metric_name(metric));
        sl_json_u64(io->report, "expansions", p.expansion_count);
        sl_json_double(io->report, "area_difference_total", total);
        sl_json_double(io->report, "area_difference_max", top);
        sl_json_double(io->report, "root_error", p.node_error[0]);
    }
    sl_priority_release(&p);
    sl_octree_release(&tree);
    return rc;
}

const sl_stage sl_priority_stage = {
    .name = "priority",
    .methods = SL_METHOD_OCTREE,
    .description = "octree -> error-driven (or area-difference) LOD array (paper 1 section 2.3)",
    .version = PRIORITY_STAGE_VERSION,
    .options = priority_options,
    .configure = priority_configure,
    .release_config = free,
    .run = priority_run,
};
