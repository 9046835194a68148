/* Normal-angle region growing (region_grow.h; paper 3, section 3.1, equation 1).
 *
 * Method comment. A segment's normals are kept as their extreme normals
 * (geometry/normal_hull.h) in the chart of the seed normal s (every member is within
 * delta < 90 degrees of s). For a candidate normal m the set { x : ang(m, x) <= delta } is
 * a circular cone of half-angle < 90 degrees, hence convex: the whole segment passes
 * equation 1 against m exactly when the hull's vertices do.
 */
#include "geometry/region_grow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/normal_hull.h"
#include "geometry/vec3.h"

#define NONE UINT32_MAX
#define FLATNESS_BINS 1024

sl_region_grow_config sl_region_grow_default_config(void)
{
    sl_region_grow_config c = {30.0, 0, 0.5, SL_REGION_GROW_MAX_DELTA, 16};
    return c;
}

void sl_segmentation_release(sl_segmentation *s)
{
    free(s->segment);
    free(s->seed);
    memset(s, 0, sizeof *s);
}

void sl_face_normals(const sl_mesh_adjacency *adj, const float *positions, double *normals)
{
    int64_t n = adj->triangle_count;
#pragma omp parallel for schedule(static)
    for (int64_t t = 0; t < n; t++) {
        double *out = normals + 3 * t;
        out[0] = out[1] = out[2] = 0.0;
        if (adj->degenerate[t])
            continue;
        const uint32_t *c = adj->triangles + 3 * t;
        const float *a = positions + 3 * (uint64_t)c[0], *b = positions + 3 * (uint64_t)c[1],
                    *d = positions + 3 * (uint64_t)c[2];
        double u[3], v[3], x[3];
        for (int k = 0; k < 3; k++) {
            u[k] = (double)b[k] - a[k];
            v[k] = (double)d[k] - a[k];
        }
        x[0] = u[1] * v[2] - u[2] * v[1];
        x[1] = u[2] * v[0] - u[0] * v[2];
        x[2] = u[0] * v[1] - u[1] * v[0];
        double len = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        if (len > 0.0 && isfinite(len))
            for (int k = 0; k < 3; k++)
                out[k] = x[k] / len;
    }
}

static int has_normal(const double *n)
{
    return n[0] != 0.0 || n[1] != 0.0 || n[2] != 0.0;
}

/* Equation 1 against the whole segment: every hull vertex within delta of n. */
static int passes(const sl_normal_hull *h, const double *n, double cos_delta)
{
    return sl_dot3(n, h->s) >= cos_delta && sl_normal_hull_min_dot(h, n) >= cos_delta;
}

/* --- the growth front: a binary heap of (key, triangle), smallest first ------------- */

typedef struct front_entry {
    double key; /* -(n . seed normal): the closest normal first */
    uint32_t tri;
} front_entry;

typedef struct front {
    front_entry *e;
    uint64_t count, cap;
} front;

static int front_less(const front_entry *a, const front_entry *b)
{
    return a->key < b->key || (a->key == b->key && a->tri < b->tri);
}

