/* One pass of the clustering LOD (paper 2, section 1; docs/clustering.md): clustering,
 * border straightening, triangulation, and the pass's bound.
 *
 * Tolerances: clusters grow within a slab of width slab_share * eps; a border between
 * clusters A and B is straightened within sqrt(eps^2 - max(w_A, w_B)^2), using the slack
 * its clusters left, so that sqrt(w^2 + d^2) <= eps for both. The bound proven for the
 * pass is beta = max over retriangulated clusters A of sqrt(w_A^2 + d_A^2) (d_A the
 * largest deviation of A's borders) plus the rounding margin; kept clusters add nothing.
 *
 * Refusals: a polygon the triangulation refuses has the straightening of the borders
 * whose segments cross (in its projection) undone, or, when none cross, of all its
 * borders (they keep every vertex), and is tried again with its neighbours across those
 * borders; a polygon refused with nothing left to undo keeps its input triangles. Each
 * round only undoes, so the loop ends; rounds are ordered by cluster index.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/region_grow.h"
#include "stages/cluster/cluster_internal.h"

void cl_pass_output_release(cl_pass_output *out)
{
    free(out->triangles);
    for (uint32_t j = 0; j < out->intermediate_count; j++)
        cl_intermediate_release(&out->intermediates[j]);
    free(out->intermediates);
    memset(out, 0, sizeof *out);
}

static double slab_width(const cl_clusters *c, uint32_t k)
{
    return c->hi[k] - c->lo[k];
}

static void set_tolerances(const cl_clusters *c, cl_borders *b, double eps)
{
    for (uint32_t br = 0; br < b->count; br++) {
        double w = slab_width(c, b->left[br]);
        if (b->right[br] != CL_NONE && slab_width(c, b->right[br]) > w)
            w = slab_width(c, b->right[br]);
        b->tolerance[br] = eps > w ? sqrt(eps * eps - w * w) : 0.0;
    }
}

/* Undoes the straightening of border br and marks its clusters dirty; 0 when it had
 * removed no vertex. */
static int revert_border(cl_borders *b, uint32_t br, uint8_t *dirty)
{
    uint32_t s = b->start[br], e = b->start[br + 1];
    int removed = 0;
    for (uint32_t i = s; i < e; i++)
        removed |= !b->keep[i];
    if (!removed)
        return 0;
    memset(b->keep + s, 1, e - s);
    b->flags[br] |= CL_BORDER_REVERTED;
    b->deviation[br] = 0.0;
    dirty[b->left[br]] = 1;
    if (b->right[br] != CL_NONE)
        dirty[b->right[br]] = 1;
    return 1;
}

/* Undoes the straightening of cluster k's borders. Returns how many borders changed. */
static uint32_t revert_cluster(cl_borders *b, uint32_t k, uint8_t *dirty)
{
    uint32_t changed = 0;
    for (uint32_t l = b->cluster_loop[k]; l < b->cluster_loop[k + 1]; l++)
        for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++)
            changed += (uint32_t)revert_border(b, b->pieces[p] >> 1, dirty);
    return changed;
}

/* Triangulates every cluster, undoing straightening around refused polygons until none
 * is refused: first only the borders whose segments cross in the polygon's projection,
 * and when none do (a fold, or a point on a segment of its own loop), all its borders. */
static int settle(cl_clusters *c, cl_borders *b, const cl_pass_input *in, cl_triangulation *t,
                  sl_cluster_pass_stats *st, sl_error *err)
{
    uint32_t n = c->count;
    uint8_t *dirty = malloc(n ? n : 1), *failed = calloc(n ? n : 1, 1);
    uint8_t *marked = calloc(b->count ? b->count : 1, 1);
    uint32_t *crossing = malloc((b->count ? b->count : 1) * sizeof *crossing);
    if (!dirty || !failed || !marked || !crossing) {
        free(marked);
        free(crossing);
        free(dirty);
        free(failed);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangulating %u clusters", n);
    }
    int rc = 0;
    for (uint32_t k = 0; k < n && rc == 0; k++) {
        dirty[k] = !c->kept[k];
        if (c->kept[k] && cl_keep_input(c, in->triangles, k, t))
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangles of cluster %u", k);
    }
    for (int any = 1; any && rc == 0;) {
        rc = cl_triangulate(c, b, in->positions, b->keep, dirty, failed, t, err, in->vertex_count);
        memset(dirty, 0, n);
        any = 0;
        for (uint32_t k = 0; k < n && rc == 0; k++) {
            if (!failed[k])
                continue;
            failed[k] = 0;
            st->triangulation_failures++;
            /* first only the borders whose segments cross: the fewest vertices back */
            int nc = cl_polygon_crossings(c, b, in->positions, b->keep, k, marked, crossing);
            if (nc < 0) {
                rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "polygon of cluster %u", k);
                break;
            }
            uint32_t changed = 0;
            for (int i = 0; i < nc; i++)
                changed += (uint32_t)revert_border(b, crossing[i], dirty);
            if (!changed) /* none crossing, or none of those straightened */
                changed = revert_cluster(b, k, dirty);
            st->borders_reverted += changed;
            if (!changed) { /* nothing left to undo: the input's triangles */
                c->kept[k] = CL_KEPT_REFUSED;
                st->clusters_kept++;
                if (cl_keep_input(c, in->triangles, k, t))
                    rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangles of cluster %u", k);
            }
            any = 1;
        }
    }
    free(dirty);
    free(failed);
    free(marked);
    free(crossing);
    return rc;
}

