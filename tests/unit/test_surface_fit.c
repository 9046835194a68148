/* The surface fit (geometry/surface_fit.h) on small real scans simplified by
 * meshopt_simplify (meshoptimizer 0.18): rocker_arm (closed), fandisk (sharp CAD),
 * bun_zipper_res3 (open). Checks, each measured with the project's own distance
 * (mesh_distance.h, seed 1 -- not the fit's samples):
 *   - the symmetric RMS drops by at least the factor below (measured, with margin), and
 *     never rises; the fit's own estimate agrees in direction; Hausdorff does not rise
 *   - no triangle flips against the level as given; open borders stay on the input's
 *   - locked vertices keep their bits; a split (seam) vertex stays closed
 *   - bit-identical positions and statistics on 1 and 2 threads
 *   - a point-set input (rocker_arm's vertices) fits too
 *   - bad input is refused with the level untouched; an interrupt likewise
 *   - the open edges (fit_open_edges, bucketed by vertex) are those, in the order, that
 *     sorting every edge by its vertex pair gives: on real scans and on a fan of 300
 *     triangles with a degenerate one, a doubled one and an edge in three
 * docs/surface-fit.md lists which mutation of the fit makes which check fail.
 */
#include <math.h>
#include <meshoptimizer.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "tests/check.h"
#include "geometry/mesh_distance.h"
#include "formats/ply.h"
#include "geometry/surface_fit.h"
#include "geometry/surface_fit_internal.h"
#include "geometry/vec3.h"

/* The input and a level of it, welded (the level indexes the welded vertices). */
typedef struct pair {
    const char *name;
    sl_mesh input;
    uint64_t vertex_count, triangle_count;
    float *positions;       /* welded vertices, 3 each */
    uint32_t *triangles;    /* the level */
} pair;

static sl_fit_config test_config(void)
{
    sl_fit_config cfg = sl_fit_default_config();
    cfg.samples = 40000; /* both ways: a few seconds for the whole test */
    if (check_light()) { /* ASan + UBSan Debug: the same paths on fewer samples */
        cfg.samples = 10000;
        cfg.iterations = 3;
    }
    return cfg;
}

static int load_pair(pair *p, const char *name, double fraction)
{
    char path[1024], rel[256];
    sl_error err;
    sl_error_init(&err);
    memset(p, 0, sizeof *p);
    p->name = name;
    snprintf(rel, sizeof rel, "tests/data/scans/%s.ply", name);
    if (sl_ply_read(check_source_path(rel, path, sizeof path), NULL, &p->input, NULL, NULL,
                    &err) != SL_OK) {
        CHECK_MSG(0, "%s: %s", path, err.message);
        return -1;
    }
    size_t n = 3 * (size_t)p->input.triangle_count;
    uint32_t *remap = malloc(p->input.vertex_count * sizeof *remap);
    uint32_t *welded = malloc(n * sizeof *welded);
    p->vertex_count = meshopt_generateVertexRemap(remap, p->input.triangles, n,
                                                  p->input.positions, p->input.vertex_count,
                                                  3 * sizeof(float));
    p->positions = malloc(3 * p->vertex_count * sizeof *p->positions);
    p->triangles = malloc(n * sizeof *p->triangles);
    meshopt_remapIndexBuffer(welded, p->input.triangles, n, remap);
    meshopt_remapVertexBuffer(p->positions, p->input.positions, p->input.vertex_count,
                              3 * sizeof(float), remap);
    size_t target = 3 * (size_t)llround(fraction * (double)p->input.triangle_count);
    p->triangle_count = meshopt_simplify(p->triangles, welded, n, p->positions,
                                         p->vertex_count, 3 * sizeof(float), target, 1.0f,
                                         0, NULL) / 3;
    free(remap);
    free(welded);
    return 0;
}

static void release_pair(pair *p)
{
    sl_mesh_release(&p->input);
    free(p->positions);
    free(p->triangles);
}

