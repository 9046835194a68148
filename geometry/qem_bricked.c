/* Quadric edge collapse by bricks: the passes (qem_simplify.h; docs/simplify.md "By
 * bricks"; the pieces in qem_bricks_internal.h).
 *
 * Why: the simplifier holds about 180 bytes per input triangle and runs one greedy queue on
 * one thread; the refine stage's first collapse takes the whole scan (20 M triangles: 4 GB).
 * Here the mesh is cut into bricks of at most `brick_triangles` triangles, consecutive in
 * the Morton order of their centroids; each brick is simplified alone with the points it
 * shares with another brick (and the ring around them) locked, so the bricks stitch back
 * without a crack whatever each did, and the bricks run in parallel. Their counts follow
 * one error, as one greedy queue over the whole would: a sample of the bricks records
 * its error curves, and every brick stops at the error that brings the sample to the
 * count. The locked borders stay
 * at full density; the next passes take them down on strips around them, cut into bricks
 * elsewhere; once the mesh fits one brick the last pass is the whole simplifier.
 *
 * Determinism: bricks, the sample, the error and the stitching depend on the mesh alone;
 * each brick's simplifier is deterministic; results are joined in brick order. The output
 * bytes do not depend on the thread count. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/qem_bricks_internal.h"
#include "geometry/qem_internal.h"

#define BRICK_FIRST_DEPTH 4   /* in the first pass a brick's first run goes to this
                                 fraction of its share of the pass's count, and no further
                                 than twice its share's collapses: how far below its share
                                 the sharing by error may put it. Later passes (what the
                                 borders kept) run to the share: one run, not two */

#define BRICK_MAX_PASSES 24   /* a pass that cannot reach its target leaves the rest to
                                 the next; this many and the count is out of reach */
#define BRICK_SAMPLE 4        /* the first pass prices every this-many-th brick (a curve
                                 run) and stops the others at the error the sample gives */
#define BRICK_SAMPLE_MARGIN 200 /* ... aiming 1/this of the triangles above the count, for
                                   the strips to take (the sample misjudges by less) */

/* Adds a brick's or a pass's figures to the total. */
static void add_stats(sl_qem_stats *sum, const sl_qem_stats *s)
{
    sum->degenerate_triangles += s->degenerate_triangles;
    sum->points += s->points;
    sum->seam_points += s->seam_points;
    sum->border_points += s->border_points;
    sum->locked_points += s->locked_points;
    sum->nonmanifold_points += s->nonmanifold_points;
    sum->collapses += s->collapses;
    sum->relaxed_collapses += s->relaxed_collapses;
    sum->cancelled_triangles += s->cancelled_triangles;
    sum->queued += s->queued;
    sum->rejected_topology += s->rejected_topology;
    sum->rejected_flip += s->rejected_flip;
    sum->rejected_shape += s->rejected_shape;
    sum->last_error = fmax(sum->last_error, s->last_error);
    if (s->stop == SL_QEM_STOP_MAX_ERROR || sum->stop == SL_QEM_STOP_MAX_ERROR)
        sum->stop = SL_QEM_STOP_MAX_ERROR;
    else if (s->stop == SL_QEM_STOP_TOPOLOGY)
        sum->stop = SL_QEM_STOP_TOPOLOGY;
}

/* One pass over the `active` triangles (NULL: all; the others are kept as they are): cut
 * into bricks; in the first pass (`deep`) each brick run once as deep as BRICK_FIRST_DEPTH
 * asks, recording its error curve, the counts shared out by error, and each run again to
 * its count (unless the first stopped there); in a later one each run once to its share;
 * the bricks joined. *border (when given): per vertex of `out`, 1 on a border between two
 * bricks, malloc'd. */
