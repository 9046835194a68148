/* Constrained Delaunay triangulation, part 2: forcing the loop edges in.
 *
 * Method (the cavity approach of Anglada, "An improved incremental algorithm for
 * constructing restricted Delaunay triangulations", Computers & Graphics 21(2), 1997):
 * for a loop edge a-b missing from the triangulation, walk from a to b collecting the
 * triangles the open segment crosses. They form a cavity whose boundary is two chains,
 * one left of the segment and one right of it. Each side, closed by the segment, is a
 * pseudo-polygon; it is triangulated by taking the chain vertex c whose circle through
 * a, b is empty of the other chain vertices (the one with the largest angle a c b: a
 * scan), cutting the triangle a b c off and recursing on the two sub-chains. The result
 * is the constrained Delaunay triangulation of each side, and the triangles outside the
 * cavity stay constrained Delaunay (a new constraint only hides points), so no flips are
 * needed afterwards. The new triangles reuse the cavity's slots (their count is the same).
 *
 * A side need not be a simple polygon: when the segment passes close to a point, it can
 * cross every triangle around it but one edge, and the chain then runs out to that point
 * and back along the same edge (a spike; the point is inside the side). The recursion
 * still triangulates it: a triangle covering the spike's tip would have the tip inside its
 * circumcircle, so the empty-circle choice never makes one. The two copies of the spike
 * edge are joined to each other instead of to the triangles beyond them, which are cavity
 * triangles themselves.
 *
 * A point exactly on the segment splits it: a-p is inserted, then p-b. Crossing an
 * already inserted loop edge refuses the input (the loops intersect); so does marking an
 * edge that is already a loop edge (two loop edges share a segment).
 */
#include <stdarg.h>
#include <stdlib.h>

#include "geometry/cdt_internal.h"
#include "geometry/predicates.h"

/* One side of a cavity: chain vertices v[0..len) from a to the segment's end, and for the
 * chain edge k (v[k] to v[k+1]) the triangle outside the cavity across it (its slot
 * there) and the edge's bits as the cavity triangle saw them: 1 loop edge, 2 forward,
 * 4 a spike (the triangle across is in the cavity too). */
typedef struct side {
    uint32_t len;
    uint32_t *v, *outer;
    uint8_t *outer_slot, *bits;
} side;

typedef struct cavity {
    uint32_t cap;            /* room in every array below */
    side left, right;
    uint32_t crossed;        /* triangles in w->crossed */
    uint32_t (*todo)[4];     /* pending sub-polygons: i, j, parent triangle, its slot */
    uint32_t (*spike)[4];    /* spike edges seen once: lower end, upper end, triangle, slot */
    uint32_t spikes;
} cavity;

/* The one way the triangulation refuses its input (cdt_internal.h): here, with the loops
 * that most refusals are about, so that cdt.c calls into this file and never the reverse. */
int cdt_refuse(cdt_work *w, int problem, uint32_t a, uint32_t b, uint32_t c, uint32_t d,
               const char *fmt, ...)
{
    w->report->problem = problem;
    w->report->v[0] = a, w->report->v[1] = b, w->report->v[2] = c, w->report->v[3] = d;
    va_list ap;
    va_start(ap, fmt);
    sl_error_setv(w->err, SL_E_BADINPUT, 0, NULL, fmt, ap);
    va_end(ap);
    return SL_E_BADINPUT;
}

static int grow_side(side *s, uint32_t cap)
{
    uint32_t *v = realloc(s->v, cap * sizeof *v), *outer;
    if (v)
        s->v = v;
    outer = v ? realloc(s->outer, cap * sizeof *outer) : NULL;
    if (outer)
        s->outer = outer;
    uint8_t *slot = outer ? realloc(s->outer_slot, cap) : NULL;
    if (slot)
        s->outer_slot = slot;
    uint8_t *bits = slot ? realloc(s->bits, cap) : NULL;
    if (bits)
        s->bits = bits;
    return bits != NULL;
}

