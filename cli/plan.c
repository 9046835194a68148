/* `scanlod plan`: a pre-flight estimate per item of the collection (peak memory, time,
 * disk) from each scan's header (sl_scan_read_info: a PLY's or OFF's counts, a glTF's
 * accessors, a quick count of a text format's lines) and the config, so a scheduler can ask
 * for the right node before anything runs (issue 14). The engine walks the input as its scan would
 * (sl_engine_each_item); reading headers and costing stages is the command's business,
 * so the engine stays below geometry/ and knows no stage by name.
 *
 * The estimate is a cost model, not a trial run: every stage of the item's method costs
 * time a + b * N^e and peak memory c + d * N^f, with N the input's triangles in millions
 * (its points for a point cloud), coefficients fitted on this project's own runs at 2
 * threads (scripts/bench/plan_calibrate.py; docs/cluster.md "Asking for the right node"),
 * N scaled for the octree stages by what the scan's geometry says about its samples
 * (cli/plan_shape.h: a mesh is read once, in a child process).
 * Stages are separate child processes, so the item's peak is the largest stage's and its
 * time their sum. The benchmark's growth and shapes phases print the plan beside what the
 * run measured, so a drift of the model shows up in docs/benchmarks.md.
 */
#include "cli/plan.h"
#include "cli/plan_shape.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/json.h"
#include "core/memory.h"
#include "formats/scan_read.h"
#include "pipeline/stage.h"
#include "stages/refine/refine.h"

/* Cost of one stage, N in millions: seconds = a + b * N^e, peak RSS MB = c + d * N^f.
 * An octree stage's work follows its samples, not its triangles (cli/plan_shape.h): for
 * it N is the triangles times the shape's ratio (samples per triangle against the
 * calibration tori's), and its memory's N that again times 1 + k * the shape's scattered
 * share; the export's memory follows its samples for a part (the model it cuts) and its
 * triangles for the rest (the levels it writes are capped at the input's count). */
typedef struct stage_cost {
    const char *stage;     /* [METHOD:]STAGE[+fidelity]: +fidelity is the export measuring
                              its levels, METHOD: a method's own cost for a shared stage */
    double a, b, e, c, d, f;
    double k;              /* octree stages: memory per sample of a soup's scattered band
                              against a surface's, minus 1 */
    double share;          /* the part of d that follows the samples: 0 for a stage whose
                              work follows its input (range, other methods' stages) */
} stage_cost;

