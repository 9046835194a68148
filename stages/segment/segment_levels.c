/* Levels of the segment method: a triangle budget or an error bound (segment.h).
 *
 * The paper gives no way to ask for a size: its parameters (delta_b, alpha) change the
 * count only indirectly. With rule error a pass records, for every segment, the scores at
 * which its greedy insertion puts vertices back; since a run to a threshold tau stops at
 * the first score at or below it, those records give the level's exact triangle count for
 * any tau, and the pass replays the insertion to the tau that fits the budget best
 * (segment_pass.c). What the records cannot foresee is the boundary: trimming uses
 * max_error, which should match the interior's sqrt(tau) (a removed boundary vertex and
 * a removed interior vertex then cost alike), so the pass is repeated with the tau found
 * until the two agree within 25 % (two or three passes). Every pass starts from the
 * input, so levels are independent and can be asked in any order.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/mesh_distance.h"
#include "stages/segment/segment_internal.h"

#define LADDER_STEPS 6 /* trimming bounds tried: the first that fits x 2^(k/2) */
#define ERROR_MIN 1e-7
#define RECORD_BELOW 16.0 /* a pass records insertions down to max_error / this */

/* Parameters for a pass at max_error `error` (world units). */
static void params_for(const sl_segment_config *cfg, double error, seg_trim_params *t,
                       seg_patch_params *p)
{
    t->paper = cfg->rule != SL_SEGMENT_RULE_ERROR;
    t->delta_b = cfg->delta_b;
    t->max_error = error;
    p->rule = cfg->rule;
    p->alpha = cfg->alpha;
    p->max_error = error;
    p->tau = error * error;
    p->record = 0;
    p->probe = 0;
    p->cos_max_deviation = cos(cfg->max_normal_deviation * (M_PI / 180.0));
}

/* One pass at max_error `error` (world units), no budget. */
static int pass_at(sl_segment_model *m, const sl_segment_config *cfg, double error,
                   sl_segment_level *lv, sl_progress *progress, sl_error *err)
{
    seg_trim_params t;
    seg_patch_params p;
    params_for(cfg, error, &t, &p);
    int rc = seg_run_pass(m, &t, &p, 0, lv, progress, err);
    lv->stats.max_error = error / m->diagonal;
    return rc;
}