/* The pass's bound and the counts of what it removed. */
static void pass_figures(const cl_clusters *c, const cl_borders *b, const cl_pass_input *in,
                         const cl_triangulation *t, sl_cluster_pass_stats *st, uint8_t *mark)
{
    double beta = 0.0, slab = 0.0, dev = 0.0;
    for (uint32_t k = 0; k < c->count; k++) {
        if (c->kept[k])
            continue;
        double d = 0.0;
        for (uint32_t l = b->cluster_loop[k]; l < b->cluster_loop[k + 1]; l++)
            for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++)
                d = fmax(d, b->deviation[b->pieces[p] >> 1]);
        double w = slab_width(c, k);
        beta = fmax(beta, sqrt(w * w + d * d));
        slab = fmax(slab, w);
        dev = fmax(dev, d);
    }
    st->bound = beta + in->margin;
    st->max_slab = slab;
    st->max_deviation = dev;
    /* mark: 1 used by the input, 2 also by the output, 4 a removed border vertex */
    memset(mark, 0, in->vertex_count);
    for (uint64_t i = 0; i < 3 * (uint64_t)in->triangle_count; i++)
        mark[in->triangles[i]] |= 1;
    for (uint32_t k = 0; k < c->count; k++)
        for (uint64_t i = 0; i < 3 * (uint64_t)t->count[k]; i++)
            mark[t->tri[k][i]] |= 2;
    for (uint32_t br = 0; br < b->count; br++)
        for (uint32_t i = b->start[br]; i < b->start[br + 1]; i++)
            if (!b->keep[i])
                mark[b->verts[i]] |= 4;
    for (uint64_t v = 0; v < in->vertex_count; v++)
        if ((mark[v] & 3) == 1) {
            if (mark[v] & 4)
                st->removed_border++;
            else
                st->removed_interior++;
        }
}

static int assemble(const cl_clusters *c, const cl_triangulation *t, cl_pass_output *out,
                    sl_error *err)
{
    uint64_t total = 0;
    for (uint32_t k = 0; k < c->count; k++)
        total += t->count[k];
    out->triangles = malloc(3 * (total ? total : 1) * sizeof *out->triangles);
    if (!out->triangles)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "%llu output triangles",
                            (unsigned long long)total);
    uint64_t at = 0;
    for (uint32_t k = 0; k < c->count; k++) {
        memcpy(out->triangles + 3 * at, t->tri[k], 3 * (size_t)t->count[k] * sizeof *out->triangles);
        at += t->count[k];
    }
    out->triangle_count = (uint32_t)total;
    return 0;
}

/* The clusters, borders and triangulation of one try. */
typedef struct pass_try {
    sl_segment_loops loops;
    cl_clusters c;
    cl_borders b;
    cl_triangulation t;
} pass_try;

static void try_release(pass_try *p)
{
    cl_triangulation_release(&p->t, p->c.count);
    cl_borders_release(&p->b);
    cl_clusters_release(&p->c);
    sl_segment_loops_release(&p->loops);
}

static int run_try(const cl_pass_input *in, const sl_mesh_adjacency *adj, const double *normals,
                   const double *slab_limit, const double *cos_limit, pass_try *p,
                   sl_cluster_pass_stats *st, sl_progress *progress, sl_error *err)
{
    memset(p, 0, sizeof *p);
    sl_cluster_pass_stats fresh = {0};
    fresh.tolerance = st->tolerance;
    fresh.triangles_in = st->triangles_in;
    *st = fresh;
    int rc = cl_grow(adj, in->positions, normals, slab_limit, cos_limit, &p->c, err);
    if (rc == 0 && sl_progress_interrupted(progress))
        rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "interrupted");
    if (rc == 0)
        rc = sl_segment_loops_build(adj, in->positions, p->c.of_triangle, p->c.count, &p->loops, err);
    if (rc == 0)
        rc = cl_borders_build(adj, &p->loops, &p->c, &p->b, err);
    if (rc == 0) {
        set_tolerances(&p->c, &p->b, in->tolerance);
        st->forced_splits = cl_borders_straighten(&p->b, in->positions);
        st->clusters = p->c.count;
        st->corners = p->b.corners;
        st->borders = p->b.count;
        for (uint32_t k = 0; k < p->c.count; k++)
            st->clusters_kept += p->c.kept[k] != 0;
        if (cl_triangulation_init(&p->t, p->c.count))
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangulation of %u clusters", p->c.count);
    }
    if (rc == 0)
        rc = settle(&p->c, &p->b, in, &p->t, st, err);
    return rc;
}

