/* Triangle BVH and exact point-triangle distance (see triangle_bvh.h).
 *
 * Build: items {centroid, triangle} are partitioned in place by quickselect around the
 * median of the widest centroid axis (geometry/axis_select.h), top-down; a range of at
 * most SL_BVH_LEAF_SIZE items becomes a leaf. Then the corners are copied out in leaf order and the bounds
 * computed bottom-up in one reverse sweep over the nodes.
 * Subtrees above PARALLEL_CUTOFF triangles run as OpenMP tasks; offsets come from
 * subtree_nodes(), so the layout does not depend on the schedule.
 */
#include "geometry/triangle_bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/axis_select.h"
#include "geometry/vec3.h"

#define PARALLEL_CUTOFF 65536

/* The records: {centroid, triangle index}. */
typedef sl_axis_record bvh_item;

/* Plain comparisons: fminf/fmaxf are out-of-line calls (NaN rules), and the inputs are
 * finite. */
static inline float min_f(float a, float b) { return a < b ? a : b; }
static inline float max_f(float a, float b) { return a > b ? a : b; }

typedef struct bvh_build {
    sl_triangle_bvh *bvh;
    const sl_mesh *mesh;
    bvh_item *items;
} bvh_build;

/* Leaves of a median-split subtree over n and over n + 1 triangles (n >= 1). The halves
 * of n and of n + 1 are always among {k, k + 1} with k = n / 2, so computing the pair
 * together takes O(log n) steps instead of one per node. */
static void leaf_counts(uint64_t n, uint64_t *leaves_n, uint64_t *leaves_n1)
{
    if (n + 1 <= SL_BVH_LEAF_SIZE) {
        *leaves_n = *leaves_n1 = 1;
        return;
    }
    if (n <= SL_BVH_LEAF_SIZE) { /* n + 1 splits into two halves that are leaves */
        *leaves_n = 1;
        *leaves_n1 = 2;
        return;
    }
    uint64_t k = n / 2, a, b;
    leaf_counts(k, &a, &b);
    if (n % 2 == 0) {
        *leaves_n = 2 * a;   /* k + k */
        *leaves_n1 = a + b;  /* k + (k + 1) */
    } else {
        *leaves_n = a + b;   /* k + (k + 1) */
        *leaves_n1 = 2 * b;  /* (k + 1) + (k + 1) */
    }
}

/* Every inner node has two children, so nodes = 2 * leaves - 1. */
static uint64_t subtree_nodes(uint64_t n)
{
    uint64_t leaves, unused;
    leaf_counts(n, &leaves, &unused);
    return 2 * leaves - 1;
}

/* Leaves only record their range here; corners and bounds are filled afterwards by
 * fill_corners() and fill_bounds(), which stream through memory instead of chasing
 * mesh indices inside the recursion. */
static void make_leaf(bvh_build *b, uint64_t node_index, uint64_t begin, uint64_t count)
{
    sl_bvh_node *node = &b->bvh->nodes[node_index];
    for (uint64_t i = begin; i < begin + count; i++)
        b->bvh->source[i] = b->items[i].index;
    node->first = (uint32_t)begin;
    node->count = (uint32_t)count;
}

static void fill_corners(sl_triangle_bvh *bvh, const sl_mesh *mesh)
{
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < bvh->triangle_count; i++) {
        const uint32_t *tri = &mesh->triangles[3 * (uint64_t)bvh->source[i]];
        for (int c = 0; c < 3; c++)
            memcpy(&bvh->corners[9 * i + 3 * c], &mesh->positions[3 * (uint64_t)tri[c]],
                   3 * sizeof(float));
    }
}

/* Children follow their parent in the array, so a reverse sweep sees both children of
 * a node before the node itself. */
