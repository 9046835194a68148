/* Surface-to-surface distance by area sampling (see mesh_distance.h, docs/fidelity.md).
 *
 * The work is cut into chunks of CHUNK triangles (area samples) or CHUNK vertices
 * (vertex samples) whose boundaries do not depend on the thread count. Each chunk runs
 * its samples in a fixed order with its own closest-triangle hint and writes one
 * partial result; the partials are combined serially in chunk order. So every figure
 * is bit-identical for 1 or N threads.
 */
#include "geometry/mesh_distance.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_distance_internal.h"

sl_mesh_distance_config sl_mesh_distance_default_config(void)
{
    sl_mesh_distance_config cfg = {SL_MESH_DISTANCE_DEFAULT_SAMPLES, 1};
    return cfg;
}

static void corners_of(const sl_mesh *m, uint64_t t, double a[3], double b[3], double c[3])
{
    const uint32_t *tri = &m->triangles[3 * t];
    for (int i = 0; i < 3; i++) {
        a[i] = m->positions[3 * (uint64_t)tri[0] + i];
        b[i] = m->positions[3 * (uint64_t)tri[1] + i];
        c[i] = m->positions[3 * (uint64_t)tri[2] + i];
    }
}

static double triangle_area(const sl_mesh *m, uint64_t t)
{
    double a[3], b[3], c[3];
    corners_of(m, t, a, b, c);
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                   u[0] * v[1] - u[1] * v[0]};
    return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* The precondition of the distance: what is wrong with `m` as a surface, into `why`
 * (SL_E_BADINPUT), or SL_OK. Fills `used` (vertex_count flags) and the bounds of the
 * used vertices. */
static int surface_problem(const sl_mesh *m, uint8_t *used, double lo[3], double hi[3],
                           char *why, size_t size)
{
    if (m->triangle_count == 0)
        return snprintf(why, size, "no triangles"), SL_E_BADINPUT;
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++) {
        if (m->triangles[i] >= m->vertex_count)
            return snprintf(why, size, "triangle %llu uses vertex %u of %llu",
                            (unsigned long long)(i / 3), m->triangles[i],
                            (unsigned long long)m->vertex_count), SL_E_BADINPUT;
        used[m->triangles[i]] = 1;
    }
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    for (uint64_t v = 0; v < m->vertex_count; v++) {
        if (!used[v])
            continue;
        for (int a = 0; a < 3; a++) {
            double x = m->positions[3 * v + a];
            if (!isfinite(x))
                return snprintf(why, size, "vertex %llu has a non-finite coordinate",
                                (unsigned long long)v), SL_E_BADINPUT;
            lo[a] = fmin(lo[a], x);
            hi[a] = fmax(hi[a], x);
        }
    }
    double area = 0.0;
    for (uint64_t t = 0; t < m->triangle_count; t++)
        area += triangle_area(m, t);
    if (!(area > 0.0) || !isfinite(area))
        return snprintf(why, size, "every triangle has zero area"), SL_E_BADINPUT;
    return SL_OK;
}

int md_check_surface(surface *s, const sl_mesh *m, const char *name, const char *file,
                         sl_error *err)
{
    char why[160];
    s->mesh = m;
    s->name = name;
    s->used = calloc(m->vertex_count ? m->vertex_count : 1, 1);
    if (!s->used)
        return sl_error_set(err, SL_E_NOMEM, 0, file, "vertex flags of mesh %s", name);
    int rc = surface_problem(m, s->used, s->lo, s->hi, why, sizeof why);
    if (rc == SL_OK)
        return SL_OK;
    if (file)
        return sl_error_set(err, rc, 0, file, "%s", why);
    return sl_error_set(err, rc, 0, NULL, "mesh %s: %s", name, why);
}

int sl_mesh_check_surface(const sl_mesh *m, const char *file, sl_error *err)
{
    surface s;
    int rc = md_check_surface(&s, m, "", file, err);
    free(s.used);
    return rc;
}

/* splitmix64's finaliser: a counter-based generator, so a sample's position depends
 * only on (seed, triangle, index) and never on which thread draws it. */
static uint64_t mix64(uint64_t x)
{
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    x ^= x >> 31;
    return x;
}

static double unit_random(uint64_t seed, uint64_t triangle, uint64_t index, uint64_t stream)
{
    uint64_t h = mix64(seed * 0x9e3779b97f4a7c15ull + triangle);
    h = mix64(h ^ (index * 2 + stream) * 0xd1b54a32d192ed03ull);
    return (double)(h >> 11) * 0x1.0p-53;
}

