/* The octree's cuts as the refine stage takes them: the cut, less the shards coarsening
 * splits off it ([refine] min_part_area; docs/lod.md "Shards").
 *
 * A signed grid cannot draw a sheet or a strand thinner than its cells: where a coarse
 * cell's corners all lie on one side of it, that stretch of the part is gone, and what is
 * left of the part floats free of the body -- the wing tips and torch of lucy's
 * 2000-triangle thumb, or closed specks of 4-24 triangles around a lone corner whose sign
 * the thin part set. When the finest level is one body (its largest part holds at least
 * SL_REFINE_ONE_BODY of its area), such a part of a coarser level is no part of the object
 * but debris of the coarsening: each published coarser level keeps the parts holding at
 * least min_part_area of its area (and always its largest). The finest level is published
 * as the octree drew it, and a scan of several real pieces (its finest level not one body)
 * keeps every part at every level. A budget level spends the triangles its shards had on
 * the body (a few more cuts, refine_cut_within, refine_octree.c).
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_distance.h"
#include "geometry/triangle_bvh.h"
#include "stages/refine/refine_internal.h"

int refine_largest_part(const sl_lod_mesh *mesh, double *fraction, sl_error *err)
{
    *fraction = 1;
    if (mesh->triangle_count == 0)
        return 0;
    uint32_t *part = malloc(mesh->triangle_count * sizeof *part);
    if (!part)
        return sl_error_nomem(err, NULL, "out of memory");
    sl_mesh view = sl_mesh_view(mesh->vertex_count, mesh->positions, NULL, NULL, mesh->triangle_count, mesh->indices);
    double *area;
    uint64_t parts;
    int rc = sl_mesh_parts(&view, part, &area, &parts, err);
    free(part);
    if (rc)
        return rc;
    double total = 0, largest = 0;
    for (uint64_t p = 0; p < parts; p++) {
        total += area[p];
        largest = area[p] > largest ? area[p] : largest;
    }
    free(area);
    *fraction = total > 0 ? largest / total : 1;
    return 0;
}

/* Moves the kept triangles and the vertices they use to the front, in their order. */
static void compact(sl_lod_mesh *mesh, const uint32_t *part, const unsigned char *keep,
                    uint32_t *new_index)
{
    uint64_t t_out = 0, v_out = 0;
    for (uint64_t v = 0; v < mesh->vertex_count; v++)
        new_index[v] = UINT32_MAX;
    for (uint64_t t = 0; t < mesh->triangle_count; t++) {
        if (!keep[part[t]])
            continue;
        for (int c = 0; c < 3; c++) {
            uint32_t v = mesh->indices[3 * t + c];
            if (new_index[v] == UINT32_MAX)
                new_index[v] = 0; /* numbered below, in vertex order */
        }
    }
    for (uint64_t v = 0; v < mesh->vertex_count; v++) {
        if (new_index[v] == UINT32_MAX)
            continue;
        new_index[v] = (uint32_t)v_out;
        memmove(mesh->positions + 3 * v_out, mesh->positions + 3 * v, 3 * sizeof(float));
        if (mesh->normals)
            memmove(mesh->normals + 3 * v_out, mesh->normals + 3 * v, 3 * sizeof(float));
        if (mesh->colors)
            memmove(mesh->colors + 4 * v_out, mesh->colors + 4 * v, 4);
        v_out++;
    }
    for (uint64_t t = 0; t < mesh->triangle_count; t++) {
        if (!keep[part[t]])
            continue;
        for (int c = 0; c < 3; c++)
            mesh->indices[3 * t_out + c] = new_index[mesh->indices[3 * t + c]];
        t_out++;
    }
    mesh->vertex_count = v_out;
    mesh->triangle_count = t_out;
}

/* The edge of an equilateral triangle of the level's mean triangle area. */
static double mean_edge(double area, uint64_t triangles)
{
    return triangles ? sqrt(4.0 * area / (sqrt(3.0) * (double)triangles)) : 0;
}

/* A small part is a shard only where the rest of the level covers it: every vertex of it
 * within `tolerance` of the kept triangles, so leaving it out moves the surface by little
 * more than that. A small part farther out (a wing tip cut loose) is the only surface
 * there and stays (keep[p] set back). */
