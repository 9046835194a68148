/* One segment: vertex selection (paper 3, section 3.3) and retriangulation (3.4).
 *
 * The patch is projected along the segment's normal (segment_model.c says why); its
 * polygon is the segment's loops with the vertices trimming kept. Which interior vertices
 * stay is the rule's:
 *  - error (default): greedy insertion, as Garland and Heckbert do for height fields
 *    ("Fast polygonal approximation of terrains and height fields", 1995): triangulate
 *    the polygon alone, then in rounds put back, in every triangle, the interior vertex
 *    farthest from that triangle's plane if it is farther than max_error, until none is.
 *    The vertices never put back are the removed ones, each within max_error of the
 *    triangle over it: the paper's "vertices near the plane go", the plane being the patch.
 *  - near / paper: equations 3-8 once, against the least-squares plane of the segment's
 *    vertices (TLS, geometry/plane_fit.h), then one triangulation.
 * Every triangulation is the constrained Delaunay triangulation of geometry/cdt.h. A new
 * triangle whose normal is farther than max_normal_deviation from the input normal at one
 * of its corners (the area-weighted normal of the segment's input triangles there) gets
 * its farthest vertex back; if it has none, the patch is refused.
 *
 * Candidates are found in triangles by rasterising each over a grid of the candidates
 * (about two a cell): a round costs about the cells plus the edges' lengths in cells.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/cdt.h"
#include "geometry/plane_fit.h"
#include "geometry/predicates.h"
#include "geometry/vec3.h"
#include "stages/segment/segment_internal.h"

enum slot_role { ROLE_DROPPED = 0, ROLE_LOOP = 1, ROLE_CANDIDATE = 2, ROLE_INSERTED = 3 };

struct seg_scratch {
    uint32_t *local;   /* vertex_count: slot + 1 in the current segment, 0 = none */
    uint32_t cap;      /* slots */
    uint32_t *vertex;  /* slot -> global vertex */
    double *uv, *h, *normal; /* per slot: 2, 1, 3 */
    double *pos;       /* per slot: 3, world, relative to the frame origin */
    uint8_t *role;
    uint32_t *cdt_index; /* slot -> CDT point index, or SEG_NONE */
    uint32_t *located_in; /* candidate slot -> triangle this round, SEG_NONE */
    double *error;        /* candidate slot -> distance to that triangle's plane */
    uint32_t *cands, *cell_start, *cell_items; /* grid of candidates */
    uint32_t loops_cap, points_cap, tri_cap;
    uint32_t *loop_start, *loop_points, *point_slot;
    double *points;
    uint32_t *best;   /* per triangle: worst candidate slot */
    double *tri_normal; /* per triangle: 3 */
    double *tri_sum;    /* per triangle: sum of squared distances of its candidates */
    uint32_t *cand_tri; /* per candidate (in cands order): its triangle */
    seg_refine *refine;
    uint8_t *bad;     /* per triangle: normal deviation too large */
};

seg_scratch *seg_scratch_new(uint32_t vertex_count)
{
    seg_scratch *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    s->local = calloc(vertex_count ? vertex_count : 1, sizeof *s->local);
    if (!s->local) {
        free(s);
        return NULL;
    }
    return s;
}

void seg_scratch_free(seg_scratch *s)
{
    if (!s)
        return;
    free(s->local);
    free(s->vertex);
    free(s->uv);
    free(s->h);
    free(s->normal);
    free(s->pos);
    free(s->role);
    free(s->cdt_index);
    free(s->located_in);
    free(s->error);
    free(s->cands);
    free(s->cell_start);
    free(s->cell_items);
    free(s->loop_start);
    free(s->loop_points);
    free(s->point_slot);
    free(s->points);
    free(s->best);
    free(s->tri_normal);
    free(s->tri_sum);
    free(s->cand_tri);
    seg_refine_free(s->refine);
    free(s->bad);
    free(s);
}