void md_accumulate(partial *acc, double d_sq, int area_sample)
{
    double d = sqrt(d_sq);
    if (d > acc->max)
        acc->max = d;
    if (area_sample) {
        acc->sum += d;
        acc->sum_sq += d_sq;
    }
    acc->count++;
}


/* Area samples of the triangles in one chunk. `cum` is the area before the chunk and
 * `cum_end` the area after it as the serial prefix sum has it, so the counts of all
 * chunks telescope to exactly `n` samples. With `store`, the samples are written there
 * (count in the result) instead of measured against `target`. */
partial md_sample_triangles(const sl_mesh *m, uint64_t first, uint64_t end, double cum,
                                double cum_end, double total, uint64_t n, uint64_t seed,
                                const sl_triangle_bvh *target, const sample_store *store)
{
    partial acc = {0.0, 0.0, 0.0, 0};
    uint32_t hint = UINT32_MAX;
    uint64_t before = (uint64_t)floor((double)n * (cum / total));
    for (uint64_t t = first; t < end; t++) {
        cum = t + 1 == end ? cum_end : cum + triangle_area(m, t);
        uint64_t after = (uint64_t)floor((double)n * (cum / total));
        if (after > n)
            after = n;
        uint64_t count = after > before ? after - before : 0;
        before = after > before ? after : before;
        if (count == 0)
            continue;
        double a[3], b[3], c[3];
        corners_of(m, t, a, b, c);
        for (uint64_t k = 0; k < count; k++) {
            /* Uniform by area: s = sqrt(u1) (Osada et al. 2002, eq. 1). */
            double s = sqrt(unit_random(seed, t, k, 0)), r = unit_random(seed, t, k, 1);
            double wa = 1.0 - s, wb = s * (1.0 - r), wc = s * r, p[3];
            for (int i = 0; i < 3; i++)
                p[i] = wa * a[i] + wb * b[i] + wc * c[i];
            if (store) { /* drawn for later queries */
                if (store->points)
                    memcpy(store->points + 3 * acc.count, p, sizeof p);
                if (store->records)
                    store->records[acc.count] = (sl_area_sample){(uint32_t)t, (float)wb,
                                                                 (float)wc};
                acc.count++;
                continue;
            }
            sl_closest q;
            sl_triangle_bvh_closest(target, p, hint, &q);
            hint = q.triangle;
            md_accumulate(&acc, q.distance_sq, 1);
        }
    }
    return acc;
}

/* The used vertices of `src` in [first, end); `in_means`: they also count towards mean
 * and rms (a point cloud's only samples), else towards the maximum alone. */
partial md_sample_vertices(const surface *src, uint64_t first, uint64_t end,
                               const sl_triangle_bvh *target, int in_means)
{
    partial acc = {0.0, 0.0, 0.0, 0};
    uint32_t hint = UINT32_MAX;
    for (uint64_t v = first; v < end; v++) {
        if (!src->used[v])
            continue;
        const float *f = &src->mesh->positions[3 * v];
        double p[3] = {f[0], f[1], f[2]};
        sl_closest q;
        sl_triangle_bvh_closest(target, p, hint, &q);
        hint = q.triangle;
        md_accumulate(&acc, q.distance_sq, in_means);
    }
    return acc;
}

uint64_t md_chunks_of(uint64_t n)
{
    return (n + CHUNK - 1) / CHUNK;
}

/* cum[c] = area of the triangles before chunk c, summed chunk by chunk in order;
 * cum has chunks + 1 entries. */
void md_prefix_areas(const sl_mesh *m, double *cum, uint64_t chunks)
{
#pragma omp parallel for schedule(static)
    for (uint64_t c = 0; c < chunks; c++) {
        uint64_t end = (c + 1) * CHUNK < m->triangle_count ? (c + 1) * CHUNK : m->triangle_count;
        double area = 0.0;
        for (uint64_t t = c * CHUNK; t < end; t++)
            area += triangle_area(m, t);
        cum[c + 1] = area;
    }
    cum[0] = 0.0;
    for (uint64_t c = 0; c < chunks; c++)
        cum[c + 1] += cum[c];
}

/* Inside a parallel loop: whether to skip the rest, the run having been interrupted (by
 * `progress`, or as seen by another thread through the shared flag). */
int md_stopping(int *interrupted, sl_progress *progress)
{
    int stop;
#pragma omp atomic read
    stop = *interrupted;
    if (!stop && !sl_progress_interrupted(progress))
        return 0;
#pragma omp atomic write
    *interrupted = 1;
    return 1;
}

/* A side's figures from its chunks' partials, summed in chunk order: the first
 * `area_chunks` are area samples (mean and RMS), the rest vertices (the maximum alone). */
