/* `scanlod plan`: a pre-flight estimate per item of a collection (cli/plan.c). */
#ifndef SCANLOD_CLI_PLAN_H
#define SCANLOD_CLI_PLAN_H

#include <stdint.h>
#include <stdio.h>

#include "core/error.h"
#include "pipeline/engine.h"

/* Per item of the engine's [run] input: the expected peak memory, time and disk from its
 * header (any scan format), its shape (cli/plan_shape.h) and the config, as a table or
 * JSON on `out`; nothing run or written.
 * `unplanned`: the items whose header could not be read (each said with its cause). */
int sl_plan_print(sl_engine *e, FILE *out, int json, uint64_t *unplanned, sl_error *err);

/* The expected peak RSS in MB of the item at `path` under the engine's config (the largest
 * stage's, named in *stage when given), from its header (sl_scan_read_info) and shape
 * (measured once per file version, in a child process); 0 when the header cannot be read.
 * The engine's memory admission (sl_engine_options.expected_peak_mb). */
double sl_plan_peak_mb(const sl_engine_facts *facts, const char *path, const char **stage);

#endif