/* The input itself, as a level (a budget at or above the input's size). */
static int copy_input(sl_segment_model *m, const sl_segment_config *cfg, sl_segment_level *lv,
                      sl_progress *progress, sl_error *err)
{
    /* a pass with the smallest bound keeps the stats consistent; its triangles are replaced */
    int rc = pass_at(m, cfg, ERROR_MIN * m->diagonal, lv, progress, err);
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

/* The symmetric RMS distance between the input and the level, as a fraction of the
 * diagonal, by the project's own fidelity measure (geometry/mesh_distance.h) with fewer
 * samples and another seed than the benchmark's. The input's side (its tree and samples)
 * is made once per search into *ref and reused by every candidate. */
static double level_rms(const sl_segment_model *m, const sl_segment_level *lv, uint64_t samples,
                        sl_distance_reference **ref, sl_error *err, int *rc)
{
    sl_mesh b;
    sl_mesh_init(&b);
    b.vertex_count = m->vertex_count;
    b.positions = (float *)m->positions;
    b.triangle_count = lv->triangle_count;
    b.triangles = lv->triangles;
    if (!*ref) {
        sl_mesh a;
        sl_mesh_init(&a);
        a.vertex_count = m->vertex_count;
        a.positions = (float *)m->positions;
        a.triangle_count = m->triangle_count;
        a.triangles = (uint32_t *)m->triangles;
        sl_mesh_distance_config dc = sl_mesh_distance_default_config();
        dc.samples = samples;
        dc.seed = 7;
        *rc = sl_distance_reference_build(&a, &dc, ref, err);
        if (*rc)
            return INFINITY;
    }
    double rms;
    *rc = sl_distance_reference_rms(*ref, &b, &rms, NULL, err);
    return *rc ? INFINITY : rms;
}

/* One pass for a budget with boundary trimming bound `chain` (world): its level and the
 * estimate to minimise (infinite when it does not fit). */
static double budget_pass(sl_segment_model *m, const sl_segment_config *cfg, double chain,
                          uint64_t budget, int probe, sl_segment_level *lv,
                          sl_distance_reference **ref, sl_progress *progress, sl_error *err,
                          int *rc)
{
    seg_trim_params t;
    seg_patch_params p;
    params_for(cfg, chain, &t, &p);
    p.tau = (chain / RECORD_BELOW) * (chain / RECORD_BELOW);
    p.probe = probe;
    *rc = seg_run_pass(m, &t, &p, budget, lv, progress, err);
    if (*rc)
        return INFINITY;
    lv->stats.max_error = (lv->stats.tau > 0 && isfinite(lv->stats.tau) ? sqrt(lv->stats.tau) : 0) /
                          m->diagonal;
    int fits = !lv->stats.over_budget && lv->triangle_count <= budget;
    if (fits && cfg->search_samples) { /* the objective: the fidelity the project reports */
        double rms = level_rms(m, lv, cfg->search_samples, ref, err, rc);
        if (*rc)
            return INFINITY;
        lv->stats.estimate = rms;
    }
    return fits ? lv->stats.estimate : INFINITY;
}

/* A budget: the trimming bound with the smallest RMS (each pass picks the interior's
 * threshold that fits the budget): from the smallest bound whose boundaries fit, up by
 * factors of sqrt(2) while the RMS improves. */
static int search_budget(sl_segment_model *m, const sl_segment_config *cfg, uint64_t budget,
                         sl_segment_level *out, sl_distance_reference **ref,
                         sl_progress *progress, sl_error *err)
{
    double guess = m->diagonal / (8.0 * sqrt((double)budget));
    sl_segment_level best;
    memset(&best, 0, sizeof best);
    double best_f = INFINITY;
    int rc = SL_OK, passes = 0;
    /* first a bound whose boundaries fit the budget: doubled until they do (probing: a
     * pass over the budget stops as soon as its bases are; the last one, when none fits,
     * is run again in full as the answer) */
    double last = guess;
    for (; passes < 8 && !rc; passes++) {
        sl_segment_level lv;
        last = guess;
        double f = budget_pass(m, cfg, guess, budget, 1, &lv, ref, progress, err, &rc);
        if (rc)
            break;
        sl_segment_level_release(&best);
        best = lv;
        best_f = f;
        if (isfinite(f) || guess >= m->diagonal)
            break;
        guess *= 2;
    }
    if (!rc && !isfinite(best_f)) {
        sl_segment_level_release(&best);
        budget_pass(m, cfg, last, budget, 0, &best, ref, progress, err, &rc);
        guess = last;
    }
    /* then a ladder by factors of sqrt(2), up while the RMS improves, and, when the first
     * step up was no better, down while it improves and the boundaries still fit */
    double at = guess, step = sqrt(2.0);
    for (int dir = 0; dir < 2 && !rc && isfinite(best_f); dir++) {
        double factor = dir ? 1 / step : step, x = at;
        for (int k = 0; k < LADDER_STEPS && !rc; k++, passes++) {
            x *= factor;
            sl_segment_level lv;
            double f = budget_pass(m, cfg, x, budget, 1, &lv, ref, progress, err, &rc);
            if (rc)
                break;
            int better = f < best_f;
            if (better) {
                sl_segment_level_release(&best);
                best = lv;
                best_f = f;
                at = x;
            } else {
                sl_segment_level_release(&lv);
            }
            if (sl_progress_step(progress, "segment", 0.5))
                rc = sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "segment method interrupted");
            if (!better)
                break;
        }
        if (dir == 0 && at != guess)
            break; /* going up helped: the minimum is not below */
    }
    if (rc) {
        sl_segment_level_release(&best);
        return rc;
    }
    *out = best;
    out->stats.search_passes = (uint32_t)passes;
    return SL_OK;
}

/* Is merged segment k one the retriangulation cannot take (not a disc with holes, or
 * not one-to-one in its plane)? */
