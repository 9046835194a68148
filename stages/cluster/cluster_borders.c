/* Borders and border straightening (paper 2, sections 3-4: "boundary straightening";
 * docs/clustering.md).
 *
 * Borders: every cluster loop (geometry/segment_loops.h: boundary half-edges with the
 * cluster on their left, traced in a canonical order) is cut at its corner vertices into
 * pieces. The cluster traced first creates a border from a piece; the cluster across it
 * (or nobody, on a mesh boundary) finds it through the twin of its piece's first
 * half-edge and uses it reversed, so both sides share one border and one straightening.
 * A loop without a corner is anchored at its lowest vertex, which both sides pick alike.
 *
 * Straightening: Douglas-Peucker (iterative, in 3D): a border's segment stands for the
 * vertices between its ends when every one lies within the border's tolerance of it;
 * else the farthest is kept and both halves recurse. A closed border starts split at its
 * vertex farthest from its anchor and keeps at least three vertices. Then two repairs,
 * each splitting a segment at its farthest vertex (which only lowers the deviation):
 * every cluster loop keeps at least three vertices, and no two borders end up with the
 * same segment (an edge in four triangles, or a polygon folded onto itself).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/cluster/cluster_internal.h"

void cl_borders_release(cl_borders *b)
{
    free(b->start);
    free(b->verts);
    free(b->left);
    free(b->right);
    free(b->flags);
    free(b->keep);
    free(b->tolerance);
    free(b->deviation);
    free(b->cluster_loop);
    free(b->loop_piece);
    free(b->pieces);
    memset(b, 0, sizeof *b);
}

double cl_segment_distance(const double p[3], const double a[3], const double b[3],
                           double closest[3])
{
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double s = dd > 0.0 ? (w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd : 0.0;
    s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
    double q[3] = {a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]};
    if (closest)
        memcpy(closest, q, sizeof q);
    return sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                (p[2] - q[2]) * (p[2] - q[2]));
}

static void point_of(const float *positions, uint32_t v, double p[3])
{
    for (int k = 0; k < 3; k++)
        p[k] = positions[3 * (uint64_t)v + k];
}

static int is_corner(const sl_mesh_adjacency *adj, const sl_segment_loops *loops, uint32_t v)
{
    uint8_t f = adj->vertex_flags[v], c = loops->vertex_changes[v];
    if (f & (SL_VERTEX_CUT | SL_VERTEX_NONMANIFOLD))
        return 1;
    if (f & SL_VERTEX_BOUNDARY) /* the open fan's label changes: two clusters meet here */
        return c >= 1;
    return c >= 3;
}

/* Growable arrays of the build. */
typedef struct builder {
    uint32_t *verts, *start, *left, *right;
    uint8_t *flags;
    uint64_t verts_len, verts_cap;
    uint32_t count, cap;
    uint32_t *pieces;
    uint64_t pieces_len, pieces_cap;
} builder;

static int reserve(void **p, uint64_t need, uint64_t *cap, size_t size)
{
    if (need <= *cap)
        return 0;
    uint64_t c = *cap ? *cap : 256;
    while (c < need)
        c *= 2;
    void *q = realloc(*p, c * size);
    if (!q)
        return -1;
    *p = q;
    *cap = c;
    return 0;
}

static int new_border(builder *bd, uint32_t left, uint32_t right, int closed)
{
    if (bd->count + 2 > bd->cap) {
        uint32_t cap = bd->cap ? 2 * bd->cap : 256;
        uint32_t *start = realloc(bd->start, (size_t)cap * sizeof *start);
        if (start)
            bd->start = start;
        uint32_t *l = realloc(bd->left, (size_t)cap * sizeof *l);
        if (l)
            bd->left = l;
        uint32_t *r = realloc(bd->right, (size_t)cap * sizeof *r);
        if (r)
            bd->right = r;
        uint8_t *f = realloc(bd->flags, cap);
        if (f)
            bd->flags = f;
        if (!start || !l || !r || !f)
            return -1;
        bd->cap = cap;
    }
    bd->start[bd->count] = (uint32_t)bd->verts_len;
    bd->left[bd->count] = left;
    bd->right[bd->count] = right;
    bd->flags[bd->count] = closed ? CL_BORDER_CLOSED : 0;
    bd->count++;
    return 0;
}

static int push_u32(uint32_t **a, uint64_t *len, uint64_t *cap, uint32_t v)
{
    if (reserve((void **)a, *len + 1, cap, sizeof **a))
        return -1;
    (*a)[(*len)++] = v;
    return 0;
}

