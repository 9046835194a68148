/* A rung's candidates and the choice among them (refine.h, docs/levels.md).
 *
 * Each method the item went through gives one candidate: the octree its cut, segment and
 * cluster their level of the rung's name; under [lod] method = best a mesh also gives the
 * scan simplified (from the previous, larger scan candidate, so the ladder is simplified
 * once from the top down). Each is collapsed to the count (refine_collapse.c). With one
 * candidate it is the level; with several, each is measured against the input (RMS and
 * Hausdorff distance over [refine] select_samples area samples, and its topology) and the
 * choice is, in this order: one that reached its count; one that keeps what the input
 * has (a single body, a closed surface); the least RMS; ties to the earlier one (octree,
 * segment, cluster, scan). Only the chosen one is then fitted to the input: the fit
 * costs more than the rest together, and it improves every candidate alike (measured:
 * docs/levels.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "geometry/mesh_distance.h"
#include "stages/refine/refine_internal.h"

/* How much farther from the input than the chosen candidate another may be, before the fit,
 * and still be fitted to be compared with it (fit_chosen). */
#define CLOSE_RMS 1.5

void refine_candidate_release(refine_candidate *c)
{
    sl_level_release_mesh(&c->level);
    memset(c, 0, sizeof *c);
}

/* The record every candidate of rung r starts with. */
static void start_record(sl_level *lv, const sl_rung *r, uint64_t target, const char *method)
{
    memset(lv, 0, sizeof *lv);
    snprintf(lv->name, sizeof lv->name, "%s", r->name);
    snprintf(lv->method, sizeof lv->method, "%s", method);
    lv->rung = *r;
    lv->budget = target;
}

/* The largest octree cut within `budget` that holds together as the input does: a coarse
 * cut splits thin parts off a body (docs/lod.md "Shards"), and the collapse keeps every
 * part it is given, so when the cut at [levels] oversample times the count breaks, cuts
 * at 2, 4 and 8 times that are tried (finer cells keep thin parts whole) and the first in
 * one piece is taken, else the one whose largest part is largest. "One piece" has a
 * margin here: the fit pulls a small part out to the surface it stands for, and its share
 * of the area grows (usnm_1145291 at 5 %: 99.5 % before the fit, 98.8 % after). */
#define OCTREE_TRIES 4
#define CUT_ONE_BODY 0.995
static int connected_cut(refine_item *it, double want, refine_cut *out, sl_error *err)
{
    int rc = 0;
    double best_share = -1;
    memset(out, 0, sizeof *out);
    for (int t = 0; t < OCTREE_TRIES && rc == 0; t++, want *= 2) {
        refine_cut cut;
        rc = refine_cut_within(&it->cutter, want < 1e18 ? (uint64_t)want : UINT64_MAX / 2, &cut,
                               err);
        double share = 1;
        if (rc == 0 && it->input_one_body)
            rc = refine_largest_part(&cut.mesh, &share, err);
        if (rc == 0 && share > best_share) {
            refine_cut_release(out);
            *out = cut;
            best_share = share;
        } else if (rc == 0) {
            refine_cut_release(&cut);
        }
        if (rc == 0 && (share >= CUT_ONE_BODY || !it->c->collapse))
            break;
    }
    if (rc)
        refine_cut_release(out);
    return rc;
}

/* The octree's cut: an expansions rung as the paper cuts it; else the largest cut within
 * [levels] oversample times the count when it is to be collapsed to it (in one piece when
 * the input is, connected_cut), within the count when not. Its arrays move into the level
 * (normals go: the export draws its own). */