static void fill_bounds(sl_triangle_bvh *bvh)
{
    for (uint64_t n = bvh->node_count; n-- > 0;) {
        sl_bvh_node *node = &bvh->nodes[n];
        if (node->count) {
            const float *f = &bvh->corners[9 * (uint64_t)node->first];
            for (int a = 0; a < 3; a++)
                node->lo[a] = node->hi[a] = f[a];
            for (uint32_t k = 1; k < 3 * node->count; k++)
                for (int a = 0; a < 3; a++) {
                    node->lo[a] = min_f(node->lo[a], f[3 * k + a]);
                    node->hi[a] = max_f(node->hi[a], f[3 * k + a]);
                }
            continue;
        }
        const sl_bvh_node *l = &bvh->nodes[n + 1], *r = &bvh->nodes[node->first];
        for (int a = 0; a < 3; a++) {
            node->lo[a] = min_f(l->lo[a], r->lo[a]);
            node->hi[a] = max_f(l->hi[a], r->hi[a]);
        }
    }
}

static void build_node(bvh_build *b, uint64_t node_index, uint64_t begin, uint64_t count)
{
    if (count <= SL_BVH_LEAF_SIZE) {
        make_leaf(b, node_index, begin, count);
        return;
    }
    uint64_t left_count = count / 2;
    int axis = sl_axis_widest(b->items + begin, count);
    sl_axis_select(b->items + begin, count, left_count, axis);

    uint64_t left = node_index + 1, right = left + subtree_nodes(left_count);
    if (count > PARALLEL_CUTOFF) {
#pragma omp task default(none) firstprivate(b, left, begin, left_count)
        build_node(b, left, begin, left_count);
        build_node(b, right, begin + left_count, count - left_count);
#pragma omp taskwait
    } else {
        build_node(b, left, begin, left_count);
        build_node(b, right, begin + left_count, count - left_count);
    }
    b->bvh->nodes[node_index].first = (uint32_t)right;
    b->bvh->nodes[node_index].count = 0;
}

int sl_triangle_bvh_build(sl_triangle_bvh *bvh, const sl_mesh *mesh, sl_error *err)
{
    memset(bvh, 0, sizeof *bvh);
    uint64_t n = mesh->triangle_count;
    if (n == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "no triangles to build a BVH over");
    if (n > UINT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "%llu triangles: the BVH holds at most 2^32 - 1",
                            (unsigned long long)n);
    bvh->triangle_count = n;
    bvh->node_count = subtree_nodes(n);
    bvh->nodes = malloc(bvh->node_count * sizeof *bvh->nodes);
    bvh->corners = malloc(n * 9 * sizeof *bvh->corners);
    bvh->source = malloc(n * sizeof *bvh->source);
    bvh_item *items = malloc(n * sizeof *items);
    if (!bvh->nodes || !bvh->corners || !bvh->source || !items) {
        free(items);
        sl_triangle_bvh_release(bvh);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "BVH over %llu triangles",
                            (unsigned long long)n);
    }

#pragma omp parallel for schedule(static)
    for (uint64_t t = 0; t < n; t++) {
        const uint32_t *tri = &mesh->triangles[3 * t];
        for (int a = 0; a < 3; a++)
            items[t].p[a] = (mesh->positions[3 * (uint64_t)tri[0] + a] +
                                    mesh->positions[3 * (uint64_t)tri[1] + a] +
                                    mesh->positions[3 * (uint64_t)tri[2] + a]) / 3.0f;
        items[t].index = (uint32_t)t;
    }

    bvh_build b = {bvh, mesh, items};
#pragma omp parallel default(none) shared(b, n)
#pragma omp single
    build_node(&b, 0, 0, n);
    free(items);
    fill_corners(bvh, mesh);
    fill_bounds(bvh);
    return SL_OK;
}

void sl_triangle_bvh_release(sl_triangle_bvh *bvh)
{
    free(bvh->nodes);
    free(bvh->corners);
    free(bvh->source);
    memset(bvh, 0, sizeof *bvh);
}

/* Closest point on segment ab to p; returns the squared distance. *end = 0 inside the
 * segment, 1 at a, 2 at b. */
