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

#include "runtime/lod_model.h"
#include "runtime/lod_splits.h"
#include "runtime/mc_cache.h"

/* A growing run of drawings (one chunk of cells' worth). */
typedef struct drawing_run {
    uint32_t *words;
    uint64_t count, capacity;
} drawing_run;

/* Appends a transition cell's drawing to the run; *offset = its place in the run. */
static int append_drawing(drawing_run *run, const sl_mc_cached *t, int crack,
                          const uint32_t point_crossing[SL_MC_MAX_POINTS], uint32_t *offset)
{
    uint64_t size = 1 + 3 * (uint64_t)t->count;
    if (run->count + size > run->capacity) {
        uint64_t grown = run->capacity ? 2 * run->capacity : 1024;
        uint32_t *words = realloc(run->words, (size_t)grown * sizeof *words);
        if (!words)
            return -1;
        run->words = words;
        run->capacity = grown;
    }
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
} layout;

static uint32_t drawing_size(const uint32_t *drawing)
{
    return 1 + 3 * (drawing[0] & 0xff);
}

static void count_drawing(uint32_t *entry, uint32_t start, void *arg)
{
    layout *l = arg;
    l->cursor[start + 1] += drawing_size(l->run + *entry);
}

static void place_drawing(uint32_t *entry, uint32_t start, void *arg)
{
    layout *l = arg;
    const uint32_t *drawing = l->run + *entry;
    uint32_t size = drawing_size(drawing);
    memcpy(l->words + l->cursor[start], drawing, size * sizeof *drawing);
    *entry = (uint32_t)l->cursor[start];
    l->cursor[start] += size;
}

int sl_lod_draw_states(sl_lod_model *m)
{
    uint32_t e = m->expansion_count, end = m->frontier_end[e];
    drawing_run runs[DRAW_CHUNKS];
    memset(runs, 0, sizeof runs);
    free(m->split_drawings);
    m->split_drawings = NULL;
    m->split_drawing_words = 0;
    int failed = 0;
#pragma omp parallel
    {
        /* Each thread triangulates each distinct configuration it meets once. */
        sl_mc_cache *configs = sl_mc_cache_new();
#pragma omp for schedule(dynamic, 1)
        for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++)
            if (!configs || draw_chunk(m, configs, chunk_start(end, chunk),
                                       chunk_start(end, chunk + 1), &runs[chunk])) {
#pragma omp atomic write
                failed = 1;
            }
        sl_mc_cache_free(configs);
    }
    uint64_t total = 0;
    for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++)
        total += runs[chunk].count;
    layout l = {NULL, NULL, NULL};
    if (!failed && total < SL_OCTREE_NONE) {
        l.cursor = calloc((size_t)e + 2, sizeof *l.cursor);
        l.words = malloc((total ? total : 1) * sizeof *l.words);
    }
    if (!l.cursor || !l.words) { /* out of memory: every transition cell drawn when cut */
        for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++)
            for_each_drawn_state(m, chunk_start(end, chunk), chunk_start(end, chunk + 1),
                                 forget, NULL);
        free(l.cursor);
        free(l.words);
    } else {
        for (int pass = 0; pass < 2; pass++) {
            for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
                l.run = runs[chunk].words;
                for_each_drawn_state(m, chunk_start(end, chunk), chunk_start(end, chunk + 1),
                                     pass ? place_drawing : count_drawing, &l);
            }
            if (pass == 0) /* cursor[k] = where the drawings of states beginning at k go */
                for (uint32_t k = 1; k <= e + 1; k++)
                    l.cursor[k] += l.cursor[k - 1];
        }
        free(l.cursor);
        m->split_drawings = l.words;
        m->split_drawing_words = total;
    }
    for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++)
        free(runs[chunk].words);
    return 0;
}