/* Octree stages: time from the growth benchmark on a quiet machine (1, 5 and 20 M
 * triangles, docs/benchmarks.md section 4; a from the bundled scans), memory from
 * plan_calibrate.py at 0.1, 0.3 and 1 M with the growth's 5 and 20 M peaks setting the
 * exponent. docs/cluster.md has the fit and the residuals. The constants c are lower
 * than fitted since OpenImageIO loads on demand (shim/oiio_loader.c): a stage without
 * images no longer maps its libraries (rocker_arm per stage, before -> after: range
 * 46 -> 6, samples 66 -> 16, merge 81 -> 30, priority 55 -> 14, crack 87 -> 46 MB);
 * samples, merge and crack are set to rocker_arm's measured peaks without thumbnails
 * (18, 33, 44 MB). The export adds IMAGES_MB when it draws thumbnails, since it loads
 * OpenImageIO then (rocker_arm's export: 126 MB with them, 22 without). The crack and
 * export memory lines were refitted when their peaks fell (docs/benchmarks.md section 7:
 * the transition records of internal nodes only, a model opened for cutting): crack
 * 33.8 / 362 / 1,796 MB and export (without images) 17.4 / 315 / 1,463 MB at rocker_arm,
 * 1 M and 5 M; then again when the export began cutting a level ahead of its writes
 * (docs/threads.md "The export's two lanes"): 371 / 1,652 MB without images at 1 M and
 * 5 M, time x 0.8 (5.7-6.3 vs 7.2-7.5 s at 1 M, 30.3 vs 38.9 s at 5 M, the same
 * machine; with fidelity x 0.95, 15.4 vs 14.6 s at 1 M). The priority line was refitted
 * when it stopped building the leaves' neighbours (0.76 / 4.2 s, 171 / 838 MB at 1 and
 * 5 M), and the merge line when its quadric slots were zeroed before the sums (3.0 / 18.0
 * s, 379 / 1,736 MB at 1 and 5 M; the line before predicted 1.4 s and 255 MB at 1 M, from
 * before quadric vertices were the default; its memory again when the colour sums left the
 * quadrics: 329 / 1,530 MB), and the crack line at zstd level 6 (3.8 / 19.9
 * s, 310 / 1,313 MB at 1 and 5 M), and the export's memory when a model opened for
 * cutting let go of its nodes, Morton keys, expansion indices and transition bases after
 * laying out its cells (400-409 / 1,433 MB with images at 1 and 5 M, 467 / 1,711 before).
 * The merge line again when its quadric vertices were built by bricks and its octree build
 * stopped holding the samples and a copy of the leaves (docs/bricks.md; growth benchmark
 * 2026-12-05: 194 / 813 / 3,065 MB at 1, 5 and 20 M; time x 0.8, the build after against
 * the build before on one machine: 0.75 / 0.73 / 0.96 at 1 / 5 / 20 M), and the crack's
 * memory when it dropped the node metrics and its layout early (251 / 1,230 / 4,828 MB);
 * their constants c set again to rocker_arm's peaks without thumbnails (merge 24, crack
 * 23 MB; 3 runs). The crack's memory again when it stopped laying out the model for
 * generation (188 / 865 / 3,449 MB at 1, 5 and 20 M, 2026-12-07; d through the three).
 * The samples' memory by its peaks at 5, 20 and 100 M (708 / 2,818 / 13,842 MB, 141.6 /
 * 140.9 / 138.4 bytes per triangle, 2026-12-08: the first 100 M run; the line had f 0.95
 * and said 10,580 MB at 100 M): f 1.0, d 139. The range's the same way (476 / 1,893 /
 * 9,446 MB, 95.2 / 94.7 / 94.5 bytes per triangle; the line said 7,472 at 100 M): f 1.0,
 * d 94.5.
 * Refit with scripts/bench/plan_calibrate.py.
 * The octree stages' lines hold for surfaces of about 1.56 samples per triangle (the
 * tori; real scans 1.2-2.2); for slivers and soups, whose samples per triangle are many
 * times that, N is scaled by the shape (cli/plan_shape.h; issue 34: 500k slivers planned
 * at 267 MB ran at 2,225 MiB). k and share fitted on gen_surface's slivers (--aspect 16;
 * they cost what a torus of as many samples costs, but the export's levels stay capped at
 * the input's count: share 0.85) and soups (--soup, 5k-80k triangles: their bands are all
 * border, with many sign changes, so merge, priority and crack cost 1.6-2x per sample, the
 * samples stage a third), by plan_calibrate.py --shapes; the peaks then within 0.85-1.27 of
 * the runs at 20k-500k slivers and 5k-80k soups (docs/benchmarks.md section 4b). */
