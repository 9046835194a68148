/* mesh_distance's internals, shared by the one-off measure (mesh_distance.c) and the
 * reference of one A against many B (mesh_distance_reference.c): the chunked sampler and
 * the per-side figures, so both sum the same samples in the same order (bit-identical
 * figures, mesh_distance.h). Not an interface: geometry/mesh_distance.h is. */
#ifndef SCANLOD_GEOMETRY_MESH_DISTANCE_INTERNAL_H
#define SCANLOD_GEOMETRY_MESH_DISTANCE_INTERNAL_H

#include <stdint.h>

#include "geometry/mesh_distance.h"
#include "geometry/triangle_bvh.h"

#define CHUNK 4096

typedef struct partial {
    double max;      /* largest distance */
    double sum;      /* of distances (area samples) */
    double sum_sq;   /* of squared distances (area samples) */
    uint64_t count;  /* samples */
} partial;

/* What validation learns about one mesh. */
typedef struct surface {
    const sl_mesh *mesh;
    const char *name;      /* "A" or "B" */
    uint8_t *used;         /* vertex_count flags: the vertex is a triangle corner */
    double lo[3], hi[3];   /* bounds of the used vertices */
} surface;

/* Where drawn samples go instead of being measured (sl_distance_reference's points,
 * sl_mesh_area_samples' records): either array, written from index 0. */
typedef struct sample_store {
    double *points;          /* 3 per sample, or NULL */
    sl_area_sample *records; /* 1 per sample, or NULL */
} sample_store;

/* Checks mesh `m` as `name` ("A" or "B") into *s: used vertices, bounds, finite
 * coordinates, a nonzero area; SL_E_BADINPUT naming the cause (and `file`), SL_E_NOMEM. */
int md_check_surface(surface *s, const sl_mesh *m, const char *name, const char *file,
                     sl_error *err);
/* One sample's distance into a chunk's partial (area samples count in mean and RMS). */
void md_accumulate(partial *acc, double d_sq, int area_sample);
/* Area samples of triangles [first, end) of `m`: measured against `target`, or with
 * `store` written there (mesh_distance.c has the stratified counts). */
partial md_sample_triangles(const sl_mesh *m, uint64_t first, uint64_t end, double cum,
                            double cum_end, double total, uint64_t n, uint64_t seed,
                            const sl_triangle_bvh *target, const sample_store *store);
/* The used vertices of `src` in [first, end) against `target`. */
partial md_sample_vertices(const surface *src, uint64_t first, uint64_t end,
                           const sl_triangle_bvh *target, int in_means);
uint64_t md_chunks_of(uint64_t n);
/* cum[c] = the area before chunk c, summed chunk by chunk; chunks + 1 entries. */
void md_prefix_areas(const sl_mesh *m, double *cum, uint64_t chunks);
/* In a parallel loop: whether to skip the rest (interrupted, or seen so by a thread). */
int md_stopping(int *interrupted, sl_progress *progress);
/* A side's figures from its chunks' partials in chunk order (area chunks first). */
void md_side_of(const partial *parts, uint64_t area_chunks, uint64_t chunks,
                sl_distance_side *side);
/* One direction: the samples of `src` (and, with_vertices, its vertices) against `target`. */
int md_measure_side(const surface *src, const sl_triangle_bvh *target,
                    const sl_mesh_distance_config *cfg, int with_vertices,
                    sl_distance_side *side, sl_progress *progress, sl_error *err);
/* The symmetric figures and the fractions of A's diagonal, from both sides. */
void md_fill_out(sl_mesh_distance *out, const surface *a);

#endif