static double closest_point_segment(const double p[3], const double a[3], const double b[3],
                                    double out[3], int *end)
{
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double len_sq = sl_dot3(ab, ab), t = 0.0;
    if (len_sq > 0.0) {
        t = sl_dot3(ap, ab) / len_sq;
        t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    }
    *end = t <= 0.0 ? 1 : t >= 1.0 ? 2 : 0;
    double d_sq = 0.0;
    for (int i = 0; i < 3; i++) {
        out[i] = a[i] + t * ab[i];
        d_sq += (p[i] - out[i]) * (p[i] - out[i]);
    }
    return d_sq;
}

/* A sliver (sine of its largest angle below 1e-6, or an edge of length 0) has no
 * well-conditioned plane; its closest point is taken on its edges instead, which is off
 * by at most the sliver's height (1e-6 of its edge length). */
static double closest_point_sliver(const double p[3], const double a[3], const double b[3],
                                   const double c[3], double out[3], int *feature)
{
    /* edge k runs from corner k to corner k + 1 (mod 3) */
    static const int edge_feature[3] = {SL_FEATURE_EDGE_AB, SL_FEATURE_EDGE_BC,
                                        SL_FEATURE_EDGE_CA};
    const double *corner[3] = {a, b, c};
    double q[3], best = INFINITY;
    for (int k = 0; k < 3; k++) {
        int end;
        double d = closest_point_segment(p, corner[k], corner[(k + 1) % 3], q, &end);
        if (d < best) {
            best = d;
            memcpy(out, q, sizeof q);
            *feature = end == 0 ? edge_feature[k] : SL_FEATURE_VERTEX_A + (k + end - 1) % 3;
        }
    }
    return best;
}

static double finish(const double p[3], double out[3])
{
    double d[3] = {p[0] - out[0], p[1] - out[1], p[2] - out[2]};
    return sl_dot3(d, d);
}

static void set_lerp(double out[3], const double a[3], const double d[3], double t)
{
    for (int i = 0; i < 3; i++)
        out[i] = a[i] + t * d[i];
}

double sl_closest_point_triangle(const double p[3], const double a[3], const double b[3],
                                 const double c[3], double out[3])
{
    int feature;
    return sl_closest_point_triangle_feature(p, a, b, c, out, &feature);
}

