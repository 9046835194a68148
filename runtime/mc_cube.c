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

/* Per face, what a walk needs (built once from the functions above): its corners and
 * edges, and the half-edge point ids at the start and the end of each boundary edge. Per
 * point id, the faces it lies on. */
typedef struct face_tables {
    uint8_t corners[6][4], edges[6][4], half_start[6][4], half_end[6][4];
    uint8_t point_faces[SL_MC_MAX_POINTS];
} face_tables;

static face_tables ft;
static pthread_once_t ft_once = PTHREAD_ONCE_INIT;

/* Half of edge e that touches corner `corner`. */
static int half_at(int e, int corner)
{
    return SL_MC_HALF_POINT(e, corner == sl_mc_edge_c0(e) ? 0 : 1);
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

static void build_face_tables(void)
{
    for (int f = 0; f < 6; f++) {
        int corners[4], edges[4];
        sl_mc_face_corners(f, corners);
        sl_mc_face_edges(f, edges);
        for (int k = 0; k < 4; k++) {
            ft.corners[f][k] = (uint8_t)corners[k];
            ft.edges[f][k] = (uint8_t)edges[k];
            ft.half_start[f][k] = (uint8_t)half_at(edges[k], corners[k]);
            ft.half_end[f][k] = (uint8_t)half_at(edges[k], corners[(k + 1) % 4]);
        }
    }
    for (int p = 0; p < SL_MC_MAX_POINTS; p++)
        ft.point_faces[p] = (uint8_t)faces_of_point(p);
}

/* A walk around one face or sub-face: sample signs (bit i) and the point id of the piece
 * that leaves each sample (towards the next one). */
typedef struct walk {
    int count;
    unsigned inside;
    uint8_t piece[8];
} walk;

static inline void walk_push(walk *w, unsigned inside, int piece)
{
    w->inside |= (inside & 1u) << w->count;
    w->piece[w->count++] = (uint8_t)piece;
}

/* The segments found so far: next[p] for every point p with bit p of `from` set. */
typedef struct links {
    int8_t next[SL_MC_MAX_POINTS];
    uint64_t from;
} links;

static void pair_runs(const walk *w, links *l)
{
    int n = w->count;
    unsigned in = w->inside, all = (1u << n) - 1u;
    if (in == 0 || in == all)
        return; /* one sign all round: no crossing */
    /* Sample i is followed by sample i + 1 (mod n): entries are pieces from an outside to
     * an inside sample, exits the reverse. From the first outside sample on, each exit
     * closes the run the last entry opened. */
    unsigned after = (in >> 1 | in << (n - 1)) & all;
    unsigned entries = ~in & after & all, both = entries | (in & ~after);
    int start = __builtin_ctz(~in & all), entry = -1;
    for (unsigned r = (both >> start | both << (n - start)) & all; r; r &= r - 1u) {
        int i = __builtin_ctz(r) + start;
        i -= i >= n ? n : 0;
        if (entries >> i & 1) {
            entry = w->piece[i];
        } else {
            l->next[w->piece[i]] = (int8_t)entry;
            l->from |= 1ull << w->piece[i];
        }
    }
}

static void walk_face(const sl_mc_cell *cell, int f, links *l)
{
    const uint8_t *corners = ft.corners[f], *edges = ft.edges[f];
    if (!(cell->split_faces >> f & 1)) {
        walk w = {0, 0, {0}};
        for (int k = 0; k < 4; k++) {
            int c = corners[k], e = edges[k];
            if (cell->split_edges >> e & 1) {
                walk_push(&w, cell->inside >> c, ft.half_start[f][k]);
                walk_push(&w, cell->mid_inside >> e, ft.half_end[f][k]);
            } else {
                walk_push(&w, cell->inside >> c, SL_MC_EDGE_POINT(e));
            }
        }
        pair_runs(&w, l);
        return;
    }
    unsigned centre = cell->centre_inside >> f & 1;
    for (int k = 0; k < 4; k++) { /* the sub-face at corner k */
        int c = corners[k], e_out = edges[k], e_in = edges[(k + 3) % 4];
        walk w = {0, 0, {0}};
        walk_push(&w, cell->inside >> c, ft.half_start[f][k]);
        walk_push(&w, cell->mid_inside >> e_out, SL_MC_SPOKE_POINT(f, k));
        walk_push(&w, centre, SL_MC_SPOKE_POINT(f, (k + 3) % 4));
        walk_push(&w, cell->mid_inside >> e_in, ft.half_end[f][(k + 3) % 4]);
        pair_runs(&w, l);
    }
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
        unsigned faces = ft.point_faces[loop[apex]];
        int ok = 1;
        for (int j = 2, q = apex + 2 < n ? apex + 2 : apex + 2 - n; j < n - 1 && ok; j++) {
            ok = !(faces & ft.point_faces[loop[q]]);
            q = q + 1 == n ? 0 : q + 1;
        }
        if (!ok)
            continue;
        for (int j = 1, q = apex + 1 < n ? apex + 1 : 0; j + 1 < n; j++) {
            int r = q + 1 == n ? 0 : q + 1;
            add_triangle(out, loop[apex], loop[q], loop[r]);
            q = r;
        }
        return;
    }
    int centre = SL_MC_CENTROID_POINT(loop_index);
    out->centroids |= (uint8_t)(1u << loop_index);
    for (int j = 0; j < n; j++)
        add_triangle(out, centre, loop[j], loop[(j + 1) % n]);
}

