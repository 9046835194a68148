/* Transition cells drawn at load (docs/lod.md "Generation cost"): for every state of every
 * split list, the cell's triangles as crossing ids, so extraction copies them.
 *
 * A state is a frontier cell between two expansions of its same-level neighbours; its
 * drawing takes the finer points from the cell's transition record (the crack
 * compensation points) and the face-rule triangulation of its configuration, each
 * distinct configuration triangulated once per thread (runtime/mc_cache.c).
 */
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_dual.h"
#include "runtime/lod_model.h"
#include "runtime/lod_splits.h"
#include "runtime/mc_cache.h"

/* A growing run of drawings (one chunk of cells' worth), and in a dual model the extra
 * vertices its drawings name (as EXTRA_REF | index in the run until they are placed). */
typedef struct drawing_run {
    uint32_t *words;
    uint64_t count, capacity;
    float *extra_position;
    uint8_t *extra_color;
    uint32_t extras, extra_capacity;
} drawing_run;

#define EXTRA_REF 0x80000000u

/* A finished run down to its size: the runs grow by doubling, and all of them are held
 * while split_drawings is filled from them (at 1 M triangles 39 MB of runs for 24 MB of
 * drawings, the crack stage's peak). */
static void run_trim(drawing_run *run)
{
    if (run->words && run->count < run->capacity) {
        uint32_t *words = realloc(run->words, (size_t)(run->count ? run->count : 1) * sizeof *words);
        if (words) {
            run->words = words;
            run->capacity = run->count ? run->count : 1;
        }
    }
}

static int run_reserve(drawing_run *run, uint64_t size)
{
    if (run->count + size <= run->capacity)
        return 0;
    uint64_t grown = run->capacity ? 2 * run->capacity : 1024;
    while (grown < run->count + size)
        grown *= 2;
    uint32_t *words = realloc(run->words, (size_t)grown * sizeof *words);
    if (!words)
        return -1;
    run->words = words;
    run->capacity = grown;
    return 0;
}

/* A vertex at the centroid of a loop's crossings, in the run; its reference. */
static int add_extra(drawing_run *run, const sl_octree *t, const uint32_t *ids, int n,
                     uint32_t *ref)
{
    if (run->extras == run->extra_capacity) {
        uint32_t cap = run->extra_capacity ? 2 * run->extra_capacity : 64;
        float *p = realloc(run->extra_position, (size_t)cap * 3 * sizeof *p);
        if (p)
            run->extra_position = p;
        uint8_t *c = t->crossing_color ? realloc(run->extra_color, (size_t)cap * 4) : NULL;
        if (c)
            run->extra_color = c;
        if (!p || (t->crossing_color && !c))
            return -1;
        run->extra_capacity = cap;
    }
    double sum[3] = {0, 0, 0}, col[4] = {0, 0, 0, 0};
    for (int i = 0; i < n; i++)
        for (int a = 0; a < 4; a++) {
            if (a < 3)
                sum[a] += t->crossing_position[3 * (size_t)ids[i] + a];
            if (t->crossing_color)
                col[a] += t->crossing_color[4 * (size_t)ids[i] + a];
        }
    uint32_t e = run->extras++;
    for (int a = 0; a < 3; a++)
        run->extra_position[3 * (size_t)e + a] = (float)(sum[a] / n);
    if (t->crossing_color)
        for (int a = 0; a < 4; a++)
            run->extra_color[4 * (size_t)e + a] = (uint8_t)(col[a] / n + 0.5);
    *ref = EXTRA_REF | e;
    return 0;
}

/* Appends a dual model's state drawing: the cell's drawn loops, each with its vertex. */
static int append_loops(drawing_run *run, const sl_lod_model *m, const sl_lod_cell_ref *c,
                        const sl_mc_cell *cell, int crack,
                        const uint32_t point_crossing[SL_MC_MAX_POINTS], uint32_t *offset)
{
    sl_mc_triangles tri;
    sl_dual_loops(cell, &tri);
    uint32_t node = m->cell_node[c - m->cells], vertex[SL_MC_MAX_LOOPS];
    sl_dual_loop_vertices(&m->tree, node, &tri, point_crossing, vertex);
    uint64_t size = 1;
    for (int l = 0; l < tri.loops; l++)
        if (vertex[l] != SL_DUAL_NOT_DRAWN)
            size += 2 + tri.loop_sizes[l];
    if (run_reserve(run, size))
        return -1;
    uint32_t at = (uint32_t)run->count, loops = 0;
    uint32_t *out = run->words + at + 1;
    for (int l = 0; l < tri.loops; l++) {
        if (vertex[l] == SL_DUAL_NOT_DRAWN)
            continue;
        uint32_t ids[SL_MC_MAX_POINTS];
        for (int i = 0; i < tri.loop_sizes[l]; i++)
            ids[i] = point_crossing[tri.loop_points[l][i]];
        if (vertex[l] == SL_DUAL_EXTRA && add_extra(run, &m->tree, ids, tri.loop_sizes[l], &vertex[l]))
            return -1;
        *out++ = tri.loop_sizes[l];
        *out++ = vertex[l];
        memcpy(out, ids, tri.loop_sizes[l] * sizeof *ids);
        out += tri.loop_sizes[l];
        loops++;
    }
    run->words[at] = loops | (uint32_t)(crack ? 1 : 0) << 8;
    *offset = at;
    run->count += size;
    return 0;
}