#define IMAGES_MB 110.0
static const stage_cost mesh_costs[] = {
    {"range", 0.014, 0.403, 1.081, 5, 94.5, 1.0, 0, 0},
    {"samples", 0.105, 2.42, 1.047, 15, 139, 1.0, -0.65, 1},
    {"merge", 0.078, 2.34, 1.13, 20, 167, 0.963, 0.6, 1},
    {"priority", 0.107, 0.65, 1.14, 7, 164, 1.0, 0.6, 1},
    {"crack", 0.117, 3.7, 1.04, 18, 171, 1.0, 1.0, 1},
    /* The export's lines refitted on tori of 1, 5 and 20 M (2 threads, one run each,
     * 2026-12-07, fidelity on and off; the 20 M export had never been measured with
     * fidelity): peaks with thumbnails 314 / 1,016 / 3,532 MB on, 207 / 585 / 1,753 MB
     * off (the line before said 405 / 1,332 / 5,060 MB for both); times 19.0 / 76.7 / 223
     * s on, 3.5 / 13.6 / 62-77 s off, on a machine 1.3 times slower than the calibration's
     * (the whole 20 M run 578 s against 442 the day before), so fitted to them / 1.3. */
    {"export", 0.3, 2.4, 1.1, 8, 100, 0.95, 0.6, 0.85},
    {"export+fidelity", 1.5, 13.5, 0.82, 8, 198, 0.95, 0.6, 0.85},
    /* The refine stage (every method's levels to their counts, docs/levels.md): its work
     * follows the input's triangles (the scan's collapses and the fit's samples), not the
     * octree's samples. plan_calibrate.py --methods best at 20k, 100k, 300k and 1 M (tori,
     * 2 threads, a loaded machine, 2026-12-06): before this line the plan said 0.09-0.26
     * of the measured time and 0.44 of the peak at 1 M, the refine stage's. Refitted when
     * levels within [refine] fit_floor stopped being fitted, the measure's input side was
     * made once, the fits borrowed its tree and an outranked octree cut stayed uncollapsed
     * (issue 38): tori of 0.1, 0.3, 1 and 5 M, 2 threads, one run each on a quiet machine,
     * 2026-12-07: 9.3 / 13.2 / 21.0 / 71.6 s, 100 / 207 / 461 / 1,956 MB (at 1 M before:
     * 76.1 s, 923 MB); then the growth benchmark's 1, 5 and 20 M (21.3 / 58.8 / 266 s,
     * 461 / 1,956 / 7,594 MB; docs/benchmarks.md section 4; 380 bytes per input triangle
     * at 20 M), and rocker_arm's 33 MB (20k): time fitted, within 0.92-1.11 of the five
     * tori; memory the least largest error over all six, within 0.88-1.14. Refitted when
     * a scan's top levels stopped getting octree candidates and the model came to be read
     * by prefixes (issue 38; tori of 1, 5 and 20 M and rocker_arm, 2 threads, one run
     * each, 2026-12-07: 18.3 / 46.6 / 149 / 4.2 s, 398 / 1,501 / 5,316 / 25.4 MB; the line
     * before said 19.7 / 66 / 248 / 9.3 s and 524 / 2,036 / 6,663 / 35.6 MB): time within
     * 0.9-1.15, memory 0.96-1.04. */
    {"refine", 4.0, 14.3, 0.773, 12, 386, 0.861, 0, 0},
    /* The refine stage when its collapses go by bricks ([refine] collapse_brick_triangles;
     * by default when the input's triangles times 300 bytes are over the memory budget,
     * sl_refine_collapse_bricks), bricks of 1 M: tori of 5 and 20 M, 2 threads, one run
     * each, 2026-12-07 (docs/bricks.md): 67.2 / 243.7 s, 1,310 / 4,377 MB (whole on the
     * same machine: 57.0 / 207-270 s, 1,318 / 5,140-5,222 MB). Memory through the two,
     * time the whole line's times 1.2. Only large inputs take this line: under a 24 GB
     * budget those above 84 M triangles. */
    {"refine+bricks", 4.0, 17.2, 0.773, 12, 320, 0.87, 0, 0},
    /* The segment and cluster methods: scripts/bench/bench_methods_scale.sh at 0.1, 0.3, 1
     * and 5 M triangles (tori, 2 threads, quiet, 2026-12-07; issue 38), each line the least
     * largest error over the four (segment: 5.4 / 14.4 / 82.7 / 344 s, 33 / 94 / 259 /
     * 1,211 MB, within 0.77-1.19 and 0.96-1.04; cluster: 1.7 / 6.5 / 23.3 / 87.0 s, 37 /
     * 117 / 291 / 1,345 MB, within 0.83-1.19 and 0.91-1.11). The lines before (30k-200k on
     * a loaded machine) said 3.5-4.8 times segment's time at 1 and 5 M, and 1.4 times the
     * peak of either. Their refine stage has one candidate per rung (no scan chain, no
     * octree cut): its own lines, fitted alike on both methods (within 0.82-1.21 of the
     * eight times, 0.93-1.07 of the four peaks). Their export writes levels from a level
     * list, not a model, hence its own lines; with fidelity (the default) refitted on the
     * same runs: 0.71-1.37 of the eight times, 1.01-1.07 of the peaks with IMAGES_MB. */
    {"segment", 0, 63.5, 1.16, 0.9, 268.7, 0.91, 0, 0},
    {"cluster", 0, 19.4, 1.04, 0, 303.3, 0.87, 0, 0},
    {"segment:refine", 0, 16.0, 0.58, 57.2, 285.7, 0.94, 0, 0},
    {"cluster:refine", 0, 16.0, 0.58, 57.2, 285.7, 0.94, 0, 0},
    {"segment:export", 0.45, 3.2, 1.0, 18, 160, 1.0, 0, 0},
    {"segment:export+fidelity", 1.43, 4.9, 0.80, 0, 235.4, 0.91, 0, 0},
    {"cluster:export", 0.45, 3.2, 1.0, 18, 160, 1.0, 0, 0},
    {"cluster:export+fidelity", 1.43, 4.9, 0.80, 0, 235.4, 0.91, 0, 0},
};