/* Halves the angle and slab limits of the triangles of clusters whose own polygon was
 * refused (a projection that folds: a cluster reaching over a crease, or over two layers
 * of a scan), when they hold at least 1/200 of the triangles (smaller ones are not worth
 * clustering everything again: they keep their triangles); 0 when there are none such. */
static int tighten(const cl_clusters *c, uint32_t triangles, double *angle, double *slab_limit,
                   double *cos_limit)
{
    uint64_t refused = 0;
    for (uint32_t k = 0; k < c->count; k++)
        if (c->kept[k] == CL_KEPT_REFUSED)
            refused += c->tri_start[k + 1] - c->tri_start[k];
    if (refused == 0 || 200 * refused < triangles)
        return 0;
    for (uint32_t k = 0; k < c->count; k++) {
        if (c->kept[k] != CL_KEPT_REFUSED)
            continue;
        for (uint32_t i = c->tri_start[k]; i < c->tri_start[k + 1]; i++) {
            uint32_t t = c->tris[i];
            angle[t] *= 0.5;
            cos_limit[t] = cos(angle[t] * (M_PI / 180.0));
            slab_limit[t] *= 0.5;
        }
    }
    return 1;
}

int cl_pass_run(const cl_pass_input *in, cl_pass_output *out, sl_progress *progress,
                sl_error *err)
{
    memset(out, 0, sizeof *out);
    sl_cluster_pass_stats *st = &out->stats;
    st->tolerance = in->tolerance;
    st->triangles_in = in->triangle_count;
    sl_mesh_adjacency adj;
    pass_try p;
    memset(&p, 0, sizeof p);
    uint8_t *mark = NULL;
    int rc = sl_mesh_adjacency_build(in->triangles, in->triangle_count, in->vertex_count,
                                     in->positions, 0, &adj, err);
    if (rc)
        return rc;
    size_t n = in->triangle_count ? in->triangle_count : 1;
    double *normals = malloc(3 * n * sizeof *normals), *angle = malloc(n * sizeof *angle);
    double *cos_limit = malloc(n * sizeof *cos_limit), *slab_limit = malloc(n * sizeof *slab_limit);
    if (!normals || !angle || !cos_limit || !slab_limit)
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals of %u triangles", in->triangle_count);
    if (rc == 0) {
        sl_face_normals(&adj, in->positions, normals);
        for (uint32_t t = 0; t < in->triangle_count; t++) {
            angle[t] = in->cfg->max_angle;
            cos_limit[t] = cos(angle[t] * (M_PI / 180.0));
            slab_limit[t] = in->cfg->slab_share * in->tolerance;
        }
    }
    for (int tries = 0; rc == 0; tries++) {
        rc = run_try(in, &adj, normals, slab_limit, cos_limit, &p, st, progress, err);
        st->regrowths = (uint32_t)tries;
        if (rc || tries == 3 || !tighten(&p.c, in->triangle_count, angle, slab_limit, cos_limit))
            break;
        try_release(&p);
    }
    if (rc == 0 && !(mark = malloc(in->vertex_count ? in->vertex_count : 1)))
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "vertex marks");
    if (rc == 0) {
        pass_figures(&p.c, &p.b, in, &p.t, st, mark);
        rc = assemble(&p.c, &p.t, out, err);
        st->triangles_out = out->triangle_count;
    }
    if (rc == 0 && in->intermediates) {
        out->intermediates = calloc(in->intermediates, sizeof *out->intermediates);
        if (!out->intermediates)
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate models");
        else {
            out->intermediate_count = in->intermediates;
            cl_morph_input mi = {&p.c, &p.b, in->positions, in->vertex_count, &p.t,
                                 in->intermediates, in->base_bound, in->margin};
            rc = cl_morph(&mi, out->intermediates, progress, err);
        }
    }
    if (rc)
        cl_pass_output_release(out);
    free(mark);
    free(normals);
    free(angle);
    free(cos_limit);
    free(slab_limit);
    try_release(&p);
    sl_mesh_adjacency_release(&adj);
    return rc;
}