/* Symmetric RMS and Hausdorff, fractions of the input's diagonal (compare's measure). */
static sl_mesh_distance measure(const pair *p, const float *positions)
{
    sl_mesh_distance_config cfg = sl_mesh_distance_default_config();
    cfg.samples = check_light() ? 20000 : 100000;
    sl_mesh level = sl_mesh_view(p->vertex_count, (float *)positions, NULL, NULL,
                                 p->triangle_count, p->triangles);
    sl_mesh_distance d;
    sl_error err;
    sl_error_init(&err);
    CHECK(sl_mesh_distance_compute(&p->input, &level, &cfg, &d, NULL, &err) == SL_OK);
    return d;
}

static void normal_of(const float *pos, const uint32_t *t, double n[3])
{
    double u[3], v[3];
    for (int i = 0; i < 3; i++) {
        u[i] = (double)pos[3 * t[1] + i] - pos[3 * t[0] + i];
        v[i] = (double)pos[3 * t[2] + i] - pos[3 * t[0] + i];
    }
    sl_cross3(u, v, n);
}

/* Triangles whose normal turned by 90 degrees or more from the level as given. */
static uint64_t flipped(const pair *p, const float *before, const float *after)
{
    uint64_t count = 0;
    for (uint64_t t = 0; t < p->triangle_count; t++) {
        double a[3], b[3];
        normal_of(before, &p->triangles[3 * t], a);
        normal_of(after, &p->triangles[3 * t], b);
        count += sl_dot3(a, a) > 0.0 && !(sl_dot3(a, b) > 0.0);
    }
    return count;
}

/* --- open edges (brute force on small meshes) -------------------------------------------- */

typedef struct edge { uint32_t a, b; } edge;

static int edge_order(const void *x, const void *y)
{
    const edge *e = x, *f = y;
    return e->a != f->a ? (e->a > f->a) - (e->a < f->a) : (e->b > f->b) - (e->b < f->b);
}

/* The edges exactly one triangle has (indices into a welded vertex buffer). */
static edge *open_edges(const uint32_t *tri, uint64_t triangle_count, uint64_t *count)
{
    edge *all = malloc(3 * triangle_count * sizeof *all), *open = malloc(3 * triangle_count * sizeof *open);
    for (uint64_t c = 0; c < 3 * triangle_count; c++) {
        uint32_t a = tri[c], b = tri[c % 3 == 2 ? c - 2 : c + 1];
        all[c] = (edge){a < b ? a : b, a < b ? b : a};
    }
    qsort(all, 3 * triangle_count, sizeof *all, edge_order);
    *count = 0;
    for (uint64_t i = 0, run; i < 3 * triangle_count; i += run) {
        for (run = 1; i + run < 3 * triangle_count && !edge_order(&all[i], &all[i + run]); run++)
            ;
        if (run == 1)
            open[(*count)++] = all[i];
    }
    free(all);
    return open;
}

/* fit_open_edges against every non-degenerate edge sorted by (pair, corner): the same
 * corners in the same order, on 1 and 2 threads. */
static void check_open_edges_of(const char *what, const uint32_t *tri, uint64_t triangle_count,
                                uint32_t vertex_count)
{
    uint64_t corners = 3 * triangle_count, n = 0;
    uint64_t *keys = malloc((corners + 1) * sizeof *keys);
    uint32_t *expect = malloc((corners + 1) * sizeof *expect), *corner = malloc((corners + 1) * 4);
    for (uint64_t c = 0; c < corners; c++) {
        uint32_t a = tri[c], b = tri[c % 3 == 2 ? c - 2 : c + 1];
        if (a != b) {
            keys[n] = (uint64_t)(a < b ? a : b) << 32 | (a < b ? b : a);
            corner[n++] = (uint32_t)c;
        }
    }
    /* (pair, corner) order: insertion by key keeps the corners ascending within a pair */
    for (uint64_t i = 1; i < n; i++) {
        uint64_t k = keys[i];
        uint32_t c = corner[i];
        uint64_t j = i;
        for (; j > 0 && keys[j - 1] > k; j--) {
            keys[j] = keys[j - 1];
            corner[j] = corner[j - 1];
        }
        keys[j] = k;
        corner[j] = c;
    }
    uint64_t expected = 0;
    for (uint64_t i = 0, run; i < n; i += run) {
        for (run = 1; i + run < n && keys[i + run] == keys[i]; run++)
            ;
        if (run == 1)
            expect[expected++] = corner[i];
    }
    for (int threads = 1; threads <= 2; threads++) {
        omp_set_num_threads(threads);
        uint32_t *open = NULL;
        uint64_t count = 0;
        sl_error err;
        sl_error_init(&err);
        CHECK(fit_open_edges(tri, triangle_count, vertex_count, &open, &count, &err) == SL_OK);
        CHECK_MSG(count == expected, "%s, %d threads: %llu open edges, expected %llu", what,
                  threads, (unsigned long long)count, (unsigned long long)expected);
        CHECK_MSG(count == expected && (!count || !memcmp(open, expect, count * sizeof *open)),
                  "%s, %d threads: open edges differ from the sorted edges'", what, threads);
        free(open);
    }
    omp_set_num_threads(2);
    free(keys);
    free(expect);
    free(corner);
}