/* Room for `need` entries per side and 2 * need pending sub-polygons. */
static int reserve(cdt_work *w, cavity *c, uint32_t need)
{
    if (need <= c->cap)
        return SL_OK;
    uint32_t cap = c->cap ? c->cap : 64;
    while (cap < need)
        cap *= 2;
    void *todo = grow_side(&c->left, cap) && grow_side(&c->right, cap)
                     ? realloc(c->todo, 2 * (uint64_t)cap * sizeof *c->todo)
                     : NULL;
    if (todo)
        c->todo = todo;
    void *spike = todo ? realloc(c->spike, 2 * (uint64_t)cap * sizeof *c->spike) : NULL;
    if (!spike)
        return sl_error_set(w->err, SL_E_NOMEM, 0, NULL, "loop edge insertion, %u triangles",
                            need);
    c->spike = spike;
    c->cap = cap;
    return SL_OK;
}

static void release_side(side *s)
{
    free(s->v);
    free(s->outer);
    free(s->outer_slot);
    free(s->bits);
}

/* Exactly collinear x lies on the ray from a through b (a != b). */
static int on_ray(const double *a, const double *b, const double *x)
{
    int axis = a[0] != b[0] ? 0 : 1;
    return b[axis] > a[axis] ? x[axis] > a[axis] : x[axis] < a[axis];
}

/* Marks edge `slot` of t, and its twin, as a loop edge; forward: the loop runs along t's
 * own direction. Refuses an edge that already is one. */
static int mark_loop_edge(cdt_work *w, uint32_t t, int slot, int forward, uint32_t from,
                          uint32_t to)
{
    cdt_tri *T = &w->tri[t];
    uint32_t p = T->v[(slot + 1) % 3], q = T->v[(slot + 2) % 3];
    if (T->flags & CDT_CONSTRAINED(slot))
        return cdt_refuse(w, SL_CDT_OVERLAP, p < q ? p : q, p < q ? q : p, CDT_NONE, CDT_NONE,
                          "the segment between points %u and %u belongs to two loop edges "
                          "(at loop edge %u-%u): a loop edge used twice, or collinear loop "
                          "edges overlapping",
                          p, q, from, to);
    T->flags |= CDT_CONSTRAINED(slot) | (forward ? CDT_FORWARD(slot) : 0);
    cdt_tri *U = &w->tri[T->n[slot]];
    int j = 3 - cdt_index_of(U, p) - cdt_index_of(U, q);
    U->flags |= CDT_CONSTRAINED(j) | (forward ? 0 : CDT_FORWARD(j));
    return SL_OK;
}

/* Turns around a for where the segment a->b leaves it: along an edge a->x of the
 * triangulation with x on the segment (x == b, or a point lying on it: OUT *x), or
 * through the interior of triangle *t = (a, right of the segment, left of it) (*x = NONE). */
static int leave_vertex(cdt_work *w, uint32_t a, uint32_t b, uint32_t *t, uint32_t *x)
{
    const double *pa = cdt_xy(w, a), *pb = cdt_xy(w, b);
    uint32_t first = w->vt[a], cur = first;
    const cdt_tri *T = &w->tri[cur];
    int sx = sl_orient2d(pa, pb, cdt_xy(w, T->v[(cdt_index_of(T, a) + 1) % 3]));
    for (uint32_t turns = 0; turns < w->tri_count; turns++) {
        T = &w->tri[cur];
        int k = cdt_index_of(T, a);
        uint32_t vx = T->v[(k + 1) % 3], vy = T->v[(k + 2) % 3];
        if (vx == b || (sx == 0 && on_ray(pa, pb, cdt_xy(w, vx)))) {
            *t = cur, *x = vx;
            return SL_OK;
        }
        int sy = sl_orient2d(pa, pb, cdt_xy(w, vy));
        if (sx < 0 && sy > 0) {
            *t = cur, *x = CDT_NONE;
            return SL_OK;
        }
        sx = sy;
        cur = T->n[(k + 1) % 3]; /* the next triangle counter-clockwise around a */
        if (cur == first || cur == CDT_NONE)
            break;
    }
    return sl_error_set(w->err, SL_E_INTERNAL, 0, NULL,
                        "loop edge %u-%u: no way out of point %u", a, b, a);
}