static int front_push(front *f, double key, uint32_t tri)
{
    if (f->count == f->cap) {
        uint64_t cap = f->cap ? 2 * f->cap : 64;
        front_entry *e = realloc(f->e, cap * sizeof *e);
        if (!e)
            return -1;
        f->e = e;
        f->cap = cap;
    }
    uint64_t i = f->count++;
    front_entry x = {key, tri};
    while (i > 0 && front_less(&x, &f->e[(i - 1) / 2])) {
        f->e[i] = f->e[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    f->e[i] = x;
    return 0;
}

static front_entry front_pop(front *f)
{
    front_entry top = f->e[0], x = f->e[--f->count];
    uint64_t i = 0;
    for (;;) {
        uint64_t c = 2 * i + 1;
        if (c >= f->count)
            break;
        if (c + 1 < f->count && front_less(&f->e[c + 1], &f->e[c]))
            c++;
        if (!front_less(&f->e[c], &x))
            break;
        f->e[i] = f->e[c];
        i = c;
    }
    if (f->count)
        f->e[i] = x;
    return top;
}

/* --- seeds: flattest first ------------------------------------------------------------ */

/* Triangle indices ordered by quantised flatness (the largest 1 - cos to an edge
 * neighbour; no normal: last), then index: a stable counting sort. */
static int seed_order(const sl_mesh_adjacency *adj, const double *normals, uint32_t *order)
{
    uint32_t n = adj->triangle_count;
    uint16_t *bin = malloc((n ? n : 1) * sizeof *bin);
    uint64_t *start = calloc(FLATNESS_BINS + 2, sizeof *start);
    if (!bin || !start) {
        free(bin);
        free(start);
        return -1;
    }
    int64_t ni = n;
#pragma omp parallel for schedule(static)
    for (int64_t t = 0; t < ni; t++) {
        const double *m = normals + 3 * t;
        if (!has_normal(m)) {
            bin[t] = FLATNESS_BINS; /* last */
            continue;
        }
        double worst = 0.0;
        for (int c = 0; c < 3; c++) {
            uint32_t tw = adj->twin[3 * t + c];
            if (tw == NONE)
                continue;
            const double *o = normals + 3 * (uint64_t)sl_halfedge_face(tw);
            if (has_normal(o) && 1.0 - sl_dot3(m, o) > worst)
                worst = 1.0 - sl_dot3(m, o);
        }
        double q = sqrt(worst / 2.0) * (FLATNESS_BINS - 1e-9); /* ~ angle / 180 */
        bin[t] = (uint16_t)(q < FLATNESS_BINS - 1 ? q : FLATNESS_BINS - 1);
    }
    for (uint32_t t = 0; t < n; t++)
        start[bin[t] + 1]++;
    for (int b = 0; b <= FLATNESS_BINS; b++)
        start[b + 1] += start[b];
    for (uint32_t t = 0; t < n; t++)
        order[start[bin[t]]++] = t;
    free(bin);
    free(start);
    return 0;
}

/* --- one Min-# growth --------------------------------------------------------------- */

typedef struct grow_work {
    const sl_mesh_adjacency *adj;
    const double *normals;
    const uint32_t *order;
    uint32_t *stamp; /* per triangle: the segment that last queued it, NONE */
    sl_normal_hull h;
    front f;
} grow_work;

/* Labels every triangle; returns the segment count, or -1 when out of memory. */
static int64_t grow(grow_work *w, double delta_degrees, uint32_t *label, uint32_t *seeds,
                    uint64_t *without_normal)
{
    const sl_mesh_adjacency *adj = w->adj;
    uint32_t n = adj->triangle_count;
    double cos_delta = cos(delta_degrees * (M_PI / 180.0));
    memset(label, 0xff, (size_t)n * sizeof *label);
    memset(w->stamp, 0xff, (size_t)n * sizeof *w->stamp);
    uint32_t count = 0;
    *without_normal = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t seed = w->order[i];
        if (label[seed] != NONE)
            continue;
        uint32_t k = count++;
        seeds[k] = seed;
        label[seed] = k;
        const double *s = w->normals + 3 * (uint64_t)seed;
        if (!has_normal(s)) {
            (*without_normal)++;
            continue;
        }
        sl_normal_hull_start(&w->h, s);
        if (sl_normal_hull_add(&w->h, s, seed))
            return -1;
        w->stamp[seed] = k;
        w->f.count = 0;
        for (uint32_t t = seed;;) {
            for (int c = 0; c < 3; c++) { /* queue t's unlabelled neighbours */
                uint32_t tw = adj->twin[3 * (uint64_t)t + c];
                if (tw == NONE)
                    continue;
                uint32_t o = sl_halfedge_face(tw);
                if (label[o] != NONE || w->stamp[o] == k)
                    continue;
                w->stamp[o] = k;
                if (front_push(&w->f, -sl_dot3(w->normals + 3 * (uint64_t)o, s), o))
                    return -1;
            }
            t = NONE;
            while (w->f.count && t == NONE) {
                front_entry e = front_pop(&w->f);
                const double *m = w->normals + 3 * (uint64_t)e.tri;
                if (label[e.tri] == NONE && has_normal(m) && passes(&w->h, m, cos_delta))
                    t = e.tri;
            }
            if (t == NONE)
                break;
            label[t] = k;
            if (sl_normal_hull_add(&w->h, w->normals + 3 * (uint64_t)t, t))
                return -1;
        }
    }
    return count;
}

static int check_config(const sl_region_grow_config *cfg, sl_error *err)
{
    double lo = cfg->target_segments ? cfg->min_delta : cfg->delta_seg;
    double hi = cfg->target_segments ? cfg->max_delta : cfg->delta_seg;
    if (!(lo > 0.0 && hi <= SL_REGION_GROW_MAX_DELTA && lo <= hi))
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "region growing: delta_seg %g..%g degrees is outside (0, %g]", lo,
                            hi, SL_REGION_GROW_MAX_DELTA);
    return SL_OK;
}