#define GROW(ptr, n) ((ptr) = realloc((ptr), ((size_t)(n) > 0 ? (size_t)(n) : 1) * sizeof *(ptr)))

static int reserve_slots(seg_scratch *s, uint32_t n)
{
    if (n <= s->cap)
        return 0;
    uint32_t cap = s->cap ? s->cap : 64;
    while (cap < n)
        cap = cap > UINT32_MAX / 2 ? n : 2 * cap;
    if (!GROW(s->vertex, cap) || !GROW(s->uv, 2 * (size_t)cap) || !GROW(s->h, cap) ||
        !GROW(s->normal, 3 * (size_t)cap) || !GROW(s->pos, 3 * (size_t)cap) ||
        !GROW(s->role, cap) || !GROW(s->cdt_index, cap) || !GROW(s->located_in, cap) ||
        !GROW(s->error, cap) || !GROW(s->cands, cap) || !GROW(s->cell_items, cap) ||
        !GROW(s->cand_tri, cap) ||
        !GROW(s->point_slot, cap) || !GROW(s->points, 2 * (size_t)cap))
        return -1;
    s->cap = cap;
    return 0;
}

static int reserve_triangles(seg_scratch *s, uint32_t n)
{
    if (n <= s->tri_cap)
        return 0;
    uint32_t cap = s->tri_cap ? s->tri_cap : 64;
    while (cap < n)
        cap = cap > UINT32_MAX / 2 ? n : 2 * cap;
    if (!GROW(s->best, cap) || !GROW(s->tri_normal, 3 * (size_t)cap) || !GROW(s->bad, cap) ||
        !GROW(s->tri_sum, cap))
        return -1;
    s->tri_cap = cap;
    return 0;
}

typedef struct patch {
    const sl_segment_model *m;
    uint32_t k;
    const seg_frame *f;
    seg_scratch *s;
    uint32_t slots, candidates, loop_slots;
    uint32_t loop_count, loop_entries;
    uint32_t problem[4];
} patch;

static uint32_t slot_of(patch *p, uint32_t v)
{
    seg_scratch *s = p->s;
    if (s->local[v])
        return s->local[v] - 1;
    uint32_t i = p->slots++;
    s->local[v] = i + 1;
    s->vertex[i] = v;
    const float *q = p->m->positions + 3 * (uint64_t)v;
    double d[3];
    for (int j = 0; j < 3; j++)
        d[j] = (double)q[j] - p->f->origin[j];
    memcpy(s->pos + 3 * (size_t)i, d, sizeof d);
    s->uv[2 * (size_t)i] = d[0] * p->f->u[0] + d[1] * p->f->u[1] + d[2] * p->f->u[2];
    s->uv[2 * (size_t)i + 1] = d[0] * p->f->v[0] + d[1] * p->f->v[1] + d[2] * p->f->v[2];
    s->h[i] = d[0] * p->f->normal[0] + d[1] * p->f->normal[1] + d[2] * p->f->normal[2];
    s->normal[3 * (size_t)i] = s->normal[3 * (size_t)i + 1] = s->normal[3 * (size_t)i + 2] = 0;
    s->role[i] = ROLE_DROPPED;
    s->cdt_index[i] = SEG_NONE;
    return i;
}

/* Slots for every vertex of the segment, their input normals, roles, and the loops as
 * CDT input over the loop slots. Returns 0 or -1 (out of memory). */
