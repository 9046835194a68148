/* Levels of the segment method: a triangle budget or an error bound (segment.h).
 *
 * The paper gives no way to ask for a size: its parameters (delta_b, alpha) change the
 * count only indirectly. With rule error the count falls monotonically (nearly: the
 * retriangulation is greedy) as max_error grows, roughly as 1 / max_error, so a budget is
 * met by a secant search on log(max_error) against log(count), bracketing the budget from
 * both sides, keeping the largest level within it; it stops within 3 % under the budget
 * or after SEARCH_PASSES passes. Every pass starts from the input (not from the previous
 * level), so levels are independent and any budget can be asked in any order.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/segment/segment_internal.h"

#define SEARCH_PASSES 12
#define SEARCH_CLOSE 0.97 /* stop once a level holds this fraction of the budget */
#define ERROR_MIN 1e-7
#define ERROR_MAX 0.5

static void params_for(const sl_segment_model *m, const sl_segment_config *cfg, double error,
                       seg_trim_params *t, seg_patch_params *p)
{
    t->paper = cfg->rule != SL_SEGMENT_RULE_ERROR;
    t->delta_b = cfg->delta_b;
    t->max_error = error * m->diagonal * (getenv("SEG_TRIM") ? atof(getenv("SEG_TRIM")) : 1.0);
    p->rule = cfg->rule;
    p->alpha = cfg->alpha;
    p->max_error = error * m->diagonal;
    p->cos_max_deviation = cos(cfg->max_normal_deviation * (M_PI / 180.0));
}

static int pass_at(sl_segment_model *m, const sl_segment_config *cfg, double error,
                   sl_segment_level *lv, sl_progress *progress, sl_error *err)
{
    seg_trim_params t;
    seg_patch_params p;
    params_for(m, cfg, error, &t, &p);
    int rc = seg_run_pass(m, &t, &p, lv, progress, err);
    lv->stats.max_error = error;
    return rc;
}

/* The input itself, as a level (a budget at or above the input's size). */
static int copy_input(sl_segment_model *m, const sl_segment_config *cfg, sl_segment_level *lv,
                      sl_progress *progress, sl_error *err)
{
    /* a pass with the smallest bound keeps the stats consistent; its triangles are replaced */
    int rc = pass_at(m, cfg, ERROR_MIN, lv, progress, err);
    if (rc)
        return rc;
    uint32_t *t = malloc(3 * (size_t)m->triangle_count * sizeof *t);
    if (!t) {
        sl_segment_level_release(lv);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "segment level");
    }
    memcpy(t, m->triangles, 3 * (size_t)m->triangle_count * sizeof *t);
    free(lv->triangles);
    lv->triangles = t;
    lv->triangle_count = m->triangle_count;
    lv->stats.removed_vertices = lv->stats.removed_boundary = lv->stats.removed_interior = 0;
    return SL_OK;
}

static int search_budget(sl_segment_model *m, const sl_segment_config *cfg, uint64_t budget,
                         sl_segment_level *out, sl_progress *progress, sl_error *err)
{
    double lo = 0, hi = 0, error = cfg->max_error; /* lo: too many triangles, hi: within */
    uint64_t n_lo = 0, n_hi = 0;
    sl_segment_level best;
    memset(&best, 0, sizeof best);
    int have_best = 0, passes = 0, rc = SL_OK;
    sl_segment_level smallest; /* if no level fits: the smallest seen */
    memset(&smallest, 0, sizeof smallest);
    while (passes < SEARCH_PASSES) {
        sl_segment_level lv;
        rc = pass_at(m, cfg, error, &lv, progress, err);
        if (rc)
            break;
        passes++;
        uint64_t n = lv.triangle_count;
        if (n <= budget) {
            if (!have_best || n > best.triangle_count) {
                sl_segment_level_release(&best);
                best = lv;
                have_best = 1;
            } else {
                sl_segment_level_release(&lv);
            }
            if (hi == 0 || error < hi) {
                hi = error;
                n_hi = n;
            }
        } else {
            if (!smallest.triangles || n < smallest.triangle_count) {
                sl_segment_level_release(&smallest);
                smallest = lv;
            } else {
                sl_segment_level_release(&lv);
            }
            if (error > lo) {
                lo = error;
                n_lo = n;
            }
        }
        if (have_best && best.triangle_count >= SEARCH_CLOSE * budget)
            break;
        if (sl_progress_step(progress, "segment", 0.5)) {
            rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "segment method interrupted");
            break;
        }
        double goal = log((1 + SEARCH_CLOSE) / 2 * budget), next;
        if (lo > 0 && hi > 0) { /* secant in log-log between the brackets */
            double x0 = log(lo), x1 = log(hi), y0 = log((double)n_lo), y1 = log((double)(n_hi ? n_hi : 1));
            next = y0 != y1 ? exp(x0 + (goal - y0) * (x1 - x0) / (y1 - y0)) : sqrt(lo * hi);
            if (!(next > lo && next < hi)) /* keep strictly inside the bracket */
                next = sqrt(lo * hi);
        } else if (lo > 0) { /* still too many: count ~ 1 / error, overshoot a little */
            if (lo >= ERROR_MAX)
                break; /* the coarsest level the method reaches */
            next = fmin(ERROR_MAX, lo * pow((double)n_lo / exp(goal), 1.2));
            next = fmax(next, lo * 1.05);
        } else {
            if (hi <= ERROR_MIN)
                break;
            next = fmax(ERROR_MIN, hi * pow((double)(n_hi ? n_hi : 1) / exp(goal), 1.0));
            next = fmin(next, hi / 1.05);
        }
        error = next;
    }
    if (rc) {
        sl_segment_level_release(&best);
        sl_segment_level_release(&smallest);
        return rc;
    }
    if (have_best) {
        sl_segment_level_release(&smallest);
        *out = best;
    } else {
        *out = smallest; /* the budget is below what the method reaches */
    }
    out->stats.search_passes = (uint32_t)passes;
    return SL_OK;
}

