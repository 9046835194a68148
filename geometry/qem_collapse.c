/* One edge collapse: is it legal, and carrying it out.
 *
 * Legality, in the order checked (docs/simplify.md):
 *  1. roles: a locked point stays; a border point stays unless the other is on the border
 *     too; a point moves only if each of its wedges lies on a triangle of the edge and
 *     maps to one wedge of the other point (so a seam point moves only along its seam, a
 *     point where seams meet or a seam meets a border never moves);
 *  2. the link condition of Dey, Edelsbrunner, Guha and Nekhayev, "Topology preserving
 *     edge contraction", 1999, with every open border closed by one virtual vertex: the
 *     points next to both a and b are exactly the edge's opposite points (so no edge gets
 *     a third triangle and no hole of three edges closes), two border points join only
 *     along a border edge (else the border would pinch), and no tetrahedron or lone
 *     triangle collapses into a flat pair or nothing;
 *  3. no remaining triangle of a or b turns its normal by more than ~75 degrees (the test
 *     meshoptimizer uses: a stricter one blocks collapses a chain of them would allow),
 *     faces away from the input its corners stand for, turns over in the texture, or
 *     becomes less compact than QEM_MIN_COMPACTNESS while being worse than it was.
 * Together they keep a manifold a manifold of the same genus, borders and components.
 * In the relaxed phase (qem_relax.c) rule 2 gives way to qem_relaxed_condition(), the
 * non-manifold points take the border's role in rule 1, and when the preferred end cannot
 * move without a flip the other end is tried (a border point may then leave its border).
 */
#include <assert.h>
#include <math.h>
#include <string.h>

#include "geometry/qem_internal.h"
#include "geometry/vec3.h"

#define QEM_FLIP_COS 0.25        /* new . old normal must exceed this * |new| |old| */
#define QEM_MIN_COMPACTNESS 0.05 /* 4 sqrt(3) area / sum of squared edges; 1 = equilateral */


/* Which end may move, from the flags alone: 1 = a may move, 2 = b may move. A point on a
 * border (relaxed: or non-manifold) stays when the other is not. */
static int movable_ends(const qem_state *st, uint32_t a, uint32_t b)
{
    uint8_t fa = st->point[a].flags, fb = st->point[b].flags;
    uint8_t edge = st->relaxed ? QEM_BORDER | QEM_COMPLEX : QEM_BORDER;
    int a_stays = (fa & QEM_LOCKED) || ((fa & edge) && !(fb & edge)) ||
                  ((fa & QEM_SEAM) && !(fb & QEM_SEAM));
    int b_stays = (fb & QEM_LOCKED) || ((fb & edge) && !(fa & edge)) ||
                  ((fb & QEM_SEAM) && !(fa & QEM_SEAM));
    int movable = (a_stays ? 0 : 1) | (b_stays ? 0 : 2);
    if (!movable && st->relaxed) /* the roles are a preference there: any unlocked end */
        movable = ((fa & QEM_LOCKED) ? 0 : 1) | ((fb & QEM_LOCKED) ? 0 : 2);
    return movable;
}

static int mode_of(int movable)
{
    static const int modes[4] = {QEM_ILLEGAL, QEM_TO_B, QEM_TO_A, QEM_OPTIMAL};
    return modes[movable & 3];
}

double qem_estimate(const qem_state *st, uint32_t a, uint32_t b)
{
    int mode = mode_of(movable_ends(st, a, b));
    double x[3];
    if (mode == QEM_ILLEGAL)
        return INFINITY;
    return qem_priority(qem_place(st, a, b, mode, x), st->point[a].quadric.area + st->point[b].quadric.area);
}

/* What the walks around a and b found. */
typedef struct edge_star {
    uint32_t flank[QEM_MAX_FLANKS], opposite[QEM_MAX_FLANKS]; /* triangles with a and b */
    uint32_t wedge_a[QEM_MAX_FLANKS], wedge_b[QEM_MAX_FLANKS]; /* their wedges at a and b */
    int flanks, triangles_a, triangles_b, common;
    int has_acd, has_bcd;            /* a / b has a triangle with both opposite points */
    uint32_t gen;                    /* a's neighbours are marked gen, counted ones gen + 1 */
} edge_star;

