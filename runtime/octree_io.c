/* Octree serialisation with full validation on read (see octree_io.h). */
#include "runtime/octree_io.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_dual.h"
#include "runtime/mc_cube.h"

_Static_assert(sizeof(sl_octree_node) == 32, "sl_octree_node is stored as 32 bytes");
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "scanlod's binary formats are little-endian; add byte swapping for this host"
#endif

#define HEADER_SIZE (4 * 4 + 8 + 8 * 4 + 4 * 2 * SL_OCTREE_MAX_LEVELS + 8 * 6 + 16)
#define HAS_VERTICES 1u
/* With vertices: the per-node errors and areas are left out (the LOD model's octree since
 * model format 4: only the priority stage reads them, from octree.slot). */
#define NO_NODE_METRICS 2u
#define LOD_ORDER SL_OCTREE_FLAG_LOD_ORDER

int sl_octree_parts(const sl_octree *t, unsigned char header[512], sl_artifact_part *parts,
                    uint32_t extra_flags)
{
    unsigned char *p = header;
    sl_put_u32(p, t->depth);
    sl_put_u32(p + 4, t->node_count);
    sl_put_u32(p + 8, t->crossing_count);
    sl_put_u32(p + 12, t->crossing_color != NULL);
    sl_put_u64(p + 16, t->node_crossing_count);
    sl_put_f64(p + 24, t->leaf_size);
    for (int a = 0; a < 3; a++)
        sl_put_f64(p + 32 + 8 * a, t->origin[a]);
    p += 56;
    for (int l = 0; l < SL_OCTREE_MAX_LEVELS; l++, p += 8) {
        sl_put_u32(p, t->level_first[l]);
        sl_put_u32(p + 4, t->level_count[l]);
    }
    const uint64_t stats[6] = {t->stats.sign_case[0], t->stats.sign_case[1], t->stats.sign_case[2],
                               t->stats.sign_case[3], t->stats.inherited_crossings,
                               t->stats.fallback_crossings};
    for (int i = 0; i < 6; i++, p += 8)
        sl_put_u64(p, stats[i]);
    sl_put_u32(p, t->vertex_count);
    int metrics = sl_octree_dual(t) && t->node_error && t->node_area;
    sl_put_u32(p + 4,
               (sl_octree_dual(t) ? HAS_VERTICES | (metrics ? 0 : NO_NODE_METRICS) : 0) | extra_flags);
    sl_put_u64(p + 8, 0);
    int n = 0;
    parts[n++] = (sl_artifact_part){header, HEADER_SIZE};
    parts[n++] = (sl_artifact_part){t->nodes, (size_t)t->node_count * sizeof *t->nodes};
    parts[n++] = (sl_artifact_part){t->node_crossings,
                                    (size_t)t->node_crossing_count * sizeof *t->node_crossings};
    parts[n++] = (sl_artifact_part){t->crossing_position, (size_t)t->crossing_count * 3 * sizeof(float)};
    if (t->crossing_color)
        parts[n++] = (sl_artifact_part){t->crossing_color, (size_t)t->crossing_count * 4};
    if (sl_octree_dual(t)) {
        parts[n++] = (sl_artifact_part){t->vertex_first, ((size_t)t->node_count + 1) * 4};
        parts[n++] = (sl_artifact_part){t->vertex_position, (size_t)t->vertex_count * 12};
        if (t->crossing_color)
            parts[n++] = (sl_artifact_part){t->vertex_color, (size_t)t->vertex_count * 4};
        if (metrics) {
            parts[n++] = (sl_artifact_part){t->node_error, (size_t)t->node_count * 4};
            parts[n++] = (sl_artifact_part){t->node_area, (size_t)t->node_count * 4};
        }
    }
    return n;
}

static int bad(sl_error *err, const char *name, const char *what)
{
    return sl_error_set(err, SL_E_CORRUPT, 0, name, "invalid octree: %s", what);
}

static uint64_t morton_of(const sl_octree_node *n)
{
    return sl_morton3((uint32_t)n->x, (uint32_t)n->y, (uint32_t)n->z);
}

uint16_t sl_octree_edge_mask(uint8_t inside)
{
    uint16_t mask = 0;
    for (int e = 0; e < 12; e++)
        mask |= (uint16_t)(((inside >> sl_mc_edge_c0(e)) ^ (inside >> sl_mc_edge_c1(e))) & 1) << e;
    return mask;
}

