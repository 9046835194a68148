/* LOD model on analytic closed surfaces, under every priority metric, at every expansion
 * count K (41 spread K with SCANLOD_LIGHT=1): neighbouring frontier cells differ by less
 * than 2 levels, the accumulation table equals the triangles actually generated, every
 * mesh is watertight (no cracks), and a .slod roundtrip is exact and hostile files are
 * refused. The order is the same on 1 and 2 threads. Under the qef metric the models have
 * quadric vertices (the dual of the marching-cube surface, runtime/lod_dual.h), fitted to
 * the finest marching-cube surface, and their meshes face outwards. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/artifact.h"
#include "runtime/lod_io.h"
#include "stages/crack/crack.h"
#include "stages/merge/merge.h"
#include "stages/priority/priority.h"
#include "tests/check.h"
#include "tests/unit/lod_format4.h"
#include "tests/unit/mesh_checks.h"
#include "tests/unit/sealed_file.h"

typedef double (*sdf_fn)(const double p[3]);

static double blob_sdf(const double p[3])
{
    /* A sphere with a bump and a dent: regions of different detail. */
    double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    double bump = 3.0 * exp(-((p[0] - 8) * (p[0] - 8) + p[1] * p[1] + (p[2] - 5) * (p[2] - 5)) / 6.0);
    double dent = 2.0 * exp(-((p[0] + 6) * (p[0] + 6) + (p[1] - 7) * (p[1] - 7) + p[2] * p[2]) / 4.0);
    return r - 10.7 - bump + dent;
}

static double torus_sdf(const double p[3])
{
    double q = sqrt(p[0] * p[0] + p[1] * p[1]) - 9.0;
    return sqrt(q * q + p[2] * p[2]) - 3.4;
}

/* Small shapes for the fuzz seeds: models of a few kilobytes. */
static double sphere_sdf(const double p[3])
{
    return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 3.3;
}

static double tiny_sphere_sdf(const double p[3])
{
    return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1.7;
}

static double small_torus_sdf(const double p[3])
{
    double q = sqrt(p[0] * p[0] + p[1] * p[1]) - 4.0;
    return sqrt(q * q + p[2] * p[2]) - 1.6;
}

/* The expansion order as the rule reads (the stage's before it ran in rank space, with
 * its keys zeroed rather than unset): a binary max-heap over node indices, the 26 cells
 * around a popped node looked up through its parent's neighbours each time. The stage's
 * order must equal it entry for entry; *waits counts the nodes held back, so a shape that
 * never exercises the rule is seen. */
typedef struct ref_entry {
    float key;
    uint32_t node;
} ref_entry;

static int ref_before(ref_entry a, ref_entry b)
{
    return a.key > b.key || (a.key == b.key && a.node < b.node);
}

static void ref_push(ref_entry *h, uint32_t *size, ref_entry e)
{
    uint32_t i = (*size)++;
    for (; i > 0 && ref_before(e, h[(i - 1) / 2]); i = (i - 1) / 2)
        h[i] = h[(i - 1) / 2];
    h[i] = e;
}

static ref_entry ref_pop(ref_entry *h, uint32_t *size)
{
    ref_entry top = h[0], last = h[--*size];
    uint32_t i = 0;
    for (uint32_t c; (c = 2 * i + 1) < *size; i = c) {
        if (c + 1 < *size && ref_before(h[c + 1], h[c]))
            c++;
        if (!ref_before(h[c], last))
            break;
        h[i] = h[c];
    }
    if (*size > 0)
        h[i] = last;
    return top;
}