/* Walks a: marks its neighbours with `generation`, finds the edge's triangles. */
static void walk_first(qem_state *st, uint32_t a, uint32_t b, edge_star *s)
{
    uint32_t gen = s->gen;
    for (uint32_t c = qem_next_corner(st, a, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, a, c)) {
        s->triangles_a++;
        for (int k = 1; k <= 2; k++) {
            uint32_t q = qem_corner_point(st, qem_corner_after(c, k));
            st->point[q].mark = gen;
            if (q == b && s->flanks <= QEM_MAX_FLANKS) { /* (more: too many) */
                if (s->flanks < QEM_MAX_FLANKS) {
                    s->flank[s->flanks] = c / 3;
                    s->opposite[s->flanks] = qem_corner_point(st, qem_corner_after(c, 3 - k));
                    s->wedge_a[s->flanks] = st->corner_wedge[c];
                    s->wedge_b[s->flanks] = st->corner_wedge[qem_corner_after(c, k)];
                }
                s->flanks++;
            }
        }
    }
}

static int holds_both(const qem_state *st, uint32_t c, uint32_t x, uint32_t y)
{
    uint32_t p = qem_corner_point(st, qem_corner_after(c, 1)), q = qem_corner_point(st, qem_corner_after(c, 2));
    return (p == x && q == y) || (p == y && q == x);
}

/* Walks b: counts the points next to both (each once), and the tetrahedron pattern. */
static void walk_second(qem_state *st, uint32_t a, uint32_t b, edge_star *s)
{
    uint32_t gen = s->gen;
    for (uint32_t c = qem_next_corner(st, b, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, b, c)) {
        s->triangles_b++;
        for (int k = 1; k <= 2; k++) {
            uint32_t q = qem_corner_point(st, qem_corner_after(c, k));
            if (q != a && st->point[q].mark == gen) {
                st->point[q].mark = gen + 1; /* counted */
                s->common++;
            }
        }
        if (s->flanks == 2 && holds_both(st, c, s->opposite[0], s->opposite[1]))
            s->has_bcd = 1;
    }
    if (s->has_bcd) /* rare: only then look for the matching triangle of a */
        for (uint32_t c = qem_next_corner(st, a, QEM_NONE); c != QEM_NONE;
             c = qem_next_corner(st, a, c))
            s->has_acd |= holds_both(st, c, s->opposite[0], s->opposite[1]);
}

/* The link condition with borders closed by a virtual vertex (see the file comment). */
static int link_condition(const qem_state *st, uint32_t a, uint32_t b, const edge_star *s)
{
    if (s->flanks < 1 || s->flanks > 2 || s->common != s->flanks)
        return 0;
    if (s->flanks == 2) {
        int both_border = (st->point[a].flags & QEM_BORDER) && (st->point[b].flags & QEM_BORDER);
        return s->opposite[0] != s->opposite[1] && !both_border && !(s->has_acd && s->has_bcd);
    }
    return s->triangles_a > 1 || s->triangles_b > 1; /* not a lone triangle */
}

int qem_point_wedges(qem_state *st, uint32_t p, uint32_t *wedges)
{
    int n = 0;
    for (uint32_t c = qem_next_corner(st, p, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, p, c)) {
        uint32_t w = st->corner_wedge[c];
        int seen = 0;
        for (int i = 0; i < n && !seen; i++)
            seen = wedges[i] == w;
        if (!seen && n <= QEM_MAX_WEDGES)
            wedges[n++] = w;
    }
    return n;
}

/* Can `from` (wedges on the edge: own[], theirs at the other end: other[]) move onto the
 * other end? Each of its wedges must be on the edge and map to one wedge there. */
