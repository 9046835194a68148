/* Face-consistent marching-cube polygonization (see mc_cube.h; docs/marching-cubes.md).
 *
 * Method: walk each face boundary counter-clockwise (seen from outside the cube). Every
 * sample piece between two samples of different sign holds one crossing point. Along the
 * walk the samples fall into runs of inside samples; each run is cut off by one segment,
 * directed from the crossing where the run ends to the crossing where it began. An edge
 * shared by two faces is walked in opposite directions by them, so a crossing that ends a
 * run on one face begins one on the other: every crossing has one incoming and one outgoing
 * segment, and the segments close into loops. Loops are fan-triangulated from their
 * smallest point id (deterministic). Because the pairing depends only on the samples of a
 * face, the two cells sharing a face draw the same segments on it: no holes between
 * same-level cells, and none between a coarse transition cell and its finer neighbour.
 */
#include "runtime/mc_cube.h"

#include <pthread.h>
#include <string.h>

void sl_mc_face_corners(int f, int corners[4])
{
    int a = f / 2, side = f % 2, b = (a + 1) % 3, c = (a + 2) % 3;
    /* (b, c, a) is right-handed: (0,0) (1,0) (1,1) (0,1) in (b, c) is counter-clockwise
     * seen from +a, which is outside for the high face; the low face walks it reversed. */
    static const int bc[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int k = 0; k < 4; k++) {
        int j = side ? k : (4 - k) % 4;
        corners[k] = (side << a) | (bc[j][0] << b) | (bc[j][1] << c);
    }
}

static int edge_between(int c0, int c1)
{
    int diff = c0 ^ c1, a = diff == 1 ? 0 : diff == 2 ? 1 : 2;
    return sl_mc_edge_of(a, c0 & c1);
}

void sl_mc_face_edges(int f, int edges[4])
{
    int corners[4];
    sl_mc_face_corners(f, corners);
    for (int k = 0; k < 4; k++)
        edges[k] = edge_between(corners[k], corners[(k + 1) % 4]);
}

/* A walk around one face or sub-face: sample signs and the point id of the piece that
 * leaves each sample (towards the next one). */
typedef struct walk {
    int count;
    uint8_t inside[8];
    uint8_t piece[8];
} walk;

static void walk_push(walk *w, int inside, int piece)
{
    w->inside[w->count] = (uint8_t)(inside != 0);
    w->piece[w->count] = (uint8_t)piece;
    w->count++;
}

/* Half of edge e that touches corner `corner`. */
static int half_at(int e, int corner)
{
    return SL_MC_HALF_POINT(e, corner == sl_mc_edge_c0(e) ? 0 : 1);
}

static void pair_runs(const walk *w, int next[SL_MC_MAX_POINTS])
{
    int n = w->count, start = -1;
    for (int i = 0; i < n; i++)
        if (!w->inside[i]) {
            start = i;
            break;
        }
    if (start < 0)
        return; /* all inside: no crossing */
    int entry = -1;
    for (int step = 0; step < n; step++) {
        int i = (start + step) % n, j = (i + 1) % n;
        if (!w->inside[i] && w->inside[j])
            entry = w->piece[i];
        else if (w->inside[i] && !w->inside[j])
            next[w->piece[i]] = entry; /* exit -> entry of the same inside run */
    }
}

static void walk_face(const sl_mc_cell *cell, int f, int next[SL_MC_MAX_POINTS])
{
    int corners[4], edges[4];
    sl_mc_face_corners(f, corners);
    sl_mc_face_edges(f, edges);
    if (!(cell->split_faces >> f & 1)) {
        walk w = {0};
        for (int k = 0; k < 4; k++) {
            int c = corners[k], e = edges[k];
            if (cell->split_edges >> e & 1) {
                walk_push(&w, cell->inside >> c & 1, half_at(e, c));
                walk_push(&w, cell->mid_inside >> e & 1, half_at(e, corners[(k + 1) % 4]));
            } else {
                walk_push(&w, cell->inside >> c & 1, SL_MC_EDGE_POINT(e));
            }
        }
        pair_runs(&w, next);
        return;
    }
    int centre = cell->centre_inside >> f & 1;
    for (int k = 0; k < 4; k++) { /* the sub-face at corner k */
        int c = corners[k], e_out = edges[k], e_in = edges[(k + 3) % 4];
        walk w = {0};
        walk_push(&w, cell->inside >> c & 1, half_at(e_out, c));
        walk_push(&w, cell->mid_inside >> e_out & 1, SL_MC_SPOKE_POINT(f, k));
        walk_push(&w, centre, SL_MC_SPOKE_POINT(f, (k + 3) % 4));
        walk_push(&w, cell->mid_inside >> e_in & 1, half_at(e_in, c));
        pair_runs(&w, next);
    }
}

