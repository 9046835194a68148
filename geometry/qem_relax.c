/* The relaxed phase of the simplifier (sl_qem_config.allow_topology_change): what it lifts
 * and what it keeps.
 *
 * Why: a scan that is open and non-manifold (the segment and cluster methods' levels of
 * usnm_1145291: edges in three triangles, points with two fans, many holes and specks)
 * runs out of collapses that keep its topology well above a small budget, and a level
 * must have the count it was asked for (docs/simplify.md "Relaxed phase"). The phase
 * starts only there, so a level the strict rules reach is made exactly as before.
 *
 * Lifted, in the spirit of meshoptimizer's permissive mode (its "complex" vertices move
 * with all their wedges) and of its sloppy and prune modes (they give up topology for the
 * count), but keeping the greedy quadric order:
 *  - points locked for their non-manifold input alone move again; in the roles of
 *    qem_collapse.c they count as border points (they stay when the other end is plain);
 *  - the link condition: an edge may have up to QEM_MAX_FLANKS triangles (all removed), a
 *    hole of three edges, a handle or a lone triangle may close, two borders may join;
 *  - the border's role: when the preferred end cannot move without a flip, the other may
 *    (a border point into the interior).
 * Kept: the caller's locks (never moved, never left without a triangle) and points of
 * more than QEM_MAX_WEDGES wedges; the seam rules;
 * the flip, shape and texture checks on every triangle that remains; a valid mesh. The
 * collapse of a-b can make a triangle of a and one of b coincide (the same other two
 * points): facing opposite ways (a pocket or small component closing) both are removed,
 * facing the same way the one of b is. So no triangle repeats a point. A collapse lands at
 * most 1 % below the target (rounded down: exactly on a target under 100).
 * When even these rules run dry above the target, two more are given up, one at a time:
 * the needle guard (usnm_1145291 relaxed to 500 triangles stopped at 520 on it), then
 * the exact landing (one below, as the strict rules' last collapse may: a closed surface
 * has an even count).
 * This file holds the rule; the flags are changed by qem_relax_rules (qem_setup.c) and the
 * phase is driven by qem_relax_further (qem_simplify.c), so the collapse check consults
 * this file and nothing here calls back into it.
 */
#include "geometry/qem_internal.h"


int qem_plan_removes(const qem_plan *plan, uint32_t t)
{
    for (int i = 0; i < plan->flank_count; i++)
        if (plan->flank[i] == t)
            return 1;
    for (int i = 0; i < plan->cancelled_count; i++)
        if (plan->cancelled[i] == t)
            return 1;
    return 0;
}

static int cancelled(const qem_plan *plan, uint32_t t)
{
    for (int i = 0; i < plan->cancelled_count; i++)
        if (plan->cancelled[i] == t)
            return 1;
    return 0;
}

/* The triangle of b (off the edge, not matched yet) with the same other two points as
 * corner ca's triangle of a: *opposite set when it runs the other way. QEM_NONE: none. */
static uint32_t coincident(qem_state *st, uint32_t a, uint32_t b, uint32_t ca,
                           const qem_plan *plan, int *opposite)
{
    uint32_t q = qem_corner_point(st, qem_corner_after(ca, 1));
    uint32_t r = qem_corner_point(st, qem_corner_after(ca, 2));
    for (uint32_t c = qem_next_corner(st, b, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, b, c)) {
        uint32_t q2 = qem_corner_point(st, qem_corner_after(c, 1));
        uint32_t r2 = qem_corner_point(st, qem_corner_after(c, 2));
        if (q2 == a || r2 == a || cancelled(plan, c / 3))
            continue;
        if ((q == q2 && r == r2) || (q == r2 && r == q2)) {
            *opposite = q == r2;
            return c / 3;
        }
    }
    return QEM_NONE;
}

/* Does locked point p keep a live triangle the plan does not remove? */
static int keeps_a_triangle(qem_state *st, uint32_t p, const qem_plan *plan)
{
    for (uint32_t c = qem_next_corner(st, p, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, p, c))
        if (!qem_plan_removes(plan, c / 3))
            return 1;
    return 0;
}

/* No locked point (the caller's: a brick border) is left without a triangle: it must stay
 * in the output. */
static int locks_kept(qem_state *st, const qem_plan *plan)
{
    for (int i = 0; i < plan->flank_count + plan->cancelled_count; i++) {
        uint32_t t = i < plan->flank_count ? plan->flank[i]
                                           : plan->cancelled[i - plan->flank_count];
        for (uint32_t c = 3 * t; c < 3 * t + 3; c++) {
            uint32_t p = qem_corner_point(st, c);
            if ((st->point[p].flags & QEM_LOCKED) && !keeps_a_triangle(st, p, plan))
                return 0;
        }
    }
    return 1;
}

int qem_relaxed_condition(qem_state *st, uint32_t a, uint32_t b, qem_plan *plan)
{
    plan->cancelled_count = 0;
    for (uint32_t c = qem_next_corner(st, a, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, a, c)) {
        if (qem_corner_point(st, qem_corner_after(c, 1)) == b ||
            qem_corner_point(st, qem_corner_after(c, 2)) == b)
            continue; /* on the edge */
        int opposite = 0;
        uint32_t t = coincident(st, a, b, c, plan, &opposite);
        if (t == QEM_NONE)
            continue;
        if (plan->cancelled_count + 1 + opposite > QEM_MAX_CANCELLED)
            return 0;
        if (opposite)
            plan->cancelled[plan->cancelled_count++] = c / 3;
        plan->cancelled[plan->cancelled_count++] = t;
    }
    uint64_t target = st->cfg.target_triangles;
    uint64_t floor = target > st->slack ? target - st->slack : 0;
    uint64_t removed = (uint64_t)plan->flank_count + (uint64_t)plan->cancelled_count;
    return st->live_triangles >= removed + floor && locks_kept(st, plan);
}
