/* The distinct transition-cell triangulations of a model, found by configuration.
 *
 * sl_mc_triangulate is a pure function of the cell's signs (corner, split-edge midpoint and
 * split-face centre signs; 44 bits), and a model's transition cells repeat a limited set of
 * configurations: at load, sl_lod_triangulate_states triangulates each distinct one once
 * through this table and copies the result into the model's split lists. One 64-byte line
 * per entry; configurations of more than SL_MC_CACHE_TRIANGLES triangles or with centroid
 * vertices get no entry.
 */
#ifndef SCANLOD_RUNTIME_MC_CACHE_H
#define SCANLOD_RUNTIME_MC_CACHE_H

#include <stdint.h>

#include "runtime/mc_cube.h"

#define SL_MC_CACHE_TRIANGLES 18
#define SL_MC_CACHE_NONE UINT32_MAX

typedef struct sl_mc_cached {
    uint8_t count;
    uint8_t points[SL_MC_CACHE_TRIANGLES][3]; /* as sl_mc_triangles.points */
    uint8_t pad[64 - 1 - 3 * SL_MC_CACHE_TRIANGLES];
} sl_mc_cached;

typedef struct sl_mc_cache sl_mc_cache;

sl_mc_cache *sl_mc_cache_new(void); /* NULL when out of memory */
void sl_mc_cache_free(sl_mc_cache *cache);
/* The entry of the cell's configuration, triangulated and added unless it is there:
 * *id = its index, or SL_MC_CACHE_NONE when it cannot be kept. Returns -1 when out of
 * memory (the table stays usable). */
int sl_mc_cache_add(sl_mc_cache *cache, const sl_mc_cell *cell, uint32_t *id);
/* Entry id (an id sl_mc_cache_add gave). */
const sl_mc_cached *sl_mc_cache_entry(const sl_mc_cache *cache, uint32_t id);

#endif
