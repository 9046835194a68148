/* One pass of the segment method over the whole mesh, its checks, and the level search.
 *
 * A pass: trim the chains of the segments that may be trimmed, retriangulate every
 * segment that is not kept (in parallel), and put the mesh together. Each segment is in
 * one of three states: trimmed (its boundary may be trimmed), boundary kept (it is
 * retriangulated inside its untrimmed loops), kept (its input triangles stay). A segment
 * whose retriangulation is refused (a trimmed loop crossing another in projection, a
 * turned triangle) moves one state up and the pass goes on; a chain is trimmed only when
 * both its segments are in the first state, so a change reaches the neighbours, which
 * are redone (a segment is redone exactly when the kept vertices on its loops changed).
 *
 * Then the whole level is checked against the input: the same number of boundary,
 * non-manifold and inconsistent edges, of non-manifold vertices, the same Euler
 * characteristic. (A new triangle's diagonal can coincide with an edge of another
 * segment, making it non-manifold.) When a count differs, the offending edges are found
 * and the segments around them kept; the pass repeats. States only go up, so this ends.
 *
 * Determinism: each segment's result depends only on its own input; states change in
 * whole rounds; the level is assembled in segment order.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stages/segment/segment_internal.h"

enum seg_state { STATE_TRIM = 0, STATE_BOUNDARY = 1, STATE_KEEP = 2 };

void sl_segment_level_release(sl_segment_level *l)
{
    free(l->triangles);
    memset(l, 0, sizeof *l);
}

/* --- one pass --------------------------------------------------------------------------- */

typedef struct pass {
    sl_segment_model *m;
    seg_trim_params trim;
    seg_patch_params patch;
    uint8_t *state;           /* per segment */
    uint8_t *kept;            /* per vertex */
    uint8_t *trimmable;       /* per segment */
    uint8_t *chain_level;     /* per chain: how far it may be trimmed (segment_trim.c) */
    uint64_t *signature;      /* per segment: of the kept flags its result was made with */
    seg_patch_result *result; /* per segment */
    uint32_t repairs;
    double tau_used;          /* the threshold a budget picked */
    int over_budget;          /* the bases alone exceed the budget */
} pass;

static void clear_result(seg_patch_result *r)
{
    free(r->triangles);
    free(r->record);
    memset(r, 0, sizeof *r);
}

static void pass_release(pass *p)
{
    if (p->result)
        for (uint32_t k = 0; k < p->m->seg.segment_count; k++)
            clear_result(&p->result[k]);
    free(p->state);
    free(p->kept);
    free(p->trimmable);
    free(p->chain_level);
    free(p->signature);
    free(p->result);
}

/* FNV-1a over the kept flags of segment k's loop vertices that are not fixed. */
static uint64_t loop_signature(const sl_segment_model *m, const uint8_t *kept, uint32_t k)
{
    uint64_t h = 0xcbf29ce484222325ull;
    uint32_t l0 = m->loops.segment_loop_start[k], l1 = m->loops.segment_loop_start[k + 1];
    for (uint32_t i = m->loops.loop_start[l0]; i < m->loops.loop_start[l1]; i++) {
        uint32_t v = m->adj.triangles[m->loops.halfedges[i]];
        if (m->fixed[v])
            continue;
        h = (h ^ (uint64_t)(kept[v] + 1)) * 0x100000001b3ull;
    }
    return h;
}

/* Does chain c hold vertex v (an end or a vertex between)? */
static int chain_has(const sl_segment_model *m, uint32_t c, uint32_t v)
{
    for (uint32_t i = m->chain_start[c]; i < m->chain_start[c + 1]; i++)
        if (m->chain_vertices[i] == v)
            return 1;
    return 0;
}

/* A refused segment: trimming may be the cause (the triangulation refused the trimmed
 * polygon, or a new triangle between trimmed loops turned), so its chains through the
 * vertices the refusal names, or else all of them, are trimmed less (a quarter of the
 * error, a sixteenth, then not at all); a segment whose chains are all untrimmed moves
 * up a state. */
