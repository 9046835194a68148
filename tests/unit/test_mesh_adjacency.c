/* Half-edge adjacency (geometry/mesh_adjacency.h): twins, fans, boundary loops, Euler
 * characteristic on analytic meshes; cut non-manifold and inconsistent edges, non-manifold
 * vertices, degenerate triangles and their refusal in strict mode; thread-count
 * independence. */
#include <omp.h>
#include <string.h>

#include "geometry/mesh_adjacency.h"
#include "tests/check.h"
#include "tests/unit/analytic_meshes.h"

static int build(const test_mesh *m, uint32_t flags, sl_mesh_adjacency *adj, sl_error *err)
{
    sl_error_init(err);
    return sl_mesh_adjacency_build(m->triangles, m->triangle_count, m->vertex_count,
                                   m->positions, flags, adj, err);
}

/* Every twin is symmetric and runs the other way; every fan walk from a vertex's stored
 * half-edge sees each of its corners once (manifold meshes). */
static void check_structure(const sl_mesh_adjacency *adj)
{
    uint64_t nh = 3 * (uint64_t)adj->triangle_count, bad_twin = 0, bad_fan = 0;
    for (uint32_t h = 0; h < nh; h++) {
        uint32_t t = adj->twin[h];
        if (t == SL_HALFEDGE_NONE)
            continue;
        bad_twin += adj->twin[t] != h || sl_halfedge_origin(adj, t) != sl_halfedge_target(adj, h) ||
                    sl_halfedge_target(adj, t) != sl_halfedge_origin(adj, h);
    }
    uint32_t *corners = calloc(adj->vertex_count, sizeof *corners);
    for (uint32_t h = 0; h < nh; h++)
        if (!adj->degenerate[h / 3])
            corners[adj->triangles[h]]++;
    for (uint32_t v = 0; v < adj->vertex_count; v++) {
        uint32_t h0 = adj->vertex_halfedge[v];
        if (h0 == SL_HALFEDGE_NONE) {
            bad_fan += corners[v] != 0;
            continue;
        }
        if (sl_halfedge_origin(adj, h0) != v)
            bad_fan++;
        if ((adj->vertex_flags[v] & SL_VERTEX_BOUNDARY) && adj->twin[h0] != SL_HALFEDGE_NONE)
            bad_fan++;
        if (adj->vertex_flags[v] & SL_VERTEX_NONMANIFOLD)
            continue;
        uint32_t seen = 0, h = h0;
        do {
            seen++;
            if (sl_halfedge_origin(adj, h) != v)
                bad_fan++;
            h = sl_halfedge_rotate(adj, h);
        } while (h != SL_HALFEDGE_NONE && h != h0 && seen < 1000);
        bad_fan += seen != corners[v];
    }
    free(corners);
    CHECK_EQ_U64(bad_twin, 0);
    CHECK_EQ_U64(bad_fan, 0);
}

static void test_closed_meshes(void)
{
    test_mesh cube = tm_cube(3), torus = tm_torus(12, 8, 2.0, 0.5), sphere = tm_sphere(16, 9);
    const test_mesh *meshes[3] = {&cube, &torus, &sphere};
    const int64_t euler[3] = {2, 0, 2};
    for (int i = 0; i < 3; i++) {
        sl_mesh_adjacency adj;
        sl_error err;
        CHECK(build(meshes[i], SL_ADJACENCY_STRICT, &adj, &err) == 0);
        const sl_adjacency_report *r = &adj.report;
        CHECK_EQ_U64(r->boundary_edges, 0);
        CHECK_EQ_U64(r->nonmanifold_edges + r->inconsistent_edges + r->nonmanifold_vertices, 0);
        CHECK_EQ_U64(r->boundary_loops, 0);
        CHECK_EQ_U64(r->edges, 3 * (uint64_t)meshes[i]->triangle_count / 2);
        CHECK_MSG(r->euler_characteristic == euler[i], "mesh %d: chi %lld", i,
                  (long long)r->euler_characteristic);
        for (uint64_t h = 0; h < 3 * (uint64_t)adj.triangle_count; h++)
            if (adj.twin[h] == SL_HALFEDGE_NONE) {
                CHECK_MSG(0, "mesh %d: half-edge %llu has no twin", i, (unsigned long long)h);
                break;
            }
        check_structure(&adj);
        sl_mesh_adjacency_release(&adj);
    }
    tm_free(&cube);
    tm_free(&torus);
    tm_free(&sphere);
}