/* One loop of cluster k: its pieces between corners, as new or reversed borders. */
static int trace_loop(const sl_mesh_adjacency *adj, const cl_clusters *c, const uint32_t *h,
                      uint32_t n, uint32_t k,
                      const uint8_t *corner, uint32_t *border_of_he, builder *bd)
{
    uint32_t start = UINT32_MAX, lowest = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t v = sl_halfedge_origin(adj, h[i]);
        if (corner[v] && start == UINT32_MAX)
            start = i;
        if (v < sl_halfedge_origin(adj, h[lowest]))
            lowest = i;
    }
    int anchored = start == UINT32_MAX;
    if (anchored)
        start = lowest;
    uint32_t i = start;
    do {
        uint32_t j = (i + 1) % n;
        while (!anchored && j != start && !corner[sl_halfedge_origin(adj, h[j])])
            j = (j + 1) % n;
        if (anchored)
            j = start;
        uint32_t first = h[i], tw = adj->twin[first];
        if (tw != SL_HALFEDGE_NONE && border_of_he[tw] != CL_NONE) {
            if (push_u32(&bd->pieces, &bd->pieces_len, &bd->pieces_cap, border_of_he[tw] << 1 | 1u))
                return -1;
        } else {
            uint32_t right = tw == SL_HALFEDGE_NONE ? CL_NONE : c->of_triangle[sl_halfedge_face(tw)];
            uint32_t id = bd->count;
            if (new_border(bd, k, right, i == j))
                return -1;
            uint32_t e = i;
            do {
                border_of_he[h[e]] = id;
                if (push_u32(&bd->verts, &bd->verts_len, &bd->verts_cap, sl_halfedge_origin(adj, h[e])))
                    return -1;
                e = (e + 1) % n;
            } while (e != j);
            if (push_u32(&bd->verts, &bd->verts_len, &bd->verts_cap, sl_halfedge_origin(adj, h[j])) ||
                push_u32(&bd->pieces, &bd->pieces_len, &bd->pieces_cap, id << 1))
                return -1;
        }
        i = j;
    } while (i != start);
    return 0;
}

int cl_borders_build(const sl_mesh_adjacency *adj, const sl_segment_loops *loops,
                     const cl_clusters *c, cl_borders *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    builder bd;
    memset(&bd, 0, sizeof bd);
    uint64_t nh = 3 * (uint64_t)adj->triangle_count;
    uint8_t *corner = malloc(adj->vertex_count ? adj->vertex_count : 1);
    uint32_t *border_of_he = malloc((nh ? nh : 1) * sizeof *border_of_he);
    out->cluster_loop = malloc(((size_t)c->count + 1) * sizeof *out->cluster_loop);
    out->loop_piece = malloc(((size_t)loops->loop_count + 1) * sizeof *out->loop_piece);
    int ok = corner && border_of_he && out->cluster_loop && out->loop_piece;
    if (ok) {
        memset(border_of_he, 0xff, nh * sizeof *border_of_he);
        uint64_t corners = 0;
        for (uint32_t v = 0; v < adj->vertex_count; v++) {
            corner[v] = (adj->vertex_flags[v] & SL_VERTEX_USED) && is_corner(adj, loops, v);
            corners += corner[v];
        }
        out->corners = corners;
        out->loop_count = loops->loop_count;
        for (uint32_t k = 0; k < c->count && ok; k++) {
            out->cluster_loop[k] = loops->segment_loop_start[k];
            for (uint32_t l = loops->segment_loop_start[k]; l < loops->segment_loop_start[k + 1] && ok; l++) {
                out->loop_piece[l] = (uint32_t)bd.pieces_len;
                const uint32_t *h = loops->halfedges + loops->loop_start[l];
                uint32_t n = loops->loop_start[l + 1] - loops->loop_start[l];
                ok = trace_loop(adj, c, h, n, k, corner, border_of_he, &bd) == 0;
            }
        }
        out->cluster_loop[c->count] = loops->loop_count;
        out->loop_piece[loops->loop_count] = (uint32_t)bd.pieces_len;
    }
    free(corner);
    free(border_of_he);
    if (ok && new_border(&bd, 0, 0, 0) == 0) /* the end offset */
        bd.count--;
    else
        ok = 0;
    out->count = bd.count;
    out->start = bd.start;
    out->verts = bd.verts;
    out->left = bd.left;
    out->right = bd.right;
    out->flags = bd.flags;
    out->pieces = bd.pieces;
    if (ok) {
        uint64_t entries = bd.verts_len ? bd.verts_len : 1;
        out->keep = calloc(entries, 1);
        out->tolerance = calloc(bd.count ? bd.count : 1, sizeof *out->tolerance);
        out->deviation = calloc(bd.count ? bd.count : 1, sizeof *out->deviation);
        ok = out->keep && out->tolerance && out->deviation;
    }
    if (!ok) {
        cl_borders_release(out);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "borders of %u clusters", c->count);
    }
    for (uint32_t b = 0; b < out->count; b++) {
        uint32_t l = out->left[b], r = out->right[b];
        if (c->kept[l] || (r != CL_NONE && c->kept[r]))
            out->flags[b] |= CL_BORDER_FROZEN;
    }
    return SL_OK;
}

