/* The input surface cut along the leaf grid, for the leaves' quadrics (octree_vertices.c
 * has the method): each triangle is split at its edge midpoints until it spans at most two
 * cubes per axis, then clipped to each; each piece's plane, weighted by its area, goes
 * into the quadric of the loop of its leaf nearest to it. A point of a cloud is a piece
 * of its own: its tangent plane, weighted by the area a point stands for. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/merge/vertices_internal.h"

typedef struct piece {
    uint32_t slot;          /* leaf vertex slot, or UINT32_MAX for none */
    double w, point[3], n[3], rgba[4];
} piece;

static int nomem(sl_error *err)
{
    return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory placing vertices");
}

typedef struct cutter {
    const sl_octree *t;
    const level_slots *leaves;
    double n[3];            /* the triangle's unit normal */
    double corner_rgba[3][4];
    int coloured;
    double tri[3][3];       /* the original triangle, grid units (for colour barycentrics) */
    piece *out;             /* NULL: count only */
    uint64_t count;
} cutter;

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
    if (!c->out) {
        c->count++;
        return;
    }
    piece *p = &c->out[c->count++];
    for (int a = 0; a < 3; a++)
        cen[a] /= area;
    p->w = area;
    memcpy(p->n, c->n, sizeof p->n);
    p->slot = UINT32_MAX;
    memset(p->rgba, 0, sizeof p->rgba);
    if (c->coloured)
        piece_color(c, cen, p->rgba);
    uint32_t leaf = sl_octree_find(c->t, 0, x, y, z);
    if (leaf == SL_OCTREE_NONE)
        return; /* outside the sampled band: no cell draws it */
    double corner[3] = {(double)x, (double)y, (double)z};
    for (int a = 0; a < 3; a++)
        p->point[a] = cen[a] - corner[a];
    const level_slots *ls = c->leaves;
    uint32_t i = leaf - ls->node0;
    p->slot = ls->first[i] + (uint32_t)sl_vertices_nearest_loop(c->t, &c->t->nodes[leaf], p->point);
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
    if (!(len > 0) || !isfinite(len))
        return;
    if (!c->out) {
        c->count++;
        return;
    }
    piece *q = &c->out[c->count++];
    int64_t cube[3];
    for (int a = 0; a < 3; a++) {
        cube[a] = (int64_t)floor(p[a]);
        q->n[a] = n[a] / len;
    }
    q->w = s->point_area / (t->leaf_size * t->leaf_size);
    q->slot = UINT32_MAX;
    for (int k = 0; k < 4; k++)
        q->rgba[k] = c->coloured ? s->colors[4 * i + (uint64_t)k] : 0;
    uint32_t leaf = sl_octree_find(t, 0, cube[0], cube[1], cube[2]);
    if (leaf == SL_OCTREE_NONE)
        return;
    for (int a = 0; a < 3; a++)
        q->point[a] = p[a] - (double)cube[a];
    q->slot = c->leaves->first[leaf - c->leaves->node0] +
              (uint32_t)sl_vertices_nearest_loop(t, &t->nodes[leaf], q->point);
}

static void item_pieces(cutter *c, const sl_surface *s, uint64_t i)
{
    if (s->triangle_count)
        triangle_pieces(c, s, i);
    else
        point_piece(c, s, i);
}

/* Pieces made at once (96 bytes each): the pieces of the whole input (a few per triangle,
 * many for triangles far larger than the leaf) were the larger part of a qef run's extra
 * peak memory (docs/lod.md, Vertices from quadrics). */
#define PIECE_CHUNK 65536

/* The leaves' quadrics: pieces counted per item, then made in parallel, about PIECE_CHUNK
 * at a time (whole items), into per-item slots and summed in item order (the same sums in
 * the same order as all at once). */
int sl_vertices_leaf_quadrics(const sl_octree *t, const sl_surface *s, level_slots *leaves,
                              sl_error *err)
{
    uint64_t items = s->triangle_count ? s->triangle_count : s->point_count, capacity = 0;
    uint64_t *start = malloc((items + 1) * sizeof *start);
    piece *pieces = NULL;
    if (!start)
        return nomem(err);
    int coloured = s->colors && t->crossing_color;
#pragma omp parallel for schedule(dynamic, 1024)
    for (uint64_t i = 0; i < items; i++) {
        cutter c = {t, leaves, {0, 0, 0}, {{0}}, coloured, {{0}}, NULL, 0};
        item_pieces(&c, s, i);
        start[i + 1] = c.count;
    }
    start[0] = 0;
    for (uint64_t i = 0; i < items; i++)
        start[i + 1] += start[i];
    for (uint64_t from = 0, to; from < items; from = to) {
        for (to = from + 1; to < items && start[to + 1] - start[from] <= PIECE_CHUNK; to++)
            ;
        uint64_t n = start[to] - start[from];
        if (n > capacity) {
            free(pieces);
            capacity = n;
            pieces = malloc(capacity * sizeof *pieces);
            if (!pieces) {
                free(start);
                return nomem(err);
            }
        }
#pragma omp parallel for schedule(dynamic, 256)
        for (uint64_t i = from; i < to; i++) {
            cutter c = {t, leaves, {0, 0, 0}, {{0}}, coloured, {{0}},
                        pieces + (start[i] - start[from]), 0};
            item_pieces(&c, s, i);
        }
        for (uint64_t k = 0; k < n; k++) {
            const piece *p = &pieces[k];
            if (p->slot == UINT32_MAX)
                continue;
            sl_qef_add_plane(&leaves->qef[p->slot], p->n, p->point, p->w);
            if (coloured)
                for (int i = 0; i < 4; i++)
                    leaves->color[4 * (size_t)p->slot + (size_t)i] += p->w * p->rgba[i];
        }
    }
    free(pieces);
    free(start);
    return 0;
}
