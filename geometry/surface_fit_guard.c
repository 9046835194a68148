/* The guards of a step (surface_fit_internal.h): the solve proposes a displacement per
 * vertex; each vertex goes as far along it as its triangles allow.
 *
 * A triangle fails when its normal turns by 90 degrees or more against its normal before
 * the step or as given (the second stops a flip done in several small turns), or when it
 * becomes a sliver: compactness below QUALITY_FLOOR, or below half its compactness as
 * given for a triangle that already was one. Each round places every vertex at
 * before + 2^-h step (h its halvings; an open-border vertex then snapped to the input's
 * open border), tests every triangle and halves the steps of the corners of the failed
 * ones; after MAX_HALVINGS a vertex stays where it was. A triangle whose corners all
 * stayed is the one before the step, which passed, so the rounds end with every triangle
 * passing. Everything is per vertex or per triangle, in parallel and deterministic.
 */
#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/surface_fit_internal.h"
#include "geometry/vec3.h"

#define QUALITY_FLOOR 0.1  /* compactness of a right triangle with a 3.3 degree angle */
#define MAX_HALVINGS 5     /* then the vertex stays: 1, 1/2 ... 1/16, 0 */

int fit_guard_init(fit_guard *g, const fit_level *lv, sl_error *err)
{
    g->before = malloc(3 * (size_t)lv->vertex_count * sizeof *g->before);
    g->halvings = malloc(lv->vertex_count);
    g->bad = malloc(lv->triangle_count);
    if (!g->before || !g->halvings || !g->bad)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: guard state");
    return SL_OK;
}

void fit_guard_release(fit_guard *g)
{
    free(g->before);
    free(g->halvings);
    free(g->bad);
    memset(g, 0, sizeof *g);
}

/* Vertex v at its step's current fraction; on the input's open border if it is on the
 * level's (a vertex that stays is not snapped: it stays exactly). */
static void place(fit_level *lv, const fit_guard *g, const sl_fit_reference *ref,
                  const double *x, uint32_t v)
{
    float *out = &lv->pos[3 * (size_t)v];
    const float *from = &g->before[3 * (size_t)v];
    if (g->halvings[v] >= MAX_HALVINGS) {
        memcpy(out, from, 3 * sizeof *out);
        return;
    }
    double f = ldexp(1.0, -(int)g->halvings[v]), p[3];
    for (int a = 0; a < 3; a++)
        p[a] = from[a] + f * x[3 * (size_t)v + a];
    if (lv->border[v] && ref->border.triangle_count) {
        sl_closest q;
        sl_triangle_bvh_closest(&ref->border, p, UINT32_MAX, &q);
        memcpy(p, q.point, sizeof p);
    }
    for (int a = 0; a < 3; a++)
        out[a] = (float)p[a];
}

static int triangle_passes(const fit_level *lv, const fit_guard *g, uint32_t t)
{
    double a[3], b[3], c[3], n[3], n0[3], start[3];
    fit_corner(lv, g->before, t, 0, a);
    fit_corner(lv, g->before, t, 1, b);
    fit_corner(lv, g->before, t, 2, c);
    fit_quality(a, b, c, n0);
    fit_corner(lv, lv->pos, t, 0, a);
    fit_corner(lv, lv->pos, t, 1, b);
    fit_corner(lv, lv->pos, t, 2, c);
    double q = fit_quality(a, b, c, n);
    for (int i = 0; i < 3; i++)
        start[i] = lv->start_normal[3 * (size_t)t + i];
    if (sl_dot3(start, start) > 0.0 && !(sl_dot3(n, start) > 0.0))
        return 0;
    if (sl_dot3(n0, n0) > 0.0 && !(sl_dot3(n, n0) > 0.0))
        return 0;
    double floor_q = 0.5 * lv->start_quality[t];
    return q >= (floor_q < QUALITY_FLOOR ? floor_q : QUALITY_FLOOR);
}

/* One round: place, test; halve where a triangle failed. Returns whether any did. */
static int guard_round(fit_level *lv, fit_guard *g, const sl_fit_reference *ref,
                       const double *x)
{
    uint64_t failed = 0, changed = 0;
#pragma omp parallel for schedule(static) if (lv->vertex_count > FIT_CHUNK)
    for (uint32_t v = 0; v < lv->vertex_count; v++)
        place(lv, g, ref, x, v);
#pragma omp parallel for schedule(static) reduction(+ : failed) if (lv->triangle_count > FIT_CHUNK)
    for (uint32_t t = 0; t < lv->triangle_count; t++) {
        g->bad[t] = !triangle_passes(lv, g, t);
        failed += g->bad[t];
    }
    if (!failed)
        return 0;
#pragma omp parallel for schedule(static) reduction(+ : changed) if (lv->vertex_count > FIT_CHUNK)
    for (uint32_t v = 0; v < lv->vertex_count; v++) {
        int hit = 0;
        for (uint32_t i = lv->corner_start[v]; i < lv->corner_start[v + 1] && !hit; i++)
            hit = g->bad[lv->corners[i] / 3u];
        if (hit && g->halvings[v] < MAX_HALVINGS) {
            g->halvings[v]++;
            changed++;
        }
    }
    if (!changed) { /* cannot happen (see the top); if it did, the step is not taken */
        assert(changed);
        memcpy(lv->pos, g->before, 3 * (size_t)lv->vertex_count * sizeof *lv->pos);
        return 0;
    }
    return 1;
}

uint64_t fit_guarded_step(fit_level *lv, fit_guard *g, const sl_fit_reference *ref,
                          const double *x)
{
    memcpy(g->before, lv->pos, 3 * (size_t)lv->vertex_count * sizeof *g->before);
    for (uint32_t v = 0; v < lv->vertex_count; v++)
        g->halvings[v] = lv->fixed[v] ? MAX_HALVINGS : 0;
    while (guard_round(lv, g, ref, x))
        ;
#ifndef NDEBUG
    for (uint32_t t = 0; t < lv->triangle_count; t++) /* no flipped triangle after a step */
        assert(triangle_passes(lv, g, t));
#endif
    uint64_t shortened = 0;
    for (uint32_t v = 0; v < lv->vertex_count; v++)
        shortened += !lv->fixed[v] && g->halvings[v] > 0;
    return shortened;
}