/* Farthest removed entry strictly between kept entries i and j of border b. */
static uint32_t farthest(const cl_borders *b, const float *positions, uint32_t i, uint32_t j,
                         double *dist)
{
    double a[3], e[3], p[3];
    point_of(positions, b->verts[i], a);
    point_of(positions, b->verts[j], e);
    uint32_t best = CL_NONE;
    *dist = -1.0;
    for (uint32_t k = i + 1; k < j; k++) {
        point_of(positions, b->verts[k], p);
        double d = cl_segment_distance(p, a, e, NULL);
        if (d > *dist) {
            *dist = d;
            best = k;
        }
    }
    return best;
}

void cl_border_deviation(cl_borders *b, const float *positions, uint32_t border)
{
    uint32_t s = b->start[border], e = b->start[border + 1];
    double dev = 0.0;
    for (uint32_t i = s; i + 1 < e;) {
        uint32_t j = i + 1;
        while (!b->keep[j])
            j++;
        double d;
        if (j - i >= 2 && farthest(b, positions, i, j, &d) != CL_NONE && d > dev)
            dev = d;
        i = j;
    }
    b->deviation[border] = dev;
}

int cl_border_split(cl_borders *b, const float *positions, uint32_t border, uint32_t entry)
{
    uint32_t s = b->start[border], e = b->start[border + 1];
    if (b->flags[border] & (CL_BORDER_FROZEN | CL_BORDER_REVERTED) || entry + 1 >= e)
        return 0;
    uint32_t i = entry, j = entry + 1;
    while (i > s && !b->keep[i])
        i--;
    while (j + 1 < e && !b->keep[j])
        j++;
    double d;
    uint32_t k = j - i >= 2 ? farthest(b, positions, i, j, &d) : CL_NONE;
    if (k == CL_NONE)
        return 0;
    b->keep[k] = 1;
    cl_border_deviation(b, positions, border);
    return 1;
}

/* Douglas-Peucker of one border with its tolerance (an explicit stack of ranges). */
static void straighten_one(cl_borders *b, const float *positions, uint32_t border,
                           uint32_t *stack)
{
    uint32_t s = b->start[border], e = b->start[border + 1];
    memset(b->keep + s, 0, e - s);
    b->keep[s] = b->keep[e - 1] = 1;
    b->deviation[border] = 0.0;
    if (b->flags[border] & (CL_BORDER_FROZEN | CL_BORDER_REVERTED)) {
        memset(b->keep + s, 1, e - s);
        return;
    }
    uint32_t top = 0;
    double tol = b->tolerance[border], dev = 0.0;
    if (b->flags[border] & CL_BORDER_CLOSED) {
        double a[3], p[3], best = -1.0;
        uint32_t far = s + 1;
        point_of(positions, b->verts[s], a);
        for (uint32_t k = s + 1; k + 1 < e; k++) {
            point_of(positions, b->verts[k], p);
            double d = sqrt((p[0] - a[0]) * (p[0] - a[0]) + (p[1] - a[1]) * (p[1] - a[1]) +
                            (p[2] - a[2]) * (p[2] - a[2]));
            if (d > best) {
                best = d;
                far = k;
            }
        }
        b->keep[far] = 1;
        stack[top++] = s;
        stack[top++] = far;
        stack[top++] = far;
        stack[top++] = e - 1;
    } else {
        stack[top++] = s;
        stack[top++] = e - 1;
    }
    while (top) {
        uint32_t j = stack[--top], i = stack[--top];
        double d;
        uint32_t k = j - i >= 2 ? farthest(b, positions, i, j, &d) : CL_NONE;
        if (k == CL_NONE)
            continue;
        if (d > tol) {
            b->keep[k] = 1;
            stack[top++] = i;
            stack[top++] = k;
            stack[top++] = k;
            stack[top++] = j;
        } else if (d > dev) {
            dev = d;
        }
    }
    b->deviation[border] = dev;
    if (b->flags[border] & CL_BORDER_CLOSED) { /* a closed border alone is a whole loop */
        uint32_t kept = 0;
        for (uint32_t k = s; k + 1 < e; k++)
            kept += b->keep[k];
        while (kept < 3 && kept + 1 < e - s) {
            uint32_t entry = s, i = s;
            double worst = -1.0;
            for (uint32_t k = s + 1; k < e; k++)
                if (b->keep[k]) {
                    double d;
                    if (k - i >= 2 && farthest(b, positions, i, k, &d) != CL_NONE && d > worst) {
                        worst = d;
                        entry = i;
                    }
                    i = k;
                }
            if (!cl_border_split(b, positions, border, entry))
                break;
            kept++;
        }
    }
}

