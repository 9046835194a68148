/* Welding by equal positions (sl_mesh_weld_positions) and the edge topology built on it
 * (sl_mesh_topology_compute, whose edge counts run in parallel from 65,536 triangles).
 * The weld's ids must be the documented numbering (a dense id per position, in order of
 * each position's first vertex; UINT32_MAX for an unused vertex), checked against a
 * numbering made here by sorting, on fandisk's triangle soup (every triangle its own three
 * vertices, the soup six times over, every other one in reverse, with unused vertices between) and
 * on a grid with -0 and +0 coordinates. The soup's topology is fandisk's edges, each one
 * shared by twelve triangles (six copies): as many non-manifold edges, no border, one
 * part; the same on 1 and 2 threads; pulled apart, six parts, on 1 and 2 threads. */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "formats/ply.h"
#include "geometry/mesh_distance.h"
#include "tests/check.h"
#include "tests/unit/glb_meshes.h"

#define NONE UINT32_MAX

static const float *pos_base;
static int cmp_by_position(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    for (int k = 0; k < 3; k++) {
        float p = pos_base[3 * (uint64_t)a + k], q = pos_base[3 * (uint64_t)b + k];
        if (p != q) /* -0 == +0 */
            return p < q ? -1 : 1;
    }
    return (a > b) - (a < b); /* then by index: a position's first vertex leads */
}

/* The numbering by sorting the used vertices by position, then by index. */
static int64_t reference_weld(const sl_mesh *m, uint32_t *weld)
{
    uint8_t *used = calloc(m->vertex_count + 1, 1);
    uint32_t *order = malloc((m->vertex_count + 1) * sizeof *order);
    uint32_t *first = malloc((m->vertex_count + 1) * sizeof *first);
    uint64_t n = 0;
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        used[m->triangles[i]] = 1;
    for (uint64_t v = 0; v < m->vertex_count; v++) {
        weld[v] = NONE;
        if (used[v])
            order[n++] = (uint32_t)v;
    }
    pos_base = m->positions;
    qsort(order, n, sizeof *order, cmp_by_position);
    /* first[v]: the first vertex of v's position (equal runs are sorted by index) */
    for (uint64_t i = 0; i < n; i++) {
        const float *p = i ? &m->positions[3 * (uint64_t)order[i - 1]] : NULL,
                    *q = &m->positions[3 * (uint64_t)order[i]];
        int same = p && p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
        first[order[i]] = same ? first[order[i - 1]] : order[i];
    }
    int64_t ids = 0;
    for (uint64_t v = 0; v < m->vertex_count; v++)
        if (used[v] && first[v] == v)
            weld[v] = (uint32_t)ids++;
    for (uint64_t v = 0; v < m->vertex_count; v++)
        if (used[v])
            weld[v] = weld[first[v]];
    free(used);
    free(order);
    free(first);
    return ids;
}

static void check_weld(const char *what, const sl_mesh *m)
{
    uint64_t n = m->vertex_count;
    uint32_t *want = malloc(n * sizeof *want), *one = malloc(n * sizeof *one),
             *two = malloc(n * sizeof *two);
    int64_t ids = reference_weld(m, want);
    omp_set_num_threads(1);
    int64_t ids1 = sl_mesh_weld_positions(m, one);
    omp_set_num_threads(2);
    int64_t ids2 = sl_mesh_weld_positions(m, two);
    CHECK_MSG(ids1 == ids && ids2 == ids, "%s: %lld / %lld ids for %lld positions", what,
              (long long)ids1, (long long)ids2, (long long)ids);
    uint64_t wrong1 = 0, wrong2 = 0;
    for (uint64_t v = 0; v < n; v++)
        wrong1 += one[v] != want[v], wrong2 += two[v] != want[v];
    CHECK_MSG(wrong1 == 0 && wrong2 == 0,
              "%s: %llu (1 thread) and %llu (2 threads) of %llu vertices numbered otherwise", what,
              (unsigned long long)wrong1, (unsigned long long)wrong2, (unsigned long long)n);
    free(want);
    free(one);
    free(two);
}

