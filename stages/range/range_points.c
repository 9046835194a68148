/* The range stage's work on one in-memory mesh (paper 1 section 4; docs/range-stage.md, "Decisions"
 * "Points"): grid -> triangles for raw scans, clean and weld, normals (faces, file or PCA),
 * colours, bounding box and spacing. Each step lives in its own file; this one decides
 * which steps apply and what is bad input.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_distance.h"
#include "runtime/octree_io.h"
#include "stages/range/range_internal.h"

int range_mean_spacing(const sl_kdtree *tree, const float *positions, uint64_t point_count,
                       double *spacing, sl_error *err)
{
    *spacing = 0.0;
    if (point_count < 2)
        return SL_OK;
    double *d = malloc(point_count * sizeof *d);
    if (!d)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "spacing: out of memory (%llu points)",
                            (unsigned long long)point_count);
#pragma omp parallel for schedule(static, 4096)
    for (int64_t i = 0; i < (int64_t)point_count; i++) {
        uint32_t idx[2];
        float d2[2];
        uint32_t found = sl_kdtree_knn(tree, positions + 3 * i, 2, idx, d2);
        /* The point itself is normally first; a welded set has no zero-distance twins. */
        d[i] = found < 2 ? 0.0 : sqrt((double)(idx[0] == (uint32_t)i ? d2[1] : d2[0]));
    }
    double sum = 0; /* serial: the same bits whatever the thread count */
    for (uint64_t i = 0; i < point_count; i++)
        sum += d[i];
    free(d);
    *spacing = sum / (double)point_count;
    return SL_OK;
}

/* (min and max are exact, so the parallel reduction is the serial loop's result.) */
static void bounding_box(const float *positions, uint64_t n, float lo[3], float hi[3])
{
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = n ? positions[k] : 0.0f;
#pragma omp parallel for schedule(static) reduction(min : lo[:3]) reduction(max : hi[:3])
    for (uint64_t i = 1; i < n; i++)
        for (int k = 0; k < 3; k++) {
            float x = positions[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
}

/* Rejects garbage (a wrong-endianness file reads as mostly NaN/Inf) and empty results. */
static int check_usable(const sl_range_config *cfg, const sl_mesh *mesh,
                        const range_clean *clean, const sl_range_counts *counts, sl_error *err)
{
    uint64_t n = mesh->vertex_count;
    if (n && (double)counts->nonfinite_vertices > cfg->max_nonfinite_fraction * (double)n)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "%llu of %llu vertices have non-finite coordinates (more than "
                            "[range] max_nonfinite_fraction = %g): wrong format or endianness?",
                            (unsigned long long)counts->nonfinite_vertices,
                            (unsigned long long)n, cfg->max_nonfinite_fraction);
    if (clean->point_count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "no usable points: %llu vertices, %llu non-finite, %llu faces "
                            "(%llu degenerate, %llu with non-finite corners)",
                            (unsigned long long)n, (unsigned long long)counts->nonfinite_vertices,
                            (unsigned long long)mesh->triangle_count,
                            (unsigned long long)counts->degenerate_faces,
                            (unsigned long long)counts->nonfinite_faces);
    return SL_OK;
}

/* The octree's grid (its origin and a root cube of a power of two leaves around the padded
 * box) must stay within SL_OCTREE_MAX_EXTENT, which the octree readers enforce
 * (docs/formats.md). Coordinates beyond a sixteenth of it are refused here, at once and
 * in the scan's own terms; the merge stage checks the grid it actually derives (a very
 * coarse leaf can still take a scan within this beyond the limit). */
#define RANGE_MAX_COORDINATE (SL_OCTREE_MAX_EXTENT / 16)

static int check_extent(const float lo[3], const float hi[3], sl_error *err)
{
    double reach = 0;
    for (int k = 0; k < 3; k++)
        reach = fmax(reach, fmax(fabs((double)lo[k]), fabs((double)hi[k])));
    if (reach > RANGE_MAX_COORDINATE)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "coordinates reach %.3g: scanlod takes up to %.3g in magnitude "
                            "(rescale the scan or move it nearer the origin)",
                            reach, RANGE_MAX_COORDINATE);
    return SL_OK;
}

/* An inside-out closed mesh (horse.ply is one: watertight, negative volume) would give
 * the samples stage inverted signs, so its normals are flipped as a whole. Only
 * watertight meshes: for them the sign of the volume is exact; open scans keep the
 * orientation their winding gives (grid meshes already face the scanner). */
static int orient_closed_mesh(const range_clean *clean, sl_pointset *ps,
                              sl_range_counts *counts, sl_error *err)
{
    sl_mesh view = sl_mesh_view(ps->count, ps->positions, NULL, NULL, clean->triangle_count,
                                clean->triangles);
    sl_mesh_topology topology;
    int rc = sl_mesh_topology_compute(&view, &topology, err);
    if (rc != SL_OK || !topology.watertight)
        return rc;
    double volume = 0; /* six times the signed volume, in triangle order */
    for (uint64_t t = 0; t < clean->triangle_count; t++) {
        const float *a = ps->positions + 3 * (uint64_t)clean->triangles[3 * t];
        const float *b = ps->positions + 3 * (uint64_t)clean->triangles[3 * t + 1];
        const float *c = ps->positions + 3 * (uint64_t)clean->triangles[3 * t + 2];
        volume += a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) -
                  a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
                  a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0]);
    }
    if (volume < 0) {
        counts->normals_flipped = 1;
        for (uint64_t i = 0; i < 3 * ps->count; i++)
            ps->normals[i] = -ps->normals[i];
    }
    return SL_OK;
}

