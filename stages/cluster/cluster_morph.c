/* Intermediate models between a pass's input M and its output M' (paper 2, section 4;
 * docs/clustering.md "Morphing").
 *
 * Border transition (4.1): every vertex b a border's straightening removed has a
 * projection Pr(b) on the segment that replaced it (the nearest point of the segment);
 * intermediate border j of m (t = j / (m + 1)) has b at b + t (Pr(b) - b), the j-th of m
 * points dividing b -> Pr(b) in m + 1 equal steps. Kept vertices stay.
 *
 * Simplification of the intermediates (section 3: "we apply the border straightening
 * process to each intermediate mesh"; the paper gives no tolerance for it): intermediate
 * border j is straightened again with tolerance tau_j = theta_j (1 - t) d_c, d_c the
 * border's deviation in M' and theta_j the j / (m + 1) quantile of o / d_c over the
 * vertices M' drops (o: a vertex's distance to its segment). A moved vertex lies (1 - t) o
 * from its segment, so intermediate j drops roughly those with o <= theta_j d_c: about
 * j / (m + 1) of them, an even progression (with theta_j = t instead, most vertices of a
 * smooth border sit near its largest offset and go only in the last steps). The sets kept
 * are nested: computed from j = m down to 1, each refining the next one's segments by
 * Douglas-Peucker on its own moved vertices, so a vertex intermediate j drops stays dropped
 * in every later one and in M' (triangle counts never rise with j). A vertex moved by t
 * lies within t o <= t d_c of its input border, a dropped one within tau_j of its new
 * segment, so the intermediate's borders stay within t d_c + theta_j (1 - t) d_c <= d_c of
 * the input's: the pass's bound holds for every intermediate (docs/clustering.md).
 *
 * Triangulation (section 4.2): each cluster's polygon with the intermediate borders, as
 * for M'. A refused polygon takes M''s borders (for this and every later intermediate,
 * so counts stay monotone) and its neighbours are tried again; a cluster whose borders
 * are all M''s is M''s polygon, which triangulated.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/predicates.h"
#include "stages/cluster/cluster_internal.h"

void cl_intermediate_release(sl_cluster_intermediate *m)
{
    free(m->positions);
    free(m->source);
    free(m->triangles);
    memset(m, 0, sizeof *m);
}

typedef struct morph {
    const cl_morph_input *in;
    uint32_t entries;
    double *proj;     /* 3 per entry: Pr(b) (the vertex itself when kept in M') */
    uint8_t *level;   /* per entry: the last intermediate keeping it (m + 1: M' keeps it) */
    uint8_t *fallen;  /* per border: takes M''s state */
    uint8_t *keep;    /* per entry: the current intermediate's keep flags */
    double *theta;    /* m + 1: theta[j], the share of d_c below which intermediate j drops */
    float *pos;       /* the current intermediate's positions (vertex_count) */
    uint8_t *moves;   /* per cluster: some border of it has a vertex M' dropped */
} morph;

static void entry_point(const morph *mo, uint32_t e, double p[3])
{
    const float *q = mo->in->positions + 3 * (uint64_t)mo->in->borders->verts[e];
    p[0] = q[0];
    p[1] = q[1];
    p[2] = q[2];
}

static void moved_point(const morph *mo, uint32_t e, double t, double p[3])
{
    entry_point(mo, e, p);
    for (int k = 0; k < 3; k++)
        p[k] += t * (mo->proj[3 * (uint64_t)e + k] - p[k]);
}

/* Projections onto M''s segments; levels of the kept. */
static void project_border(morph *mo, uint32_t br)
{
    const cl_borders *b = mo->in->borders;
    uint32_t s = b->start[br], e = b->start[br + 1], m = mo->in->m;
    int straight = !(b->flags[br] & (CL_BORDER_FROZEN | CL_BORDER_REVERTED));
    for (uint32_t i = s; i < e; i++) {
        double p[3];
        entry_point(mo, i, p);
        memcpy(mo->proj + 3 * (uint64_t)i, p, sizeof p);
        mo->level[i] = (uint8_t)(b->keep[i] || !straight ? m + 1 : 0);
    }
    if (!straight)
        return;
    for (uint32_t i = s; i + 1 < e;) {
        uint32_t j = i + 1;
        while (!b->keep[j])
            j++;
        double a[3], z[3];
        entry_point(mo, i, a);
        entry_point(mo, j, z);
        for (uint32_t k = i + 1; k < j; k++) {
            double p[3];
            entry_point(mo, k, p);
            cl_segment_distance(p, a, z, mo->proj + 3 * (uint64_t)k);
        }
        i = j;
    }
}

