/* Which faces and edges of a cell a neighbour's expansion splits (runtime/lod_layout.c
 * builds the split lists with it, runtime/lod_states.c and lod_generate.c draw transition
 * cells with it), and the frontier cell they share. Built once, read-only afterwards. */
#ifndef SCANLOD_RUNTIME_LOD_SPLITS_H
#define SCANLOD_RUNTIME_LOD_SPLITS_H

#include <stdint.h>

#include "runtime/lod_model.h"

/* Per neighbour direction: the faces (bit f) and edges (bit e) of a cell that must be
 * split when the neighbour in that direction is expanded (a face neighbour: that face and
 * its 4 edges; any of the 3 neighbours around an edge: that edge; a corner neighbour:
 * nothing). The directions that split anything, in increasing order, are its slots. */
typedef struct sl_lod_split_table {
    uint8_t faces[27];
    uint16_t edges[27];
    uint32_t split_dirs;
    int slot_of_dir[27];
    uint8_t slot_faces[SL_LOD_SPLIT_DIRS];
    uint16_t slot_edges[SL_LOD_SPLIT_DIRS];
    uint8_t edge_c0[12], edge_c1[12], face_edges[6][4]; /* mc_cube.h numbering */
} sl_lod_split_table;

const sl_lod_split_table *sl_lod_split_table_get(void);

/* Frontier cell c after k expansions: its own signs and crossings, split where an expanded
 * neighbour requires, the finer points taken from its transition record. *entry is the
 * split list's word naming the state's drawing (NULL when not split: then the uniform
 * table is the cell's drawing). Returns 0, or -1 when a split lacked data (a crack). */
int sl_lod_frontier_cell(const sl_lod_model *m, uint32_t k, const sl_lod_cell_ref *c,
                         const sl_lod_split_table *st, sl_mc_cell *cell,
                         uint32_t point_crossing[SL_MC_MAX_POINTS], uint32_t **entry);

#endif
