/* Input vertices -> points (docs/range-stage.md, "Decisions": the PLY vertices that faces
 * reference, exact duplicates welded first, since scans often come unwelded).
 *
 * Weld rule: two finite vertices weld when their three coordinates compare equal as
 * floats (so -0.0 welds with +0.0); the group's representative is its lowest input index.
 * Found by a stable LSD radix sort of the vertices on (x, y, z) starting from index order,
 * which leaves every group as one run with its lowest index first: O(n), no hashing, and
 * the result does not depend on the thread count. Every pass runs in parallel: the sort
 * in the key tables' slices, the compactions and numberings in fixed slices of the input
 * (counted, prefixed, then written), so the output is the serial loops' bits.
 * Faces: a face with a non-finite corner is dropped (counted as nonfinite_faces); after
 * welding, a face with a repeated corner or an exactly zero cross product is degenerate.
 * Points are the representatives that a kept face references, numbered in input order;
 * a mesh without faces is a point cloud and keeps every representative.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/key_table.h"
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

/* Fixed slices of the loops that compact or number in input order (sl_slice_begin). */
#define SLICES 64

/* rep[v] = lowest index with the same position, for finite v; RANGE_NONE otherwise.
 * The finite vertices as (key, value) pairs sorted by the key tables' stable radix sort
 * (in parallel slices, the same order on any thread count): first on z's key, then on
 * x's and y's with z's key carried in the value beside the index, so a group of equal
 * positions is one run, lowest index first, found without reading the positions again. */
static int weld_vertices(const sl_mesh *mesh, const uint8_t *finite, uint32_t *rep,
                         uint64_t *welded, sl_error *err)
{
    uint64_t n = mesh->vertex_count;
    uint64_t first[SLICES + 1];
    first[0] = 0;
#pragma omp parallel for schedule(dynamic, 1)
    for (int s = 0; s < SLICES; s++) {
        uint64_t c = 0;
        for (uint64_t v = sl_slice_begin(n, s, SLICES); v < sl_slice_begin(n, s + 1, SLICES); v++) {
            rep[v] = RANGE_NONE;
            c += finite[v];
        }
        first[s + 1] = c;
    }
    for (int s = 0; s < SLICES; s++)
        first[s + 1] += first[s];
    uint64_t m = first[SLICES];
    sl_key_pair *pairs = malloc((m ? m : 1) * sizeof *pairs);
    if (!pairs)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "weld: out of memory (%llu vertices)",
                            (unsigned long long)n);
