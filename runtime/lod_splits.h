/* Which faces and edges of a cell a neighbour's expansion splits (runtime/lod_generate.c
 * draws transition cells with it; sl_lod_model_prepare lays out the split rows by its
 * slots). Built once, read-only afterwards. */
#ifndef SCANLOD_RUNTIME_LOD_SPLITS_H
#define SCANLOD_RUNTIME_LOD_SPLITS_H

#include <stdint.h>

#include "runtime/lod_model.h"

/* Per neighbour direction: the faces (bit f) and edges (bit e) of a cell that must be
 * split when the neighbour in that direction is expanded (a face neighbour: that face and
 * its 4 edges; any of the 3 neighbours around an edge: that edge; a corner neighbour:
 * nothing). The directions that split anything, in increasing order, are the model's
 * split row slots. */
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

#endif