static void refused_segment(pass *p, uint32_t k)
{
    const sl_segment_model *m = p->m;
    const seg_patch_result *r = &p->result[k];
    int raised = 0;
    if ((r->status == SEG_PATCH_REFUSED || r->status == SEG_PATCH_TURNED) &&
        p->state[k] == STATE_TRIM) {
        for (int all = 0; all < 2 && !raised; all++)
            for (uint32_t i = m->seg_chain_start[k]; i < m->seg_chain_start[k + 1]; i++) {
                uint32_t c = m->seg_chains[i];
                if (p->chain_level[c] >= SEG_CHAIN_KEEP)
                    continue;
                int named = all;
                for (int q = 0; q < 4 && !named; q++)
                    named = r->problem[q] != SEG_NONE && chain_has(m, c, r->problem[q]);
                if (named) {
                    p->chain_level[c]++;
                    raised = 1;
                }
            }
    }
    if (!raised)
        p->state[k]++;
}

/* Retriangulates every segment that is not kept and whose loops changed; handles the
 * refused ones (refused_segment). Returns the number refused, or -1 when out of memory. */
static int64_t retriangulate(pass *p)
{
    sl_segment_model *m = p->m;
    int64_t ns = m->seg.segment_count, refused = 0;
    int nomem = 0;
#pragma omp parallel reduction(+ : refused)
    {
        seg_scratch *s = seg_scratch_new(m->vertex_count);
        if (!s) {
#pragma omp atomic write
            nomem = 1;
        }
#pragma omp for schedule(dynamic, 1)
        for (int64_t i = 0; i < ns; i++) {
            uint32_t k = m->by_size[i]; /* the largest first: no long one left at the end */
            if (!s || p->state[k] == STATE_KEEP)
                continue;
            uint64_t sig = loop_signature(m, p->kept, (uint32_t)k);
            if (p->result[k].triangles && p->signature[k] == sig)
                continue;
            clear_result(&p->result[k]);
            seg_patch_run(m, (uint32_t)k, p->kept, &p->patch, s, &p->result[k]);
            p->signature[k] = sig;
            if (p->result[k].status == SEG_PATCH_NOMEM) {
#pragma omp atomic write
                nomem = 1;
            } else if (p->result[k].status != SEG_PATCH_OK) {
                free(p->result[k].triangles);
                p->result[k].triangles = NULL;
                refused++;
            }
        }
        seg_scratch_free(s);
    }
    if (!nomem && refused) /* serially, in segment order: deterministic */
        for (int64_t k = 0; k < ns; k++)
            if (p->state[k] != STATE_KEEP && !p->result[k].triangles &&
                p->result[k].status != SEG_PATCH_OK)
                refused_segment(p, (uint32_t)k);
    return nomem ? -1 : refused;
}

/* The level: kept segments' input triangles and the others' new ones, in segment order;
 * tri_segment (may be NULL) gets each triangle's segment. */
static int assemble(const pass *p, sl_segment_level *out, uint32_t **tri_segment)
{
    const sl_segment_model *m = p->m;
    uint64_t total = 0;
    for (uint32_t k = 0; k < m->seg.segment_count; k++)
        total += p->state[k] == STATE_KEEP ? m->seg_tri_start[k + 1] - m->seg_tri_start[k]
                                           : p->result[k].triangle_count;
    out->triangles = malloc(3 * (total ? total : 1) * sizeof *out->triangles);
    uint32_t *ts = tri_segment ? malloc((total ? total : 1) * sizeof *ts) : NULL;
    if (!out->triangles || (tri_segment && !ts)) {
        free(out->triangles);
        free(ts);
        out->triangles = NULL;
        return -1;
    }
    uint64_t at = 0;
    for (uint32_t k = 0; k < m->seg.segment_count; k++) {
        if (p->state[k] == STATE_KEEP) {
            for (uint32_t i = m->seg_tri_start[k]; i < m->seg_tri_start[k + 1]; i++) {
                memcpy(out->triangles + 3 * at, m->triangles + 3 * (uint64_t)m->seg_tris[i],
                       3 * sizeof *out->triangles);
                if (ts)
                    ts[at] = k;
                at++;
            }
        } else {
            memcpy(out->triangles + 3 * at, p->result[k].triangles,
                   3 * (size_t)p->result[k].triangle_count * sizeof *out->triangles);
            if (ts)
                for (uint32_t i = 0; i < p->result[k].triangle_count; i++)
                    ts[at + i] = k;
            at += p->result[k].triangle_count;
        }
    }
    out->triangle_count = total;
    if (tri_segment)
        *tri_segment = ts;
    return 0;
}

