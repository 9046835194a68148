/* Triangle BVH closest-point queries against brute force on bundled scans (fandisk, cow,
 * the bunny): points on, near and far from the surface, with no hint, a random hint and
 * the last answer as the hint. Every answer's distance must be the brute force's minimum
 * to the bit (the tree may only skip what cannot be closer), and its triangle must be one
 * at that distance; the answers must not depend on the hint. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "formats/ply.h"
#include "geometry/triangle_bvh.h"
#include "tests/check.h"
#include "tests/unit/glb_meshes.h"

static uint64_t rng_state = 0x2545f4914f6cdd1dull;
static double uniform(void)
{
    rng_state ^= rng_state << 13, rng_state ^= rng_state >> 7, rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* The least squared distance from p to any triangle of the tree, every triangle tried. */
static double brute_closest(const sl_triangle_bvh *bvh, const double p[3])
{
    double best = INFINITY;
    for (uint64_t t = 0; t < bvh->triangle_count; t++) {
        const float *f = &bvh->corners[9 * t];
        double a[3] = {f[0], f[1], f[2]}, b[3] = {f[3], f[4], f[5]}, c[3] = {f[6], f[7], f[8]};
        double q[3];
        int feature;
        double d = sl_closest_point_triangle_feature(p, a, b, c, q, &feature);
        if (d < best)
            best = d;
    }
    return best;
}

/* A query point: a random triangle's random point moved by up to `reach` times the
 * diagonal along each axis. */
static void query_point(const sl_mesh *m, double diagonal, double reach, double p[3])
{
    uint64_t t = (uint64_t)(uniform() * (double)m->triangle_count) % m->triangle_count;
    double u = uniform(), v = uniform();
    if (u + v > 1)
        u = 1 - u, v = 1 - v;
    for (int a = 0; a < 3; a++) {
        const float *x = m->positions;
        const uint32_t *tri = &m->triangles[3 * t];
        double pa = x[3 * tri[0] + a], pb = x[3 * tri[1] + a], pc = x[3 * tri[2] + a];
        p[a] = pa + u * (pb - pa) + v * (pc - pa) + (2 * uniform() - 1) * reach * diagonal;
    }
}

static void check_scan(const char *name)
{
    sl_mesh m;
    sl_mesh_init(&m);
    CHECK_MSG(meshes_read_scan(name, &m) == 0, "%s: read", name);
    if (m.triangle_count == 0)
        return;
    sl_triangle_bvh bvh;
    sl_error err;
    sl_error_init(&err);
    CHECK_MSG(sl_triangle_bvh_build(&bvh, &m, &err) == 0, "%s: build", name);
    const sl_bvh_node *root = &bvh.nodes[0];
    double diagonal = 0;
    for (int a = 0; a < 3; a++)
        diagonal += (double)(root->hi[a] - root->lo[a]) * (root->hi[a] - root->lo[a]);
    diagonal = sqrt(diagonal);

    const double reaches[4] = {0, 1e-3, 3e-2, 2}; /* on, near, farther, far off */
    int wrong = 0, wrong_triangle = 0, hint_changed = 0, queries = 0;
    uint32_t last = UINT32_MAX;
    for (int r = 0; r < 4; r++)
        for (int i = 0; i < 500; i++, queries++) {
            double p[3];
            query_point(&m, diagonal, reaches[r], p);
            double want = brute_closest(&bvh, p);
            uint32_t random_hint = (uint32_t)(uniform() * (double)bvh.triangle_count);
            const uint32_t hints[3] = {UINT32_MAX, random_hint, last};
            for (int h = 0; h < 3; h++) {
                sl_closest got;
                sl_triangle_bvh_closest(&bvh, p, hints[h], &got);
                wrong += got.distance_sq != want;
                const float *f = &bvh.corners[9 * (uint64_t)got.triangle];
                double a[3] = {f[0], f[1], f[2]}, b[3] = {f[3], f[4], f[5]},
                       c[3] = {f[6], f[7], f[8]}, q[3];
                int feature;
                wrong_triangle +=
                    sl_closest_point_triangle_feature(p, a, b, c, q, &feature) != want ||
                    feature != got.feature;
                if (h == 2)
                    last = got.triangle;
                if (h > 0) {
                    sl_closest plain;
                    sl_triangle_bvh_closest(&bvh, p, UINT32_MAX, &plain);
                    hint_changed += plain.distance_sq != got.distance_sq ||
                                    memcmp(plain.point, got.point, sizeof plain.point) != 0;
                }
            }
        }
    CHECK_MSG(wrong == 0, "%s: %d of %d answers not the least distance", name, wrong,
              3 * queries);
    CHECK_MSG(wrong_triangle == 0, "%s: %d answers name a triangle not at their distance", name,
              wrong_triangle);
    CHECK_MSG(hint_changed == 0, "%s: %d answers moved by the hint", name, hint_changed);
    sl_triangle_bvh_release(&bvh);
    sl_mesh_release(&m);
}

int main(void)
{
    check_scan("fandisk");
    check_scan("cow");
    check_scan("bun_zipper_res3");
    return check_report();
}
