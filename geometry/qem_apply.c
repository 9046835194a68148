/* Carrying out a collapse that qem_plan_collapse() found legal, and queueing edges.
 *
 * The edge's triangles die; the removed point's corners take the survivor's wedges (the
 * plan's wedge pairs) and its corner list is spliced onto the survivor's; quadrics and
 * attribute fields add up. Only the survivor's edges change cost (their quadrics changed),
 * so its stamp is bumped and its edges queued again; a neighbour whose collapse was refused
 * earlier (QEM_BLOCKED) is queued again too, since its surroundings just changed.
 */
#include <assert.h>
#include <math.h>
#include <string.h>

#include "geometry/qem_internal.h"


static uint32_t wedge_target(const qem_plan *plan, uint32_t w)
{
    for (int i = 0; i < plan->wedge_pairs; i++)
        if (plan->wedge_from[i] == w)
            return plan->wedge_to[i];
    assert(!"a wedge of the removed point has no pair");
    return plan->wedge_to[0];
}

/* Gives the removed point's corners the survivor's wedges and splices its list on. */
static void move_corners(qem_state *st, const qem_plan *plan)
{
    uint32_t last = QEM_NONE;
    for (uint32_t c = qem_next_corner(st, plan->gone, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, plan->gone, c)) {
        st->corner_wedge[c] = wedge_target(plan, st->corner_wedge[c]);
        last = c;
    }
    if (last != QEM_NONE) {
        st->corner_next[last] = st->point[plan->keep].head;
        st->point[plan->keep].head = st->point[plan->gone].head;
    }
    st->point[plan->gone].head = QEM_NONE;
}

static void merge_attributes(qem_state *st, const qem_plan *plan)
{
    int n = st->attribute_count, stride = 1 + 4 * n;
    for (int i = 0; i < plan->wedge_pairs; i++) {
        uint32_t from = plan->wedge_from[i], to = plan->wedge_to[i];
        if (plan->mode == QEM_OPTIMAL) /* before the fields add: the plan priced it so */
            qem_merged_attributes(st, from, to, plan->x, st->attribute + (uint64_t)to * n);
        double *ft = st->field + (uint64_t)to * stride;
        const double *ff = st->field + (uint64_t)from * stride;
        for (int k = 0; k < stride; k++)
            ft[k] += ff[k];
    }
}

/* The survivor's position; it keeps an input position (and which) when x is one. */
static void move_point(qem_state *st, const qem_plan *plan)
{
    double *pk = st->point[plan->keep].position;
    const double *pg = st->point[plan->gone].position;
    if (memcmp(plan->x, pk, 3 * sizeof *pk) == 0)
        return;
    if (memcmp(plan->x, pg, 3 * sizeof *pg) == 0) {
        st->point[plan->keep].flags = (uint8_t)((st->point[plan->keep].flags & ~QEM_MOVED) |
                                          (st->point[plan->gone].flags & QEM_MOVED));
        st->point[plan->keep].wedge = st->point[plan->gone].wedge;
    } else {
        st->point[plan->keep].flags |= QEM_MOVED;
    }
    memcpy(pk, plan->x, 3 * sizeof *pk);
}

static int push_edge(qem_state *st, uint32_t p, uint32_t q)
{
    uint32_t a = p < q ? p : q, b = p < q ? q : p;
    double priority = qem_estimate(st, a, b);
    if (!isfinite(priority))
        return 0;
    qem_entry e = qem_make_entry(st, priority, a, b);
    if (qem_queue_push(&st->queue, &e) != 0)
        return -1;
    st->stats.queued++;
    return 0;
}

/* Neighbours are gathered first and their quadrics prefetched, so the cache misses of
 * pricing ~8 edges overlap instead of following one another (the walk itself is a chain
 * of dependent loads that cannot be). */
int qem_push_point_edges(qem_state *st, uint32_t p, uint32_t skip)
{
    enum { RING = 64 };
    uint32_t ring[RING];
    int n = 0;
    uint32_t gen = qem_generation(st, 1);
    for (uint32_t c = qem_next_corner(st, p, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, p, c))
        for (int k = 1; k <= 2; k++) {
            uint32_t q = qem_corner_point(st, qem_corner_after(c, k));
            if (q == skip || st->point[q].mark == gen)
                continue;
            st->point[q].mark = gen;
            if (n < RING) {
                ring[n++] = q;
                __builtin_prefetch(&st->point[q].quadric);
                __builtin_prefetch((const char *)&st->point[q].quadric + 64);
            } else if (push_edge(st, p, q) != 0) {
                return -1;
            }
        }
    for (int i = 0; i < n; i++)
        if (push_edge(st, p, ring[i]) != 0)
            return -1;
    return 0;
}