/* --- the whole-mesh check ------------------------------------------------------------ */

static int cmp_double_desc(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? 1 : x > y ? -1 : 0;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Directed edges (a << 32 | b) of triangles, sorted. */
static uint64_t *directed_edges(const uint32_t *tri, uint64_t n)
{
    uint64_t *e = malloc(3 * (n ? n : 1) * sizeof *e);
    if (!e)
        return NULL;
    for (uint64_t t = 0; t < n; t++)
        for (int c = 0; c < 3; c++) {
            uint64_t a = tri[3 * t + c], b = tri[3 * t + (c + 1) % 3];
            e[3 * t + c] = a << 32 | b;
        }
    qsort(e, 3 * n, sizeof *e, cmp_u64);
    return e;
}

static uint64_t count_of(const uint64_t *e, uint64_t n, uint64_t key)
{
    uint64_t lo = 0, hi = n;
    while (lo < hi) {
        uint64_t mid = (lo + hi) / 2;
        if (e[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    uint64_t c = 0;
    while (lo + c < n && e[lo + c] == key)
        c++;
    return c;
}

/* Keeps the segments of every output triangle with an edge whose directed counts
 * (a->b, b->a) differ from the input's, or with a corner at a vertex whose fan count
 * changed. Returns the number of segments newly kept, -1 when out of memory. */
static int64_t keep_offenders(pass *p, const sl_segment_level *lv, const uint32_t *ts,
                              const sl_mesh_adjacency *out_adj)
{
    const sl_segment_model *m = p->m;
    uint64_t *ein = directed_edges(m->triangles, m->triangle_count);
    uint64_t *eout = directed_edges(lv->triangles, lv->triangle_count);
    if (!ein || !eout) {
        free(ein);
        free(eout);
        return -1;
    }
    uint64_t nin = 3 * (uint64_t)m->triangle_count, nout = 3 * lv->triangle_count;
    int64_t newly = 0;
    for (uint64_t t = 0; t < lv->triangle_count; t++) {
        int bad = 0;
        for (int c = 0; c < 3 && !bad; c++) {
            uint64_t a = lv->triangles[3 * t + c], b = lv->triangles[3 * t + (c + 1) % 3];
            uint64_t ab = a << 32 | b, ba = b << 32 | a;
            uint64_t oa = count_of(eout, nout, ab), ob = count_of(eout, nout, ba);
            int ok_out = oa == 1 && ob == 1;
            if (!ok_out && (oa != count_of(ein, nin, ab) || ob != count_of(ein, nin, ba)))
                bad = 1;
            if ((out_adj->vertex_flags[a] ^ m->adj.vertex_flags[a]) & SL_VERTEX_NONMANIFOLD)
                bad = 1; /* a fan appeared or went */
        }
        if (bad && p->state[ts[t]] != STATE_KEEP) {
            p->state[ts[t]] = STATE_KEEP;
            newly++;
        }
    }
    free(ein);
    free(eout);
    return newly;
}

/* 0: the level's topology matches the input's; 1: segments were kept, run again;
 * -1: out of memory; -2: a mismatch no segment explains (a bug). */
static int check_level(pass *p, sl_segment_level *lv, const uint32_t *ts, sl_error *err)
{
    const sl_segment_model *m = p->m;
    sl_mesh_adjacency a;
    sl_error scratch;
    sl_error_init(&scratch);
    if (sl_mesh_adjacency_build(lv->triangles, lv->triangle_count, m->vertex_count, NULL, 0, &a,
                                &scratch))
        return -1;
    sl_adjacency_report r = a.report; /* a copy: `a` is released below */
    int same = r.boundary_edges == m->input_boundary_edges &&
               r.nonmanifold_edges == m->input_nonmanifold_edges &&
               r.inconsistent_edges == m->input_inconsistent_edges &&
               r.nonmanifold_vertices == m->input_nonmanifold_vertices &&
               r.degenerate_triangles == m->adj.report.degenerate_triangles &&
               r.euler_characteristic == m->input_euler;
    lv->stats.euler_characteristic = r.euler_characteristic;
    lv->stats.watertight = r.edges > 0 && r.boundary_edges == 0 && r.nonmanifold_edges == 0 &&
                           r.inconsistent_edges == 0;
    if (same) {
        sl_mesh_adjacency_release(&a);
        return 0;
    }
    int64_t newly = keep_offenders(p, lv, ts, &a);
    sl_mesh_adjacency_release(&a);
    if (newly < 0)
        return -1;
    if (newly > 0)
        return 1;
    /* Nothing local explains it (the Euler characteristic alone differs): keep all. */
    int any = 0;
    for (uint32_t k = 0; k < m->seg.segment_count; k++)
        if (p->state[k] != STATE_KEEP) {
            p->state[k] = STATE_KEEP;
            any = 1;
        }
    if (any)
        return 1;
    sl_error_set(err, SL_E_INTERNAL, 0, NULL,
                 "segment method: the level's topology differs from the input's with every "
                 "segment kept (boundary edges %llu vs %llu, Euler %lld vs %lld)",
                 (unsigned long long)r.boundary_edges,
                 (unsigned long long)m->input_boundary_edges, (long long)r.euler_characteristic,
                 (long long)m->input_euler);
    return -2;
}

static void fill_stats(const pass *p, sl_segment_level *lv)
{
    const sl_segment_model *m = p->m;
    sl_segment_stats *s = &lv->stats;
    s->segments = m->seg.segment_count;
    s->delta_seg = m->seg.delta_seg;
    s->input_vertices = m->used_vertices;
    s->diagonal = m->diagonal;
    s->corners = s->boundary_vertices = s->interior_vertices = 0;
    s->nonmanifold_edges_kept = m->input_nonmanifold_edges;
    uint8_t *used = calloc(m->vertex_count ? m->vertex_count : 1, 1);
    if (used) {
        for (uint64_t i = 0; i < 3 * lv->triangle_count; i++)
            used[lv->triangles[i]] = 1;
        s->removed_vertices = s->removed_boundary = s->removed_interior = 0;
        for (uint32_t v = 0; v < m->vertex_count; v++) {
            int kind = m->loops.vertex_kind[v];
            s->corners += m->fixed[v] && kind != SL_SEGMENT_VERTEX_UNUSED;
            s->boundary_vertices += !m->fixed[v] && kind == SL_SEGMENT_VERTEX_TWO_SEGMENT;
            s->interior_vertices += kind == SL_SEGMENT_VERTEX_INTERIOR;
            if (used[v] || kind == SL_SEGMENT_VERTEX_UNUSED)
                continue;
            s->removed_vertices++;
            s->removed_boundary += kind == SL_SEGMENT_VERTEX_TWO_SEGMENT;
            s->removed_interior += kind == SL_SEGMENT_VERTEX_INTERIOR;
        }
        free(used);
    }
    s->patches_retriangulated = s->patches_boundary_kept = s->patches_kept = s->patches_folded = 0;
    for (uint32_t k = 0; k < m->seg.segment_count; k++) {
        if (p->state[k] == STATE_KEEP) {
            s->patches_kept += m->unfit[k] != SEG_UNFIT_TRIVIAL;
            s->patches_folded += m->unfit[k] == SEG_UNFIT_FOLD || m->unfit[k] == SEG_UNFIT_OVERLAP;
        } else {
            s->patches_retriangulated++;
            s->patches_boundary_kept += p->state[k] == STATE_BOUNDARY;
        }
    }
    s->repairs = p->repairs;
}

/* The threshold for a budget (rule error): the level's triangles at tau are the kept
 * segments' plus, for each other one, its base triangulation and two per insertion whose
 * running minimum of scores exceeds tau (the greedy run to tau stops at the first score
 * at or below it). Returns the largest count's tau within the budget: >= 0; -1 when the
 * records stop before it (record further), -2 when the bases alone exceed the budget,
 * -3 out of memory. */
static double pick_tau(const pass *p, uint64_t budget, double recorded_to)
{
    const sl_segment_model *m = p->m;
    uint64_t base = 0, values = 0;
    for (uint32_t k = 0; k < m->seg.segment_count; k++) {
        if (p->state[k] == STATE_KEEP)
            base += m->seg_tri_start[k + 1] - m->seg_tri_start[k];
        else
            base += p->result[k].base_triangles, values += p->result[k].record_count;
    }
    if (base > budget)
        return -2;
    uint64_t room = (budget - base) / 2; /* insertions the budget allows */
    double *v = malloc((values ? values : 1) * sizeof *v);
    if (!v)
        return -3;
    uint64_t n = 0;
    for (uint32_t k = 0; k < m->seg.segment_count; k++) {
        if (p->state[k] == STATE_KEEP)
            continue;
        double low = INFINITY;
        for (uint32_t i = 0; i < p->result[k].record_count; i++) {
            low = fmin(low, p->result[k].record[i]);
            v[n++] = low;
        }
    }
    double tau;
    if (room >= n) {
        tau = recorded_to > 0 ? -1 : 0; /* every vertex is back: the finest level fits */
    } else {
        qsort(v, n, sizeof *v, cmp_double_desc);
        tau = v[room]; /* #{v > tau} <= room */
    }
    free(v);
    return tau;
}

static void clear_all(pass *p)
{
    for (uint32_t k = 0; k < p->m->seg.segment_count; k++)
        clear_result(&p->result[k]);
}

/* The pass's state for model m, every fitted segment to trim. SL_OK or SL_E_NOMEM. */
static int pass_start(pass *p, sl_segment_model *m, const seg_trim_params *trim,
                      const seg_patch_params *patch)
{
    memset(p, 0, sizeof *p);
    p->m = m;
    p->trim = *trim;
    p->patch = *patch;
    uint32_t ns = m->seg.segment_count;
    size_t nsz = ns ? ns : 1;
    p->state = malloc(nsz);
    p->trimmable = malloc(nsz);
    p->signature = calloc(nsz, sizeof *p->signature);
    p->result = calloc(nsz, sizeof *p->result);
    p->kept = calloc(m->vertex_count ? m->vertex_count : 1, 1);
    p->chain_level = calloc(m->chain_count ? m->chain_count : 1, 1);
    if (!p->state || !p->trimmable || !p->signature || !p->result || !p->kept || !p->chain_level)
        return SL_E_NOMEM;
    for (uint32_t k = 0; k < ns; k++)
        p->state[k] = m->unfit[k] == SEG_FIT ? STATE_TRIM : STATE_KEEP;
    return SL_OK;
}

/* Back to recording the insertions down to tau_min: what was recorded no longer holds. */
static void record_again(pass *p, double tau_min, int *replaying)
{
    *replaying = 0;
    p->patch.record = 1;
    p->patch.tau = tau_min;
    clear_all(p);
}

/* With a budget, after a recording round: tau picked from the records, and the pass set
 * to replay the insertions to it. 1: replay (or record further), 0: over budget with a
 * probe (the pass stops, p->over_budget), SL_E_NOMEM. */
static int settle_tau(pass *p, uint64_t budget, double *tau_min, int *replaying, int *probed)
{
    const sl_segment_model *m = p->m;
    double tau = pick_tau(p, budget, *tau_min);
    if (tau == -3)
        return SL_E_NOMEM;
    if (tau == -1 && *tau_min > 1e-18 * m->diagonal * m->diagonal) { /* record further */
        *tau_min = *tau_min > 0 ? *tau_min / 64 : 0;
        p->patch.tau = *tau_min;
        clear_all(p);
        return 1;
    }
    p->over_budget = tau == -2;
    if (p->over_budget && p->patch.probe) { /* kept segments only add: over it stays */
        *probed = 1;
        return 0;
    }
    /* a vertex within a billionth of the diagonal never comes back: it would only be
     * rounding noise on a flat patch */
    double floor2 = 1e-18 * m->diagonal * m->diagonal;
    p->patch.tau = tau == -2 ? INFINITY : fmax(tau, floor2);
    p->patch.record = 0;
    if (p->patch.tau > 0 && isfinite(p->patch.tau))
        p->patch.max_error = sqrt(p->patch.tau); /* the final flips' bound */
    p->tau_used = p->patch.tau;
    *replaying = 1;
    clear_all(p);
    return 1;
}

/* One round of trimming and retriangulation. SL_OK, 1 (a segment refused: go again),
 * SL_E_NOMEM, SL_E_INTERRUPTED. */
static int trim_and_patch(pass *p, sl_progress *progress)
{
    for (uint32_t k = 0; k < p->m->seg.segment_count; k++)
        p->trimmable[k] = p->state[k] == STATE_TRIM;
    seg_trim_chains(p->m, &p->trim, p->trimmable, p->chain_level, p->kept);
    int64_t refused = retriangulate(p);
    if (refused < 0)
        return SL_E_NOMEM;
    if (sl_progress_interrupted(progress))
        return SL_E_INTERRUPTED;
    return refused > 0;
}

/* The level assembled and checked: SL_OK (done), 1 (repaired: go again), SL_E_NOMEM,
 * SL_E_INTERNAL. */
static int assemble_checked(pass *p, sl_segment_level *lv, sl_error *err)
{
    uint32_t *ts = NULL;
    sl_segment_level_release(lv);
    int c = assemble(p, lv, &ts) ? -1 : check_level(p, lv, ts, err);
    free(ts);
    if (c == 0)
        return SL_OK;
    if (c == -1)
        return SL_E_NOMEM;
    if (c == -2)
        return SL_E_INTERNAL;
    p->repairs++;
    return 1;
}

/* The level's statistics after a pass that ended with `rc` (and `probed`: over budget). */
static void pass_finish(pass *p, sl_segment_level *lv, int rc, int probed, sl_error *err)
{
    const sl_segment_model *m = p->m;
    uint32_t ns = m->seg.segment_count;
    if (!rc && probed) {
        sl_segment_level_release(lv);
        lv->stats.over_budget = 1;
        lv->stats.tau = INFINITY;
    } else if (!rc) {
        fill_stats(p, lv);
        double residual = seg_chain_residual(m, p->kept);
        for (uint32_t k = 0; k < ns; k++)
            if (p->state[k] != STATE_KEEP)
                residual += p->result[k].residual;
        lv->stats.estimate = m->used_vertices
                                 ? sqrt(residual / (double)m->used_vertices) / m->diagonal : 0;
        lv->stats.tau = p->tau_used;
        lv->stats.over_budget = p->over_budget;
    } else {
        sl_segment_level_release(lv);
        if (rc == SL_E_NOMEM)
            sl_error_set(err, SL_E_NOMEM, 0, NULL, "segment method: a pass over %u segments", ns);
        else if (rc == SL_E_INTERRUPTED)
            sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "segment method interrupted");
    }
}

int seg_run_pass(sl_segment_model *m, const seg_trim_params *trim, const seg_patch_params *patch,
                 uint64_t budget, sl_segment_level *lv, sl_progress *progress, sl_error *err)
{
    memset(lv, 0, sizeof *lv);
    pass p;
    int rc = pass_start(&p, m, trim, patch);
    /* budget: record the insertions down to tau_min, pick tau, then replay to it */
    int search = budget > 0 && patch->rule == SL_SEGMENT_RULE_ERROR, replaying = 0;
    double tau_min = patch->tau;
    if (search) {
        p.patch.record = 1;
        p.patch.tau = tau_min;
    }
    int probed = 0;
    while (!rc) {
        int step = trim_and_patch(&p, progress);
        if (step == 1 && replaying) /* the records no longer hold: record again */
            record_again(&p, tau_min, &replaying);
        if (step) {
            rc = step < 0 ? step : SL_OK;
            continue;
        }
        if (search && !replaying) {
            step = settle_tau(&p, budget, &tau_min, &replaying, &probed);
            if (step <= 0) {
                rc = step;
                break;
            }
            continue;
        }
        step = assemble_checked(&p, lv, err);
        if (step == 1 && search) /* kept segments change the count: pick tau again */
            record_again(&p, tau_min, &replaying);
        if (step <= 0) {
            rc = step;
            break;
        }
    }
    pass_finish(&p, lv, rc, probed, err);
    pass_release(&p);
    return rc;
}
