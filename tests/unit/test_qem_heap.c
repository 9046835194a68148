/* The simplifier's queue heap (geometry/qem_heap.c) grown from the smallest capacity a bin
 * can open it with (one entry: the heap once grew by cap / 2 = 0 there and wrote past its
 * block, caught as a crash on cow's chained 1 % level), and popping in key order. */
#include "geometry/qem_internal.h"
#include "tests/check.h"

static void test_grow_from_one(void)
{
    qem_heap h = {0};
    CHECK(qem_heap_reserve(&h, 1) == 0 && h.cap == 1);
    for (int i = 0; i < 300; i++) { /* a scrambled order */
        qem_entry e = {(float)((i * 7919) % 300), (uint32_t)i, (uint32_t)i + 1, 0};
        CHECK(qem_heap_push(&h, &e) == 0);
        CHECK(h.size <= h.cap);
    }
    float last = 0;
    int ordered = 1;
    for (int i = 0; i < 300; i++) {
        qem_entry e;
        qem_heap_pop(&h, &e);
        ordered &= i == 0 || e.key >= last;
        last = e.key;
    }
    CHECK(ordered && h.size == 0);
    qem_heap_free(&h);
}

int main(void)
{
    test_grow_from_one();
    return check_report();
}