/* fandisk as a soup: six copies of it, each triangle with its own corners, every fourth vertex
 * slot unused; every other copy's triangles in reverse order. */
static void fandisk_soup(sl_mesh *soup)
{
    sl_mesh m;
    sl_mesh_init(&m);
    CHECK_MSG(meshes_read_scan("fandisk", &m) == 0, "fandisk read");
    const int copies = 6;
    sl_mesh_init(soup);
    soup->triangle_count = copies * m.triangle_count;
    soup->vertex_count = 4 * soup->triangle_count; /* 3 used + 1 unused per triangle */
    soup->positions = calloc(3 * soup->vertex_count, sizeof *soup->positions);
    soup->triangles = malloc(3 * soup->triangle_count * sizeof *soup->triangles);
    uint64_t t = 0;
    for (int c = 0; c < copies; c++)
        for (uint64_t k = 0; k < m.triangle_count; k++, t++) {
            uint64_t src = c % 2 ? m.triangle_count - 1 - k : k;
            for (int j = 0; j < 3; j++) {
                uint64_t v = 4 * t + (uint64_t)j + (j >= 1); /* slot 4t+1 stays unused */
                memcpy(&soup->positions[3 * v], &m.positions[3 * (uint64_t)m.triangles[3 * src + j]],
                       3 * sizeof(float));
                soup->triangles[3 * t + j] = (uint32_t)v;
            }
        }
    sl_mesh_release(&m);
}

/* A 200 x 200 grid of quads, each its own four corners, centred on zero: the coordinates
 * on the axes are -0 in one quad and +0 in its neighbour. */
static void signed_zero_grid(sl_mesh *g)
{
    const int s = 200;
    sl_mesh_init(g);
    g->vertex_count = 4ull * s * s;
    g->triangle_count = 2ull * s * s;
    g->positions = malloc(3 * g->vertex_count * sizeof *g->positions);
    g->triangles = malloc(3 * g->triangle_count * sizeof *g->triangles);
    for (int i = 0; i < s; i++)
        for (int j = 0; j < s; j++) {
            uint64_t q = (uint64_t)i * s + j, v = 4 * q;
            for (int c = 0; c < 4; c++) {
                int x = i - s / 2 + (c & 1), y = j - s / 2 + (c >> 1);
                float fx = (float)x, fy = (float)y;
                if (x == 0 && (i & 1))
                    fx = -0.0f;
                if (y == 0 && (j & 1))
                    fy = -0.0f;
                g->positions[3 * (v + c)] = fx;
                g->positions[3 * (v + c) + 1] = fy;
                g->positions[3 * (v + c) + 2] = 0.0f;
            }
            uint32_t a = (uint32_t)v;
            uint32_t tri[6] = {a, a + 1, a + 3, a, a + 3, a + 2};
            memcpy(&g->triangles[6 * q], tri, sizeof tri);
        }
}

