/* Step (a) of a round (surface_fit_internal.h): every sample's closest point on the other
 * surface, written as a term. Four kinds, each a block of p->terms:
 *
 *   input   the reference's area samples (every input_stride-th) against the level's BVH,
 *           rebuilt each round: the level point is the closest point's barycentric
 *           combination of its triangle, weight 1 / count (the mean of compare's A->B)
 *   level   the level's fixed barycentric samples against the input's BVH, weight
 *           area(t) / (samples on t * area): the area-weighted mean of compare's B->A
 *   level border, input border  (open inputs) the level's open edges against the input's
 *           and back, weight border_weight spread by length: keeps the border on the
 *           input's border and lets it slide along it
 *
 * Each block runs in fixed chunks of FIT_CHUNK samples, a chunk's queries in order with
 * the previous answer as the hint (or the sample's own answer of the last round); the
 * squared distances are summed per chunk and the chunks in order, so the measure is the
 * same for any thread count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/surface_fit_internal.h"
#include "geometry/vec3.h"

/* Per-round state of the projection: the level's trees and areas at its positions. */
typedef struct round_state {
    sl_triangle_bvh level;      /* the level's triangles */
    sl_triangle_bvh border;     /* its open edges as (a, b, b), or empty */
    uint32_t *leaf_of;          /* per level triangle: its leaf-order index in `level` */
    double *weight;             /* per level triangle: area / (samples * sampled area) */
    double border_length;       /* of the level's open edges */
} round_state;

uint64_t fit_term_count(const fit_project *p)
{
    uint64_t borders = (uint64_t)p->lv->border_edge_count * FIT_BORDER_PER_EDGE +
                       p->ref->border_sample_count;
    return p->input_count + p->lv->sample_count + (p->borders ? borders : 0);
}

static void to_double(const float *f, double d[3])
{
    d[0] = f[0];
    d[1] = f[1];
    d[2] = f[2];
}

/* Weights of the segment p0 -> p1 (corners i0, i1) at the point nearest q. */
static void on_segment(const double q[3], const double p0[3], const double p1[3], int i0,
                       int i1, float w[3])
{
    double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    double e[3] = {q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]};
    double len_sq = sl_dot3(d, d), s = len_sq > 0.0 ? sl_dot3(e, d) / len_sq : 0.0;
    s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
    w[0] = w[1] = w[2] = 0.0f;
    w[i0] = (float)(1.0 - s);
    w[i1] += (float)s;
}

/* Barycentric weights of q, a point on triangle (c[0], c[1], c[2]) (Ericson 3.4); a
 * sliver's point is placed on its longest edge, as the closest-point query does. */
static void barycentric(const double q[3], double c[3][3], float w[3])
{
    double v0[3], v1[3], v2[3];
    for (int i = 0; i < 3; i++) {
        v0[i] = c[1][i] - c[0][i];
        v1[i] = c[2][i] - c[0][i];
        v2[i] = q[i] - c[0][i];
    }
    double d00 = sl_dot3(v0, v0), d01 = sl_dot3(v0, v1), d11 = sl_dot3(v1, v1);
    double den = d00 * d11 - d01 * d01;
    if (den > 1e-12 * d00 * d11) {
        double y = (d11 * sl_dot3(v2, v0) - d01 * sl_dot3(v2, v1)) / den;
        double z = (d00 * sl_dot3(v2, v1) - d01 * sl_dot3(v2, v0)) / den;
        y = y < 0.0 ? 0.0 : y;
        z = z < 0.0 ? 0.0 : z;
        if (y + z > 1.0) { /* rounding: back onto the triangle */
            double s = y + z;
            y /= s;
            z /= s;
        }
        w[0] = (float)(1.0 - y - z), w[1] = (float)y, w[2] = (float)z;
        return;
    }
    double d12[3] = {c[2][0] - c[1][0], c[2][1] - c[1][1], c[2][2] - c[1][2]};
    double l01 = d00, l12 = sl_dot3(d12, d12), l20 = d11;
    if (l01 >= l12 && l01 >= l20)
        on_segment(q, c[0], c[1], 0, 1, w);
    else if (l12 >= l20)
        on_segment(q, c[1], c[2], 1, 2, w);
    else
        on_segment(q, c[2], c[0], 2, 0, w);
}

