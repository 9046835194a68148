/* The expansion order (paper 1, section 2.3; priority.h): a max-heap of the expandable
 * frontier nodes, restricted by the level-difference rule (a node waits while a coarser
 * neighbour is unexpanded). The keys it orders by: priority_metric.c. */
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

/* A coarser unexpanded node around n (the level-difference rule), or NONE. The nodes one
 * level up around n are n's parent (expanded) and its neighbours. */
static uint32_t blocker(const sl_octree *t, const sl_neighbours *nb, const uint32_t *expanded_at,
                        uint32_t n)
{
    const sl_octree_node *node = &t->nodes[n];
    if (node->parent == SL_OCTREE_NONE)
        return SL_OCTREE_NONE;
    const sl_octree_node *p = &t->nodes[node->parent];
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
        if (pd == 13)
            continue;
        uint32_t m = sl_neighbour(nb, node->parent, pd);
        if (m != SL_OCTREE_NONE && expanded_at[m] == SL_OCTREE_NONE)
            return m;
    }
    return SL_OCTREE_NONE;
}

enum { NOT_YET, IN_HEAP, WAITING, EXPANDED };

typedef struct order_state {
    heap_entry *heap;
    uint32_t size, cap;
    float *key;         /* current (possibly raised) key per node */
    uint8_t *state;
    uint32_t *wait_on;  /* WAITING: the node it waits on */
    uint32_t *wait_head, *wait_next;
} order_state;

static int push(order_state *o, uint32_t node, float key)
{
    if (o->size == o->cap) {
        uint32_t cap = o->cap * 2;
        heap_entry *h = realloc(o->heap, (size_t)cap * sizeof *h);
        if (!h)
            return -1;
        o->heap = h;
        o->cap = cap;
    }
    o->key[node] = key;
    o->state[node] = IN_HEAP;
    heap_push(o->heap, &o->size, (heap_entry){key, node});
    return 0;
}

/* Priority inheritance: node b holds back a node of key k, so b (and whatever holds b
 * back) is expanded no later than a node of key k would be. */
static int raise_key(order_state *o, uint32_t b, float k)
{
    while (o->key[b] < k) {
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
    uint32_t n = t->node_count, k = 0;
    size_t slots = n ? n : 1;
    order_state o = {malloc(slots * sizeof *o.heap), 0, (uint32_t)slots, malloc(slots * sizeof *o.key),
                     calloc(slots, 1), malloc(slots * sizeof *o.wait_on),
                     malloc(slots * sizeof *o.wait_head), malloc(slots * sizeof *o.wait_next)};
    uint32_t *expanded_at = malloc(slots * sizeof *expanded_at);
    int rc = !o.heap || !o.key || !o.state || !o.wait_on || !o.wait_head || !o.wait_next ||
             !expanded_at;
    if (!rc) {
        memset(expanded_at, 0xff, (size_t)n * sizeof *expanded_at);
        memset(o.wait_head, 0xff, (size_t)n * sizeof *o.wait_head);
        if (t->nodes[0].child_mask)
            rc = push(&o, 0, key[0]);
    }
    while (!rc && o.size > 0) {
        heap_entry top = heap_pop(o.heap, &o.size);
        uint32_t node = top.node;
        if (o.state[node] != IN_HEAP || top.key != o.key[node])
            continue; /* stale: the node was raised, or already expanded */
        uint32_t b = blocker(t, nb, expanded_at, node);
        if (b != SL_OCTREE_NONE) { /* wait until the coarser neighbour expands */
            o.state[node] = WAITING;
            o.wait_on[node] = b;
            o.wait_next[node] = o.wait_head[b];
            o.wait_head[b] = node;
            if (inherit)
                rc = raise_key(&o, b, o.key[node]);
            continue;
        }
        o.state[node] = EXPANDED;
        expanded_at[node] = k;
        lod_array[k++] = node;
        const sl_octree_node *p = &t->nodes[node];
        for (int c = 0; c < __builtin_popcount(p->child_mask) && !rc; c++) {
            uint32_t child = p->first_child + (uint32_t)c;
            if (t->nodes[child].child_mask)
                rc = push(&o, child, key[child]);
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
    free(expanded_at);
    if (rc)
        return sl_error_set(err, SL_E_NOMEM, ENOMEM, NULL, "out of memory ordering the LOD");
    uint32_t internal = 0;
    for (uint32_t i = 0; i < n; i++)
        internal += t->nodes[i].child_mask != 0;
    *expansion_count = k;
    if (k != internal)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL,
                            "expansion order stopped after %u of %u internal nodes", k, internal);
    return 0;
}