/* Kept vertices along loop l (entries, repeats counted). */
static uint32_t loop_kept(const cl_borders *b, uint32_t l)
{
    uint32_t n = 0;
    for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++) {
        uint32_t br = b->pieces[p] >> 1;
        for (uint32_t i = b->start[br]; i + 1 < b->start[br + 1]; i++)
            n += b->keep[i];
    }
    return n;
}

/* Splits the loop's segment with the farthest removed vertex; 0 if it has none. */
static int split_loop(cl_borders *b, const float *positions, uint32_t l)
{
    uint32_t best_border = CL_NONE, best_entry = 0;
    double worst = -1.0;
    for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++) {
        uint32_t br = b->pieces[p] >> 1, s = b->start[br], e = b->start[br + 1];
        if (b->flags[br] & (CL_BORDER_FROZEN | CL_BORDER_REVERTED))
            continue;
        for (uint32_t i = s; i + 1 < e;) {
            uint32_t j = i + 1;
            while (!b->keep[j])
                j++;
            double d;
            if (j - i >= 2 && farthest(b, positions, i, j, &d) != CL_NONE && d > worst) {
                worst = d;
                best_border = br;
                best_entry = i;
            }
            i = j;
        }
    }
    return best_border != CL_NONE && cl_border_split(b, positions, best_border, best_entry);
}

typedef struct segment_key {
    uint32_t lo, hi, border, entry;
} segment_key;

static int key_cmp(const void *a, const void *b)
{
    const segment_key *x = a, *y = b;
    if (x->lo != y->lo)
        return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi)
        return x->hi < y->hi ? -1 : 1;
    if (x->border != y->border)
        return x->border < y->border ? -1 : 1;
    return x->entry < y->entry ? -1 : x->entry > y->entry;
}

/* Splits segments that two borders (or one border twice) share; returns the splits. */
static uint64_t split_shared(cl_borders *b, const float *positions)
{
    uint64_t n = 0, splits = 0;
    for (uint32_t br = 0; br < b->count; br++)
        for (uint32_t i = b->start[br]; i + 1 < b->start[br + 1]; i++)
            n += b->keep[i];
    segment_key *keys = malloc((n ? n : 1) * sizeof *keys);
    if (!keys)
        return 0;
    for (int round = 0; round < 8; round++) {
        uint64_t m = 0;
        for (uint32_t br = 0; br < b->count; br++)
            for (uint32_t i = b->start[br]; i + 1 < b->start[br + 1];) {
                uint32_t j = i + 1;
                while (!b->keep[j])
                    j++;
                uint32_t u = b->verts[i], v = b->verts[j];
                keys[m++] = (segment_key){u < v ? u : v, u < v ? v : u, br, i};
                i = j;
            }
        qsort(keys, m, sizeof *keys, key_cmp);
        uint64_t done = 0;
        for (uint64_t i = 1; i < m; i++)
            if (keys[i].lo == keys[i - 1].lo && keys[i].hi == keys[i - 1].hi)
                done += cl_border_split(b, positions, keys[i].border, keys[i].entry) ||
                        cl_border_split(b, positions, keys[i - 1].border, keys[i - 1].entry);
        splits += done;
        if (!done)
            break;
        if (m + done > n) { /* every split adds one segment */
            segment_key *k2 = realloc(keys, (m + done + 1) * sizeof *keys);
            if (!k2)
                break;
            keys = k2;
            n = m + done;
        }
    }
    free(keys);
    return splits;
}

uint64_t cl_borders_straighten(cl_borders *b, const float *positions)
{
    int64_t nb = b->count;
    uint64_t longest = 4;
    for (uint32_t br = 0; br < b->count; br++)
        if (b->start[br + 1] - b->start[br] + 4 > longest)
            longest = b->start[br + 1] - b->start[br] + 4;
#pragma omp parallel
    {
        uint32_t *stack = malloc(4 * longest * sizeof *stack);
#pragma omp for schedule(dynamic, 64)
        for (int64_t br = 0; br < nb; br++) {
            if (stack)
                straighten_one(b, positions, (uint32_t)br, stack);
            else /* no memory for the stack: keep the border as it is */
                memset(b->keep + b->start[br], 1, b->start[br + 1] - b->start[br]);
        }
        free(stack);
    }
    uint64_t splits = 0;
    for (uint32_t l = 0; l < b->loop_count; l++)
        while (loop_kept(b, l) < 3 && split_loop(b, positions, l))
            splits++;
    return splits + split_shared(b, positions);
}