/* Appends vertex v to a side; the chain edge ending at v is edge `slot` of cavity triangle t. */
static void extend(cdt_work *w, side *s, uint32_t v, uint32_t t, int slot)
{
    const cdt_tri *T = &w->tri[t];
    uint32_t k = s->len - 1, o = T->n[slot];
    s->v[s->len++] = v;
    s->outer[k] = o;
    s->bits[k] = (uint8_t)((T->flags & CDT_CONSTRAINED(slot) ? 1 : 0) |
                           (T->flags & CDT_FORWARD(slot) ? 2 : 0));
    if (o != CDT_NONE) {
        const cdt_tri *O = &w->tri[o];
        uint32_t p = T->v[(slot + 1) % 3], q = T->v[(slot + 2) % 3];
        s->outer_slot[k] = (uint8_t)(3 - cdt_index_of(O, p) - cdt_index_of(O, q));
    }
}

/* Collects the triangles the open segment a->b crosses, starting at t = (a, r, l), and
 * the two chains; stops at b or at the first point on the segment (OUT: *end). */
static int walk(cdt_work *w, cavity *c, uint32_t a, uint32_t b, uint32_t t, uint32_t from,
                uint32_t to, uint32_t *end)
{
    const double *pa = cdt_xy(w, a), *pb = cdt_xy(w, b);
    int k = cdt_index_of(&w->tri[t], a);
    uint32_t r = w->tri[t].v[(k + 1) % 3], l = w->tri[t].v[(k + 2) % 3];
    c->left.len = c->right.len = 1;
    c->left.v[0] = c->right.v[0] = a;
    extend(w, &c->right, r, t, (k + 2) % 3);
    extend(w, &c->left, l, t, (k + 1) % 3);
    c->crossed = 0;
    w->crossed[c->crossed++] = t;
    w->tri[t].flags |= CDT_IN_CAVITY;
    for (;;) {
        const cdt_tri *T = &w->tri[t];
        int s = 3 - cdt_index_of(T, r) - cdt_index_of(T, l);
        if (T->flags & CDT_CONSTRAINED(s))
            return cdt_refuse(w, SL_CDT_CROSSING, from, to, r, l,
                              "loop edge %u-%u crosses the loop edge through points %u and %u "
                              "(self-intersecting loops, or a folded projection)",
                              from, to, r, l);
        uint32_t u = T->n[s];
        if (u == CDT_NONE)
            return sl_error_set(w->err, SL_E_INTERNAL, 0, NULL,
                                "loop edge %u-%u leaves the bounding triangle", from, to);
        int rc = reserve(w, c, c->crossed + 4);
        if (rc)
            return rc;
        w->crossed[c->crossed++] = u;
        w->tri[u].flags |= CDT_IN_CAVITY;
        const cdt_tri *U = &w->tri[u];
        int ir = cdt_index_of(U, r), il = cdt_index_of(U, l);
        uint32_t x = U->v[3 - ir - il];
        int side_of_x = x == b ? 0 : sl_orient2d(pa, pb, cdt_xy(w, x));
        if (side_of_x == 0) { /* b, or a point on the segment: the cavity closes */
            extend(w, &c->right, x, u, il);
            extend(w, &c->left, x, u, ir);
            *end = x;
            return SL_OK;
        }
        if (side_of_x > 0) {
            extend(w, &c->left, x, u, ir);
            l = x;
        } else {
            extend(w, &c->right, x, u, il);
            r = x;
        }
        t = u;
    }
}