/* Refines the vertices kept by intermediate j + 1 into those kept by j: Douglas-Peucker
 * on the moved border within each of j + 1's segments, tolerance tau. */
static void refine_border(morph *mo, uint32_t br, uint32_t j, double t, double tau,
                          uint32_t *stack)
{
    const cl_borders *b = mo->in->borders;
    uint32_t s = b->start[br], e = b->start[br + 1];
    for (uint32_t i = s; i + 1 < e;) {
        uint32_t k = i + 1;
        while (mo->level[k] <= j)
            k++;
        uint32_t top = 0;
        stack[top++] = i;
        stack[top++] = k;
        while (top) {
            uint32_t hi = stack[--top], lo = stack[--top];
            if (hi - lo < 2)
                continue;
            double a[3], z[3], best = -1.0;
            uint32_t far = lo;
            moved_point(mo, lo, t, a);
            moved_point(mo, hi, t, z);
            for (uint32_t x = lo + 1; x < hi; x++) {
                double p[3];
                moved_point(mo, x, t, p);
                double d = cl_segment_distance(p, a, z, NULL);
                if (d > best) {
                    best = d;
                    far = x;
                }
            }
            if (best > tau) {
                mo->level[far] = (uint8_t)j;
                stack[top++] = lo;
                stack[top++] = far;
                stack[top++] = far;
                stack[top++] = hi;
            }
        }
        i = k;
    }
}

static int ratio_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* theta[j]: the j / (m + 1) quantile of o / d_c over the vertices M' dropped, so that
 * each intermediate drops about as many as the one before. */
static int quantiles(morph *mo)
{
    const cl_borders *b = mo->in->borders;
    uint32_t m = mo->in->m;
    uint64_t n = 0;
    for (uint32_t i = 0; i < mo->entries; i++)
        n += mo->level[i] == 0;
    double *r = malloc((n ? n : 1) * sizeof *r);
    if (!r)
        return -1;
    n = 0;
    for (uint32_t br = 0; br < b->count; br++)
        for (uint32_t i = b->start[br]; i < b->start[br + 1]; i++)
            if (mo->level[i] == 0) {
                double p[3], o2 = 0.0;
                entry_point(mo, i, p);
                for (int k = 0; k < 3; k++)
                    o2 += (p[k] - mo->proj[3 * (uint64_t)i + k]) * (p[k] - mo->proj[3 * (uint64_t)i + k]);
                double d = b->deviation[br];
                r[n++] = d > 0.0 ? fmin(1.0, sqrt(o2) / d) : 0.0;
            }
    qsort(r, n, sizeof *r, ratio_cmp);
    for (uint32_t j = 1; j <= m; j++)
        mo->theta[j] = n ? r[(uint64_t)((double)j / (m + 1) * (double)n)] : 1.0;
    free(r);
    return 0;
}

static int levels(morph *mo)
{
    const cl_borders *b = mo->in->borders;
    uint32_t m = mo->in->m;
    uint32_t longest = 4;
    for (uint32_t br = 0; br < b->count; br++)
        if (b->start[br + 1] - b->start[br] + 4 > longest)
            longest = b->start[br + 1] - b->start[br] + 4;
    int64_t nb = b->count;
#pragma omp parallel for schedule(dynamic, 64)
    for (int64_t br = 0; br < nb; br++)
        project_border(mo, (uint32_t)br);
    if (quantiles(mo))
        return -1;
    int ok = 1;
#pragma omp parallel
    {
        uint32_t *stack = malloc(4 * (size_t)longest * sizeof *stack);
        if (!stack) {
#pragma omp atomic write
            ok = 0;
        }
#pragma omp for schedule(dynamic, 64)
        for (int64_t br = 0; br < nb; br++) {
            if (!stack || (b->flags[br] & (CL_BORDER_FROZEN | CL_BORDER_REVERTED)))
                continue;
            for (uint32_t j = m; j >= 1; j--) {
                double t = (double)j / (m + 1);
                refine_border(mo, (uint32_t)br, j, t, mo->theta[j] * (1.0 - t) * b->deviation[br],
                              stack);
            }
        }
        free(stack);
    }
    return ok ? 0 : -1;
}