static int octree_candidate(refine_item *it, const sl_rung *r, uint64_t target,
                            refine_candidate *cand, sl_error *err)
{
    refine_cut cut;
    int rc = refine_model(it, err);
    if (rc)
        return rc;
    if (r->kind == SL_RUNG_EXPANSIONS)
        rc = refine_cut_percent(&it->cutter, r->percent, &cut, err);
    else
        rc = connected_cut(it, it->c->ladder.oversample * (double)target, &cut, err);
    if (rc)
        return rc;
    sl_level *lv = &cand->level;
    start_record(lv, r, target, "octree");
    lv->expansions = cut.k;
    lv->unpatched_cells = cut.cracks > UINT32_MAX ? UINT32_MAX : (uint32_t)cut.cracks;
    lv->bound = it->cutter.levels->error_after[cut.k];
    lv->bound_fraction = it->diagonal > 0 ? lv->bound / it->diagonal : 0;
    lv->vertex_count = cut.mesh.vertex_count;
    lv->triangle_count = cut.mesh.triangle_count;
    lv->positions = cut.mesh.positions;
    lv->colors = cut.mesh.colors;
    lv->triangles = cut.mesh.indices;
    free(cut.mesh.normals);
    cand->base_triangles = lv->triangle_count;
    cand->capped = cut.capped;
    cand->dropped = cut.dropped;
    return 0;
}

/* The segment or cluster method's level of rung r's name. */
static int list_candidate(refine_item *it, struct refine_method_list *m, const sl_rung *r,
                          uint64_t target, refine_candidate *cand, sl_error *err)
{
    for (uint32_t i = 0; i < m->list.count; i++) {
        const sl_level *rec = &m->list.levels[i];
        if ((rec->flags & SL_LEVEL_INTERMEDIATE) || strcmp(rec->name, r->name))
            continue;
        sl_level_copy_record(&cand->level, rec);
        cand->level.budget = target;
        int rc = sl_level_read_mesh(m->dir, &cand->level, it->points.count, err);
        cand->base_triangles = cand->level.triangle_count;
        return rc;
    }
    return sl_error_corrupt(err, m->dir, "the %s method's levels have no level %s", m->method,
                            r->name);
}

int refine_scan_level(refine_item *it, const sl_rung *r, uint64_t target, sl_level *lv,
                      sl_error *err)
{
    start_record(lv, r, target, "scan");
    lv->flags = SL_LEVEL_SCAN | SL_LEVEL_REACHED | (target >= it->points.triangle_count ? SL_LEVEL_CLAMPED : 0);
    return sl_level_from_points(lv, it->points.count, it->points.positions, it->points.colors,
                                it->points.texcoords, it->points.triangle_count,
                                it->points.triangles, err);
}

/* best: the scan simplified, from the last scan candidate (before its fit) while it is
 * larger than the count, else from the scan. */
static int scan_candidate(refine_item *it, const sl_rung *r, uint64_t target,
                          refine_candidate *cand, sl_error *err)
{
    sl_level *lv = &cand->level;
    int rc;
    sl_level *chain = &it->scan_chain;
    if (chain->positions && chain->triangle_count > target) {
        /* The chain's own arrays, taken over: sl_level_from_points made it (keep_chain), so
         * every point of it is used and a copy made the same way would be the same arrays,
         * and this collapse replaces it; a copy beside it was 320 MB through the 20 M torus's
         * lod60 collapse, the refine stage's peak. */
        start_record(lv, r, target, "scan");
        lv->vertex_count = chain->vertex_count;
        lv->positions = chain->positions;
        lv->colors = chain->colors;
        lv->texcoords = chain->texcoords;
        lv->source = chain->source; /* the input's points */
        lv->triangle_count = chain->triangle_count;
        lv->triangles = chain->triangles;
        chain->positions = NULL;
        chain->colors = NULL;
        chain->texcoords = NULL;
        chain->source = NULL;
        chain->triangles = NULL;
        snprintf(lv->from, sizeof lv->from, "%s", chain->name);
        rc = 0;
    } else {
        rc = refine_scan_level(it, r, target, lv, err);
        lv->flags = 0;
    }
    cand->base_triangles = lv->triangle_count;
    return rc;
}

