/* Triangulating a raw range scan along its scanner grid (paper 1 section 4: range data
 * become a mesh whose triangles give the normals; Turk & Levoy, "Zippered Polygon Meshes
 * from Range Images", SIGGRAPH 1994, section 3: a range image is triangulated cell by
 * cell, and triangles with an edge much longer than the sample spacing are discarded
 * because they span depth discontinuities, not surface).
 *
 * Each 2x2 block of grid cells with four valid samples gives two triangles split along
 * the shorter diagonal; with three valid samples, one triangle. Triangles whose longest
 * edge exceeds grid_max_edge = factor x (median distance between grid neighbours) are
 * skipped. All triangles share one winding in grid space; the whole set is then flipped
 * if needed so that the area-weighted normals face the scanner: towards the viewpoint the
 * file states, else towards +z (Cyberware and Stanford range scans are stored in scanner
 * coordinates with the sensor on the +z side; checked on bunny_range, docs/range-stage.md).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/range/range_internal.h"

typedef struct grid_ctx {
    const sl_mesh *mesh;
    double max_edge2;
    uint32_t *out;   /* NULL: count only */
    uint64_t emitted, too_long;
} grid_ctx;

static double dist2(const sl_mesh *m, uint32_t a, uint32_t b)
{
    const float *p = m->positions + 3 * (uint64_t)a, *q = m->positions + 3 * (uint64_t)b;
    double d = 0;
    for (int k = 0; k < 3; k++)
        d += ((double)p[k] - q[k]) * ((double)p[k] - q[k]);
    return d;
}

static void emit(grid_ctx *g, uint32_t a, uint32_t b, uint32_t c)
{
    double longest = dist2(g->mesh, a, b);
    double e = dist2(g->mesh, b, c);
    if (e > longest)
        longest = e;
    e = dist2(g->mesh, c, a);
    if (e > longest)
        longest = e;
    if (!(longest <= g->max_edge2)) {
        g->too_long++;
        return;
    }
    if (g->out) {
        g->out[3 * g->emitted] = a;
        g->out[3 * g->emitted + 1] = b;
        g->out[3 * g->emitted + 2] = c;
    }
    g->emitted++;
}

/* Grid sample -> vertex, or RANGE_NONE when empty or non-finite. */
static uint32_t sample(const sl_mesh *m, uint64_t row, uint64_t col)
{
    int64_t v = m->grid_index[row * m->grid_cols + col];
    if (v < 0)
        return RANGE_NONE;
    const float *p = m->positions + 3 * (uint64_t)v;
    return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]) ? (uint32_t)v : RANGE_NONE;
}

/* Corners a (r, c), b (r, c+1), d (r+1, c), e (r+1, c+1); every triangle below is
 * counter-clockwise in (col, row) coordinates. */
static void triangulate_cell(grid_ctx *g, uint64_t r, uint64_t c)
{
    const sl_mesh *m = g->mesh;
    uint32_t a = sample(m, r, c), b = sample(m, r, c + 1);
    uint32_t d = sample(m, r + 1, c), e = sample(m, r + 1, c + 1);
    int valid = (a != RANGE_NONE) + (b != RANGE_NONE) + (d != RANGE_NONE) + (e != RANGE_NONE);
    if (valid < 3)
        return;
    if (valid == 4) {
        if (dist2(m, a, e) <= dist2(m, b, d)) {
            emit(g, a, b, e);
            emit(g, a, e, d);
        } else {
            emit(g, a, b, d);
            emit(g, b, e, d);
        }
    } else if (e == RANGE_NONE) {
        emit(g, a, b, d);
    } else if (d == RANGE_NONE) {
        emit(g, a, b, e);
    } else if (b == RANGE_NONE) {
        emit(g, a, e, d);
    } else {
        emit(g, b, e, d);
    }
}

