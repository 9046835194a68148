/* Merging segments to a target count: the Min-delta side of the paper's segmentation
 * (section 3.1: "for a given number of segmented patches, minimise the angle threshold"),
 * by merging instead of regrowing.
 *
 * Why: every vertex on three or more segments is a corner that no level can remove.
 * Scans with noisy or small features (rocker_arm: 113 one-triangle segments at
 * delta_seg 60) get so many segments from equation 1 that their corners alone exceed a
 * small budget, whatever delta_seg (up to 89 degrees) is. So for a budget, the
 * segmentation of equation 1 is coarsened: adjacent segments are merged, the pair whose
 * union is flattest first, until the count fits the budget.
 *
 * Cost of merging A and B: the normal energy added, E(A u B) - E(A) - E(B) with
 * E(S) = sum of area_i (1 - n_i . m_S) = area(S) - |N_S| (N_S the area-weighted normal
 * sum, m_S = N_S / |N_S|), i.e. |N_A| + |N_B| - |N_A + N_B|: small for coplanar
 * neighbours and for small segments, large across a crease between large ones, so
 * creases go last. Constraint: every triangle of the union within max_angle (< 90) of
 * its mean normal, so the union still projects onto its plane without a triangle turning
 * over (what the retriangulation needs); checked on the union's extreme normals
 * (geometry/normal_hull.h), kept per segment. Heap order (cost, ids) with stale entries
 * skipped by version: deterministic.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/normal_hull.h"
#include "stages/segment/segment_internal.h"

typedef struct mseg {
    double N[3];        /* area-weighted normal sum */
    double *ext;        /* 3 per extreme normal */
    uint32_t ext_count;
    uint32_t *nb;       /* live neighbours */
    uint32_t nb_count, nb_cap;
    uint32_t version;
    uint32_t parent;
    int alive, mergeable;
} mseg;

typedef struct pair_entry {
    double cost;
    uint32_t a, b, va, vb;
} pair_entry;

typedef struct pair_heap {
    pair_entry *e;
    uint64_t count, cap;
} pair_heap;

static int entry_less(const pair_entry *x, const pair_entry *y)
{
    return x->cost < y->cost || (x->cost == y->cost && (x->a < y->a || (x->a == y->a && x->b < y->b)));
}

