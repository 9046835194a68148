/* The stage registry: every stage, in pipeline order (docs/architecture.md, "The flow"). The
 * program hands this list to the engine (sl_engine_options.stages); the engine itself
 * names no stage. Adding a stage: docs/adding-a-stage.md. */
#ifndef SCANLOD_STAGES_REGISTRY_H
#define SCANLOD_STAGES_REGISTRY_H

#include "pipeline/stage.h"

/* The registered stages, in pipeline order, NULL-terminated. */
const sl_stage *const *sl_stage_registry(void);
/* The stage called `name`, or NULL. */
const sl_stage *sl_stage_find(const char *name);

#endif
