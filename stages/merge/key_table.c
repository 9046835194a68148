/* LSD radix sort on 64-bit keys, 16 bits per pass (see key_table.h). */
#include "stages/merge/key_table.h"

#include <stdlib.h>
#include <string.h>

#define RADIX_BITS 16
#define RADIX (1u << RADIX_BITS)

int sl_sort_pairs(sl_key_pair *pairs, size_t count, int bits)
{
    if (count < 2)
        return 0;
    sl_key_pair *tmp = malloc(count * sizeof *tmp);
    size_t *histogram = malloc(RADIX * sizeof *histogram);
    if (!tmp || !histogram) {
        free(tmp);
        free(histogram);
        return -1;
    }
    sl_key_pair *src = pairs, *dst = tmp;
    for (int shift = 0; shift < bits; shift += RADIX_BITS) {
        memset(histogram, 0, RADIX * sizeof *histogram);
        for (size_t i = 0; i < count; i++)
            histogram[(src[i].key >> shift) & (RADIX - 1)]++;
        size_t sum = 0;
        for (size_t b = 0; b < RADIX; b++) {
            size_t c = histogram[b];
            histogram[b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < count; i++)
            dst[histogram[(src[i].key >> shift) & (RADIX - 1)]++] = src[i];
        sl_key_pair *swap = src;
        src = dst;
        dst = swap;
    }
    if (src != pairs)
        memcpy(pairs, src, count * sizeof *pairs);
    free(tmp);
    free(histogram);
    return 0;
}

int sl_sort_keys(uint64_t *keys, size_t count, int bits)
{
    if (count < 2)
        return 0;
    uint64_t *tmp = malloc(count * sizeof *tmp);
    size_t *histogram = malloc(RADIX * sizeof *histogram);
    if (!tmp || !histogram) {
        free(tmp);
        free(histogram);
        return -1;
    }
    uint64_t *src = keys, *dst = tmp;
    for (int shift = 0; shift < bits; shift += RADIX_BITS) {
        memset(histogram, 0, RADIX * sizeof *histogram);
        for (size_t i = 0; i < count; i++)
            histogram[(src[i] >> shift) & (RADIX - 1)]++;
        size_t sum = 0;
        for (size_t b = 0; b < RADIX; b++) {
            size_t c = histogram[b];
            histogram[b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < count; i++)
            dst[histogram[(src[i] >> shift) & (RADIX - 1)]++] = src[i];
        uint64_t *swap = src;
        src = dst;
        dst = swap;
    }
    if (src != keys)
        memcpy(keys, src, count * sizeof *keys);
    free(tmp);
    free(histogram);
    return 0;
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
