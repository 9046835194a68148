/* One A measured against many B (mesh_distance.h, sl_distance_reference): A's checks,
 * tree and area samples made once, then the same chunks as mesh_distance.c's measure, so
 * every figure is bit-identical to sl_mesh_distance_compute's. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_distance_internal.h"

struct sl_distance_reference {
    surface a;
    sl_triangle_bvh bvh;       /* A's tree, for B's samples */
    sl_mesh_distance_config cfg;
    double *points;            /* A's area samples, chunk after chunk */
    uint64_t *chunk_start;     /* chunks + 1 offsets (in samples) into points */
    uint64_t chunks;
};

const sl_triangle_bvh *sl_distance_reference_tree(const sl_distance_reference *r)
{
    return &r->bvh;
}

void sl_distance_reference_free(sl_distance_reference *r)
{
    if (!r)
        return;
    sl_triangle_bvh_release(&r->bvh);
    free(r->a.used);
    free(r->points);
    free(r->chunk_start);
    free(r);
}

int sl_distance_reference_build(const sl_mesh *a, const sl_mesh_distance_config *cfg,
                                sl_distance_reference **out, sl_error *err)
{
    sl_mesh_distance_config defaults = sl_mesh_distance_default_config();
    *out = NULL;
    if (!cfg)
        cfg = &defaults;
    if (cfg->samples == 0)
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "sample count must be at least 1");
    sl_distance_reference *r = calloc(1, sizeof *r);
    if (!r)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "distance reference");
    r->cfg = *cfg;
    int rc = md_check_surface(&r->a, a, "A", NULL, err);
    if (rc == SL_OK)
        rc = sl_triangle_bvh_build(&r->bvh, a, err);
    r->chunks = md_chunks_of(a->triangle_count);
    double *cum = NULL;
    if (rc == SL_OK) {
        cum = malloc((r->chunks + 1) * sizeof *cum);
        r->chunk_start = malloc((r->chunks + 1) * sizeof *r->chunk_start);
        /* the counts telescope to `samples`; a chunk never holds more than that */
        r->points = malloc(3 * (cfg->samples + r->chunks) * sizeof *r->points);
        if (!cum || !r->chunk_start || !r->points)
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "%llu distance samples",
                              (unsigned long long)cfg->samples);
    }
    if (rc == SL_OK) {
        md_prefix_areas(a, cum, r->chunks);
        double total = cum[r->chunks];
        /* serial in chunk order: each chunk's samples follow the previous chunk's */
        r->chunk_start[0] = 0;
        for (uint64_t c = 0; c < r->chunks; c++) {
            uint64_t end = (c + 1) * CHUNK < a->triangle_count ? (c + 1) * CHUNK
                                                               : a->triangle_count;
            sample_store store = {r->points + 3 * r->chunk_start[c], NULL};
            partial got = md_sample_triangles(a, c * CHUNK, end, cum[c], cum[c + 1], total,
                                           cfg->samples, cfg->seed, NULL, &store);
            r->chunk_start[c + 1] = r->chunk_start[c] + got.count;
        }
    }
    free(cum);
    if (rc != SL_OK) {
        sl_distance_reference_free(r);
        return rc;
    }
    *out = r;
    return SL_OK;
}

/* A's stored area samples (and, `with_vertices`, its used vertices) against B's tree, as
 * measure_side has them: the same chunks, each from a fresh hint, summed in order. */
static int reference_side(const sl_distance_reference *r, const sl_triangle_bvh *bvh_b,
                          int with_vertices, sl_distance_side *side, sl_progress *progress,
                          sl_error *err)
{
    const sl_mesh *m = r->a.mesh;
    uint64_t vert_chunks = with_vertices ? md_chunks_of(m->vertex_count) : 0;
    uint64_t total = r->chunks + vert_chunks;
    partial *parts = malloc((total ? total : 1) * sizeof *parts);
    if (!parts)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "sample bookkeeping of mesh A");
    int interrupted = 0;
#pragma omp parallel for schedule(dynamic, 1)
    for (uint64_t c = 0; c < total; c++) {
        if (md_stopping(&interrupted, progress))
            continue;
        if (c >= r->chunks) {
            uint64_t v = (c - r->chunks) * CHUNK;
            uint64_t end = v + CHUNK < m->vertex_count ? v + CHUNK : m->vertex_count;
            parts[c] = md_sample_vertices(&r->a, v, end, bvh_b, 0);
            continue;
        }
        partial acc = {0.0, 0.0, 0.0, 0};
        uint32_t hint = UINT32_MAX;
        for (uint64_t i = r->chunk_start[c]; i < r->chunk_start[c + 1]; i++) {
            sl_closest q;
            sl_triangle_bvh_closest(bvh_b, r->points + 3 * i, hint, &q);
            hint = q.triangle;
            md_accumulate(&acc, q.distance_sq, 1);
        }
        parts[c] = acc;
    }
    if (interrupted) {
        free(parts);
        return sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "distance sampling of mesh A");
    }
    md_side_of(parts, r->chunks, total, side);
    free(parts);
    return SL_OK;
}

/* Both sides against B: with_vertices as in sl_mesh_distance_compute (every figure), or
 * without (the RMS alone). */
static int reference_measure(const sl_distance_reference *r, const sl_mesh *b, int with_vertices,
                             sl_mesh_distance *out, sl_progress *progress, sl_error *err)
{
    memset(out, 0, sizeof *out);
    surface sb = {0};
    sl_triangle_bvh bvh_b = {0};
    int rc = md_check_surface(&sb, b, "B", NULL, err);
    if (rc == SL_OK)
        rc = sl_triangle_bvh_build(&bvh_b, b, err);
    if (rc == SL_OK)
        rc = reference_side(r, &bvh_b, with_vertices, &out->a_to_b, progress, err);
    sl_triangle_bvh_release(&bvh_b);
    if (rc == SL_OK)
        rc = md_measure_side(&sb, &r->bvh, &r->cfg, with_vertices, &out->b_to_a, progress, err);
    if (rc == SL_OK)
        md_fill_out(out, &r->a);
    free(sb.used);
    return rc;
}

int sl_distance_reference_rms(const sl_distance_reference *r, const sl_mesh *b, double *rms,
                              sl_progress *progress, sl_error *err)
{
    *rms = INFINITY;
    sl_mesh_distance d;
    int rc = reference_measure(r, b, 0, &d, progress, err);
    if (rc == SL_OK)
        *rms = d.fraction.rms;
    return rc;
}

int sl_distance_reference_compute(const sl_distance_reference *r, const sl_mesh *b,
                                  int vertices, sl_mesh_distance *out, sl_progress *progress,
                                  sl_error *err)
{
    return reference_measure(r, b, vertices != 0, out, progress, err);
}