static uint32_t reference_order(const sl_octree *t, const sl_neighbours *nb, const float *key,
                                int inherit, uint32_t *order, uint32_t *waits)
{
    enum { NOT_YET, IN_HEAP, WAITING, EXPANDED };
    uint32_t n = t->node_count, k = 0, size = 0;
    ref_entry *heap = malloc(8 * (size_t)n * sizeof *heap); /* raised entries go stale in it */
    float *cur = calloc(n, sizeof *cur);
    uint8_t *state = calloc(n, 1);
    uint32_t *wait_on = malloc(n * sizeof *wait_on), *head = malloc(n * sizeof *head);
    uint32_t *next = malloc(n * sizeof *next);
    memset(head, 0xff, n * sizeof *head);
    *waits = 0;
#define REF_PUSH(node, value) (cur[node] = (value), state[node] = IN_HEAP, ref_push(heap, &size, (ref_entry){cur[node], node}))
    if (t->nodes[0].child_mask)
        REF_PUSH(0, key[0]);
    while (size > 0) {
        ref_entry top = ref_pop(heap, &size);
        uint32_t v = top.node, b = SL_OCTREE_NONE;
        if (state[v] != IN_HEAP || top.key != cur[v])
            continue;
        const sl_octree_node *node = &t->nodes[v];
        for (int d = 0; d < 27 && b == SL_OCTREE_NONE && node->parent != SL_OCTREE_NONE; d++) {
            const sl_octree_node *p = &t->nodes[node->parent];
            int64_t q[3] = {(int64_t)node->x + d % 3 - 1, (int64_t)node->y + d / 3 % 3 - 1,
                            (int64_t)node->z + d / 9 - 1}, pc[3] = {p->x, p->y, p->z};
            int off[3];
            for (int a = 0; a < 3; a++)
                off[a] = (int)((q[a] >= 0 ? q[a] / 2 : -1) - pc[a]);
            int pd = sl_direction(off[0], off[1], off[2]);
            uint32_t m = d == 13 || pd == 13 ? SL_OCTREE_NONE : sl_neighbour(nb, node->parent, pd);
            if (m != SL_OCTREE_NONE && state[m] != EXPANDED)
                b = m;
        }
        if (b != SL_OCTREE_NONE) {
            ++*waits;
            state[v] = WAITING;
            wait_on[v] = b;
            next[v] = head[b];
            head[b] = v;
            for (float raised = cur[v]; inherit && cur[b] < raised;) {
                if (state[b] == IN_HEAP) {
                    REF_PUSH(b, raised);
                    break;
                }
                cur[b] = raised;
                if (state[b] != WAITING)
                    break;
                b = wait_on[b];
            }
            continue;
        }
        state[v] = EXPANDED;
        order[k++] = v;
        for (int c = 0; c < __builtin_popcount(node->child_mask); c++)
            if (t->nodes[node->first_child + (uint32_t)c].child_mask)
                REF_PUSH(node->first_child + (uint32_t)c, key[node->first_child + (uint32_t)c]);
        for (uint32_t w = head[v]; w != SL_OCTREE_NONE; w = next[w])
            REF_PUSH(w, cur[w]);
        head[v] = SL_OCTREE_NONE;
    }
#undef REF_PUSH
    free(heap);
    free(cur);
    free(state);
    free(wait_on);
    free(head);
    free(next);
    return k;
}

