/* Sorted 64-bit key tables on the leaf grid (the samples stage's vertex sets, the merge
 * stage's level tables): LSD radix sort of (key, value) pairs and binary search, and the
 * packing of grid vertices and edges into keys. Sorted arrays instead of hash maps:
 * deterministic, compact, and trivially shared by OpenMP threads for lookups. */
#ifndef SCANLOD_GEOMETRY_KEY_TABLE_H
#define SCANLOD_GEOMETRY_KEY_TABLE_H

#include <stddef.h>
#include <stdint.h>

typedef struct sl_key_pair {
    uint64_t key;
    uint64_t value;
} sl_key_pair;

/* Sorts by key (stable); `bits` = how many low bits of the key are used (<= 64).
 * Returns 0, or -1 when out of memory. */
int sl_sort_pairs(sl_key_pair *pairs, size_t count, int bits);
int sl_sort_keys(uint64_t *keys, size_t count, int bits);
/* Short runs (a bucket's or a vertex's few entries) sorted ascending: by insertion up to
 * 32 entries, by qsort above (a fan's apex on a broken mesh can hold thousands, which
 * insertion would make quadratic). */
void sl_sort_run_u32(uint32_t *v, size_t n);
void sl_sort_run_u64(uint64_t *v, size_t n);
/* The first element of slice s of n elements cut into `slices` fixed slices (the loops
 * that count per slice, prefix the counts, then write at the offsets: the serial loop's
 * result whatever the thread count). */
static inline uint64_t sl_slice_begin(uint64_t n, int s, int slices)
{
    return n * (uint64_t)s / (uint64_t)slices;
}
/* Removes adjacent duplicates of a sorted array; returns the new count. */
size_t sl_unique_keys(uint64_t *keys, size_t count);

/* Index of `key` in the sorted `keys`, or -1. */
static inline int64_t sl_find_key(const uint64_t *keys, size_t count, uint64_t key)
{
    size_t lo = 0, hi = count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (keys[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < count && keys[lo] == key ? (int64_t)lo : -1;
}

/* Leaf-grid and level-grid vertex keys: 20 bits per coordinate. */
#define SL_COORD_BITS 20
#define SL_COORD_LIMIT (1u << SL_COORD_BITS)
static inline uint64_t sl_vertex_key(uint32_t x, uint32_t y, uint32_t z)
{
    return (uint64_t)x << 40 | (uint64_t)y << 20 | (uint64_t)z;
}
static inline void sl_vertex_unpack(uint64_t key, uint32_t p[3])
{
    p[0] = (uint32_t)(key >> 40) & (SL_COORD_LIMIT - 1);
    p[1] = (uint32_t)(key >> 20) & (SL_COORD_LIMIT - 1);
    p[2] = (uint32_t)key & (SL_COORD_LIMIT - 1);
}
/* An edge: its first vertex and its axis. */
static inline uint64_t sl_edge_key(uint64_t vertex_key, int axis)
{
    return vertex_key << 2 | (uint64_t)axis;
}

#endif