static int unfit_union(const sl_segment_model *m, uint32_t k)
{
    return m->unfit[k] == SEG_UNFIT_TOPOLOGY || m->unfit[k] == SEG_UNFIT_FOLD ||
           m->unfit[k] == SEG_UNFIT_OVERLAP || m->unfit[k] == SEG_UNFIT_NO_OUTER;
}

/* Triangle labels from one label per base segment (first-appearance order). */
static uint32_t *labels_of(const sl_segment_model *m, const uint32_t *group, uint32_t *count)
{
    uint32_t ns = m->seg.segment_count, top = 0;
    for (uint32_t k = 0; k < ns; k++)
        top = group[k] > top ? group[k] : top;
    uint32_t *map = malloc(((size_t)top + 1) * sizeof *map);
    uint32_t *labels = malloc((size_t)(m->triangle_count ? m->triangle_count : 1) * sizeof *labels);
    if (!map || !labels) {
        free(map);
        free(labels);
        return NULL;
    }
    memset(map, 0xff, ((size_t)top + 1) * sizeof *map);
    uint32_t next = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        uint32_t g = group[m->seg.segment[t]];
        if (map[g] == SEG_NONE)
            map[g] = next++;
        labels[t] = map[g];
    }
    free(map);
    *count = next;
    return labels;
}

/* The model of `m` with its segments merged down to `target` (segment_merge.c). A union
 * the retriangulation cannot take (its loops overlap in its plane, it is not a disc with
 * holes) is merged again from its pieces with a smaller angle (20 degrees less, twice),
 * the unions that work staying as they are; what still fails keeps its pieces. */
static int merged_model(sl_segment_model *m, const sl_segment_config *cfg, uint32_t target,
                        sl_segment_model **out, sl_error *err)
{
    *out = NULL;
    uint32_t ns = m->seg.segment_count;
    uint32_t *group = malloc(((size_t)ns + 1) * sizeof *group); /* base segment -> union */
    uint8_t *allowed = malloc(ns ? ns : 1);
    if (!group || !allowed) {
        free(group);
        free(allowed);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "merging segments");
    }
    for (uint32_t k = 0; k < ns; k++) {
        group[k] = k; /* unmerged: its own */
        allowed[k] = 1;
    }
    uint32_t next_group = ns; /* union ids above the base ids */
    int rc = SL_OK;
    for (int round = 0; round < 3 && !rc; round++) {
        double angle = cfg->merge_angle - 20.0 * round;
        uint64_t free_triangles = 0;
        for (uint32_t k = 0; k < ns; k++)
            if (allowed[k])
                free_triangles += m->seg_tri_start[k + 1] - m->seg_tri_start[k];
        if (angle < 10 || !free_triangles)
            break;
        uint32_t part = (uint32_t)fmax(1, (double)target * (double)free_triangles / m->triangle_count);
        uint32_t *lab, count;
        rc = seg_merge(m, part, angle, allowed, &lab, &count, err);
        if (rc)
            break;
        uint32_t *trial = malloc(((size_t)ns + 1) * sizeof *trial);
        if (!trial) {
            free(lab);
            rc = sl_error_set(err, SL_E_NOMEM, 0, NULL, "merging segments");
            break;
        }
        for (uint32_t k = 0; k < ns; k++) /* a union takes whole base segments */
            trial[k] = allowed[k] ? next_group + lab[m->seg_tris[m->seg_tri_start[k]]] : group[k];
        free(lab);
        uint32_t n;
        uint32_t *labels = labels_of(m, trial, &n);
        sl_segment_model *mm = NULL;
        rc = labels ? seg_model_relabel(m, labels, n, &mm, err)
                    : sl_error_set(err, SL_E_NOMEM, 0, NULL, "merging segments");
        if (rc) {
            free(trial);
            break;
        }
        int failed = 0;
        for (uint32_t k = 0; k < ns; k++) {
            if (!allowed[k])
                continue;
            uint32_t merged = mm->seg.segment[m->seg_tris[m->seg_tri_start[k]]];
            if (unfit_union(mm, merged)) {
                failed = 1; /* stays allowed: merged again next round */
            } else {
                group[k] = trial[k];
                allowed[k] = 0;
            }
        }
        next_group += count;
        free(trial);
        if (!failed) {
            *out = mm;
            break;
        }
        sl_segment_model_free(mm);
    }
    if (!rc && !*out) { /* what still fails keeps its own pieces */
        uint32_t n;
        uint32_t *labels = labels_of(m, group, &n);
        rc = labels ? seg_model_relabel(m, labels, n, out, err)
                    : sl_error_set(err, SL_E_NOMEM, 0, NULL, "merging segments");
    }
    free(group);
    free(allowed);
    return rc;
}