/* Positions and keep flags of intermediate j (t), given the fallen borders. */
static void state_of(morph *mo, uint32_t j, double t)
{
    const cl_borders *b = mo->in->borders;
    memcpy(mo->pos, mo->in->positions, 3 * mo->in->vertex_count * sizeof *mo->pos);
    for (uint32_t br = 0; br < b->count; br++)
        for (uint32_t i = b->start[br]; i < b->start[br + 1]; i++) {
            if (mo->fallen[br]) {
                mo->keep[i] = b->keep[i];
                continue;
            }
            mo->keep[i] = mo->level[i] >= j;
            if (mo->level[i] <= mo->in->m) { /* moves */
                double p[3];
                moved_point(mo, i, t, p);
                float *q = mo->pos + 3 * (uint64_t)b->verts[i];
                for (int k = 0; k < 3; k++)
                    q[k] = (float)p[k];
            }
        }
}

/* The rounding of the moved positions to float: the largest distance it moved a vertex
 * (of the borders that move: a fallen border's kept vertices are M''s, unmoved). */
static double rounding(const morph *mo, double t)
{
    const cl_borders *b = mo->in->borders;
    double worst = 0.0;
    for (uint32_t br = 0; br < b->count; br++)
        for (uint32_t i = b->start[br]; i < b->start[br + 1] && !mo->fallen[br]; i++)
            if (mo->level[i] <= mo->in->m) {
                double p[3], d2 = 0.0;
                moved_point(mo, i, t, p);
                const float *q = mo->pos + 3 * (uint64_t)b->verts[i];
                for (int k = 0; k < 3; k++)
                    d2 += (p[k] - q[k]) * (p[k] - q[k]);
                worst = fmax(worst, sqrt(d2));
            }
    return worst;
}

/* Compacts the triangulation into intermediate `out`, with its bound. */
static int assemble(const morph *mo, const cl_triangulation *t, uint32_t j, double tj,
                    sl_cluster_intermediate *out)
{
    const cl_clusters *c = mo->in->clusters;
    const cl_borders *b = mo->in->borders;
    uint64_t nv = mo->in->vertex_count, total = 0;
    for (uint32_t k = 0; k < c->count; k++)
        total += t->count[k];
    uint32_t *map = malloc((nv ? nv : 1) * sizeof *map);
    out->triangles = malloc(3 * (total ? total : 1) * sizeof *out->triangles);
    if (!map || !out->triangles) {
        free(map);
        return -1;
    }
    memset(map, 0xff, nv * sizeof *map);
    for (uint32_t k = 0; k < c->count; k++)
        for (uint64_t i = 0; i < 3 * (uint64_t)t->count[k]; i++)
            map[t->tri[k][i]] = 0;
    uint64_t used = 0;
    for (uint64_t v = 0; v < nv; v++)
        if (map[v] != CL_NONE)
            map[v] = (uint32_t)used++;
    out->positions = malloc(3 * (used ? used : 1) * sizeof *out->positions);
    out->source = malloc((used ? used : 1) * sizeof *out->source);
    if (!out->positions || !out->source) {
        free(map);
        return -1;
    }
    for (uint64_t v = 0; v < nv; v++)
        if (map[v] != CL_NONE) {
            memcpy(out->positions + 3 * (uint64_t)map[v], mo->pos + 3 * v, 3 * sizeof(float));
            out->source[map[v]] = (uint32_t)v;
        }
    uint64_t at = 0;
    for (uint32_t k = 0; k < c->count; k++)
        for (uint64_t i = 0; i < 3 * (uint64_t)t->count[k]; i++)
            out->triangles[at++] = map[t->tri[k][i]];
    free(map);
    out->vertex_count = used;
    out->triangle_count = total;
    double beta = 0.0;
    for (uint32_t k = 0; k < c->count; k++) {
        if (c->kept[k])
            continue;
        double lat = 0.0;
        for (uint32_t l = b->cluster_loop[k]; l < b->cluster_loop[k + 1]; l++)
            for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++) {
                uint32_t br = b->pieces[p] >> 1;
                double share = tj + mo->theta[j] * (1.0 - tj); /* t d + tau <= d */
                double d = b->deviation[br] * (mo->fallen[br] ? 1.0 : share);
                lat = fmax(lat, d);
            }
        double w = c->hi[k] - c->lo[k];
        beta = fmax(beta, sqrt(w * w + lat * lat));
    }
    out->bound = mo->in->base_bound + beta + fmax(mo->in->margin, rounding(mo, tj));
    return 0;
}