static int compare_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Median distance between horizontally or vertically adjacent valid samples; 0 if none. */
static int median_neighbour_distance(const sl_mesh *m, double *median, sl_error *err)
{
    uint64_t rows = m->grid_rows, cols = m->grid_cols, n = 0;
    double *d = malloc((2 * rows * cols + 1) * sizeof *d);
    if (!d)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "range grid: out of memory");
    for (uint64_t r = 0; r < rows; r++)
        for (uint64_t c = 0; c < cols; c++) {
            uint32_t a = sample(m, r, c);
            if (a == RANGE_NONE)
                continue;
            uint32_t right = c + 1 < cols ? sample(m, r, c + 1) : RANGE_NONE;
            uint32_t down = r + 1 < rows ? sample(m, r + 1, c) : RANGE_NONE;
            if (right != RANGE_NONE)
                d[n++] = sqrt(dist2(m, a, right));
            if (down != RANGE_NONE)
                d[n++] = sqrt(dist2(m, a, down));
        }
    qsort(d, n, sizeof *d, compare_double);
    *median = n ? d[n / 2] : 0.0;
    free(d);
    return SL_OK;
}

/* Flips every triangle when their area-weighted normals face away from the scanner. */
static int orient_to_scanner(const sl_mesh *m, uint32_t *tris, uint64_t count)
{
    double vote = 0;
    for (uint64_t t = 0; t < count; t++) {
        const float *a = m->positions + 3 * (uint64_t)tris[3 * t];
        const float *b = m->positions + 3 * (uint64_t)tris[3 * t + 1];
        const float *c = m->positions + 3 * (uint64_t)tris[3 * t + 2];
        double u[3], w[3], n[3], view[3] = {0, 0, 1};
        for (int k = 0; k < 3; k++) {
            u[k] = (double)b[k] - a[k];
            w[k] = (double)c[k] - a[k];
            if (m->has_viewpoint)
                view[k] = m->viewpoint[k] - ((double)a[k] + b[k] + c[k]) / 3.0;
        }
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        double len = sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
        if (len > 0)
            vote += (n[0] * view[0] + n[1] * view[1] + n[2] * view[2]) / len;
    }
    if (vote >= 0)
        return 0;
    for (uint64_t t = 0; t < count; t++) {
        uint32_t tmp = tris[3 * t + 1];
        tris[3 * t + 1] = tris[3 * t + 2];
        tris[3 * t + 2] = tmp;
    }
    return 1;
}

int range_grid_triangulate(sl_mesh *mesh, double max_edge_factor, sl_range_counts *counts,
                           sl_progress *progress, sl_error *err)
{
    uint64_t rows = mesh->grid_rows, cols = mesh->grid_cols;
    for (uint64_t i = 0; i < rows * cols; i++)
        if (mesh->grid_index[i] >= (int64_t)mesh->vertex_count)
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "range_grid cell %llu names vertex %lld of %llu",
                                (unsigned long long)i, (long long)mesh->grid_index[i],
                                (unsigned long long)mesh->vertex_count);
    double median = 0.0;
    int rc = median_neighbour_distance(mesh, &median, err);
    if (rc != SL_OK)
        return rc;
    grid_ctx g = {mesh, (max_edge_factor * median) * (max_edge_factor * median), NULL, 0, 0};
    counts->grid_max_edge = max_edge_factor * median;
    for (int pass = 0; pass < 2; pass++) {
        g.emitted = g.too_long = 0;
        for (uint64_t r = 0; r + 1 < rows; r++) {
            if ((r & 63) == 0 && sl_progress_step(progress, "range grid", (double)r / rows))
                return SL_E_INTERRUPTED;
            for (uint64_t c = 0; c + 1 < cols; c++)
                triangulate_cell(&g, r, c);
        }
        if (pass == 0) {
            g.out = malloc((g.emitted ? g.emitted : 1) * 3 * sizeof *g.out);
            if (!g.out)
                return sl_error_set(err, SL_E_NOMEM, 0, NULL,
                                    "range grid: out of memory (%llu triangles)",
                                    (unsigned long long)g.emitted);
        }
    }
    counts->grid_flipped = orient_to_scanner(mesh, g.out, g.emitted);
    counts->grid_triangles = g.emitted;
    counts->grid_long_edges = g.too_long;
    free(mesh->triangles);
    free(mesh->face_texcoords);
    mesh->face_texcoords = NULL;
    mesh->triangles = g.out;
    mesh->triangle_count = g.emitted;
    return SL_OK;
}
