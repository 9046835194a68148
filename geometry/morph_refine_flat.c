/* Whether targets share a coarser triangle, for the morph refinement (morph_refine.h):
 * one coarser triangle, or a flat pair. Flat pairs: targets in two coarser triangles
 * that share an edge and lie in one plane already span the coarser surface, when every
 * chord between them crosses that shared edge. The refinement would otherwise cut the
 * finer level along an edge where the coarser surface does not bend: on a CAD part, or on
 * the planar patches of the segment and cluster methods, most of the triangles it added.
 *
 * Why it holds: the two triangles are a quadrilateral q in one plane (to eps), a
 * topological disk. A chord between points of one triangle stays in it (convex); one from
 * a point of the first to a point of the second that crosses the shared edge within its
 * ends runs in the first up to the edge and in the second after it. So each tested chord
 * lies in q, and a triangle whose three edges lie in the disk q lies in q. */
#include <math.h>

#include "geometry/morph_refine_core.h"
#include "geometry/vec3.h"

/* The triangle across coarser triangle g's edge k (corners k, k + 1), or NONE. */
static uint32_t across(const refine *R, uint32_t g, int k)
{
    const uint32_t *t = R->c->triangles + 3 * (uint64_t)g;
    uint32_t a = t[k], b = t[(k + 1) % 3];
    for (uint32_t i = R->ring_start[a]; i < R->ring_start[a + 1]; i++) {
        uint32_t h = R->ring[i];
        if (h == g)
            continue;
        const uint32_t *s = R->c->triangles + 3 * (uint64_t)h;
        if (s[0] == b || s[1] == b || s[2] == b)
            return h;
    }
    return NONE;
}

/* Coarser triangle t's (unnormalised) normal. */
static void normal_of(const refine *R, uint32_t t, double n[3])
{
    double a[3], b[3], c[3], ab[3], ac[3];
    mr_corner(R->c, t, 0, a), mr_corner(R->c, t, 1, b), mr_corner(R->c, t, 2, c);
    for (int k = 0; k < 3; k++)
        ab[k] = b[k] - a[k], ac[k] = c[k] - a[k];
    sl_cross3(ab, ac, n);
}

/* Whether h's corner off the edge it shares with g lies within eps of g's plane (normal
 * n, length nl), the two normals alike. */
static int coplanar(const refine *R, uint32_t g, uint32_t h, const double n[3], double nl)
{
    double hn[3], a[3], d[3], ad[3];
    normal_of(R, h, hn);
    if (sl_dot3(hn, n) <= 0)
        return 0;
    const uint32_t *tg = R->c->triangles + 3 * (uint64_t)g, *th = R->c->triangles + 3 * (uint64_t)h;
    int off = 0;
    for (int k = 0; k < 3; k++)
        if (th[k] != tg[0] && th[k] != tg[1] && th[k] != tg[2])
            off = k;
    mr_corner(R->c, g, 0, a), mr_corner(R->c, h, off, d);
    for (int k = 0; k < 3; k++)
        ad[k] = d[k] - a[k];
    double dist = sl_dot3(ad, n) / nl;
    return dist * dist <= R->eps2;
}

/* Whether the chord p -> q (p in g only, q in h only) crosses g's edge k within its ends;
 * n is g's normal. */
static int crosses_edge(const refine *R, uint32_t g, int k, const double n[3], const double p[3],
                        const double q[3])
{
    double a[3], b[3], ab[3], side[3], pa[3], qa[3];
    mr_corner(R->c, g, k, a), mr_corner(R->c, g, (k + 1) % 3, b);
    for (int j = 0; j < 3; j++)
        ab[j] = b[j] - a[j], pa[j] = p[j] - a[j], qa[j] = q[j] - a[j];
    sl_cross3(n, ab, side); /* in g's plane, across the edge */
    double dp = sl_dot3(pa, side), dq = sl_dot3(qa, side);
    if (dp == dq || (dp > 0 && dq > 0) || (dp < 0 && dq < 0))
        return 0;
    double s = dp / (dp - dq), x[3];
    for (int j = 0; j < 3; j++)
        x[j] = pa[j] + s * (qa[j] - pa[j]);
    double l2 = sl_dot3(ab, ab), t = sl_dot3(x, ab) / l2, slack = sqrt(R->eps2 / l2);
    return t >= -slack && t <= 1 + slack;
}

/* Whether points p[0..count) lie in g and the triangle across g's edge k, coplanar with
 * g, with every chord between the two crossing that edge. */
static int flat_pair(const refine *R, const double (*p)[3], int count, uint32_t g, int k,
                     const double n[3], double nl)
{
    uint32_t h = across(R, g, k);
    if (h == NONE || !coplanar(R, g, h, n, nl))
        return 0;
    int in_g[3], in_h[3];
    for (int i = 0; i < count; i++) {
        in_g[i] = mr_lies_in(R, p[i], g), in_h[i] = mr_lies_in(R, p[i], h);
        if (!in_g[i] && !in_h[i])
            return 0;
    }
    for (int i = 0; i < count; i++)
        for (int j = i + 1; j < count; j++) {
            if ((in_g[i] && in_g[j]) || (in_h[i] && in_h[j]))
                continue; /* in one triangle: convex */
            const double *pg = in_g[i] ? p[i] : p[j], *ph = in_g[i] ? p[j] : p[i];
            if (!crosses_edge(R, g, k, n, pg, ph))
                return 0;
        }
    return 1;
}

int mr_flat_share(const refine *R, const double (*p)[3], int count, const uint32_t *members,
                  int member_count)
{
    for (int i = 0; i < member_count; i++) {
        uint32_t g = members[i];
        double n[3];
        normal_of(R, g, n);
        double nl = sqrt(sl_dot3(n, n));
        if (!(nl > 0))
            continue;
        for (int k = 0; k < 3; k++)
            if (flat_pair(R, p, count, g, k, n, nl))
                return 1;
    }
    return 0;
}

/* Whether the targets of u and w lie in one coarser triangle (and of x too, x != NONE),
 * or in a flat pair of them (mr_flat_share). */
static int share(const refine *R, uint32_t u, uint32_t w, uint32_t x, int flat)
{
    uint32_t m[MEMBERS_MAX];
    int n = mr_members(R, u, m);
    double pw[3], px[3];
    mr_target_of(R, w, pw);
    if (x != NONE)
        mr_target_of(R, x, px);
    for (int i = 0; i < n; i++)
        if (mr_lies_in(R, pw, m[i]) && (x == NONE || mr_lies_in(R, px, m[i])))
            return 1;
    if (!flat)
        return 0;
    double p[3][3];
    mr_target_of(R, u, p[0]);
    for (int k = 0; k < 3; k++)
        p[1][k] = pw[k], p[2][k] = x == NONE ? 0.0 : px[k];
    return mr_flat_share(R, (const double (*)[3])p, x == NONE ? 2 : 3, m, n);
}

int mr_share(const refine *R, uint32_t u, uint32_t w, uint32_t x)
{
    return share(R, u, w, x, 1);
}

int mr_share_one(const refine *R, uint32_t u, uint32_t w, uint32_t x)
{
    return share(R, u, w, x, 0);
}