static int build_model(sdf_fn sdf, int n, sl_priority_metric metric, sl_lod_model *m)
{
    size_t cap = 4096, count = 0;
    int32_t *coords = malloc(cap * 3 * sizeof *coords);
    float *dist = malloc(cap * sizeof *dist);
    for (int x = -n; x <= n; x++)
        for (int y = -n; y <= n; y++)
            for (int z = -n; z <= n; z++) {
                double p[3] = {x, y, z}, d = sdf(p);
                /* The blob's field is not a true distance: a wide band keeps every cube
                 * the surface crosses fully sampled, as the samples stage's band does. */
                if (fabs(d) > 4.0)
                    continue;
                if (count == cap) {
                    cap *= 2;
                    coords = realloc(coords, cap * 3 * sizeof *coords);
                    dist = realloc(dist, cap * sizeof *dist);
                }
                coords[3 * count] = x;
                coords[3 * count + 1] = y;
                coords[3 * count + 2] = z;
                dist[count++] = (float)d;
            }
    sl_sample_grid g = {count, coords, dist, NULL, 0.5, {1, 2, 3}};
    sl_error err;
    sl_error_init(&err);
    sl_lod_model_init(m);
    int rc = sl_octree_build(&g, &m->tree, NULL, &err);
    free(coords);
    free(dist);
    if (rc == 0 && metric == SL_PRIORITY_QEF) { /* vertices fitted to the finest surface */
        sl_lod_mesh leaves;
        rc = sl_octree_level_mesh(&m->tree, 0, &leaves);
        sl_surface surface = {leaves.vertex_count, leaves.positions, NULL, NULL,
                              leaves.triangle_count, leaves.indices, 0, 0};
        omp_set_num_threads(1);
        rc = rc || sl_octree_vertices(&m->tree, &surface, 0.02, SL_VERTEX_BRICK_LEVEL, &err);
        uint32_t vertices_one = m->tree.vertex_count;
        float *one = malloc((vertices_one ? vertices_one : 1) * 12);
        if (!rc)
            memcpy(one, m->tree.vertex_position, vertices_one * 12);
        omp_set_num_threads(2);
        rc = rc || sl_octree_vertices(&m->tree, &surface, 0.02, SL_VERTEX_BRICK_LEVEL, &err);
        CHECK_MSG(rc || (vertices_one == m->tree.vertex_count &&
                         memcmp(one, m->tree.vertex_position, vertices_one * 12) == 0),
                  "the vertices differ between 1 and 2 threads");
        free(one);
        sl_lod_mesh_release(&leaves);
    }
    if (rc)
        return rc;
    uint32_t nodes = m->tree.node_count;
    float *area = malloc(nodes * sizeof *area), *error = malloc(nodes * sizeof *error);
    float *key = malloc(nodes * sizeof *key);
    uint32_t *one_thread = malloc(nodes * sizeof *one_thread), count_one = 0;
    m->lod_array = malloc(nodes * sizeof *m->lod_array);
    uint64_t unresolved;
    int inherit = metric != SL_PRIORITY_AREA;
    omp_set_num_threads(1);
    rc = sl_priority_metrics(&m->tree, area, error) ||
         sl_priority_keys(&m->tree, metric, area, key) || sl_neighbours_build(&m->tree, &m->neighbours) ||
         sl_priority_order(&m->tree, &m->neighbours, key, inherit, one_thread, &count_one, &err);
    omp_set_num_threads(2);
    rc = rc || sl_priority_metrics(&m->tree, area, error) ||
         sl_priority_keys(&m->tree, metric, area, key) ||
         sl_priority_order(&m->tree, &m->neighbours, key, inherit, m->lod_array, &m->expansion_count, &err) ||
         sl_transitions_build(&m->tree, NULL, &m->transitions, &unresolved);
    float *expansion_error = rc ? NULL : malloc((m->expansion_count + 1) * sizeof *expansion_error);
    for (uint32_t i = 0; expansion_error && i < m->expansion_count; i++)
        expansion_error[i] = error[m->lod_array[i]];
    rc = rc || !expansion_error || sl_lod_model_finish(m, expansion_error, &err) ||
         sl_lod_model_prepare(m);
    free(expansion_error);
    if (!rc) { /* the crack stage's way: the internal nodes' links, not searches */
        sl_neighbours links;
        sl_transitions linked;
        uint64_t all_links, unresolved_linked = 0;
        memset(&links, 0, sizeof links);
        memset(&linked, 0, sizeof linked);
        CHECK(sl_neighbours_build_internal(&m->tree, &links, &all_links) == 0 &&
              sl_transitions_build(&m->tree, &links, &linked, &unresolved_linked) == 0);
        CHECK_MSG(linked.count == m->transitions.count && unresolved_linked == unresolved &&
                      memcmp(linked.base, m->transitions.base, m->tree.node_count * sizeof *linked.base) == 0 &&
                      memcmp(linked.words, m->transitions.words, linked.count * sizeof *linked.words) == 0,
                  "metric %s: the transition records differ found through the links",
                  sl_priority_metric_name(metric));
        sl_transitions_release(&linked);
        sl_neighbours_release(&links);
    }
    CHECK_MSG(rc || (count_one == m->expansion_count &&
                     memcmp(one_thread, m->lod_array, count_one * sizeof *one_thread) == 0),
              "metric %s: the order differs between 1 and 2 threads", sl_priority_metric_name(metric));
    if (!rc) {
        uint32_t waits = 0, count_ref = reference_order(&m->tree, &m->neighbours, key, inherit, one_thread, &waits);
        CHECK_MSG(count_ref == m->expansion_count &&
                      memcmp(one_thread, m->lod_array, count_ref * sizeof *one_thread) == 0,
                  "metric %s: the order differs from the rule's reference", sl_priority_metric_name(metric));
        CHECK_MSG(waits > 0 || m->expansion_count < 64, "metric %s: no node was held back (%u expansions)",
                  sl_priority_metric_name(metric), m->expansion_count);
    }
    free(area);
    free(error);
    free(key);
    free(one_thread);
    return rc;
}


/* The level check can fail: an order that dives from the root to a leaf's parent, always
 * into the first child, leaves level-0 cells beside unexpanded cells 2+ levels up. */