/* Faces a point id lies on (bit f). */
static unsigned faces_of_point(int p)
{
    if (p >= 36)
        return 1u << ((p - 36) / 4);
    int e = p < 12 ? p : (p - 12) / 2;
    int a = e / 4, c0 = sl_mc_edge_c0(e), b = (a + 1) % 3, c = (a + 2) % 3;
    return (1u << (2 * b + ((c0 >> b) & 1))) | (1u << (2 * c + ((c0 >> c) & 1)));
}

static void add_triangle(sl_mc_triangles *out, int a, int b, int c)
{
    if (out->count == SL_MC_MAX_TRIANGLES)
        return;
    uint8_t *t = out->points[out->count++];
    /* Loops run with the inside on their left; reversed, triangles face outwards. */
    t[0] = (uint8_t)a;
    t[1] = (uint8_t)c;
    t[2] = (uint8_t)b;
}

/* A fan whose chords all cross the cell interior: a chord between two points on one
 * face could be drawn by the neighbour across that face too, and the edge would then have
 * four triangles. Without such an apex, the loop is fanned from its centroid instead. */
static void triangulate_loop(const int *loop, int n, int loop_index, sl_mc_triangles *out)
{
    if (n == 3) {
        add_triangle(out, loop[0], loop[1], loop[2]);
        return;
    }
    for (int apex = 0; apex < n; apex++) {
        int ok = 1;
        for (int j = 2; j < n - 1 && ok; j++)
            ok = !(faces_of_point(loop[apex]) & faces_of_point(loop[(apex + j) % n]));
        if (!ok)
            continue;
        for (int j = 1; j + 1 < n; j++)
            add_triangle(out, loop[apex], loop[(apex + j) % n], loop[(apex + j + 1) % n]);
        return;
    }
    int centre = SL_MC_CENTROID_POINT(loop_index);
    out->centroids |= (uint8_t)(1u << loop_index);
    for (int j = 0; j < n; j++)
        add_triangle(out, centre, loop[j], loop[(j + 1) % n]);
}

void sl_mc_triangulate(const sl_mc_cell *cell, sl_mc_triangles *out)
{
    int next[SL_MC_MAX_POINTS];
    for (int i = 0; i < SL_MC_MAX_POINTS; i++)
        next[i] = -1;
    for (int f = 0; f < 6; f++)
        walk_face(cell, f, next);
    memset(out, 0, sizeof *out);
    uint8_t used[SL_MC_MAX_POINTS] = {0};
    int loops = 0;
    for (int start = 0; start < SL_MC_MAX_POINTS; start++) {
        if (next[start] < 0 || used[start])
            continue;
        int *loop = out->loop_points[loops], n = 0;
        for (int p = start; p >= 0 && !used[p] && n < SL_MC_MAX_POINTS; p = next[p]) {
            used[p] = 1;
            loop[n++] = p;
        }
        out->loop_sizes[loops] = (uint8_t)n;
        triangulate_loop(loop, n, loops, out);
        if (++loops == SL_MC_MAX_LOOPS)
            break;
    }
    out->loops = (uint8_t)loops;
}

static sl_mc_triangles uniform_table[256];
static pthread_once_t uniform_once = PTHREAD_ONCE_INIT;

static void build_uniform_table(void)
{
    for (int config = 0; config < 256; config++) {
        sl_mc_cell cell;
        memset(&cell, 0, sizeof cell);
        cell.inside = (uint8_t)config;
        sl_mc_triangulate(&cell, &uniform_table[config]);
    }
}

const sl_mc_triangles *sl_mc_uniform_table(void)
{
    pthread_once(&uniform_once, build_uniform_table);
    return uniform_table;
}
