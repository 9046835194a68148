/* samples stage: sign repair by the distance balls ([samples] closest = triangles).
 *
 * The pseudonormal sign (samples_surface.c) is exact for a closed, consistently wound mesh
 * without self-intersections. Real scans are not always that: a fold whose two faces are
 * almost back to back (the cow's ear tips) or a self-intersection makes the pseudonormal
 * of an edge or vertex a tiny vector of arbitrary direction, and a vertex a leaf and a half
 * outside the model then comes out "inside". At the band's outer edge that opens the
 * surface.
 *
 * The samples carry the exact unsigned distance d(v) to the surface, and that is enough to
 * find such errors: no surface passes within d(v) of v, so any grid vertex u closer to v
 * than d(v) is on the same side. Linking every pair of axis neighbours (one leaf apart)
 * of which one is more than a leaf from the surface partitions the band into regions
 * that must each have one sign; each region takes the sign of the majority of its
 * samples (ties keep theirs). A wrong sign is a local accident of the geometry, so it is
 * outvoted by the rest of its region. Samples closer than a leaf to the surface on both
 * ends of every link stay as computed: there the surface itself decides.
 *
 * Linear time: the samples are sorted by key (x, y, z), so the +z neighbour of sample i
 * is i + 1 when present, and the +y and +x neighbours are found by two pointers that only
 * move forward. Union-find with path halving and union by index (deterministic).
 */
#include <math.h>
#include <stdlib.h>

#include "stages/samples/samples_internal.h"

static uint64_t find_root(uint64_t *parent, uint64_t i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static void unite(uint64_t *parent, uint64_t a, uint64_t b)
{
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a < b)
        parent[b] = a;
    else if (b < a)
        parent[a] = b;
}

int samples_repair_signs(const uint64_t *keys, sl_vdb_samples *s, double leaf,
                         uint64_t *repaired, sl_error *err)
{
    uint64_t n = s->count;
    *repaired = 0;
    uint64_t *parent = malloc(n * sizeof *parent + 1);
    int64_t *balance = calloc(n + 1, sizeof *balance);
    if (!parent || !balance) {
        free(parent), free(balance);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "out of memory repairing %llu signs",
                            (unsigned long long)n);
    }
    for (uint64_t i = 0; i < n; i++)
        parent[i] = i;
    const float reach = (float)(leaf * (1.0 + 1e-6)); /* strictly beyond the neighbour */
    const uint64_t step[3] = {1, (uint64_t)1 << SL_COORD_BITS, (uint64_t)1 << (2 * SL_COORD_BITS)};
    uint64_t at[3] = {0, 0, 0};
    for (uint64_t i = 0; i < n; i++) {
        for (int axis = 0; axis < 3; axis++) {
            uint64_t want = keys[i] + step[axis], j = axis == 0 ? i + 1 : at[axis];
            if (axis > 0) {
                while (j < n && keys[j] < want)
                    j++;
                at[axis] = j;
            }
            if (j >= n || keys[j] != want)
                continue;
            if (fabsf(s->distance[i]) > reach || fabsf(s->distance[j]) > reach)
                unite(parent, i, j);
        }
    }
    for (uint64_t i = 0; i < n; i++)
        balance[find_root(parent, i)] += s->distance[i] < 0 ? -1 : 1;
    for (uint64_t i = 0; i < n; i++) {
        int64_t b = balance[find_root(parent, i)];
        int negative = s->distance[i] < 0;
        if ((b < 0 && !negative) || (b > 0 && negative)) {
            s->distance[i] = s->distance[i] == 0 ? -0x1p-126f : -s->distance[i];
            (*repaired)++;
        }
    }
    free(parent);
    free(balance);
    return SL_OK;
}