static const stage_cost *find_cost(const char *key)
{
    for (size_t i = 0; i < sizeof mesh_costs / sizeof mesh_costs[0]; i++)
        if (!strcmp(mesh_costs[i].stage, key))
            return &mesh_costs[i];
    return NULL;
}

/* The method's own line for the stage ("segment:export") if it has one, else the stage's;
 * `bricks`: the refine stage's collapses go by bricks. */
static const stage_cost *cost_of(const char *method, const char *stage, int fidelity,
                                 int bricks)
{
    char key[96];
    const char *suffix = fidelity && !strcmp(stage, "export")  ? "+fidelity"
                         : bricks && !strcmp(stage, "refine") ? "+bricks"
                                                              : "";
    snprintf(key, sizeof key, "%s:%s%s", method, stage, suffix);
    const stage_cost *c = find_cost(key);
    if (!c) {
        snprintf(key, sizeof key, "%s%s", stage, suffix);
        c = find_cost(key);
    }
    return c;
}

/* Measured speed-up of the whole pipeline from 1 to 2 threads is 1.2-1.4 (docs/benchmarks.md
 * section 1): time ~ threads^-0.4 around the calibration's 2 threads. */
static double thread_factor(int threads)
{
    return pow(2.0 / (threads > 0 ? threads : 1), 0.4);
}

/* Disk per item, MB = a + b * N (work folder; published folder): b from the growth
 * benchmark's 1/5/20 M surfaces on model format 3 (work 378-407, published 106-134 MB per
 * million triangles, default ladder, fidelity off; docs/benchmarks.md section 4), a from
 * the bundled scans (thumbnails, pages); the work's b again when priority.slpri lost the
 * leaves' neighbour links (format 2): 276 and 1,280 MB at 1 and 5 M; both again with the
 * refine stage's level files in the work folder (growth benchmark 2026-12-07: work 375 /
 * 1,729 / 6,759 MB, published 135 / 578 / 2,194 MB at 1, 5 and 20 M). */
static const double work_mb[2] = {39, 336}, published_mb[2] = {27, 108};

typedef struct plan_state {
    FILE *out;
    const sl_engine *engine;
    sl_json *json;
    sl_engine_facts facts;
    uint64_t items, errors;
    double total_seconds, peak_mb, work_mb, published_mb;
} plan_state;

/* The item's stages costed from its header and shape: the sum of their times and the
 * largest peak (and which stage has it, when `peak_stage` is given); each stage into
 * `json` when it is not NULL. */
static void stage_costs(const sl_engine_facts *e, const sl_scan_info *info,
                        const sl_plan_shape *shape, sl_json *json, double *seconds, double *peak,
                        const char **peak_stage)
{
    int points = info->declared_faces == 0;
    double n = (double)(points ? info->declared_vertices : info->declared_faces) / 1e6;
    double tf = thread_factor(e->threads);
    int fidelity = sl_config_bool(e->cfg, "export", "fidelity");
    int thumbnails = sl_config_int(e->cfg, "export", "thumbnail_size") > 0;
    /* The refine stage's collapses by bricks when its rule says so for this input and
     * budget (the stage asks the same function with its own count and budget). */
    uint64_t budget = sl_memory_budget_mb(e->memory_limit_mb, NULL, 0);
    uint64_t brick = sl_refine_collapse_bricks(
        sl_config_int(e->cfg, "refine", "collapse_brick_triangles"), points ? 0 : n * 1e6, budget);
    int bricks = brick > 0 && n * 1e6 > (double)brick;
    *seconds = *peak = 0;
    for (int s = 0; s < e->stage_count; s++) {
        const char *name = e->stages[s]->name;
        const stage_cost *c = cost_of(e->method, name, fidelity, bricks);
        if (!c)
            continue; /* a stage the model has not been fitted for: costs nothing here */
        double nt = c->share > 0 ? n * shape->ratio : n;
        double nm = nt * (1 + c->k * shape->scattered);
        double t = (c->a + c->b * pow(nt, c->e)) * tf;
        double m = c->c + c->d * (c->share * pow(nm, c->f) + (1 - c->share) * pow(n, c->f));
        if (!strcmp(name, "export") && thumbnails)
            m += IMAGES_MB;
        *seconds += t;
        if (m > *peak && peak_stage)
            *peak_stage = name;
        *peak = m > *peak ? m : *peak;
        if (json) {
            sl_json_object_begin(json, name);
            sl_json_double(json, "seconds", t);
            sl_json_double(json, "peak_rss_mb", m);
            sl_json_object_end(json);
        }
    }
}