/* The root node's cube in world coordinates (needs a valid leaf size and depth). */
static void root_cube(const sl_octree *t, double lo[3], double hi[3])
{
    double root = ldexp(t->leaf_size, (int)t->depth);
    const int32_t corner[3] = {t->nodes[0].x, t->nodes[0].y, t->nodes[0].z};
    for (int a = 0; a < 3; a++) {
        lo[a] = t->origin[a] + corner[a] * root;
        hi[a] = lo[a] + root;
    }
}

int sl_octree_grid_ok(const sl_octree *t)
{
    const double limit = SL_OCTREE_MAX_EXTENT;
    if (!(t->leaf_size > 0) || !isfinite(t->leaf_size) || t->depth >= SL_OCTREE_MAX_LEVELS ||
        t->node_count == 0 || !(ldexp(t->leaf_size, (int)t->depth) <= limit))
        return 0;
    double lo[3], hi[3];
    root_cube(t, lo, hi);
    for (int a = 0; a < 3; a++)
        if (!(fabs(t->origin[a]) <= limit) || !(fabs(lo[a]) <= 2 * limit) ||
            !(fabs(hi[a]) <= 2 * limit))
            return 0;
    return 1;
}


/* Why item i of a table is invalid, or NULL (ctx: the check's own data). */
typedef const char *(*item_check)(const sl_octree *t, uint64_t i, const void *ctx);

/* The problem of the smallest i in [0, n) that has one, or NULL: the message a serial
 * loop over the items would give, found by fixed chunks in parallel (reading a 1 M
 * triangle model spent about half the priority stage checking its octree, on one
 * thread). */
static const char *first_problem(const sl_octree *t, uint64_t n, item_check check,
                                 const void *ctx)
{
    enum { CHUNKS = 64 };
    uint64_t best = UINT64_MAX;
    const char *why = NULL;
#pragma omp parallel for schedule(dynamic, 1)
    for (int c = 0; c < CHUNKS; c++)
        for (uint64_t i = n * (uint64_t)c / CHUNKS; i < n * (uint64_t)(c + 1) / CHUNKS; i++) {
            const char *w = check(t, i, ctx);
            if (!w)
                continue;
#pragma omp critical(sl_octree_first_problem)
            if (i < best) {
                best = i;
                why = w;
            }
            break;
        }
    return why;
}

static const char *node_problem(const sl_octree *t, uint64_t at, const void *ctx)
{
    (void)ctx;
    uint32_t i = (uint32_t)at;
    const sl_octree_node *n = &t->nodes[i];
    int kids = __builtin_popcount(n->child_mask);
    if (n->level > t->depth || i < t->level_first[n->level] ||
        i >= t->level_first[n->level] + t->level_count[n->level])
        return "node outside its level's range";
    if (n->x < 0 || n->y < 0 || n->z < 0 || n->x >= (1 << 20) || n->y >= (1 << 20) ||
        n->z >= (1 << 20))
        return "node coordinates out of range";
    if ((i == 0) != (n->parent == SL_OCTREE_NONE) || (i && n->parent >= i))
        return "bad parent link";
    if (kids && (n->level == 0 || n->first_child == SL_OCTREE_NONE ||
                 n->first_child < t->level_first[n->level - 1] ||
                 (uint64_t)n->first_child + (uint64_t)kids >
                     (uint64_t)t->level_first[n->level - 1] + t->level_count[n->level - 1]))
        return "bad child range";
    /* Each child names this node as its parent and sits in its octant: child ranges are
     * then disjoint, and a walk down the tree meets every node once. */
    for (int j = 0, mask = n->child_mask; mask; mask &= mask - 1, j++) {
        const sl_octree_node *c = &t->nodes[n->first_child + (uint32_t)j];
        int o = __builtin_ctz((unsigned)mask);
        if (c->parent != i || c->x != 2 * n->x + (o & 1) || c->y != 2 * n->y + (o >> 1 & 1) ||
            c->z != 2 * n->z + (o >> 2))
            return "child does not belong to its parent";
    }
    if (i > t->level_first[n->level] && t->nodes[i - 1].level == n->level &&
        morton_of(&t->nodes[i - 1]) >= morton_of(n))
        return "nodes of a level out of Morton order";
    /* The crossings are exactly the edges whose corners differ in sign: generation looks
     * up a crossing for every such edge and for no other. */
    if ((uint64_t)n->crossing_base + (uint64_t)__builtin_popcount(n->edge_mask) >
            t->node_crossing_count || n->edge_mask != sl_octree_edge_mask(n->inside))
        return "bad crossing range";
    return NULL;
}

static const char *crossing_id_problem(const sl_octree *t, uint64_t i, const void *ctx)
{
    (void)ctx;
    return t->node_crossings[i] >= t->crossing_count ? "crossing id out of range" : NULL;
}