static int measure(refine_item *it, refine_candidate *cand, sl_error *err)
{
    const sl_level *lv = &cand->level;
    if (lv->triangle_count == 0)
        return 0;
    sl_mesh view = sl_mesh_view(lv->vertex_count, lv->positions, NULL, NULL, lv->triangle_count,
                                lv->triangles);
    sl_mesh_distance d;
    sl_error derr;
    sl_error_init(&derr);
    int rc = 0;
    if (!it->distance_reference) { /* the input's side, once per item */
        sl_mesh_distance_config dc = sl_mesh_distance_default_config();
        dc.samples = it->c->select_samples;
        rc = sl_distance_reference_build(&it->surface, &dc, &it->distance_reference, &derr);
    }
    if (rc == 0)
        rc = sl_distance_reference_compute(it->distance_reference, &view, 0, &d,
                                           it->io->progress, &derr);
    if (rc == SL_E_INTERRUPTED || rc == SL_E_NOMEM) {
        sl_error_merge(err, &derr);
        return rc;
    }
    if (rc == 0) { /* a candidate that cannot be measured (no area) is never chosen */
        cand->measured = 1;
        cand->rms = d.fraction.rms;
        cand->hausdorff = d.fraction.hausdorff;
    }
    sl_mesh_topology topo;
    rc = sl_mesh_topology_compute(&view, &topo, err);
    if (rc == 0) {
        cand->watertight = topo.watertight;
        cand->largest_part = topo.area > 0 ? topo.largest_component_area / topo.area : 0;
    }
    return rc;
}

/* Within 1 % of the count, or below it. */
static int reached(const sl_level *lv, uint64_t target)
{
    return target == 0 || (double)lv->triangle_count <= 1.01 * (double)target;
}

/* How well candidate c keeps what the input has: 2 one body (when the input is), 1 closed
 * (when the input is); the sum. */
static int keeps(const refine_item *it, const refine_candidate *c)
{
    return 2 * (it->input_one_body && c->largest_part >= SL_REFINE_ONE_BODY) +
           (it->input_watertight && c->watertight);
}

/* a before b: reached, then keeps more of the input's topology, then less RMS. */
static int better(const refine_item *it, const refine_candidate *a, const refine_candidate *b,
                  uint64_t target)
{
    int ra = reached(&a->level, target), rb = reached(&b->level, target);
    if (ra != rb)
        return ra;
    int ka = keeps(it, a), kb = keeps(it, b);
    if (ka != kb)
        return ka > kb;
    return a->measured && (!b->measured || a->rms < b->rms);
}

/* a and b alike but for their RMS: both reached or not, keeping as much. */
static int same_rank(const refine_item *it, const refine_candidate *a, const refine_candidate *b,
                     uint64_t target)
{
    return reached(&a->level, target) == reached(&b->level, target) &&
           keeps(it, a) == keeps(it, b);
}

static int choose(const refine_item *it, const refine_candidate *cands, int count,
                  uint64_t target)
{
    int best = 0;
    for (int i = 1; i < count; i++)
        if (better(it, &cands[i], &cands[best], target))
            best = i;
    return best;
}

/* One candidate made by `make` and collapsed to the count, timed. */
typedef int (*make_fn)(refine_item *, const sl_rung *, uint64_t, refine_candidate *,
                       sl_error *);

/* Whether a candidate measured before its collapse can be left there: `lead` (may be
 * NULL), a candidate made before it that reached the count and keeps at least as much of
 * the input, is already more than CLOSE_RMS times closer to the input than it is with all
 * its triangles. Collapsing it would only take it farther (its triangles are a superset's
 * worth of the surface), and a candidate past CLOSE_RMS of the chosen one is not fitted to
 * be compared (fit_chosen), so it could not be chosen: its collapse, on a large scan the
 * most of the stage's time, is spared (docs/levels.md, "Choice"). Nor can it be chosen
 * when it is farther than a lead within [refine] fit_floor at all: the lead, if chosen,
 * is fitted with no rival (fit_chosen), so the candidate would meet it collapsed and
 * unfitted, farther still (the 100 M torus's lod20: the octree's 40 M-triangle cut at 1.38
 * times the scan's RMS, 359 of the stage's 1,024 s and its 20 GB peak to lose at 1.63). */
