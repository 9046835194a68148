/* `scanlod plan`: a pre-flight estimate per item of the collection (peak memory, time,
 * disk) from each scan's PLY header and the config, so a scheduler can ask for the right
 * node before anything runs (issue 14; docs/engine.md "Planning a run").
 *
 * The estimate is a cost model, not a trial run: every stage of the item's method costs
 * time a + b * N^e and peak memory c + d * N, with N the input's triangles in millions
 * (its points for a point cloud), coefficients fitted on this project's own runs at 2
 * threads (scripts/bench/plan_calibrate.py; docs/cluster.md "Asking for the right node").
 * Stages are separate child processes, so the item's peak is the largest stage's and its
 * time their sum. The benchmark's growth phase prints the plan beside what the run
 * measured, so a drift of the model shows up in docs/benchmarks.md.
 */
#include "pipeline/engine_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "core/json.h"
#include "geometry/ply.h"

/* Cost of one stage, N in millions: seconds = a + b * N^e, peak RSS MB = c + d * N^f. */
typedef struct stage_cost {
    const char *stage;     /* a stage name; "export+fidelity" is the export measuring its levels */
    double a, b, e, c, d, f;
} stage_cost;

/* Octree stages: time from the growth benchmark on a quiet machine (1, 5 and 20 M
 * triangles, docs/benchmarks.md section 4; a from the bundled scans), memory from
 * plan_calibrate.py at 0.1, 0.3 and 1 M with the growth's 5 and 20 M peaks setting the
 * exponent. docs/cluster.md has the fit and the residuals. */
static const stage_cost mesh_costs[] = {
    {"range", 0.014, 0.403, 1.081, 45, 94, 0.95},
    {"samples", 0.105, 2.42, 1.047, 60, 133, 0.95},
    {"merge", 0.078, 1.37, 1.100, 70, 228, 0.95},
    {"priority", 0.107, 3.82, 1.052, 48, 224, 0.95},
    {"crack", 0.117, 3.04, 1.049, 47, 333, 0.95},
    {"export", 0.3, 5.06, 1.062, 48, 516, 0.92},
    {"export+fidelity", 2.5, 5.8, 1.062, 48, 516, 0.92},
    {"segment", 0.20, 60.0, 1.0, 50, 900, 1.0},
    {"cluster", 0.10, 8.0, 1.0, 50, 600, 1.0},
};

static const stage_cost *cost_of(const char *stage)
{
    for (size_t i = 0; i < sizeof mesh_costs / sizeof mesh_costs[0]; i++)
        if (!strcmp(mesh_costs[i].stage, stage))
            return &mesh_costs[i];
    return NULL;
}

/* Measured speed-up of the whole pipeline from 1 to 2 threads is 1.2-1.4 (docs/benchmarks.md
 * section 1): time ~ threads^-0.4 around the calibration's 2 threads. */
static double thread_factor(int threads)
{
    return pow(2.0 / (threads > 0 ? threads : 1), 0.4);
}

/* Disk per item, MB = a + b * N (work folder; published folder), octree at 0.1-1 M with
 * fidelity off (plan_calibrate.py); a from the bundled scans (thumbnails, pages). */
static const double work_mb[2] = {1, 760}, published_mb[2] = {1.4, 325};

struct sl_engine_plan {
    FILE *out;
    sl_json *json;
    int threads;
    uint64_t items, errors;
    double total_seconds, peak_mb, work_mb, published_mb;
};