static void test_level_check_catches_a_dive(const sl_lod_model *good)
{
    sl_lod_model dive = *good; /* shares the tree: only the order and its index differ */
    const sl_octree *t = &good->tree;
    uint32_t n = t->node_count, order[SL_OCTREE_MAX_LEVELS], count = 0;
    for (uint32_t node = 0; t->nodes[node].level > 0 && t->nodes[node].child_mask;
         node = t->nodes[node].first_child)
        order[count++] = node;
    uint32_t *index = malloc(n * sizeof *index);
    memset(index, 0xff, n * sizeof *index);
    for (uint32_t i = 0; i < count; i++)
        index[order[i]] = i;
    dive.lod_array = order;
    dive.expansion_count = count;
    dive.expansion_index = index;
    CHECK_MSG(count >= 3 && level_gap(&dive, count),
              "a %u-expansion dive to the leaves is not seen as a level gap", count);
    CHECK(!level_gap(&dive, 1)); /* the root's children alone are one level */
    free(index);
}

/* Writes m (a valid checksum over whatever it holds) as format 4, whose layout holds any
 * mutation (format 5's writer reorders by the tree, lod_order.h; its own hostile bodies
 * are test_lod_pack's), and expects reading it back to be refused as corrupt with `cause`
 * in the message: no crash, no hang (ASan in CI). The checks are the ones every format's
 * reader makes once its tables are in level order. */
static void expect_refused(const sl_lod_model *m, const char *path, const char *what,
                           const char *cause)
{
    sl_error err;
    sl_error_init(&err);
    CHECK(write_format4(path, m, &err) == 0);
    sl_lod_model back;
    int rc = sl_lod_model_read(path, &back, &err);
    CHECK_MSG(rc == SL_E_CORRUPT && strstr(err.message, cause),
              "%s: read gave %d (%s), expected corrupt: %s", what, rc, err.message, cause);
    if (rc == 0)
        sl_lod_model_release(&back);
}

static int internal_level_one(const sl_lod_model *m, uint32_t i)
{
    return m->tree.nodes[i].child_mask && m->tree.nodes[i].level == 1;
}

static int has_record(const sl_lod_model *m, uint32_t i)
{
    return m->transitions.base[i] != SL_OCTREE_NONE;
}

/* The first two nodes with a property; 0 when there are not two. */
static int first_two(const sl_lod_model *m, int (*want)(const sl_lod_model *, uint32_t),
                     uint32_t *a, uint32_t *b)
{
    int found = 0;
    for (uint32_t i = 0; i < m->tree.node_count && found < 2; i++)
        if (want(m, i))
            *(found++ ? b : a) = i;
    return found == 2;
}

/* Files with a valid checksum and hostile contents (docs/formats.md, model.slod): each
 * mutation of a good model is refused by the reader, which is all that stands between such
 * a file and the extraction code. */
static void test_hostile_files(sl_lod_model *m, const char *path)
{
    sl_octree *t = &m->tree;
    /* Two internal nodes of one level claiming the same children. */
    uint32_t a = SL_OCTREE_NONE, b = SL_OCTREE_NONE;
    int found = first_two(m, internal_level_one, &a, &b);
    CHECK(found);
    if (found) {
        sl_octree_node saved = t->nodes[a];
        t->nodes[a].first_child = t->nodes[b].first_child;
        t->nodes[a].child_mask = t->nodes[b].child_mask;
        expect_refused(m, path, "shared children", "child does not belong");
        t->nodes[a] = saved;
    }
    /* A triangle count whose byte size wraps around 64 bits. */
    uint32_t k = m->expansion_count / 2;
    uint64_t count = m->accumulation[k];
    m->accumulation[k] = 0x1555555555555556ull;
    expect_refused(m, path, "huge accumulation", "accumulation table out of range");
    m->accumulation[k] = count;
    /* A crossing on an edge whose corners agree (and none where they differ). */
    uint32_t node = SL_OCTREE_NONE;
    for (uint32_t i = 0; i < t->node_count && node == SL_OCTREE_NONE; i++)
        if (t->nodes[i].edge_mask && t->nodes[i].edge_mask != 0xfff)
            node = i;
    CHECK(node != SL_OCTREE_NONE);
    if (node != SL_OCTREE_NONE) {
        uint16_t mask = t->nodes[node].edge_mask, low = mask & (uint16_t)-mask;
        uint16_t free_edges = (uint16_t)(~mask & 0xfff), moved = free_edges & (uint16_t)-free_edges;
        t->nodes[node].edge_mask = (uint16_t)((mask & ~low) | moved);
        expect_refused(m, path, "edge mask against the signs", "bad crossing range");
        t->nodes[node].edge_mask = mask;
    }
    /* Two nodes sharing one transition record. */
    uint32_t r1 = SL_OCTREE_NONE, r2 = SL_OCTREE_NONE;
    found = first_two(m, has_record, &r1, &r2);
    CHECK(found);
    if (found) {
        uint32_t base = m->transitions.base[r2];
        m->transitions.base[r2] = m->transitions.base[r1];
        expect_refused(m, path, "shared transition record", "transition records overlap");
        m->transitions.base[r2] = base;
    }
    /* Undone, the model reads again. */
    sl_error err;
    sl_error_init(&err);
    sl_lod_model back;
    CHECK(sl_lod_model_write(path, m, 1, &err) == 0);
    CHECK_MSG(sl_lod_model_read(path, &back, &err) == 0, "restored model: %s", err.message);
    sl_lod_model_release(&back);
}

