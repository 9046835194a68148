/* The segment stage's config ([segment] and the ladder; segment.h): its options, declared
 * once, the resolved section, its defaults and their check. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/segment/segment_internal.h"

/* The error bound of a level asked by max_error alone (the stage asks by count). */
#define SEGMENT_MAX_ERROR 0.001

const sl_option sl_segment_options[] = {
    {"segment", "delta_seg", SL_OPT_DOUBLE, "20", 0.01, 89, NULL,
     "Equation 1 (paper 3): the largest angle in degrees between two triangles of a "
     "segment."},
    {"segment", "target_segments", SL_OPT_INT, "0", 0, 4294967295.0, NULL,
     "Min-delta instead: the smallest delta_seg giving at most this many segments "
     "(0: Min-# with delta_seg)."},
    {"segment", "delta_b", SL_OPT_DOUBLE, "180", 0, 180, NULL,
     "Equation 2: a boundary vertex on exactly two segments may go when its angle is "
     "within delta_b degrees of straight (180: no angle test, the error bound alone "
     "decides; the paper uses 20 and 60)."},
    {"segment", "rule", SL_OPT_ENUM, "error", 0, 0, "error|near|paper",
     "Which interior vertices go (section 3.3, equation 8): error = greedy insertion, "
     "the vertices far from the rebuilt patch stay (levels of any size); near = those "
     "near the fitted plane go; paper = equation 8 as printed (far ones go). near and "
     "paper take no size: every level is the same single pass."},
    {"segment", "alpha", SL_OPT_DOUBLE, "-1.5", -1e6, 1e6, NULL,
     "Equation 8's control parameter (rules near and paper)."},
    {"segment", "max_normal_deviation", SL_OPT_DOUBLE, "90", 1, 180, NULL,
     "A new triangle whose normal is farther than this many degrees from the input's "
     "normals at its corners gets a vertex back, or its segment is kept as it was."},
    {"segment", "merge_ratio", SL_OPT_DOUBLE, "25", 0, 1e9, NULL,
     "Levels with a budget merge segments down to budget / merge_ratio (so that their "
     "corners fit); 0 = never merge."},
    {"segment", "merge_angle", SL_OPT_DOUBLE, "60", 1, 89, NULL,
     "Merging keeps every triangle of a segment within this many degrees of its mean "
     "normal (so that it still projects onto its plane one-to-one), and merges two parts "
     "only when their mean normals are that close (a crease sharper than this stays)."},
    {"segment", "search_samples", SL_OPT_INT, "50000", 0, 100000000, NULL,
     "Area samples per surface of the RMS distance the budget search minimises; 0 = "
     "estimate it from the removed vertices (faster, less faithful)."},
    SL_OPTION_END,
};

int sl_segment_configure(const sl_config *cfg, void **out, sl_error *err)
{
    sl_segment_stage_config *c = calloc(1, sizeof *c);
    if (!c)
        return sl_error_nomem(err, NULL, "out of memory");
    c->seg.delta_seg = sl_config_double(cfg, "segment", "delta_seg");
    c->seg.target_segments = (uint32_t)sl_config_int(cfg, "segment", "target_segments");
    c->seg.delta_b = sl_config_double(cfg, "segment", "delta_b");
    const char *rule = sl_config_string(cfg, "segment", "rule");
    c->seg.rule = !strcmp(rule, "near") ? SL_SEGMENT_RULE_NEAR
                  : !strcmp(rule, "paper") ? SL_SEGMENT_RULE_PAPER : SL_SEGMENT_RULE_ERROR;
    c->seg.alpha = sl_config_double(cfg, "segment", "alpha");
    c->seg.max_error = SEGMENT_MAX_ERROR;
    c->seg.max_normal_deviation = sl_config_double(cfg, "segment", "max_normal_deviation");
    c->seg.merge_ratio = sl_config_double(cfg, "segment", "merge_ratio");
    c->seg.merge_angle = sl_config_double(cfg, "segment", "merge_angle");
    c->seg.search_samples = (uint64_t)sl_config_int(cfg, "segment", "search_samples");
    int rc = sl_ladder_read(cfg, &c->ladder, err);
    sl_error check;
    sl_error_init(&check);
    if (rc == 0 && sl_segment_check_config(&c->seg, &check))
        rc = sl_error_set(err, SL_E_CONFIG, 0, "[segment]", "%s", check.message);
    if (rc) {
        free(c);
        return rc;
    }
    *out = c;
    return SL_OK;
}

sl_segment_config sl_segment_default_config(void)
{
    sl_segment_config c; /* the stage config's first member */
    sl_stage_default_config(&sl_segment_stage, &c, sizeof c);
    return c;
}

int sl_segment_check_config(const sl_segment_config *c, sl_error *err)
{
    if (!c->target_segments && !(c->delta_seg > 0 && c->delta_seg <= SL_REGION_GROW_MAX_DELTA))
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "delta_seg %g is outside (0, %g] degrees",
                            c->delta_seg, SL_REGION_GROW_MAX_DELTA);
    if (!(c->delta_b >= 0 && c->delta_b <= 180))
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "delta_b %g is outside [0, 180] degrees",
                            c->delta_b);
    if (c->rule < SL_SEGMENT_RULE_ERROR || c->rule > SL_SEGMENT_RULE_PAPER)
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "unknown vertex rule %d", c->rule);
    if (!isfinite(c->alpha))
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "alpha must be a finite number");
    if (!(c->max_error > 0 && c->max_error <= 1))
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "max_error %g is outside (0, 1] (a fraction of the diagonal)",
                            c->max_error);
    if (!(c->max_normal_deviation > 0 && c->max_normal_deviation <= 180))
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "max_normal_deviation %g is outside (0, 180] degrees",
                            c->max_normal_deviation);
    if (!(c->merge_ratio >= 0 && isfinite(c->merge_ratio)))
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "merge_ratio %g must be >= 0",
                            c->merge_ratio);
    if (!(c->merge_angle > 0 && c->merge_angle <= SL_REGION_GROW_MAX_DELTA))
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "merge_angle %g is outside (0, %g] degrees",
                            c->merge_angle, SL_REGION_GROW_MAX_DELTA);
    return SL_OK;
}
