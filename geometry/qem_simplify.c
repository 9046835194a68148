/* Quadric edge-collapse simplification: the greedy loop and the output (the method is in
 * qem_simplify.h and docs/simplify.md; set-up in qem_setup.c, the rules of one collapse in
 * qem_collapse.c and qem_apply.c, placement and cost in qem_place.c, the queue in
 * qem_queue.c).
 *
 * The loop pops the cheapest queued edge. Queue keys are estimates from the points' flags
 * (no walk); the full check then prices the collapse exactly, and when that is dearer the
 * edge goes back with the exact price (lazy re-evaluation: what is popped is never worse
 * than its key, so the order stays greedy). A refused collapse marks its points; they are
 * queued again when a neighbouring collapse changes their surroundings. When the queue
 * runs dry above the target and the config allows topology changes, a rule is given up
 * and every edge queued again (qem_relax_further).
 */
#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/qem_internal.h"

#define QEM_PROGRESS_EVERY 4096 /* collapses between progress reports */

/* Queues the edges of p to neighbours of a higher index (each edge once). */
static int push_higher_edges(qem_state *st, uint32_t p)
{
    uint32_t gen = qem_generation(st, 1);
    for (uint32_t c = qem_next_corner(st, p, QEM_NONE); c != QEM_NONE;
         c = qem_next_corner(st, p, c))
        for (int k = 1; k <= 2; k++) {
            uint32_t q = qem_corner_point(st, qem_corner_after(c, k));
            if (q < p || st->point[q].mark == gen)
                continue;
            st->point[q].mark = gen;
            double priority = qem_estimate(st, p, q);
            if (!isfinite(priority))
                continue;
            qem_entry e = qem_make_entry(st, priority, p, q);
            if (qem_queue_push(&st->queue, &e) != 0)
                return -1;
            st->stats.queued++;
        }
    return 0;
}

int qem_relax_further(qem_state *st)
{
    int mode = st->cfg.allow_topology_change;
    if (mode == SL_QEM_TOPOLOGY_KEEP)
        return 0;
    if (!st->relaxed) /* SL_QEM_TOPOLOGY_RELAX_LAST: the last phase begins */
        qem_relax_rules(st);
    else if (!st->needles) /* rather a thin triangle than a missed count */
        st->needles = 1;
    else if (st->slack == 0) /* exact was out of reach: one below */
        st->slack = 1;
    else
        return 0;
    for (uint32_t p = 0; p < st->point_count; p++) {
        st->point[p].flags &= (uint8_t)~QEM_BLOCKED;
        if (!(st->point[p].flags & QEM_DEAD) && push_higher_edges(st, p) != 0)
            return -1;
    }
    return 1;
}

sl_qem_config sl_qem_default_config(void)
{
    sl_qem_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.optimal_placement = 1;
    cfg.border_weight = 10.0;
    cfg.attribute_weight = 0.02;
    return cfg;
}

void sl_qem_mesh_release(sl_qem_mesh *m)
{
    free(m->positions);
    free(m->colors);
    free(m->texcoords);
    free(m->triangles);
    free(m->source);
    memset(m, 0, sizeof *m);
}

static void count_rejection(qem_state *st, int reason)
{
    if (reason == QEM_REJECT_FLIP)
        st->stats.rejected_flip++;
    else if (reason == QEM_REJECT_SHAPE)
        st->stats.rejected_shape++;
    else
        st->stats.rejected_topology++;
}

/* One popped entry: 1 when a collapse was made, 0 when not, -1 out of memory, 2 when the
 * max_error stop is reached. */
static int step(qem_state *st, const qem_entry *e)
{
    if (!qem_entry_valid(e, st->point))
        return 0;
    qem_plan plan;
    qem_plan_collapse(st, e->a, e->b, &plan);
    if (plan.mode == QEM_ILLEGAL) {
        st->point[e->a].flags |= QEM_BLOCKED;
        st->point[e->b].flags |= QEM_BLOCKED;
        count_rejection(st, plan.reason);
        return 0;
    }
    if (qem_key(st, plan.priority) > e->key) { /* the estimate was low: price it right */
        qem_entry again = *e;
        again.key = qem_key(st, plan.priority);
        return qem_queue_push(&st->queue, &again) != 0 ? -1 : 0;
    }
    if (st->cfg.max_error > 0 && plan.error > st->cfg.max_error)
        return 2;
    return qem_apply(st, &plan) != 0 ? -1 : 1;
}