static int gather(patch *p, const uint8_t *kept)
{
    const sl_segment_model *m = p->m;
    seg_scratch *s = p->s;
    uint32_t b = m->seg_tri_start[p->k], e = m->seg_tri_start[p->k + 1];
    if (reserve_slots(s, 3 * (e - b)))
        return -1;
    p->slots = 0;
    for (uint32_t i = b; i < e; i++) {
        const uint32_t *c = m->triangles + 3 * (uint64_t)m->seg_tris[i];
        for (int q = 0; q < 3; q++)
            slot_of(p, c[q]);
    }
    p->candidates = 0;
    for (uint32_t i = 0; i < p->slots; i++) {
        /* the input's normal there, what a new triangle is checked against */
        memcpy(s->normal + 3 * (size_t)i, m->vertex_normal + 3 * (size_t)s->vertex[i],
               3 * sizeof *s->normal);
        if (m->loops.vertex_kind[s->vertex[i]] == SL_SEGMENT_VERTEX_INTERIOR) {
            s->role[i] = ROLE_CANDIDATE;
            s->cands[p->candidates++] = i;
        }
    }
    /* loops: kept vertices in order; CDT point indices for loop slots in first-seen order */
    uint32_t l0 = m->loops.segment_loop_start[p->k], l1 = m->loops.segment_loop_start[p->k + 1];
    uint32_t entries = m->loops.loop_start[l1] - m->loops.loop_start[l0];
    if (p->s->loops_cap < entries + (l1 - l0) + 1) {
        uint32_t cap = entries + (l1 - l0) + 1;
        if (!GROW(s->loop_start, cap) || !GROW(s->loop_points, cap))
            return -1;
        s->loops_cap = cap;
    }
    p->loop_count = 0;
    p->loop_entries = 0;
    p->loop_slots = 0;
    for (uint32_t l = l0; l < l1; l++) {
        s->loop_start[p->loop_count++] = p->loop_entries;
        for (uint32_t i = m->loops.loop_start[l]; i < m->loops.loop_start[l + 1]; i++) {
            uint32_t v = m->adj.triangles[m->loops.halfedges[i]];
            if (!m->fixed[v] && !kept[v])
                continue;
            uint32_t sl = s->local[v] - 1;
            if (s->cdt_index[sl] == SEG_NONE) {
                s->cdt_index[sl] = p->loop_slots;
                s->point_slot[p->loop_slots++] = sl;
                s->role[sl] = ROLE_LOOP;
            }
            s->loop_points[p->loop_entries++] = s->cdt_index[sl];
        }
    }
    s->loop_start[p->loop_count] = p->loop_entries;
    /* A fixed vertex inside the segment (a non-manifold vertex whose fan here is all in
     * this segment) is on no loop but must stay: an interior point from the start. */
    for (uint32_t i = 0; i < p->slots; i++)
        if (s->role[i] == ROLE_DROPPED && m->fixed[s->vertex[i]]) {
            s->role[i] = ROLE_LOOP;
            s->cdt_index[i] = p->loop_slots;
            s->point_slot[p->loop_slots++] = i;
        }
    return 0;
}

static void release_slots(patch *p)
{
    for (uint32_t i = 0; i < p->slots; i++)
        p->s->local[p->s->vertex[i]] = 0;
}

/* --- the candidate grid ---------------------------------------------------------------- */

typedef struct grid {
    double lo[2], cell;
    uint32_t nx, ny;
} grid;