/* Face or PCA normals, then the file's where asked and usable. */
static int compute_normals(const sl_range_config *cfg, const sl_mesh *mesh,
                           const range_clean *clean, const sl_kdtree *tree, sl_pointset *ps,
                           int from_grid, sl_range_counts *counts, sl_progress *progress,
                           sl_error *err)
{
    int rc;
    if (clean->triangle_count) {
        ps->normal_source = from_grid ? SL_NORMALS_RANGE_GRID : SL_NORMALS_FACES;
        rc = range_face_normals(ps->positions, ps->count, clean->triangles,
                                clean->triangle_count, ps->normals, counts, progress, err);
        if (rc == SL_OK && !from_grid)
            rc = orient_closed_mesh(clean, ps, counts, err);
    } else {
        rc = range_pca_normals(tree, ps->positions, ps->count, cfg->knn,
                               mesh->has_viewpoint ? mesh->viewpoint : NULL, ps->normals,
                               &ps->normal_source, counts, progress, err);
    }
    if (rc != SL_OK || !cfg->normals_from_file)
        return rc;
    if (!mesh->normals) {
        counts->normal_fallbacks += ps->count; /* asked for file normals, the file has none */
        return SL_OK;
    }
    float *file = malloc(12 * ps->count);
    uint8_t *valid = malloc(ps->count);
    if (!file || !valid) {
        free(file), free(valid);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals: out of memory");
    }
    rc = range_file_normals(mesh, clean, file, valid, err);
    for (uint64_t p = 0; rc == SL_OK && p < ps->count; p++) {
        if (valid[p])
            memcpy(ps->normals + 3 * p, file + 3 * p, 12);
        else
            counts->normal_fallbacks++;
    }
    ps->normal_source = SL_NORMALS_FILE;
    free(file), free(valid);
    return rc;
}

int sl_range_points_from_mesh(const sl_range_config *cfg, sl_mesh *mesh, const char *texture_dir,
                              sl_pointset *out, sl_range_counts *counts, sl_progress *progress,
                              sl_error *err)
{
    memset(out, 0, sizeof *out);
    memset(counts, 0, sizeof *counts);
    counts->input_vertices = mesh->vertex_count;
    counts->input_faces = mesh->triangle_count;
    counts->polygons_triangulated = mesh->stats.polygons_triangulated;
    counts->color_source = "none";
    counts->texcoord_source = "none";
    int rc, from_grid = 0;
    if (mesh->triangle_count == 0 && mesh->grid_index && mesh->grid_cols && mesh->grid_rows) {
        if ((rc = range_grid_triangulate(mesh, cfg->grid_max_edge_factor, counts, progress,
                                         err)) != SL_OK)
            return rc;
        from_grid = mesh->triangle_count > 0;
    }
    range_clean clean;
    if ((rc = range_clean_mesh(mesh, &clean, counts, progress, err)) != SL_OK)
        return rc;
    sl_kdtree *tree = NULL;
    if ((rc = check_usable(cfg, mesh, &clean, counts, err)) != SL_OK)
        goto done;
    uint64_t n = clean.point_count;
    out->count = n;
    out->positions = malloc(12 * n);
    out->normals = malloc(12 * n);
    if (!out->positions || !out->normals) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory (%llu points)",
                          (unsigned long long)n);
        goto done;
    }
#pragma omp parallel for schedule(static)
    for (uint64_t p = 0; p < n; p++)
        memcpy(out->positions + 3 * p, mesh->positions + 3 * (uint64_t)clean.point_vertex[p], 12);
    bounding_box(out->positions, n, out->bbox_min, out->bbox_max);
    if ((rc = check_extent(out->bbox_min, out->bbox_max, err)) != SL_OK)
        goto done;
    if ((rc = sl_kdtree_build(&tree, out->positions, n, err)) != SL_OK)
        goto done;
    if (sl_progress_step(progress, "normals", 0.0)) {
        rc = SL_E_INTERRUPTED;
        goto done;
    }
    if ((rc = compute_normals(cfg, mesh, &clean, tree, out, from_grid, counts, progress, err)))
        goto done;
    if ((rc = range_colors(mesh, &clean, texture_dir, cfg->colors, &out->colors, counts, err)))
        goto done;
    if ((rc = range_texcoords(mesh, &clean, &out->texcoords, counts, err)))
        goto done;
    if ((rc = range_mean_spacing(tree, out->positions, n, &out->mean_spacing, err)))
        goto done;
    counts->points = n;
    counts->normal_source = out->normal_source;
    if (clean.triangle_count) {
        /* An inside-out mesh had its normals flipped; its triangles turn with them, so
         * the winding and the normals agree (the samples stage signs by the winding). */
        if (counts->normals_flipped)
            for (uint64_t t = 0; t < clean.triangle_count; t++) {
                uint32_t swap = clean.triangles[3 * t + 1];
                clean.triangles[3 * t + 1] = clean.triangles[3 * t + 2];
                clean.triangles[3 * t + 2] = swap;
            }
        out->triangles = clean.triangles;
        out->triangle_count = clean.triangle_count;
        clean.triangles = NULL;
    }
done:
    sl_kdtree_free(tree);
    range_clean_release(&clean);
    if (rc != SL_OK)
        sl_pointset_release(out);
    return rc;
}