static void corners_of(const fit_level *lv, uint32_t t, double c[3][3])
{
    for (int k = 0; k < 3; k++)
        fit_corner(lv, lv->pos, t, k, c[k]);
}

static void set_residual(fit_term *term, const double target[3], const double from[3])
{
    for (int i = 0; i < 3; i++)
        term->r[i] = (float)(target[i] - from[i]);
}

/* One input sample against the level; returns its share of the mean squared distance. */
static double project_input(const fit_project *p, const round_state *rs, uint64_t i,
                            uint32_t *hint)
{
    fit_term *term = &p->terms[i];
    double x[3], c[3][3];
    to_double(&p->ref->samples[3 * i * p->input_stride], x);
    if (term->weight > 0.0f) /* this sample's triangle last round */
        *hint = rs->leaf_of[term->triangle];
    sl_closest q;
    sl_triangle_bvh_closest(&rs->level, x, *hint, &q);
    *hint = q.triangle;
    term->triangle = rs->level.source[q.triangle];
    corners_of(p->lv, term->triangle, c);
    barycentric(q.point, c, term->w);
    set_residual(term, x, q.point);
    term->weight = (float)(1.0 / (double)p->input_count);
    return q.distance_sq / (double)p->input_count;
}

/* One level sample against the input; returns its weighted squared distance. */
static double project_level(const fit_project *p, const round_state *rs, uint64_t j,
                            uint32_t *hint)
{
    const sl_area_sample *s = &p->lv->samples[j];
    fit_term *term = &p->terms[p->input_count + j];
    double x[3], c[3][3];
    corners_of(p->lv, s->triangle, c);
    term->triangle = s->triangle;
    term->w[0] = 1.0f - s->b - s->c, term->w[1] = s->b, term->w[2] = s->c;
    for (int i = 0; i < 3; i++)
        x[i] = term->w[0] * c[0][i] + term->w[1] * c[1][i] + term->w[2] * c[2][i];
    if (p->level_hint[j] != UINT32_MAX)
        *hint = p->level_hint[j];
    sl_closest q;
    sl_triangle_bvh_closest(p->ref->surface, x, *hint, &q);
    *hint = p->level_hint[j] = q.triangle;
    set_residual(term, q.point, x);
    term->weight = (float)rs->weight[s->triangle];
    return rs->weight[s->triangle] * q.distance_sq;
}

/* Sample k of the level's open edge e, against the input's open edges. */
static double project_level_border(const fit_project *p, const round_state *rs, uint64_t i,
                                   uint32_t *hint)
{
    uint64_t e = i / FIT_BORDER_PER_EDGE;
    uint32_t corner = p->lv->border_edges[e], t = corner / 3u;
    int k0 = (int)(corner % 3u), k1 = (int)(fit_next_corner(corner) % 3u);
    fit_term *term = &p->terms[p->input_count + p->lv->sample_count + i];
    double c[3][3], x[3], s = ((double)(i % FIT_BORDER_PER_EDGE) + 0.5) / FIT_BORDER_PER_EDGE;
    corners_of(p->lv, t, c);
    for (int a = 0; a < 3; a++)
        x[a] = (1.0 - s) * c[k0][a] + s * c[k1][a];
    sl_closest q;
    sl_triangle_bvh_closest(&p->ref->border, x, *hint, &q);
    *hint = q.triangle;
    term->triangle = t;
    term->w[0] = term->w[1] = term->w[2] = 0.0f;
    term->w[k0] = (float)(1.0 - s);
    term->w[k1] = (float)s;
    set_residual(term, q.point, x);
    double len_sq = 0.0;
    for (int a = 0; a < 3; a++)
        len_sq += (c[k1][a] - c[k0][a]) * (c[k1][a] - c[k0][a]);
    double wgt = rs->border_length > 0.0 ? p->border_weight * sqrt(len_sq) /
                                               (FIT_BORDER_PER_EDGE * rs->border_length)
                                         : 0.0;
    term->weight = (float)wgt;
    return 0.0;
}

