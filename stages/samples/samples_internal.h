/* Internals of the samples stage shared by its files (not part of its interface). */
#ifndef SCANLOD_STAGES_SAMPLES_INTERNAL_H
#define SCANLOD_STAGES_SAMPLES_INTERNAL_H

#include <math.h>
#include <stdint.h>

#include "stages/merge/key_table.h"
#include "stages/samples/samples.h"

/* A sorted array of unique keys (sl_vertex_key: cubes by their minimum corner). */
typedef struct samples_keys {
    uint64_t *keys;
    uint64_t count;
} samples_keys;

void samples_keys_release(samples_keys *k);

/* The leaf cube holding world coordinate `p` on `axis` (clamped to the cubes the
 * bounding box spans, so a point on the far face belongs to the last cube). */
static inline uint32_t samples_cube_of(const sl_samples_plan *plan, double p, int axis)
{
    double c = floor((p - plan->origin[axis]) / plan->leaf_size);
    double lo = plan->band, hi = plan->band + (double)plan->cells[axis] - 1.0;
    return (uint32_t)(c < lo ? lo : c > hi ? hi : c);
}

/* Occupied cubes: the cubes of every point, sorted and unique. */
int samples_occupied_cubes(const sl_samples_plan *plan, const sl_pointset *ps, samples_keys *out,
                           sl_error *err);

/* Replaces `k` by its union with copies shifted by each of `offsets` (grid steps) along
 * `axis`; keys must stay in range (the caller's invariant). Refuses (SL_E_LIMIT) a result
 * of more than `max_count` keys before allocating it. */
int samples_dilate(samples_keys *k, int axis, const int *offsets, int offset_count,
                   uint64_t max_count, sl_error *err);

/* Band cubes (occupied cubes dilated by plan->band in the 26-neighbourhood), then the
 * grid vertices of the band cubes, with the counts of each. */
int samples_band_vertices(const sl_samples_plan *plan, samples_keys *cubes, uint64_t max_count,
                          uint64_t *band_cubes, sl_error *err);

#endif
