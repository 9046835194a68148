/* The finer level cut along the coarser level's edges (morph_refine.h has the method).
 *
 * Arithmetic is in double on the float positions and targets as stored, so what is
 * tested ("lies in a coarser triangle") is what a viewer gets at weight 1. A round's
 * tests run in parallel and are used in order; its splits are serial and ordered (edges
 * by their vertex pair, triangles by index): the result does not depend on the thread
 * count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/morph_refine_core.h"

static void emit(refine *R, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t *t = R->r->triangles + 3 * R->r->triangle_count++;
    t[0] = a, t[1] = b, t[2] = c;
}

/* Quad a, b, c, d (counter-clockwise) as two triangles: along the diagonal whose ends'
 * targets share a coarser triangle, else the shorter one at weight 1. */
static void emit_quad(refine *R, uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    int ac = mr_share(R, a, c, NONE), bd = mr_share(R, b, d, NONE);
    if (ac == bd) {
        double pa[3], pb[3], pc[3], pd[3], l1 = 0, l2 = 0;
        mr_target_of(R, a, pa), mr_target_of(R, b, pb), mr_target_of(R, c, pc), mr_target_of(R, d, pd);
        for (int k = 0; k < 3; k++)
            l1 += (pa[k] - pc[k]) * (pa[k] - pc[k]), l2 += (pb[k] - pd[k]) * (pb[k] - pd[k]);
        ac = l1 <= l2;
    }
    if (ac)
        emit(R, a, b, c), emit(R, a, c, d);
    else
        emit(R, a, b, d), emit(R, b, c, d);
}

/* Triangle v[0..2] with split vertices s[k] on edge v[k] v[k+1] (NONE: not split). */
static void emit_split(refine *R, const uint32_t *v, const uint32_t *s)
{
    int n = (s[0] != NONE) + (s[1] != NONE) + (s[2] != NONE), r = 0;
    if (n == 1)
        r = s[0] != NONE ? 0 : s[1] != NONE ? 1 : 2; /* the split edge first */
    if (n == 2)
        r = s[2] == NONE ? 0 : s[0] == NONE ? 1 : 2; /* the unsplit edge last */
    uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3];
    uint32_t x = s[r], y = s[(r + 1) % 3], z = s[(r + 2) % 3];
    if (n == 0)
        emit(R, a, b, c);
    else if (n == 1)
        emit(R, a, x, c), emit(R, x, b, c);
    else if (n == 2)
        emit(R, x, b, y), emit_quad(R, a, x, y, c);
    else
        emit(R, a, x, z), emit(R, x, b, y), emit(R, z, y, c), emit(R, x, y, z);
}

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

/* One round: `split_edges` 0 adds a vertex in each triangle that spans a coarser vertex,
 * 1 splits each failing edge at its first coarser edge. The two alternate: a triangle
 * around a coarser vertex gets that vertex before its edges are split, or the splits
 * would close in on the vertex without reaching it. *changed: whether anything was.
 * *failing_edges: in: the fewest failing edges of an edge round so far (UINT64_MAX: none
 * yet); out: updated. The second edge round in a row without a new fewest splits nothing
 * (splits chasing a fold of the closest-point map). */