/* The model of `m` with its segments merged down to `target` (segment_merge.c). A
 * merged segment that cannot be retriangulated (its union is not a disc with holes, or
 * folds) is split back into the segments it was made of. */
static int merged_model(sl_segment_model *m, uint32_t target, sl_segment_model **out,
                        sl_error *err)
{
    uint32_t *labels, count;
    double angle = getenv("SEG_MERGE_ANGLE") ? atof(getenv("SEG_MERGE_ANGLE")) : 80;
    int rc = seg_merge(m, target, angle, &labels, &count, err);
    uint32_t *keep = rc ? NULL : malloc(((size_t)count + 1) * sizeof *keep);
    if (!rc && !keep) {
        free(labels);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "merging segments");
    }
    if (!rc) {
        uint32_t *copy = malloc((size_t)m->triangle_count * sizeof *copy);
        if (!copy)
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "merging segments");
        else
            memcpy(copy, labels, (size_t)m->triangle_count * sizeof *copy);
        if (!rc)
            rc = seg_model_relabel(m, copy, count, out, err);
    }
    if (rc) {
        free(labels);
        free(keep);
        return rc;
    }
    uint32_t split = 0;
    for (uint32_t k = 0; k < count; k++) {
        int bad = (*out)->unfit[k] == SEG_UNFIT_TOPOLOGY || (*out)->unfit[k] == SEG_UNFIT_FOLD ||
                  (*out)->unfit[k] == SEG_UNFIT_OVERLAP ||
                  (*out)->unfit[k] == SEG_UNFIT_NO_OUTER;
        keep[k] = bad ? SEG_NONE : k;
        split += bad;
    }
    if (!split) {
        free(labels);
        free(keep);
        return SL_OK;
    }
    /* the unfit unions: their triangles go back to their segments of equation 1 */
    uint32_t *map = malloc(((size_t)count + m->seg.segment_count) * sizeof *map);
    if (!map) {
        free(labels);
        free(keep);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "merging segments");
    }
    memset(map, 0xff, ((size_t)count + m->seg.segment_count) * sizeof *map);
    uint32_t next = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        uint32_t key = keep[labels[t]] != SEG_NONE ? labels[t] : count + m->seg.segment[t];
        if (map[key] == SEG_NONE)
            map[key] = next++;
        labels[t] = map[key];
    }
    free(map);
    free(keep);
    sl_segment_model_free(*out);
    *out = NULL;
    return seg_model_relabel(m, labels, next, out, err);
}

int sl_segment_model_level(sl_segment_model *m, const sl_segment_config *cfg,
                           const sl_segment_target *target, sl_segment_level *out,
                           sl_progress *progress, sl_error *err)
{
    memset(out, 0, sizeof *out);
    int rc = sl_segment_check_config(cfg, err);
    if (rc)
        return rc;
    uint64_t budget = target->triangles;
    if (!budget && target->ratio > 0)
        budget = (uint64_t)floor(target->ratio * m->triangle_count);
    if (budget || target->ratio > 0) {
        if (budget < 1)
            budget = 1;
        if (cfg->rule != SL_SEGMENT_RULE_ERROR)
            return sl_error_set(err, SL_E_USAGE, 0, NULL,
                                "a triangle budget needs the error rule (rules near and paper "
                                "take no size: give their alpha instead)");
        if (budget >= m->triangle_count)
            return copy_input(m, cfg, out, progress, err);
        double ratio = getenv("SEG_MERGE_RATIO") ? atof(getenv("SEG_MERGE_RATIO")) : 12;
        uint32_t target_segments = (uint32_t)fmax(1, budget / ratio);
        if (ratio <= 0 || m->seg.segment_count <= target_segments)
            return search_budget(m, cfg, budget, out, progress, err);
        sl_segment_model *merged = NULL;
        rc = merged_model(m, target_segments, &merged, err);
        if (!rc)
            rc = search_budget(merged, cfg, budget, out, progress, err);
        sl_segment_model_free(merged);
        return rc;
    }
    double error = target->max_error > 0 ? target->max_error : cfg->max_error;
    if (!(error > 0 && error <= 1))
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "max_error %g is outside (0, 1] (a fraction of the diagonal)", error);
    rc = pass_at(m, cfg, error, out, progress, err);
    out->stats.search_passes = 1;
    return rc;
}

int sl_segment_simplify(const sl_segment_config *cfg, const sl_segment_input *in,
                        const sl_segment_target *target, sl_segment_level *level,
                        sl_progress *progress, sl_error *err)
{
    memset(level, 0, sizeof *level);
    sl_segment_model *m = NULL;
    int rc = sl_segment_model_build(cfg, in, &m, progress, err);
    if (!rc)
        rc = sl_segment_model_level(m, cfg, target, level, progress, err);
    sl_segment_model_free(m);
    return rc;
}
