/* The table of transition-cell triangulations (see mc_cache.h): entries in a dense array
 * in the order they were added, found by configuration through an open-addressing index
 * (at most half full) while the table is filled. */
#include "runtime/mc_cache.h"

#include <stdlib.h>
#include <string.h>

_Static_assert(sizeof(sl_mc_cached) == 64, "one cache line per entry");

#define INITIAL_BITS 10

struct sl_mc_cache {
    sl_mc_cached *entries;
    uint32_t count, capacity;
    unsigned bits;
    uint64_t keyed; /* configurations in the index, kept or not */
    uint64_t *keys; /* per index slot: configuration key (0: empty) */
    uint32_t *ids;  /* per index slot: entry id, or SL_MC_CACHE_NONE (not kept) */
};

sl_mc_cache *sl_mc_cache_new(void)
{
    sl_mc_cache *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->bits = INITIAL_BITS;
    c->keys = calloc((size_t)1 << c->bits, sizeof *c->keys);
    c->ids = malloc(((size_t)1 << c->bits) * sizeof *c->ids);
    if (!c->keys || !c->ids) {
        sl_mc_cache_free(c);
        return NULL;
    }
    return c;
}

void sl_mc_cache_free(sl_mc_cache *cache)
{
    if (cache) {
        free(cache->entries);
        free(cache->keys);
        free(cache->ids);
    }
    free(cache);
}

const sl_mc_cached *sl_mc_cache_entry(const sl_mc_cache *cache, uint32_t id)
{
    return &cache->entries[id];
}

/* Every bit the triangulation can read (also midpoint and centre bits of unsplit edges
 * and faces), plus a "valid" bit. */
static inline uint64_t cell_key(const sl_mc_cell *cell)
{
    return (uint64_t)cell->inside | (uint64_t)(cell->split_edges & 0xfffu) << 8 |
           (uint64_t)(cell->mid_inside & 0xfffu) << 20 |
           (uint64_t)(cell->split_faces & 0x3fu) << 32 |
           (uint64_t)(cell->centre_inside & 0x3fu) << 38 | (uint64_t)1 << 44;
}

/* The index slot holding key, or the empty slot where it would go. */
static size_t probe(const uint64_t *keys, unsigned bits, uint64_t key)
{
    size_t mask = ((size_t)1 << bits) - 1u;
    size_t i = (size_t)((key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
    while (keys[i] && keys[i] != key)
        i = (i + 1) & mask;
    return i;
}

static int grow_index(sl_mc_cache *c)
{
    size_t size = (size_t)1 << (c->bits + 1);
    uint64_t *keys = calloc(size, sizeof *keys);
    uint32_t *ids = malloc(size * sizeof *ids);
    if (!keys || !ids) {
        free(keys);
        free(ids);
        return -1;
    }
    for (size_t i = 0; i < (size_t)1 << c->bits; i++)
        if (c->keys[i]) {
            size_t j = probe(keys, c->bits + 1, c->keys[i]);
            keys[j] = c->keys[i];
            ids[j] = c->ids[i];
        }
    free(c->keys);
    free(c->ids);
    c->keys = keys;
    c->ids = ids;
    c->bits++;
    return 0;
}

static int add_entry(sl_mc_cache *c, const sl_mc_triangles *tri, uint32_t *id)
{
    if (c->count == c->capacity) {
        uint32_t capacity = c->capacity ? 2 * c->capacity : 256;
        sl_mc_cached *entries = realloc(c->entries, (size_t)capacity * sizeof *entries);
        if (!entries)
            return -1;
        c->entries = entries;
        c->capacity = capacity;
    }
    sl_mc_cached *e = &c->entries[c->count];
    memset(e, 0, sizeof *e);
    e->count = tri->count;
    memcpy(e->points, tri->points, 3 * (size_t)tri->count);
    *id = c->count++;
    return 0;
}

int sl_mc_cache_add(sl_mc_cache *cache, const sl_mc_cell *cell, uint32_t *id)
{
    uint64_t key = cell_key(cell);
    size_t slot = probe(cache->keys, cache->bits, key);
    if (cache->keys[slot]) {
        *id = cache->ids[slot];
        return 0;
    }
    *id = SL_MC_CACHE_NONE;
    if (2 * (cache->keyed + 1) > (uint64_t)1 << cache->bits) {
        if (grow_index(cache))
            return -1;
        slot = probe(cache->keys, cache->bits, key);
    }
    sl_mc_triangles tri;
    sl_mc_triangulate(cell, &tri);
    uint32_t kept = SL_MC_CACHE_NONE;
    if (!tri.centroids && tri.count <= SL_MC_CACHE_TRIANGLES && add_entry(cache, &tri, &kept))
        return -1;
    cache->keys[slot] = key;
    cache->ids[slot] = kept;
    cache->keyed++;
    *id = kept;
    return 0;
}