/* Appends a transition cell's drawing to the run; *offset = its place in the run. */
static int append_drawing(drawing_run *run, const sl_mc_cached *t, int crack,
                          const uint32_t point_crossing[SL_MC_MAX_POINTS], uint32_t *offset)
{
    uint64_t size = 1 + 3 * (uint64_t)t->count;
    if (run_reserve(run, size))
        return -1;
    uint32_t *out = run->words + run->count;
    out[0] = t->count | (uint32_t)(crack ? 1 : 0) << 8;
    for (int i = 0; i < 3 * t->count; i++)
        out[1 + i] = point_crossing[(&t->points[0][0])[i]];
    *offset = (uint32_t)run->count;
    run->count += size;
    return 0;
}

/* Draws every state of the split lists of cells [from, to) into the run (offsets relative
 * to the run), triangulating through `configs`. */
static int draw_chunk(sl_lod_model *m, sl_mc_cache *configs, uint32_t from, uint32_t to,
                      drawing_run *run)
{
    const sl_lod_split_table *st = sl_lod_split_table_get();
    for (uint32_t pos = from; pos < to; pos++) {
        const sl_lod_cell_ref *c = &m->cells[pos];
        if (c->splits == SL_OCTREE_NONE || !c->draws)
            continue;
        /* Its state when it appears, and after each event. */
        const uint32_t *w = m->split_words + c->splits;
        for (uint32_t i = 0; i <= w[1] >> 24; i++) {
            uint32_t k = i == 0 ? sl_lod_first_frontier(m, pos) : w[3 * i] + 1u;
            sl_mc_cell cell;
            uint32_t point_crossing[SL_MC_MAX_POINTS], *entry, id;
            int crack = sl_lod_frontier_cell(m, k, c, st, &cell, point_crossing, &entry);
            if (!entry)
                continue;
            if (m->dual_position) {
                if (append_loops(run, m, c, &cell, crack, point_crossing, entry))
                    return -1;
                continue;
            }
            if (sl_mc_cache_add(configs, &cell, &id) ||
                (id != SL_MC_CACHE_NONE &&
                 append_drawing(run, sl_mc_cache_entry(configs, id), crack, point_crossing, entry)))
                return -1;
            if (run->count >= SL_OCTREE_NONE)
                return -1;
        }
    }
    return 0;
}

#define DRAW_CHUNKS 256 /* fixed, so the result does not depend on the thread count */

static uint32_t chunk_start(uint32_t end, int chunk)
{
    return (uint32_t)((uint64_t)end * (uint64_t)chunk / DRAW_CHUNKS);
}

/* Calls fn(m, entry, start, arg) for every state word of the split lists of cells [from, to)
 * that names a drawing; start = the k at which the state begins. */
static void for_each_drawn_state(sl_lod_model *m, uint32_t from, uint32_t to,
                                 void (*fn)(uint32_t *entry, uint32_t start, void *arg),
                                 void *arg)
{
    for (uint32_t pos = from; pos < to; pos++) {
        const sl_lod_cell_ref *c = &m->cells[pos];
        if (c->splits == SL_OCTREE_NONE)
            continue;
        uint32_t *w = m->split_words + c->splits;
        for (uint32_t i = 0; i <= w[1] >> 24; i++)
            if (w[2 + 3 * i] != SL_OCTREE_NONE)
                fn(w + 2 + 3 * i, i == 0 ? sl_lod_first_frontier(m, pos) : w[3 * i] + 1u, arg);
    }
}

static void forget(uint32_t *entry, uint32_t start, void *arg)
{
    (void)start;
    (void)arg;
    *entry = SL_OCTREE_NONE; /* drawn the general way */
}

/* The final layout: drawings ordered by the k at which their state begins (then in LOD
 * order), so every drawing a cut after k expansions can use lies in the part of
 * split_drawings holding states that begin at or before k: a small cut reads a compact
 * prefix instead of picking its cells' first states from between their later ones. */
typedef struct layout {
    uint64_t *cursor;         /* per start k: where its next drawing goes (pass 1) */
    const uint32_t *run;      /* the chunk's run the entries point into */
    uint32_t *words;          /* split_drawings being filled */
    int dual;
    uint32_t extra_base;      /* dual: the id of the chunk's first extra vertex */
} layout;

static uint32_t drawing_size(const layout *l, const uint32_t *drawing)
{
    if (!l->dual)
        return 1 + 3 * (drawing[0] & 0xff);
    uint32_t size = 1;
    for (uint32_t i = 0; i < (drawing[0] & 0xff); i++)
        size += 2 + drawing[size];
    return size;
}