static void check_open_edges(void)
{
    const char *scans[] = {"bun_zipper_res3", "cow", "rocker_arm"};
    for (size_t i = 0; i < sizeof scans / sizeof scans[0]; i++) {
        pair p;
        if (load_pair(&p, scans[i], 0.5) != 0)
            continue;
        /* the input welded as the fit's reference welds it */
        size_t n = 3 * (size_t)p.input.triangle_count;
        uint32_t *remap = malloc(p.input.vertex_count * sizeof *remap), *tri = malloc(n * 4);
        meshopt_generateVertexRemap(remap, p.input.triangles, n, p.input.positions,
                                    p.input.vertex_count, 3 * sizeof(float));
        for (size_t c = 0; c < n; c++)
            tri[c] = remap[p.input.triangles[c]];
        check_open_edges_of(scans[i], tri, p.input.triangle_count,
                            (uint32_t)p.input.vertex_count);
        check_open_edges_of(scans[i], p.triangles, p.triangle_count,
                            (uint32_t)p.vertex_count); /* the level */
        free(remap);
        free(tri);
        release_pair(&p);
    }
    /* A fan of 300 triangles round vertex 0 (one bucket of 600 edges), then a degenerate
     * triangle, the fan's first triangle again and a third triangle on edge (1, 2). */
    enum { FAN = 300 };
    uint32_t tri[3 * (FAN + 3)];
    for (uint32_t t = 0; t < FAN; t++) {
        tri[3 * t] = 0;
        tri[3 * t + 1] = 1 + t;
        tri[3 * t + 2] = 2 + t;
    }
    uint32_t extra[9] = {5, 5, 6, 0, 1, 2, 1, 2, FAN + 2};
    memcpy(tri + 3 * FAN, extra, sizeof extra);
    check_open_edges_of("fan", tri, FAN + 3, FAN + 3);
}

static double segment_distance(const float *p, const float *a, const float *b)
{
    double d[3], e[3], dd = 0.0, de = 0.0;
    for (int i = 0; i < 3; i++) {
        d[i] = (double)b[i] - a[i];
        e[i] = (double)p[i] - a[i];
        dd += d[i] * d[i];
        de += d[i] * e[i];
    }
    double s = dd > 0.0 ? fmin(fmax(de / dd, 0.0), 1.0) : 0.0, q = 0.0;
    for (int i = 0; i < 3; i++)
        q += (e[i] - s * d[i]) * (e[i] - s * d[i]);
    return sqrt(q);
}