static int build_grid(patch *p, grid *g)
{
    seg_scratch *s = p->s;
    uint32_t n = p->candidates;
    g->lo[0] = g->lo[1] = INFINITY;
    double hi[2] = {-INFINITY, -INFINITY};
    for (uint32_t i = 0; i < n; i++)
        for (int j = 0; j < 2; j++) {
            double x = s->uv[2 * (size_t)s->cands[i] + j];
            g->lo[j] = x < g->lo[j] ? x : g->lo[j];
            hi[j] = x > hi[j] ? x : hi[j];
        }
    double w = hi[0] - g->lo[0], h = hi[1] - g->lo[1];
    double area = w * h > 0 ? w * h : (w > h ? w : h) * (w > h ? w : h);
    g->cell = area > 0 ? sqrt(2.0 * area / n) : 1.0;
    if (!(g->cell > 0) || !isfinite(g->cell))
        g->cell = 1.0;
    g->nx = (uint32_t)fmin(w / g->cell + 1, 65535);
    g->ny = (uint32_t)fmin(h / g->cell + 1, 65535);
    uint64_t cells = (uint64_t)g->nx * g->ny;
    if (cells > 4 * (uint64_t)n + 16) { /* a degenerate spread: fewer, larger cells */
        g->cell *= sqrt((double)cells / (4.0 * n + 16));
        g->nx = (uint32_t)fmin(w / g->cell + 1, 65535);
        g->ny = (uint32_t)fmin(h / g->cell + 1, 65535);
        cells = (uint64_t)g->nx * g->ny;
    }
    free(s->cell_start);
    s->cell_start = calloc(cells + 2, sizeof *s->cell_start);
    if (!s->cell_start)
        return -1;
    for (uint32_t i = 0; i < n; i++) {
        const double *q = s->uv + 2 * (size_t)s->cands[i];
        uint32_t cx = (uint32_t)fmin((q[0] - g->lo[0]) / g->cell, g->nx - 1);
        uint32_t cy = (uint32_t)fmin((q[1] - g->lo[1]) / g->cell, g->ny - 1);
        s->cell_start[(uint64_t)cy * g->nx + cx + 2]++;
    }
    for (uint64_t c = 0; c < cells; c++)
        s->cell_start[c + 2] += s->cell_start[c + 1];
    for (uint32_t i = 0; i < n; i++) {
        const double *q = s->uv + 2 * (size_t)s->cands[i];
        uint32_t cx = (uint32_t)fmin((q[0] - g->lo[0]) / g->cell, g->nx - 1);
        uint32_t cy = (uint32_t)fmin((q[1] - g->lo[1]) / g->cell, g->ny - 1);
        s->cell_items[s->cell_start[(uint64_t)cy * g->nx + cx + 1]++] = s->cands[i];
    }
    return 0;
}

static int32_t cell_coord(const grid *g, double x, int axis, uint32_t n)
{
    double c = floor((x - g->lo[axis]) / g->cell);
    return (int32_t)(c < 0 ? 0 : c > n - 1 ? n - 1 : c);
}

/* Calls visit(slot) for the candidates in the cells triangle a-b-c covers (conservatively:
 * each row band's x extent, from the edges at the band's bounds and the corners in it). */
static void raster(const grid *g, const seg_scratch *s, const double *a, const double *b,
                   const double *c, void (*visit)(void *, uint32_t), void *ctx)
{
    const double *v[3] = {a, b, c};
    double ylo = fmin(a[1], fmin(b[1], c[1])), yhi = fmax(a[1], fmax(b[1], c[1]));
    int32_t r0 = cell_coord(g, ylo, 1, g->ny), r1 = cell_coord(g, yhi, 1, g->ny);
    for (int32_t r = r0; r <= r1; r++) {
        double y0 = g->lo[1] + r * g->cell, y1 = y0 + g->cell;
        if (r == r0)
            y0 = ylo;
        if (r == r1)
            y1 = yhi;
        double xlo = INFINITY, xhi = -INFINITY;
        for (int i = 0; i < 3; i++) {
            const double *p = v[i], *q = v[(i + 1) % 3];
            if (p[1] >= y0 && p[1] <= y1) {
                xlo = fmin(xlo, p[0]);
                xhi = fmax(xhi, p[0]);
            }
            double ey[2] = {y0, y1};
            for (int j = 0; j < 2; j++)
                if ((p[1] - ey[j]) * (q[1] - ey[j]) <= 0 && p[1] != q[1]) {
                    double t = (ey[j] - p[1]) / (q[1] - p[1]);
                    double x = p[0] + t * (q[0] - p[0]);
                    xlo = fmin(xlo, x);
                    xhi = fmax(xhi, x);
                }
        }
        if (!(xlo <= xhi))
            continue;
        double margin = 1e-9 * (g->cell + fabs(xlo) + fabs(xhi));
        int32_t c0 = cell_coord(g, xlo - margin, 0, g->nx), c1 = cell_coord(g, xhi + margin, 0, g->nx);
        for (int32_t col = c0; col <= c1; col++) {
            uint64_t cell = (uint64_t)r * g->nx + col;
            for (uint32_t i = s->cell_start[cell]; i < s->cell_start[cell + 1]; i++)
                visit(ctx, s->cell_items[i]);
        }
    }
}