void sl_mc_triangulate(const sl_mc_cell *cell, sl_mc_triangles *out)
{
    pthread_once(&ft_once, build_face_tables);
    links l;
    l.from = 0;
    for (int f = 0; f < 6; f++)
        walk_face(cell, f, &l);
    /* Only the counts are reset: the arrays are valid up to them. */
    out->count = 0;
    out->loops = 0;
    out->centroids = 0;
    /* Loops start at the smallest point id with a segment not yet in one; a point without
     * a segment of its own ends its loop. */
    uint64_t used = 0;
    int loops = 0;
    while (l.from & ~used) {
        int start = __builtin_ctzll(l.from & ~used);
        int *loop = out->loop_points[loops], n = 0;
        for (int p = start; p >= 0 && !(used >> p & 1) && n < SL_MC_MAX_POINTS;
             p = (l.from >> p & 1) ? l.next[p] : -1) {
            used |= 1ull << p;
            loop[n++] = p;
        }
        out->loop_sizes[loops] = (uint8_t)n;
        triangulate_loop(loop, n, loops, out);
        if (++loops == SL_MC_MAX_LOOPS)
            break;
    }
    out->loops = (uint8_t)loops;
}

/* The face region the segment from point p to point q (in loop order) lies in: its face,
 * or for a split face its sub-face (6 + 4 f + k, the sub-face at corner k); -1 when they
 * share no face. The two halves of one split edge lie on both of its faces: the segment
 * between them is on the face that walks the edge from p to q when the edge's midpoint is
 * outside (pair_runs links the exit before the midpoint to the entry after it), from q to
 * p when it is inside. Where levels meet (the edge's midpoint inside, its corners outside,
 * its other face split), leaving it at -1 missed a loop that runs along the edge and
 * crosses the same face once more: the same-level neighbour across that face draws the
 * same two segments, and the two cells' dual vertices were joined by an edge of four
 * triangles (docs/lod.md, Vertices from quadrics). */
static int segment_region(const sl_mc_cell *cell, int p, int q)
{
    unsigned common = ft.point_faces[p] & ft.point_faces[q];
    if (__builtin_popcount(common) == 2) {
        for (unsigned r = common; r; r &= r - 1u) {
            int f = __builtin_ctz(r);
            for (int k = 0; k < 4; k++) {
                int out = !(cell->mid_inside >> ft.edges[f][k] & 1), s = ft.half_start[f][k],
                    e = ft.half_end[f][k];
                if ((out && s == p && e == q) || (!out && e == p && s == q))
                    return cell->split_faces >> f & 1 ? -1 : f;
            }
        }
        return -1;
    }
    if (__builtin_popcount(common) != 1)
        return -1;
    int f = __builtin_ctz(common);
    if (!(cell->split_faces >> f & 1))
        return f;
    for (int k = 0; k < 4; k++) {
        const int pts[4] = {ft.half_start[f][k], SL_MC_SPOKE_POINT(f, k),
                            SL_MC_SPOKE_POINT(f, (k + 3) % 4), ft.half_end[f][(k + 3) % 4]};
        int has_p = 0, has_q = 0;
        for (int i = 0; i < 4; i++) {
            has_p |= pts[i] == p;
            has_q |= pts[i] == q;
        }
        if (has_p && has_q)
            return 6 + 4 * f + k;
    }
    return -1;
}

void sl_mc_split_double_passes(const sl_mc_cell *cell, sl_mc_triangles *tri)
{
    pthread_once(&ft_once, build_face_tables);
    for (int l = 0; l < tri->loops; l++) {
        int n = tri->loop_sizes[l], *x = tri->loop_points[l], i = -1, j = -1;
        int region[12 + 24];
        for (int a = 0; a < n; a++)
            region[a] = segment_region(cell, x[a], x[(a + 1) % n]);
        for (int a = 0; a < n && j < 0; a++)
            for (int b = a + 2; b < n && j < 0; b++)
                if (region[a] >= 0 && region[a] == region[b]) {
                    i = a;
                    j = b;
                }
        if (j < 0 || tri->loops == SL_MC_MAX_LOOPS)
            continue;
        /* x[i+1] .. x[j+1] keeps segment j; x[j+1] .. x[i+1] (around) keeps segment i. */
        int first[12 + 24], second[12 + 24], n1 = 0, n2 = 0;
        for (int a = i + 1; a <= j + 1; a++)
            first[n1++] = x[a % n];
        for (int a = j + 1; a <= i + 1 + n; a++)
            second[n2++] = x[a % n];
        memcpy(x, first, (size_t)n1 * sizeof *x);
        tri->loop_sizes[l] = (uint8_t)n1;
        memcpy(tri->loop_points[tri->loops], second, (size_t)n2 * sizeof *x);
        tri->loop_sizes[tri->loops++] = (uint8_t)n2;
        l--; /* the shortened loop may pass a face twice yet */
    }
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