/* Is level a better answer to the budget than level b (which may be empty)? One within
 * the budget beats one over it; then the lower RMS; over budget, the fewer triangles. */
static int better(const sl_segment_level *a, const sl_segment_level *b, uint64_t budget)
{
    if (!b->triangles)
        return 1;
    int fa = !a->stats.over_budget && a->triangle_count <= budget;
    int fb = !b->stats.over_budget && b->triangle_count <= budget;
    if (fa != fb)
        return fa;
    return fa ? a->stats.estimate < b->stats.estimate : a->triangle_count < b->triangle_count;
}

/* A budget: with the segments of equation 1 when their corners take at most a tenth of
 * the budget; else merged down to budget / merge_ratio and, searching, to half that
 * (the lower RMS wins); when even that is over the budget, merged harder (a quarter and
 * an eighth, with a merge angle of 80 degrees) until one fits. */
static int merged_levels(sl_segment_model *m, const sl_segment_config *cfg, uint64_t budget,
                         sl_segment_level *out, sl_distance_reference **ref,
                         sl_progress *progress, sl_error *err)
{
    uint64_t fixed = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++)
        fixed += m->fixed[v] && m->loops.vertex_kind[v] != SL_SEGMENT_VERTEX_UNUSED;
    double ratio = cfg->merge_ratio;
    if (ratio <= 0 || m->seg.segment_count <= fmax(1, budget / fmax(ratio, 1)) ||
        10 * fixed <= budget)
        return search_budget(m, cfg, budget, out, ref, progress, err);
    const double scale[4] = {1, 2, 4, 8};
    sl_segment_level best;
    memset(&best, 0, sizeof best);
    int rc = SL_OK;
    for (int i = 0; i < 4 && !rc; i++) {
        int fits = best.triangles && !best.stats.over_budget && best.triangle_count <= budget;
        if (fits && (i >= 2 || !cfg->search_samples))
            break; /* harder merging only while nothing fits; the second try only searching */
        sl_segment_config c = *cfg;
        if (i >= 2)
            c.merge_angle = fmax(c.merge_angle, 80);
        uint32_t target = (uint32_t)fmax(1, budget / (ratio * scale[i]));
        if (target >= m->seg.segment_count)
            continue;
        sl_segment_model *merged = NULL;
        sl_segment_level lv;
        memset(&lv, 0, sizeof lv);
        rc = merged_model(m, &c, target, &merged, err);
        if (!rc)
            rc = search_budget(merged, &c, budget, &lv, ref, progress, err);
        sl_segment_model_free(merged);
        if (!rc && better(&lv, &best, budget)) {
            sl_segment_level_release(&best);
            best = lv;
        } else {
            sl_segment_level_release(&lv);
        }
    }
    if (rc) {
        sl_segment_level_release(&best);
        return rc;
    }
    *out = best;
    return SL_OK;
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
        sl_distance_reference *ref = NULL; /* the input's side of the search's RMS */
        rc = merged_levels(m, cfg, budget, out, &ref, progress, err);
        sl_distance_reference_free(ref);
        return rc;
    }
    double error = target->max_error > 0 ? target->max_error : cfg->max_error;
    if (!(error > 0 && error <= 1))
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "max_error %g is outside (0, 1] (a fraction of the diagonal)", error);
    rc = pass_at(m, cfg, error * m->diagonal, out, progress, err);
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
