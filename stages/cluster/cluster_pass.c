/* One pass of the clustering LOD (paper 2, section 1; docs/clustering.md): clustering,
 * border straightening, triangulation, and the pass's bound.
 *
 * Tolerances: clusters grow within a slab of width slab_share * eps; a border between
 * clusters A and B is straightened within sqrt(eps^2 - max(w_A, w_B)^2), using the slack
 * its clusters left, so that sqrt(w^2 + d^2) <= eps for both. The bound proven for the
 * pass is beta = max over retriangulated clusters A of sqrt(w_A^2 + d_A^2) (d_A the
 * largest deviation of A's borders) plus the rounding margin; kept clusters add nothing.
 *
 * Refusals: a polygon the triangulation refuses has all its borders' straightening
 * undone (they keep every vertex) and is tried again with its neighbours across those
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

/* Undoes the straightening of cluster k's borders; marks the clusters they touch dirty.
 * Returns how many borders changed. */
static uint32_t revert_cluster(cl_borders *b, uint32_t k, uint8_t *dirty)
{
    uint32_t changed = 0;
    for (uint32_t l = b->cluster_loop[k]; l < b->cluster_loop[k + 1]; l++)
        for (uint32_t p = b->loop_piece[l]; p < b->loop_piece[l + 1]; p++) {
            uint32_t br = b->pieces[p] >> 1, s = b->start[br], e = b->start[br + 1];
            int removed = 0;
            for (uint32_t i = s; i < e; i++)
                removed |= !b->keep[i];
            if (!removed)
                continue;
            memset(b->keep + s, 1, e - s);
            b->flags[br] |= CL_BORDER_REVERTED;
            b->deviation[br] = 0.0;
            dirty[b->left[br]] = 1;
            if (b->right[br] != CL_NONE)
                dirty[b->right[br]] = 1;
            changed++;
        }
    return changed;
}

/* Triangulates every cluster, undoing straightening around refused polygons until none
 * is refused. */
static int settle(cl_clusters *c, cl_borders *b, const cl_pass_input *in, cl_triangulation *t,
                  sl_cluster_pass_stats *st, sl_error *err)
{
    uint32_t n = c->count;
    uint8_t *dirty = malloc(n ? n : 1), *failed = calloc(n ? n : 1, 1);
    if (!dirty || !failed) {
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
            uint32_t changed = revert_cluster(b, k, dirty);
            st->borders_reverted += changed;
            if (!changed) { /* nothing left to undo: the input's triangles */
                c->kept[k] = 1;
                st->clusters_kept++;
                if (cl_keep_input(c, in->triangles, k, t))
                    rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangles of cluster %u", k);
            }
            any = 1;
        }
    }
    free(dirty);
    free(failed);
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

int cl_pass_run(const cl_pass_input *in, cl_pass_output *out, sl_progress *progress,
                sl_error *err)
{
    memset(out, 0, sizeof *out);
    sl_cluster_pass_stats *st = &out->stats;
    st->tolerance = in->tolerance;
    st->triangles_in = in->triangle_count;
    sl_mesh_adjacency adj;
    sl_segment_loops loops;
    cl_clusters c;
    cl_borders b;
    cl_triangulation t;
    memset(&loops, 0, sizeof loops);
    memset(&c, 0, sizeof c);
    memset(&b, 0, sizeof b);
    memset(&t, 0, sizeof t);
    double *normals = NULL;
    uint8_t *mark = NULL;
    int rc = sl_mesh_adjacency_build(in->triangles, in->triangle_count, in->vertex_count,
                                     in->positions, 0, &adj, err);
    if (rc)
        return rc;
    normals = malloc(3 * (size_t)(in->triangle_count ? in->triangle_count : 1) * sizeof *normals);
    if (!normals)
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "normals of %u triangles", in->triangle_count);
    if (rc == 0) {
        sl_face_normals(&adj, in->positions, normals);
        rc = cl_grow(&adj, in->positions, normals, in->cfg->slab_share * in->tolerance,
                     cos(in->cfg->max_angle * (M_PI / 180.0)), &c, err);
    }
    if (rc == 0 && sl_progress_interrupted(progress))
        rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "interrupted");
    if (rc == 0)
        rc = sl_segment_loops_build(&adj, in->positions, c.of_triangle, c.count, &loops, err);
    if (rc == 0)
        rc = cl_borders_build(&adj, &loops, &c, &b, err);
    if (rc == 0) {
        set_tolerances(&c, &b, in->tolerance);
        st->forced_splits = cl_borders_straighten(&b, in->positions);
        st->clusters = c.count;
        st->corners = b.corners;
        st->borders = b.count;
        for (uint32_t k = 0; k < c.count; k++)
            st->clusters_kept += c.kept[k];
        if (cl_triangulation_init(&t, c.count))
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "triangulation of %u clusters", c.count);
    }
    if (rc == 0)
        rc = settle(&c, &b, in, &t, st, err);
    if (rc == 0 && !(mark = malloc(in->vertex_count ? in->vertex_count : 1)))
        rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "vertex marks");
    if (rc == 0) {
        pass_figures(&c, &b, in, &t, st, mark);
        rc = assemble(&c, &t, out, err);
        st->triangles_out = out->triangle_count;
    }
    if (rc == 0 && in->intermediates) {
        out->intermediates = calloc(in->intermediates, sizeof *out->intermediates);
        if (!out->intermediates)
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "intermediate models");
        else {
            out->intermediate_count = in->intermediates;
            cl_morph_input mi = {&c, &b, in->positions, in->vertex_count, &t,
                                 in->intermediates, in->base_bound, in->margin};
            rc = cl_morph(&mi, out->intermediates, progress, err);
        }
    }
    if (rc)
        cl_pass_output_release(out);
    free(mark);
    free(normals);
    cl_triangulation_release(&t, c.count);
    cl_borders_release(&b);
    cl_clusters_release(&c);
    sl_segment_loops_release(&loops);
    sl_mesh_adjacency_release(&adj);
    return rc;
}
