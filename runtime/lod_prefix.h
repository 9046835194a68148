/* A model opened for cutting that reads, of a format 5 file (lod_order.h), only what its
 * cuts need: opening reads the envelope's header, the piece table and the whole model's
 * level tables (how many triangles and what error after k expansions, the surface
 * counts, the bounds); a cut of k expansions then reads the prefix of every section that
 * the first k expansions reach, checks each piece it unpacks against the table's check,
 * and turns that prefix into a model of k expansions (sl_lod_raw_build: every check
 * the whole model gets, on what was read). So a small level of a 20 M-triangle model
 * costs milliseconds and megabytes, not the whole model (docs/benchmarks.md).
 *
 * The prefix held grows (to at least twice the last one, so a viewer stepping up through
 * levels reads about twice the finest it asks for in all) and never shrinks. The file
 * stays open: a model republished under the same name (a rename) does not change what
 * an open one reads. Files of formats 2 to 4 are read whole at opening, as before.
 *
 * The envelope's checksum is not checked (that would read the whole file); the pieces'
 * checks cover every byte a cut uses, and `scanlod verify`/`inspect` read whole files.
 */
#ifndef SCANLOD_RUNTIME_LOD_PREFIX_H
#define SCANLOD_RUNTIME_LOD_PREFIX_H

#include <stdint.h>

#include "core/error.h"
#include "runtime/lod_model.h"

typedef struct sl_lod_file sl_lod_file;

int sl_lod_file_open(const char *path, sl_lod_file **out, sl_error *err);
void sl_lod_file_close(sl_lod_file *f);

/* The whole model's level tables, for the level helpers (sl_lod_expansions_for_*) and
 * counts: expansion_count, accumulation, error_after and surface_before are set (and,
 * for files of formats 2 to 4, all the rest). */
const sl_lod_model *sl_lod_file_levels(const sl_lod_file *f);
/* Bounding box of every crossing: min[3], max[3]. */
void sl_lod_file_bounds(const sl_lod_file *f, float min[3], float max[3]);
/* A model holding at least the first k expansions (k is clamped to the model's), to cut
 * any level up to k from; owned by f, valid until the next call or sl_lod_file_close.
 * Returns 0, or an error naming the file (a damaged piece, a read error, OOM). */
int sl_lod_file_reach(sl_lod_file *f, uint32_t k, sl_lod_model **model, sl_error *err);
/* Expansions the held model has (0 before the first reach of a format 5 file). */
uint32_t sl_lod_file_reached(const sl_lod_file *f);

#endif