void md_side_of(const partial *parts, uint64_t area_chunks, uint64_t chunks,
                    sl_distance_side *side)
{
    partial area = {0.0, 0.0, 0.0, 0}, verts = {0.0, 0.0, 0.0, 0};
    for (uint64_t c = 0; c < chunks; c++) {
        partial *acc = c < area_chunks ? &area : &verts;
        acc->max = fmax(acc->max, parts[c].max);
        acc->sum += parts[c].sum;
        acc->sum_sq += parts[c].sum_sq;
        acc->count += parts[c].count;
    }
    side->world.hausdorff = fmax(area.max, verts.max);
    side->world.mean = area.count ? area.sum / (double)area.count : 0.0;
    side->world.rms = area.count ? sqrt(area.sum_sq / (double)area.count) : 0.0;
    side->area_samples = area.count;
    side->vertex_samples = verts.count;
}

/* One direction: samples of `src` against `target`, into `side` (world units). */
int md_measure_side(const surface *src, const sl_triangle_bvh *target,
                        const sl_mesh_distance_config *cfg, int with_vertices,
                        sl_distance_side *side, sl_progress *progress, sl_error *err)
{
    const sl_mesh *m = src->mesh;
    uint64_t tri_chunks = md_chunks_of(m->triangle_count);
    uint64_t vert_chunks = with_vertices ? md_chunks_of(m->vertex_count) : 0;
    double *cum = malloc((tri_chunks + 1) * sizeof *cum);
    partial *parts = malloc((tri_chunks + vert_chunks) * sizeof *parts);
    if (!cum || !parts) {
        free(cum);
        free(parts);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "sample bookkeeping of mesh %s",
                            src->name);
    }
    md_prefix_areas(m, cum, tri_chunks);
    double total = cum[tri_chunks]; /* > 0: md_check_surface() saw a nonzero area */

    int interrupted = 0;
#pragma omp parallel for schedule(dynamic, 1)
    for (uint64_t c = 0; c < tri_chunks + vert_chunks; c++) {
        if (md_stopping(&interrupted, progress))
            continue;
        if (c < tri_chunks) {
            uint64_t end = (c + 1) * CHUNK < m->triangle_count ? (c + 1) * CHUNK
                                                               : m->triangle_count;
            parts[c] = md_sample_triangles(m, c * CHUNK, end, cum[c], cum[c + 1], total,
                                        cfg->samples, cfg->seed, target, NULL);
        } else {
            uint64_t v = (c - tri_chunks) * CHUNK;
            uint64_t end = v + CHUNK < m->vertex_count ? v + CHUNK : m->vertex_count;
            parts[c] = md_sample_vertices(src, v, end, target, 0);
        }
    }
    free(cum);
    if (interrupted) {
        free(parts);
        return sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "distance sampling of mesh %s",
                            src->name);
    }

    md_side_of(parts, tri_chunks, tri_chunks + vert_chunks, side);
    free(parts);
    return SL_OK;
}

static sl_distance_figures figures_over(sl_distance_figures w, double diagonal)
{
    double scale = diagonal > 0.0 ? 1.0 / diagonal : 0.0;
    sl_distance_figures f = {w.hausdorff * scale, w.mean * scale, w.rms * scale};
    return f;
}

void md_fill_out(sl_mesh_distance *out, const surface *a)
{
    double d_sq = 0.0;
    for (int i = 0; i < 3; i++)
        d_sq += (a->hi[i] - a->lo[i]) * (a->hi[i] - a->lo[i]);
    out->diagonal = sqrt(d_sq);
    out->world.hausdorff = fmax(out->a_to_b.world.hausdorff, out->b_to_a.world.hausdorff);
    out->world.mean = fmax(out->a_to_b.world.mean, out->b_to_a.world.mean);
    out->world.rms = fmax(out->a_to_b.world.rms, out->b_to_a.world.rms);
    out->a_to_b.fraction = figures_over(out->a_to_b.world, out->diagonal);
    out->b_to_a.fraction = figures_over(out->b_to_a.world, out->diagonal);
    out->fraction = figures_over(out->world, out->diagonal);
}

/* A point cloud as A: its bounds, every point finite, every point flagged used. */
static int check_points(surface *sa, const sl_mesh *a, sl_error *err)
{
    sa->mesh = a;
    sa->name = "A";
    if (a->vertex_count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "mesh A: no triangles and no points");
    sa->used = malloc(a->vertex_count);
    if (!sa->used)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "vertex flags of mesh A");
    memset(sa->used, 1, a->vertex_count);
    for (int i = 0; i < 3; i++)
        sa->lo[i] = sa->hi[i] = a->positions[i];
    for (uint64_t v = 0; v < a->vertex_count; v++)
        for (int i = 0; i < 3; i++) {
            double x = a->positions[3 * v + i];
            if (!isfinite(x))
                return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                    "mesh A: point %llu has a non-finite coordinate",
                                    (unsigned long long)v);
            sa->lo[i] = fmin(sa->lo[i], x);
            sa->hi[i] = fmax(sa->hi[i], x);
        }
    return SL_OK;
}