/* The farthest of the level's open-border vertices from the input's open border. */
static double border_gap(const pair *p, const float *positions, uint64_t *border_vertices)
{
    uint64_t n_in, n_lv;
    /* the input's open edges, welded as the level's vertices are (p->positions) */
    uint32_t *remap = malloc(p->input.vertex_count * sizeof *remap);
    uint32_t *welded = malloc(3 * p->input.triangle_count * sizeof *welded);
    meshopt_generateVertexRemap(remap, p->input.triangles, 3 * p->input.triangle_count,
                                p->input.positions, p->input.vertex_count, 3 * sizeof(float));
    meshopt_remapIndexBuffer(welded, p->input.triangles, 3 * p->input.triangle_count, remap);
    edge *in = open_edges(welded, p->input.triangle_count, &n_in);
    edge *lv = open_edges(p->triangles, p->triangle_count, &n_lv);
    double worst = 0.0;
    *border_vertices = 0;
    for (uint64_t e = 0; e < n_lv; e++) {
        const float *v = &positions[3 * (size_t)lv[e].a];
        double best = INFINITY;
        for (uint64_t f = 0; f < n_in; f++)
            best = fmin(best, segment_distance(v, &p->positions[3 * (size_t)in[f].a],
                                               &p->positions[3 * (size_t)in[f].b]));
        worst = fmax(worst, best);
        (*border_vertices)++;
    }
    free(remap);
    free(welded);
    free(in);
    free(lv);
    return worst;
}

/* --- the checks ------------------------------------------------------------------------ */

static sl_fit_reference *reference_of(const sl_mesh *input, const sl_fit_config *cfg)
{
    sl_fit_reference *ref = NULL;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_fit_reference_build(input, cfg, &ref, &err);
    CHECK_MSG(rc == SL_OK, "reference: %s", err.message);
    return ref;
}

/* A fitted copy of the level's positions (NULL if the fit failed). */
static float *fitted(const pair *p, const sl_fit_reference *ref, const sl_fit_config *cfg,
                     sl_fit_stats *st)
{
    size_t bytes = 3 * p->vertex_count * sizeof(float);
    float *out = malloc(bytes);
    memcpy(out, p->positions, bytes);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_surface_fit(ref, out, p->vertex_count, p->triangles, p->triangle_count, cfg, st,
                            NULL, &err);
    CHECK_MSG(rc == SL_OK, "%s: %s", p->name, err.message);
    if (rc != SL_OK) {
        free(out);
        return NULL;
    }
    return out;
}

typedef struct gain_case {
    const char *name, *light_name; /* the scan; a smaller one under SCANLOD_LIGHT */
    double fraction;               /* of its triangles kept by meshopt_simplify */
    double min_gain, light_gain;   /* RMS before / after, at least: measured x1.895, x1.577,
                                      x2.118 (light: x1.553, x1.517, x1.556), less 5 %: the
                                      figures are deterministic (any thread count, Debug or
                                      Release); without the level -> input term rocker_arm
                                      reaches x1.725 */
    int open;                      /* has an open border */
} gain_case;