/* --- rounds of triangulation ----------------------------------------------------------- */

typedef struct locate_ctx {
    patch *p;
    uint32_t tri;
    const double *a, *b, *c; /* uv */
    const double *pa;        /* world, relative: the triangle's first corner */
    const double *n;         /* unit normal of the lifted triangle */
} locate_ctx;

static void locate_visit(void *vctx, uint32_t slot)
{
    locate_ctx *x = vctx;
    seg_scratch *s = x->p->s;
    if (s->role[slot] != ROLE_CANDIDATE || s->located_in[slot] != SEG_NONE)
        return;
    const double *q = s->uv + 2 * (size_t)slot;
    if (sl_orient2d(x->a, x->b, q) < 0 || sl_orient2d(x->b, x->c, q) < 0 ||
        sl_orient2d(x->c, x->a, q) < 0)
        return;
    const double *w = s->pos + 3 * (size_t)slot;
    double d = (w[0] - x->pa[0]) * x->n[0] + (w[1] - x->pa[1]) * x->n[1] + (w[2] - x->pa[2]) * x->n[2];
    s->located_in[slot] = x->tri;
    s->error[slot] = fabs(d);
    s->tri_sum[x->tri] += d * d;
    uint32_t best = s->best[x->tri];
    if (best == SEG_NONE || s->error[slot] > s->error[best])
        s->best[x->tri] = slot;
}

/* The CDT of the loops and the points inserted so far. */
static int triangulate(patch *p, uint32_t point_count, sl_cdt_result **res)
{
    seg_scratch *s = p->s;
    for (uint32_t i = 0; i < point_count; i++) {
        s->points[2 * (size_t)i] = s->uv[2 * (size_t)s->point_slot[i]];
        s->points[2 * (size_t)i + 1] = s->uv[2 * (size_t)s->point_slot[i] + 1];
    }
    sl_cdt_input in = {point_count, s->points, p->loop_count, s->loop_start, s->loop_points};
    sl_error scratch;
    sl_error_init(&scratch);
    sl_cdt_report report;
    int rc = sl_cdt_triangulate(&in, 0, res, &report, &scratch);
    if (rc == SL_E_NOMEM)
        return SEG_PATCH_NOMEM;
    if (rc || (*res)->split_edges || (*res)->merged_points || (*res)->unused_points) {
        for (int i = 0; i < 4; i++) /* what the refusal names, as mesh vertices */
            p->problem[i] = rc && report.v[i] < point_count ? s->vertex[s->point_slot[report.v[i]]]
                                                             : SEG_NONE;
        sl_cdt_free(*res);
        *res = NULL;
        return SEG_PATCH_REFUSED;
    }
    return SEG_PATCH_OK;
}

/* Normals of the lifted triangles, the deviation check, and (with candidates) where
 * each candidate lies and each triangle's farthest one. Returns the bad triangle count. */