/* A dual model's hostile vertex sections: a vertex outside its node's cube, a node with
 * more vertices than loops, ranges out of order, a negative node area; each refused. */
static void test_hostile_vertices(sl_lod_model *m, const char *path)
{
    sl_octree *t = &m->tree;
    uint32_t node = SL_OCTREE_NONE;
    for (uint32_t i = 0; i < t->node_count && node == SL_OCTREE_NONE; i++)
        if (t->vertex_first[i + 1] > t->vertex_first[i] && t->nodes[i].level > 0)
            node = i;
    CHECK(node != SL_OCTREE_NONE);
    if (node == SL_OCTREE_NONE)
        return;
    uint32_t v = t->vertex_first[node];
    float saved = t->vertex_position[3 * v];
    t->vertex_position[3 * v] += (float)(4 * t->leaf_size * (double)(1u << t->nodes[node].level));
    expect_refused(m, path, "vertex outside its cube", "vertex outside its node's cube");
    t->vertex_position[3 * v] = saved;
    t->vertex_first[node + 1]++; /* one vertex more, taken from the next node */
    expect_refused(m, path, "more vertices than loops", "vertex count does not match");
    t->vertex_first[node + 1]--;
    uint32_t first = t->vertex_first[node];
    t->vertex_first[node] = t->vertex_first[node + 1] + 1;
    expect_refused(m, path, "ranges out of order", "vertex");
    t->vertex_first[node] = first;
    float area = t->node_area[node];
    t->node_area[node] = -1;
    expect_refused(m, path, "negative area", "node error or area");
    t->node_area[node] = area;
}

typedef struct k_findings {
    uint64_t mismatches, cracked, gaps, incomplete;
    uint32_t checked;
} k_findings;

/* The mesh at K: accumulation = generated, every edge in two triangles, no level gap,
 * every cell with its transition data. */
static void check_k(sl_lod_model *m, uint32_t k, const char *name, k_findings *f)
{
    sl_lod_mesh mesh;
    uint64_t incomplete;
    CHECK(sl_lod_generate(m, k, &mesh, &incomplete) == 0);
    f->checked++;
    f->incomplete += incomplete;
    if (mesh.triangle_count != m->accumulation[k] && f->mismatches++ < 3)
        fprintf(stderr, "%s K=%u: accumulation %llu, generated %llu\n", name, k,
                (unsigned long long)m->accumulation[k], (unsigned long long)mesh.triangle_count);
    uint64_t bad = bad_edges(&mesh);
    if (bad && f->cracked++ < 3)
        fprintf(stderr, "%s K=%u: %llu edges not in exactly two triangles\n", name, k,
                (unsigned long long)bad);
    if (level_gap(m, k))
        f->gaps++;
    sl_lod_mesh_release(&mesh);
}

/* priority.slpri read back as written, and refused when its bytes are changed (the
 * checksum) or when a producer with a bug sealed wrong contents: counts that do not fit
 * the octree, a LOD entry that is a leaf, an error that is not finite. */
static int priority_mutant(const char *path, const unsigned char *bytes, size_t size, int seal,
                           const sl_octree *t, sl_error *err)
{
    sl_priority back;
    sl_error_init(err);
    int rc = sealed_file_write(path, bytes, size, seal) == 0 ? sl_priority_read(path, t, &back, err) : -1;
    if (rc == 0)
        sl_priority_release(&back);
    return rc;
}