static void link(cdt_work *w, uint32_t t, int slot, uint32_t u, int uslot)
{
    w->tri[t].n[slot] = u;
    if (u != CDT_NONE)
        w->tri[u].n[uslot] = t;
}

/* Edge p-q of new triangle t (its `slot`) is a spike: join it to the other copy, or keep it
 * until the other copy's triangle exists. */
static void join_spike(cdt_work *w, cavity *c, uint32_t p, uint32_t q, uint32_t t, int slot)
{
    uint32_t lo = p < q ? p : q, hi = p < q ? q : p;
    for (uint32_t k = 0; k < c->spikes; k++)
        if (c->spike[k][0] == lo && c->spike[k][1] == hi) {
            link(w, t, slot, c->spike[k][2], (int)c->spike[k][3]);
            c->spikes--;
            for (int f = 0; f < 4; f++)
                c->spike[k][f] = c->spike[c->spikes][f];
            return;
        }
    uint32_t *e = c->spike[c->spikes++];
    e[0] = lo, e[1] = hi, e[2] = t, e[3] = (uint32_t)slot;
}

/* Flags the chain edges whose triangle across is in the cavity too (spikes). */
static void find_spikes(const cdt_work *w, side *s)
{
    for (uint32_t k = 0; k + 1 < s->len; k++)
        if (s->outer[k] != CDT_NONE && (w->tri[s->outer[k]].flags & CDT_IN_CAVITY))
            s->bits[k] |= 4;
}

/* Chain position i of a side, read forwards or (for the right side) backwards, so that
 * the chain vertices lie left of the base from position 0 to position len - 1. */
static uint32_t at(const side *s, int reversed, uint32_t i)
{
    return s->v[reversed ? s->len - 1 - i : i];
}

/* Triangulates one side of the cavity into the next free cavity slots. OUT: *top, the
 * triangle on the segment (its edge 2). */
static int fill_side(cdt_work *w, cavity *c, const side *s, int reversed, uint32_t *next,
                     uint32_t *top)
{
    uint32_t sp = 0;
    c->todo[sp][0] = 0, c->todo[sp][1] = s->len - 1, c->todo[sp][2] = CDT_NONE;
    c->todo[sp++][3] = 0;
    while (sp > 0) {
        sp--;
        uint32_t i = c->todo[sp][0], j = c->todo[sp][1], parent = c->todo[sp][2];
        int pslot = (int)c->todo[sp][3];
        cdt_tri *P = parent == CDT_NONE ? NULL : &w->tri[parent];
        if (j == i + 1) { /* a chain edge: join the parent to the triangle outside */
            uint32_t e = reversed ? s->len - 2 - i : i;
            P->flags |= (s->bits[e] & 1 ? CDT_CONSTRAINED(pslot) : 0) |
                        (s->bits[e] & 2 ? CDT_FORWARD(pslot) : 0);
            if (s->bits[e] & 4)
                join_spike(w, c, s->v[e], s->v[e + 1], parent, pslot);
            else
                link(w, parent, pslot, s->outer[e], s->outer_slot[e]);
            continue;
        }
        const double *pi = cdt_xy(w, at(s, reversed, i)), *pj = cdt_xy(w, at(s, reversed, j));
        uint32_t best = CDT_NONE;
        for (uint32_t m = i + 1; m < j; m++) {
            const double *pm = cdt_xy(w, at(s, reversed, m));
            if (best == CDT_NONE ? sl_orient2d(pi, pj, pm) > 0
                                 : sl_incircle(pi, pj, cdt_xy(w, at(s, reversed, best)), pm) > 0 &&
                                       sl_orient2d(pi, pj, pm) > 0)
                best = m;
        }
        if (best == CDT_NONE || *next >= c->crossed)
            return sl_error_set(w->err, SL_E_INTERNAL, 0, NULL,
                                "loop edge insertion: no apex for a cavity side");
        uint32_t t = w->crossed[(*next)++];
        cdt_tri *T = &w->tri[t];
        T->v[0] = at(s, reversed, i), T->v[1] = at(s, reversed, j);
        T->v[2] = at(s, reversed, best);
        T->n[0] = T->n[1] = T->n[2] = CDT_NONE;
        T->flags = 0;
        for (int k = 0; k < 3; k++)
            w->vt[T->v[k]] = t;
        if (P) {
            T->n[2] = parent;
            P->n[pslot] = t;
        } else {
            *top = t;
        }
        uint32_t sub[2][4] = {{i, best, t, 1}, {best, j, t, 0}};
        for (int k = 0; k < 2; k++)
            for (int f = 0; f < 4; f++)
                c->todo[sp + k][f] = sub[k][f];
        sp += 2;
    }
    return SL_OK;
}