static uint32_t measure_round(patch *p, const sl_cdt_result *res, const grid *g,
                              double cos_max)
{
    seg_scratch *s = p->s;
    uint32_t bad = 0;
    for (uint32_t i = 0; i < p->candidates; i++)
        s->located_in[s->cands[i]] = SEG_NONE;
    for (uint32_t t = 0; t < res->triangle_count; t++) {
        const uint32_t *c = res->triangles + 3 * (size_t)t;
        uint32_t sl[3] = {s->point_slot[c[0]], s->point_slot[c[1]], s->point_slot[c[2]]};
        double u[3], w[3], *n = s->tri_normal + 3 * (size_t)t;
        for (int j = 0; j < 3; j++) {
            u[j] = s->pos[3 * (size_t)sl[1] + j] - s->pos[3 * (size_t)sl[0] + j];
            w[j] = s->pos[3 * (size_t)sl[2] + j] - s->pos[3 * (size_t)sl[0] + j];
        }
        sl_cross3(u, w, n);
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int j = 0; j < 3; j++)
            n[j] = len > 0 ? n[j] / len : 0;
        s->bad[t] = 0;
        for (int q = 0; q < 3; q++) {
            const double *vn = s->normal + 3 * (size_t)sl[q];
            if (n[0] * vn[0] + n[1] * vn[1] + n[2] * vn[2] < cos_max || !(len > 0))
                s->bad[t] = 1;
        }
        bad += s->bad[t];
        s->best[t] = SEG_NONE;
        s->tri_sum[t] = 0;
        if (p->candidates) {
            locate_ctx x = {p, t, s->uv + 2 * (size_t)sl[0], s->uv + 2 * (size_t)sl[1],
                            s->uv + 2 * (size_t)sl[2], s->pos + 3 * (size_t)sl[0], n};
            raster(g, s, x.a, x.b, x.c, locate_visit, &x);
        }
    }
    return bad;
}

static void emit(patch *p, const sl_cdt_result *res, seg_patch_result *out)
{
    seg_scratch *s = p->s;
    out->triangles = malloc(3 * (res->triangle_count ? res->triangle_count : 1) * sizeof *out->triangles);
    if (!out->triangles) {
        out->status = SEG_PATCH_NOMEM;
        return;
    }
    for (uint64_t i = 0; i < 3 * res->triangle_count; i++)
        out->triangles[i] = s->vertex[s->point_slot[res->triangles[i]]];
    out->triangle_count = (uint32_t)res->triangle_count;
    out->status = SEG_PATCH_OK;
}

/* Rule error: the trimmed polygon's CDT, then greedy insertion (segment_refine.c). */
static void run_error(patch *p, const seg_patch_params *prm, seg_patch_result *out)
{
    seg_scratch *s = p->s;
    grid g;
    memset(&g, 0, sizeof g);
    sl_cdt_result *res = NULL;
    int st = triangulate(p, p->loop_slots, &res);
    if (st != SEG_PATCH_OK) {
        out->status = st;
        return;
    }
    uint32_t nt = (uint32_t)res->triangle_count;
    out->base_triangles = nt;
    if (reserve_triangles(s, nt) || (p->candidates && build_grid(p, &g))) {
        sl_cdt_free(res);
        out->status = SEG_PATCH_NOMEM;
        return;
    }
    measure_round(p, res, &g, prm->cos_max_deviation); /* locates the candidates */
    for (uint64_t i = 0; i < 3 * (uint64_t)nt; i++) /* CDT points -> slots */
        res->triangles[i] = s->point_slot[res->triangles[i]];
    for (uint32_t i = 0; i < p->candidates; i++) /* outside (cut off by a chord): dropped */
        s->cand_tri[i] = s->located_in[s->cands[i]];
    if (!s->refine)
        s->refine = seg_refine_new();
    seg_refine_input in = {s->uv, s->pos, s->h, s->normal, prm->cos_max_deviation,
                           prm->max_error, p->slots, nt, res->triangles, p->candidates,
                           s->cands, s->cand_tri};
    int rc = s->refine ? seg_refine_start(s->refine, &in) : -1;
    sl_cdt_free(res);
    if (!rc && prm->record) {
        out->record = malloc((p->candidates ? p->candidates : 1) * sizeof *out->record);
        rc = out->record ? 0 : -1;
    }
    uint32_t inserted = 0;
    if (!rc)
        rc = seg_refine_run(s->refine, prm->tau, out->record, &out->record_count, NULL, &inserted);
    if (rc) {
        out->status = SEG_PATCH_NOMEM;
        return;
    }
    uint32_t corners[3];
    if (seg_refine_turned(s->refine, corners)) {
        for (int q = 0; q < 3; q++)
            p->problem[q] = s->vertex[corners[q]];
        out->status = SEG_PATCH_TURNED;
        return;
    }
    const uint32_t *tri;
    uint32_t count = seg_refine_triangles(s->refine, &tri);
    out->triangles = malloc(3 * (size_t)(count ? count : 1) * sizeof *out->triangles);
    if (!out->triangles) {
        out->status = SEG_PATCH_NOMEM;
        return;
    }
    for (uint64_t i = 0; i < 3 * (uint64_t)count; i++)
        out->triangles[i] = s->vertex[tri[i]];
    out->triangle_count = count;
    out->kept_interior = inserted;
    out->residual = seg_refine_residual(s->refine);
    out->status = SEG_PATCH_OK;
}