/* ctx: the root's cube with its slack, lo[3] then hi[3]. */
static const char *position_problem(const sl_octree *t, uint64_t i, const void *ctx)
{
    const double *box = ctx;
    double v = t->crossing_position[i];
    if (!isfinite(v))
        return "non-finite crossing position";
    if (!(v >= box[i % 3] && v <= box[3 + i % 3]))
        return "crossing outside the octree's cube";
    return NULL;
}

/* Every index in range, levels consistent, the tree a tree: nothing downstream
 * re-checks, so a file with a valid checksum but hostile contents stops here. */
static int validate(const sl_octree *t, const char *name, sl_error *err)
{
    if (t->depth >= SL_OCTREE_MAX_LEVELS || !(t->leaf_size > 0) || !isfinite(t->leaf_size))
        return bad(err, name, "depth or leaf size out of range");
    if (!sl_octree_grid_ok(t))
        return bad(err, name, "grid origin or extent out of range");
    uint64_t sum = 0;
    for (uint32_t l = 0; l < SL_OCTREE_MAX_LEVELS; l++) {
        if (l > t->depth && t->level_count[l])
            return bad(err, name, "nodes above the root level");
        if (l <= t->depth && ((uint64_t)t->level_first[l] + t->level_count[l] > t->node_count))
            return bad(err, name, "level range outside the node table");
        sum += t->level_count[l];
    }
    if (sum != t->node_count || t->level_count[t->depth] != 1 || t->level_first[t->depth] != 0)
        return bad(err, name, "level counts do not add up to one root");
    const char *why = first_problem(t, t->node_count, node_problem, NULL);
    if (why)
        return bad(err, name, why);
    uint64_t children = 0;
#pragma omp parallel for schedule(static) reduction(+ : children)
    for (uint32_t i = 0; i < t->node_count; i++)
        children += (uint64_t)__builtin_popcount(t->nodes[i].child_mask);
    if (children != (uint64_t)t->node_count - 1)
        return bad(err, name, "nodes outside the tree");
    if ((why = first_problem(t, t->node_crossing_count, crossing_id_problem, NULL)))
        return bad(err, name, why);
    /* Crossings lie on cube edges, so inside the root's cube, give or take their rounding
     * to float (a scan far from the origin with a fine grid rounds by more than a leaf). */
    double box[6];
    root_cube(t, box, box + 3);
    for (int a = 0; a < 3; a++) {
        double slack = t->leaf_size + 2 * FLT_EPSILON * fmax(fabs(box[a]), fabs(box[3 + a]));
        box[a] -= slack;
        box[3 + a] += slack;
    }
    if ((why = first_problem(t, 3 * (uint64_t)t->crossing_count, position_problem, box)))
        return bad(err, name, why);
    return 0;
}

/* Dual vertices: each node's count is its uniform loop count (or 0: trimmed), or 1 or 0
 * for a node without loops; every vertex finite and in its node's cube (give or take
 * float rounding: the normals' scaling relies on it, lod_mesh.c); errors and areas finite
 * and not negative. */
static const char *vertex_order_problem(const sl_octree *t, uint64_t i, const void *ctx)
{
    (void)ctx;
    return t->vertex_first[i + 1] < t->vertex_first[i] ? "vertex ranges out of order" : NULL;
}

/* ctx: the uniform loop table. */
static const char *node_vertices_problem(const sl_octree *t, uint64_t at, const void *ctx)
{
    const sl_mc_triangles *table = ctx;
    uint32_t i = (uint32_t)at;
    const sl_octree_node *n = &t->nodes[i];
    uint32_t first = t->vertex_first[i], next = t->vertex_first[i + 1];
    uint32_t count = next - first, loops = table[n->inside].loops;
    if (count != 0 && count != (loops ? loops : 1))
        return "vertex count does not match the node's loops";
    if (t->node_error && (!isfinite(t->node_error[i]) || !(t->node_error[i] >= 0) ||
                          !isfinite(t->node_area[i]) || !(t->node_area[i] >= 0)))
        return "node error or area not finite and positive";
    double lo[3], hi[3];
    sl_octree_corner_world(t, n, 0, lo);
    sl_octree_corner_world(t, n, 7, hi);
    for (uint32_t v = first; v < next; v++)
        for (int a = 0; a < 3; a++) {
            double slack = 2 * FLT_EPSILON * fmax(fabs(lo[a]), fabs(hi[a])) +
                           1e-6 * (hi[a] - lo[a]);
            double x = t->vertex_position[3 * (size_t)v + (size_t)a];
            if (!isfinite(x) || !(x >= lo[a] - slack && x <= hi[a] + slack))
                return "vertex outside its node's cube";
        }
    return NULL;
}