static void count_drawing(uint32_t *entry, uint32_t start, void *arg)
{
    layout *l = arg;
    l->cursor[start + 1] += drawing_size(l, l->run + *entry);
}

static void place_drawing(uint32_t *entry, uint32_t start, void *arg)
{
    layout *l = arg;
    const uint32_t *drawing = l->run + *entry;
    uint32_t size = drawing_size(l, drawing), *out = l->words + l->cursor[start];
    memcpy(out, drawing, size * sizeof *drawing);
    if (l->dual) /* the chunk's extra vertices get their ids in the model's table */
        for (uint32_t i = 0, at = 1; i < (out[0] & 0xff); i++, at += 2 + out[at])
            if (out[at + 1] & EXTRA_REF)
                out[at + 1] = l->extra_base + (out[at + 1] & ~EXTRA_REF);
    *entry = (uint32_t)l->cursor[start];
    l->cursor[start] += size;
}

/* A dual model's vertex table: the tree's vertices, then the chunks' extra vertices in
 * chunk order (whose first ids go to extra_base[chunk]). Returns -1 when out of memory. */
static int dual_table(sl_lod_model *m, const drawing_run *runs, uint32_t *extra_base)
{
    const sl_octree *t = &m->tree;
    uint64_t total = t->vertex_count;
    for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
        extra_base[chunk] = (uint32_t)total;
        total += runs[chunk].extras;
    }
    if (total >= EXTRA_REF)
        return -1;
    float *p = realloc(m->dual_position, (total ? total : 1) * 3 * sizeof *p);
    if (p)
        m->dual_position = p;
    uint8_t *c = t->crossing_color ? realloc(m->dual_color, (total ? total : 1) * 4) : NULL;
    if (c)
        m->dual_color = c;
    if (!p || (t->crossing_color && !c))
        return -1;
    for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
        const drawing_run *r = &runs[chunk];
        if (!r->extras)
            continue;
        memcpy(p + 3 * (size_t)extra_base[chunk], r->extra_position, 3 * (size_t)r->extras * sizeof *p);
        if (c)
            memcpy(c + 4 * (size_t)extra_base[chunk], r->extra_color, 4 * (size_t)r->extras);
    }
    m->dual_count = (uint32_t)total;
    return 0;
}

int sl_lod_draw_states(sl_lod_model *m)
{
    uint32_t e = m->expansion_count, end = m->frontier_end[e];
    drawing_run runs[DRAW_CHUNKS];
    uint32_t extra_base[DRAW_CHUNKS];
    memset(runs, 0, sizeof runs);
    free(m->split_drawings);
    m->split_drawings = NULL;
    m->split_drawing_words = 0;
    int failed = 0, dual = m->dual_position != NULL;
#pragma omp parallel
    {
        /* Each thread triangulates each distinct configuration it meets once. */
        sl_mc_cache *configs = sl_mc_cache_new();
#pragma omp for schedule(dynamic, 1)
        for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
            if (!configs || draw_chunk(m, configs, chunk_start(end, chunk),
                                       chunk_start(end, chunk + 1), &runs[chunk])) {
#pragma omp atomic write
                failed = 1;
            }
            run_trim(&runs[chunk]);
        }
        sl_mc_cache_free(configs);
    }
    uint64_t total = 0;
    for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++)
        total += runs[chunk].count;
    layout l = {NULL, NULL, NULL, dual, 0};
    if (!failed && total < SL_OCTREE_NONE && (!dual || dual_table(m, runs, extra_base) == 0)) {
        l.cursor = calloc((size_t)e + 2, sizeof *l.cursor);
        l.words = malloc((total ? total : 1) * sizeof *l.words);
    }
    int rc = 0;
    if (!l.cursor || !l.words) { /* out of memory: every transition cell drawn when cut,
                                    which a dual model cannot (its extra vertices are made
                                    here): its load fails */
        for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++)
            for_each_drawn_state(m, chunk_start(end, chunk), chunk_start(end, chunk + 1),
                                 forget, NULL);
        free(l.cursor);
        free(l.words);
        rc = dual ? -1 : 0;
    } else {
        for (int pass = 0; pass < 2; pass++) {
            for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
                l.run = runs[chunk].words;
                l.extra_base = dual ? extra_base[chunk] : 0;
                for_each_drawn_state(m, chunk_start(end, chunk), chunk_start(end, chunk + 1),
                                     pass ? place_drawing : count_drawing, &l);
                if (pass) { /* placed: the chunk's run is not read again */
                    free(runs[chunk].words);
                    runs[chunk].words = NULL;
                }
            }
            if (pass == 0) /* cursor[k] = where the drawings of states beginning at k go */
                for (uint32_t k = 1; k <= e + 1; k++)
                    l.cursor[k] += l.cursor[k - 1];
        }
        free(l.cursor);
        m->split_drawings = l.words;
        m->split_drawing_words = total;
    }
    for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
        free(runs[chunk].words);
        free(runs[chunk].extra_position);
        free(runs[chunk].extra_color);
    }
    return rc;
}
