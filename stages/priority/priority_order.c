/* The expansion order (paper 1, section 2.3; priority.h): a max-heap of the expandable
 * frontier nodes, restricted by the level-difference rule (a node waits while a coarser
 * neighbour is unexpanded). The keys it orders by: priority_metric.c. */
#include <assert.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "stages/priority/priority.h"

typedef struct heap_entry {
    float key;
    uint32_t node;
} heap_entry;

/* a before b: larger key first, then smaller index (deterministic). */
static int before(heap_entry a, heap_entry b)
{
    return a.key > b.key || (a.key == b.key && a.node < b.node);
}

static void heap_push(heap_entry *h, uint32_t *size, heap_entry e)
{
    uint32_t i = (*size)++;
    while (i > 0 && before(e, h[(i - 1) / 2])) {
        h[i] = h[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h[i] = e;
}

static heap_entry heap_pop(heap_entry *h, uint32_t *size)
{
    heap_entry top = h[0], last = h[--*size];
    uint32_t i = 0;
    for (;;) {
        uint32_t c = 2 * i + 1;
        if (c >= *size)
            break;
        if (c + 1 < *size && before(h[c + 1], h[c]))
            c++;
        if (!before(h[c], last))
            break;
        h[i] = h[c];
        i = c;
    }
    if (*size > 0)
        h[i] = last;
    return top;
}

/* The expansion order runs in *rank space*: the internal nodes (the only ones ever
 * expanded) numbered 0..count-1 in node order, so the rank order is the node order and
 * ties break the same way. Everything the sequential loop looks up is made beforehand, in
 * parallel: a node's internal children (their ranks are consecutive, since children are
 * contiguous nodes) and the coarser neighbours that can hold it back (the level-difference
 * rule), as ranks in the order the rule looks at them. The loop then touches a few small
 * arrays per expansion instead of node records and the neighbour table (at 20 M triangles
 * the order was 7-8 s, a third of the stage, all of it on one thread). */

/* A coarser neighbour without children: it never expands, so what waits on it waits for
 * ever (the order then stops short, an internal error, as the rule says). Not
 * SL_OCTREE_NONE, which `blocker` returns for "nothing holds it back". */
#define NEVER_EXPANDED (UINT32_MAX - 1)
#define COARSER_MAX 7 /* the parent's neighbours on a child's side: 2^3 - 1 directions */

typedef struct rank_tables {
    uint32_t count;
    uint32_t *node;          /* rank -> node */
    uint32_t *child_first;   /* rank of the first internal child */
    uint8_t *child_count;    /* internal children */
    uint8_t *blocker_count;  /* coarser neighbours, at most COARSER_MAX */
    uint32_t *blocker;       /* COARSER_MAX slots per rank: their ranks, or NEVER_EXPANDED */
} rank_tables;

static void rank_tables_release(rank_tables *r)
{
    free(r->node);
    free(r->child_first);
    free(r->child_count);
    free(r->blocker_count);
    free(r->blocker);
    memset(r, 0, sizeof *r);
}

/* The coarser neighbours around node n that the level-difference rule waits for, in the
 * rule's order (the 26 directions around n, each mapped to the parent's neighbour it falls
 * in; the first occurrence of each), as ranks into out. Returns how many. */
static uint32_t coarser_neighbours(const sl_octree *t, const sl_neighbours *nb, const uint32_t *rank_of,
                                   uint32_t n, uint32_t *out)
{
    const sl_octree_node *node = &t->nodes[n];
    if (node->parent == SL_OCTREE_NONE)
        return 0;
    const sl_octree_node *p = &t->nodes[node->parent];
    int seen[27] = {0};
    uint32_t count = 0;
    for (int d = 0; d < 27; d++) {
        if (d == 13)
            continue;
        int64_t q[3] = {(int64_t)node->x + d % 3 - 1, (int64_t)node->y + d / 3 % 3 - 1,
                        (int64_t)node->z + d / 9 - 1};
        int off[3];
        int64_t pc[3] = {p->x, p->y, p->z};
        for (int a = 0; a < 3; a++)
            off[a] = (int)((q[a] >= 0 ? q[a] / 2 : -1) - pc[a]);
        int pd = sl_direction(off[0], off[1], off[2]);
        if (pd == 13 || seen[pd])
            continue;
        seen[pd] = 1;
        uint32_t m = sl_neighbour(nb, node->parent, pd);
        if (m == SL_OCTREE_NONE)
            continue;
        assert(count < COARSER_MAX);
        out[count++] = rank_of[m];
    }
    return count;
}

static int rank_tables_build(const sl_octree *t, const sl_neighbours *nb, rank_tables *r)
{
    uint32_t n = t->node_count;
    memset(r, 0, sizeof *r);
    uint32_t *rank_of = malloc((n ? n : 1) * sizeof *rank_of);
    if (!rank_of)
        return -1;
    /* ranks by chunks: each chunk's internal nodes counted, the counts summed, the chunks
     * numbered from their sums (in parallel both times) */
    enum { RANK_CHUNK = 1 << 16 };
    uint32_t chunks = n / RANK_CHUNK + 1, count = 0;
    uint32_t *chunk_first = malloc(((size_t)chunks + 1) * sizeof *chunk_first);
    if (!chunk_first) {
        free(rank_of);
        return -1;
    }
#pragma omp parallel for schedule(static)
    for (uint32_t c = 0; c < chunks; c++) {
        uint32_t end = c == chunks - 1 ? n : (c + 1) * RANK_CHUNK, internal = 0;
        for (uint32_t i = c * RANK_CHUNK; i < end; i++)
            internal += t->nodes[i].child_mask != 0;
        chunk_first[c + 1] = internal;
    }
    chunk_first[0] = 0;
    for (uint32_t c = 0; c < chunks; c++)
        chunk_first[c + 1] += chunk_first[c];
    count = chunk_first[chunks];
    size_t slots = count ? count : 1;
    r->count = count;
    r->node = malloc(slots * sizeof *r->node);
    r->child_first = malloc(slots * sizeof *r->child_first);
    r->child_count = malloc(slots);
    r->blocker_count = malloc(slots);
    r->blocker = malloc(slots * COARSER_MAX * sizeof *r->blocker);
    int failed = !r->node || !r->child_first || !r->child_count || !r->blocker_count || !r->blocker;
    if (!failed) {
#pragma omp parallel for schedule(static)
        for (uint32_t c = 0; c < chunks; c++) {
            uint32_t end = c == chunks - 1 ? n : (c + 1) * RANK_CHUNK, k = chunk_first[c];
            for (uint32_t i = c * RANK_CHUNK; i < end; i++) {
                rank_of[i] = t->nodes[i].child_mask ? k : NEVER_EXPANDED;
                if (t->nodes[i].child_mask)
                    r->node[k++] = i;
            }
        }
#pragma omp parallel for schedule(dynamic, 4096)
        for (uint32_t k = 0; k < count; k++) {
            const sl_octree_node *node = &t->nodes[r->node[k]];
            uint32_t first = SL_OCTREE_NONE, internal = 0;
            for (int c = 0; c < __builtin_popcount(node->child_mask); c++) {
                uint32_t child = rank_of[node->first_child + (uint32_t)c];
                if (child != NEVER_EXPANDED) {
                    assert(first == SL_OCTREE_NONE || child == first + internal);
                    first = internal++ ? first : child;
                }
            }
            r->child_first[k] = first;
            r->child_count[k] = (uint8_t)internal;
            r->blocker_count[k] = (uint8_t)coarser_neighbours(t, nb, rank_of, r->node[k],
                                                              r->blocker + (size_t)COARSER_MAX * k);
        }
    }
    free(rank_of);
    free(chunk_first);
    if (failed)
        rank_tables_release(r);
    return failed ? -1 : 0;
}

enum { NOT_YET, IN_HEAP, WAITING, EXPANDED };

typedef struct order_state {
    heap_entry *heap;  /* entries name ranks */
    uint32_t size, cap;
    float *key;        /* current (possibly raised) key per rank */
    uint8_t *state;
    uint32_t *wait_on; /* WAITING: the rank it waits on, or NEVER_EXPANDED */
    uint32_t *wait_head, *wait_next;
} order_state;

/* A coarser unexpanded neighbour of rank k (the level-difference rule), or NONE. */
static uint32_t blocker(const rank_tables *r, const uint8_t *state, uint32_t k)
{
    const uint32_t *around = r->blocker + (size_t)COARSER_MAX * k;
    for (uint32_t i = 0; i < r->blocker_count[k]; i++) {
        uint32_t m = around[i];
        if (m == NEVER_EXPANDED || state[m] != EXPANDED)
            return m;
    }
    return SL_OCTREE_NONE;
}

static int push(order_state *o, uint32_t k, float key)
{
    if (o->size == o->cap) {
        uint32_t cap = o->cap * 2;
        heap_entry *h = realloc(o->heap, (size_t)cap * sizeof *h);
        if (!h)
            return -1;
        o->heap = h;
        o->cap = cap;
    }
    o->key[k] = key;
    o->state[k] = IN_HEAP;
    heap_push(o->heap, &o->size, (heap_entry){key, k});
    return 0;
}

/* Priority inheritance: rank b holds back a node of key k, so b (and whatever holds b
 * back) is expanded no later than a node of key k would be. A node not yet in the heap is
 * left alone: it enters with its own key when its parent expands (the order before rank
 * space wrote the raised key to a slot that push then overwrote). */
static int raise_key(order_state *o, uint32_t b, float k)
{
    while (b != NEVER_EXPANDED && o->state[b] != NOT_YET && o->key[b] < k) {
        if (o->state[b] == IN_HEAP)
            return push(o, b, k); /* the old entry goes stale */
        o->key[b] = k;
        if (o->state[b] != WAITING)
            return 0;
        b = o->wait_on[b];
    }
    return 0;
}

int sl_priority_order(const sl_octree *t, const sl_neighbours *nb, const float *key, int inherit,
                      uint32_t *lod_array, uint32_t *expansion_count, sl_error *err)
{
    rank_tables r;
    if (rank_tables_build(t, nb, &r))
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory ordering the LOD");
    uint32_t internal = r.count, k = 0;
    size_t slots = internal ? internal : 1;
    order_state o = {malloc(slots * sizeof *o.heap), 0, (uint32_t)slots, malloc(slots * sizeof *o.key),
                     calloc(slots, 1), malloc(slots * sizeof *o.wait_on),
                     malloc(slots * sizeof *o.wait_head), malloc(slots * sizeof *o.wait_next)};
    int rc = !o.heap || !o.key || !o.state || !o.wait_on || !o.wait_head || !o.wait_next;
    if (!rc) {
#pragma omp parallel for schedule(static)
        for (uint32_t i = 0; i < internal; i++)
            o.key[i] = key[r.node[i]]; /* each node's own key until it is raised */
        memset(o.wait_head, 0xff, slots * sizeof *o.wait_head);
        if (internal > 0 && r.node[0] == 0) /* the root, when it has children */
            rc = push(&o, 0, o.key[0]);
    }
    while (!rc && o.size > 0) {
        heap_entry top = heap_pop(o.heap, &o.size);
        uint32_t node = top.node;
        if (o.state[node] != IN_HEAP || top.key != o.key[node])
            continue; /* stale: the node was raised, or already expanded */
        uint32_t b = blocker(&r, o.state, node);
        if (b != SL_OCTREE_NONE) { /* wait until the coarser neighbour expands */
            o.state[node] = WAITING;
            o.wait_on[node] = b;
            if (b != NEVER_EXPANDED) {
                o.wait_next[node] = o.wait_head[b];
                o.wait_head[b] = node;
            }
            if (inherit)
                rc = raise_key(&o, b, o.key[node]);
            continue;
        }
        o.state[node] = EXPANDED;
        lod_array[k++] = r.node[node];
        for (uint32_t c = 0; c < r.child_count[node] && !rc; c++) {
            uint32_t child = r.child_first[node] + c;
            rc = push(&o, child, o.key[child]);
        }
        for (uint32_t w = o.wait_head[node]; w != SL_OCTREE_NONE && !rc; w = o.wait_next[w])
            rc = push(&o, w, o.key[w]);
        o.wait_head[node] = SL_OCTREE_NONE;
    }
    free(o.heap);
    free(o.key);
    free(o.state);
    free(o.wait_on);
    free(o.wait_head);
    free(o.wait_next);
    rank_tables_release(&r);
    if (rc)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory ordering the LOD");
    *expansion_count = k;
    if (k != internal)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL,
                            "expansion order stopped after %u of %u internal nodes", k, internal);
    return 0;
}