double sl_closest_point_triangle_feature(const double p[3], const double a[3], const double b[3],
                                         const double c[3], double out[3], int *feature)
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], n[3];
    for (int i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ac[i] = c[i] - a[i];
        ap[i] = p[i] - a[i];
        bp[i] = p[i] - b[i];
        cp[i] = p[i] - c[i];
    }
    n[0] = ab[1] * ac[2] - ab[2] * ac[1];
    n[1] = ab[2] * ac[0] - ab[0] * ac[2];
    n[2] = ab[0] * ac[1] - ab[1] * ac[0];
    double area_sq = sl_dot3(n, n);
    if (!(area_sq > 1e-12 * sl_dot3(ab, ab) * sl_dot3(ac, ac)))
        return closest_point_sliver(p, a, b, c, out, feature);

    /* Ericson 5.1.5: find the Voronoi region of p among vertices, edges and face. */
    double d1 = sl_dot3(ab, ap), d2 = sl_dot3(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        *feature = SL_FEATURE_VERTEX_A;
        memcpy(out, a, 3 * sizeof *out);
        return finish(p, out);
    }
    double d3 = sl_dot3(ab, bp), d4 = sl_dot3(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) {
        *feature = SL_FEATURE_VERTEX_B;
        memcpy(out, b, 3 * sizeof *out);
        return finish(p, out);
    }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        *feature = SL_FEATURE_EDGE_AB;
        set_lerp(out, a, ab, d1 / (d1 - d3));
        return finish(p, out);
    }
    double d5 = sl_dot3(ab, cp), d6 = sl_dot3(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) {
        *feature = SL_FEATURE_VERTEX_C;
        memcpy(out, c, 3 * sizeof *out);
        return finish(p, out);
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        *feature = SL_FEATURE_EDGE_CA;
        set_lerp(out, a, ac, d2 / (d2 - d6));
        return finish(p, out);
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        double bc[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
        *feature = SL_FEATURE_EDGE_BC;
        set_lerp(out, b, bc, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
        return finish(p, out);
    }
    double sum = va + vb + vc;
    if (!(sum > 0.0)) /* rounding with p far away from a thin triangle */
        return closest_point_sliver(p, a, b, c, out, feature);
    *feature = SL_FEATURE_FACE;
    double v = vb / sum, w = vc / sum;
    for (int i = 0; i < 3; i++)
        out[i] = a[i] + ab[i] * v + ac[i] * w;
    return finish(p, out);
}

static double box_distance_sq(const sl_bvh_node *node, const double p[3])
{
    double d_sq = 0.0;
    for (int a = 0; a < 3; a++) {
        double d = 0.0;
        if (p[a] < node->lo[a])
            d = node->lo[a] - p[a];
        else if (p[a] > node->hi[a])
            d = p[a] - node->hi[a];
        d_sq += d * d;
    }
    return d_sq;
}

/* Squared distance from p to the bounding box of the triangle at corners f: a lower
 * bound of its distance to the triangle, a tenth of the exact test's cost. */
static inline double corners_box_distance_sq(const float *f, const double p[3])
{
    double d_sq = 0.0;
    for (int a = 0; a < 3; a++) {
        double lo = min_f(min_f(f[a], f[3 + a]), f[6 + a]);
        double hi = max_f(max_f(f[a], f[3 + a]), f[6 + a]);
        double below = lo - p[a], above = p[a] - hi;
        double d = below > above ? below : above;
        d = d > 0.0 ? d : 0.0;
        d_sq += d * d;
    }
    return d_sq;
}

/* A triangle replaces the best only when strictly closer, so one whose box is not closer
 * than the best cannot: it is skipped without the exact test. The margin keeps the skip
 * exact under rounding (the exact test's point may fall a rounding step outside the box),
 * so the answers are the same as without it. */
#define BOX_SKIP_MARGIN (1.0 - 1e-9)

static void try_triangle(const sl_triangle_bvh *bvh, const double p[3], uint32_t t,
                         sl_closest *best)
{
    const float *f = &bvh->corners[9 * (uint64_t)t];
    if (corners_box_distance_sq(f, p) * BOX_SKIP_MARGIN >= best->distance_sq)
        return;
    double a[3] = {f[0], f[1], f[2]}, b[3] = {f[3], f[4], f[5]}, c[3] = {f[6], f[7], f[8]};
    double q[3];
    int feature;
    double d_sq = sl_closest_point_triangle_feature(p, a, b, c, q, &feature);
    if (d_sq < best->distance_sq) {
        best->distance_sq = d_sq;
        memcpy(best->point, q, sizeof q);
        best->triangle = t;
        best->feature = feature;
    }
}

void sl_triangle_bvh_closest(const sl_triangle_bvh *bvh, const double p[3], uint32_t hint,
                             sl_closest *out)
{
    /* Depth-first, nearer child first; a median-split tree over < 2^32 triangles is at
     * most 32 levels deep and the stack holds at most one entry per level. */
    struct entry { uint32_t node; double d_sq; } stack[64];
    int top = 0;
    out->distance_sq = INFINITY;
    out->triangle = 0;
    out->feature = SL_FEATURE_FACE;
    if (hint < bvh->triangle_count)
        try_triangle(bvh, p, hint, out);
    stack[top++] = (struct entry){0, box_distance_sq(&bvh->nodes[0], p)};
    while (top > 0) {
        struct entry e = stack[--top];
        if (e.d_sq >= out->distance_sq)
            continue;
        const sl_bvh_node *node = &bvh->nodes[e.node];
        if (node->count) {
            for (uint32_t i = 0; i < node->count; i++)
                try_triangle(bvh, p, node->first + i, out);
            continue;
        }
        uint32_t l = e.node + 1, r = node->first;
        double dl = box_distance_sq(&bvh->nodes[l], p), dr = box_distance_sq(&bvh->nodes[r], p);
        if (dl > dr) {
            uint32_t ti = l; l = r; r = ti;
            double td = dl; dl = dr; dr = td;
        }
        if (dr < out->distance_sq)
            stack[top++] = (struct entry){r, dr};
        if (dl < out->distance_sq)
            stack[top++] = (struct entry){l, dl};
    }
}