/* One sample of the input's open edges, against the level's. */
static double project_input_border(const fit_project *p, const round_state *rs, uint64_t i,
                                   uint32_t *hint)
{
    fit_term *term = &p->terms[fit_term_count(p) - p->ref->border_sample_count + i];
    double x[3], c[3][3];
    to_double(&p->ref->border_samples[3 * i], x);
    sl_closest q;
    sl_triangle_bvh_closest(&rs->border, x, *hint, &q);
    *hint = q.triangle;
    uint32_t corner = p->lv->border_edges[rs->border.source[q.triangle]];
    int k0 = (int)(corner % 3u), k1 = (int)(fit_next_corner(corner) % 3u);
    term->triangle = corner / 3u;
    corners_of(p->lv, term->triangle, c);
    on_segment(q.point, c[k0], c[k1], k0, k1, term->w);
    set_residual(term, x, q.point);
    term->weight = (float)(p->border_weight / (double)p->ref->border_sample_count);
    return 0.0;
}

typedef double (*project_fn)(const fit_project *, const round_state *, uint64_t, uint32_t *);

/* Runs `fn` over n samples in fixed chunks; returns the chunks' sums added in order. */
static int project_block(const fit_project *p, const round_state *rs, project_fn fn,
                         uint64_t n, double *partial, double *sum, sl_progress *progress)
{
    uint64_t chunks = (n + FIT_CHUNK - 1) / FIT_CHUNK;
    int interrupted = 0;
#pragma omp parallel for schedule(dynamic, 1) if (chunks > 1)
    for (uint64_t c = 0; c < chunks; c++) {
        if (sl_progress_interrupted(progress)) {
#pragma omp atomic write
            interrupted = 1;
            continue;
        }
        uint32_t hint = UINT32_MAX;
        double acc = 0.0;
        for (uint64_t i = c * FIT_CHUNK; i < n && i < (c + 1) * FIT_CHUNK; i++)
            acc += fn(p, rs, i, &hint);
        partial[c] = acc;
    }
    *sum = 0.0;
    for (uint64_t c = 0; c < chunks; c++)
        *sum += partial[c];
    return interrupted ? SL_E_INTERRUPTED : SL_OK;
}

/* Triangle weights of the level samples (if any) and the open edges' length at the
 * positions. */
static void level_weights(const fit_project *p, round_state *rs, double *partial)
{
    const fit_level *lv = p->lv;
    uint64_t chunks = lv->per_triangle ? (lv->triangle_count + FIT_CHUNK - 1) / FIT_CHUNK : 0;
#pragma omp parallel for schedule(static) if (chunks > 1)
    for (uint64_t ch = 0; ch < chunks; ch++) {
        double acc = 0.0;
        for (uint64_t t = ch * FIT_CHUNK; t < lv->triangle_count && t < (ch + 1) * FIT_CHUNK; t++) {
            double c[3][3], n[3];
            corners_of(lv, (uint32_t)t, c);
            fit_quality(c[0], c[1], c[2], n);
            rs->weight[t] = lv->per_triangle[t] ? 0.5 * sqrt(sl_dot3(n, n)) : 0.0;
            acc += rs->weight[t];
        }
        partial[ch] = acc;
    }
    double area = 0.0;
    for (uint64_t ch = 0; ch < chunks; ch++)
        area += partial[ch];
#pragma omp parallel for schedule(static) if (lv->triangle_count > FIT_CHUNK)
    for (uint64_t t = 0; t < (lv->per_triangle ? lv->triangle_count : 0); t++)
        if (lv->per_triangle[t])
            rs->weight[t] = area > 0.0 ? rs->weight[t] / (lv->per_triangle[t] * area) : 0.0;
    rs->border_length = 0.0;
    for (uint32_t e = 0; e < lv->border_edge_count; e++) {
        double a[3], b[3], d[3];
        uint32_t corner = lv->border_edges[e];
        fit_corner(lv, lv->pos, corner / 3u, (int)(corner % 3u), a);
        fit_corner(lv, lv->pos, corner / 3u, (int)(fit_next_corner(corner) % 3u), b);
        for (int i = 0; i < 3; i++)
            d[i] = b[i] - a[i];
        rs->border_length += sqrt(sl_dot3(d, d));
    }
}

