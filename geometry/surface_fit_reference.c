/* The surface fit's input (surface_fit.h): checked once, then its BVH, its area samples
 * (mesh_distance's stratified sampler with the fit's own seed) and its open border (the
 * edges one triangle has, after welding equal positions) as a BVH of segments and evenly
 * spaced samples. A point set keeps its points and nothing else.
 */
#include <math.h>
#include <meshoptimizer.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/surface_fit_internal.h"
#include "geometry/vec3.h"

#define AUTO_PER_TRIANGLE 4
#define AUTO_MIN_SAMPLES 100000u
#define AUTO_MAX_SAMPLES 4000000u

void sl_fit_reference_free(sl_fit_reference *ref)
{
    if (!ref)
        return;
    free(ref->samples);
    sl_triangle_bvh_release(&ref->own_surface);
    sl_triangle_bvh_release(&ref->border);
    free(ref->border_samples);
    free(ref);
}

static double box_diagonal(const double lo[3], const double hi[3])
{
    double d_sq = 0.0;
    for (int i = 0; i < 3; i++)
        d_sq += (hi[i] - lo[i]) * (hi[i] - lo[i]);
    return sqrt(d_sq);
}

static int take_points(sl_fit_reference *r, const sl_mesh *in, sl_error *err)
{
    if (in->vertex_count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "fit input: no triangles and no points");
    if (in->vertex_count > SL_FIT_MAX_SAMPLES)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "fit input: %llu points, at most %llu",
                            (unsigned long long)in->vertex_count, SL_FIT_MAX_SAMPLES);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < 3 * in->vertex_count; i++) {
        if (!isfinite(in->positions[i]))
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "fit input: point %llu has a non-finite coordinate",
                                (unsigned long long)(i / 3));
        lo[i % 3] = fmin(lo[i % 3], in->positions[i]);
        hi[i % 3] = fmax(hi[i % 3], in->positions[i]);
    }
    r->samples = malloc(3 * in->vertex_count * sizeof *r->samples);
    if (!r->samples)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit input: %llu points",
                            (unsigned long long)in->vertex_count);
    memcpy(r->samples, in->positions, 3 * in->vertex_count * sizeof *r->samples);
    r->is_points = 1;
    r->sample_count = in->vertex_count;
    r->diagonal = box_diagonal(lo, hi);
    return SL_OK;
}

static uint64_t sample_budget(const sl_mesh *in, const sl_fit_config *cfg)
{
    if (cfg->samples)
        return cfg->samples;
    uint64_t n = AUTO_PER_TRIANGLE * in->triangle_count;
    return n < AUTO_MIN_SAMPLES ? AUTO_MIN_SAMPLES : n > AUTO_MAX_SAMPLES ? AUTO_MAX_SAMPLES : n;
}

static void sample_point(const sl_mesh *m, const sl_area_sample *s, float out[3])
{
    const uint32_t *t = &m->triangles[3 * (uint64_t)s->triangle];
    double wa = 1.0 - (double)s->b - (double)s->c;
    for (int i = 0; i < 3; i++)
        out[i] = (float)(wa * m->positions[3 * (uint64_t)t[0] + i] +
                         s->b * (double)m->positions[3 * (uint64_t)t[1] + i] +
                         s->c * (double)m->positions[3 * (uint64_t)t[2] + i]);
}

/* The input's area samples as points (the records only while drawing them). */
static int take_area_samples(sl_fit_reference *r, const sl_mesh *in, uint64_t n, uint64_t seed,
                             sl_error *err)
{
    uint64_t bound = sl_mesh_area_samples_bound(in, n);
    sl_area_sample *rec = bound <= SIZE_MAX / sizeof *rec ? malloc(bound * sizeof *rec) : NULL;
    r->samples = rec ? malloc(3 * bound * sizeof *r->samples) : NULL;
    if (!r->samples) {
        free(rec);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit input: %llu samples",
                            (unsigned long long)n);
    }
    int rc = sl_mesh_area_samples(in, n, seed, rec, &r->sample_count, err);
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < (rc == SL_OK ? r->sample_count : 0); i++)
        sample_point(in, &rec[i], &r->samples[3 * i]);
    free(rec);
    return rc;
}

/* Welded corner indices of the input (equal positions share one), for its open edges. */
static int welded_triangles(const sl_mesh *in, uint32_t **out, sl_error *err)
{
    size_t n = 3 * (size_t)in->triangle_count;
    uint32_t *remap = malloc(in->vertex_count * sizeof *remap);
    *out = malloc(n * sizeof **out);
    if (!remap || !*out) {
        free(remap);
        free(*out);
        *out = NULL;
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit input: welding");
    }
    meshopt_generateVertexRemap(remap, in->triangles, n, in->positions, in->vertex_count,
                                3 * sizeof(float));
    for (size_t i = 0; i < n; i++)
        (*out)[i] = remap[in->triangles[i]];
    free(remap);
    return SL_OK;
}

/* The open edge starting at corner id `corner` of `in`: its ends; returns its length. */
static double open_edge(const sl_mesh *in, uint32_t corner, const float **a, const float **b)
{
    *a = &in->positions[3 * (uint64_t)in->triangles[corner]];
    *b = &in->positions[3 * (uint64_t)in->triangles[fit_next_corner(corner)]];
    double d[3] = {(double)(*b)[0] - (*a)[0], (double)(*b)[1] - (*a)[1], (double)(*b)[2] - (*a)[2]};
    return sqrt(sl_dot3(d, d));
}