/* Cluster k's triangles in M' as its triangles in t; -1 out of memory. */
static int copy_destination(const morph *mo, uint32_t k, cl_triangulation *t)
{
    const cl_triangulation *dst = mo->in->destination;
    uint32_t n = dst->count[k];
    uint32_t *tri = malloc(3 * (size_t)(n ? n : 1) * sizeof *tri);
    if (!tri)
        return -1;
    memcpy(tri, dst->tri[k], 3 * (size_t)n * sizeof *tri);
    free(t->tri[k]);
    t->tri[k] = tri;
    t->count[k] = n;
    return 0;
}

/* A hash of cluster k's polygon's vertex sequence in the current state. */
static uint64_t polygon_signature(const morph *mo, uint32_t k)
{
    const cl_borders *b = mo->in->borders;
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (uint32_t l = b->cluster_loop[k]; l < b->cluster_loop[k + 1]; l++) {
        h = (h ^ 0xffffffffull) * 0x100000001b3ull;
        for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++) {
            uint32_t br = b->pieces[p] >> 1, rev = b->pieces[p] & 1u;
            uint32_t first = b->start[br], last = b->start[br + 1] - 1;
            for (uint32_t i = 0; i < last - first; i++) {
                uint32_t e = rev ? last - i : first + i;
                if (mo->keep[e])
                    h = (h ^ b->verts[e]) * 0x100000001b3ull;
            }
        }
    }
    return h;
}

/* Cluster k keeps the previous intermediate's triangles when its polygon has the same
 * vertices and every triangle is still strictly counter-clockwise at the moved positions
 * (a set of such triangles bounded by the polygon covers each point as often as the polygon
 * winds around it, all the proof of the bound needs; docs/clustering.md). 1 when reused. */
static int reuse_previous(const morph *mo, uint32_t k, const cl_triangulation *prev,
                          cl_triangulation *t)
{
    uint32_t n = prev->count[k];
    if (!n || !prev->tri[k])
        return 0;
    const double *frame = mo->in->clusters->frame + 12 * (uint64_t)k;
    for (uint32_t i = 0; i < n; i++) {
        double uv[3][2];
        for (int c = 0; c < 3; c++)
            cl_project(frame, mo->pos + 3 * (uint64_t)prev->tri[k][3 * i + c], uv[c], NULL);
        if (sl_orient2d(uv[0], uv[1], uv[2]) <= 0)
            return 0;
    }
    uint32_t *tri = malloc(3 * (size_t)n * sizeof *tri);
    if (!tri)
        return 0;
    memcpy(tri, prev->tri[k], 3 * (size_t)n * sizeof *tri);
    free(t->tri[k]);
    t->tri[k] = tri;
    t->count[k] = n;
    return 1;
}

/* Triangulates intermediate j into t (prev: intermediate j - 1's, with the polygon
 * signatures sig); refused clusters make their borders fall back. */
