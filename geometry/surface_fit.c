/* The surface fit's rounds (surface_fit.h; Hoppe et al. 1993, section 4.2): project
 * (surface_fit_project.c), solve (surface_fit_solve.c), step under the guards
 * (surface_fit_guard.c). Each projection also measures the level as it stands, so the
 * best state seen -- the start included -- is what is returned: a fit never makes the
 * level worse by its own measure.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/surface_fit_internal.h"

/* Samples each way, at least: below this a small level is fitted to its own samples (with
 * 4 per triangle, a 2,000-triangle dragon measured 7 % worse by compare's other samples
 * than with 100 k; docs/surface-fit.md). */
#define MIN_SAMPLES 100000u

sl_fit_config sl_fit_default_config(void)
{
    sl_fit_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.seed = 0x5f17;
    cfg.input_per_triangle = 8;
    cfg.level_per_triangle = 4;
    cfg.iterations = 8;
    cfg.spring = 0.01;
    cfg.border_weight = 1.0;
    return cfg;
}

static int check_config(const sl_fit_config *cfg, sl_error *err)
{
    if (cfg->iterations < 0 || cfg->iterations > SL_FIT_MAX_ITERATIONS)
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "fit: iterations %d not in 0..%d",
                            cfg->iterations, SL_FIT_MAX_ITERATIONS);
    if (!(cfg->spring >= 0.0 && cfg->spring < INFINITY) ||
        !(cfg->border_weight >= 0.0 && cfg->border_weight < INFINITY))
        return sl_error_set(err, SL_E_USAGE, 0, NULL,
                            "fit: spring and border_weight must be finite and >= 0");
    if (cfg->input_per_triangle == 0 || cfg->level_per_triangle == 0)
        return sl_error_set(err, SL_E_USAGE, 0, NULL, "fit: samples per triangle must be >= 1");
    return SL_OK;
}

/* Everything one fit holds. */
typedef struct fit_run {
    fit_level lv;
    fit_project proj;
    fit_solver solver;
    fit_guard guard;
    float *best;               /* 3 per welded vertex: the best positions seen */
    double *last_f, *last_g;   /* 3 per welded vertex: the last round's D and P + D */
} fit_run;

static void run_release(fit_run *run)
{
    fit_level_release(&run->lv);
    free(run->proj.terms);
    free(run->proj.level_hint);
    fit_solver_release(&run->solver);
    fit_guard_release(&run->guard);
    free(run->best);
    free(run->last_f);
    free(run->last_g);
}

/* Which of the reference's samples this level uses: every stride-th of the stratified
 * sequence is itself stratified. */
static void choose_input_samples(fit_project *p, const sl_fit_config *cfg)
{
    uint64_t want = (uint64_t)cfg->input_per_triangle * p->lv->triangle_count;
    uint64_t n = p->ref->sample_count;
    if (want < MIN_SAMPLES)
        want = MIN_SAMPLES;
    p->input_stride = want < n ? n / want : 1;
    p->input_count = (n + p->input_stride - 1) / p->input_stride;
}

/* The level's samples: level_per_triangle each, at least as many as the input side uses
 * for a small level (MIN_SAMPLES, or all the reference has if fewer). */
static int draw_level_samples(fit_level *lv, const sl_fit_reference *ref,
                              const sl_fit_config *cfg, sl_error *err)
{
    uint64_t n = (uint64_t)cfg->level_per_triangle * lv->triangle_count;
    uint64_t floor = ref->sample_count < MIN_SAMPLES ? ref->sample_count : MIN_SAMPLES;
    if (n < floor)
        n = floor;
    if (n > SL_FIT_MAX_SAMPLES)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL, "fit: %llu level samples",
                            (unsigned long long)n);
    return fit_level_samples(lv, n, cfg->seed, err);
}

