/* Marching-cube polygonizer: orientation of all 256 configurations, watertightness of
 * same-level grids, and of coarse transition cells meeting a finer region (no cracks); the
 * dual drawing's split of a loop that passes one face twice along split edges. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/mc_cube.h"
#include "tests/check.h"

/* ---- a grid of signs on (2N+1)^3 fine vertices; coarse vertices are the even ones ---- */
#define N 4                 /* coarse cells per axis */
#define F (2 * N)           /* fine cells per axis */
#define V (F + 1)           /* fine vertices per axis */

static uint8_t sign_at[V][V][V];

static uint32_t rng_state = 12345;
static uint32_t rng(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return rng_state >> 8;
}

static void random_field(int inside_percent)
{
    for (int x = 0; x < V; x++)
        for (int y = 0; y < V; y++)
            for (int z = 0; z < V; z++) {
                int border = x == 0 || y == 0 || z == 0 || x == V - 1 || y == V - 1 || z == V - 1;
                sign_at[x][y][z] = !border && (int)(rng() % 100) < inside_percent;
            }
}

/* A fine-grid edge id: its lower vertex and axis. */
static uint32_t fine_edge_id(int x, int y, int z, int axis)
{
    return (uint32_t)(((x * V + y) * V + z) * 3 + axis);
}

static int corner_offset(int c, int axis)
{
    return (c >> axis) & 1;
}

/* Edges are keyed by (min vertex id, max vertex id) of the welded mesh. */
typedef struct edge_count {
    uint32_t a, b;
    int count;
} edge_count;

static edge_count edges[200000];
static int edge_total;
static int triangle_total;

static void count_edge(uint32_t a, uint32_t b)
{
    if (a > b) {
        uint32_t t = a;
        a = b;
        b = t;
    }
    for (int i = 0; i < edge_total; i++)
        if (edges[i].a == a && edges[i].b == b) {
            edges[i].count++;
            return;
        }
    edges[edge_total++] = (edge_count){a, b, 1};
}

static int count_bad_edges(void)
{
    int bad = 0;
    for (int i = 0; i < edge_total; i++)
        bad += edges[i].count != 2;
    return bad;
}

/* Coarse cell (cx, cy, cz) at scale s (1 = fine cell, 2 = coarse cell) with its split edges
 * and faces; resolves point ids to fine-edge ids and counts the triangles' edges. */
static void emit_cell(int x0, int y0, int z0, int s, const sl_mc_cell *cell)
{
    static sl_mc_triangles tri;
    static uint32_t cell_serial;
    sl_mc_triangulate(cell, &tri);
    cell_serial++;
    for (int t = 0; t < tri.count; t++) {
        uint32_t ids[3];
        for (int k = 0; k < 3; k++) {
            int p = tri.points[t][k];
            if (p >= 60) { /* a centroid: this cell's own vertex */
                ids[k] = 0x80000000u + cell_serial * 8 + (uint32_t)(p - 60);
                continue;
            }
            int e, half = -1, face = -1, spoke = -1;
            if (p < 12)
                e = p;
            else if (p < 36)
                e = (p - 12) / 2, half = (p - 12) % 2;
            else
                face = (p - 36) / 4, spoke = (p - 36) % 4, e = -1;
            if (face >= 0) { /* centre -> midpoint of the face's spoke-th edge */
                int fe[4];
                sl_mc_face_edges(face, fe);
                int a = sl_mc_edge_axis(fe[spoke]), c0 = sl_mc_edge_c0(fe[spoke]);
                int mx = x0 + s * corner_offset(c0, 0), my = y0 + s * corner_offset(c0, 1),
                    mz = z0 + s * corner_offset(c0, 2);
                int h = s / 2;
                if (a == 0) mx += h; else if (a == 1) my += h; else mz += h;
                int fa = face / 2;
                int cx = x0 + h, cy = y0 + h, cz = z0 + h;
                if (fa == 0) cx = x0 + s * (face % 2);
                if (fa == 1) cy = y0 + s * (face % 2);
                if (fa == 2) cz = z0 + s * (face % 2);
                /* the spoke lies on a fine edge between the centre and the midpoint */
                int lx = cx < mx ? cx : mx, ly = cy < my ? cy : my, lz = cz < mz ? cz : mz;
                int axis = cx != mx ? 0 : cy != my ? 1 : 2;
                ids[k] = fine_edge_id(lx, ly, lz, axis);
                continue;
            }
            int a = sl_mc_edge_axis(e), c0 = sl_mc_edge_c0(e);
            int vx = x0 + s * corner_offset(c0, 0), vy = y0 + s * corner_offset(c0, 1),
                vz = z0 + s * corner_offset(c0, 2);
            if (s == 1 || half == 1 || half == 0) {
                int step = half == 1 ? s / 2 : 0;
                if (a == 0) vx += step; else if (a == 1) vy += step; else vz += step;
                ids[k] = fine_edge_id(vx, vy, vz, a);
            } else { /* whole coarse edge: the crossing is on the half where the sign flips */
                int mx = vx + (a == 0), my = vy + (a == 1), mz = vz + (a == 2);
                int first_half = sign_at[vx][vy][vz] != sign_at[mx][my][mz];
                if (!first_half) { vx = mx; vy = my; vz = mz; }
                ids[k] = fine_edge_id(vx, vy, vz, a);
            }
        }
        triangle_total++;
        count_edge(ids[0], ids[1]);
        count_edge(ids[1], ids[2]);
        count_edge(ids[2], ids[0]);
    }
}