static void test_priority_file(const sl_lod_model *m, const char *path)
{
    sl_priority p;
    memset(&p, 0, sizeof p);
    p.node_count = m->tree.node_count;
    p.expansion_count = m->expansion_count;
    p.lod_array = m->lod_array;
    p.expansion_error = malloc((m->expansion_count + 1) * sizeof *p.expansion_error);
    for (uint32_t i = 0; i < m->expansion_count; i++)
        p.expansion_error[i] = 1.0f / (float)(i + 1);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_neighbours_build_internal(&m->tree, &p.neighbours, &p.neighbour_links) == 0);
    CHECK(sl_priority_write(path, &p, 1, &err) == 0);
    sl_priority back;
    CHECK(sl_priority_read(path, &m->tree, &back, &err) == 0);
    CHECK(back.expansion_count == p.expansion_count && back.neighbour_links == p.neighbour_links &&
          back.neighbours.count == p.neighbours.count &&
          memcmp(back.lod_array, p.lod_array, p.expansion_count * 4) == 0 &&
          memcmp(back.expansion_error, p.expansion_error, p.expansion_count * 4) == 0 &&
          memcmp(back.neighbours.mask, p.neighbours.mask, p.node_count * 4) == 0 &&
          memcmp(back.neighbours.index, p.neighbours.index, p.neighbours.count * 4) == 0);
    sl_priority_release(&back);
    free(p.expansion_error);
    sl_neighbours_release(&p.neighbours);

    size_t size = 0;
    unsigned char *bytes = sealed_file_bytes(path, 0, &size);
    CHECK(bytes && size > 100);
    if (!bytes || size <= 100) {
        free(bytes);
        return;
    }
    unsigned char *body = bytes + SL_ARTIFACT_HEADER_SIZE, *lod = body + 24;
    uint32_t e = m->expansion_count;
    bytes[size - 2] ^= 0x11;
    CHECK(priority_mutant(path, bytes, size, 0, &m->tree, &err) == SL_E_CORRUPT &&
          strstr(err.message, "checksum mismatch"));
    bytes[size - 2] ^= 0x11;
    sl_put_u32(body + 4, m->tree.node_count); /* every node expanded: the size disagrees */
    CHECK(priority_mutant(path, bytes, size, 1, &m->tree, &err) == SL_E_CORRUPT &&
          strstr(err.message, "counts do not match"));
    sl_put_u32(body + 4, e);
    uint32_t first = sl_get_u32(lod);
    sl_put_u32(lod, m->tree.node_count - 1); /* the last node: a leaf */
    CHECK(priority_mutant(path, bytes, size, 1, &m->tree, &err) == SL_E_CORRUPT &&
          strstr(err.message, "not an internal node"));
    sl_put_u32(lod, first);
    sl_put_f32(lod + 4 * (size_t)e, NAN);
    CHECK(priority_mutant(path, bytes, size, 1, &m->tree, &err) == SL_E_CORRUPT &&
          strstr(err.message, "non-finite error"));
    sl_put_f32(lod + 4 * (size_t)e, 1.0f);
    CHECK(priority_mutant(path, bytes, size, 1, &m->tree, &err) == 0);
    free(bytes);
}