static int validate_vertices(const sl_octree *t, const char *name, sl_error *err)
{
    if (t->vertex_first[0] != 0 || t->vertex_first[t->node_count] != t->vertex_count)
        return bad(err, name, "vertex ranges do not cover the vertex table");
    /* All ranges in order before any is read. */
    const char *why = first_problem(t, t->node_count, vertex_order_problem, NULL);
    if (!why)
        why = first_problem(t, t->node_count, node_vertices_problem, sl_dual_uniform_table());
    return why ? bad(err, name, why) : 0;
}

static void *copy_out(const unsigned char *src, uint64_t size)
{
    void *p = malloc(size ? size : 1);
    if (p && size)
        memcpy(p, src, size);
    return p;
}

int sl_octree_parse_header(const unsigned char *body, uint64_t size, const char *name,
                           sl_octree *out, sl_octree_layout *lay, sl_error *err)
{
    sl_octree_init(out);
    memset(lay, 0, sizeof *lay);
    if (size < HEADER_SIZE)
        return bad(err, name, "truncated header");
    const unsigned char *p = body;
    out->depth = sl_get_u32(p);
    out->node_count = sl_get_u32(p + 4);
    out->crossing_count = sl_get_u32(p + 8);
    uint32_t has_color = sl_get_u32(p + 12);
    out->node_crossing_count = sl_get_u64(p + 16);
    out->leaf_size = sl_get_f64(p + 24);
    for (int a = 0; a < 3; a++)
        out->origin[a] = sl_get_f64(p + 32 + 8 * a);
    p += 56;
    for (int l = 0; l < SL_OCTREE_MAX_LEVELS; l++, p += 8) {
        out->level_first[l] = sl_get_u32(p);
        out->level_count[l] = sl_get_u32(p + 4);
    }
    uint64_t *stats[6] = {&out->stats.sign_case[0], &out->stats.sign_case[1],
                          &out->stats.sign_case[2], &out->stats.sign_case[3],
                          &out->stats.inherited_crossings, &out->stats.fallback_crossings};
    for (int i = 0; i < 6; i++, p += 8)
        *stats[i] = sl_get_u64(p);
    uint32_t vertex_count = sl_get_u32(p), flags = sl_get_u32(p + 4);
    if (has_color > 1 || out->node_count == 0 || out->node_crossing_count > (uint64_t)1 << 40 ||
        (flags & ~(HAS_VERTICES | NO_NODE_METRICS | LOD_ORDER)) || sl_get_u64(p + 8) != 0 ||
        (!(flags & HAS_VERTICES) && (vertex_count || (flags & NO_NODE_METRICS))) ||
        (uint64_t)vertex_count > (uint64_t)SL_OCTREE_MAX_NODE_VERTICES * out->node_count)
        return bad(err, name, "header counts out of range");
    /* 64-bit sizes: no overflow for 32-bit counts. */
    int dual = (flags & HAS_VERTICES) != 0, metrics = dual && !(flags & NO_NODE_METRICS);
    lay->flags = flags;
    lay->has_color = (int)has_color;
    lay->vertex_count = vertex_count;
    lay->nodes = (uint64_t)out->node_count * sizeof(sl_octree_node);
    lay->ids = out->node_crossing_count * 4;
    lay->positions = (uint64_t)out->crossing_count * 12;
    lay->colors = has_color ? (uint64_t)out->crossing_count * 4 : 0;
    lay->vertex_first = dual ? ((uint64_t)out->node_count + 1) * 4 : 0;
    lay->vertices = (uint64_t)vertex_count * 12;
    lay->vertex_colors = has_color ? (uint64_t)vertex_count * 4 : 0;
    lay->metrics = metrics ? (uint64_t)out->node_count * 4 : 0;
    lay->total = HEADER_SIZE + lay->nodes + lay->ids + lay->positions + lay->colors +
                 lay->vertex_first + lay->vertices + lay->vertex_colors + 2 * lay->metrics;
    return 0;
}

int sl_octree_check(sl_octree *t, const char *name, sl_error *err)
{
    int rc = validate(t, name, err);
    if (rc == 0 && sl_octree_dual(t))
        rc = validate_vertices(t, name, err);
    if (rc == 0 && sl_octree_index(t))
        rc = sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
    return rc;
}

/* Where a parse takes its arrays from: a body in memory (`at`), or a file read in order. */
typedef struct part_source {
    const unsigned char *at;
    sl_artifact_reader *reader;
} part_source;

