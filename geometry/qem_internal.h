/* The simplifier's working state, shared by qem_setup.c (welding, classification, initial
 * quadrics), qem_collapse.c (the legality of one collapse), qem_apply.c (carrying it out),
 * qem_place.c (placement and cost), qem_queue.c and qem_heap.c (the queue) and
 * qem_simplify.c (the loop and the output). Not a public header.
 *
 * Words: a *wedge* is an input vertex (position + attributes); a *point* is a welded
 * position, holding one wedge or several (an attribute seam). Triangles refer to wedges;
 * topology is that of points. Each point keeps the corners of its triangles in a singly
 * linked list (corner c = 3 t + k); a collapse splices the removed point's list into the
 * survivor's, and dead triangles are unlinked lazily when a walk meets them.
 */
#ifndef SCANLOD_GEOMETRY_QEM_INTERNAL_H
#define SCANLOD_GEOMETRY_QEM_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "geometry/qef.h"
#include "geometry/qem_simplify.h"

#define QEM_NONE UINT32_MAX

enum qem_point_flags {
    QEM_LOCKED = 1u << 0,  /* never moves, never removed */
    QEM_BORDER = 1u << 1,  /* on an open border */
    QEM_SEAM = 1u << 2,    /* two or more wedges */
    QEM_DEAD = 1u << 3,    /* removed by a collapse */
    QEM_MOVED = 1u << 4,   /* no longer at its input position */
    QEM_BLOCKED = 1u << 5, /* a collapse of one of its edges was refused: retry when its
                              neighbourhood changes */
    QEM_COMPLEX = 1u << 6  /* locked for its non-manifold input alone: the relaxed phase
                              frees it (qem_relax.c) */
};

/* A welded position: everything a collapse reads of a point, in one 192-byte record
 * (three cache lines, 64-byte aligned). Why: the greedy order visits the surface at
 * random, so nearly every point a collapse touches is cold; in separate arrays each
 * field was a miss of its own (eight lines), here they come together. The first line
 * holds what the walks and the flip checks read of every neighbour; the quadric, read
 * when an edge is priced, fills the other two. */
typedef struct qem_point {
    double position[3];     /* relative to the origin */
    double normal[3];       /* area-weighted normal of the input surface merged into it
                               (which way is out) */
    uint32_t head;          /* first corner of its list */
    uint32_t stamp;         /* bumped when its edges' costs change */
    uint32_t mark;          /* scratch marks, compared with `generation` */
    uint8_t flags;          /* enum qem_point_flags */
    uint8_t pad0[3];
    sl_qef quadric;         /* relative to the origin */
    uint32_t wedge;         /* the wedge whose input position it had */
    uint8_t pad1[12];
} qem_point;
_Static_assert(sizeof(qem_point) == 192 && offsetof(qem_point, quadric) == 64,
               "a point is three cache lines, the hot fields in the first");

/* One queued collapse, 16 bytes (four siblings of the heap share a cache line): valid
 * while both points' stamps are unchanged. Stamps only grow, so their sum is unchanged
 * exactly when both are. The key is the priority (qem_priority) scaled by
 * 1 / diagonal^3 (area^1/2 times squared distance, made scale-free), in single precision. */
typedef struct qem_entry {
    float key;
    uint32_t a, b;          /* a < b */
    uint32_t stamps;        /* stamp[a] + stamp[b] when queued */
} qem_entry;

typedef struct qem_heap {
    void *block;            /* the allocation (64-byte aligned) */
    qem_entry *items;       /* block + 3 entries: each node's four children start a line */
    uint64_t size, cap;
} qem_heap;

#define QEM_BINS 32768u     /* queue bins: the top 16 bits of a non-negative float key */

typedef struct qem_bin {
    qem_entry *items;       /* unordered */
    uint32_t size, cap;
} qem_bin;

typedef struct qem_queue {
    qem_heap front;         /* the entries of bins up to `cursor`, in exact order */
    qem_bin *bins;          /* QEM_BINS: the entries of the later bins */
    uint32_t cursor;
    uint64_t bitmap[QEM_BINS / 64]; /* non-empty bins */
    uint64_t size;          /* entries held, stale ones included */
} qem_queue;

/* What a collapse of edge a-b would do, worked out by qem_plan_collapse(). */
enum qem_mode { QEM_ILLEGAL = 0, QEM_TO_A, QEM_TO_B, QEM_OPTIMAL };
enum qem_reject { QEM_REJECT_TOPOLOGY = 1, QEM_REJECT_FLIP, QEM_REJECT_SHAPE };

#define QEM_MAX_WEDGES 8 /* wedges a point may have and still move (more: locked) */
#define QEM_MAX_FLANKS 8 /* triangles on one edge a relaxed collapse may remove (strict: 2) */
#define QEM_MAX_CANCELLED 8 /* triangles a relaxed collapse makes coincident and removes */