static int outranked(const refine_item *it, const refine_candidate *lead,
                     const refine_candidate *raw, uint64_t target)
{
    if (!(lead && lead->measured && raw->measured && reached(&lead->level, target) &&
          keeps(it, lead) >= keeps(it, raw)))
        return 0;
    return raw->rms > CLOSE_RMS * lead->rms ||
           (lead->rms <= it->c->fit_floor && raw->rms > lead->rms);
}

/* A candidate measured before its collapse; an octree cut the last rung measured so (the
 * same expansions, so the same mesh: the cuts of the top rungs are all capped at the
 * input's count) takes that rung's figures instead of a second measure (at 20 M
 * triangles, 20 s a rung). */
static int measure_raw(refine_item *it, refine_candidate *cand, sl_error *err)
{
    struct refine_raw_cut *m = &it->raw_cut;
    int octree = !strcmp(cand->level.method, "octree");
    if (octree && m->valid && m->k == cand->level.expansions &&
        m->triangles == cand->level.triangle_count) {
        cand->measured = 1;
        cand->rms = m->rms;
        cand->hausdorff = m->hausdorff;
        cand->largest_part = m->largest_part;
        cand->watertight = m->watertight;
        return 0;
    }
    int rc = measure(it, cand, err);
    if (rc == 0 && octree && cand->measured) {
        m->valid = 1;
        m->k = cand->level.expansions;
        m->triangles = cand->level.triangle_count;
        m->rms = cand->rms;
        m->hausdorff = cand->hausdorff;
        m->largest_part = cand->largest_part;
        m->watertight = cand->watertight;
    }
    return rc;
}

static int one(refine_item *it, const sl_rung *r, uint64_t target, make_fn make,
               const refine_candidate *lead, refine_candidate *cand, sl_error *err)
{
    double t0 = omp_get_wtime();
    memset(cand, 0, sizeof *cand);
    int rc = make(it, r, target, cand, err);
    int paper = r->kind == SL_RUNG_EXPANSIONS; /* published as paper 1 cuts it */
    if (rc == 0 && !paper && lead && it->c->collapse && cand->level.triangle_count > target) {
        rc = measure_raw(it, cand, err); /* as it comes: is it worth collapsing? */
        cand->rms_uncollapsed = rc == 0 && cand->measured ? cand->rms : 0;
        cand->outranked = rc == 0 && outranked(it, lead, cand, target);
    }
    if (rc == 0 && !paper && !cand->outranked)
        rc = refine_collapse(it, target, cand, err);
    if (rc == 0 && reached(&cand->level, target))
        cand->level.flags |= SL_LEVEL_REACHED;
    if (rc == 0 && target && target >= it->input_triangles)
        cand->level.flags |= SL_LEVEL_CLAMPED;
    cand->seconds = omp_get_wtime() - t0;
    return rc;
}

static int method_0(refine_item *it, const sl_rung *r, uint64_t t, refine_candidate *c,
                    sl_error *e)
{
    return list_candidate(it, &it->methods[0], r, t, c, e);
}

static int method_1(refine_item *it, const sl_rung *r, uint64_t t, refine_candidate *c,
                    sl_error *e)
{
    return list_candidate(it, &it->methods[1], r, t, c, e);
}

/* A candidate fitted, its seconds counted; measured again when it is to be compared. */
static int fit_one(refine_item *it, refine_candidate *c, int remeasure, sl_error *err)
{
    double t0 = omp_get_wtime();
    int rc = refine_fit(it, c, err);
    c->fitted = rc == 0 && it->c->fit;
    if (rc == 0 && remeasure) {
        c->rms_collapsed = c->rms;
        rc = measure(it, c, err);
    }
    c->seconds += omp_get_wtime() - t0;
    return rc;
}