static int take_part(part_source *src, void *dest, uint64_t size, const char *name, sl_error *err)
{
    void **out = dest;
    if (src->reader)
        return sl_artifact_reader_take_new(src->reader, out, size, err);
    *out = copy_out(src->at, size);
    src->at += size;
    return *out ? 0 : sl_error_set(err, SL_E_NOMEM, ENOMEM, name, "out of memory");
}

/* The arrays after the header, in file order. On failure the tree is released. */
static int take_arrays(part_source *src, const sl_octree_layout *lay, const char *name,
                       sl_octree *out, sl_error *err)
{
    int rc = take_part(src, &out->nodes, lay->nodes, name, err);
    if (rc == 0)
        rc = take_part(src, &out->node_crossings, lay->ids, name, err);
    if (rc == 0)
        rc = take_part(src, &out->crossing_position, lay->positions, name, err);
    if (rc == 0 && lay->has_color)
        rc = take_part(src, &out->crossing_color, lay->colors, name, err);
    if (rc == 0 && (lay->flags & HAS_VERTICES)) {
        out->vertex_count = lay->vertex_count;
        rc = take_part(src, &out->vertex_first, lay->vertex_first, name, err);
        if (rc == 0)
            rc = take_part(src, &out->vertex_position, lay->vertices, name, err);
        if (rc == 0 && lay->has_color)
            rc = take_part(src, &out->vertex_color, lay->vertex_colors, name, err);
        if (rc == 0 && lay->metrics)
            rc = take_part(src, &out->node_error, lay->metrics, name, err);
        if (rc == 0 && lay->metrics)
            rc = take_part(src, &out->node_area, lay->metrics, name, err);
    }
    if (rc)
        sl_octree_release(out);
    return rc;
}

int sl_octree_parse(const unsigned char *body, uint64_t size, const char *name, sl_octree *out,
                    uint64_t *used, sl_error *err)
{
    sl_octree_layout lay;
    int rc = sl_octree_parse_header(body, size, name, out, &lay, err);
    if (rc)
        return rc;
    if (lay.flags & LOD_ORDER)
        return bad(err, name, "nodes in LOD order where levels are expected");
    if (lay.total > size)
        return bad(err, name, "counts exceed the bytes present");
    part_source src = {body + HEADER_SIZE, NULL};
    rc = take_arrays(&src, &lay, name, out, err);
    if (rc == 0)
        rc = sl_octree_check(out, name, err);
    if (rc) {
        sl_octree_release(out);
        return rc;
    }
    *used = lay.total;
    return 0;
}

int sl_octree_write(const char *path, const sl_octree *t, uint32_t stage_version, sl_error *err)
{
    unsigned char header[512];
    sl_artifact_part parts[SL_OCTREE_PARTS];
    int n = sl_octree_parts(t, header, parts, 0);
    return sl_artifact_write(path, SL_OCTREE_MAGIC, SL_OCTREE_FORMAT_VERSION, stage_version,
                             parts, n, err);
}

/* Read in order straight into the tree's arrays (sl_artifact_reader): the whole body held
 * beside them was the priority stage's peak. The header's counts are checked against the
 * body's size before they size anything; the tree is checked once the checksum is. */
int sl_octree_read(const char *path, sl_octree *out, sl_error *err)
{
    sl_octree_init(out);
    sl_artifact_reader reader;
    int rc = sl_artifact_reader_open(&reader, path, SL_OCTREE_MAGIC, SL_OCTREE_FORMAT_VERSION,
                                     SL_OCTREE_FORMAT_VERSION, (uint64_t)1 << 40, err);
    if (rc)
        return rc;
    uint64_t size = reader.info.body_size;
    unsigned char header[HEADER_SIZE];
    sl_octree_layout lay;
    rc = size < HEADER_SIZE ? bad(err, path, "truncated header")
                            : sl_artifact_reader_take(&reader, header, HEADER_SIZE, err);
    if (rc == 0)
        rc = sl_octree_parse_header(header, size, path, out, &lay, err);
    if (rc == 0 && (lay.flags & LOD_ORDER))
        rc = bad(err, path, "nodes in LOD order where levels are expected");
    if (rc == 0 && lay.total > size)
        rc = bad(err, path, "counts exceed the bytes present");
    if (rc == 0 && lay.total != size)
        rc = bad(err, path, "trailing bytes");
    part_source src = {NULL, &reader};
    if (rc == 0)
        rc = take_arrays(&src, &lay, path, out, err);
    if (rc == 0)
        rc = sl_artifact_reader_finish(&reader, err);
    if (rc == 0)
        rc = sl_octree_check(out, path, err);
    if (rc)
        sl_octree_release(out);
    sl_artifact_reader_close(&reader);
    return rc;
}
