/* The shortcuts of direct generation (runtime/lod_generate.c) change nothing: the constant
 * uniform cell table equals sl_mc_uniform_table(), and sl_lod_generate -- which skips cells
 * that cannot draw anything and draws unsplit cells from that table -- gives, at every
 * expansion count, the very mesh and crack count of drawing every frontier cell of
 * sl_lod_frontier with sl_lod_cell and sl_mc_triangulate (41 spread K with SCANLOD_LIGHT=1).
 * The expansion orders are random (parents first), so cells meet neighbours one and more
 * levels finer. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_io.h"
#include "stages/crack/crack.h"
#include "stages/priority/priority.h"
#include "tests/check.h"
#include "tests/unit/sdf_octree.h"

/* Prints the table rows as lod_tables.c has them (to paste there when the rule changes). */
static void print_uniform_rows(const sl_mc_triangles *table)
{
    int column = 100;
    for (int c = 0; c < 256; c++) {
        char row[64];
        int len = snprintf(row, sizeof row, "{%d", table[c].count);
        for (int t = 0; t < table[c].count && t < 5; t++)
            for (int i = 0; i < 3; i++)
                len += snprintf(row + len, sizeof row - (size_t)len, ",%d", table[c].points[t][i]);
        len += snprintf(row + len, sizeof row - (size_t)len, "},");
        if (column + 1 + len > 96) {
            printf("\n   ");
            column = 3;
        }
        printf(" %s", row);
        column += 1 + len;
    }
    printf("\n");
}

static void test_uniform_table(void)
{
    const sl_mc_triangles *table = sl_mc_uniform_table();
    int bad = 0;
    for (int c = 0; c < 256; c++) {
        const uint8_t *row = sl_lod_uniform_cells[c];
        int same = table[c].centroids == 0 && table[c].count == row[0] &&
                   3 * table[c].count < SL_LOD_UNIFORM_ROW;
        for (int t = 0; same && t < table[c].count; t++)
            for (int i = 0; i < 3; i++)
                same &= table[c].points[t][i] == row[1 + 3 * t + i];
        bad += !same;
    }
    CHECK_MSG(bad == 0, "%d rows of sl_lod_uniform_cells differ from sl_mc_uniform_table()", bad);
    if (bad)
        print_uniform_rows(table);
}

static double blob_sdf(const double p[3])
{
    double r = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    double bump = 3.0 * exp(-((p[0] - 8) * (p[0] - 8) + p[1] * p[1] + (p[2] - 5) * (p[2] - 5)) / 6.0);
    double ring = 1.5 * sin(p[0] * 0.7) * sin(p[1] * 0.5);
    return r - 10.7 - bump + ring;
}

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;

static uint64_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

/* A model of the blob with a random expansion order: any unexpanded child of an expanded
 * node may come next. */
static int build_model(int n, int coloured, sl_lod_model *m)
{
    sl_error err;
    sl_error_init(&err);
    sl_lod_model_init(m);
    int rc = sdf_octree(blob_sdf, n, 4.0, 0.5, coloured, &m->tree);
    if (rc)
        return rc;
    const sl_octree *t = &m->tree;
    uint32_t *ready = malloc(t->node_count * sizeof *ready), ready_count = 0;
    m->lod_array = malloc(t->node_count * sizeof *m->lod_array);
    m->expansion_count = 0;
    if (t->node_count && t->nodes[0].child_mask)
        ready[ready_count++] = 0;
    while (ready_count) {
        uint32_t pick = (uint32_t)(rng() % ready_count), node = ready[pick];
        ready[pick] = ready[--ready_count];
        m->lod_array[m->expansion_count++] = node;
        const sl_octree_node *p = &t->nodes[node];
        for (int c = 0; c < __builtin_popcount(p->child_mask); c++)
            if (t->nodes[p->first_child + (uint32_t)c].child_mask)
                ready[ready_count++] = p->first_child + (uint32_t)c;
    }
    free(ready);
    uint64_t unresolved;
    return sl_neighbours_build(t, &m->neighbours) ||
           sl_transitions_build(t, &m->neighbours, &m->transitions, &unresolved) ||
           sl_lod_model_finish(m, NULL, &err) || sl_lod_model_prepare(m);
}

/* The mesh after k expansions, every frontier cell drawn the general way. */
static int reference_mesh(sl_lod_model *m, uint32_t k, sl_lod_mesh *out, uint64_t *cracks)
{
    uint32_t *cells = malloc(sl_lod_frontier_bound(m, k) * sizeof *cells);
    uint64_t count = sl_lod_frontier(m, k, cells);
    sl_mesh_builder b;
    if (sl_mesh_builder_init(&b, &m->tree, NULL))
        return -1;
    *cracks = 0;
    for (uint64_t i = 0; i < count; i++) {
        sl_mc_cell cell;
        uint32_t point_crossing[SL_MC_MAX_POINTS];
        sl_mc_triangles tri;
        *cracks += sl_lod_cell(&m->tree, &m->neighbours, &m->transitions, m->expansion_index,
                               k, cells[i], &cell, point_crossing) != 0;
        sl_mc_triangulate(&cell, &tri);
        sl_mesh_builder_add_cell(&b, &tri, point_crossing);
    }
    free(cells);
    return sl_mesh_builder_finish(&b, out);
}