/* Rules near and paper: equations 3-8 once, then one triangulation. */
static void run_plane_rule(patch *p, const seg_patch_params *prm, seg_patch_result *out)
{
    seg_scratch *s = p->s;
    uint32_t n = p->slots;
    sl_plane plane;
    sl_error scratch;
    sl_error_init(&scratch);
    /* the plane of all the segment's vertices, unweighted (equation 3 sums over them) */
    if (sl_plane_fit(p->m->positions, s->vertex, n, NULL, SL_PLANE_TLS, &plane, &scratch)) {
        out->status = SEG_PATCH_REFUSED;
        return;
    }
    double sum = 0, sum2 = 0;
    for (uint32_t i = 0; i < n; i++) {
        const float *q = p->m->positions + 3 * (uint64_t)s->vertex[i];
        double d = plane.normal[0] * q[0] + plane.normal[1] * q[1] + plane.normal[2] * q[2] - plane.offset;
        s->error[i] = d * d; /* q_i of equation 7 */
        sum += s->error[i];
        sum2 += s->error[i] * s->error[i];
    }
    double mean = sum / n, variance = sum2 / n - mean * mean;
    if (variance < 0)
        variance = 0;
    uint32_t points = p->loop_slots;
    for (uint32_t i = 0; i < p->candidates; i++) {
        uint32_t c = s->cands[i];
        int removed = prm->rule == SL_SEGMENT_RULE_PAPER
                          ? s->error[c] >= mean + prm->alpha * variance        /* eq. 8 as printed */
                          : s->error[c] <= mean + prm->alpha * sqrt(variance); /* the text's intent */
        if (removed)
            continue;
        s->role[c] = ROLE_INSERTED;
        s->cdt_index[c] = points;
        s->point_slot[points++] = c;
    }
    sl_cdt_result *res = NULL;
    int st = triangulate(p, points, &res);
    if (st != SEG_PATCH_OK) {
        out->status = st;
        return;
    }
    if (reserve_triangles(s, (uint32_t)res->triangle_count)) {
        sl_cdt_free(res);
        out->status = SEG_PATCH_NOMEM;
        return;
    }
    p->candidates = 0; /* no location needed: only the deviation check */
    grid g;
    memset(&g, 0, sizeof g);
    if (measure_round(p, res, &g, prm->cos_max_deviation)) {
        sl_cdt_free(res);
        out->status = SEG_PATCH_TURNED;
        return;
    }
    out->kept_interior = points - p->loop_slots;
    emit(p, res, out);
    sl_cdt_free(res);
}

void seg_patch_run(const sl_segment_model *m, uint32_t k, const uint8_t *kept,
                   const seg_patch_params *prm, seg_scratch *s, seg_patch_result *out)
{
    memset(out, 0, sizeof *out);
    patch p;
    memset(&p, 0, sizeof p);
    p.m = m;
    p.k = k;
    p.f = &m->frame[k];
    p.s = s;
    if (gather(&p, kept)) {
        release_slots(&p);
        out->status = SEG_PATCH_NOMEM;
        return;
    }
    out->interior = p.candidates;
    memset(p.problem, 0xff, sizeof p.problem);
    if (prm->rule == SL_SEGMENT_RULE_ERROR)
        run_error(&p, prm, out);
    else
        run_plane_rule(&p, prm, out);
    memcpy(out->problem, p.problem, sizeof out->problem);
    release_slots(&p);
}
