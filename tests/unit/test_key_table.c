/* The radix sort of geometry/key_table.h: sorted by key, stable, the same bytes on any
 * thread count (the slices of the parallel passes: key_table.c), against a comparison
 * sort of (key, original index); and the key-only sort and sl_unique_keys. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/key_table.h"
#include "../check.h"

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static uint64_t next_random(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static int by_key_then_value(const void *a, const void *b)
{
    const sl_key_pair *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->value < y->value ? -1 : x->value > y->value;
}

/* n pairs with keys of `bits` bits drawn from `distinct` values (many equal keys: the
 * stability shows), values their original index. */
static sl_key_pair *random_pairs(size_t n, int bits, uint64_t distinct)
{
    sl_key_pair *p = malloc((n ? n : 1) * sizeof *p);
    uint64_t *pool = malloc(distinct * sizeof *pool);
    if (!p || !pool) {
        free(p);
        free(pool);
        return NULL;
    }
    uint64_t mask = bits == 64 ? ~0ull : (1ull << bits) - 1;
    for (uint64_t i = 0; i < distinct; i++)
        pool[i] = next_random() & mask;
    for (size_t i = 0; i < n; i++) {
        p[i].key = pool[next_random() % distinct];
        p[i].value = i;
    }
    free(pool);
    return p;
}

static void check_pairs(size_t n, int bits, uint64_t distinct)
{
    sl_key_pair *input = random_pairs(n, bits, distinct);
    CHECK(input != NULL);
    if (!input)
        return;
    sl_key_pair *want = malloc((n ? n : 1) * sizeof *want), *got = malloc((n ? n : 1) * sizeof *got);
    CHECK(want && got);
    if (want && got) {
        memcpy(want, input, n * sizeof *want);
        qsort(want, n, sizeof *want, by_key_then_value);
        for (int threads = 1; threads <= 3; threads++) {
            omp_set_num_threads(threads);
            memcpy(got, input, n * sizeof *got);
            CHECK(sl_sort_pairs(got, n, bits) == 0);
            CHECK_MSG(memcmp(got, want, n * sizeof *got) == 0,
                      "%zu pairs, %d-bit keys, %llu distinct, %d threads: not the stable order",
                      n, bits, (unsigned long long)distinct, threads);
        }
    }
    free(input);
    free(want);
    free(got);
}

static int by_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static void check_keys(size_t n)
{
    uint64_t *keys = malloc(n * sizeof *keys), *want = malloc(n * sizeof *want);
    CHECK(keys && want);
    if (keys && want) {
        for (size_t i = 0; i < n; i++)
            want[i] = keys[i] = next_random() % (n / 3 + 1); /* duplicates */
        qsort(want, n, sizeof *want, by_u64);
        omp_set_num_threads(2);
        CHECK(sl_sort_keys(keys, n, 64) == 0);
        CHECK(memcmp(keys, want, n * sizeof *keys) == 0);
        size_t unique = sl_unique_keys(keys, n), expect = n ? 1 : 0;
        for (size_t i = 1; i < n; i++)
            expect += want[i] != want[i - 1];
        CHECK_MSG(unique == expect, "%zu unique of %zu, expected %zu", unique, n, expect);
        int increasing = 1;
        for (size_t i = 1; i < unique; i++)
            increasing &= keys[i - 1] < keys[i];
        CHECK(increasing);
    }
    free(keys);
    free(want);
}

/* Short runs of every length up to 100 (insertion below 33, qsort above), with repeats,
 * against their counts: ascending, and the same multiset. */
static void check_runs(void)
{
    uint64_t state = 99, bad = 0;
    uint32_t a[100];
    uint64_t b[100];
    for (size_t n = 0; n <= 100; n++) {
        uint64_t sum_a = 0, sum_b = 0, after_a = 0, after_b = 0;
        for (size_t i = 0; i < n; i++) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            a[i] = (uint32_t)(state >> 59); /* 0..31: repeats */
            b[i] = state >> 1;
            sum_a += a[i], sum_b += b[i] & 0xffff;
        }
        sl_sort_run_u32(a, n);
        sl_sort_run_u64(b, n);
        for (size_t i = 0; i < n; i++) {
            after_a += a[i], after_b += b[i] & 0xffff;
            bad += i > 0 && (a[i - 1] > a[i] || b[i - 1] > b[i]);
        }
        bad += sum_a != after_a || sum_b != after_b;
    }
    CHECK_MSG(bad == 0, "short runs: %llu out of order or changed", (unsigned long long)bad);
}

int main(void)
{
    check_runs();
    check_pairs(0, 64, 1);
    check_pairs(1, 64, 1);
    check_pairs(1000, 62, 50);           /* one slice */
    check_pairs(300000, 62, 1000);       /* several slices: 4 passes of 16 bits */
    check_pairs(300001, 64, 300000);     /* all 64 bits */
    check_pairs(200000, 20, 7);          /* few distinct keys: long equal runs */
    check_pairs(250000, 64, 1);          /* one key: the input order is the answer */
    check_keys(400000);
    return check_report();
}