static void test_open_meshes(void)
{
    /* a 4x4 grid: one boundary loop of 16 edges, chi 1 */
    test_mesh grid = tm_grid(4, NULL);
    sl_mesh_adjacency adj;
    sl_error err;
    CHECK(build(&grid, SL_ADJACENCY_STRICT, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.boundary_edges, 16);
    CHECK_EQ_U64(adj.report.boundary_loops, 1);
    CHECK(adj.report.euler_characteristic == 1);
    check_structure(&adj);
    /* the boundary loop, followed by next_boundary, has 16 half-edges */
    uint32_t h0 = adj.vertex_halfedge[0], h = h0, n = 0;
    CHECK(adj.twin[h0] == SL_HALFEDGE_NONE);
    do {
        n++;
        h = sl_halfedge_next_boundary(&adj, h);
    } while (h != h0 && n < 100);
    CHECK_EQ_U64(n, 16);
    sl_mesh_adjacency_release(&adj);
    /* the grid with its middle 2x2 quads (8 triangles) removed: an annulus, chi 0 */
    test_mesh ring;
    memset(&ring, 0, sizeof ring);
    for (uint32_t v = 0; v < grid.vertex_count; v++)
        tm_vertex(&ring, grid.positions[3 * v], grid.positions[3 * v + 1], 0);
    for (uint32_t t = 0; t < grid.triangle_count; t++) {
        uint32_t q = t / 2, i = q % 4, j = q / 4;
        if (i >= 1 && i <= 2 && j >= 1 && j <= 2)
            continue;
        tm_triangle(&ring, grid.triangles[3 * t], grid.triangles[3 * t + 1],
                    grid.triangles[3 * t + 2]);
    }
    CHECK(build(&ring, SL_ADJACENCY_STRICT, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.boundary_loops, 2);
    CHECK_EQ_U64(adj.report.boundary_edges, 24);
    CHECK(adj.report.euler_characteristic == 0);
    check_structure(&adj);
    sl_mesh_adjacency_release(&adj);
    tm_free(&ring);
    tm_free(&grid);

    /* a single triangle: 3 boundary edges, one loop */
    test_mesh one;
    memset(&one, 0, sizeof one);
    tm_vertex(&one, 0, 0, 0);
    tm_vertex(&one, 1, 0, 0);
    tm_vertex(&one, 0, 1, 0);
    tm_triangle(&one, 0, 1, 2);
    CHECK(build(&one, SL_ADJACENCY_STRICT, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.boundary_edges, 3);
    CHECK_EQ_U64(adj.report.boundary_loops, 1);
    CHECK(adj.report.euler_characteristic == 1);
    check_structure(&adj);
    sl_mesh_adjacency_release(&adj);
    tm_free(&one);

    /* no triangles at all */
    test_mesh none;
    memset(&none, 0, sizeof none);
    CHECK(build(&none, SL_ADJACENCY_STRICT, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.edges, 0);
    sl_mesh_adjacency_release(&adj);
}

/* Three triangles on one edge (a book of three pages), two triangles running an edge the
 * same way, two fans meeting at a vertex, a degenerate triangle, an index out of range. */
static void test_problems(void)
{
    sl_mesh_adjacency adj;
    sl_error err;
    test_mesh book;
    memset(&book, 0, sizeof book);
    tm_vertex(&book, 0, 0, 0);
    tm_vertex(&book, 0, 0, 1);
    tm_vertex(&book, 1, 0, 0);
    tm_vertex(&book, 0, 1, 0);
    tm_vertex(&book, -1, -1, 0);
    tm_triangle(&book, 0, 1, 2);
    tm_triangle(&book, 1, 0, 3);
    tm_triangle(&book, 1, 0, 4);
    CHECK(build(&book, 0, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.nonmanifold_edges, 1);
    CHECK(adj.report.problem == SL_ADJACENCY_NONMANIFOLD_EDGE);
    CHECK(adj.report.v[0] == 0 && adj.report.v[1] == 1 && adj.report.edge_triangles == 3);
    CHECK(adj.twin[0] == SL_HALFEDGE_NONE && adj.twin[3] == SL_HALFEDGE_NONE &&
          adj.twin[6] == SL_HALFEDGE_NONE);
    CHECK((adj.vertex_flags[0] & SL_VERTEX_CUT) && (adj.vertex_flags[1] & SL_VERTEX_CUT));
    CHECK(!(adj.vertex_flags[2] & SL_VERTEX_CUT));
    check_structure(&adj);
    sl_mesh_adjacency_release(&adj);
    CHECK(build(&book, SL_ADJACENCY_STRICT, &adj, &err) == SL_E_BADINPUT);
    CHECK_MSG(strstr(err.message, "shared by 3 triangles") && strstr(err.message, "non-manifold"),
              "%s", err.message);
    CHECK(adj.twin == NULL);

    /* inconsistent: triangles 0 1 2 and 0 1 3 both run 0 -> 1 */
    test_mesh flip;
    memset(&flip, 0, sizeof flip);
    tm_vertex(&flip, 0, 0, 0);
    tm_vertex(&flip, 1, 0, 0);
    tm_vertex(&flip, 0, 1, 0);
    tm_vertex(&flip, 0, -1, 0);
    tm_triangle(&flip, 0, 1, 2);
    tm_triangle(&flip, 0, 1, 3);
    CHECK(build(&flip, 0, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.inconsistent_edges, 1);
    CHECK_EQ_U64(adj.report.nonmanifold_edges, 0);
    CHECK(adj.twin[0] == SL_HALFEDGE_NONE && adj.twin[3] == SL_HALFEDGE_NONE);
    sl_mesh_adjacency_release(&adj);
    CHECK(build(&flip, SL_ADJACENCY_STRICT, &adj, &err) == SL_E_BADINPUT);
    CHECK_MSG(strstr(err.message, "orientations disagree"), "%s", err.message);

    /* a bow tie: two triangles sharing vertex 0 only; and two closed cones tip to tip */
    test_mesh bow;
    memset(&bow, 0, sizeof bow);
    tm_vertex(&bow, 0, 0, 0);
    tm_vertex(&bow, 1, 0, 0);
    tm_vertex(&bow, 1, 1, 0);
    tm_vertex(&bow, -1, 0, 0);
    tm_vertex(&bow, -1, -1, 0);
    tm_triangle(&bow, 0, 1, 2);
    tm_triangle(&bow, 0, 3, 4);
    CHECK(build(&bow, 0, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.nonmanifold_vertices, 1);
    CHECK(adj.vertex_flags[0] & SL_VERTEX_NONMANIFOLD);
    CHECK(adj.report.problem == SL_ADJACENCY_NONMANIFOLD_VERTEX && adj.report.v[0] == 0);
    CHECK_EQ_U64(adj.report.boundary_loops, 2);
    sl_mesh_adjacency_release(&adj);
    CHECK(build(&bow, SL_ADJACENCY_STRICT, &adj, &err) == SL_E_BADINPUT);
    CHECK_MSG(strstr(err.message, "vertex 0") && strstr(err.message, "more than one fan"), "%s",
              err.message);

    test_mesh cones;
    memset(&cones, 0, sizeof cones);
    uint32_t tip = tm_vertex(&cones, 0, 0, 0);
    for (int side = 0; side < 2; side++) {
        double z = side ? 1 : -1;
        uint32_t base = cones.vertex_count;
        for (int a = 0; a < 4; a++)
            tm_vertex(&cones, cos(a * M_PI / 2), sin(a * M_PI / 2), z);
        uint32_t centre = tm_vertex(&cones, 0, 0, z);
        for (uint32_t a = 0; a < 4; a++) {
            uint32_t b = (a + 1) % 4;
            if (side) {
                tm_triangle(&cones, tip, base + b, base + a);
                tm_triangle(&cones, base + a, base + b, centre);
            } else {
                tm_triangle(&cones, tip, base + a, base + b);
                tm_triangle(&cones, base + b, base + a, centre);
            }
        }
    }
    CHECK(build(&cones, 0, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.boundary_edges, 0);
    CHECK_EQ_U64(adj.report.nonmanifold_vertices, 1);
    CHECK(adj.vertex_flags[tip] & SL_VERTEX_NONMANIFOLD);
    sl_mesh_adjacency_release(&adj);

    /* degenerate: left out, counted, refused in strict mode */
    test_mesh deg = tm_grid(2, NULL);
    tm_triangle(&deg, 0, 1, 1);
    CHECK(build(&deg, 0, &adj, &err) == 0);
    CHECK_EQ_U64(adj.report.degenerate_triangles, 1);
    CHECK(adj.degenerate[8] == 1);
    CHECK(adj.twin[24] == SL_HALFEDGE_NONE && adj.twin[25] == SL_HALFEDGE_NONE);
    CHECK_EQ_U64(adj.report.boundary_edges, 8);
    check_structure(&adj);
    sl_mesh_adjacency_release(&adj);
    CHECK(build(&deg, SL_ADJACENCY_STRICT, &adj, &err) == SL_E_BADINPUT);
    CHECK_MSG(strstr(err.message, "degenerate"), "%s", err.message);

    /* an index out of range is refused in any mode */
    deg.triangles[3 * 8 + 2] = 99;
    CHECK(build(&deg, 0, &adj, &err) == SL_E_BADINPUT);
    CHECK_MSG(strstr(err.message, "names vertex 99"), "%s", err.message);
    tm_free(&book);
    tm_free(&flip);
    tm_free(&bow);
    tm_free(&cones);
    tm_free(&deg);
}

/* The same twins, flags and first problem on 1 and 2 threads, on a torus whose triangles
 * are shuffled and which carries some non-manifold edges (extra triangles on its edges). */
static void test_threads(void)
{
    test_mesh m = tm_torus(60, 40, 2.0, 0.7);
    uint64_t state = 12345;
    for (uint32_t t = m.triangle_count - 1; t > 0; t--) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        uint32_t o = (uint32_t)((state >> 33) % (t + 1));
        for (int c = 0; c < 3; c++) {
            uint32_t x = m.triangles[3 * t + c];
            m.triangles[3 * t + c] = m.triangles[3 * o + c];
            m.triangles[3 * o + c] = x;
        }
    }
    uint32_t apex = tm_vertex(&m, 0, 0, 5);
    for (uint32_t t = 100; t < 2000; t += 97)
        tm_triangle(&m, m.triangles[3 * t + 1], m.triangles[3 * t], apex);
    sl_mesh_adjacency a1, a2;
    sl_error err;
    omp_set_num_threads(1);
    CHECK(build(&m, 0, &a1, &err) == 0);
    omp_set_num_threads(2);
    CHECK(build(&m, 0, &a2, &err) == 0);
    CHECK(a1.report.nonmanifold_edges >= 20);
    CHECK(memcmp(a1.twin, a2.twin, 3 * (size_t)m.triangle_count * sizeof *a1.twin) == 0);
    CHECK(memcmp(a1.vertex_halfedge, a2.vertex_halfedge, m.vertex_count * sizeof(uint32_t)) == 0);
    CHECK(memcmp(a1.vertex_flags, a2.vertex_flags, m.vertex_count) == 0);
    CHECK(memcmp(&a1.report, &a2.report, sizeof a1.report) == 0);
    sl_mesh_adjacency_release(&a1);
    sl_mesh_adjacency_release(&a2);
    tm_free(&m);
}

int main(void)
{
    test_closed_meshes();
    test_open_meshes();
    test_problems();
    test_threads();
    return check_report();
}