static int wedges_follow(qem_state *st, uint32_t from, const uint32_t *own, const uint32_t *other,
                         int flanks)
{
    for (int i = 1; i < flanks; i++)
        for (int j = 0; j < i; j++)
            if (own[i] == own[j] && other[i] != other[j])
                return 0; /* one wedge would split in two */
    if (!(st->point[from].flags & QEM_SEAM))
        return 1; /* its one wedge is on the edge */
    uint32_t wedges[QEM_MAX_WEDGES + 1];
    int n = qem_point_wedges(st, from, wedges);
    for (int i = 0; i < n; i++) {
        int on_edge = 0;
        for (int j = 0; j < flanks && !on_edge; j++)
            on_edge = wedges[i] == own[j];
        if (!on_edge)
            return 0; /* a wedge off the edge: moving would drag a seam across a chart */
    }
    return 1;
}

static void fill_wedge_pairs(qem_plan *plan, const edge_star *s)
{
    int gone_is_b = plan->mode != QEM_TO_B;
    plan->wedge_pairs = 0;
    for (int i = 0; i < s->flanks; i++) {
        uint32_t from = gone_is_b ? s->wedge_b[i] : s->wedge_a[i];
        uint32_t to = gone_is_b ? s->wedge_a[i] : s->wedge_b[i];
        int seen = 0; /* (wedges_follow made sure each maps to one) */
        for (int j = 0; j < plan->wedge_pairs && !seen; j++)
            seen = plan->wedge_from[j] == from;
        if (seen || plan->wedge_pairs == QEM_MAX_WEDGES)
            continue;
        plan->wedge_from[plan->wedge_pairs] = from;
        plan->wedge_to[plan->wedge_pairs++] = to;
    }
}