static uint8_t corner_signs(int x0, int y0, int z0, int s)
{
    uint8_t inside = 0;
    for (int c = 0; c < 8; c++)
        if (sign_at[x0 + s * corner_offset(c, 0)][y0 + s * corner_offset(c, 1)][z0 + s * corner_offset(c, 2)])
            inside |= (uint8_t)(1 << c);
    return inside;
}

/* refined[cx][cy][cz]: coarse cell replaced by its 8 fine cells. */
static int refined[N][N][N];

static int is_refined(int cx, int cy, int cz)
{
    if (cx < 0 || cy < 0 || cz < 0 || cx >= N || cy >= N || cz >= N)
        return 0;
    return refined[cx][cy][cz];
}

static void polygonize_mixed(void)
{
    edge_total = triangle_total = 0;
    for (int cx = 0; cx < N; cx++)
        for (int cy = 0; cy < N; cy++)
            for (int cz = 0; cz < N; cz++) {
                int x0 = 2 * cx, y0 = 2 * cy, z0 = 2 * cz;
                if (refined[cx][cy][cz]) {
                    for (int c = 0; c < 8; c++) {
                        sl_mc_cell cell = {0};
                        int fx = x0 + corner_offset(c, 0), fy = y0 + corner_offset(c, 1),
                            fz = z0 + corner_offset(c, 2);
                        cell.inside = corner_signs(fx, fy, fz, 1);
                        emit_cell(fx, fy, fz, 1, &cell);
                    }
                    continue;
                }
                sl_mc_cell cell = {0};
                cell.inside = corner_signs(x0, y0, z0, 2);
                for (int f = 0; f < 6; f++) { /* face neighbour refined: split the face */
                    int a = f / 2, d = f % 2 ? 1 : -1;
                    int nx = cx + (a == 0) * d, ny = cy + (a == 1) * d, nz = cz + (a == 2) * d;
                    if (!is_refined(nx, ny, nz))
                        continue;
                    cell.split_faces |= (uint8_t)(1 << f);
                    int fx = x0 + 1, fy = y0 + 1, fz = z0 + 1;
                    if (a == 0) fx = x0 + 2 * (f % 2);
                    if (a == 1) fy = y0 + 2 * (f % 2);
                    if (a == 2) fz = z0 + 2 * (f % 2);
                    if (sign_at[fx][fy][fz])
                        cell.centre_inside |= (uint8_t)(1 << f);
                    int fe[4];
                    sl_mc_face_edges(f, fe);
                    for (int k = 0; k < 4; k++)
                        cell.split_edges |= (uint16_t)(1 << fe[k]);
                }
                for (int e = 0; e < 12; e++) { /* any of the 3 other cells at the edge refined */
                    int a = sl_mc_edge_axis(e), c0 = sl_mc_edge_c0(e);
                    int b = (a + 1) % 3, c = (a + 2) % 3;
                    int ob = corner_offset(c0, b) ? 1 : -1, oc = corner_offset(c0, c) ? 1 : -1;
                    int base[3] = {cx, cy, cz};
                    int n1[3] = {cx, cy, cz}, n2[3] = {cx, cy, cz}, n3[3] = {cx, cy, cz};
                    n1[b] += ob;
                    n2[c] += oc;
                    n3[b] += ob;
                    n3[c] += oc;
                    (void)base;
                    if (is_refined(n1[0], n1[1], n1[2]) || is_refined(n2[0], n2[1], n2[2]) ||
                        is_refined(n3[0], n3[1], n3[2]))
                        cell.split_edges |= (uint16_t)(1 << e);
                }
                for (int e = 0; e < 12; e++) {
                    if (!(cell.split_edges >> e & 1))
                        continue;
                    int a = sl_mc_edge_axis(e), c0 = sl_mc_edge_c0(e);
                    int mx = x0 + 2 * corner_offset(c0, 0) + (a == 0),
                        my = y0 + 2 * corner_offset(c0, 1) + (a == 1),
                        mz = z0 + 2 * corner_offset(c0, 2) + (a == 2);
                    if (sign_at[mx][my][mz])
                        cell.mid_inside |= (uint16_t)(1 << e);
                }
                emit_cell(x0, y0, z0, 2, &cell);
            }
}

