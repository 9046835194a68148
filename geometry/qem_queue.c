/* The collapse queue: exact priority order at nearly the cost of a bucket queue.
 *
 * Entries are binned by the top 16 bits of their (non-negative, single-precision) key,
 * which orders bins like keys. A cursor bin splits the queue: every entry of a bin at or
 * below it lives in `front`, a 4-ary heap (qem_heap.c) that gives the exact order (key,
 * then edge); the later bins are unsorted lists in a pool. A pop takes the front's
 * minimum; when the front runs dry the cursor moves to the next non-empty bin (a bitmap
 * scan that only ever moves forward) and that bin's entries, less the stale ones, are
 * heaped. A push at or below the cursor goes to the front, so the order stays exact even
 * for keys below ones already popped. Each later bin is an array of its own (read in one
 * sweep when opened: a linked list through a shared pool cost a cache miss per entry).
 *
 * Why: with one heap of all entries each pop walked ~10 levels of a tree far larger than
 * the cache, half the simplifier's time on a 270k-triangle scan; here a push is an append
 * and the heap holds one bin at a time.
 */
#include <stdlib.h>
#include <string.h>

#include "geometry/qem_internal.h"

static uint32_t bin_of(float key)
{
    uint32_t bits;
    memcpy(&bits, &key, sizeof bits);
    return bits >> 16; /* non-negative floats: bits order like values */
}

int qem_queue_init(qem_queue *q)
{
    memset(q, 0, sizeof *q);
    q->bins = calloc(QEM_BINS, sizeof *q->bins);
    return q->bins ? 0 : -1;
}

void qem_queue_free(qem_queue *q)
{
    qem_heap_free(&q->front);
    for (uint32_t i = 0; q->bins && i < QEM_BINS; i++)
        free(q->bins[i].items);
    free(q->bins);
    memset(q, 0, sizeof *q);
}

static int bin_append(qem_bin *b, const qem_entry *e)
{
    if (b->size == b->cap) {
        if (b->cap > UINT32_MAX / 2)
            return -1;
        uint32_t cap = b->cap ? 2 * b->cap : 16;
        qem_entry *items = realloc(b->items, (size_t)cap * sizeof *items);
        if (!items)
            return -1;
        b->items = items;
        b->cap = cap;
    }
    b->items[b->size++] = *e;
    return 0;
}

int qem_queue_push(qem_queue *q, const qem_entry *e)
{
    uint32_t bin = bin_of(e->key);
    if (bin <= q->cursor) {
        if (qem_heap_push(&q->front, e) != 0)
            return -1;
    } else {
        if (bin_append(&q->bins[bin], e) != 0)
            return -1;
        q->bitmap[bin / 64] |= 1ull << (bin % 64);
    }
    q->size++;
    return 0;
}

/* The first non-empty bin after the cursor, or QEM_BINS. */
static uint32_t next_bin(const qem_queue *q)
{
    uint32_t bin = q->cursor + 1;
    while (bin < QEM_BINS) {
        uint64_t word = q->bitmap[bin / 64] >> (bin % 64);
        if (word)
            return bin + (uint32_t)__builtin_ctzll(word);
        bin = (bin / 64 + 1) * 64;
    }
    return QEM_BINS;
}

/* Moves bin `bin`'s live entries into the (empty) front heap and frees the bin. */
static int open_bin(qem_queue *q, uint32_t bin, const qem_point *point)
{
    qem_bin *b = &q->bins[bin];
    if (qem_heap_reserve(&q->front, b->size) != 0)
        return -1;
    for (uint32_t i = 0; i < b->size; i++)
        if (qem_entry_valid(&b->items[i], point))
            q->front.items[q->front.size++] = b->items[i];
    q->size -= b->size - q->front.size;
    free(b->items);
    memset(b, 0, sizeof *b);
    q->bitmap[bin / 64] &= ~(1ull << (bin % 64));
    q->cursor = bin;
    qem_heap_build(&q->front);
    return 0;
}

int qem_queue_pop(qem_queue *q, const qem_point *point, qem_entry *out)
{
    while (q->front.size == 0) {
        uint32_t bin = next_bin(q);
        if (bin == QEM_BINS)
            return 0;
        if (open_bin(q, bin, point) != 0)
            return -1;
    }
    qem_heap_pop(&q->front, out);
    q->size--;
    return 1;
}

void qem_queue_compact(qem_queue *q, const qem_point *point)
{
    uint64_t before = q->front.size;
    qem_heap_compact(&q->front, point);
    q->size -= before - q->front.size;
    for (uint32_t bin = q->cursor + 1; bin < QEM_BINS; bin++) {
        qem_bin *b = &q->bins[bin];
        uint32_t kept = 0;
        for (uint32_t i = 0; i < b->size; i++)
            if (qem_entry_valid(&b->items[i], point))
                b->items[kept++] = b->items[i];
        q->size -= b->size - kept;
        b->size = kept;
        if (!kept) {
            free(b->items);
            memset(b, 0, sizeof *b);
            q->bitmap[bin / 64] &= ~(1ull << (bin % 64));
        }
    }
}