/* RMS gain, never worse, no flips, borders kept, 1 thread = 2 threads. */
static void check_gain(const gain_case *c)
{
    pair p;
    if (load_pair(&p, check_light() ? c->light_name : c->name, c->fraction))
        return;
    sl_fit_config cfg = test_config();
    sl_fit_reference *ref = reference_of(&p.input, &cfg);
    sl_fit_stats st, st2;
    int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    float *one = ref ? fitted(&p, ref, &cfg, &st) : NULL;
    omp_set_num_threads(2);
    float *two = ref ? fitted(&p, ref, &cfg, &st2) : NULL;
    omp_set_num_threads(threads);
    if (one && two) {
        sl_mesh_distance before = measure(&p, p.positions), after = measure(&p, one);
        double gain = before.fraction.rms / after.fraction.rms;
        double level_gain = before.b_to_a.fraction.rms / after.b_to_a.fraction.rms;
        printf("%s: %llu triangles, RMS %.4e -> %.4e (x%.3f; level to input x%.3f), "
               "Hausdorff %.4e -> %.4e, backtracked %llu, fixed %llu, best round %d\n", p.name,
               (unsigned long long)p.triangle_count, before.fraction.rms, after.fraction.rms,
               gain, level_gain, before.fraction.hausdorff, after.fraction.hausdorff,
               (unsigned long long)st.vertices_backtracked, (unsigned long long)st.fixed_vertices,
               st.best_iteration);
        double least = check_light() ? c->light_gain : c->min_gain;
        CHECK_MSG(gain >= least, "%s: gain %.3f < %.3f", p.name, gain, least);
        CHECK_MSG(after.fraction.rms <= before.fraction.rms, "%s: RMS rose", p.name);
        CHECK_MSG(after.fraction.hausdorff <= before.fraction.hausdorff, "%s: Hausdorff rose",
                  p.name);
        CHECK(st.rms_after <= st.rms_before);
        CHECK_EQ_U64(flipped(&p, p.positions, one), 0);
        CHECK_MSG(!memcmp(one, two, 3 * p.vertex_count * sizeof *one) && !memcmp(&st, &st2, sizeof st),
                  "%s: 1 and 2 threads differ", p.name);
        /* A reference borrowing a distance reference's tree over the same input (the
         * refine stage's one tree) fits to the same bytes. */
        sl_distance_reference *dref = NULL;
        sl_error derr;
        sl_error_init(&derr);
        CHECK(sl_distance_reference_build(&p.input, NULL, &dref, &derr) == SL_OK);
        sl_fit_config borrow = cfg;
        borrow.surface_tree = dref ? sl_distance_reference_tree(dref) : NULL;
        sl_fit_reference *bref = dref ? reference_of(&p.input, &borrow) : NULL;
        sl_fit_stats st3;
        float *three = bref ? fitted(&p, bref, &borrow, &st3) : NULL;
        CHECK_MSG(three && !memcmp(one, three, 3 * p.vertex_count * sizeof *one) &&
                  st3.rms_after == st2.rms_after, "%s: the borrowed tree fits otherwise", p.name);
        free(three);
        sl_fit_reference_free(bref);
        sl_distance_reference_free(dref);
        uint64_t border_vertices;
        double gap = border_gap(&p, one, &border_vertices);
        CHECK_MSG(c->open == (border_vertices > 0), "%s: %llu border vertices", p.name,
                  (unsigned long long)border_vertices);
        CHECK_MSG(gap <= 1e-6 * before.diagonal, "%s: a border vertex %.3g off the input's "
                  "border", p.name, gap / before.diagonal);
    }
    free(one);
    free(two);
    sl_fit_reference_free(ref);
    release_pair(&p);
}

/* Locked vertices keep their bits while the others move; a vertex split in two at one
 * position (a texture seam) moves as one. */
static void check_locked_and_seam(void)
{
    pair p;
    if (load_pair(&p, check_light() ? "cow" : "rocker_arm", check_light() ? 0.1 : 0.05))
        return;
    sl_fit_config cfg = test_config();
    sl_fit_reference *ref = reference_of(&p.input, &cfg);
    uint8_t *locked = calloc(p.vertex_count + 1, 1);
    for (uint64_t v = 0; v < p.vertex_count; v += 3)
        locked[v] = 1;
    /* the seam: the level's first corner gets a twin vertex at its position, which the
     * level's first triangle uses instead */
    uint32_t seam = p.triangles[0];
    p.positions = realloc(p.positions, 3 * (p.vertex_count + 1) * sizeof *p.positions);
    memcpy(&p.positions[3 * p.vertex_count], &p.positions[3 * seam], 3 * sizeof(float));
    p.triangles[0] = (uint32_t)p.vertex_count++;
    locked[seam] = locked[p.vertex_count - 1] = 0;
    cfg.locked = locked;
    sl_fit_stats st;
    float *out = ref ? fitted(&p, ref, &cfg, &st) : NULL;
    if (out) {
        uint64_t moved = 0, kept = 1, used = 0;
        uint8_t *in_level = calloc(p.vertex_count, 1);
        for (uint64_t c = 0; c < 3 * p.triangle_count; c++)
            in_level[p.triangles[c]] = 1;
        for (uint64_t v = 0; v < p.vertex_count; v++) {
            int same = !memcmp(&out[3 * v], &p.positions[3 * v], 3 * sizeof *out);
            kept &= !locked[v] || same;
            moved += !same;
            used += in_level[v];
        }
        free(in_level);
        CHECK_MSG(kept, "a locked vertex moved");
        CHECK_MSG(moved > used / 2, "only %llu of %llu vertices moved",
                  (unsigned long long)moved, (unsigned long long)used);
        CHECK_MSG(!memcmp(&out[3 * seam], &out[3 * (p.vertex_count - 1)], 3 * sizeof *out),
                  "the seam opened");
        CHECK_MSG(memcmp(&out[3 * seam], &p.positions[3 * seam], 3 * sizeof *out),
                  "the seam vertex did not move (the check would say nothing)");
        CHECK(measure(&p, out).fraction.rms < measure(&p, p.positions).fraction.rms);
    }
    free(out);
    free(locked);
    sl_fit_reference_free(ref);
    release_pair(&p);
}