/* Samples about `step` apart along the open edges (corner ids `open` of `in`): the
 * middles of equal steps along the edges one after the other. */
static int sample_border(sl_fit_reference *r, const sl_mesh *in, const uint32_t *open,
                         uint64_t open_count, double step, sl_error *err)
{
    const float *a, *b;
    double length = 0.0;
    for (uint64_t e = 0; e < open_count; e++)
        length += open_edge(in, open[e], &a, &b);
    double n = ceil(length / step);
    if (!(n < (double)SL_FIT_MAX_SAMPLES))
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "fit input: border samples");
    uint64_t count = n > 1.0 ? (uint64_t)n : 1;
    r->border_samples = malloc(3 * count * sizeof *r->border_samples);
    if (!r->border_samples)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit input: border samples");
    step = length / (double)count;
    double at = 0.5 * step, start = 0.0; /* along the edges one after the other */
    uint64_t k = 0;
    for (uint64_t e = 0; e < open_count && k < count; e++) {
        double len = open_edge(in, open[e], &a, &b);
        for (; at < start + len && k < count; at += step, k++)
            for (int i = 0; i < 3; i++)
                r->border_samples[3 * k + i] = (float)(a[i] + (at - start) / len * (b[i] - a[i]));
        start += len;
    }
    r->border_sample_count = k;
    return SL_OK;
}

/* The open edges as a BVH of segments (a, b, b) and as samples. */
static int take_border(sl_fit_reference *r, const sl_mesh *in, double step, sl_error *err)
{
    uint32_t *welded = NULL, *open = NULL;
    uint64_t open_count = 0;
    int rc = welded_triangles(in, &welded, err);
    if (rc == SL_OK)
        rc = fit_open_edges(welded, in->triangle_count, (uint32_t)in->vertex_count, &open,
                            &open_count, err);
    free(welded);
    if (rc != SL_OK || open_count == 0) {
        free(open);
        return rc;
    }
    uint32_t *seg = malloc(3 * open_count * sizeof *seg);
    if (!seg) {
        free(open);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit input: %llu open edges",
                            (unsigned long long)open_count);
    }
    for (uint64_t e = 0; e < open_count; e++) {
        seg[3 * e] = in->triangles[open[e]];
        seg[3 * e + 1] = seg[3 * e + 2] = in->triangles[fit_next_corner(open[e])];
    }
    sl_mesh view = sl_mesh_view(in->vertex_count, in->positions, NULL, NULL, open_count, seg);
    rc = sl_triangle_bvh_build(&r->border, &view, err);
    free(seg);
    if (rc == SL_OK)
        rc = sample_border(r, in, open, open_count, step, err);
    free(open);
    return rc;
}

static int take_surface(sl_fit_reference *r, const sl_mesh *in, const sl_fit_config *cfg,
                        sl_error *err)
{
    sl_error why;
    sl_error_init(&why);
    int rc = sl_mesh_check_surface(in, "input", &why); /* "input": the message alone */
    if (rc != SL_OK)
        return sl_error_set(err, rc, 0, NULL, "fit input: %s", why.message);
    if (in->triangle_count > (UINT32_MAX - 1u) / 3u)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "fit input: %llu triangles",
                            (unsigned long long)in->triangle_count);
    uint64_t n = sample_budget(in, cfg);
    if (cfg->surface_tree && cfg->surface_tree->triangle_count == in->triangle_count) {
        r->surface = cfg->surface_tree; /* borrowed: the same tree this mesh would give */
    } else {
        rc = sl_triangle_bvh_build(&r->own_surface, in, err);
        r->surface = &r->own_surface;
    }
    if (rc == SL_OK)
        rc = take_area_samples(r, in, n, cfg->seed, err);
    if (rc != SL_OK)
        return rc;
    const sl_bvh_node *root = &r->surface->nodes[0];
    double lo[3] = {root->lo[0], root->lo[1], root->lo[2]};
    double hi[3] = {root->hi[0], root->hi[1], root->hi[2]};
    r->diagonal = box_diagonal(lo, hi);
    double area = 0.0; /* spacing of the area samples, for the border's */
    for (uint64_t t = 0; t < in->triangle_count; t++) {
        double c[3][3], nrm[3];
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++)
                c[k][i] = in->positions[3 * (uint64_t)in->triangles[3 * t + k] + i];
        fit_quality(c[0], c[1], c[2], nrm);
        area += 0.5 * sqrt(sl_dot3(nrm, nrm));
    }
    return take_border(r, in, sqrt(area / (double)r->sample_count), err);
}

int sl_fit_reference_build(const sl_mesh *input, const sl_fit_config *config,
                           sl_fit_reference **out, sl_error *err)
{
    sl_fit_config defaults = sl_fit_default_config();
    const sl_fit_config *cfg = config ? config : &defaults;
    *out = NULL;
    if (cfg->samples > SL_FIT_MAX_SAMPLES)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "fit: %llu samples, at most %llu",
                            (unsigned long long)cfg->samples, SL_FIT_MAX_SAMPLES);
    sl_fit_reference *r = calloc(1, sizeof *r);
    if (!r)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit reference");
    r->surface = &r->own_surface;
    int rc = input->triangle_count == 0 ? take_points(r, input, err)
                                        : take_surface(r, input, cfg, err);
    if (rc != SL_OK) {
        sl_fit_reference_free(r);
        return rc;
    }
    *out = r;
    return SL_OK;
}