static void test_model(sdf_fn sdf, int n, sl_priority_metric metric, const char *shape)
{
    char name[64];
    snprintf(name, sizeof name, "%s/%s", shape, sl_priority_metric_name(metric));
    sl_lod_model m;
    CHECK(build_model(sdf, n, metric, &m) == 0);
    CHECK(m.expansion_count > 100);
    k_findings at_k = {0};
    for (uint32_t k = 0; k <= m.expansion_count; k = check_k_next(k, m.expansion_count))
        check_k(&m, k, name, &at_k);
    uint64_t mismatches = at_k.mismatches, cracked = at_k.cracked, gaps = at_k.gaps,
             incomplete_total = at_k.incomplete;
    CHECK_MSG(mismatches == 0, "%s: %llu K with accumulation != generated", name,
              (unsigned long long)mismatches);
    CHECK_MSG(cracked == 0, "%s: %llu K with cracks", name, (unsigned long long)cracked);
    CHECK_MSG(gaps == 0, "%s: %llu K with neighbours 2+ levels apart", name, (unsigned long long)gaps);
    CHECK_MSG(incomplete_total == 0, "%s: %llu cells lacked transition data", name,
              (unsigned long long)incomplete_total);
    CHECK(m.accumulation[0] < m.accumulation[m.expansion_count]);
    if (sl_octree_dual(&m.tree)) { /* counter-clockwise seen from outside at every 10 % */
        for (int p = 10; p <= 100; p += 10) {
            sl_lod_mesh mesh;
            CHECK(sl_lod_generate(&m, sl_lod_expansions_for_percent(&m, p), &mesh, NULL) == 0);
            CHECK_MSG(signed_volume(&mesh) > 0, "%s at %d %%: the dual faces inwards", name, p);
            sl_lod_mesh_release(&mesh);
        }
    }
    /* Error table: non-increasing, zero at the finest level, and K(E) meets E. */
    for (uint32_t k = 0; k < m.expansion_count; k++)
        CHECK(m.error_after[k] >= m.error_after[k + 1]);
    CHECK(m.error_after[m.expansion_count] == 0);
    uint32_t k_err = sl_lod_expansions_for_error(&m, 0.1);
    CHECK(m.error_after[k_err] <= 0.1 && (k_err == 0 || m.error_after[k_err - 1] > 0.1));
    uint32_t k_tri = sl_lod_expansions_for_triangles(&m, m.accumulation[m.expansion_count] / 3);
    CHECK(m.accumulation[k_tri] <= m.accumulation[m.expansion_count] / 3);
    /* LOD percents count the expansions of nodes with surface below them: 100 % is the
     * finest mesh exactly, reached no later than the last expansion; percents are
     * monotone. */
    uint32_t k100 = sl_lod_expansions_for_percent(&m, 100);
    CHECK(k100 <= m.expansion_count);
    CHECK(sl_lod_expansions_for_percent(&m, 0) == 0);
    for (int p = 10; p <= 100; p += 10)
        CHECK(sl_lod_expansions_for_percent(&m, p - 10) <= sl_lod_expansions_for_percent(&m, p));
    {
        sl_lod_mesh at100, finest;
        CHECK(sl_lod_generate(&m, k100, &at100, NULL) == 0);
        CHECK(sl_lod_generate(&m, m.expansion_count, &finest, NULL) == 0);
        CHECK_MSG(at100.triangle_count == finest.triangle_count &&
                      at100.vertex_count == finest.vertex_count &&
                      memcmp(at100.positions, finest.positions,
                             finest.vertex_count * 3 * sizeof(float)) == 0 &&
                      memcmp(at100.indices, finest.indices,
                             finest.triangle_count * 3 * sizeof(uint32_t)) == 0,
                  "%s: 100 %% (k %u) is not the finest mesh (k %u)", name, k100,
                  m.expansion_count);
        sl_lod_mesh_release(&at100);
        sl_lod_mesh_release(&finest);
    }
    /* Into caller buffers (the runtime API's path): the same bytes as the allocating
     * path at several k; a capacity one triangle short fails, and leaves the scratch
     * clean for the next extraction. */
    {
        uint64_t cap_t = 0; /* an expansion may also remove triangles: the largest level */
        for (uint32_t k = 0; k <= m.expansion_count; k++)
            cap_t = m.accumulation[k] > cap_t ? m.accumulation[k] : cap_t;
        uint64_t cap_v = 3 * cap_t + 1;
        sl_lod_mesh buf = {0, 0, malloc(cap_v * 12), malloc(cap_v * 12), malloc(cap_v * 4),
                           malloc((cap_t + 1) * 12)};
        for (int p = 0; p <= 100; p += 25) {
            uint32_t k = sl_lod_expansions_for_percent(&m, p);
            sl_lod_mesh ref, into = buf;
            CHECK(sl_lod_generate(&m, k, &ref, NULL) == 0);
            CHECK(sl_lod_generate_into(&m, k, &into, cap_v, cap_t, NULL) == 0);
            int same = into.triangle_count == ref.triangle_count &&
                       into.vertex_count == ref.vertex_count;
            if (same && ref.vertex_count) /* (an empty level has NULL arrays) */
                same = memcmp(into.positions, ref.positions, ref.vertex_count * 12) == 0 &&
                       memcmp(into.normals, ref.normals, ref.vertex_count * 12) == 0 &&
                       memcmp(into.indices, ref.indices, ref.triangle_count * 12) == 0 &&
                       (!ref.colors || memcmp(ref.colors, into.colors, ref.vertex_count * 4) == 0);
            CHECK_MSG(same,
                      "%s: generate_into differs from generate at %d %%", name, p);
            if (ref.triangle_count > 0) {
                sl_lod_mesh short_buf = buf;
                CHECK(sl_lod_generate_into(&m, k, &short_buf, cap_v, ref.triangle_count - 1,
                                           NULL) != 0);
                sl_lod_mesh again;
                CHECK(sl_lod_generate(&m, k, &again, NULL) == 0);
                CHECK_MSG(again.vertex_count == ref.vertex_count &&
                              memcmp(again.indices, ref.indices, ref.triangle_count * 12) == 0,
                          "%s: a failed extraction left the scratch dirty", name);
                sl_lod_mesh_release(&again);
            }
            sl_lod_mesh_release(&ref);
        }
        free(buf.positions);
        free(buf.normals);
        free(buf.colors);
        free(buf.indices);
    }
    printf("%s: %u nodes, %u expansions (%u checked), triangles %llu .. %llu\n", name,
           m.tree.node_count, m.expansion_count, at_k.checked, (unsigned long long)m.accumulation[0],
           (unsigned long long)m.accumulation[m.expansion_count]);

    /* .slod roundtrip: same mesh at 40 %, and a flipped byte is refused. */
    char path[] = "/tmp/scanlod-test-lod-XXXXXX";
    int fd = mkstemp(path);
    close(fd);
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_lod_model_write(path, &m, 1, &err) == 0);
    sl_lod_model back;
    CHECK(sl_lod_model_read(path, &back, &err) == 0);
    uint32_t k40 = sl_lod_expansions_for_percent(&m, 40);
    sl_lod_mesh a, b;
    CHECK(sl_lod_generate(&m, k40, &a, NULL) == 0 && sl_lod_generate(&back, k40, &b, NULL) == 0);
    CHECK(a.triangle_count == b.triangle_count && a.vertex_count == b.vertex_count);
    CHECK(memcmp(a.positions, b.positions, a.vertex_count * 3 * sizeof(float)) == 0);
    CHECK(memcmp(a.indices, b.indices, a.triangle_count * 3 * sizeof(uint32_t)) == 0);
    sl_lod_mesh_release(&a);
    sl_lod_mesh_release(&b);
    sl_lod_model_release(&back);
    FILE *f = fopen(path, "r+b");
    fseek(f, 200, SEEK_SET);
    fputc(0x5a, f);
    fclose(f);
    sl_error_init(&err);
    CHECK(sl_lod_model_read(path, &back, &err) == SL_E_CORRUPT);
    if (metric == SL_PRIORITY_ERROR) {
        test_priority_file(&m, path);
        test_hostile_files(&m, path);
        test_level_check_catches_a_dive(&m);
    }
    if (metric == SL_PRIORITY_QEF) {
        test_hostile_vertices(&m, path);
        test_hostile_files(&m, path);
    }
    unlink(path);
    sl_lod_model_release(&m);
}