static int check_positions(const sl_mesh_adjacency *adj, const float *positions, sl_error *err)
{
    for (uint64_t v = 0; v < adj->vertex_count; v++)
        if ((adj->vertex_flags[v] & SL_VERTEX_USED) &&
            !(isfinite(positions[3 * v]) && isfinite(positions[3 * v + 1]) &&
              isfinite(positions[3 * v + 2])))
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "region growing: vertex %llu has a non-finite coordinate",
                                (unsigned long long)v);
    return SL_OK;
}

int sl_region_grow(const sl_mesh_adjacency *adj, const float *positions,
                   const sl_region_grow_config *cfg, sl_segmentation *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    int rc = check_config(cfg, err);
    if (!rc)
        rc = check_positions(adj, positions, err);
    if (rc)
        return rc;
    uint32_t n = adj->triangle_count;
    size_t nn = n ? n : 1;
    grow_work w;
    memset(&w, 0, sizeof w);
    w.adj = adj;
    double *normals = malloc(3 * nn * sizeof *normals);
    uint32_t *order = malloc(nn * sizeof *order);
    w.stamp = malloc(nn * sizeof *w.stamp);
    uint32_t *label = malloc(nn * sizeof *label), *seeds = malloc(nn * sizeof *seeds);
    sl_normal_hull_init(&w.h);
    int ok = normals && order && w.stamp && label && seeds;
    if (ok) {
        sl_face_normals(adj, positions, normals);
        w.normals = normals;
        ok = seed_order(adj, normals, order) == 0;
        w.order = order;
    }
    int64_t count = -1;
    uint64_t without = 0;
    double delta = cfg->delta_seg;
    if (ok && !cfg->target_segments) {
        count = grow(&w, delta, label, seeds, &without);
    } else if (ok) { /* Min-delta: the smallest delta whose count is within the target */
        uint32_t target = cfg->target_segments;
        double lo = cfg->min_delta, hi = cfg->max_delta;
        delta = lo;
        count = grow(&w, lo, label, seeds, &without);
        if (count > (int64_t)target) {
            delta = hi;
            count = grow(&w, hi, label, seeds, &without);
            for (uint32_t step = 0; count >= 0 && count <= (int64_t)target &&
                                    step < cfg->search_steps; step++) {
                double mid = 0.5 * (lo + hi);
                int64_t c = grow(&w, mid, label, seeds, &without);
                if (c < 0)
                    count = -1;
                else if (c <= (int64_t)target)
                    hi = mid;
                else
                    lo = mid;
            }
            if (count >= 0 && count <= (int64_t)target) { /* hi's labels, grown again */
                delta = hi;
                count = grow(&w, hi, label, seeds, &without);
            }
        }
    }
    free(normals);
    free(order);
    free(w.stamp);
    sl_normal_hull_release(&w.h);
    free(w.f.e);
    if (count < 0) {
        free(label);
        free(seeds);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "region growing of %u triangles", n);
    }
    out->triangle_count = n;
    out->segment_count = (uint32_t)count;
    out->segment = label;
    uint32_t *shrunk = realloc(seeds, (count ? (size_t)count : 1) * sizeof *seeds);
    out->seed = shrunk ? shrunk : seeds;
    out->delta_seg = delta;
    out->without_normal = without;
    return SL_OK;
}