static int run(qem_state *st, sl_progress *progress, sl_error *err)
{
    uint64_t start = st->live_triangles, target = st->cfg.target_triangles;
    uint64_t made = 0, compacted = 0; /* the queue's size after the last compaction */
    st->stats.stop = SL_QEM_STOP_TARGET;
    st->slack = target / 100;
    float *curve = st->cfg.error_curve;
    double worst = 0;
    for (uint64_t c = start; curve && c <= st->triangle_count; c++)
        curve[c] = 0; /* (degenerate triangles dropped: start below the input's count) */
    while (st->live_triangles > target) {
        qem_entry e;
        int rc = qem_queue_pop(&st->queue, st->point, &e);
        if (rc == 0) { /* dry above the target: a rule given up, if the config allows one */
            int further = qem_relax_further(st);
            if (further < 0)
                return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: queue");
            if (further)
                continue;
            st->stats.stop = SL_QEM_STOP_TOPOLOGY;
            break;
        }
        uint64_t before = st->live_triangles;
        if (rc > 0)
            rc = step(st, &e);
        if (rc == 1 && curve) { /* the running maximum at each count passed */
            worst = fmax(worst, st->stats.last_error);
            for (uint64_t c = st->live_triangles; c < before; c++)
                curve[c] = (float)worst;
        }
        if (rc < 0)
            return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: queue");
        if (rc == 2) {
            st->stats.stop = SL_QEM_STOP_MAX_ERROR;
            break;
        }
        if (rc == 1 && ++made % QEM_PROGRESS_EVERY == 0 &&
            sl_progress_step(progress, "simplify",
                             (double)(start - st->live_triangles) / (double)(start - target)))
            return sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "simplify: interrupted");
        if (st->queue.size > 4 * (st->live_triangles + 1024) && st->queue.size > 2 * compacted) {
            qem_queue_compact(&st->queue, st->point); /* mostly stale entries */
            compacted = st->queue.size;
        }
    }
    return 0;
}

/* Output vertex of each wedge that a live triangle uses (input order), or NONE. */
static uint64_t number_wedges(const qem_state *st, uint32_t *out_index)
{
    for (uint32_t w = 0; w < st->vertex_count; w++)
        out_index[w] = QEM_NONE;
    for (uint32_t t = 0; t < st->triangle_count; t++)
        if (!qem_triangle_dead(st, t))
            for (int k = 0; k < 3; k++)
                out_index[st->corner_wedge[3 * t + k]] = 0;
    uint64_t n = 0;
    for (uint32_t w = 0; w < st->vertex_count; w++)
        if (out_index[w] == 0)
            out_index[w] = (uint32_t)n++;
    return n;
}

static void write_vertex(const qem_state *st, uint32_t w, uint32_t i, sl_qem_mesh *out)
{
    uint32_t p = st->wedge_point[w];
    out->source[i] = w;
    for (int k = 0; k < 3; k++)
        out->positions[3 * (uint64_t)i + k] =
            st->point[p].flags & QEM_MOVED
                ? (float)(st->point[p].position[k] + st->origin[k])
                : st->in->positions[3 * (uint64_t)st->point[p].wedge + k]; /* exact */
    const double *a = st->attribute ? st->attribute + (uint64_t)w * st->attribute_count : NULL;
    if (out->colors)
        for (int k = 0; k < 4; k++)
            out->colors[4 * (uint64_t)i + k] = (uint8_t)lrint(fmin(fmax(a[k], 0), 1) * 255);
    if (out->texcoords)
        for (int k = 0; k < 2; k++)
            out->texcoords[2 * (uint64_t)i + k] = (float)a[(out->colors ? 4 : 0) + k];
}

static int build_output(const qem_state *st, sl_qem_mesh *out, sl_error *err)
{
    uint32_t *index = malloc((st->vertex_count ? st->vertex_count : 1) * sizeof *index);
    if (!index)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: output");
    uint64_t nv = number_wedges(st, index), nt = st->live_triangles;
    out->vertex_count = nv;
    out->triangle_count = nt;
    out->positions = malloc((3 * nv + 1) * sizeof *out->positions);
    out->source = malloc((nv + 1) * sizeof *out->source);
    out->triangles = malloc((3 * nt + 1) * sizeof *out->triangles);
    out->colors = st->in->colors ? malloc(4 * nv + 1) : NULL;
    out->texcoords = st->in->texcoords ? malloc((2 * nv + 1) * sizeof *out->texcoords) : NULL;
    if (!out->positions || !out->source || !out->triangles || (st->in->colors && !out->colors) ||
        (st->in->texcoords && !out->texcoords)) {
        free(index);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: output of %llu vertices",
                            (unsigned long long)nv);
    }
    for (uint32_t w = 0; w < st->vertex_count; w++)
        if (index[w] != QEM_NONE)
            write_vertex(st, w, index[w], out);
    uint64_t k = 0;
    for (uint32_t t = 0; t < st->triangle_count; t++)
        if (!qem_triangle_dead(st, t))
            for (int c = 0; c < 3; c++)
                out->triangles[k++] = index[st->corner_wedge[3 * t + c]];
    assert(k == 3 * nt); /* the live count was kept right */
    free(index);
    return 0;
}

int sl_qem_simplify(const sl_qem_mesh *in, const sl_qem_config *cfg, sl_qem_mesh *out,
                    sl_qem_stats *stats, sl_progress *progress, sl_error *err)
{
    memset(out, 0, sizeof *out);
    sl_qem_config defaults = sl_qem_default_config();
    qem_state st;
    int rc = qem_setup(&st, in, cfg ? cfg : &defaults, err);
    if (!rc)
        rc = run(&st, progress, err);
    if (!rc)
        rc = build_output(&st, out, err);
    if (rc)
        sl_qem_mesh_release(out);
    st.stats.output_triangles = out->triangle_count;
    st.stats.output_vertices = out->vertex_count;
    if (stats)
        *stats = st.stats;
    qem_release(&st);
    return rc;
}