typedef struct qem_plan {
    int mode;
    int reason;             /* enum qem_reject when mode is QEM_ILLEGAL, else 0 */
    uint32_t keep, gone;    /* survivor and removed point */
    double x[3];            /* the new position, relative to the origin */
    double cost;            /* quadric error at x, plus the attribute term */
    double priority;        /* the queue's order: cost / sqrt(merged area) */
    double error;           /* world: sqrt(quadric error / merged area) */
    uint32_t flank[QEM_MAX_FLANKS]; /* the triangles on the edge (1 on a border, 2 inside;
                                       more only in the relaxed phase) */
    int flank_count;
    uint32_t cancelled[QEM_MAX_CANCELLED]; /* relaxed phase: triangles of a and b that the
                                              collapse lays onto one another, removed */
    int cancelled_count;
    int breaks_topology;    /* relaxed rules: the strict ones would refuse it */
    int wedge_pairs;        /* gone's wedges and the keep wedge each one joins */
    uint32_t wedge_from[QEM_MAX_WEDGES], wedge_to[QEM_MAX_WEDGES];
} qem_plan;

typedef struct qem_state {
    const sl_qem_mesh *in;
    sl_qem_config cfg;
    uint32_t vertex_count, triangle_count, point_count;
    uint32_t *wedge_point;  /* vertex_count: point of each wedge, NONE if unused */
    uint32_t *corner_wedge; /* 3 * triangle_count: wedge at each corner; [3t] = NONE: dead */
    uint32_t *corner_next;  /* 3 * triangle_count: next corner of the same point */
    qem_point *point;       /* point_count */
    uint32_t generation;
    int attribute_count;    /* 0, 2 (uv), 4 (rgba) or 6 */
    double *attribute;      /* attribute_count per wedge: rgba / 255, then uv */
    double *field;          /* (1 + 4 attribute_count) per wedge: area, then per attribute
                               the area-weighted linear field g . x + g0 (Hoppe 1999) */
    double attribute_scale; /* cost per (area * attribute^2) */
    double origin[3];       /* world */
    double diagonal;        /* world */
    double key_scale;       /* queue key per unit of priority: 1 / diagonal^3 */
    uint64_t live_triangles;
    int relaxed;            /* the relaxed rules are in force (cfg.allow_topology_change) */
    uint64_t slack;         /* relaxed rules: how far below the target a collapse may land */
    int needles;            /* relaxed rules, last resort: the needle guard is off */
    qem_queue queue;
    sl_qem_stats stats;
} qem_state;

/* qem_setup.c */
/* The input's and the config's checks (sl_qem_simplify's errors). */
int qem_check_input(const sl_qem_mesh *in, const sl_qem_config *cfg, sl_error *err);
int qem_setup(qem_state *st, const sl_qem_mesh *in, const sl_qem_config *cfg, sl_error *err);
void qem_release(qem_state *st);

/* qem_collapse.c */
/* Priority of collapsing a-b judged from the points' flags and quadrics alone (no walk):
 * the queue's key. Returns INFINITY when the flags forbid it. */
double qem_estimate(const qem_state *st, uint32_t a, uint32_t b);
/* The full check of a collapse (topology, seams, flips, shapes) and its exact cost. */
void qem_plan_collapse(qem_state *st, uint32_t a, uint32_t b, qem_plan *plan);

/* The distinct wedges of p's live triangles, at most QEM_MAX_WEDGES + 1 of them. */
int qem_point_wedges(qem_state *st, uint32_t p, uint32_t *wedges);

/* qem_setup.c (with the flags it sets) */
/* Puts the relaxed rules in force: frees the points locked for their non-manifold input
 * alone (before the queue is filled: SL_QEM_TOPOLOGY_RELAX). */
void qem_relax_rules(qem_state *st);
/* The queue has run dry above the target: gives up the next rule the config allows (the
 * topology under SL_QEM_TOPOLOGY_RELAX_LAST, then the needle guard, then landing exactly)
 * and queues every edge again. 1 when it gave one up, 0 when none is left, -1 out of
 * memory. */
int qem_relax_further(qem_state *st); /* qem_simplify.c: the driver's */

/* qem_relax.c */
/* The relaxed phase's rule in place of the link condition, for an edge whose triangles
 * (plan->flank, flank_count) are known: finds the triangles the collapse would lay onto one
 * another (plan->cancelled) and refuses (0) when it would remove too many, or land more
 * than 1 % below the target. */
int qem_relaxed_condition(qem_state *st, uint32_t a, uint32_t b, qem_plan *plan);
/* Does the plan remove triangle t (an edge triangle or a cancelled one)? */
int qem_plan_removes(const qem_plan *plan, uint32_t t);