static int effective_threads(const sl_engine *e)
{
    if (e->threads > 0)
        return e->threads;
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

int sl_engine_plan_item(sl_engine *e, const char *rel, const char *unreadable)
{
    struct sl_engine_plan *p = e->plan;
    char full[PATH_MAX];
    sl_ply_info info;
    sl_error err;
    sl_error_init(&err);
    int rc = -1;
    if (unreadable)
        sl_error_set(&err, SL_E_BADINPUT, 0, rel, "%s", unreadable);
    else if (sl_engine_path(full, sizeof full, "%s/%s", e->input, rel))
        sl_error_set(&err, SL_E_BADINPUT, 0, rel, "path too long");
    else
        rc = sl_ply_read_info(full, NULL, &info, &err);
    p->items++;
    if (rc != 0) {
        char line[1400];
        sl_error_format(&err, line, sizeof line);
        p->errors++;
        if (p->json) {
            sl_json_object_begin(p->json, NULL);
            sl_json_string(p->json, "item", rel);
            sl_json_string(p->json, "error", line);
            sl_json_object_end(p->json);
        } else {
            fprintf(p->out, "%-32s cannot be planned: %s\n", rel, line);
        }
        return 0; /* one bad scan never stops the plan; the exit code says so */
    }
    int points = info.declared_faces == 0;
    double n = (double)(points ? info.declared_vertices : info.declared_faces) / 1e6;
    double tf = thread_factor(p->threads), seconds = 0, peak = 0;
    int fidelity = sl_config_bool(e->cfg, "export", "fidelity");
    if (p->json) {
        sl_json_object_begin(p->json, NULL);
        sl_json_string(p->json, "item", rel);
        sl_json_u64(p->json, "vertices", info.declared_vertices);
        sl_json_u64(p->json, "triangles", info.declared_faces);
        sl_json_string(p->json, "basis", points ? "points" : "triangles");
        sl_json_object_begin(p->json, "stages");
    }
    for (int s = 0; s < e->stage_count; s++) {
        const char *name = e->stages[s]->name;
        const stage_cost *c = cost_of(!strcmp(name, "export") && fidelity ? "export+fidelity"
                                                                            : name);
        if (!c)
            continue; /* a stage the model has not been fitted for: costs nothing here */
        double t = (c->a + c->b * pow(n, c->e)) * tf, m = c->c + c->d * pow(n, c->f);
        seconds += t;
        peak = m > peak ? m : peak;
        if (p->json) {
            sl_json_object_begin(p->json, name);
            sl_json_double(p->json, "seconds", t);
            sl_json_double(p->json, "peak_rss_mb", m);
            sl_json_object_end(p->json);
        }
    }
    double work = work_mb[0] + work_mb[1] * n, published = published_mb[0] + published_mb[1] * n;
    int fits = e->memory_limit_mb <= 0 || peak <= (double)e->memory_limit_mb;
    if (p->json) {
        sl_json_object_end(p->json);
        sl_json_double(p->json, "peak_rss_mb", peak);
        sl_json_double(p->json, "seconds", seconds);
        sl_json_double(p->json, "work_mb", work);
        sl_json_double(p->json, "published_mb", published);
        sl_json_bool(p->json, "fits_memory_limit", fits);
        sl_json_object_end(p->json);
    } else {
        fprintf(p->out, "%-32s %12llu %-9s %9.0f %9.1f %9.0f %9.0f%s\n", rel,
                (unsigned long long)(points ? info.declared_vertices : info.declared_faces),
                points ? "points" : "triangles", peak, seconds, work, published,
                fits ? "" : "  over [run] memory_limit_mb");
    }
    p->total_seconds += seconds;
    p->work_mb += work;
    p->published_mb += published;
    if (peak > p->peak_mb)
        p->peak_mb = peak;
    return 0;
}

int sl_engine_plan(sl_engine *e, FILE *out, int json, uint64_t *unplanned, sl_error *err)
{
    struct sl_engine_plan p = {.out = out, .threads = effective_threads(e)};
    sl_json j;
    if (json) {
        sl_json_init(&j, 1);
        p.json = &j;
        sl_json_object_begin(&j, NULL);
        sl_json_string(&j, "method", sl_config_string(e->cfg, "lod", "method"));
        sl_json_i64(&j, "threads", p.threads);
        sl_json_i64(&j, "memory_limit_mb", e->memory_limit_mb);
        sl_json_array_begin(&j, "items");
    } else {
        fprintf(out, "method %s, %d threads; per item: peak memory, time, disk\n",
                sl_config_string(e->cfg, "lod", "method"), p.threads);
        fprintf(out, "%-32s %12s %-9s %9s %9s %9s %9s\n", "item", "count", "of",
                "peak MB", "time s", "work MB", "publ. MB");
    }
    e->plan = &p;
    int rc = sl_engine_walk_input(e, err);
    e->plan = NULL;
    if (json) {
        sl_json_array_end(&j);
        sl_json_object_begin(&j, "totals");
        sl_json_u64(&j, "items", p.items);
        sl_json_u64(&j, "errors", p.errors);
        sl_json_double(&j, "peak_rss_mb", p.peak_mb);
        sl_json_double(&j, "seconds", p.total_seconds);
        sl_json_double(&j, "work_mb", p.work_mb);
        sl_json_double(&j, "published_mb", p.published_mb);
        sl_json_object_end(&j);
        sl_json_object_end(&j);
        if (rc == 0)
            fprintf(out, "%s\n", sl_json_text(&j));
        sl_json_release(&j);
    } else if (rc == 0) {
        fprintf(out, "collection: %llu items (%llu cannot be planned), largest peak %.0f MB, "
                     "%.0f s one after another, disk %.0f MB work + %.0f MB published\n",
                (unsigned long long)p.items, (unsigned long long)p.errors, p.peak_mb,
                p.total_seconds, p.work_mb, p.published_mb);
    }
    *unplanned = p.errors;
    return rc;
}