static int intermediate(morph *mo, uint32_t j, cl_triangulation *t, const cl_triangulation *prev,
                        uint64_t *sig, uint8_t *dirty, uint8_t *failed, sl_error *err)
{
    const cl_clusters *c = mo->in->clusters;
    const cl_borders *b = mo->in->borders;
    double tj = (double)j / (mo->in->m + 1);
    state_of(mo, j, tj);
    for (uint32_t k = 0; k < c->count; k++) { /* a cluster whose borders never move: M''s */
        dirty[k] = mo->moves[k] && !c->kept[k];
        if (!mo->moves[k] && !c->kept[k] && copy_destination(mo, k, t))
            return sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate %u", j);
        if (dirty[k]) {
            uint64_t now = polygon_signature(mo, k);
            if (j > 1 && now == sig[k] && reuse_previous(mo, k, prev, t))
                dirty[k] = 0;
            sig[k] = now;
        }
    }
    for (int round = 0;; round++) {
        state_of(mo, j, tj);
        int rc = cl_triangulate(c, b, mo->pos, mo->keep, dirty, failed, t, err,
                                mo->in->vertex_count);
        if (rc)
            return rc;
        memset(dirty, 0, c->count);
        int any = 0;
        for (uint32_t k = 0; k < c->count; k++) {
            if (!failed[k])
                continue;
            failed[k] = 0;
            int changed = 0;
            for (uint32_t l = b->cluster_loop[k]; l < b->cluster_loop[k + 1]; l++)
                for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++) {
                    uint32_t br = b->pieces[p] >> 1;
                    if (mo->fallen[br])
                        continue;
                    mo->fallen[br] = changed = 1;
                    dirty[b->left[br]] = 1;
                    if (b->right[br] != CL_NONE)
                        dirty[b->right[br]] = 1;
                }
            if (!changed && copy_destination(mo, k, t)) /* M''s own polygon */
                return sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate %u", j);
            sig[k] = 0; /* its state changed: no reuse next time */
            any = 1;
        }
        if (!any)
            break;
    }
    for (uint32_t k = 0; k < c->count; k++)
        if (c->kept[k] && copy_destination(mo, k, t))
            return sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate %u", j);
    return 0;
}

int cl_morph(const cl_morph_input *in, sl_cluster_intermediate *out, sl_progress *progress,
             sl_error *err)
{
    const cl_borders *b = in->borders;
    uint32_t nc = in->clusters->count;
    morph mo = {in, b->start[b->count], NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    uint64_t entries = mo.entries ? mo.entries : 1;
    mo.proj = malloc(3 * entries * sizeof *mo.proj);
    mo.level = malloc(entries);
    mo.keep = malloc(entries);
    mo.fallen = calloc(b->count ? b->count : 1, 1);
    mo.theta = calloc((size_t)in->m + 1, sizeof *mo.theta);
    mo.moves = calloc(nc ? nc : 1, 1);
    mo.pos = malloc(3 * (in->vertex_count ? in->vertex_count : 1) * sizeof *mo.pos);
    uint8_t *dirty = malloc(nc ? nc : 1), *failed = calloc(nc ? nc : 1, 1);
    int rc = mo.proj && mo.level && mo.keep && mo.fallen && mo.theta && mo.moves && mo.pos && dirty && failed &&
                     levels(&mo) == 0
                 ? 0
                 : sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate models");
    for (uint32_t br = 0; br < b->count && rc == 0; br++)
        for (uint32_t i = b->start[br]; i < b->start[br + 1]; i++)
            if (mo.level[i] <= in->m) {
                mo.moves[b->left[br]] = 1;
                if (b->right[br] != CL_NONE)
                    mo.moves[b->right[br]] = 1;
                break;
            }
    cl_triangulation prev;
    memset(&prev, 0, sizeof prev);
    uint64_t *sig = calloc(nc ? nc : 1, sizeof *sig);
    if (rc == 0 && (cl_triangulation_init(&prev, nc) || !sig))
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate models");
    for (uint32_t j = 1; j <= in->m && rc == 0; j++) {
        if (sl_progress_interrupted(progress)) {
            rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "interrupted");
            break;
        }
        cl_triangulation t;
        if (cl_triangulation_init(&t, nc)) {
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate %u", j);
            break;
        }
        rc = intermediate(&mo, j, &t, &prev, sig, dirty, failed, err);
        if (rc == 0) {
            state_of(&mo, j, (double)j / (in->m + 1)); /* the final state's positions */
            if (assemble(&mo, &t, j, (double)j / (in->m + 1), &out[j - 1]))
                rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate %u", j);
        }
        cl_triangulation_release(&prev, nc);
        prev = t;
    }
    cl_triangulation_release(&prev, nc);
    free(sig);
    if (rc)
        for (uint32_t j = 0; j < in->m; j++)
            cl_intermediate_release(&out[j]);
    free(mo.proj);
    free(mo.level);
    free(mo.keep);
    free(mo.fallen);
    free(mo.theta);
    free(mo.moves);
    free(mo.pos);
    free(dirty);
    free(failed);
    return rc;
}