static int run_prepare(fit_run *run, const sl_fit_reference *ref, const float *positions,
                       uint64_t vertex_count, const uint32_t *triangles,
                       uint64_t triangle_count, const sl_fit_config *cfg, sl_error *err)
{
    fit_level *lv = &run->lv;
    int rc = fit_level_build(lv, positions, vertex_count, triangles, triangle_count,
                             cfg->locked, err);
    if (rc == SL_OK && !ref->is_points) /* a point set has no surface to pull them to */
        rc = draw_level_samples(lv, ref, cfg, err);
    if (rc != SL_OK)
        return rc;
    fit_project *p = &run->proj;
    p->ref = ref;
    p->lv = lv;
    p->border_weight = cfg->border_weight;
    p->borders = lv->border_edge_count && ref->border_sample_count;
    choose_input_samples(p, cfg);
    p->terms = calloc(fit_term_count(p), sizeof *p->terms);
    p->level_hint = malloc((lv->sample_count + 1) * sizeof *p->level_hint);
    run->best = malloc(3 * (size_t)lv->vertex_count * sizeof *run->best);
    run->last_f = malloc(3 * (size_t)lv->vertex_count * sizeof *run->last_f);
    run->last_g = malloc(3 * (size_t)lv->vertex_count * sizeof *run->last_g);
    if (!p->terms || !p->level_hint || !run->best || !run->last_f || !run->last_g)
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "fit: %llu terms",
                            (unsigned long long)fit_term_count(p));
    memset(p->level_hint, 0xff, (lv->sample_count + 1) * sizeof *p->level_hint);
    memcpy(run->best, lv->pos, 3 * (size_t)lv->vertex_count * sizeof *run->best);
    rc = fit_solver_init(&run->solver, lv, err);
    if (rc == SL_OK)
        rc = fit_guard_init(&run->guard, lv, err);
    return rc;
}

static double symmetric_rms(const fit_measure *m)
{
    return sqrt(fmax(m->input_to_level, m->level_to_input));
}

/* Anderson acceleration with one step of history (Walker and Ni, SIAM J. Numer. Anal.
 * 49(4), 2011; as used for ICP by Zhang, Yao and Deng, "Fast and robust iterative closest
 * point", TPAMI 2021) of the fixed-point map G(P) = P + D(P), the plain round: with
 * f = D, the step becomes f - theta (G_k - G_k-1), theta minimising
 * |f_k - theta (f_k - f_k-1)|. Alternating projection and point-to-point solve creeps
 * along the surface (every closest-point residual is normal to it, so a round has no
 * reason to slide a vertex and the next finds it only a little better placed); the
 * extrapolation takes several such rounds at once (lucy at 20 %: 6 accelerated rounds go
 * about as far as 12 plain ones, docs/surface-fit.md).
 * The dot products are summed per fixed chunk and the chunks in order. */
static void accelerate(fit_run *run, int have_history)
{
    size_t n = 3 * (size_t)run->lv.vertex_count, chunks = (n + FIT_CHUNK - 1) / FIT_CHUNK;
    double *f = run->solver.x, *part = run->solver.partial, num = 0.0, den = 0.0;
    const float *pos = run->lv.pos;
    if (have_history) {
#pragma omp parallel for schedule(static) if (chunks > 1)
        for (size_t c = 0; c < chunks; c++) {
            double nu = 0.0, de = 0.0;
            for (size_t i = c * FIT_CHUNK; i < n && i < (c + 1) * FIT_CHUNK; i++) {
                double df = f[i] - run->last_f[i];
                nu += f[i] * df;
                de += df * df;
            }
            part[2 * c] = nu;
            part[2 * c + 1] = de;
        }
        for (size_t c = 0; c < chunks; c++) {
            num += part[2 * c];
            den += part[2 * c + 1];
        }
    }
    double theta = den > 0.0 ? num / den : 0.0;
#pragma omp parallel for schedule(static) if (n > FIT_CHUNK)
    for (size_t i = 0; i < n; i++) {
        double g = pos[i] + f[i];
        run->last_f[i] = f[i];
        if (have_history) /* (the history is not initialised before the first round) */
            f[i] -= theta * (g - run->last_g[i]);
        run->last_g[i] = g;
    }
}