/* A config under which later rounds make the level worse again (border terms 10^4 times
 * the surface's drag it off the surface): the best round is what comes back. */
static void check_never_worse(void)
{
    pair p;
    if (load_pair(&p, check_light() ? "bun_zipper_res4" : "bun_zipper_res3", 0.1))
        return;
    sl_fit_config cfg = test_config();
    cfg.border_weight = 1e4;
    sl_fit_reference *ref = reference_of(&p.input, &cfg);
    sl_fit_stats st;
    float *out = ref ? fitted(&p, ref, &cfg, &st) : NULL;
    if (out) {
        double before = measure(&p, p.positions).fraction.rms;
        double after = measure(&p, out).fraction.rms;
        printf("%s, border weight 10^4: RMS %.4e -> %.4e, best round %d\n", p.name, before,
               after, st.best_iteration);
        CHECK_MSG(after <= before, "%s: RMS rose under a bad config", p.name);
        CHECK(st.rms_after <= st.rms_before);
    }
    free(out);
    sl_fit_reference_free(ref);
    release_pair(&p);
}

/* An input without triangles: its points are pulled to the level, as compare measures. */
static void check_point_set(void)
{
    pair p;
    if (load_pair(&p, check_light() ? "cow" : "rocker_arm", check_light() ? 0.1 : 0.05))
        return;
    sl_fit_config cfg = test_config();
    sl_mesh points = sl_mesh_view(p.input.vertex_count, p.input.positions, NULL, NULL, 0, NULL);
    sl_fit_reference *ref = reference_of(&points, &cfg);
    sl_fit_stats st;
    float *out = ref ? fitted(&p, ref, &cfg, &st) : NULL;
    if (out) {
        sl_mesh_distance_config dc = sl_mesh_distance_default_config();
        sl_mesh before = sl_mesh_view(p.vertex_count, p.positions, NULL, NULL, p.triangle_count,
                                      p.triangles);
        sl_mesh after = sl_mesh_view(p.vertex_count, out, NULL, NULL, p.triangle_count,
                                     p.triangles);
        sl_mesh_distance d0, d1;
        sl_error err;
        sl_error_init(&err);
        CHECK(sl_mesh_distance_compute(&points, &before, &dc, &d0, NULL, &err) == SL_OK);
        CHECK(sl_mesh_distance_compute(&points, &after, &dc, &d1, NULL, &err) == SL_OK);
        printf("%s as points: RMS %.4e -> %.4e\n", p.name, d0.fraction.rms, d1.fraction.rms);
        CHECK(d1.a_is_points && d1.fraction.rms < 0.8 * d0.fraction.rms);
        CHECK(st.level_samples == 0 && st.rms_level_to_input == 0.0);
        CHECK_EQ_U64(flipped(&p, p.positions, out), 0);
    }
    free(out);
    sl_fit_reference_free(ref);
    release_pair(&p);
}

/* One refused fit: the code, and the level left as given. */
static void expect_refused(const char *what, const sl_fit_reference *ref, float *pos, uint64_t nv,
                           const uint32_t *tri, uint64_t nt, const sl_fit_config *cfg,
                           sl_progress *progress, int code)
{
    float *copy = malloc(3 * nv * sizeof *copy + 1);
    memcpy(copy, pos, 3 * nv * sizeof *copy);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_surface_fit(ref, pos, nv, tri, nt, cfg, NULL, progress, &err);
    CHECK_MSG(rc == code, "%s: %s, not %s", what, sl_error_name(rc), sl_error_name(code));
    CHECK_MSG(!memcmp(copy, pos, 3 * nv * sizeof *copy), "%s: the level changed", what);
    printf("refused %s: %s\n", what, err.message);
    free(copy);
}

