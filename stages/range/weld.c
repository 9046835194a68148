/* Input vertices -> points (docs/range-stage.md, "Decisions": the PLY vertices that faces
 * reference, exact duplicates welded first, since scans often come unwelded).
 *
 * Weld rule: two finite vertices weld when their three coordinates compare equal as
 * floats (so -0.0 welds with +0.0); the group's representative is its lowest input index.
 * Found by a stable LSD radix sort of the vertices on (x, y, z) starting from index order,
 * which leaves every group as one run with its lowest index first: O(n), no hashing, and
 * the result does not depend on the thread count.
 * Faces: a face with a non-finite corner is dropped (counted as nonfinite_faces); after
 * welding, a face with a repeated corner or an exactly zero cross product is degenerate.
 * Points are the representatives that a kept face references, numbered in input order;
 * a mesh without faces is a point cloud and keeps every representative.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/range/range_internal.h"

enum { FACE_KEEP = 0, FACE_NONFINITE = 1, FACE_DEGENERATE = 2 };

/* Float bits -> unsigned key with the same order as the float values (finite inputs). */
static uint32_t sortable_key(float f)
{
    if (f == 0.0f)
        f = 0.0f; /* -0.0 sorts (and welds) with +0.0 */
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

/* Stable counting-sort pass of `src` into `dst` on 16 bits of the keys. */
static void radix_pass(const uint32_t *src, uint32_t *dst, uint64_t n, const uint32_t *keys,
                       int shift, uint64_t *histogram)
{
    memset(histogram, 0, 65536 * sizeof *histogram);
    for (uint64_t i = 0; i < n; i++)
        histogram[(keys[src[i]] >> shift) & 0xffffu]++;
    uint64_t sum = 0;
    for (int d = 0; d < 65536; d++) {
        uint64_t c = histogram[d];
        histogram[d] = sum;
        sum += c;
    }
    for (uint64_t i = 0; i < n; i++)
        dst[histogram[(keys[src[i]] >> shift) & 0xffffu]++] = src[i];
}

/* rep[v] = lowest index with the same position, for finite v; RANGE_NONE otherwise. */
static int weld_vertices(const sl_mesh *mesh, const uint8_t *finite, uint32_t *rep,
                         uint64_t *welded, sl_error *err)
{
    uint64_t n = mesh->vertex_count, m = 0;
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    uint32_t *tmp = malloc((n ? n : 1) * sizeof *tmp);
    uint32_t *keys = malloc((n ? n : 1) * sizeof *keys);
    uint64_t *histogram = malloc(65536 * sizeof *histogram);
    if (!order || !tmp || !keys || !histogram) {
        free(order), free(tmp), free(keys), free(histogram);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "weld: out of memory (%llu vertices)",
                            (unsigned long long)n);
    }
    for (uint64_t v = 0; v < n; v++) {
        rep[v] = RANGE_NONE;
        if (finite[v])
            order[m++] = (uint32_t)v;
    }
    /* Least significant key first: z, y, x; each in two 16-bit passes. */
    for (int axis = 2; axis >= 0; axis--) {
        for (uint64_t i = 0; i < m; i++)
            keys[order[i]] = sortable_key(mesh->positions[3 * (uint64_t)order[i] + axis]);
        radix_pass(order, tmp, m, keys, 0, histogram);
        radix_pass(tmp, order, m, keys, 16, histogram);
    }
    uint64_t count = 0;
    for (uint64_t i = 0; i < m;) {
        const float *p = mesh->positions + 3 * (uint64_t)order[i];
        uint64_t j = i + 1;
        while (j < m) {
            const float *q = mesh->positions + 3 * (uint64_t)order[j];
            if (p[0] != q[0] || p[1] != q[1] || p[2] != q[2])
                break;
            j++;
        }
        for (uint64_t g = i; g < j; g++)
            rep[order[g]] = order[i];
        count += j - i - 1;
        i = j;
    }
    *welded = count;
    free(order), free(tmp), free(keys), free(histogram);
    return SL_OK;
}

static int classify_face(const sl_mesh *mesh, const uint8_t *finite, const uint32_t *rep,
                         uint64_t t)
{
    const uint32_t *tri = mesh->triangles + 3 * t;
    if (!finite[tri[0]] || !finite[tri[1]] || !finite[tri[2]])
        return FACE_NONFINITE;
    uint32_t a = rep[tri[0]], b = rep[tri[1]], c = rep[tri[2]];
    if (a == b || b == c || a == c)
        return FACE_DEGENERATE;
    const float *pa = mesh->positions + 3 * (uint64_t)a;
    const float *pb = mesh->positions + 3 * (uint64_t)b;
    const float *pc = mesh->positions + 3 * (uint64_t)c;
    double u[3], w[3];
    for (int k = 0; k < 3; k++) {
        u[k] = (double)pb[k] - pa[k];
        w[k] = (double)pc[k] - pa[k];
    }
    double nx = u[1] * w[2] - u[2] * w[1];
    double ny = u[2] * w[0] - u[0] * w[2];
    double nz = u[0] * w[1] - u[1] * w[0];
    return (nx == 0.0 && ny == 0.0 && nz == 0.0) ? FACE_DEGENERATE : FACE_KEEP;
}