static int round_once(refine *R, int split_edges, uint64_t *failing_edges, int *changed,
                      sl_error *err)
{
    sl_morph_refined *r = R->r;
    uint64_t tn = r->triangle_count, nb = 0;
    uint64_t *bad = malloc((3 * tn + 1) * sizeof *bad);
    uint32_t *old = malloc((3 * tn + 1) * sizeof *old);
    if (!bad || !old) {
        free(bad), free(old);
        return mr_nomem(err);
    }
    memcpy(old, r->triangles, 3 * tn * sizeof *old);
    /* The tests read only the vertices there are (in parallel); what they find is used
     * in triangle order. Per triangle: bit k, edge k fails; bit 3, its targets share a
     * coarser triangle. */
    uint8_t *test = malloc(tn + 1);
    if (!test) {
        free(bad), free(old);
        return mr_nomem(err);
    }
#pragma omp parallel for schedule(dynamic, 256)
    for (int64_t t = 0; t < (int64_t)tn; t++) {
        const uint32_t *v = old + 3 * t;
        uint8_t bits = 0;
        for (int k = 0; split_edges && k < 3; k++)
            bits |= (uint8_t)(!mr_share(R, v[k], v[(k + 1) % 3], NONE) << k);
        /* edges that lie on the coarser surface only as flat pairs, in a triangle that
         * does not: split as before (else nothing would, and it would tear) */
        if (split_edges && bits == 0 && !mr_share(R, v[0], v[1], v[2]))
            for (int k = 0; k < 3; k++)
                bits |= (uint8_t)(!mr_share_one(R, v[k], v[(k + 1) % 3], NONE) << k);
        if (!split_edges && mr_share(R, v[0], v[1], v[2]))
            bits |= 8;
        test[t] = bits;
    }
    for (uint64_t t = 0; split_edges && t < tn; t++)
        for (int k = 0; k < 3; k++)
            if (test[t] >> k & 1)
                bad[nb++] = edge_key(old[3 * t + k], old[3 * t + (k + 1) % 3]);
    qsort(bad, nb, sizeof *bad, mr_cmp_u64);
    uint64_t nu = 0;
    for (uint64_t i = 0; i < nb; i++)
        if (nu == 0 || bad[i] != bad[nu - 1])
            bad[nu++] = bad[i];
    *changed = 0;
    if (split_edges && nu >= *failing_edges) {
        /* one edge round may add failing edges on the way (a chord over several coarser
         * triangles is split once per round, and its halves fail until the last); two in
         * a row without a new fewest is a fold of the closest-point map, where splits
         * make new failing chords as fast as they mend old ones */
        if (R->stale_rounds >= 1) {
            free(bad), free(old), free(test);
            return 0;
        }
        R->stale_rounds++;
    } else if (split_edges) {
        R->stale_rounds = 0;
        *failing_edges = nu;
    }
    uint32_t *split = malloc((nu + 1) * sizeof *split);
    /* at most one vertex per failing edge and per triangle; at most 4 triangles each */
    int rc = split ? mr_reserve(R, r->vertex_count + nu + tn, 4 * tn, err) : mr_nomem(err);
    for (uint64_t i = 0; rc == 0 && i < nu; i++)
        split[i] = mr_split_edge(R, (uint32_t)(bad[i] >> 32), (uint32_t)bad[i]);
    *changed = 0;
    for (uint64_t i = 0; rc == 0 && i < nu; i++)
        *changed |= split[i] != NONE;
    r->triangle_count = 0;
    for (uint64_t t = 0; rc == 0 && t < tn; t++) {
        uint32_t *v = old + 3 * t, s[3];
        int failing = 0;
        for (int k = 0; k < 3; k++) {
            uint64_t key = edge_key(v[k], v[(k + 1) % 3]);
            uint64_t *at = nu ? bsearch(&key, bad, nu, sizeof *bad, mr_cmp_u64) : NULL;
            s[k] = at ? split[at - bad] : NONE;
            failing |= at != NULL;
        }
        uint32_t x = split_edges || failing || test[t] & 8
                         ? NONE : mr_split_triangle(R, v[0], v[1], v[2]);
        if (x != NONE) {
            emit(R, v[0], v[1], x), emit(R, v[1], v[2], x), emit(R, v[2], v[0], x);
            *changed = 1;
        } else {
            emit_split(R, v, s);
        }
    }
    free(bad), free(old), free(split), free(test);
    return rc == 0 && R->failed ? mr_nomem(err) : rc;
}

/* Coarser vertex -> triangle lists, and the BVH. */
static int build_coarse(refine *R, sl_error *err)
{
    const sl_mesh *c = R->c;
    R->dist = malloc((c->vertex_count + 1) * sizeof *R->dist);
    R->prev = malloc((c->vertex_count + 1) * sizeof *R->prev);
    R->stamp = calloc(c->vertex_count + 1, sizeof *R->stamp);
    if (!R->dist || !R->prev || !R->stamp ||
        mr_vertex_rings(c->triangles, c->triangle_count, c->vertex_count, &R->ring_start,
                        &R->ring))
        return mr_nomem(err);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < c->vertex_count; i++)
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], c->positions[3 * i + k]), hi[k] = fmax(hi[k], c->positions[3 * i + k]);
    double diag2 = 0;
    for (int k = 0; k < 3; k++)
        diag2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    R->eps2 = SL_MORPH_REFINE_EPS * SL_MORPH_REFINE_EPS * diag2;
    return sl_triangle_bvh_build(&R->bvh, c, err);
}

