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

/* Adds `base` to the drawing offsets of cells [from, to) (or makes them all
 * SL_OCTREE_NONE: drawn the general way). */
static void rebase_chunk(sl_lod_model *m, uint32_t from, uint32_t to, uint64_t base, int none)
{
    for (uint32_t pos = from; pos < to; pos++) {
        const sl_lod_cell_ref *c = &m->cells[pos];
        if (c->splits == SL_OCTREE_NONE)
            continue;
        uint32_t *w = m->split_words + c->splits;
        for (uint32_t i = 0; i <= w[1] >> 24; i++) {
            uint32_t *entry = i == 0 ? w + 2 : w + 2 + 3 * i;
            if (*entry != SL_OCTREE_NONE)
                *entry = none ? SL_OCTREE_NONE : (uint32_t)(*entry + base);
        }
    }
}

/* Lays the drawings out by the k at which their state begins (then in LOD order), so that
 * every drawing a cut after k expansions can use lies in the part of split_drawings
 * holding states that begin at or before k: a small cut reads a compact prefix instead of
 * picking its cells' first states from between their later ones. Leaves the drawings as
 * they are when out of memory. */
static void order_drawings(sl_lod_model *m)
{
    uint32_t e = m->expansion_count, end = m->frontier_end[e];
    uint64_t *cursor = calloc((size_t)e + 2, sizeof *cursor);
    uint32_t *words = malloc((m->split_drawing_words ? m->split_drawing_words : 1) * sizeof *words);
    if (!cursor || !words) {
        free(cursor);
        free(words);
        return;
    }
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t pos = 0; pos < end; pos++) {
            const sl_lod_cell_ref *c = &m->cells[pos];
            if (c->splits == SL_OCTREE_NONE)
                continue;
            uint32_t *w = m->split_words + c->splits;
            for (uint32_t i = 0; i <= w[1] >> 24; i++) {
                uint32_t *entry = i == 0 ? w + 2 : w + 2 + 3 * i;
                if (*entry == SL_OCTREE_NONE)
                    continue;
                uint32_t start = i == 0 ? sl_lod_first_frontier(m, pos) : w[3 * i] + 1u;
                const uint32_t *drawing = m->split_drawings + *entry;
                uint32_t size = 1 + 3 * (drawing[0] & 0xff);
                if (pass == 0) {
                    cursor[start + 1] += size;
                } else {
                    memcpy(words + cursor[start], drawing, size * sizeof *words);
                    *entry = (uint32_t)cursor[start];
                    cursor[start] += size;
                }
            }
        }
        if (pass == 0) /* cursor[k] = where the drawings of states beginning at k go */
            for (uint32_t k = 1; k <= e + 1; k++)
                cursor[k] += cursor[k - 1];
    }
    free(cursor);
    free(m->split_drawings);
    m->split_drawings = words;
}

#define DRAW_CHUNKS 256 /* fixed, so the result does not depend on the thread count */

int sl_lod_draw_states(sl_lod_model *m)
{
    uint32_t end = m->frontier_end[m->expansion_count];
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
        for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
            uint32_t from = (uint32_t)((uint64_t)end * (uint64_t)chunk / DRAW_CHUNKS);
            uint32_t to = (uint32_t)((uint64_t)end * (uint64_t)(chunk + 1) / DRAW_CHUNKS);
            if (!configs || draw_chunk(m, configs, from, to, &runs[chunk])) {
#pragma omp atomic write
                failed = 1;
            }
        }
        sl_mc_cache_free(configs);
    }
    uint64_t base[DRAW_CHUNKS], total = 0;
    for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
        base[chunk] = total;
        total += runs[chunk].count;
    }
    if (!failed && total < SL_OCTREE_NONE)
        m->split_drawings = malloc((total ? total : 1) * sizeof *m->split_drawings);
    int none = !m->split_drawings; /* then every transition cell is drawn the general way */
#pragma omp parallel for schedule(static)
    for (int chunk = 0; chunk < DRAW_CHUNKS; chunk++) {
        uint32_t from = (uint32_t)((uint64_t)end * (uint64_t)chunk / DRAW_CHUNKS);
        uint32_t to = (uint32_t)((uint64_t)end * (uint64_t)(chunk + 1) / DRAW_CHUNKS);
        rebase_chunk(m, from, to, base[chunk], none);
        if (!none && runs[chunk].count)
            memcpy(m->split_drawings + base[chunk], runs[chunk].words,
                   runs[chunk].count * sizeof *runs[chunk].words);
        free(runs[chunk].words);
    }
    m->split_drawing_words = none ? 0 : total;
    if (!none)
        order_drawings(m);
    return 0;
}