/* Only the chosen candidate is fitted (and none measured within [refine] fit_floor of the
 * input), unless another ranks alike and is within
 * CLOSE_RMS of it before the fit: the fit gains more on a remesh (an octree cut's even
 * triangles) than on the scan collapsed, so then both are fitted and measured again, and
 * the better one after the fit is chosen (usnm_1145291 at 10 %: the octree's 1.24 times the
 * scan's RMS before the fit, 0.83 times after). */
static int fit_chosen(refine_item *it, refine_candidate *cands, int count, uint64_t target,
                      int *chosen, sl_error *err)
{
    refine_candidate *c = &cands[*chosen];
    if (c->measured && c->rms <= it->c->fit_floor)
        return 0; /* already closer than the published file can show ([refine] fit_floor) */
    int rival = -1;
    for (int i = 0; i < count && c->measured; i++)
        if (i != *chosen && cands[i].measured && same_rank(it, c, &cands[i], target) &&
            cands[i].rms <= CLOSE_RMS * c->rms && (rival < 0 || cands[i].rms < cands[rival].rms))
            rival = i;
    int rc = fit_one(it, c, rival >= 0, err);
    if (rc == 0 && rival >= 0)
        rc = fit_one(it, &cands[rival], 1, err);
    if (rc == 0 && rival >= 0 && cands[rival].rms < c->rms)
        *chosen = rival;
    return rc;
}

int refine_octree_wanted(const refine_item *it, const sl_rung *r, uint64_t target)
{
    if (r->kind == SL_RUNG_EXPANSIONS || !(it->c->best && it->is_mesh && it->c->collapse))
        return 1; /* no scan simplified to the count beside it (collapse off: paper 1's mode) */
    return (double)target <= it->c->octree_max_share * (double)it->input_triangles;
}

int refine_make_candidates(refine_item *it, const sl_rung *r, uint64_t target,
                           refine_candidate *cands, int *count, int *chosen, sl_error *err)
{
    make_fn makes[SL_REFINE_MAX_CANDIDATES];
    int n = 0;
    if (it->have_model && refine_octree_wanted(it, r, target))
        makes[n++] = octree_candidate;
    if (r->kind != SL_RUNG_EXPANSIONS) {
        if (it->method_count > 0)
            makes[n++] = method_0;
        if (it->method_count > 1)
            makes[n++] = method_1;
        if (it->c->best && it->is_mesh)
            makes[n++] = scan_candidate;
    }
    *count = n;
    *chosen = 0;
    int rc = 0;
    /* The scan simplified first (the last in the list, so ties still go to the methods):
     * the others are measured as they come against it, and one it outranks is left
     * uncollapsed (outranked). */
    int lead = n > 1 && makes[n - 1] == scan_candidate ? n - 1 : -1;
    /* One candidate is measured too when the fit is to judge it by [refine] fit_floor. */
    int judge = n > 1 || (it->c->fit && it->c->fit_floor > 0 && r->kind != SL_RUNG_EXPANSIONS);
    for (int at = 0; at < n && rc == 0; at++) {
        int i = lead < 0 ? at : (at + n - 1) % n; /* lead, then 0, 1, ... */
        rc = one(it, r, target, makes[i], i == lead || lead < 0 ? NULL : &cands[lead],
                 &cands[i], err);
        if (rc == 0 && judge && !cands[i].outranked)
            rc = measure(it, &cands[i], err);
        if (rc == 0)
            rc = sl_stage_step(it->io, "refine", 0, err);
    }
    if (rc == 0 && n == 0)
        return sl_error_set(err, SL_E_INTERNAL, 0, NULL, "level %s: no method made a candidate",
                            r->name);
    if (rc == 0)
        *chosen = choose(it, cands, *count, target);
    if (rc == 0 && r->kind != SL_RUNG_EXPANSIONS)
        rc = fit_chosen(it, cands, *count, target, chosen, err);
    return rc;
}