static int same_mesh(const sl_lod_mesh *a, const sl_lod_mesh *b)
{
    if (a->vertex_count != b->vertex_count || a->triangle_count != b->triangle_count)
        return 0;
    if (!a->vertex_count)
        return 1;
    size_t v = (size_t)a->vertex_count, t = (size_t)a->triangle_count;
    return !memcmp(a->positions, b->positions, 3 * v * sizeof(float)) &&
           !memcmp(a->normals, b->normals, 3 * v * sizeof(float)) &&
           !memcmp(a->indices, b->indices, 3 * t * sizeof(uint32_t)) &&
           (!a->colors) == (!b->colors) && (!a->colors || !memcmp(a->colors, b->colors, 4 * v));
}

static void test_generation(int n, int coloured, int localized, uint64_t seed)
{
    rng_state ^= seed;
    sl_lod_model m;
    CHECK(build_model(n, coloured, &m) == 0);
    CHECK(m.expansion_count > 100);
    /* As a model read from a file is: crossings renumbered, pools in LOD order. */
    if (localized)
        CHECK(sl_lod_model_localize(&m) == 0 && sl_lod_model_prepare(&m) == 0);
    uint64_t differ = 0, cracks_total = 0;
    for (uint32_t k = 0; k <= m.expansion_count; k = check_k_next(k, m.expansion_count)) {
        sl_lod_mesh fast, slow;
        uint64_t fast_cracks = 0, slow_cracks = 0;
        CHECK(sl_lod_generate(&m, k, &fast, &fast_cracks) == 0);
        CHECK(reference_mesh(&m, k, &slow, &slow_cracks) == 0);
        if ((!same_mesh(&fast, &slow) || fast_cracks != slow_cracks) && differ++ < 3)
            fprintf(stderr, "K=%u: generated %llu triangles (%llu cracks), reference %llu (%llu)\n",
                    k, (unsigned long long)fast.triangle_count, (unsigned long long)fast_cracks,
                    (unsigned long long)slow.triangle_count, (unsigned long long)slow_cracks);
        cracks_total += fast_cracks;
        sl_lod_mesh_release(&fast);
        sl_lod_mesh_release(&slow);
    }
    CHECK_MSG(differ == 0, "%llu K where generation differs from the reference",
              (unsigned long long)differ);
    printf("random order %llx%s: %u nodes, %u expansions, %llu cells drawn with a crack\n",
           (unsigned long long)seed, localized ? " (localized)" : "", m.tree.node_count, m.expansion_count,
           (unsigned long long)cracks_total);
    sl_lod_model_release(&m);
}

/* The layout derived at load (cells, split lists, drawings) is the same on 1 and on 2
 * threads: it is laid out in fixed chunks, not per thread. */
static void test_layout_threads(uint64_t seed)
{
    rng_state ^= seed;
    sl_lod_model m;
    CHECK(build_model(13, 0, &m) == 0);
    uint32_t cells = m.frontier_end[m.expansion_count];
    uint64_t words = 0, drawing_words[2] = {0, 0};
    for (uint32_t pos = 0; pos < cells; pos++)
        if (m.cells[pos].splits != SL_OCTREE_NONE)
            words = m.cells[pos].splits + 3u + 3u * (m.split_words[m.cells[pos].splits + 1] >> 24);
    uint32_t *copy[2] = {NULL, NULL}, *lists[2] = {NULL, NULL};
    for (int run = 0; run < 2; run++) {
        omp_set_num_threads(run + 1);
        CHECK(sl_lod_model_prepare(&m) == 0);
        drawing_words[run] = m.split_drawing_words;
        copy[run] = malloc((drawing_words[run] + 1) * sizeof(uint32_t));
        lists[run] = malloc((words + 1) * sizeof(uint32_t));
        memcpy(copy[run], m.split_drawings, drawing_words[run] * sizeof(uint32_t));
        memcpy(lists[run], m.split_words, words * sizeof(uint32_t));
    }
    omp_set_num_threads(omp_get_num_procs());
    CHECK(drawing_words[0] > 0 && drawing_words[0] == drawing_words[1]);
    CHECK(!memcmp(copy[0], copy[1], drawing_words[0] * sizeof(uint32_t)));
    CHECK(!memcmp(lists[0], lists[1], words * sizeof(uint32_t)));
    printf("layout: %u cells, %llu split-list words, %llu drawing words, same on 1 and 2 threads\n",
           cells, (unsigned long long)words, (unsigned long long)drawing_words[0]);
    for (int run = 0; run < 2; run++) {
        free(copy[run]);
        free(lists[run]);
    }
    sl_lod_model_release(&m);
}

int main(void)
{
    test_uniform_table();
    test_generation(13, 0, 0, 1);
    test_generation(14, 1, 1, 2);
    test_generation(12, 0, 1, 3);
    test_layout_threads(4);
    return check_report();
}
