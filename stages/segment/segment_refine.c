/* Greedy insertion into a patch's triangulation, one vertex at a time (rule error):
 * Garland and Heckbert (1995), algorithm III, with a data-dependent triangulation (Dyn,
 * Levin and Rippa, 1990). The patch starts as the CDT of its trimmed loops; each triangle
 * holds the removed vertices projecting into it and its score, the sum of their squared
 * distances to its plane (sums, not maxima: the RMS is what counts; docs/segmentation.md);
 * the worst triangle (a heap) gets its farthest vertex back (split in three, or in four
 * on an edge), its vertices are shared out, and edges are flipped while a flip lowers the
 * two triangles' score (or the Delaunay criterion asks, where they hold none), the quad
 * is convex in projection, the surface moves by at most flip_height and the normal check
 * passes. It stops when the worst score is at most tau. A triangle failing the normal
 * check goes first; one with no vertex to put back refuses the patch. The scores at
 * which vertices go back are recorded: one run tells the triangles of any smaller tau
 * (segment_levels.c).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/predicates.h"
#include "geometry/triangle_bvh.h"
#include "stages/segment/segment_internal.h"

#define NONE SEG_NONE
#define FLIPS_PER_INSERTION 256

static uint32_t nxt(uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
static uint32_t prv(uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }

typedef struct heap_entry {
    double score;
    uint32_t tri, version;
} heap_entry;

struct seg_refine {
    const double *uv, *pos, *h, *normal; /* per slot (borrowed) */
    double cos_max, flip_height;
    uint32_t nt, cap;
    uint32_t *tri, *twin;
    uint8_t *fixed;
    uint32_t *head, *worst, *version;
    double *score, *tn; /* per triangle: score (sum), unit normal (3) */
    uint8_t *bad;
    uint32_t *next, *in_tri; /* per slot */
    double *d2;              /* per slot */
    heap_entry *heap;
    uint64_t heap_count, heap_cap;
    uint32_t *stack;         /* legalisation: half-edges */
    uint32_t stack_count, stack_cap;
    uint32_t slots;
};

seg_refine *seg_refine_new(void)
{
    return calloc(1, sizeof(seg_refine));
}

void seg_refine_free(seg_refine *r)
{
    if (!r)
        return;
    free(r->tri);
    free(r->twin);
    free(r->fixed);
    free(r->head);
    free(r->worst);
    free(r->version);
    free(r->score);
    free(r->tn);
    free(r->bad);
    free(r->next);
    free(r->in_tri);
    free(r->d2);
    free(r->heap);
    free(r->stack);
    free(r);
}

#define GROWTO(ptr, n) ((ptr) = realloc((ptr), ((size_t)(n) > 0 ? (size_t)(n) : 1) * sizeof *(ptr)))

static int reserve(seg_refine *r, uint32_t triangles, uint32_t slots)
{
    if (triangles > r->cap) {
        uint32_t *t = realloc(r->tri, 3 * (size_t)triangles * sizeof *t);
        if (t)
            r->tri = t;
        uint32_t *w = realloc(r->twin, 3 * (size_t)triangles * sizeof *w);
        if (w)
            r->twin = w;
        if (!t || !w || !GROWTO(r->fixed, 3 * (size_t)triangles) || !GROWTO(r->head, triangles) ||
            !GROWTO(r->worst, triangles) || !GROWTO(r->version, triangles) ||
            !GROWTO(r->score, triangles) || !GROWTO(r->tn, 3 * (size_t)triangles) ||
            !GROWTO(r->bad, triangles))
            return -1;
        r->cap = triangles;
    }
    if (slots > r->slots) {
        if (!GROWTO(r->next, slots) || !GROWTO(r->in_tri, slots) || !GROWTO(r->d2, slots))
            return -1;
        r->slots = slots;
    }
    return 0;
}

/* --- the heap (largest score first; ties: lower triangle) ------------------------------ */

static int above(const heap_entry *a, const heap_entry *b)
{
    return a->score > b->score || (a->score == b->score && a->tri < b->tri);
}

