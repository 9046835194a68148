/* The input surface cut along the leaf grid, for the leaves' quadrics (octree_vertices.c
 * has the method): each triangle is split at its edge midpoints until it spans at most two
 * cubes per axis, then clipped to each; each piece's plane, weighted by its area, goes
 * into the quadric of the loop of its leaf nearest to it. A point of a cloud is a piece
 * of its own: its tangent plane, weighted by the area a point stands for. One brick at a
 * time (octree_bricks.c): the pieces outside the brick's leaves are dropped, the others
 * summed as they are made, in item order. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/merge/vertices_internal.h"

typedef struct cutter {
    const sl_octree *t;
    level_slots *leaves;    /* the brick's leaves: pieces elsewhere are another brick's */
    double n[3];            /* the triangle's unit normal */
    double corner_rgba[3][4];
    int coloured;
    double tri[3][3];       /* the original triangle, grid units (for colour barycentrics) */
} cutter;

/* The brick's leaf at cube (x, y, z), or UINT32_MAX: a binary search in the brick's run of
 * the leaves' Morton order. */
static uint32_t brick_leaf(const cutter *c, int64_t x, int64_t y, int64_t z)
{
    if (x < 0 || y < 0 || z < 0 || x >= (1 << 20) || y >= (1 << 20) || z >= (1 << 20))
        return UINT32_MAX;
    uint64_t key = sl_morton3((uint32_t)x, (uint32_t)y, (uint32_t)z);
    const uint64_t *m = c->t->morton;
    uint32_t lo = c->leaves->node0, hi = lo + c->leaves->nodes;
    if (lo == hi || (m && (key < m[lo] || key > m[hi - 1])))
        return UINT32_MAX; /* another brick's: no search */
    uint32_t leaf = sl_octree_search(c->t, lo, hi, key);
    return leaf == SL_OCTREE_NONE ? UINT32_MAX : leaf;
}

/* A piece's plane (unit normal n through `point`, grid units from its leaf's corner),
 * weighted by w, into the quadric of the leaf's loop nearest to it. */
static void add_piece(const cutter *c, uint32_t leaf, const double point[3], const double n[3],
                      double w, const double rgba[4])
{
    level_slots *ls = c->leaves;
    uint32_t slot = ls->first[leaf - ls->node0] +
                    (uint32_t)sl_vertices_nearest_loop(c->t, &c->t->nodes[leaf], point);
    sl_qef_add_plane(&ls->qef[slot], n, point, w);
    if (c->coloured)
        for (int i = 0; i < 4; i++)
            ls->color[4 * (size_t)slot + (size_t)i] += w * rgba[i];
}

static int clip(double in[][3], int n, double out[][3], int axis, double v, int keep_below)
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        const double *p = in[i], *q = in[(i + 1) % n];
        double dp = keep_below ? v - p[axis] : p[axis] - v;
        double dq = keep_below ? v - q[axis] : q[axis] - v;
        if (dp >= 0)
            memcpy(out[m++], p, sizeof out[0]);
        if ((dp >= 0) != (dq >= 0)) {
            double s = dp / (dp - dq);
            for (int a = 0; a < 3; a++)
                out[m][a] = p[a] + s * (q[a] - p[a]);
            m++;
        }
    }
    return m;
}

/* Colour at p of the original triangle (barycentric), into rgba. */
static void piece_color(const cutter *c, const double p[3], double rgba[4])
{
    const double(*v)[3] = c->tri;
    double e0[3], e1[3], e2[3];
    for (int a = 0; a < 3; a++) {
        e0[a] = v[1][a] - v[0][a];
        e1[a] = v[2][a] - v[0][a];
        e2[a] = p[a] - v[0][a];
    }
    double d00 = e0[0] * e0[0] + e0[1] * e0[1] + e0[2] * e0[2];
    double d01 = e0[0] * e1[0] + e0[1] * e1[1] + e0[2] * e1[2];
    double d11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    double d20 = e2[0] * e0[0] + e2[1] * e0[1] + e2[2] * e0[2];
    double d21 = e2[0] * e1[0] + e2[1] * e1[1] + e2[2] * e1[2];
    double den = d00 * d11 - d01 * d01, b1 = 0, b2 = 0;
    if (den > 0) {
        b1 = (d11 * d20 - d01 * d21) / den;
        b2 = (d00 * d21 - d01 * d20) / den;
    }
    b1 = fmin(fmax(b1, 0), 1);
    b2 = fmin(fmax(b2, 0), 1 - b1);
    for (int k = 0; k < 4; k++)
        rgba[k] = (1 - b1 - b2) * c->corner_rgba[0][k] + b1 * c->corner_rgba[1][k] +
                  b2 * c->corner_rgba[2][k];
}

static void emit_piece(cutter *c, int64_t x, int64_t y, int64_t z, double poly[][3], int m)
{
    double area = 0, cen[3] = {0, 0, 0};
    for (int k = 1; k + 1 < m; k++) {
        double e1[3], e2[3];
        for (int a = 0; a < 3; a++) {
            e1[a] = poly[k][a] - poly[0][a];
            e2[a] = poly[k + 1][a] - poly[0][a];
        }
        double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
        double ar = 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        area += ar;
        for (int a = 0; a < 3; a++)
            cen[a] += ar * (poly[0][a] + poly[k][a] + poly[k + 1][a]) / 3;
    }
    if (!(area > 0))
        return;
    uint32_t leaf = brick_leaf(c, x, y, z);
    if (leaf == UINT32_MAX)
        return; /* outside the sampled band (no cell draws it), or another brick's */
    double corner[3] = {(double)x, (double)y, (double)z}, point[3], rgba[4] = {0, 0, 0, 0};
    for (int a = 0; a < 3; a++) {
        cen[a] /= area;
        point[a] = cen[a] - corner[a];
    }
    if (c->coloured)
        piece_color(c, cen, rgba);
    add_piece(c, leaf, point, c->n, area, rgba);
}