/* The level's vertices, their closest points and the triangles they start in. */
static int start(refine *R, sl_error *err)
{
    const sl_mesh *l = R->level;
    sl_morph_refined *r = R->r;
    int rc = mr_reserve(R, l->vertex_count, l->triangle_count, err);
    if (rc)
        return rc;
    memcpy(r->positions, l->positions, 12 * l->vertex_count);
    memcpy(r->triangles, l->triangles, 12 * l->triangle_count);
    r->vertex_count = r->level_vertices = l->vertex_count;
    r->triangle_count = r->level_triangles = l->triangle_count;
    int64_t chunks = (int64_t)((l->vertex_count + 1023) / 1024);
    double worst2 = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(max : worst2)
    for (int64_t ch = 0; ch < chunks; ch++) {
        uint32_t hint = NONE;
        for (uint64_t i = (uint64_t)ch * 1024; i < (uint64_t)(ch + 1) * 1024 && i < l->vertex_count; i++) {
            double q[3] = {l->positions[3 * i], l->positions[3 * i + 1], l->positions[3 * i + 2]};
            sl_closest hit;
            sl_triangle_bvh_closest(&R->bvh, q, hint, &hit);
            hint = hit.triangle;
            for (int k = 0; k < 3; k++)
                r->targets[3 * i + k] = (float)hit.point[k];
            R->hint[i] = R->bvh.source[hit.triangle];
            r->source[3 * i] = r->source[3 * i + 1] = r->source[3 * i + 2] = (uint32_t)i;
            r->weight[3 * i] = 1, r->weight[3 * i + 1] = r->weight[3 * i + 2] = 0;
            worst2 = hit.distance_sq > worst2 ? hit.distance_sq : worst2;
        }
    }
    r->max_move = sqrt(worst2);
    /* Their members, in parallel into up to SMALL slots each, kept in vertex order (the
     * few with more are found again when kept). */
    enum { SMALL = 8 };
    uint32_t *small = malloc((SMALL * l->vertex_count + 1) * sizeof *small);
    uint8_t *count = malloc(l->vertex_count + 1);
    if (!small || !count) {
        free(small), free(count);
        return mr_nomem(err);
    }
#pragma omp parallel for schedule(dynamic, 1024)
    for (int64_t i = 0; i < (int64_t)l->vertex_count; i++) {
        uint32_t m[MEMBERS_MAX];
        double p[3] = {r->targets[3 * i], r->targets[3 * i + 1], r->targets[3 * i + 2]};
        int n = mr_members_of(R, p, R->hint[i], m);
        count[i] = (uint8_t)n;
        memcpy(small + SMALL * i, m, (size_t)(n < SMALL ? n : SMALL) * sizeof *m);
    }
    for (uint64_t i = 0; rc == 0 && i < l->vertex_count; i++) {
        uint32_t m[MEMBERS_MAX];
        double p[3] = {r->targets[3 * i], r->targets[3 * i + 1], r->targets[3 * i + 2]};
        int n = count[i] <= SMALL ? count[i] : mr_members_of(R, p, R->hint[i], m);
        if (mr_members_keep(R, (uint32_t)i, count[i] <= SMALL ? small + SMALL * i : m, n))
            rc = mr_nomem(err);
    }
    free(small), free(count);
    return rc;
}

/* How far triangle t[0..2] is from the coarser surface, squared: the farthest of its
 * corners, edge midpoints and centre (a chord bulges off the surface between its
 * corners). */
static double triangle_distance2(const refine *R, const double t[3][3])
{
    static const double at[7][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {.5, .5, 0},
                                    {0, .5, .5}, {.5, 0, .5}, {1 / 3., 1 / 3., 1 / 3.}};
    double worst = 0;
    for (int i = 0; i < 7; i++) {
        double q[3];
        sl_closest hit;
        for (int k = 0; k < 3; k++)
            q[k] = at[i][0] * t[0][k] + at[i][1] * t[1][k] + at[i][2] * t[2][k];
        sl_triangle_bvh_closest(&R->bvh, q, UINT32_MAX, &hit);
        worst = hit.distance_sq > worst ? hit.distance_sq : worst;
    }
    return worst;
}

/* The travel bound (squared): how far the level is from the coarser surface (sampled as
 * triangle_distance2), at least "lies in". A new, retargeted or torn vertex travels no
 * farther: each triangle then moves into one coarser triangle by at most that, so at
 * weight w the blend is within (1 - w) times the level's own distance of the coarser
 * surface: it never strays farther than weight 0 is, and comes closer as w grows. */