/* Position of a point id of the uniform table with crossings at edge midpoints. */
static void point_position(const sl_mc_triangles *tri, int id, double out[3])
{
    if (id >= 60) { /* centroid of its loop */
        const sl_mc_triangles *t = tri;
        int l = id - 60;
        out[0] = out[1] = out[2] = 0;
        for (int i = 0; i < t->loop_sizes[l]; i++) {
            double q[3];
            point_position(tri, t->loop_points[l][i], q);
            for (int a = 0; a < 3; a++)
                out[a] += q[a] / t->loop_sizes[l];
        }
        return;
    }
    int c0 = sl_mc_edge_c0(id), c1 = sl_mc_edge_c1(id);
    for (int a = 0; a < 3; a++)
        out[a] = 0.5 * (corner_offset(c0, a) + corner_offset(c1, a));
}

/* Trilinear interpolation of +1 (outside) / -1 (inside) corner values. */
static double trilinear(int config, const double p[3])
{
    double sum = 0;
    for (int c = 0; c < 8; c++) {
        double w = 1;
        for (int a = 0; a < 3; a++)
            w *= corner_offset(c, a) ? p[a] : 1 - p[a];
        sum += w * ((config >> c & 1) ? -1 : 1);
    }
    return sum;
}

/* Every triangle must face the outside: the field grows along its normal. */
static void test_orientation(void)
{
    const sl_mc_triangles *table = sl_mc_uniform_table();
    int wrong = 0, empty_mismatch = 0, checked = 0;
    for (int config = 0; config < 256; config++) {
        int n_in = __builtin_popcount((unsigned)config);
        empty_mismatch += (table[config].count == 0) != (n_in == 0 || n_in == 8);
        for (int t = 0; t < table[config].count; t++) {
            double p[3][3], u[3], v[3], n[3], c[3], ahead[3], behind[3];
            for (int k = 0; k < 3; k++)
                point_position(&table[config], table[config].points[t][k], p[k]);
            for (int a = 0; a < 3; a++) {
                u[a] = p[1][a] - p[0][a];
                v[a] = p[2][a] - p[0][a];
                c[a] = (p[0][a] + p[1][a] + p[2][a]) / 3;
            }
            n[0] = u[1] * v[2] - u[2] * v[1];
            n[1] = u[2] * v[0] - u[0] * v[2];
            n[2] = u[0] * v[1] - u[1] * v[0];
            double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (int a = 0; a < 3; a++) {
                ahead[a] = c[a] + 0.05 * n[a] / len;
                behind[a] = c[a] - 0.05 * n[a] / len;
            }
            wrong += trilinear(config, ahead) <= trilinear(config, behind);
            checked++;
        }
    }
    CHECK_MSG(wrong == 0, "%d of %d triangles face inwards", wrong, checked);
    CHECK_MSG(empty_mismatch == 0, "%d configurations with wrong emptiness", empty_mismatch);
    CHECK_EQ_U64(table[0x01].count, 1);
    CHECK_EQ_U64(table[0x0f].count, 2);
}