/* With SCANLOD_SLOD_SEED_DIR=dir, writes the bodies (the .slod after its 32-byte
 * envelope) of small models under every metric there: the seeds of the fuzz target
 * (tests/fuzz/README.md). */
static void write_fuzz_seeds(const char *dir)
{
    sdf_fn shapes[] = {tiny_sphere_sdf, sphere_sdf, small_torus_sdf};
    const char *names[] = {"tiny", "sphere", "torus"};
    int sizes[] = {3, 5, 7};
    for (int s = 0; s < 3; s++)
        for (int metric = SL_PRIORITY_ERROR; metric <= SL_PRIORITY_QEF; metric++) {
            sl_lod_model m;
            char path[1200], seed[1200];
            snprintf(path, sizeof path, "%s/%s-%s.slod", dir, names[s],
                     sl_priority_metric_name((sl_priority_metric)metric));
            snprintf(seed, sizeof seed, "%s/%s-%s", dir, names[s],
                     sl_priority_metric_name((sl_priority_metric)metric));
            sl_error err;
            sl_error_init(&err);
            CHECK(build_model(shapes[s], sizes[s], (sl_priority_metric)metric, &m) == 0);
            CHECK(sl_lod_model_write(path, &m, 1, &err) == 0);
            sl_lod_model_release(&m);
            FILE *in = fopen(path, "rb"), *out = fopen(seed, "wb");
            CHECK(in && out && fseek(in, SL_ARTIFACT_HEADER_SIZE, SEEK_SET) == 0);
            for (int c; in && out && (c = fgetc(in)) != EOF;)
                fputc(c, out);
            if (in)
                fclose(in);
            if (out)
                fclose(out);
            unlink(path);
        }
}

int main(void)
{
    const char *seed_dir = getenv("SCANLOD_SLOD_SEED_DIR");
    if (seed_dir && seed_dir[0]) {
        write_fuzz_seeds(seed_dir);
        return check_report();
    }
    const char *only = getenv("SCANLOD_TEST_METRIC"); /* one metric, when iterating on it */
    for (int metric = SL_PRIORITY_ERROR; metric <= SL_PRIORITY_QEF; metric++) {
        if (only && only[0] && strcmp(only, sl_priority_metric_name((sl_priority_metric)metric)))
            continue;
        test_model(blob_sdf, 13, (sl_priority_metric)metric, "blob");
        test_model(torus_sdf, 14, (sl_priority_metric)metric, "torus");
    }
    return check_report();
}