/* Replaces the cavity by the triangulations of its two sides, joined along a->end. */
static int fill_cavity(cdt_work *w, cavity *c)
{
    uint32_t next = 0, top_left = CDT_NONE, top_right = CDT_NONE;
    find_spikes(w, &c->left);
    find_spikes(w, &c->right);
    c->spikes = 0;
    int rc = fill_side(w, c, &c->left, 0, &next, &top_left);
    if (rc == SL_OK)
        rc = fill_side(w, c, &c->right, 1, &next, &top_right);
    if (rc == SL_OK && (next != c->crossed || c->spikes != 0))
        rc = sl_error_set(w->err, SL_E_INTERNAL, 0, NULL,
                          "loop edge insertion: %u cavity triangles, %u refilled, %u spike "
                          "edges unpaired", c->crossed, next, c->spikes);
    if (rc)
        return rc;
    /* Left: (a, end, apex), edge 2 runs a -> end, as the loop does; right: (end, a, apex). */
    w->tri[top_left].n[2] = top_right;
    w->tri[top_right].n[2] = top_left;
    w->tri[top_left].flags |= CDT_CONSTRAINED(2) | CDT_FORWARD(2);
    w->tri[top_right].flags |= CDT_CONSTRAINED(2);
    return SL_OK;
}

/* Inserts the loop edge from -> to, piece by piece where points lie on it. */
static int insert_loop_edge(cdt_work *w, cavity *c, uint32_t from, uint32_t to)
{
    uint32_t a = from;
    while (a != to) {
        uint32_t t = CDT_NONE, x = CDT_NONE, end = to;
        int rc = leave_vertex(w, a, to, &t, &x);
        if (rc == SL_OK && x != CDT_NONE) { /* along an existing edge a -> x */
            int k = cdt_index_of(&w->tri[t], a);
            rc = mark_loop_edge(w, t, (k + 2) % 3, 1, from, to);
            end = x;
        } else if (rc == SL_OK) {
            rc = walk(w, c, a, to, t, from, to, &end);
            if (rc == SL_OK)
                rc = fill_cavity(w, c);
        }
        if (rc)
            return rc;
        w->split_edges += end != to;
        a = end;
    }
    return SL_OK;
}

int cdt_insert_loops(cdt_work *w, const sl_cdt_input *in)
{
    cavity c = {0};
    int rc = reserve(w, &c, 64);
    for (uint32_t l = 0; l < in->loop_count && rc == SL_OK; l++) {
        uint32_t s = in->loop_start[l], len = in->loop_start[l + 1] - s;
        for (uint32_t k = 0; k < len && rc == SL_OK; k++) {
            uint32_t a = w->rep[in->loop_points[s + k]];
            uint32_t b = w->rep[in->loop_points[s + (k + 1) % len]];
            if (a != b)
                rc = insert_loop_edge(w, &c, a, b);
        }
    }
    release_side(&c.left);
    release_side(&c.right);
    free(c.todo);
    free(c.spike);
    return rc;
}