static int heap_push(pair_heap *h, pair_entry x)
{
    if (h->count == h->cap) {
        uint64_t cap = h->cap ? 2 * h->cap : 256;
        pair_entry *e = realloc(h->e, cap * sizeof *e);
        if (!e)
            return -1;
        h->e = e;
        h->cap = cap;
    }
    uint64_t i = h->count++;
    while (i > 0 && entry_less(&x, &h->e[(i - 1) / 2])) {
        h->e[i] = h->e[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h->e[i] = x;
    return 0;
}

static pair_entry heap_pop(pair_heap *h)
{
    pair_entry top = h->e[0], x = h->e[--h->count];
    uint64_t i = 0;
    for (;;) {
        uint64_t c = 2 * i + 1;
        if (c >= h->count)
            break;
        if (c + 1 < h->count && entry_less(&h->e[c + 1], &h->e[c]))
            c++;
        if (!entry_less(&h->e[c], &x))
            break;
        h->e[i] = h->e[c];
        i = c;
    }
    if (h->count)
        h->e[i] = x;
    return top;
}

static double norm3(const double *v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static double min_dot(const mseg *s, const double m[3])
{
    double lo = 1;
    for (uint32_t i = 0; i < s->ext_count; i++) {
        const double *n = s->ext + 3 * (size_t)i;
        double d = n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
        lo = d < lo ? d : lo;
    }
    return lo;
}

/* The cost of merging a and b, or -1 when the union breaks the angle constraint. */
static double merge_cost(const mseg *a, const mseg *b, double cos_max)
{
    double N[3] = {a->N[0] + b->N[0], a->N[1] + b->N[1], a->N[2] + b->N[2]};
    double len = norm3(N);
    if (!(len > 0))
        return -1;
    double m[3] = {N[0] / len, N[1] / len, N[2] / len};
    if (min_dot(a, m) < cos_max || min_dot(b, m) < cos_max)
        return -1;
    /* and the two parts' own mean normals within the angle of each other: two large
     * segments meeting at a crease of more than merge_angle stay apart however flat
     * each is (a cube's faces, a cylinder's caps and side) */
    double la = norm3(a->N), lb = norm3(b->N);
    if (la > 0 && lb > 0 &&
        (a->N[0] * b->N[0] + a->N[1] * b->N[1] + a->N[2] * b->N[2]) < cos_max * la * lb)
        return -1;
    return norm3(a->N) + norm3(b->N) - len;
}

/* The extreme normals of the given normals, in the chart of m, into s->ext. */
static int set_extremes(mseg *s, sl_normal_hull *h, const double m[3], const double *normals,
                        uint32_t count)
{
    sl_normal_hull_start(h, m);
    for (uint32_t i = 0; i < count; i++)
        if (sl_normal_hull_add(h, normals + 3 * (size_t)i, i))
            return -1;
    double *ext = malloc(3 * (size_t)(h->count ? h->count : 1) * sizeof *ext);
    if (!ext)
        return -1;
    memcpy(ext, h->n, 3 * (size_t)h->count * sizeof *ext);
    free(s->ext);
    s->ext = ext;
    s->ext_count = h->count;
    return 0;
}

static int add_neighbour(mseg *s, uint32_t c)
{
    for (uint32_t i = 0; i < s->nb_count; i++)
        if (s->nb[i] == c)
            return 0;
    if (s->nb_count == s->nb_cap) {
        uint32_t cap = s->nb_cap ? 2 * s->nb_cap : 8;
        uint32_t *nb = realloc(s->nb, cap * sizeof *nb);
        if (!nb)
            return -1;
        s->nb = nb;
        s->nb_cap = cap;
    }
    s->nb[s->nb_count++] = c;
    return 0;
}

static void remove_neighbour(mseg *s, uint32_t c)
{
    for (uint32_t i = 0; i < s->nb_count; i++)
        if (s->nb[i] == c) {
            s->nb[i] = s->nb[--s->nb_count];
            return;
        }
}

/* Per segment: normal sum, extreme normals, neighbours. */
static int init_segments(const sl_segment_model *m, const uint8_t *allowed, mseg *segs,
                         double *normals)
{
    uint32_t ns = m->seg.segment_count;
    sl_face_normals(&m->adj, m->positions, normals);
    int ok = 1;
    int64_t nsi = ns;
#pragma omp parallel
    {
        sl_normal_hull h;
        sl_normal_hull_init(&h);
        double *buf = NULL;
        uint32_t cap = 0;
#pragma omp for schedule(dynamic, 32)
        for (int64_t k = 0; k < nsi; k++) {
            mseg *s = &segs[k];
            uint32_t b = m->seg_tri_start[k], e = m->seg_tri_start[k + 1], n = 0;
            if (e - b > cap) {
                double *nb = realloc(buf, 3 * (size_t)(e - b) * sizeof *nb);
                if (!nb) {
#pragma omp atomic write
                    ok = 0;
                    continue;
                }
                buf = nb;
                cap = e - b;
            }
            for (uint32_t i = b; i < e; i++) {
                uint32_t t = m->seg_tris[i];
                const uint32_t *c = m->triangles + 3 * (uint64_t)t;
                double u[3], w[3];
                seg_sub(m->positions + 3 * (uint64_t)c[1], m->positions + 3 * (uint64_t)c[0], u);
                seg_sub(m->positions + 3 * (uint64_t)c[2], m->positions + 3 * (uint64_t)c[0], w);
                s->N[0] += u[1] * w[2] - u[2] * w[1];
                s->N[1] += u[2] * w[0] - u[0] * w[2];
                s->N[2] += u[0] * w[1] - u[1] * w[0];
                const double *fn = normals + 3 * (uint64_t)t;
                if (fn[0] != 0 || fn[1] != 0 || fn[2] != 0)
                    memcpy(buf + 3 * (size_t)n++, fn, 3 * sizeof *buf);
            }
            double len = norm3(s->N);
            s->mergeable = len > 0 && n == e - b && m->unfit[k] != SEG_UNFIT_NO_NORMAL &&
                           (!allowed || allowed[k]);
            if (!s->mergeable)
                continue;
            double mean[3] = {s->N[0] / len, s->N[1] / len, s->N[2] / len};
            int positive = 1;
            for (uint32_t i = 0; i < n && positive; i++)
                positive = buf[3 * i] * mean[0] + buf[3 * i + 1] * mean[1] + buf[3 * i + 2] * mean[2] > 0;
            if (!positive || set_extremes(s, &h, mean, buf, n))
                s->mergeable = 0;
        }
        free(buf);
        sl_normal_hull_release(&h);
    }
    for (uint64_t hh = 0; ok && hh < 3 * (uint64_t)m->triangle_count; hh++) {
        uint32_t tw = m->adj.twin[hh];
        if (tw == SEG_NONE)
            continue;
        uint32_t a = m->seg.segment[hh / 3], b = m->seg.segment[tw / 3];
        if (a != b && (add_neighbour(&segs[a], b) || add_neighbour(&segs[b], a)))
            ok = 0;
    }
    return ok ? 0 : -1;
}

static int push_pairs_of(pair_heap *heap, mseg *segs, uint32_t a, double cos_max)
{
    for (uint32_t i = 0; i < segs[a].nb_count; i++) {
        uint32_t c = segs[a].nb[i];
        if (!segs[c].mergeable)
            continue;
        double cost = merge_cost(&segs[a], &segs[c], cos_max);
        if (cost < 0)
            continue;
        uint32_t x = a < c ? a : c, y = a < c ? c : a;
        pair_entry e = {cost, x, y, segs[x].version, segs[y].version};
        if (heap_push(heap, e))
            return -1;
    }
    return 0;
}

/* Merges b into a. */
static int merge_into(mseg *segs, uint32_t a, uint32_t b, sl_normal_hull *h)
{
    mseg *A = &segs[a], *B = &segs[b];
    for (int k = 0; k < 3; k++)
        A->N[k] += B->N[k];
    double len = norm3(A->N), m[3] = {A->N[0] / len, A->N[1] / len, A->N[2] / len};
    uint32_t n = A->ext_count + B->ext_count;
    double *all = malloc(3 * (size_t)n * sizeof *all);
    if (!all)
        return -1;
    memcpy(all, A->ext, 3 * (size_t)A->ext_count * sizeof *all);
    memcpy(all + 3 * (size_t)A->ext_count, B->ext, 3 * (size_t)B->ext_count * sizeof *all);
    int rc = set_extremes(A, h, m, all, n);
    free(all);
    if (rc)
        return -1;
    for (uint32_t i = 0; i < B->nb_count; i++) {
        uint32_t c = B->nb[i];
        remove_neighbour(&segs[c], b);
        if (c != a && (add_neighbour(&segs[c], a) || add_neighbour(A, c)))
            return -1;
    }
    remove_neighbour(A, b);
    free(B->ext);
    free(B->nb);
    B->ext = NULL;
    B->nb = NULL;
    B->nb_count = B->ext_count = 0;
    B->alive = 0;
    B->parent = a;
    A->version++;
    return 0;
}

int seg_merge(const sl_segment_model *m, uint32_t target, double max_angle,
              const uint8_t *allowed, uint32_t **labels, uint32_t *count, sl_error *err)
{
    uint32_t ns = m->seg.segment_count;
    *labels = NULL;
    *count = ns;
    mseg *segs = calloc(ns ? ns : 1, sizeof *segs);
    double *normals = malloc(3 * (size_t)(m->triangle_count ? m->triangle_count : 1) * sizeof *normals);
    uint32_t *out = malloc((size_t)(m->triangle_count ? m->triangle_count : 1) * sizeof *out);
    uint32_t *renumber = malloc((ns ? ns : 1) * sizeof *renumber);
    pair_heap heap = {NULL, 0, 0};
    sl_normal_hull h;
    sl_normal_hull_init(&h);
    int rc = !segs || !normals || !out || !renumber ? -1 : 0;
    for (uint32_t k = 0; !rc && k < ns; k++) {
        segs[k].alive = 1;
        segs[k].parent = k;
    }
    if (!rc)
        rc = init_segments(m, allowed, segs, normals);
    double cos_max = cos(max_angle * (M_PI / 180.0));
    for (uint32_t a = 0; !rc && a < ns; a++)
        if (segs[a].mergeable)
            for (uint32_t i = 0; !rc && i < segs[a].nb_count; i++)
                if (segs[a].nb[i] > a && segs[segs[a].nb[i]].mergeable) {
                    uint32_t b = segs[a].nb[i];
                    double cost = merge_cost(&segs[a], &segs[b], cos_max);
                    pair_entry e = {cost, a, b, 0, 0};
                    if (cost >= 0 && heap_push(&heap, e))
                        rc = -1;
                }
    uint32_t alive = ns;
    while (!rc && alive > target && heap.count) {
        pair_entry e = heap_pop(&heap);
        if (!segs[e.a].alive || !segs[e.b].alive || segs[e.a].version != e.va ||
            segs[e.b].version != e.vb)
            continue;
        if (merge_into(segs, e.a, e.b, &h) || push_pairs_of(&heap, segs, e.a, cos_max))
            rc = -1;
        alive--;
    }
    if (!rc) { /* labels: each triangle's surviving segment, renumbered by first triangle */
        memset(renumber, 0xff, (ns ? ns : 1) * sizeof *renumber);
        uint32_t next = 0;
        for (uint32_t t = 0; t < m->triangle_count; t++) {
            uint32_t k = m->seg.segment[t];
            while (segs[k].parent != k)
                k = segs[k].parent;
            if (renumber[k] == SEG_NONE)
                renumber[k] = next++;
            out[t] = renumber[k];
        }
        *labels = out;
        *count = next;
        out = NULL;
    }
    for (uint32_t k = 0; segs && k < ns; k++) {
        free(segs[k].ext);
        free(segs[k].nb);
    }
    free(segs);
    free(normals);
    free(out);
    free(renumber);
    free(heap.e);
    sl_normal_hull_release(&h);
    return rc ? sl_error_set(err, SL_E_NOMEM, 0, NULL, "merging %u segments", ns) : SL_OK;
}