static int brick_pass(const sl_qem_mesh *m, const uint8_t *active, const sl_qem_config *cfg,
                      uint64_t brick_triangles, double shift, int deep, int exact,
                      uint64_t target,
                      sl_qem_mesh *out, uint8_t **border_out, sl_qem_stats *stats,
                      sl_progress *progress, sl_error *err)
{
    brick_cut cut;
    if (qem_cut_bricks(m, active, brick_triangles, shift, &cut) != 0)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: cutting %llu triangles into "
                            "bricks", (unsigned long long)m->triangle_count);
    uint64_t border = 0, n = cut.count ? cut.first[cut.count] : 0;
    uint64_t alone = m->triangle_count - n; /* left as they are */
    uint8_t *locked = qem_brick_locks(m, &cut, active, cfg->locked, &border);
    brick_result *r = calloc(cut.count + 1, sizeof *r);
    if (!locked || !r) {
        free(locked);
        free(r);
        qem_brick_cut_release(&cut);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: brick borders");
    }
    /* The bricks' part of the target; the locked borders keep their triangles this pass,
     * so the count it aims at leaves them what the target would have taken of them, for
     * the next pass (elsewhere) to take. */
    uint64_t part = target > alone ? target - alone : 0;
    double kept = n ? 1 - (double)part / (double)n : 0;
    uint64_t aim = part + (uint64_t)((double)border * kept);
    aim = aim < n ? aim : n;
    for (uint64_t b = 0; b < cut.count; b++) { /* the rounding of the running sum, so the
                                                   shares add up */
        r[b].triangles = cut.first[b + 1] - cut.first[b];
        r[b].share = (uint64_t)((double)aim * (double)cut.first[b + 1] / (double)n + 0.5) -
                     (uint64_t)((double)aim * (double)cut.first[b] / (double)n + 0.5);
    }
    /* How far a curve run goes: BRICK_FIRST_DEPTH below its share, no more than twice its
     * share's collapses. */
    uint64_t stride = exact ? 1 : BRICK_SAMPLE;
    deep = deep && aim < n; /* (nothing to take: each brick copied) */
    for (uint64_t b = 0; b < cut.count; b++) {
        uint64_t nb = r[b].triangles, share = r[b].share, floor = share / BRICK_FIRST_DEPTH;
        if (nb > 2 * (nb - share) && nb - 2 * (nb - share) > floor)
            floor = nb - 2 * (nb - share);
        r[b].task = !deep ? TASK_FINAL : b % stride == 0 ? TASK_CURVE : TASK_NONE;
        r[b].want = deep ? floor : share;
    }
    int rc = qem_run_bricks(m, &cut, locked, cfg, r, 0, progress, err);
    if (rc == 0 && deep) {
        if (exact) { /* every brick's curve: the counts exactly */
            qem_share_by_error(r, cut.count, aim);
        } else { /* the sample's error for all; a little above the aim, for the strips */
            double e = qem_sampled_error(r, cut.count, stride, aim + n / BRICK_SAMPLE_MARGIN);
            for (uint64_t b = 0; b < cut.count; b++) {
                if (b % stride == 0) {
                    r[b].want = qem_count_within(&r[b], e);
                } else {
                    r[b].max_error = e > 0 ? e : DBL_MIN; /* 0 would be no limit */
                }
            }
        }
        for (uint64_t b = 0; b < cut.count; b++) {
            r[b].task = r[b].curve && r[b].want == r[b].reached ? TASK_NONE : TASK_FINAL;
            free(r[b].curve); /* (its mesh is the count's when the task is none) */
            r[b].curve = NULL;
        }
        rc = qem_run_bricks(m, &cut, locked, cfg, r, 1, progress, err);
    }
    for (uint64_t b = 0; b < cut.count && rc == 0; b++)
        add_stats(stats, &r[b].stats);
    if (rc == 0)
        rc = qem_stitch_bricks(m, active, r, cut.count, out, err);
    if (rc == 0 && border_out) {
        *border_out = malloc(out->vertex_count + 1);
        if (!*border_out) {
            sl_qem_mesh_release(out);
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: brick borders");
        }
        for (uint64_t v = 0; rc == 0 && v < out->vertex_count; v++)
            (*border_out)[v] = (locked[out->source[v]] & (LOCK_BORDER | LOCK_RING)) != 0;
    }
    free(locked);
    for (uint64_t b = 0; b < cut.count; b++) {
        free(r[b].curve);
        sl_qem_mesh_release(&r[b].mesh);
    }
    free(r);
    qem_brick_cut_release(&cut);
    return rc;
}

/* `source` of `next` made to name the original input's vertices through `prev`'s. */
static void compose_source(sl_qem_mesh *next, const uint32_t *prev_source)
{
    if (prev_source)
        for (uint64_t v = 0; v < next->vertex_count; v++)
            next->source[v] = prev_source[next->source[v]];
}

/* The caller's locks carried to a pass's mesh (its `source` names the input's vertices):
 * *out NULL when there are none. -1 when out of memory. */
static int carry_locks(const uint8_t *locked, const sl_qem_mesh *cur, uint8_t **out)
{
    *out = NULL;
    if (!locked || !cur->source)
        return 0;
    *out = malloc(cur->vertex_count + 1);
    if (!*out)
        return -1;
    for (uint64_t v = 0; v < cur->vertex_count; v++)
        (*out)[v] = locked[cur->source[v]];
    return 0;
}

