/* LSD radix sort on 64-bit keys, 16 bits per pass, in parallel slices (see key_table.h). One routine serves
 * bare keys and (key, value) pairs: an element is `size` bytes whose first 8 are the key. */
#include "geometry/key_table.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define RADIX_BITS 16
#define RADIX (1u << RADIX_BITS)

static uint64_t key_at(const unsigned char *base, size_t i, size_t size)
{
    uint64_t key;
    memcpy(&key, base + i * size, sizeof key);
    return key;
}

/* One pass: the elements of src by the 16 bits at `shift`, stably into dst. With several
 * threads each takes a fixed slice of src: the slices' histograms, prefixed bucket by
 * bucket and slice by slice, place every element exactly where the one-slice pass would
 * (a stable order is unique), so the result does not depend on the thread count. */
static void radix_pass(const unsigned char *src, unsigned char *dst, size_t count, size_t size,
                       int shift, size_t *histograms, int slices)
{
#pragma omp parallel for schedule(static) num_threads(slices)
    for (int t = 0; t < slices; t++) {
        size_t *h = histograms + (size_t)t * RADIX;
        memset(h, 0, RADIX * sizeof *h);
        for (size_t i = count * (size_t)t / (size_t)slices;
             i < count * (size_t)(t + 1) / (size_t)slices; i++)
            h[(key_at(src, i, size) >> shift) & (RADIX - 1)]++;
    }
    size_t sum = 0;
    for (size_t b = 0; b < RADIX; b++)
        for (int t = 0; t < slices; t++) {
            size_t c = histograms[(size_t)t * RADIX + b];
            histograms[(size_t)t * RADIX + b] = sum;
            sum += c;
        }
#pragma omp parallel for schedule(static) num_threads(slices)
    for (int t = 0; t < slices; t++) {
        size_t *h = histograms + (size_t)t * RADIX;
        for (size_t i = count * (size_t)t / (size_t)slices;
             i < count * (size_t)(t + 1) / (size_t)slices; i++) {
            size_t to = h[(key_at(src, i, size) >> shift) & (RADIX - 1)]++;
            memcpy(dst + to * size, src + i * size, size);
        }
    }
}

static int radix_sort(void *data, size_t count, size_t size, int bits)
{
    if (count < 2)
        return 0;
    /* A slice per thread, of at least 64 Ki elements (below that the histogram dominates). */
    int slices = omp_in_parallel() ? 1 : omp_get_max_threads();
    if ((size_t)slices > count / 65536)
        slices = count / 65536 > 0 ? (int)(count / 65536) : 1;
    unsigned char *tmp = malloc(count * size);
    size_t *histograms = malloc((size_t)slices * RADIX * sizeof *histograms);
    if (!tmp || !histograms) {
        free(tmp);
        free(histograms);
        return -1;
    }
    unsigned char *src = data, *dst = tmp;
    for (int shift = 0; shift < bits; shift += RADIX_BITS) {
        radix_pass(src, dst, count, size, shift, histograms, slices);
        unsigned char *swap = src;
        src = dst;
        dst = swap;
    }
    if (src != (unsigned char *)data)
        memcpy(data, src, count * size);
    free(tmp);
    free(histograms);
    return 0;
}

int sl_sort_pairs(sl_key_pair *pairs, size_t count, int bits)
{
    return radix_sort(pairs, count, sizeof *pairs, bits);
}

int sl_sort_keys(uint64_t *keys, size_t count, int bits)
{
    return radix_sort(keys, count, sizeof *keys, bits);
}

/* One body for both widths: T the element type, CMP its qsort comparison. */
#define SORT_RUN(T, CMP, v, n)                                                                    \
    do {                                                                                       \
        if ((n) > 32) {                                                                        \
            qsort((v), (n), sizeof(T), CMP);                                                   \
            break;                                                                             \
        }                                                                                      \
        for (size_t i = 1; i < (n); i++) {                                                     \
            T x = (v)[i];                                                                      \
            size_t j = i;                                                                      \
            for (; j > 0 && (v)[j - 1] > x; j--)                                               \
                (v)[j] = (v)[j - 1];                                                           \
            (v)[j] = x;                                                                        \
        }                                                                                      \
    } while (0)

static int cmp_u32(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

void sl_sort_run_u32(uint32_t *v, size_t n)
{
    SORT_RUN(uint32_t, cmp_u32, v, n);
}

void sl_sort_run_u64(uint64_t *v, size_t n)
{
    SORT_RUN(uint64_t, cmp_u64, v, n);
}

size_t sl_unique_keys(uint64_t *keys, size_t count)
{
    if (count == 0)
        return 0;
    size_t out = 1;
    for (size_t i = 1; i < count; i++)
        if (keys[i] != keys[out - 1])
            keys[out++] = keys[i];
    return out;
}