static int heap_push(seg_refine *r, uint32_t t)
{
    if (r->heap_count == r->heap_cap) {
        uint64_t cap = r->heap_cap ? 2 * r->heap_cap : 256;
        heap_entry *e = realloc(r->heap, cap * sizeof *e);
        if (!e)
            return -1;
        r->heap = e;
        r->heap_cap = cap;
    }
    heap_entry x = {r->bad[t] && r->head[t] != NONE ? INFINITY : r->score[t], t, r->version[t]};
    uint64_t i = r->heap_count++;
    while (i > 0 && above(&x, &r->heap[(i - 1) / 2])) {
        r->heap[i] = r->heap[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    r->heap[i] = x;
    return 0;
}

static heap_entry heap_pop(seg_refine *r)
{
    heap_entry top = r->heap[0], x = r->heap[--r->heap_count];
    uint64_t i = 0;
    for (;;) {
        uint64_t c = 2 * i + 1;
        if (c >= r->heap_count)
            break;
        if (c + 1 < r->heap_count && above(&r->heap[c + 1], &r->heap[c]))
            c++;
        if (!above(&r->heap[c], &x))
            break;
        r->heap[i] = r->heap[c];
        i = c;
    }
    if (r->heap_count)
        r->heap[i] = x;
    return top;
}

/* --- triangles -------------------------------------------------------------------------- */

/* The unit normal of slots a b c, and whether it passes the normal check. */
static int plane_of(const seg_refine *r, uint32_t a, uint32_t b, uint32_t c, double n[3])
{
    const double *pa = r->pos + 3 * (size_t)a, *pb = r->pos + 3 * (size_t)b,
                 *pc = r->pos + 3 * (size_t)c;
    double u[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
    double w[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    int ok = len > 0;
    for (int k = 0; k < 3; k++)
        n[k] = ok ? n[k] / len : 0;
    /* against the mean of the input normals at its corners (one corner's normal alone
     * is too strict for a thin triangle along a curved boundary) */
    const double *na = r->normal + 3 * (size_t)a, *nb = r->normal + 3 * (size_t)b,
                 *nc = r->normal + 3 * (size_t)c;
    double m[3] = {na[0] + nb[0] + nc[0], na[1] + nb[1] + nc[1], na[2] + nb[2] + nc[2]};
    double ml = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    return ok && ml > 0 && (n[0] * m[0] + n[1] * m[1] + n[2] * m[2]) >= r->cos_max * ml;
}

/* Squared distance from slot q to the triangle of slots a b c (not its plane: a steep
 * triangle's plane can pass near a vertex that the triangle itself is far from). */
static double dist2(const seg_refine *r, uint32_t a, uint32_t b, uint32_t c, uint32_t q)
{
    double closest[3];
    return sl_closest_point_triangle(r->pos + 3 * (size_t)q, r->pos + 3 * (size_t)a,
                                     r->pos + 3 * (size_t)b, r->pos + 3 * (size_t)c, closest);
}

/* Recomputes triangle t's plane, its vertices' distances, score and worst; pushes it. */
static int refresh(seg_refine *r, uint32_t t)
{
    const uint32_t *c = r->tri + 3 * (size_t)t;
    double *n = r->tn + 3 * (size_t)t;
    r->bad[t] = !plane_of(r, c[0], c[1], c[2], n);
    double sum = 0, far = -1;
    uint32_t worst = NONE;
    for (uint32_t q = r->head[t]; q != NONE; q = r->next[q]) {
        r->in_tri[q] = t;
        r->d2[q] = dist2(r, c[0], c[1], c[2], q);
        sum += r->d2[q];
        if (r->d2[q] > far || (r->d2[q] == far && q < worst)) {
            far = r->d2[q];
            worst = q;
        }
    }
    r->score[t] = sum;
    r->worst[t] = worst;
    r->version[t]++;
    return r->head[t] != NONE ? heap_push(r, t) : 0;
}

static int inside(const seg_refine *r, uint32_t t, uint32_t q)
{
    const uint32_t *c = r->tri + 3 * (size_t)t;
    const double *p = r->uv + 2 * (size_t)q;
    return sl_orient2d(r->uv + 2 * (size_t)c[0], r->uv + 2 * (size_t)c[1], p) >= 0 &&
           sl_orient2d(r->uv + 2 * (size_t)c[1], r->uv + 2 * (size_t)c[2], p) >= 0 &&
           sl_orient2d(r->uv + 2 * (size_t)c[2], r->uv + 2 * (size_t)c[0], p) >= 0;
}

/* Shares the vertices of `list` out among triangles ts[0..n) (the first that holds one). */
static void share_out(seg_refine *r, uint32_t list, const uint32_t *ts, int n)
{
    for (int i = 0; i < n; i++)
        r->head[ts[i]] = NONE;
    while (list != NONE) {
        uint32_t nx = r->next[list];
        int i = 0;
        while (i < n - 1 && !inside(r, ts[i], list))
            i++;
        r->next[list] = r->head[ts[i]];
        r->head[ts[i]] = list;
        list = nx;
    }
}

static uint32_t take_lists(seg_refine *r, const uint32_t *ts, int n)
{
    uint32_t list = NONE;
    for (int i = 0; i < n; i++) {
        uint32_t q = r->head[ts[i]];
        while (q != NONE) {
            uint32_t nx = r->next[q];
            r->next[q] = list;
            list = q;
            q = nx;
        }
        r->head[ts[i]] = NONE;
    }
    return list;
}

static void set_tri(seg_refine *r, uint32_t t, uint32_t a, uint32_t b, uint32_t c)
{
    r->tri[3 * (size_t)t] = a;
    r->tri[3 * (size_t)t + 1] = b;
    r->tri[3 * (size_t)t + 2] = c;
}

/* Half-edge e (just rewritten) gets twin o (may be NONE) and flag f. */
static void pair_up(seg_refine *r, uint32_t e, uint32_t o, uint8_t f)
{
    r->twin[e] = o;
    r->fixed[e] = f;
    if (o != NONE) {
        r->twin[o] = e;
        r->fixed[o] = f;
    }
}

static int push_edge(seg_refine *r, uint32_t h)
{
    if (r->stack_count == r->stack_cap) {
        uint32_t cap = r->stack_cap ? 2 * r->stack_cap : 64;
        uint32_t *s = realloc(r->stack, cap * sizeof *s);
        if (!s)
            return -1;
        r->stack = s;
        r->stack_cap = cap;
    }
    r->stack[r->stack_count++] = h;
    return 0;
}

/* Flips the edge of half-edge h if the phase asks: inserting, the Delaunay criterion (well
 * shaped triangles, no thin one hiding the input); optimising, a lower score of the two,
 * the surface moving at most flip_height, the normal check passed. 1 flipped, 0 not, -1
 * out of memory. */
static int try_flip(seg_refine *r, uint32_t h, int optimise)
{
    uint32_t g = r->twin[h];
    if (g == NONE || r->fixed[h])
        return 0;
    uint32_t t1 = h / 3, t2 = g / 3;
    uint32_t a = r->tri[h], b = r->tri[nxt(h)], c = r->tri[prv(h)], d = r->tri[prv(g)];
    const double *ua = r->uv + 2 * (size_t)a, *ub = r->uv + 2 * (size_t)b,
                 *uc = r->uv + 2 * (size_t)c, *ud = r->uv + 2 * (size_t)d;
    if (sl_orient2d(ua, ud, uc) <= 0 || sl_orient2d(ud, ub, uc) <= 0)
        return 0; /* not strictly convex: the flip would fold */
    if (!optimise) {
        if (sl_incircle(ua, ub, uc, ud) <= 0)
            return 0; /* Delaunay already */
    } else {
        if (r->head[t1] == NONE && r->head[t2] == NONE)
            return 0; /* nothing to measure: stays Delaunay */
        double n1[3], n2[3];
        if (!plane_of(r, a, d, c, n1) || !plane_of(r, d, b, c, n2))
            return 0;
        /* the two surfaces differ most where the diagonals cross */
        double ex = ub[0] - ua[0], ey = ub[1] - ua[1], fx = ud[0] - uc[0], fy = ud[1] - uc[1];
        double den = ex * fy - ey * fx;
        if (den == 0)
            return 0;
        double s1 = ((uc[0] - ua[0]) * fy - (uc[1] - ua[1]) * fx) / den;
        double s2 = ((uc[0] - ua[0]) * ey - (uc[1] - ua[1]) * ex) / den;
        double hab = r->h[a] + s1 * (r->h[b] - r->h[a]), hcd = r->h[c] + s2 * (r->h[d] - r->h[c]);
        if (fabs(hab - hcd) > r->flip_height)
            return 0;
        double before = r->score[t1] + r->score[t2], after = 0;
        for (int side = 0; side < 2; side++)
            for (uint32_t q = r->head[side ? t2 : t1]; q != NONE; q = r->next[q])
                after += sl_orient2d(ud, uc, r->uv + 2 * (size_t)q) >= 0 ? dist2(r, a, d, c, q)
                                                                        : dist2(r, d, b, c, q);
        if (!(after < before * (1 - 1e-9)))
            return 0;
    }
    uint32_t o_bc = r->twin[nxt(h)], o_ca = r->twin[prv(h)], o_ad = r->twin[nxt(g)],
             o_db = r->twin[prv(g)];
    uint8_t f_bc = r->fixed[nxt(h)], f_ca = r->fixed[prv(h)], f_ad = r->fixed[nxt(g)],
            f_db = r->fixed[prv(g)];
    uint32_t ts[2] = {t1, t2};
    uint32_t list = take_lists(r, ts, 2);
    set_tri(r, t1, a, d, c); /* a->d, d->c, c->a */
    set_tri(r, t2, d, b, c); /* d->b, b->c, c->d */
    pair_up(r, 3 * t1, o_ad, f_ad);
    pair_up(r, 3 * t1 + 2, o_ca, f_ca);
    pair_up(r, 3 * t2, o_db, f_db);
    pair_up(r, 3 * t2 + 1, o_bc, f_bc);
    r->twin[3 * t1 + 1] = 3 * t2 + 2;
    r->twin[3 * t2 + 2] = 3 * t1 + 1;
    r->fixed[3 * t1 + 1] = r->fixed[3 * t2 + 2] = 0;
    share_out(r, list, ts, 2);
    if (refresh(r, t1) || refresh(r, t2))
        return -1;
    if (push_edge(r, 3 * t1) || push_edge(r, 3 * t1 + 2) || push_edge(r, 3 * t2) ||
        push_edge(r, 3 * t2 + 1))
        return -1;
    return 1;
}

static int legalize(seg_refine *r, int optimise, uint64_t max_flips)
{
    uint64_t flips = 0;
    while (r->stack_count && flips < max_flips) {
        int f = try_flip(r, r->stack[--r->stack_count], optimise);
        if (f < 0)
            return -1;
        flips += (uint64_t)f;
    }
    r->stack_count = 0;
    return 0;
}

/* --- insertion -------------------------------------------------------------------------- */

/* Removes q from triangle t's list (it cannot go back: it lies on a loop edge). */
static int drop_candidate(seg_refine *r, uint32_t t, uint32_t q)
{
    uint32_t *link_to = &r->head[t];
    while (*link_to != q)
        link_to = &r->next[*link_to];
    *link_to = r->next[q];
    r->in_tri[q] = NONE;
    return refresh(r, t);
}

/* Puts q (in triangle t) back. Returns 1 inserted, 0 not (dropped), -1 out of memory. */
static int insert(seg_refine *r, uint32_t t, uint32_t q)
{
    const double *p = r->uv + 2 * (size_t)q;
    uint32_t h0 = 3 * t, on = NONE;
    for (uint32_t e = h0; e < h0 + 3; e++) {
        int o = sl_orient2d(r->uv + 2 * (size_t)r->tri[e], r->uv + 2 * (size_t)r->tri[nxt(e)], p);
        if (o == 0)
            on = on == NONE ? e : UINT32_MAX - 1; /* two zeros: q is a corner's twin */
    }
    if (on == UINT32_MAX - 1 || (on != NONE && (r->fixed[on] || r->twin[on] == NONE)))
        return drop_candidate(r, t, q);
    if (on == NONE) { /* split t = (a, b, c) into (a, b, q), (b, c, q), (c, a, q) */
        uint32_t a = r->tri[h0], b = r->tri[h0 + 1], c = r->tri[h0 + 2];
        uint32_t o1 = r->twin[h0 + 1], o2 = r->twin[h0 + 2];
        uint8_t f1 = r->fixed[h0 + 1], f2 = r->fixed[h0 + 2];
        uint32_t t1 = r->nt++, t2 = r->nt++;
        uint32_t ts[3] = {t, t1, t2};
        uint32_t list = take_lists(r, ts, 1);
        set_tri(r, t, a, b, q);
        set_tri(r, t1, b, c, q);
        set_tri(r, t2, c, a, q);
        pair_up(r, 3 * t1, o1, f1);
        pair_up(r, 3 * t2, o2, f2);
        pair_up(r, 3 * t + 1, 3 * t1 + 2, 0);
        pair_up(r, 3 * t1 + 1, 3 * t2 + 2, 0);
        pair_up(r, 3 * t2 + 1, 3 * t + 2, 0);
        r->version[t1] = r->version[t2] = 0;
        for (uint32_t *l = &list; *l != NONE; l = &r->next[*l]) /* q itself leaves the list */
            if (*l == q) {
                *l = r->next[q];
                break;
            }
        share_out(r, list, ts, 3);
        for (int i = 0; i < 3; i++)
            if (refresh(r, ts[i]) || push_edge(r, 3 * ts[i]))
                return -1;
        return legalize(r, 0, FLIPS_PER_INSERTION) ? -1 : 1;
    }
    /* q on edge `on` = a->b of t, shared with u: four triangles */
    uint32_t g = r->twin[on], u = g / 3;
    uint32_t a = r->tri[on], b = r->tri[nxt(on)], c = r->tri[prv(on)], d = r->tri[prv(g)];
    uint32_t o_bc = r->twin[nxt(on)], o_ca = r->twin[prv(on)], o_ad = r->twin[nxt(g)],
             o_db = r->twin[prv(g)];
    uint8_t f_bc = r->fixed[nxt(on)], f_ca = r->fixed[prv(on)], f_ad = r->fixed[nxt(g)],
            f_db = r->fixed[prv(g)];
    uint32_t t3 = r->nt++, t4 = r->nt++;
    uint32_t ts[4] = {t, t3, u, t4};
    uint32_t list = take_lists(r, ts, 1);
    uint32_t ul = take_lists(r, ts + 2, 1);
    while (ul != NONE) {
        uint32_t nx = r->next[ul];
        r->next[ul] = list;
        list = ul;
        ul = nx;
    }
    for (uint32_t *l = &list; *l != NONE; l = &r->next[*l])
        if (*l == q) {
            *l = r->next[q];
            break;
        }
    set_tri(r, t, a, q, c);  /* a->q, q->c, c->a */
    set_tri(r, t3, q, b, c); /* q->b, b->c, c->q */
    set_tri(r, u, b, q, d);  /* b->q, q->d, d->b */
    set_tri(r, t4, q, a, d); /* q->a, a->d, d->q */
    r->version[t3] = r->version[t4] = 0;
    pair_up(r, 3 * t + 2, o_ca, f_ca);
    pair_up(r, 3 * t3 + 1, o_bc, f_bc);
    pair_up(r, 3 * u + 2, o_db, f_db);
    pair_up(r, 3 * t4 + 1, o_ad, f_ad);
    pair_up(r, 3 * t, 3 * t4, 0);
    pair_up(r, 3 * t3, 3 * u, 0);
    pair_up(r, 3 * t + 1, 3 * t3 + 2, 0);
    pair_up(r, 3 * u + 1, 3 * t4 + 2, 0);
    share_out(r, list, ts, 4);
    for (int i = 0; i < 4; i++)
        if (refresh(r, ts[i]))
            return -1;
    if (push_edge(r, 3 * t + 2) || push_edge(r, 3 * t3 + 1) || push_edge(r, 3 * u + 2) ||
        push_edge(r, 3 * t4 + 1))
        return -1;
    return legalize(r, 0, FLIPS_PER_INSERTION) ? -1 : 1;
}

typedef struct edge_key {
    uint64_t key;
    uint32_t half;
} edge_key;

static int cmp_edge_key(const void *x, const void *y)
{
    const edge_key *a = x, *b = y;
    return a->key != b->key ? (a->key > b->key) - (a->key < b->key)
                            : (a->half > b->half) - (a->half < b->half);
}

int seg_refine_start(seg_refine *r, const seg_refine_input *in)
{
    r->uv = in->uv;
    r->pos = in->pos;
    r->h = in->h;
    r->normal = in->normal;
    r->cos_max = in->cos_max_deviation;
    r->flip_height = in->flip_height;
    r->nt = in->triangle_count;
    r->heap_count = 0;
    r->stack_count = 0;
    if (reserve(r, in->triangle_count + 2 * in->candidate_count + 2, in->slot_count))
        return -1;
    memcpy(r->tri, in->triangles, 3 * (size_t)in->triangle_count * sizeof *r->tri);
    /* twins by sorting (undirected key, half-edge): an edge in two triangles is
     * inside; one in a single triangle is on a loop (fixed; the CDT refuses loops that
     * share an edge, so no loop edge has triangles on both sides) */
    uint64_t nh = 3 * (uint64_t)r->nt;
    edge_key *key = malloc((nh ? nh : 1) * sizeof *key);
    if (!key)
        return -1;
    for (uint64_t e = 0; e < nh; e++) {
        uint64_t a = r->tri[e], b = r->tri[nxt((uint32_t)e)];
        key[e].key = a < b ? a << 32 | b : b << 32 | a;
        key[e].half = (uint32_t)e;
        r->twin[e] = NONE;
        r->fixed[e] = 1;
    }
    qsort(key, nh, sizeof *key, cmp_edge_key);
    for (uint64_t i = 0; i + 1 < nh; i++)
        if (key[i].key == key[i + 1].key) {
            uint32_t e = key[i].half, f = key[i + 1].half;
            r->twin[e] = f;
            r->twin[f] = e;
            r->fixed[e] = r->fixed[f] = 0;
            i++;
        }
    free(key);
    for (uint32_t t = 0; t < r->nt; t++) {
        r->head[t] = NONE;
        r->version[t] = 0;
    }
    for (uint32_t i = in->candidate_count; i-- > 0;) {
        uint32_t q = in->candidates[i], t = in->candidate_tri[i];
        r->in_tri[q] = t;
        if (t == NONE)
            continue;
        r->next[q] = r->head[t];
        r->head[t] = q;
    }
    for (uint32_t t = 0; t < r->nt; t++)
        if (refresh(r, t))
            return -1;
    return 0;
}

uint64_t seg_refine_check(const seg_refine *r)
{
    uint64_t bad = 0;
    for (uint32_t t = 0; t < r->nt; t++) {
        const uint32_t *c = r->tri + 3 * (size_t)t;
        bad += sl_orient2d(r->uv + 2 * (size_t)c[0], r->uv + 2 * (size_t)c[1],
                           r->uv + 2 * (size_t)c[2]) <= 0;
        for (int k = 0; k < 3; k++) {
            uint32_t e = 3 * t + k, o = r->twin[e];
            if (o != NONE)
                bad += r->twin[o] != e || r->tri[o] != r->tri[nxt(e)] || r->tri[nxt(o)] != r->tri[e];
        }
        for (uint32_t q = r->head[t]; q != NONE; q = r->next[q])
            bad += !inside(r, t, q);
    }
    return bad;
}

int seg_refine_run(seg_refine *r, double tau, double *record, uint32_t *record_count,
                   uint32_t *inserted, uint32_t *inserted_count)
{
    uint32_t n = 0, rec = 0;
    while (r->heap_count) {
        heap_entry e = heap_pop(r);
        if (e.version != r->version[e.tri] || r->head[e.tri] == NONE)
            continue;
        if (e.score <= tau)
            break;
        uint32_t q = r->worst[e.tri];
        int rc = insert(r, e.tri, q);
        if (rc < 0)
            return -1;
        if (rc == 1) {
            if (inserted)
                inserted[n] = q;
            n++;
            if (record)
                record[rec++] = e.score;
        }
    }
    /* the final data-dependent pass: every interior edge once, then what flips reach */
    for (uint32_t e = 0; e < 3 * r->nt; e++)
        if (r->twin[e] != NONE && e < r->twin[e] && push_edge(r, e))
            return -1;
    if (legalize(r, 1, 20 * (uint64_t)r->nt + 100))
        return -1;
    if (inserted_count)
        *inserted_count = n;
    if (record_count)
        *record_count = rec;
    return 0;
}

uint32_t seg_refine_triangles(const seg_refine *r, const uint32_t **triangles)
{
    *triangles = r->tri;
    return r->nt;
}

int seg_refine_turned(const seg_refine *r, uint32_t corners[3])
{
    for (uint32_t t = 0; t < r->nt; t++)
        if (r->bad[t]) {
            memcpy(corners, r->tri + 3 * (size_t)t, 3 * sizeof *corners);
            return 1;
        }
    return 0;
}

double seg_refine_residual(const seg_refine *r)
{
    double sum = 0;
    for (uint32_t t = 0; t < r->nt; t++)
        sum += r->score[t];
    return sum;
}
