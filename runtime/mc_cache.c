/* Cached transition-cell triangulations (see mc_cache.h). */
#include "runtime/mc_cache.h"

#include <stdlib.h>
#include <string.h>

#define CACHE_BITS 12 /* 4096 entries, 256 KiB */

typedef struct entry {
    uint64_t key; /* cell signs + 1 bit "valid" */
    uint8_t count;
    uint8_t points[SL_MC_CACHE_TRIANGLES][3];
    uint8_t pad[64 - 8 - 1 - 3 * SL_MC_CACHE_TRIANGLES];
} entry;

_Static_assert(sizeof(entry) == 64, "one cache line per entry");

struct sl_mc_cache {
    entry slots[1u << CACHE_BITS];
};

sl_mc_cache *sl_mc_cache_new(void)
{
    sl_mc_cache *c = aligned_alloc(64, sizeof *c);
    if (c)
        memset(c, 0, sizeof *c);
    return c;
}

void sl_mc_cache_free(sl_mc_cache *cache)
{
    free(cache);
}

static inline uint64_t cell_key(const sl_mc_cell *cell)
{
    return (uint64_t)cell->inside | (uint64_t)(cell->split_edges & 0xfffu) << 8 |
           (uint64_t)(cell->mid_inside & 0xfffu) << 20 |
           (uint64_t)(cell->split_faces & 0x3fu) << 32 |
           (uint64_t)(cell->centre_inside & 0x3fu) << 38 | (uint64_t)1 << 44;
}

void sl_mc_triangulate_cached(sl_mc_cache *cache, const sl_mc_cell *cell,
                              sl_mc_triangles *out)
{
    if (!cache) {
        sl_mc_triangulate(cell, out);
        return;
    }
    /* Every bit the triangulation can read is in the key (also midpoint and centre bits
     * of unsplit edges and faces), so a hit is exactly a configuration triangulated before. */
    uint64_t key = cell_key(cell);
    entry *e = &cache->slots[(key * 0x9E3779B97F4A7C15ull) >> (64 - CACHE_BITS)];
    if (e->key == key) {
        out->count = e->count;
        out->centroids = 0;
        memcpy(out->points, e->points, 3 * (size_t)e->count);
        return;
    }
    sl_mc_triangulate(cell, out);
    if (!out->centroids && out->count <= SL_MC_CACHE_TRIANGLES) {
        e->key = key;
        e->count = out->count;
        memcpy(e->points, out->points, 3 * (size_t)out->count);
    }
}