static void triangle_normal(const double p[3], const double q[3], const double r[3], double n[3])
{
    double e0[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    double e1[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    sl_cross3(e0, e1, n);
}

/* 4 sqrt(3) area / sum of squared edges: 1 for an equilateral triangle, 0 for a needle;
 * n is the triangle's (unnormalised) normal. */
static double compactness(const double p[3], const double q[3], const double r[3],
                          const double n[3])
{
    double sum = 0;
    for (int i = 0; i < 3; i++)
        sum += (q[i] - p[i]) * (q[i] - p[i]) + (r[i] - p[i]) * (r[i] - p[i]) +
               (r[i] - q[i]) * (r[i] - q[i]);
    return sum > 0 ? 2 * sqrt(3.0) * sqrt(sl_dot3(n, n)) / sum : 0;
}

/* Which way the surface faces at a triangle of q and r whose third corner is the merged
 * point of a and b: the sum of the three points' input normals. */
static void reference_normal(const qem_state *st, uint32_t a, uint32_t b, uint32_t q, uint32_t r,
                             double out[3])
{
    const qem_point *pt = st->point;
    for (int i = 0; i < 3; i++)
        out[i] = pt[a].normal[i] + pt[b].normal[i] + pt[q].normal[i] + pt[r].normal[i];
}

/* 0 when every remaining triangle of p keeps its side and shape with p at x; else the
 * reason (QEM_REJECT_FLIP or QEM_REJECT_SHAPE). A flip is a turn of more than ~75 degrees
 * in this collapse, or a normal against the input surface its corners stand for (turns
 * below 75 degrees each could add up to a fold over many collapses). */
static int fan_check(qem_state *st, const qem_plan *plan, uint32_t p, uint32_t other,
                     const double x[3])
{
    const double *pp = st->point[p].position;
    for (uint32_t c = qem_next_corner(st, p, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, p, c)) {
        uint32_t q = qem_corner_point(st, qem_corner_after(c, 1));
        uint32_t r = qem_corner_point(st, qem_corner_after(c, 2));
        if (q == other || r == other || (plan->cancelled_count && qem_plan_removes(plan, c / 3)))
            continue; /* removed with the edge */
        const double *pq = st->point[q].position, *pr = st->point[r].position;
        double n_old[3], n_new[3], ref[3];
        triangle_normal(pp, pq, pr, n_old);
        triangle_normal(x, pq, pr, n_new);
        double old2 = sl_dot3(n_old, n_old), dot = sl_dot3(n_old, n_new);
        reference_normal(st, p, other, q, r, ref);
        if ((old2 > 0 && dot <= QEM_FLIP_COS * sqrt(old2 * sl_dot3(n_new, n_new))) ||
            sl_dot3(n_new, ref) <= 0)
            return QEM_REJECT_FLIP;
        double after = compactness(x, pq, pr, n_new);
        if (after < QEM_MIN_COMPACTNESS && after < compactness(pp, pq, pr, n_old) &&
            !st->needles)
            return QEM_REJECT_SHAPE;
    }
    return 0;
}

/* The texture coordinates wedge w of a moving end takes in this collapse: the survivor's
 * wedge it joins, or (both ends moving) the merged field's value at x. */
static void new_texcoord(const qem_state *st, const qem_plan *plan, uint32_t w, double uv[2])
{
    int n = st->attribute_count, at = n - 2;
    const double *now = st->attribute + (uint64_t)w * n + at;
    double merged[6];
    for (int i = 0; i < plan->wedge_pairs; i++) {
        uint32_t from = plan->wedge_from[i], to = plan->wedge_to[i];
        if (w != from && w != to)
            continue;
        if (plan->mode == QEM_OPTIMAL) {
            qem_merged_attributes(st, from, to, plan->x, merged);
            now = merged + at;
        } else {
            now = st->attribute + (uint64_t)to * n + at;
        }
        break;
    }
    uv[0] = now[0];
    uv[1] = now[1];
}

static double texture_area(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* 0 when no remaining triangle of moving end p turns over in the texture (its texture
 * coordinates follow the wedge merge, so a triangle the surface keeps upright can still
 * fold in texture space); else QEM_REJECT_FLIP. */
static int texture_check(const qem_state *st, const qem_plan *plan, uint32_t p, uint32_t other)
{
    int n = st->attribute_count, at = n - 2;
    for (uint32_t c = st->point[p].head; c != QEM_NONE; c = st->corner_next[c]) {
        if (qem_triangle_dead(st, c / 3))
            continue;
        uint32_t q = qem_corner_after(c, 1), r = qem_corner_after(c, 2);
        if (qem_corner_point(st, q) == other || qem_corner_point(st, r) == other ||
            (plan->cancelled_count && qem_plan_removes(plan, c / 3)))
            continue;
        const double *uq = st->attribute + (uint64_t)st->corner_wedge[q] * n + at;
        const double *ur = st->attribute + (uint64_t)st->corner_wedge[r] * n + at;
        const double *uw = st->attribute + (uint64_t)st->corner_wedge[c] * n + at;
        double uv[2];
        new_texcoord(st, plan, st->corner_wedge[c], uv);
        double before = texture_area(uw, uq, ur), after = texture_area(uv, uq, ur);
        if (before != 0 && (before > 0) != (after > 0))
            return QEM_REJECT_FLIP;
    }
    return 0;
}

/* Of the ends in `movable`, those whose wedges may follow the collapse (wedges_follow). */
static int wedges_movable(qem_state *st, uint32_t a, uint32_t b, const edge_star *s, int movable)
{
    if ((movable & 1) && !wedges_follow(st, a, s->wedge_a, s->wedge_b, s->flanks))
        movable &= ~1;
    if ((movable & 2) && !wedges_follow(st, b, s->wedge_b, s->wedge_a, s->flanks))
        movable &= ~2;
    return movable;
}

/* An optimal placement that is exactly one endpoint is a half-edge collapse onto it: that
 * point and its wedges keep their input values (exact with optimal_placement = 0). */
static void settle_on_endpoint(const qem_state *st, uint32_t a, uint32_t b, qem_plan *plan)
{
    if (memcmp(plan->x, st->point[a].position, sizeof plan->x) == 0) {
        plan->mode = QEM_TO_A;
    } else if (memcmp(plan->x, st->point[b].position, sizeof plan->x) == 0) {
        plan->mode = QEM_TO_B;
        plan->keep = b;
        plan->gone = a;
    }
}

/* The plan in `mode`: position, cost, wedges, then the flip, shape and texture checks.
 * Returns 0 when it passes them, else the reason. */
static int try_mode(qem_state *st, uint32_t a, uint32_t b, const edge_star *s, int mode,
                    qem_plan *plan)
{
    plan->mode = mode;
    plan->keep = mode == QEM_TO_B ? b : a;
    plan->gone = mode == QEM_TO_B ? a : b;
    plan->cost = qem_place(st, a, b, plan->mode, plan->x);
    if (plan->mode == QEM_OPTIMAL) /* landed on an endpoint: the other one just moves there */
        settle_on_endpoint(st, a, b, plan);
    fill_wedge_pairs(plan, s);
    int reason = plan->mode != QEM_TO_B ? fan_check(st, plan, b, a, plan->x) : 0;
    if (!reason && plan->mode != QEM_TO_A)
        reason = fan_check(st, plan, a, b, plan->x);
    if (!reason && st->in->texcoords && plan->mode != QEM_TO_B)
        reason = texture_check(st, plan, b, a);
    if (!reason && st->in->texcoords && plan->mode != QEM_TO_A)
        reason = texture_check(st, plan, a, b);
    return reason;
}

/* Relaxed phase, the preferred end refused: the other single ends that may move, tried in
 * turn (a border or non-manifold point onto an interior one). 0 when one passes. */
static int try_other_ends(qem_state *st, uint32_t a, uint32_t b, const edge_star *s, int tried,
                          int reason, qem_plan *plan)
{
    int unlocked = ((st->point[a].flags & QEM_LOCKED) ? 0 : 1) |
                   ((st->point[b].flags & QEM_LOCKED) ? 0 : 2);
    int free = wedges_movable(st, a, b, s, unlocked);
    static const int modes[2] = {QEM_TO_A, QEM_TO_B}, needs[2] = {2, 1};
    for (int i = 0; i < 2 && reason; i++)
        if (modes[i] != tried && (free & needs[i]))
            reason = try_mode(st, a, b, s, modes[i], plan);
    return reason;
}

/* Would the strict rules move p (towards other)? Judged by the flags as they are now. */
static int strict_moves(const qem_state *st, uint32_t p, uint32_t other)
{
    uint8_t fp = st->point[p].flags, fo = st->point[other].flags;
    return !(fp & QEM_COMPLEX) && !((fp & QEM_BORDER) && !(fo & QEM_BORDER));
}

/* A relaxed plan the strict rules would refuse (what stats.relaxed_collapses counts). */
static int breaks_strict_rules(const qem_state *st, uint32_t a, uint32_t b, const edge_star *s,
                               const qem_plan *plan)
{
    return plan->cancelled_count > 0 || !link_condition(st, a, b, s) ||
           (plan->mode != QEM_TO_B && !strict_moves(st, b, a)) ||
           (plan->mode != QEM_TO_A && !strict_moves(st, a, b));
}

void qem_plan_collapse(qem_state *st, uint32_t a, uint32_t b, qem_plan *plan)
{
    memset(plan, 0, sizeof *plan);
    plan->reason = QEM_REJECT_TOPOLOGY;
    int movable = movable_ends(st, a, b);
    if (!movable)
        return;
    edge_star s;
    memset(&s, 0, sizeof s);
    s.gen = qem_generation(st, 2);
    walk_first(st, a, b, &s);
    walk_second(st, a, b, &s);
    if (s.flanks < 1 || s.flanks > QEM_MAX_FLANKS)
        return;
    plan->flank_count = s.flanks;
    memcpy(plan->flank, s.flank, sizeof plan->flank);
    if (st->relaxed ? !qem_relaxed_condition(st, a, b, plan) : !link_condition(st, a, b, &s))
        return;
    movable = wedges_movable(st, a, b, &s, movable);
    if (!movable)
        return;
    int reason = try_mode(st, a, b, &s, mode_of(movable), plan);
    if (reason && st->relaxed)
        reason = try_other_ends(st, a, b, &s, mode_of(movable), reason, plan);
    if (reason) {
        plan->mode = QEM_ILLEGAL;
        plan->reason = reason;
        return;
    }
    plan->reason = 0;
    plan->breaks_topology = st->relaxed && breaks_strict_rules(st, a, b, &s, plan);
    double area = st->point[a].quadric.area + st->point[b].quadric.area;
    plan->error = area > 0 ? sqrt(plan->cost / area) : 0;
    plan->cost += qem_attribute_cost(st, plan);
    plan->priority = qem_priority(plan->cost, area);
}