/* The item's shape, measured in a child process: a hostile file can then cost the plan
 * (and the engine's admission, which runs in the run's own process) neither its memory
 * nor its life; a child that fails leaves the header's estimate. */
static void measure_shape(const sl_engine_facts *e, const char *path, const sl_scan_info *info,
                          sl_plan_shape *out)
{
    memset(out, 0, sizeof *out);
    out->ratio = 1;
    int fds[2];
    if (pipe(fds) != 0)
        return;
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        close(fds[0]);
        sl_plan_shape shape;
        sl_plan_shape_of(path, info, e->stages, e->stage_count, e->cfg, &shape);
        _exit(write(fds[1], &shape, sizeof shape) == (ssize_t)sizeof shape ? 0 : 1);
    }
    close(fds[1]);
    sl_plan_shape shape;
    ssize_t got = pid > 0 ? read(fds[0], &shape, sizeof shape) : -1;
    close(fds[0]);
    int status = 0;
    while (pid > 0 && waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (got == (ssize_t)sizeof shape && WIFEXITED(status) && WEXITSTATUS(status) == 0)
        *out = shape;
}

/* The item's shape, measured once per file version: the engine's admission asks before
 * each of an item's stages, and measuring costs about the range stage's time. */
#define SHAPE_CACHE 64
static void shape_of(const sl_engine_facts *e, const char *path, const sl_scan_info *info,
                     sl_plan_shape *out)
{
    static struct {
        char path[PATH_MAX];
        struct stat st;
        sl_plan_shape shape;
    } cache[SHAPE_CACHE];
    static unsigned next;
    struct stat st;
    if (stat(path, &st) != 0) {
        measure_shape(e, path, info, out);
        return;
    }
    for (int i = 0; i < SHAPE_CACHE; i++)
        if (!strcmp(cache[i].path, path) && st.st_dev == cache[i].st.st_dev &&
            st.st_ino == cache[i].st.st_ino && st.st_size == cache[i].st.st_size &&
            st.st_mtim.tv_sec == cache[i].st.st_mtim.tv_sec &&
            st.st_mtim.tv_nsec == cache[i].st.st_mtim.tv_nsec) {
            *out = cache[i].shape;
            return;
        }
    measure_shape(e, path, info, out);
    unsigned slot = next++ % SHAPE_CACHE;
    snprintf(cache[slot].path, sizeof cache[slot].path, "%s", path);
    cache[slot].st = st;
    cache[slot].shape = *out;
}

double sl_plan_peak_mb(const sl_engine_facts *facts, const char *path, const char **stage)
{
    sl_scan_info info;
    sl_error err;
    sl_error_init(&err);
    if (sl_scan_read_info(path, NULL, &info, &err) != 0)
        return 0; /* the range stage says what is wrong with it */
    double seconds, peak;
    sl_plan_shape shape;
    shape_of(facts, path, &info, &shape);
    stage_costs(facts, &info, &shape, NULL, &seconds, &peak, stage);
    return peak;
}