/* Project, keep the state if it is the best so far, then (unless last) solve and step.
 * A round that made things worse drops the acceleration's history. */
static int run_rounds(fit_run *run, const sl_fit_config *cfg, sl_fit_stats *st,
                      sl_progress *progress, sl_error *err)
{
    fit_level *lv = &run->lv;
    fit_measure best = {INFINITY, INFINITY}, last = {INFINITY, INFINITY};
    int history = 0;
    for (int round = 0; round <= cfg->iterations; round++) {
        fit_measure m;
        if (sl_progress_step(progress, "surface fit", round / (cfg->iterations + 1.0)))
            return sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "surface fit");
        int rc = fit_project_all(&run->proj, &m, progress, err);
        if (rc != SL_OK)
            return rc;
        if (round == 0)
            st->rms_before = symmetric_rms(&m);
        if (round == 0 || symmetric_rms(&m) < symmetric_rms(&best)) {
            best = m;
            st->best_iteration = round;
            memcpy(run->best, lv->pos, 3 * (size_t)lv->vertex_count * sizeof *run->best);
        }
        history = history && symmetric_rms(&m) < symmetric_rms(&last);
        last = m;
        if (round == cfg->iterations)
            break;
        fit_solve(&run->solver, run->proj.terms, fit_term_count(&run->proj), cfg->spring);
        accelerate(run, history);
        history = 1;
        st->cg_iterations += run->solver.iterations;
        st->vertices_backtracked += fit_guarded_step(lv, &run->guard, run->proj.ref,
                                                     run->solver.x);
        st->iterations = round + 1;
    }
    st->rms_after = symmetric_rms(&best);
    st->rms_input_to_level = sqrt(best.input_to_level);
    st->rms_level_to_input = sqrt(best.level_to_input);
    return SL_OK;
}

/* The best positions to every given vertex of its welded one; counts the moved ones. */
static uint64_t write_back(const fit_run *run, float *positions, uint64_t vertex_count)
{
    uint64_t moved = 0;
    for (uint64_t v = 0; v < vertex_count; v++) {
        uint32_t g = run->lv.group[v];
        if (g == UINT32_MAX)
            continue;
        const float *p = &run->best[3 * (size_t)g];
        moved += memcmp(&positions[3 * v], p, 3 * sizeof *p) != 0;
        memcpy(&positions[3 * v], p, 3 * sizeof *p);
    }
    return moved;
}

int sl_surface_fit(const sl_fit_reference *ref, float *positions, uint64_t vertex_count,
                   const uint32_t *triangles, uint64_t triangle_count,
                   const sl_fit_config *config, sl_fit_stats *stats, sl_progress *progress,
                   sl_error *err)
{
    sl_fit_config defaults = sl_fit_default_config();
    const sl_fit_config *cfg = config ? config : &defaults;
    sl_fit_stats st;
    memset(&st, 0, sizeof st);
    if (stats)
        *stats = st;
    int rc = check_config(cfg, err);
    if (rc != SL_OK)
        return rc;
    fit_run run;
    memset(&run, 0, sizeof run);
    rc = run_prepare(&run, ref, positions, vertex_count, triangles, triangle_count, cfg, err);
    if (rc == SL_OK)
        rc = run_rounds(&run, cfg, &st, progress, err);
    if (rc == SL_OK) {
        st.vertices_moved = write_back(&run, positions, vertex_count);
        st.diagonal = ref->diagonal;
        st.input_samples = run.proj.input_count;
        st.level_samples = run.lv.sample_count;
        st.border_samples = fit_term_count(&run.proj) - run.proj.input_count -
                            run.lv.sample_count;
        for (uint32_t v = 0; v < run.lv.vertex_count; v++) {
            st.border_vertices += run.lv.border[v];
            st.fixed_vertices += run.lv.fixed[v];
        }
        if (stats)
            *stats = st;
    }
    run_release(&run);
    return rc;
}