/* Splits a triangle until it spans at most two cubes per axis, then clips it to them. */
static void cut_triangle(cutter *c, const double v[3][3], int depth)
{
    double lo[3], hi[3];
    int big = 0;
    for (int a = 0; a < 3; a++) {
        lo[a] = fmin(v[0][a], fmin(v[1][a], v[2][a]));
        hi[a] = fmax(v[0][a], fmax(v[1][a], v[2][a]));
        big |= hi[a] - lo[a] > 1.0;
    }
    if (big && depth < 24) {
        double m[3][3];
        for (int a = 0; a < 3; a++) {
            m[0][a] = 0.5 * (v[0][a] + v[1][a]);
            m[1][a] = 0.5 * (v[1][a] + v[2][a]);
            m[2][a] = 0.5 * (v[2][a] + v[0][a]);
        }
        const double t0[3][3] = {{v[0][0], v[0][1], v[0][2]}, {m[0][0], m[0][1], m[0][2]},
                                 {m[2][0], m[2][1], m[2][2]}};
        const double t1[3][3] = {{m[0][0], m[0][1], m[0][2]}, {v[1][0], v[1][1], v[1][2]},
                                 {m[1][0], m[1][1], m[1][2]}};
        const double t2[3][3] = {{m[2][0], m[2][1], m[2][2]}, {m[1][0], m[1][1], m[1][2]},
                                 {v[2][0], v[2][1], v[2][2]}};
        cut_triangle(c, t0, depth + 1);
        cut_triangle(c, t1, depth + 1);
        cut_triangle(c, t2, depth + 1);
        cut_triangle(c, (const double(*)[3])m, depth + 1);
        return;
    }
    int64_t c0[3], c1[3];
    for (int a = 0; a < 3; a++) {
        c0[a] = (int64_t)floor(lo[a]);
        c1[a] = (int64_t)floor(hi[a]);
    }
    for (int64_t x = c0[0]; x <= c1[0]; x++)
        for (int64_t y = c0[1]; y <= c1[1]; y++)
            for (int64_t z = c0[2]; z <= c1[2]; z++) {
                double poly[16][3], tmp[16][3];
                int m = 3;
                memcpy(poly, v, 3 * sizeof poly[0]);
                const int64_t cube[3] = {x, y, z};
                for (int a = 0; a < 3 && m >= 3; a++) {
                    m = clip(poly, m, tmp, a, (double)cube[a], 0);
                    m = clip(tmp, m, poly, a, (double)cube[a] + 1, 1);
                }
                if (m >= 3)
                    emit_piece(c, x, y, z, poly, m);
            }
}

/* Pieces of triangle i into c (grid units). */
static void triangle_pieces(cutter *c, const sl_surface *s, uint64_t i)
{
    const sl_octree *t = c->t;
    double v[3][3];
    for (int k = 0; k < 3; k++) {
        uint32_t p = s->triangles[3 * i + (uint64_t)k];
        for (int a = 0; a < 3; a++)
            v[k][a] = (s->positions[3 * (size_t)p + a] - t->origin[a]) / t->leaf_size;
        if (c->coloured)
            for (int j = 0; j < 4; j++)
                c->corner_rgba[k][j] = s->colors[4 * (size_t)p + j];
    }
    double e1[3], e2[3];
    for (int a = 0; a < 3; a++) {
        e1[a] = v[1][a] - v[0][a];
        e2[a] = v[2][a] - v[0][a];
    }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0) || !isfinite(len))
        return;
    for (int a = 0; a < 3; a++)
        c->n[a] = n[a] / len;
    memcpy(c->tri, v, sizeof c->tri);
    cut_triangle(c, (const double(*)[3])v, 0);
}

/* The piece of point i of a cloud: its tangent plane, weighted by the area it stands for. */
static void point_piece(cutter *c, const sl_surface *s, uint64_t i)
{
    const sl_octree *t = c->t;
    double p[3], n[3];
    for (int a = 0; a < 3; a++) {
        p[a] = (s->positions[3 * i + (uint64_t)a] - t->origin[a]) / t->leaf_size;
        n[a] = s->normals[3 * i + (uint64_t)a];
    }
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0) || !isfinite(len) || !isfinite(p[0] + p[1] + p[2]))
        return;
    double cube[3], point[3], unit[3], rgba[4];
    for (int a = 0; a < 3; a++) {
        cube[a] = fmax(-1, fmin(floor(p[a]), 1 << 20)); /* out of range: no leaf */
        point[a] = p[a] - cube[a];
        unit[a] = n[a] / len;
    }
    uint32_t leaf = brick_leaf(c, (int64_t)cube[0], (int64_t)cube[1], (int64_t)cube[2]);
    if (leaf == UINT32_MAX)
        return;
    for (int k = 0; k < 4; k++)
        rgba[k] = c->coloured ? s->colors[4 * i + (uint64_t)k] : 0;
    add_piece(c, leaf, point, unit, s->point_area / (t->leaf_size * t->leaf_size), rgba);
}

void sl_vertices_leaf_quadrics(const sl_octree *t, const sl_surface *s, level_slots *leaves,
                               const uint32_t *items, uint64_t count)
{
    cutter c = {t, leaves, {0, 0, 0}, {{0}}, s->colors && t->crossing_color, {{0}}};
    for (uint64_t k = 0; k < count; k++) {
        uint64_t i = items ? items[k] : k;
        if (s->triangle_count)
            triangle_pieces(&c, s, i);
        else
            point_piece(&c, s, i);
    }
}
