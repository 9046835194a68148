/* The last resorts of the morph refinement (morph_refine.h, steps 3 and 4): where no
 * split mends a triangle, its corners' targets are moved within the coarser surface
 * (retargeting) when that leaves fewer failing triangles, and what still fails is torn.
 * Retargeting runs serially in triangle order, the tears' tests in parallel and their
 * copies in order: deterministic on any thread count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/morph_refine_core.h"

/* The coarser triangle holding the most of v's three targets (the first such), and a
 * bit per corner whose target it holds. */
uint32_t mr_best_face(const refine *R, const uint32_t *v, int *held)
{
    uint32_t best = R->hint[v[0]];
    int most = -1;
    *held = 0;
    for (int c = 0; c < 3; c++) {
        uint32_t m[MEMBERS_MAX];
        int n = mr_members(R, v[c], m);
        for (int i = 0; i < n; i++) {
            int bits = 0, count = 0;
            for (int k = 0; k < 3; k++) {
                double p[3];
                mr_target_of(R, v[k], p);
                if (mr_lies_in(R, p, m[i]))
                    bits |= 1 << k, count++;
            }
            if (count > most)
                most = count, best = m[i], *held = bits;
        }
    }
    return best;
}

/* How many of a vertex's triangles (`ring`, `count` of them) fail to share a coarser
 * triangle. */
static int failing_around(const refine *R, const uint32_t *ring, uint32_t count)
{
    int fails = 0;
    for (uint32_t i = 0; i < count; i++) {
        const uint32_t *v = R->r->triangles + 3 * (uint64_t)ring[i];
        fails += !mr_share(R, v[0], v[1], v[2]);
    }
    return fails;
}

/* Sets v's target to t in coarser triangle g (and its members); -1 out of memory. */
static int set_target(refine *R, uint32_t v, const float t[3], uint32_t g)
{
    uint32_t m[MEMBERS_MAX];
    double q[3] = {t[0], t[1], t[2]};
    memcpy(R->r->targets + 3 * (uint64_t)v, t, 3 * sizeof *t);
    R->hint[v] = g;
    return mr_members_keep(R, v, m, mr_members_of(R, q, g, m));
}

int mr_retarget(refine *R, sl_error *err)
{
    sl_morph_refined *r = R->r;
    uint64_t vn = r->vertex_count, tn = r->triangle_count;
    /* Per triangle: whether it may fail (tested in parallel at each pass's start, and set
     * again around every vertex that moves, the only way a triangle's test can change), so
     * the serial pass tests only those, in triangle order, as a test of every one would. */
    uint8_t *maybe = malloc(tn + 1);
    uint32_t *start = NULL, *ring = NULL;
    if (!maybe)
        return mr_nomem(err);
    int rc = 0, any_moved = 0;
    for (int pass = 0, moved = 1; rc == 0 && moved && pass < MR_RETARGET_PASSES; pass++) {
        moved = 0;
        uint64_t failing = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : failing)
        for (int64_t t = 0; t < (int64_t)tn; t++) {
            const uint32_t *v = r->triangles + 3 * t;
            maybe[t] = (uint8_t)!mr_share(R, v[0], v[1], v[2]);
            failing += maybe[t];
        }
        if (!failing)
            break;
        if (!ring && mr_vertex_rings(r->triangles, tn, vn, &start, &ring)) {
            rc = mr_nomem(err);
            break;
        }
        for (uint64_t t = 0; rc == 0 && t < tn; t++) {
            const uint32_t *v = r->triangles + 3 * t;
            if (!maybe[t] || mr_share(R, v[0], v[1], v[2]))
                continue;
            int held;
            uint32_t g = mr_best_face(R, v, &held);
            for (int k = 0; rc == 0 && k < 3; k++) {
                uint32_t x = v[k], n = start[x + 1] - start[x];
                if (held >> k & 1 || n > 64)
                    continue;
                double p[3], a[3], b[3], c[3], q[3];
                mr_position_of(R, x, p); /* the point of g it travels least to */
                mr_corner(R->c, g, 0, a), mr_corner(R->c, g, 1, b), mr_corner(R->c, g, 2, c);
                if (sl_closest_point_triangle(p, a, b, c, q) > R->travel2)
                    continue; /* farther than the travel bound (morph_refine.c) */
                int before = failing_around(R, ring + start[x], n);
                float was[3], now[3];
                memcpy(was, r->targets + 3 * (uint64_t)x, sizeof was);
                uint32_t was_hint = R->hint[x];
                uint64_t was_members = R->members_at[x];
                now[0] = (float)q[0], now[1] = (float)q[1], now[2] = (float)q[2];
                if (set_target(R, x, now, g)) {
                    rc = mr_nomem(err);
                    break;
                }
                if (failing_around(R, ring + start[x], n) < before) {
                    moved = any_moved = 1;
                    for (uint32_t i = start[x]; i < start[x + 1]; i++)
                        maybe[ring[i]] = 1;
                } else { /* back as it was (the members' new entry stays unused) */
                    memcpy(r->targets + 3 * (uint64_t)x, was, sizeof was);
                    R->hint[x] = was_hint, R->members_at[x] = was_members;
                }
            }
        }
    }
    /* the level's vertices may have moved farther than their closest points */
    double worst2 = r->max_move * r->max_move;
    for (uint64_t i = 0; any_moved && i < r->level_vertices; i++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            double d = (double)r->targets[3 * i + k] - r->positions[3 * i + k];
            d2 += d * d;
        }
        worst2 = d2 > worst2 ? d2 : worst2;
    }
    r->max_move = sqrt(worst2);
    free(start), free(ring), free(maybe);
    return rc;
}