static int keep_uncovered(const sl_lod_mesh *mesh, const uint32_t *part, uint64_t parts,
                          unsigned char *keep, double tolerance, sl_error *err)
{
    uint64_t kept = 0;
    for (uint64_t t = 0; t < mesh->triangle_count; t++)
        kept += keep[part[t]];
    if (kept == mesh->triangle_count)
        return 0;
    uint32_t *tri = malloc(3 * kept * sizeof *tri);
    double *reach = calloc(parts ? parts : 1, sizeof *reach);
    if (!tri || !reach) {
        free(tri);
        free(reach);
        return sl_error_nomem(err, NULL, "out of memory");
    }
    for (uint64_t t = 0, at = 0; t < mesh->triangle_count; t++)
        if (keep[part[t]])
            memcpy(tri + 3 * at++, mesh->indices + 3 * t, 3 * sizeof *tri);
    sl_mesh body = sl_mesh_view(mesh->vertex_count, mesh->positions, NULL, NULL, kept, tri);
    sl_triangle_bvh bvh;
    int rc = sl_triangle_bvh_build(&bvh, &body, err);
    if (rc == 0) {
        uint32_t hint = UINT32_MAX;
        for (uint64_t t = 0; t < mesh->triangle_count; t++) {
            if (keep[part[t]] || reach[part[t]] > tolerance)
                continue;
            for (int c = 0; c < 3; c++) {
                const float *v = mesh->positions + 3 * (size_t)mesh->indices[3 * t + c];
                double p[3] = {v[0], v[1], v[2]};
                sl_closest q;
                sl_triangle_bvh_closest(&bvh, p, hint, &q);
                hint = q.triangle;
                reach[part[t]] = fmax(reach[part[t]], sqrt(q.distance_sq));
            }
        }
        for (uint64_t p = 0; p < parts; p++)
            if (!keep[p] && reach[p] > tolerance)
                keep[p] = 1;
        sl_triangle_bvh_release(&bvh);
    }
    free(tri);
    free(reach);
    return rc;
}

int refine_drop_parts(sl_lod_mesh *mesh, double min_fraction, double reach,
                      refine_parts *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    if (mesh->triangle_count == 0 || !(min_fraction > 0))
        return 0;
    uint32_t *part = malloc(mesh->triangle_count * sizeof *part);
    uint32_t *new_index = malloc((mesh->vertex_count ? mesh->vertex_count : 1) * sizeof *new_index);
    if (!part || !new_index) {
        free(part);
        free(new_index);
        return sl_error_nomem(err, NULL, "out of memory");
    }
    sl_mesh view = sl_mesh_view(mesh->vertex_count, mesh->positions, NULL, NULL, mesh->triangle_count, mesh->indices);
    double *area = NULL;
    uint64_t parts = 0;
    int rc = sl_mesh_parts(&view, part, &area, &parts, err);
    unsigned char *keep = rc ? NULL : calloc(parts ? parts : 1, 1);
    if (rc == 0 && !keep)
        rc = sl_error_nomem(err, NULL, "out of memory");
    if (rc == 0) {
        double total = 0;
        uint64_t largest = 0;
        for (uint64_t p = 0; p < parts; p++) {
            total += area[p];
            if (area[p] > area[largest])
                largest = p;
        }
        for (uint64_t p = 0; p < parts; p++)
            keep[p] = p == largest || area[p] >= min_fraction * total;
        rc = keep_uncovered(mesh, part, parts, keep, reach * mean_edge(total, mesh->triangle_count), err);
        for (uint64_t p = 0; p < parts && rc == 0; p++)
            if (!keep[p]) {
                out->parts++;
                out->area_fraction += total > 0 ? area[p] / total : 0;
            }
        if (rc == 0 && out->parts) {
            uint64_t before = mesh->triangle_count;
            compact(mesh, part, keep, new_index);
            out->triangles = before - mesh->triangle_count;
        }
    }
    free(keep);
    free(area);
    free(part);
    free(new_index);
    return rc;
}