static void plan_item(void *ctx, const char *rel, const char *path, const char *unreadable)
{
    plan_state *p = ctx;
    const sl_engine_facts *e = &p->facts;
    sl_scan_info info;
    sl_error err;
    sl_error_init(&err);
    int rc = -1;
    if (unreadable)
        sl_error_set(&err, SL_E_BADINPUT, 0, path, "%s", unreadable);
    else
        rc = sl_scan_read_info(path, NULL, &info, &err);
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
        return; /* one bad scan never stops the plan; the exit code says so */
    }
    int points = info.declared_faces == 0;
    double n = (double)(points ? info.declared_vertices : info.declared_faces) / 1e6;
    if (p->json) {
        sl_json_object_begin(p->json, NULL);
        sl_json_string(p->json, "item", rel);
        sl_json_u64(p->json, "vertices", info.declared_vertices);
        sl_json_u64(p->json, "triangles", info.declared_faces);
        sl_json_string(p->json, "basis", points ? "points" : "triangles");
        sl_json_object_begin(p->json, "stages");
    }
    double seconds = 0, peak = 0;
    sl_plan_shape shape;
    shape_of(e, path, &info, &shape);
    stage_costs(e, &info, &shape, p->json, &seconds, &peak, NULL);
    double work = work_mb[0] + work_mb[1] * n, published = published_mb[0] + published_mb[1] * n;
    int fits = e->memory_limit_mb <= 0 || peak <= (double)e->memory_limit_mb;
    /* Work items below the item ([queue] part_mb): what a scheduler can spread. */
    int samples_parts = sl_engine_stage_parts(p->engine, "samples", rel);
    if (p->json) {
        sl_json_object_end(p->json);
        if (samples_parts > 1) {
            sl_json_object_begin(p->json, "parts");
            sl_json_u64(p->json, "samples", (uint64_t)samples_parts);
            sl_json_object_end(p->json);
        }
        if (shape.read) { /* what the geometry said (cli/plan_shape.h) */
            sl_json_object_begin(p->json, "shape");
            sl_json_double(p->json, "leaf_size", shape.leaf);
            sl_json_double(p->json, "samples", shape.samples);
            sl_json_double(p->json, "samples_ratio", shape.ratio);
            sl_json_double(p->json, "scattered", shape.scattered);
            sl_json_object_end(p->json);
        }
        sl_json_double(p->json, "peak_rss_mb", peak);
        sl_json_double(p->json, "seconds", seconds);
        sl_json_double(p->json, "work_mb", work);
        sl_json_double(p->json, "published_mb", published);
        sl_json_bool(p->json, "fits_memory_limit", fits);
        sl_json_object_end(p->json);
    } else {
        char parts_note[48] = "", shape_note[80] = "";
        if (samples_parts > 1)
            snprintf(parts_note, sizeof parts_note, "  samples in %d parts", samples_parts);
        /* Why a small scan plans big: slivers, a soup (cli/plan_shape.h). */
        if (shape.ratio >= 2)
            snprintf(shape_note, sizeof shape_note, "  %.1fx the samples of a smooth surface",
                     shape.ratio);
        fprintf(p->out, "%-32s %12llu %-9s %9.0f %9.1f %9.0f %9.0f%s%s%s\n", rel,
                (unsigned long long)(points ? info.declared_vertices : info.declared_faces),
                points ? "points" : "triangles", peak, seconds, work, published,
                fits ? "" : "  over [run] memory_limit_mb", parts_note, shape_note);
    }
    p->total_seconds += seconds;
    p->work_mb += work;
    p->published_mb += published;
    if (peak > p->peak_mb)
        p->peak_mb = peak;
}

int sl_plan_print(sl_engine *engine, FILE *out, int json, uint64_t *unplanned, sl_error *err)
{
    plan_state p = {.out = out, .engine = engine};
    sl_engine_facts_of(engine, &p.facts);
    const sl_engine_facts *e = &p.facts;
    sl_json j;
    if (json) {
        sl_json_init(&j, 1);
        p.json = &j;
        sl_json_object_begin(&j, NULL);
        sl_json_string(&j, "method", e->method);
        sl_json_i64(&j, "threads", e->threads);
        sl_json_i64(&j, "memory_limit_mb", e->memory_limit_mb);
        sl_json_array_begin(&j, "items");
    } else {
        fprintf(out, "method %s, %d threads; per item: peak memory, time, disk\n",
                e->method, e->threads);
        fprintf(out, "%-32s %12s %-9s %9s %9s %9s %9s\n", "item", "count", "of",
                "peak MB", "time s", "work MB", "publ. MB");
    }
    int rc = sl_engine_each_item(engine, plan_item, &p, err);
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