/* qem_apply.c */
/* Carries out a legal plan and queues the changed edges again. 0 or -1 (out of memory). */
int qem_apply(qem_state *st, const qem_plan *plan);
/* Queues every edge of point p except the one to `skip`; -1 when out of memory. */
int qem_push_point_edges(qem_state *st, uint32_t p, uint32_t skip);

/* A fresh mark value, `used` of them reserved (marks are reset before they wrap). */
static inline uint32_t qem_generation(qem_state *st, uint32_t used)
{
    if (st->generation > UINT32_MAX - 8) {
        for (uint32_t p = 0; p < st->point_count; p++)
            st->point[p].mark = 0;
        st->generation = 1;
    }
    uint32_t gen = st->generation;
    st->generation += used;
    return gen;
}

static inline uint32_t qem_corner_point(const qem_state *st, uint32_t c)
{
    return st->wedge_point[st->corner_wedge[c]];
}
static inline int qem_triangle_dead(const qem_state *st, uint32_t t)
{
    return st->corner_wedge[3 * t] == QEM_NONE;
}
/* The corner k steps after corner c in its triangle (k = 1, 2). */
static inline uint32_t qem_corner_after(uint32_t c, int k) { return c - c % 3 + (c % 3 + k) % 3; }
/* The next live corner of p's list after corner c (QEM_NONE: the first), unlinking the
 * dead ones it passes; QEM_NONE at the end. Every file walks the corner lists with it. */
static inline uint32_t qem_next_corner(qem_state *st, uint32_t p, uint32_t c)
{
    uint32_t *link = c == QEM_NONE ? &st->point[p].head : &st->corner_next[c];
    uint32_t n = *link;
    while (n != QEM_NONE && qem_triangle_dead(st, n / 3)) {
        n = st->corner_next[n];
        *link = n; /* unlink the dead corner: lists stay short */
    }
    return n;
}

/* The queue's order of a collapse of `cost` (area-weighted squared distance) over `area`:
 * cost / sqrt(area), between the integral of the squared distance (what an RMS distance
 * weighs; a thin feature of small area goes cheaply) and its mean (what a Hausdorff
 * distance feels; a large flat area goes late). Measured in docs/simplify.md. */
static inline double qem_priority(double cost, double area)
{
    return area > 0 ? cost / sqrt(area) : cost;
}

/* qem_place.c */
/* Position x (relative to the origin) of collapsing a-b in `mode`; returns the merged
 * quadric's error there (area-weighted squared distance). */
double qem_place(const qem_state *st, uint32_t a, uint32_t b, int mode, double x[3]);
/* The attribute term of a plan's cost (its wedge pairs and x filled in). */
double qem_attribute_cost(const qem_state *st, const qem_plan *plan);
/* The attributes of wedges `from` and `to` merged at x (attribute_count values). */
void qem_merged_attributes(const qem_state *st, uint32_t from, uint32_t to, const double x[3],
                           double *out);

/* qem_queue.c */
int qem_queue_init(qem_queue *q);
void qem_queue_free(qem_queue *q);
int qem_queue_push(qem_queue *q, const qem_entry *e);
/* 1: *out is the entry of least key (stale ones may come out: check them); 0: empty;
 * -1: out of memory. */
int qem_queue_pop(qem_queue *q, const qem_point *point, qem_entry *out);
/* Drops stale entries when they crowd the live ones (deterministic). */
void qem_queue_compact(qem_queue *q, const qem_point *point);

/* qem_heap.c */
/* Room for `cap` entries (keeps the ones held); -1 when out of memory. */
int qem_heap_reserve(qem_heap *h, uint64_t cap);
void qem_heap_free(qem_heap *h);
int qem_heap_push(qem_heap *h, const qem_entry *e);
void qem_heap_pop(qem_heap *h, qem_entry *out);
void qem_heap_build(qem_heap *h);
/* Drops stale entries (a dead point or a changed stamp) and rebuilds. */
void qem_heap_compact(qem_heap *h, const qem_point *point);
static inline int qem_entry_valid(const qem_entry *e, const qem_point *point)
{
    return point[e->a].stamp + point[e->b].stamp == e->stamps;
}
/* The queue key of a cost (finite costs stay finite). */
static inline float qem_key(const qem_state *st, double cost)
{
    double k = cost * st->key_scale;
    return k < 3.4e38 ? (float)k : 3.4e38f;
}
static inline qem_entry qem_make_entry(const qem_state *st, double priority, uint32_t a,
                                       uint32_t b)
{
    qem_entry e = {qem_key(st, priority), a, b, st->point[a].stamp + st->point[b].stamp};
    return e;
}

#endif