#ifndef NDEBUG
/* No edge of p is in more than two live triangles (the link condition's promise; a
 * locked point may sit on a non-manifold edge of the input). */
static int fan_is_manifold(qem_state *st, uint32_t p)
{
    for (uint32_t c = qem_next_corner(st, p, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, p, c)) {
        uint32_t q = qem_corner_point(st, qem_corner_after(c, 1));
        int count = 0;
        for (uint32_t d = qem_next_corner(st, p, QEM_NONE); d != QEM_NONE;
             d = qem_next_corner(st, p, d))
            count += qem_corner_point(st, qem_corner_after(d, 1)) == q ||
                     qem_corner_point(st, qem_corner_after(d, 2)) == q;
        if (count > 2)
            return 0;
    }
    return 1;
}
#endif

/* Queues the survivor's edges, and those of refused neighbours. */
static int requeue(qem_state *st, uint32_t keep)
{
    uint32_t ring[64];
    int n = 0;
    uint32_t gen = qem_generation(st, 1);
    for (uint32_t c = qem_next_corner(st, keep, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, keep, c))
        for (int k = 1; k <= 2; k++) {
            uint32_t q = qem_corner_point(st, qem_corner_after(c, k));
            if (st->point[q].mark != gen && (st->point[q].flags & QEM_BLOCKED) && n < 64) {
                st->point[q].flags &= (uint8_t)~QEM_BLOCKED;
                st->point[q].stamp++;
                ring[n++] = q;
            }
            st->point[q].mark = gen;
        }
    if (qem_push_point_edges(st, keep, QEM_NONE) != 0)
        return -1;
    for (int i = 0; i < n; i++)
        if (qem_push_point_edges(st, ring[i], keep) != 0)
            return -1;
    return 0;
}

/* The edge's triangles die, and in the relaxed phase those laid onto one another. */
static void remove_triangles(qem_state *st, const uint32_t *list, int count)
{
    for (int i = 0; i < count; i++) {
        assert(!qem_triangle_dead(st, list[i]));
        st->corner_wedge[3 * list[i]] = QEM_NONE;
    }
    assert(st->live_triangles >= (uint64_t)count);
    st->live_triangles -= (uint64_t)count;
}

int qem_apply(qem_state *st, const qem_plan *plan)
{
    assert(plan->mode != QEM_ILLEGAL && plan->flank_count >= 1 &&
           plan->flank_count <= (st->relaxed ? QEM_MAX_FLANKS : 2));
    remove_triangles(st, plan->flank, plan->flank_count);
    remove_triangles(st, plan->cancelled, plan->cancelled_count);
    if (st->attribute_count)
        merge_attributes(st, plan);
    move_corners(st, plan);
    move_point(st, plan);
    sl_qef_add(&st->point[plan->keep].quadric, &st->point[plan->gone].quadric);
    for (int i = 0; i < 3; i++)
        st->point[plan->keep].normal[i] += st->point[plan->gone].normal[i];
    int seams = (st->point[plan->keep].flags | st->point[plan->gone].flags) & QEM_SEAM;
    st->point[plan->keep].flags |= st->point[plan->gone].flags & (QEM_BORDER | QEM_COMPLEX);
    st->point[plan->gone].flags = QEM_DEAD;
    uint32_t wedges[QEM_MAX_WEDGES + 1];
    if (seams && qem_point_wedges(st, plan->keep, wedges) == 1) /* the seam ended here */
        st->point[plan->keep].flags &= (uint8_t)~QEM_SEAM;
    st->point[plan->gone].stamp++;
    st->point[plan->keep].stamp++;
    st->point[plan->keep].flags &= (uint8_t)~QEM_BLOCKED;
    st->stats.collapses++;
    st->stats.relaxed_collapses += (uint64_t)plan->breaks_topology;
    st->stats.cancelled_triangles += (uint64_t)plan->cancelled_count;
    st->stats.last_error = plan->error;
    assert(st->relaxed || (st->point[plan->keep].flags & QEM_LOCKED) ||
           fan_is_manifold(st, plan->keep));
    return requeue(st, plan->keep);
}