int sl_qem_simplify_bricked(const sl_qem_mesh *in, const sl_qem_config *cfg,
                            uint64_t brick_triangles, sl_qem_mesh *out, sl_qem_stats *stats,
                            sl_progress *progress, sl_error *err)
{
    sl_qem_config defaults = sl_qem_default_config();
    if (!cfg)
        cfg = &defaults;
    if (brick_triangles == 0 || in->triangle_count <= brick_triangles)
        return sl_qem_simplify(in, cfg, out, stats, progress, err);
    memset(out, 0, sizeof *out);
    sl_qem_stats sum;
    memset(&sum, 0, sizeof sum);
    sum.input_triangles = in->triangle_count;
    int rc = qem_check_input(in, cfg, err);
    sl_qem_config c = *cfg;
    if (rc == 0 && c.diagonal == 0) { /* the whole's, so every brick prices alike */
        double lo[3], hi[3];
        qem_mesh_box(in, lo, hi);
        for (int a = 0; a < 3; a++)
            c.diagonal += (hi[a] - lo[a]) * (hi[a] - lo[a]);
        c.diagonal = sqrt(c.diagonal);
    }
    uint64_t target = cfg->target_triangles;
    sl_qem_mesh cur = *in; /* borrowed until the first pass */
    cur.source = NULL;
    uint8_t *border = NULL; /* per vertex of cur: on the last pass's brick borders */
    int owned = 0, max_error = 0, whole = 0, full = 1;
    uint64_t brick = brick_triangles; /* doubled when a pass could take nothing (below) */
    for (int pass = 0; rc == 0; pass++) {
        int last = owned && cur.triangle_count <= brick;
        if (owned && (cur.triangle_count <= target || whole || pass == BRICK_MAX_PASSES))
            break;
        uint8_t *locks = NULL, *active = NULL;
        uint64_t strip = 0;
        if (carry_locks(cfg->locked, &cur, &locks) != 0 ||
            (!last && !full &&
             !(active = qem_brick_strip(&cur, border, cur.triangle_count - target, &strip)))) {
            free(locks);
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "simplify: locks");
            break;
        }
        c.locked = owned ? locks : cfg->locked;
        sl_qem_mesh next;
        sl_qem_stats s;
        memset(&s, 0, sizeof s);
        uint8_t *next_border = NULL;
        if (last) { /* the mesh fits one brick: the whole, nothing but the caller's locked */
            c.target_triangles = target;
            rc = sl_qem_simplify(&cur, &c, &next, &s, progress, err);
            whole = 1;
        } else { /* (a first pass at or below the target only copies, as the whole would) */
            /* the golden-ratio sequence: each pass's grid off the earlier ones' */
            double shift = fmod(pass * 0.6180339887498949, 1.0);
            /* after the first pass, aim up to half the 1 % the count allows below it: the
             * borders' last triangles sit beside locked ones, and an exact aim takes them
             * a few at a time, pass after pass */
            uint64_t aim = pass == 0 ? target : target - target / 200;
            rc = brick_pass(&cur, active, &c, brick, shift, pass == 0, 0, aim, &next,
                            &next_border, &s, progress, err);
            if (rc == 0 && pass == 0 && next.triangle_count < target - target / 100) {
                /* the sample misjudged the error below the count: every brick priced */
                sl_qem_mesh_release(&next);
                free(next_border);
                next_border = NULL;
                memset(&s, 0, sizeof s);
                rc = brick_pass(&cur, active, &c, brick, shift, 1, 1, target, &next,
                                &next_border, &s, progress, err);
            }
        }
        free(locks);
        free(active);
        if (rc)
            break;
        add_stats(&sum, &s);
        max_error |= cfg->max_error > 0 && s.stop == SL_QEM_STOP_MAX_ERROR; /* the caller's */
        /* The next pass on strips around these borders, unless this one (on strips) took
         * less than half of what was left to take: then on all of it; and when a pass on
         * all of it took nothing (bricks so small that their locked borders and rings are
         * most of them), on bricks twice as large, up to the whole. */
        uint64_t excess = cur.triangle_count > target ? cur.triangle_count - target : 0;
        uint64_t taken = cur.triangle_count - next.triangle_count;
        if (full && pass > 0 && 2 * taken < excess)
            brick = brick > UINT64_MAX / 2 ? UINT64_MAX : 2 * brick;
        full = !full && 2 * taken < excess;
        compose_source(&next, cur.source);
        if (owned)
            sl_qem_mesh_release(&cur);
        free(border);
        border = next_border;
        cur = next;
        owned = 1;
    }
    free(border);
    if (rc == 0) {
        *out = cur;
        sum.stop = cur.triangle_count <= target ? SL_QEM_STOP_TARGET
                   : max_error                  ? SL_QEM_STOP_MAX_ERROR
                                                : SL_QEM_STOP_TOPOLOGY;
        sum.output_triangles = out->triangle_count;
        sum.output_vertices = out->vertex_count;
    } else if (owned) {
        sl_qem_mesh_release(&cur);
    }
    if (stats)
        *stats = sum;
    return rc;
}