static void check_bad_input(void)
{
    static const float square[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    static const uint32_t two[] = {0, 1, 2, 0, 2, 3}, out_of_range[] = {0, 1, 2, 0, 2, 4};
    sl_mesh in = sl_mesh_view(4, (float *)square, NULL, NULL, 2, (uint32_t *)two);
    sl_fit_config cfg = sl_fit_default_config();
    sl_fit_reference *ref = reference_of(&in, &cfg);
    float pos[12];
    memcpy(pos, square, sizeof pos);
    pos[2] = 0.1f;
    if (ref) {
        expect_refused("no triangles", ref, pos, 4, two, 0, &cfg, NULL, SL_E_BADINPUT);
        expect_refused("index out of range", ref, pos, 4, out_of_range, 2, &cfg, NULL,
                       SL_E_BADINPUT);
        pos[4] = NAN;
        expect_refused("NaN", ref, pos, 4, two, 2, &cfg, NULL, SL_E_BADINPUT);
        pos[4] = 0.0f;
        sl_fit_config bad = cfg;
        bad.iterations = -1;
        expect_refused("iterations -1", ref, pos, 4, two, 2, &bad, NULL, SL_E_USAGE);
        bad = cfg;
        bad.spring = NAN;
        expect_refused("spring NaN", ref, pos, 4, two, 2, &bad, NULL, SL_E_USAGE);
        volatile sig_atomic_t stop = 1;
        sl_progress progress = {NULL, NULL, &stop};
        expect_refused("interrupted", ref, pos, 4, two, 2, &cfg, &progress, SL_E_INTERRUPTED);
        sl_error err;
        sl_error_init(&err);
        CHECK(sl_surface_fit(ref, pos, 4, two, 2, &cfg, NULL, NULL, &err) == SL_OK);
        CHECK(fabsf(pos[2]) < 0.1f); /* the lifted corner came down towards the square */
    }
    sl_fit_reference_free(ref);

    /* references refused */
    float nan_square[12];
    memcpy(nan_square, square, sizeof nan_square);
    nan_square[7] = NAN;
    sl_mesh bad_in = sl_mesh_view(4, nan_square, NULL, NULL, 2, (uint32_t *)two);
    sl_mesh empty = sl_mesh_view(0, NULL, NULL, NULL, 0, NULL);
    sl_mesh bad_points = sl_mesh_view(4, nan_square, NULL, NULL, 0, NULL);
    sl_fit_config huge = cfg;
    huge.samples = SL_FIT_MAX_SAMPLES + 1;
    const struct { const char *what; const sl_mesh *m; const sl_fit_config *c; int code; } refs[] = {
        {"input NaN", &bad_in, &cfg, SL_E_BADINPUT}, {"input empty", &empty, &cfg, SL_E_BADINPUT},
        {"points NaN", &bad_points, &cfg, SL_E_BADINPUT}, {"samples", &in, &huge, SL_E_LIMIT}};
    for (size_t i = 0; i < sizeof refs / sizeof refs[0]; i++) {
        sl_error err;
        sl_error_init(&err);
        sl_fit_reference *r = (sl_fit_reference *)1;
        int rc = sl_fit_reference_build(refs[i].m, refs[i].c, &r, &err);
        CHECK_MSG(rc == refs[i].code && r == NULL, "%s: %s", refs[i].what, sl_error_name(rc));
        printf("refused reference %s: %s\n", refs[i].what, err.message);
    }
}

int main(void)
{
    static const gain_case cases[] = {
        {"rocker_arm", "cow", 0.05, 1.8, 1.45, 0},
        {"fandisk", "fandisk", 0.5, 1.5, 1.45, 0}, /* at 50 %: without the flip guard, 4 flip */
        {"bun_zipper_res3", "bun_zipper_res4", 0.1, 2.0, 1.45, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        check_gain(&cases[i]);
    check_locked_and_seam();
    check_never_worse();
    check_point_set();
    check_bad_input();
    check_open_edges();
    return check_report();
}
