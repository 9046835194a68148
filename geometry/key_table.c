/* LSD radix sort on 64-bit keys, 16 bits per pass (see key_table.h). One routine serves
 * bare keys and (key, value) pairs: an element is `size` bytes whose first 8 are the key. */
#include "geometry/key_table.h"

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

static int radix_sort(void *data, size_t count, size_t size, int bits)
{
    if (count < 2)
        return 0;
    unsigned char *tmp = malloc(count * size);
    size_t *histogram = malloc(RADIX * sizeof *histogram);
    if (!tmp || !histogram) {
        free(tmp);
        free(histogram);
        return -1;
    }
    unsigned char *src = data, *dst = tmp;
    for (int shift = 0; shift < bits; shift += RADIX_BITS) {
        memset(histogram, 0, RADIX * sizeof *histogram);
        for (size_t i = 0; i < count; i++)
            histogram[(key_at(src, i, size) >> shift) & (RADIX - 1)]++;
        size_t sum = 0;
        for (size_t b = 0; b < RADIX; b++) {
            size_t c = histogram[b];
            histogram[b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < count; i++) {
            size_t to = histogram[(key_at(src, i, size) >> shift) & (RADIX - 1)]++;
            memcpy(dst + to * size, src + i * size, size);
        }
        unsigned char *swap = src;
        src = dst;
        dst = swap;
    }
    if (src != (unsigned char *)data)
        memcpy(data, src, count * size);
    free(tmp);
    free(histogram);
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
