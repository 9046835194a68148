/* Segment boundary loops and corners (geometry/segment_loops.h): a cube's six faces (one
 * loop each, 8 corners, 24 two-segment vertices), a planar annulus (outer loop and hole),
 * a cylinder, a segment touching itself at a vertex, bad labels. */
#include <string.h>

#include "geometry/region_grow.h"
#include "geometry/segment_loops.h"
#include "tests/check.h"
#include "tests/unit/analytic_meshes.h"

typedef struct looped {
    sl_mesh_adjacency adj;
    sl_segmentation seg;
    sl_segment_loops loops;
} looped;

static int build(const test_mesh *m, double delta, looped *l, sl_error *err)
{
    memset(l, 0, sizeof *l);
    sl_error_init(err);
    sl_region_grow_config cfg = sl_region_grow_default_config();
    cfg.delta_seg = delta;
    int rc = sl_mesh_adjacency_build(m->triangles, m->triangle_count, m->vertex_count,
                                     m->positions, 0, &l->adj, err);
    if (!rc)
        rc = sl_region_grow(&l->adj, m->positions, &cfg, &l->seg, err);
    if (!rc)
        rc = sl_segment_loops_build(&l->adj, m->positions, l->seg.segment,
                                    l->seg.segment_count, &l->loops, err);
    return rc;
}

static void looped_free(looped *l)
{
    sl_segment_loops_release(&l->loops);
    sl_segmentation_release(&l->seg);
    sl_mesh_adjacency_release(&l->adj);
}

/* Every loop is closed (each half-edge's successor is the next one), lies on its
 * segment's boundary, and every boundary half-edge is in exactly one loop. */
static uint64_t check_loops(const looped *l)
{
    const sl_segment_loops *s = &l->loops;
    uint64_t bad = 0, total = 0;
    for (uint32_t k = 0; k < s->segment_count; k++)
        for (uint32_t i = s->segment_loop_start[k]; i < s->segment_loop_start[k + 1]; i++) {
            uint32_t b = s->loop_start[i], e = s->loop_start[i + 1];
            for (uint32_t j = b; j < e; j++) {
                uint32_t h = s->halfedges[j], next = s->halfedges[j + 1 < e ? j + 1 : b];
                bad += l->seg.segment[h / 3] != k;
                bad += !sl_segment_is_boundary(&l->adj, l->seg.segment, h);
                bad += sl_halfedge_target(&l->adj, h) != sl_halfedge_origin(&l->adj, next);
                bad += sl_segment_next_boundary(&l->adj, l->seg.segment, h) != next;
                total++;
            }
        }
    for (uint32_t h = 0; h < 3 * l->adj.triangle_count; h++)
        total -= sl_segment_is_boundary(&l->adj, l->seg.segment, h);
    return bad + (total != 0);
}

static void test_cube(void)
{
    test_mesh cube = tm_cube(3);
    looped l;
    sl_error err;
    CHECK(build(&cube, 30, &l, &err) == 0);
    CHECK_EQ_U64(l.loops.loop_count, 6);
    CHECK_EQ_U64(check_loops(&l), 0);
    for (uint32_t k = 0; k < 6; k++) {
        uint32_t first = l.loops.segment_loop_start[k];
        CHECK_EQ_U64(l.loops.segment_loop_start[k + 1] - first, 1);
        CHECK_EQ_U64(l.loops.loop_start[first + 1] - l.loops.loop_start[first], 12);
        CHECK_NEAR(l.loops.loop_area[first], 9.0, 1e-9);
        CHECK(l.loops.outer[k] == first);
    }
    CHECK_EQ_U64(l.loops.corners, 8);
    CHECK_EQ_U64(l.loops.two_segment_vertices, 24);
    uint64_t corner_ok = 0;
    for (uint32_t v = 0; v < cube.vertex_count; v++) {
        const float *p = cube.positions + 3 * v;
        int extremes = (p[0] == 0 || p[0] == 3) + (p[1] == 0 || p[1] == 3) + (p[2] == 0 || p[2] == 3);
        int kind = l.loops.vertex_kind[v];
        corner_ok += (extremes == 3) == (kind == SL_SEGMENT_VERTEX_CORNER) &&
                     (extremes == 2) == (kind == SL_SEGMENT_VERTEX_TWO_SEGMENT) &&
                     (extremes == 1) == (kind == SL_SEGMENT_VERTEX_INTERIOR);
    }
    CHECK_EQ_U64(corner_ok, cube.vertex_count);
    looped_free(&l);
    tm_free(&cube);
}