#pragma omp parallel for schedule(dynamic, 1)
    for (int s = 0; s < SLICES; s++) {
        uint64_t i = first[s];
        for (uint64_t v = sl_slice_begin(n, s, SLICES); v < sl_slice_begin(n, s + 1, SLICES); v++)
            if (finite[v])
                pairs[i++] = (sl_key_pair){sortable_key(mesh->positions[3 * v + 2]), v};
    }
    int rc = sl_sort_pairs(pairs, m, 32);
    if (rc == 0) {
#pragma omp parallel for schedule(static)
        for (uint64_t i = 0; i < m; i++) {
            const float *p = mesh->positions + 3 * pairs[i].value;
            pairs[i].value |= pairs[i].key << 32; /* z's key above the index */
            pairs[i].key = (uint64_t)sortable_key(p[0]) << 32 | sortable_key(p[1]);
        }
        rc = sl_sort_pairs(pairs, m, 64);
    }
    if (rc) {
        free(pairs);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "weld: out of memory (%llu vertices)",
                            (unsigned long long)n);
    }
    /* A run of equal (key, z key) is a group; sortable keys are equal exactly when the
     * floats compare equal (finite values, -0 as +0). A slice starting inside a group
     * looks back for its first element. */
    uint64_t count = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : count)
    for (int s = 0; s < SLICES; s++) {
        uint64_t lo = sl_slice_begin(m, s, SLICES), hi = sl_slice_begin(m, s + 1, SLICES), head = lo;
        while (head > 0 && pairs[head - 1].key == pairs[lo].key &&
               pairs[head - 1].value >> 32 == pairs[lo].value >> 32)
            head--;
        for (uint64_t i = lo; i < hi; i++) {
            if (i > head && (pairs[i].key != pairs[head].key ||
                             pairs[i].value >> 32 != pairs[head].value >> 32))
                head = i;
            rep[(uint32_t)pairs[i].value] = (uint32_t)pairs[head].value;
            count += i > head;
        }
    }
    *welded = count;
    free(pairs);
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
    uint64_t first[SLICES + 1], nonfinite = 0, degenerate = 0;
    first[0] = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : nonfinite, degenerate)
    for (int s = 0; s < SLICES; s++) {
        uint64_t kept = 0;
        for (uint64_t t = sl_slice_begin(nt, s, SLICES); t < sl_slice_begin(nt, s + 1, SLICES); t++) {
            cls[t] = (uint8_t)classify_face(mesh, finite, rep, t);
            kept += cls[t] == FACE_KEEP;
            nonfinite += cls[t] == FACE_NONFINITE;
            degenerate += cls[t] == FACE_DEGENERATE;
        }
        first[s + 1] = kept;
    }
    for (int s = 0; s < SLICES; s++)
        first[s + 1] += first[s];
    uint64_t kept = first[SLICES];
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
#pragma omp parallel for schedule(dynamic, 1)
    for (int s = 0; s < SLICES; s++) {
        uint64_t k = first[s];
        for (uint64_t t = sl_slice_begin(nt, s, SLICES); t < sl_slice_begin(nt, s + 1, SLICES); t++) {
            if (cls[t] != FACE_KEEP)
                continue;
            for (int c = 0; c < 3; c++)
                out->triangles[3 * k + c] = rep[mesh->triangles[3 * t + c]];
            out->triangle_source[k++] = t;
        }
    }
    free(cls);
    return SL_OK;
}

/* Numbers the referenced representatives in input order and remaps the triangles. */
static int number_points(const sl_mesh *mesh, const uint32_t *rep, range_clean *out,
                         sl_range_counts *counts, sl_error *err)
{
    uint64_t n = mesh->vertex_count, corners = 3 * out->triangle_count;
    int cloud = mesh->triangle_count == 0;
    uint32_t *point_of_rep = out->vertex_point; /* reused: first per rep, then per vertex */
#pragma omp parallel for schedule(static)
    for (uint64_t v = 0; v < n; v++)
        point_of_rep[v] = RANGE_NONE;
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < corners; i++) {
        uint32_t *mark = &point_of_rep[out->triangles[i]];
#pragma omp atomic write
        *mark = 0; /* referenced (every writer writes the same 0) */
    }
    uint64_t first[SLICES + 1], unreferenced = 0;
    first[0] = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : unreferenced)
    for (int s = 0; s < SLICES; s++) {
        uint64_t points = 0;
        for (uint64_t v = sl_slice_begin(n, s, SLICES); v < sl_slice_begin(n, s + 1, SLICES); v++) {
            if (rep[v] != v)
                continue;
            if (cloud || point_of_rep[v] == 0)
                points++;
            else
                unreferenced++;
        }
        first[s + 1] = points;
    }
    for (int s = 0; s < SLICES; s++)
        first[s + 1] += first[s];
    uint64_t points = first[SLICES];
    out->point_count = points;
    counts->unreferenced = unreferenced;
    out->point_vertex = malloc((points ? points : 1) * sizeof *out->point_vertex);
    if (!out->point_vertex)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "weld: out of memory (%llu points)",
                            (unsigned long long)points);
#pragma omp parallel for schedule(dynamic, 1)
    for (int s = 0; s < SLICES; s++) {
        uint64_t p = first[s];
        for (uint64_t v = sl_slice_begin(n, s, SLICES); v < sl_slice_begin(n, s + 1, SLICES); v++)
            if (rep[v] == v && (cloud || point_of_rep[v] == 0)) {
                point_of_rep[v] = (uint32_t)p;
                out->point_vertex[p++] = (uint32_t)v;
            }
    }
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < corners; i++)
        out->triangles[i] = point_of_rep[out->triangles[i]];
    /* Welded twins take their representative's point (a representative is never a twin,
     * so no loop reads what another writes). */
#pragma omp parallel for schedule(static)
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