/* The coarser triangle a failing triangle v tears to: of the coarser triangles its targets
 * lie in, the one its torn corners travel least to (the largest distance from a corner
 * whose target is not in it to its closest point there; ties: more corners held, then
 * the first); *held a bit per corner whose target it holds. */
static uint32_t tear_face(const refine *R, const uint32_t *v, int *held)
{
    uint32_t best = R->hint[v[0]];
    double best_cost = INFINITY;
    int best_count = -1;
    *held = 0;
    for (int c = 0; c < 3; c++) {
        uint32_t m[MEMBERS_MAX];
        int n = mr_members(R, v[c], m);
        for (int i = 0; i < n; i++) {
            int bits = 0, count = 0;
            double cost = 0, a[3], b[3], cc[3];
            mr_corner(R->c, m[i], 0, a), mr_corner(R->c, m[i], 1, b), mr_corner(R->c, m[i], 2, cc);
            for (int k = 0; k < 3; k++) {
                double p[3], q[3];
                mr_target_of(R, v[k], p);
                if (mr_lies_in(R, p, m[i])) {
                    bits |= 1 << k, count++;
                    continue;
                }
                mr_position_of(R, v[k], p);
                double d2 = sl_closest_point_triangle(p, a, b, cc, q);
                cost = d2 > cost ? d2 : cost;
            }
            if (cost < best_cost || (cost == best_cost && count > best_count))
                best_cost = cost, best_count = count, best = m[i], *held = bits;
        }
    }
    return best;
}

/* Tears what no split mends (targets on pieces of the coarser surface that do not meet:
 * a fold, a thin part, another component): in each such triangle, the corners whose
 * targets are not in the coarser triangle it tears to (tear_face) get a copy (same bytes at
 * weight 0) whose target is the point of that coarser triangle nearest to it; triangles that
 * tear the same vertex towards the same coarser triangle share the copy. */
int mr_tear(refine *R, sl_error *err)
{
    sl_morph_refined *r = R->r;
    uint64_t nk = 0, tn = r->triangle_count;
    uint64_t *keys = malloc((3 * tn + 1) * sizeof *keys);
    uint32_t *face = malloc((tn + 1) * sizeof *face); /* per triangle: best_face, */
    uint8_t *holds = malloc(tn + 1);                   /* and the corners it holds */
    if (!keys || !face || !holds) {
        free(keys), free(face), free(holds);
        return mr_nomem(err);
    }
#pragma omp parallel for schedule(dynamic, 256)
    for (int64_t t = 0; t < (int64_t)tn; t++) {
        const uint32_t *v = r->triangles + 3 * t;
        int held = 7;
        face[t] = mr_share(R, v[0], v[1], v[2]) ? NONE : tear_face(R, v, &held);
        holds[t] = (uint8_t)held;
    }
    for (uint64_t t = 0; t < tn; t++)
        for (int k = 0; k < 3; k++)
            if (!(holds[t] >> k & 1))
                keys[nk++] = (uint64_t)r->triangles[3 * t + k] << 32 | face[t];
    qsort(keys, nk, sizeof *keys, mr_cmp_u64);
    uint64_t nu = 0;
    for (uint64_t i = 0; i < nk; i++)
        if (nu == 0 || keys[i] != keys[nu - 1])
            keys[nu++] = keys[i];
    uint32_t *copy = malloc((nu + 1) * sizeof *copy);
    int rc = copy ? mr_reserve(R, r->vertex_count + nu, tn, err) : mr_nomem(err);
    for (uint64_t i = 0; rc == 0 && i < nu; i++) {
        uint32_t v = (uint32_t)(keys[i] >> 32), g = (uint32_t)keys[i];
        double p[3], a[3], b[3], c[3], t[3], was[3], f = 1, d2 = 0;
        mr_position_of(R, v, p); /* the point of g the copy travels least to */
        mr_target_of(R, v, was);
        mr_corner(R->c, g, 0, a), mr_corner(R->c, g, 1, b), mr_corner(R->c, g, 2, c);
        sl_closest_point_triangle(p, a, b, c, t);
        for (int k = 0; k < 3; k++)
            d2 += (t[k] - was[k]) * (t[k] - was[k]);
        copy[i] = mr_add_vertex(R, 1, &v, &f, t, g);
        r->tear_max = fmax(r->tear_max, sqrt(d2)); /* the crack between the two at weight 1 */
    }
    for (uint64_t t = 0; rc == 0 && t < tn; t++) {
        uint32_t *v = r->triangles + 3 * t, g = face[t];
        int held = holds[t];
        uint32_t was[3] = {v[0], v[1], v[2]};
        for (int k = 0; k < 3; k++)
            if (!(held >> k & 1)) {
                uint64_t key = (uint64_t)was[k] << 32 | g;
                v[k] = copy[(uint64_t *)bsearch(&key, keys, nu, sizeof *keys, mr_cmp_u64) - keys];
            }
        r->torn_triangles += held != 7;
    }
    r->torn_vertices = rc == 0 ? nu : 0;
    free(keys), free(copy), free(face), free(holds);
    return rc == 0 && R->failed ? mr_nomem(err) : rc;
}
