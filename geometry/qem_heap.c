/* The collapse queue: a 4-ary min-heap of (cost, edge, stamps), with lazy deletion. An
 * entry whose points' stamps have changed since it was pushed is stale and skipped when
 * popped; compaction drops them all when they outnumber the live ones. Ties in cost are
 * broken by the edge's point indices, so the order is total and the run deterministic.
 *
 * Why 4-ary with a bottom-up pop: popping is half the simplifier's time on a large mesh,
 * nearly all of it cache misses down the tree. Four children per node halve the depth
 * (the four siblings share one or two cache lines), and the pop first walks the hole
 * down to a leaf along the smallest children (no comparison with the moved element),
 * then sifts the last element up from there, which is short: it came from the bottom.
 */
#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/qem_internal.h"

static int entry_less(const qem_entry *x, const qem_entry *y)
{
    if (x->key != y->key)
        return x->key < y->key;
    if (x->a != y->a)
        return x->a < y->a;
    return x->b < y->b;
}

#define ARITY 4

static void sift_up(qem_entry *items, uint64_t i)
{
    qem_entry e = items[i];
    while (i > 0) {
        uint64_t parent = (i - 1) / ARITY;
        if (!entry_less(&e, &items[parent]))
            break;
        items[i] = items[parent];
        i = parent;
    }
    items[i] = e;
}

/* The smallest of the children of i (there is at least one). */
static uint64_t smallest_child(const qem_entry *items, uint64_t size, uint64_t i)
{
    uint64_t first = ARITY * i + 1, last = first + ARITY < size ? first + ARITY : size;
    uint64_t best = first;
    for (uint64_t c = first + 1; c < last; c++)
        if (entry_less(&items[c], &items[best]))
            best = c;
    return best;
}

static void sift_down(qem_entry *items, uint64_t size, uint64_t i)
{
    qem_entry e = items[i];
    while (ARITY * i + 1 < size) {
        uint64_t child = smallest_child(items, size, i);
        if (!entry_less(&items[child], &e))
            break;
        items[i] = items[child];
        i = child;
    }
    items[i] = e;
}

#ifndef NDEBUG
/* The heap order around slot i: its parent is not greater (a local check per operation;
 * the whole array is checked after every build). */
static int heap_ordered_at(const qem_heap *h, uint64_t i)
{
    return i == 0 || i >= h->size || !entry_less(&h->items[i], &h->items[(i - 1) / ARITY]);
}
#endif

int qem_heap_reserve(qem_heap *h, uint64_t cap)
{
    if (cap <= h->cap)
        return 0;
    size_t bytes = (size_t)(cap + 3) * sizeof(qem_entry);
    void *block = aligned_alloc(64, (bytes + 63) / 64 * 64);
    if (!block)
        return -1;
    qem_entry *items = (qem_entry *)block + 3;
    if (h->size)
        memcpy(items, h->items, h->size * sizeof *items);
    free(h->block);
    h->block = block;
    h->items = items;
    h->cap = cap;
    return 0;
}

void qem_heap_free(qem_heap *h)
{
    free(h->block);
    memset(h, 0, sizeof *h);
}

int qem_heap_push(qem_heap *h, const qem_entry *e)
{
    assert(e->key == e->key && e->a < e->b);
    /* Grows by half, and by at least 16: a heap opened on a bin of one entry has cap 1. */
    if (h->size == h->cap && qem_heap_reserve(h, h->cap ? h->cap + h->cap / 2 + 16 : 1024) != 0)
        return -1;
    h->items[h->size] = *e;
    sift_up(h->items, h->size++);
    return 0;
}

void qem_heap_pop(qem_heap *h, qem_entry *out)
{
    assert(h->size > 0);
    *out = h->items[0];
    uint64_t size = --h->size, hole = 0;
    if (size == 0)
        return;
    while (ARITY * hole + 1 < size) { /* the hole down to a leaf */
        uint64_t child = smallest_child(h->items, size, hole);
        h->items[hole] = h->items[child];
        hole = child;
    }
    h->items[hole] = h->items[size];
    sift_up(h->items, hole);
    assert(heap_ordered_at(h, 1) && heap_ordered_at(h, hole));
    assert(h->size == 0 || !entry_less(&h->items[0], out));
}

void qem_heap_build(qem_heap *h)
{
    if (h->size < 2)
        return;
    for (uint64_t i = (h->size - 2) / ARITY + 1; i-- > 0;) /* from the last parent up */
        sift_down(h->items, h->size, i);
#ifndef NDEBUG
    for (uint64_t i = 1; i < h->size; i++)
        assert(heap_ordered_at(h, i));
#endif
}

void qem_heap_compact(qem_heap *h, const qem_point *point)
{
    uint64_t kept = 0;
    for (uint64_t i = 0; i < h->size; i++) {
        const qem_entry *e = &h->items[i];
        if (qem_entry_valid(e, point) && !((point[e->a].flags | point[e->b].flags) & QEM_DEAD))
            h->items[kept++] = *e;
    }
    h->size = kept;
    qem_heap_build(h);
}