static void test_annulus(void)
{
    /* a 6x6 grid without its middle 2x2 quads: one planar segment, outer loop and hole */
    test_mesh grid = tm_grid(6, NULL), ring;
    memset(&ring, 0, sizeof ring);
    for (uint32_t v = 0; v < grid.vertex_count; v++)
        tm_vertex(&ring, grid.positions[3 * v], grid.positions[3 * v + 1], 0);
    for (uint32_t t = 0; t < grid.triangle_count; t++) {
        uint32_t q = t / 2, i = q % 6, j = q / 6;
        if (i >= 2 && i <= 3 && j >= 2 && j <= 3)
            continue;
        tm_triangle(&ring, grid.triangles[3 * t], grid.triangles[3 * t + 1],
                    grid.triangles[3 * t + 2]);
    }
    looped l;
    sl_error err;
    CHECK(build(&ring, 30, &l, &err) == 0);
    CHECK_EQ_U64(l.seg.segment_count, 1);
    CHECK_EQ_U64(l.loops.loop_count, 2);
    CHECK_EQ_U64(check_loops(&l), 0);
    uint32_t outer = l.loops.outer[0], hole = 1 - outer;
    CHECK_NEAR(l.loops.loop_area[outer], 1.0, 1e-6);
    CHECK_NEAR(l.loops.loop_area[hole], -4.0 / 36.0, 1e-6);
    CHECK_EQ_U64(l.loops.loop_start[outer + 1] - l.loops.loop_start[outer], 24);
    /* every boundary vertex is a corner (mesh boundary), the others interior */
    CHECK_EQ_U64(l.loops.corners, 24 + 8);
    CHECK_EQ_U64(l.loops.two_segment_vertices, 0);
    looped_free(&l);
    tm_free(&ring);
    tm_free(&grid);
}

static void test_cylinder(void)
{
    test_mesh cyl = tm_cylinder(24, 4, 3, 2.0);
    looped l;
    sl_error err;
    CHECK(build(&cyl, 20, &l, &err) == 0);
    CHECK_EQ_U64(check_loops(&l), 0);
    /* the caps (normals +-z) have one loop of 24 rim edges and a positive area */
    uint32_t caps = 0;
    for (uint32_t k = 0; k < l.seg.segment_count; k++) {
        uint32_t seed = l.seg.seed[k];
        const uint32_t *c = cyl.triangles + 3 * seed;
        if (cyl.positions[3 * c[0] + 2] != cyl.positions[3 * c[1] + 2] ||
            cyl.positions[3 * c[1] + 2] != cyl.positions[3 * c[2] + 2])
            continue;
        caps++;
        uint32_t first = l.loops.segment_loop_start[k];
        CHECK_EQ_U64(l.loops.segment_loop_start[k + 1] - first, 1);
        CHECK_EQ_U64(l.loops.loop_start[first + 1] - l.loops.loop_start[first], 24);
        CHECK(l.loops.outer[k] == first);
        CHECK(l.loops.loop_area[first] > 3.0 && l.loops.loop_area[first] < M_PI);
    }
    CHECK_EQ_U64(caps, 2);
    looped_free(&l);
    tm_free(&cyl);
}

/* Labels set by hand on a 2x2 grid: the 6 triangles around the centre vertex 4 run
 * A A B A A B: the centre is on two segments but on
 * segment A twice: a corner, with 4 label changes. (Labels per quad: A B / B A.) */
static void test_pinch_and_bad_labels(void)
{
    test_mesh grid = tm_grid(2, NULL);
    sl_mesh_adjacency adj;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_mesh_adjacency_build(grid.triangles, grid.triangle_count, grid.vertex_count,
                                  grid.positions, 0, &adj, &err) == 0);
    /* quads 0 (lower left), 1 (lower right), 2 (upper left), 3 (upper right): A B / B A */
    uint32_t label[8] = {0, 0, 1, 1, 1, 1, 0, 0};
    sl_segment_loops loops;
    CHECK(sl_segment_loops_build(&adj, grid.positions, label, 2, &loops, &err) == 0);
    CHECK(loops.vertex_kind[4] == SL_SEGMENT_VERTEX_CORNER);
    CHECK_EQ_U64(loops.vertex_changes[4], 4);
    /* each segment is two squares touching at the centre: turning inside the segment
     * around the centre stays in one square, so each square is a loop of its own */
    CHECK_EQ_U64(loops.loop_count, 4);
    uint32_t through_centre = 0;
    for (uint32_t i = 0; i < loops.loop_start[loops.loop_count]; i++)
        through_centre += adj.triangles[loops.halfedges[i]] == 4;
    CHECK_EQ_U64(through_centre, 4);
    sl_segment_loops_release(&loops);
    label[3] = 7;
    CHECK(sl_segment_loops_build(&adj, grid.positions, label, 2, &loops, &err) == SL_E_BADINPUT);
    CHECK(strstr(err.message, "segment 7") != NULL);
    sl_mesh_adjacency_release(&adj);
    tm_free(&grid);
}

int main(void)
{
    test_cube();
    test_annulus();
    test_cylinder();
    test_pinch_and_bad_labels();
    return check_report();
}