/* The soup's topology against fandisk's own (below the parallel size). */
static void check_soup_topology(const sl_mesh *soup)
{
    sl_mesh m;
    sl_mesh_init(&m);
    CHECK_MSG(meshes_read_scan("fandisk", &m) == 0, "fandisk read");
    sl_mesh_topology own, one, two;
    sl_error err;
    sl_error_init(&err);
    CHECK_MSG(sl_mesh_topology_compute(&m, &own, &err) == 0, "fandisk topology");
    omp_set_num_threads(1);
    CHECK_MSG(sl_mesh_topology_compute(soup, &one, &err) == 0, "soup topology, 1 thread");
    omp_set_num_threads(2);
    CHECK_MSG(sl_mesh_topology_compute(soup, &two, &err) == 0, "soup topology, 2 threads");
    CHECK_MSG(own.watertight && own.edges > 0, "fandisk is closed (%llu edges)",
              (unsigned long long)own.edges);
    CHECK_MSG(two.edges == own.edges && two.nonmanifold_edges == own.edges &&
                  two.boundary_edges == 0 && two.degenerate_triangles == 0 && !two.watertight &&
                  two.welded_vertices == own.welded_vertices && two.components == 1,
              "soup: %llu edges (%llu non-manifold, %llu border), %llu welded, %llu parts; "
              "fandisk %llu edges, %llu welded",
              (unsigned long long)two.edges, (unsigned long long)two.nonmanifold_edges,
              (unsigned long long)two.boundary_edges, (unsigned long long)two.welded_vertices,
              (unsigned long long)two.components, (unsigned long long)own.edges,
              (unsigned long long)own.welded_vertices);
    CHECK_MSG(memcmp(&one, &two, sizeof one) == 0, "soup topology differs on 1 and 2 threads");
    sl_mesh_release(&m);
}

/* The soup pulled apart: copy c moved by c metres along x, so six parts of one fandisk
 * each, found by the union-find shared by the threads: the same parts, areas and
 * numbering on 1 and 2 threads, each part a sixth of the area. */
static void check_parts(sl_mesh *soup)
{
    uint64_t per_copy = soup->triangle_count / 6;
    for (uint64_t t = 0; t < soup->triangle_count; t++)
        for (int j = 0; j < 3; j++)
            soup->positions[3 * (uint64_t)soup->triangles[3 * t + j]] += (float)(t / per_copy);
    uint32_t *part[2];
    double *area[2] = {NULL, NULL};
    uint64_t parts[2] = {0, 0};
    sl_mesh_topology topo[2];
    sl_error err;
    for (int r = 0; r < 2; r++) {
        omp_set_num_threads(r + 1);
        part[r] = malloc(soup->triangle_count * sizeof *part[r]);
        sl_error_init(&err);
        CHECK_MSG(sl_mesh_parts(soup, part[r], &area[r], &parts[r], &err) == 0, "parts: %s",
                  err.message);
        CHECK_MSG(sl_mesh_topology_compute(soup, &topo[r], &err) == 0, "topology: %s",
                  err.message);
    }
    CHECK_MSG(parts[0] == 6 && parts[1] == 6 && topo[0].components == 6 && topo[1].components == 6,
              "six parts: %llu and %llu (parts), %llu and %llu (topology)",
              (unsigned long long)parts[0], (unsigned long long)parts[1],
              (unsigned long long)topo[0].components, (unsigned long long)topo[1].components);
    CHECK(memcmp(part[0], part[1], soup->triangle_count * sizeof *part[0]) == 0);
    CHECK(memcmp(&topo[0], &topo[1], sizeof topo[0]) == 0);
    uint64_t off = 0;
    for (uint64_t t = 0; t < soup->triangle_count; t++)
        off += part[1][t] != t / per_copy;
    CHECK_MSG(off == 0, "%llu triangles in another copy's part", (unsigned long long)off);
    for (uint64_t k = 0; parts[1] == 6 && k < 6; k++)
        CHECK_MSG(fabs(area[1][k] * 6 - topo[1].area) < 1e-6 * topo[1].area,
                  "part %llu: area %g of %g", (unsigned long long)k, area[1][k], topo[1].area);
    for (int r = 0; r < 2; r++)
        free(part[r]), free(area[r]);
}

int main(void)
{
    sl_mesh m;
    fandisk_soup(&m);
    CHECK_MSG(m.triangle_count >= 65536, "the soup takes the parallel path (%llu triangles)",
              (unsigned long long)m.triangle_count);
    check_weld("fandisk soup", &m);
    check_soup_topology(&m);
    check_parts(&m);
    sl_mesh_release(&m);
    signed_zero_grid(&m);
    check_weld("grid with -0 and +0", &m);
    sl_mesh_release(&m);
    return check_report();
}