static double travel_bound2(const refine *R)
{
    const sl_mesh *l = R->level;
    double worst = R->eps2;
#pragma omp parallel for schedule(dynamic, 1024) reduction(max : worst)
    for (int64_t i = 0; i < (int64_t)l->triangle_count; i++) {
        double t[3][3];
        for (int k = 0; k < 3; k++)
            mr_corner(l, (uint32_t)i, k, t[k]);
        double d2 = triangle_distance2(R, t);
        worst = d2 > worst ? d2 : worst;
    }
    return worst;
}

int sl_morph_refine(const sl_mesh *coarser, const sl_mesh *level, unsigned flags,
                    sl_morph_refined *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    if (coarser->triangle_count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "morph target: the coarser level has no triangles");
    refine R;
    memset(&R, 0, sizeof R);
    R.c = coarser, R.level = level, R.r = out;
    int rc = build_coarse(&R, err);
    if (rc == 0)
        rc = start(&R, err);
    if (rc == 0)
        R.travel2 = travel_bound2(&R);
    R.tear = (flags & SL_MORPH_REFINE_TEAR) != 0;
    int idle = 0; /* rounds in a row that changed nothing */
    uint64_t failing = UINT64_MAX;
    for (int round = 0; rc == 0 && idle < 2 && round < SL_MORPH_REFINE_ROUNDS &&
                        out->triangle_count <= SL_MORPH_REFINE_GROWTH * level->triangle_count;
         round++) {
        int changed = 0;
        rc = round_once(&R, round % 2, &failing, &changed, err);
        idle = changed ? 0 : idle + 1;
    }
    if (rc == 0)
        rc = mr_retarget(&R, err);
    if (rc == 0 && R.tear)
        rc = mr_tear(&R, err);
    uint64_t unresolved = 0;
    double far2 = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : unresolved) reduction(max : far2)
    for (int64_t t = 0; t < (rc == 0 ? (int64_t)out->triangle_count : 0); t++) {
        const uint32_t *v = out->triangles + 3 * t;
        if (mr_share(&R, v[0], v[1], v[2]))
            continue;
        unresolved++;
        double at1[3][3]; /* the triangle at weight 1 */
        for (int k = 0; k < 3; k++)
            mr_target_of(&R, v[k], at1[k]);
        double d2 = triangle_distance2(&R, at1);
        far2 = d2 > far2 ? d2 : far2;
    }
    out->unresolved = unresolved;
    out->unresolved_max = sqrt(far2);
    sl_triangle_bvh_release(&R.bvh);
    free(R.ring_start), free(R.ring), free(R.hint);
    free(R.dist), free(R.prev), free(R.stamp), free(R.heap_v), free(R.heap_k);
    free(R.members_at), free(R.members_pool);
    if (rc)
        sl_morph_refined_release(out);
    return rc;
}

void sl_morph_refined_release(sl_morph_refined *r)
{
    free(r->positions), free(r->targets), free(r->triangles), free(r->source), free(r->weight);
    memset(r, 0, sizeof *r);
}

void sl_morph_refined_interpolate(const sl_morph_refined *r, const float *level_attr, int comps,
                                  float *out)
{
    for (uint64_t i = 0; i < r->vertex_count; i++)
        for (int k = 0; k < comps; k++) {
            double s = 0;
            for (int j = 0; j < 3; j++)
                s += (double)r->weight[3 * i + j] * level_attr[(uint64_t)comps * r->source[3 * i + j] + k];
            out[(uint64_t)comps * i + k] = (float)s;
        }
}

void sl_morph_refined_normals(const sl_morph_refined *r, const float *level_normals, float *out)
{
    sl_morph_refined_interpolate(r, level_normals, 3, out);
    for (uint64_t i = r->level_vertices; i < r->vertex_count; i++) {
        float *q = out + 3 * i;
        double l = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2]);
        for (int k = 0; l > 0 && k < 3; k++)
            q[k] = (float)(q[k] / l);
    }
}

void sl_morph_refined_interpolate_rgba(const sl_morph_refined *r, const uint8_t *level_rgba,
                                       uint8_t *out)
{
    for (uint64_t i = 0; i < r->vertex_count; i++)
        for (int k = 0; k < 4; k++) {
            double s = 0;
            for (int j = 0; j < 3; j++)
                s += (double)r->weight[3 * i + j] * level_rgba[4 * (uint64_t)r->source[3 * i + j] + k];
            out[4 * i + k] = (uint8_t)(s < 0 ? 0 : s > 255 ? 255 : lrint(s));
        }
}