/* The level's open edges as segments (a, b, b) at the current positions. */
static int build_border_tree(const fit_level *lv, sl_triangle_bvh *bvh, sl_error *err)
{
    uint32_t *seg = malloc(3 * (size_t)lv->border_edge_count * sizeof *seg);
    if (!seg)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: level border");
    for (uint32_t e = 0; e < lv->border_edge_count; e++) {
        seg[3 * e] = lv->tri[lv->border_edges[e]];
        seg[3 * e + 1] = seg[3 * e + 2] = lv->tri[fit_next_corner(lv->border_edges[e])];
    }
    sl_mesh view = sl_mesh_view(lv->vertex_count, lv->pos, NULL, NULL, lv->border_edge_count,
                                seg);
    int rc = sl_triangle_bvh_build(bvh, &view, err);
    free(seg);
    return rc;
}

static int round_begin(const fit_project *p, round_state *rs, uint64_t n_partial,
                       sl_error *err)
{
    const fit_level *lv = p->lv;
    memset(rs, 0, sizeof *rs);
    rs->leaf_of = malloc((size_t)lv->triangle_count * sizeof *rs->leaf_of);
    rs->weight = malloc((size_t)lv->triangle_count * sizeof *rs->weight);
    if (!rs->leaf_of || !rs->weight || !n_partial)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: round state");
    sl_mesh view = sl_mesh_view(lv->vertex_count, lv->pos, NULL, NULL, lv->triangle_count,
                                lv->tri);
    int rc = sl_triangle_bvh_build(&rs->level, &view, err);
    if (rc == SL_OK && p->borders)
        rc = build_border_tree(lv, &rs->border, err);
    for (uint32_t l = 0; rc == SL_OK && l < lv->triangle_count; l++)
        rs->leaf_of[rs->level.source[l]] = l;
    return rc;
}

static void round_end(round_state *rs)
{
    sl_triangle_bvh_release(&rs->level);
    sl_triangle_bvh_release(&rs->border);
    free(rs->leaf_of);
    free(rs->weight);
}

int fit_project_all(fit_project *p, fit_measure *m, sl_progress *progress, sl_error *err)
{
    const fit_level *lv = p->lv;
    uint64_t most = p->input_count > lv->sample_count ? p->input_count : lv->sample_count;
    if (p->ref->border_sample_count > most)
        most = p->ref->border_sample_count;
    if (lv->triangle_count > most)
        most = lv->triangle_count;
    uint64_t n_partial = (most + FIT_CHUNK - 1) / FIT_CHUNK + 1;
    double *partial = malloc(n_partial * sizeof *partial), unused;
    round_state rs;
    int rc = round_begin(p, &rs, partial ? n_partial : 0, err);
    memset(m, 0, sizeof *m);
    if (rc == SL_OK) {
        level_weights(p, &rs, partial);
        rc = project_block(p, &rs, project_input, p->input_count, partial, &m->input_to_level,
                           progress);
    }
    if (rc == SL_OK && !p->ref->is_points)
        rc = project_block(p, &rs, project_level, lv->sample_count, partial,
                           &m->level_to_input, progress);
    if (rc == SL_OK && p->borders)
        rc = project_block(p, &rs, project_level_border,
                           (uint64_t)lv->border_edge_count * FIT_BORDER_PER_EDGE, partial,
                           &unused, progress);
    if (rc == SL_OK && p->borders)
        rc = project_block(p, &rs, project_input_border, p->ref->border_sample_count, partial,
                           &unused, progress);
    round_end(&rs);
    free(partial);
    if (rc == SL_E_INTERRUPTED)
        return sl_error_set(err, rc, 0, NULL, "surface fit");
    return rc;
}
