/* Internals of the samples stage shared by its files (not part of its interface). */
#ifndef SCANLOD_STAGES_SAMPLES_INTERNAL_H
#define SCANLOD_STAGES_SAMPLES_INTERNAL_H

#include <math.h>
#include <stdint.h>

#include "geometry/triangle_bvh.h"
#include "geometry/key_table.h"
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

/* Occupied cubes: the cubes of every point, sorted and unique. With `use_triangles`, also
 * the cubes of a regular grid of points on every triangle longer than a leaf (steps of at
 * most a leaf, so each point of the triangle is less than a leaf from one of them, and
 * every cube the triangle passes through is within one cube of an occupied one: the band
 * covers it). *triangle_keys counts those extra points; above `max_count` of them the
 * item is refused (SL_E_LIMIT) before they are allocated. */
int samples_occupied_cubes(const sl_samples_plan *plan, const sl_pointset *ps, int use_triangles,
                           uint64_t max_count, samples_keys *out, uint64_t *triangle_keys,
                           sl_error *err);

/* The input's triangles as a signed-distance source (samples_surface.c). */
typedef struct samples_surface {
    const sl_pointset *ps;     /* borrowed: positions, triangles, colours */
    sl_triangle_bvh bvh;
    float *vertex_normals;     /* 3 per point: angle-weighted pseudonormal (not unit) */
    uint64_t *incident_first;  /* points + 1: start of each point's triangles */
    uint32_t *incident;        /* 3 per triangle: triangles around each point, ascending */
    int closed;                /* every edge is used as often in one direction as in
                                  the other: inside and outside are well defined */
} samples_surface;

int samples_surface_build(samples_surface *s, const sl_pointset *ps, sl_error *err);
void samples_surface_release(samples_surface *s);

/* The signed distance from v to the triangles (> 0 outside: the side the winding faces),
 * and when rgba is not NULL and the points have colours, the closest point's colour.
 * *hint: a triangle to try first (UINT32_MAX: none); set to this query's triangle. */
double samples_surface_signed_distance(const samples_surface *s, const double v[3],
                                       uint32_t *hint, uint8_t rgba[4]);

/* Makes the signs of `s` (exact unsigned distances; `keys` their sorted vertex keys)
 * consistent: axis neighbours of which one lies more than `leaf` from the surface are
 * on the same side, so each region so linked takes its majority sign
 * (samples_signs.c). *repaired: samples whose sign changed. */
int samples_repair_signs(const uint64_t *keys, sl_vdb_samples *s, double leaf,
                         uint64_t *repaired, sl_error *err);

/* Replaces `k` by its union with copies shifted by each of `offsets` (grid steps) along
 * `axis`; keys must stay in range (the caller's invariant). Refuses (SL_E_LIMIT) a result
 * of more than `max_count` keys before allocating it. */
int samples_dilate(samples_keys *k, int axis, const int *offsets, int offset_count,
                   uint64_t max_count, sl_error *err);

/* Band cubes (occupied cubes dilated by plan->band in the 26-neighbourhood), then the
 * grid vertices of the band cubes, with the counts of each. */
int samples_band_vertices(const sl_samples_plan *plan, samples_keys *cubes, uint64_t max_count,
                          uint64_t *band_cubes, sl_error *err);

/* Parts (samples_parts.c): part p's values in its own artifact folder, joined by the
 * stage's run when the engine split it (docs/engine.md, "Parts"). */
#define SL_SAMPLES_PART_FILE "samples.part"
typedef struct samples_parts {
    const char *const *dirs; /* the parts' artifact folders, in order */
    int count;
} samples_parts;
/* Writes part `part` of `parts` of `s` (its run of vertices: sl_samples_part_range). */
int samples_part_write(const char *path, const sl_vdb_samples *s, int part, int parts,
                       int closed, uint64_t flips, sl_error *err);
/* sl_samples_split.fill over a samples_parts: SL_E_CORRUPT naming the file when a part
 * does not fit its place. */
int samples_parts_fill(void *ctx, sl_vdb_samples *out, int *closed, uint64_t *flips,
                       sl_error *err);

#endif