/* Classifies every face, then compacts the kept ones in input order. */
static int keep_faces(const sl_mesh *mesh, const uint8_t *finite, const uint32_t *rep,
                      range_clean *out, sl_range_counts *counts, sl_error *err)
{
    uint64_t nt = mesh->triangle_count;
    uint8_t *cls = malloc(nt ? nt : 1);
    if (!cls)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "weld: out of memory (%llu faces)",
                            (unsigned long long)nt);
    uint64_t kept = 0, nonfinite = 0, degenerate = 0;
#pragma omp parallel for schedule(static) reduction(+ : kept, nonfinite, degenerate)
    for (int64_t t = 0; t < (int64_t)nt; t++) {
        cls[t] = (uint8_t)classify_face(mesh, finite, rep, (uint64_t)t);
        kept += cls[t] == FACE_KEEP;
        nonfinite += cls[t] == FACE_NONFINITE;
        degenerate += cls[t] == FACE_DEGENERATE;
    }
    counts->nonfinite_faces = nonfinite;
    counts->degenerate_faces = degenerate;
    out->triangle_count = kept;
    out->triangles = malloc((kept ? kept : 1) * 3 * sizeof *out->triangles);
    out->triangle_source = malloc((kept ? kept : 1) * sizeof *out->triangle_source);
    if (!out->triangles || !out->triangle_source) {
        free(cls);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "weld: out of memory (%llu faces)",
                            (unsigned long long)kept);
    }
    uint64_t k = 0;
    for (uint64_t t = 0; t < nt; t++) {
        if (cls[t] != FACE_KEEP)
            continue;
        for (int c = 0; c < 3; c++)
            out->triangles[3 * k + c] = rep[mesh->triangles[3 * t + c]];
        out->triangle_source[k++] = t;
    }
    free(cls);
    return SL_OK;
}

/* Numbers the referenced representatives in input order and remaps the triangles. */
static int number_points(const sl_mesh *mesh, const uint32_t *rep, range_clean *out,
                         sl_range_counts *counts, sl_error *err)
{
    uint64_t n = mesh->vertex_count;
    int cloud = mesh->triangle_count == 0;
    uint32_t *point_of_rep = out->vertex_point; /* reused: first per rep, then per vertex */
    for (uint64_t v = 0; v < n; v++)
        point_of_rep[v] = RANGE_NONE;
    for (uint64_t i = 0; i < 3 * out->triangle_count; i++)
        point_of_rep[out->triangles[i]] = 0; /* referenced */
    uint64_t points = 0, unreferenced = 0;
    for (uint64_t v = 0; v < n; v++) {
        if (rep[v] != v)
            continue;
        if (cloud || point_of_rep[v] == 0)
            point_of_rep[v] = (uint32_t)points++;
        else
            unreferenced++;
    }
    out->point_count = points;
    counts->unreferenced = unreferenced;
    out->point_vertex = malloc((points ? points : 1) * sizeof *out->point_vertex);
    if (!out->point_vertex)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "weld: out of memory (%llu points)",
                            (unsigned long long)points);
    for (uint64_t v = 0; v < n; v++)
        if (rep[v] == v && point_of_rep[v] != RANGE_NONE)
            out->point_vertex[point_of_rep[v]] = (uint32_t)v;
    for (uint64_t i = 0; i < 3 * out->triangle_count; i++)
        out->triangles[i] = point_of_rep[out->triangles[i]];
    /* Welded twins take their representative's point (reps come first in index order). */
    for (uint64_t v = 0; v < n; v++)
        if (rep[v] != RANGE_NONE && rep[v] != v)
            point_of_rep[v] = point_of_rep[rep[v]];
    return SL_OK;
}

int range_clean_mesh(const sl_mesh *mesh, range_clean *out, sl_range_counts *counts,
                     sl_progress *progress, sl_error *err)
{
    memset(out, 0, sizeof *out);
    uint64_t n = mesh->vertex_count;
    uint8_t *finite = malloc(n ? n : 1);
    uint32_t *rep = malloc((n ? n : 1) * sizeof *rep);
    out->vertex_point = malloc((n ? n : 1) * sizeof *out->vertex_point);
    int rc = SL_OK;
    if (!finite || !rep || !out->vertex_point) {
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "weld: out of memory (%llu vertices)",
                          (unsigned long long)n);
        goto done;
    }
    uint64_t nonfinite = 0;
#pragma omp parallel for schedule(static) reduction(+ : nonfinite)
    for (int64_t v = 0; v < (int64_t)n; v++) {
        const float *p = mesh->positions + 3 * v;
        finite[v] = isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
        nonfinite += !finite[v];
    }
    counts->nonfinite_vertices = nonfinite;
    if ((rc = weld_vertices(mesh, finite, rep, &counts->welded, err)) != SL_OK)
        goto done;
    if (sl_progress_step(progress, "weld", 0.5)) {
        rc = SL_E_INTERRUPTED;
        goto done;
    }
    if ((rc = keep_faces(mesh, finite, rep, out, counts, err)) != SL_OK)
        goto done;
    rc = number_points(mesh, rep, out, counts, err);
done:
    free(finite);
    free(rep);
    if (rc != SL_OK)
        range_clean_release(out);
    return rc;
}

void range_clean_release(range_clean *c)
{
    free(c->vertex_point);
    free(c->point_vertex);
    free(c->triangles);
    free(c->triangle_source);
    memset(c, 0, sizeof *c);
}