static void test_uniform_watertight(void)
{
    int bad_total = 0, triangles = 0;
    for (int trial = 0; trial < 40; trial++) {
        random_field(20 + trial);
        memset(refined, 0, sizeof refined);
        /* all coarse cells refined = a uniform fine grid */
        for (int x = 0; x < N; x++)
            for (int y = 0; y < N; y++)
                for (int z = 0; z < N; z++)
                    refined[x][y][z] = 1;
        polygonize_mixed();
        bad_total += count_bad_edges();
        triangles += triangle_total;
    }
    CHECK_MSG(bad_total == 0, "%d edges not shared by exactly two triangles", bad_total);
    CHECK(triangles > 1000);
}

static void test_transition_watertight(void)
{
    int bad_total = 0, triangles = 0;
    for (int trial = 0; trial < 200; trial++) {
        random_field(15 + trial % 50);
        for (int x = 0; x < N; x++)
            for (int y = 0; y < N; y++)
                for (int z = 0; z < N; z++)
                    refined[x][y][z] = (int)(rng() % 2);
        polygonize_mixed();
        int bad = count_bad_edges();
        if (bad && bad_total == 0)
            fprintf(stderr, "trial %d: %d bad edges\n", trial, bad);
        bad_total += bad;
        triangles += triangle_total;
    }
    CHECK_MSG(bad_total == 0, "%d crack edges across one level of refinement", bad_total);
    CHECK(triangles > 5000);
}

/* Whether loop l of tri has the segment from point p to point q. */
static int loop_has_segment(const sl_mc_triangles *tri, int l, int p, int q)
{
    int n = tri->loop_sizes[l];
    for (int a = 0; a < n; a++)
        if (tri->loop_points[l][a] == p && tri->loop_points[l][(a + 1) % n] == q)
            return 1;
    return 0;
}

/* The dual drawing's loop split (sl_mc_split_double_passes, docs/lod.md "Vertices from
 * quadrics"), on a transition cell of cow's qef model: edge 0 (corners 0 and 1 outside)
 * split with its midpoint inside, face 2 (the finer side) split, face 4 whole. Face 4's
 * walk joins the two halves of edge 0 (points 12 -> 13) and cuts corner 2 off (1 -> 4);
 * one loop passes both. The same-level neighbour across face 4 draws the same two
 * segments: left whole, its loop and this one share both, and their dual vertices an
 * edge of four triangles. Split, each segment is in a loop of its own. */
static void test_split_edge_double_pass(void)
{
    sl_mc_cell cell;
    memset(&cell, 0, sizeof cell);
    cell.inside = 0xf4;
    cell.split_edges = 0x305;
    cell.mid_inside = 0x105;
    cell.split_faces = 0x04;
    cell.centre_inside = 0x04;
    sl_mc_triangles tri;
    sl_mc_triangulate(&cell, &tri);
    int whole = -1, loops = tri.loops, sizes = 0;
    for (int l = 0; l < tri.loops; l++) {
        sizes += tri.loop_sizes[l];
        if (loop_has_segment(&tri, l, 12, 13) && loop_has_segment(&tri, l, 1, 4))
            whole = l;
    }
    CHECK_MSG(whole >= 0, "no loop with both of face 4's segments (%d loops)", tri.loops);
    sl_mc_split_double_passes(&cell, &tri);
    int both = 0, small = 0, split_sizes = 0;
    for (int l = 0; l < tri.loops; l++) {
        split_sizes += tri.loop_sizes[l];
        small += tri.loop_sizes[l] < 3;
        both += loop_has_segment(&tri, l, 12, 13) && loop_has_segment(&tri, l, 1, 4);
    }
    CHECK_MSG(both == 0 && tri.loops == loops + 1,
              "after the split %d loops (want %d), %d with both segments", tri.loops, loops + 1,
              both);
    CHECK_MSG(split_sizes == sizes + 2 && small == 0,
              "points %d (want %d + the chord's 2), %d loops under 3", split_sizes, sizes, small);
}

int main(void)
{
    test_orientation();
    test_uniform_watertight();
    test_transition_watertight();
    test_split_edge_double_pass();
    return check_report();
}