/* Every point of `src` against `target`; mean and rms over the points. */
static int measure_points(const surface *src, const sl_triangle_bvh *target,
                          sl_distance_side *side, sl_error *err)
{
    uint64_t n = src->mesh->vertex_count, chunks = md_chunks_of(n);
    partial *parts = malloc(chunks * sizeof *parts);
    if (!parts)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "sample bookkeeping of mesh A");
#pragma omp parallel for schedule(dynamic, 1)
    for (uint64_t c = 0; c < chunks; c++)
        parts[c] = md_sample_vertices(src, c * CHUNK, (c + 1) * CHUNK < n ? (c + 1) * CHUNK : n,
                                   target, 1);
    partial all = {0.0, 0.0, 0.0, 0};
    for (uint64_t c = 0; c < chunks; c++) {
        all.max = fmax(all.max, parts[c].max);
        all.sum += parts[c].sum;
        all.sum_sq += parts[c].sum_sq;
        all.count += parts[c].count;
    }
    free(parts);
    side->world.hausdorff = all.max;
    side->world.mean = all.sum / (double)all.count;
    side->world.rms = sqrt(all.sum_sq / (double)all.count);
    side->vertex_samples = all.count;
    return SL_OK;
}

int sl_mesh_distance_compute(const sl_mesh *a, const sl_mesh *b,
                             const sl_mesh_distance_config *cfg, sl_mesh_distance *out,
                             sl_progress *progress, sl_error *err)
{
    sl_mesh_distance_config defaults = sl_mesh_distance_default_config();
    if (!cfg)
        cfg = &defaults;
    memset(out, 0, sizeof *out);
    if (cfg->samples == 0)
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "sample count must be at least 1");

    surface sa = {0}, sb = {0};
    sl_triangle_bvh bvh_a = {0}, bvh_b = {0};
    out->a_is_points = a->triangle_count == 0;
    int rc = out->a_is_points ? check_points(&sa, a, err) : md_check_surface(&sa, a, "A", NULL, err);
    if (rc == SL_OK)
        rc = md_check_surface(&sb, b, "B", NULL, err);
    if (rc == SL_OK)
        rc = sl_triangle_bvh_build(&bvh_b, b, err);
    if (rc == SL_OK && out->a_is_points) {
        rc = measure_points(&sa, &bvh_b, &out->a_to_b, err);
        if (rc == SL_OK && sl_progress_interrupted(progress))
            rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "distance of points A");
        sl_triangle_bvh_release(&bvh_b);
        if (rc == SL_OK)
            md_fill_out(out, &sa);
        free(sa.used);
        free(sb.used);
        return rc;
    }
    if (rc == SL_OK)
        rc = md_measure_side(&sa, &bvh_b, cfg, 1, &out->a_to_b, progress, err);
    sl_triangle_bvh_release(&bvh_b);
    if (rc == SL_OK)
        rc = sl_triangle_bvh_build(&bvh_a, a, err);
    if (rc == SL_OK)
        rc = md_measure_side(&sb, &bvh_a, cfg, 1, &out->b_to_a, progress, err);
    sl_triangle_bvh_release(&bvh_a);
    if (rc == SL_OK)
        md_fill_out(out, &sa);
    free(sa.used);
    free(sb.used);
    return rc;
}

uint64_t sl_mesh_area_samples_bound(const sl_mesh *m, uint64_t samples)
{
    return samples + md_chunks_of(m->triangle_count);
}

int sl_mesh_area_samples(const sl_mesh *m, uint64_t samples, uint64_t seed,
                         sl_area_sample *out, uint64_t *count, sl_error *err)
{
    uint64_t chunks = md_chunks_of(m->triangle_count);
    double *cum = malloc((chunks + 1) * sizeof *cum);
    *count = 0;
    if (!cum)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "area sample bookkeeping");
    md_prefix_areas(m, cum, chunks);
    for (uint64_t c = 0; c < chunks; c++) { /* serial: each chunk's samples follow */
        uint64_t end = (c + 1) * CHUNK < m->triangle_count ? (c + 1) * CHUNK : m->triangle_count;
        sample_store store = {NULL, out + *count};
        *count += md_sample_triangles(m, c * CHUNK, end, cum[c], cum[c + 1], cum[chunks],
                                   samples, seed, NULL, &store).count;
    }
    free(cum);
    return SL_OK;
}
