/* The stage registry: every stage, in pipeline order (ARCHITECTURE section 2).
 * Adding a stage: docs/adding-a-stage.md. */
#include <string.h>

#include "pipeline/stage.h"
#include "stages/range/range.h"

static const sl_stage *const registry[] = {
    &sl_range_stage,
    NULL,
};

const sl_stage *const *sl_stage_registry(void)
{
    return registry;
}

const sl_stage *sl_stage_find(const char *name)
{
    for (const sl_stage *const *s = registry; *s; s++)
        if (strcmp((*s)->name, name) == 0)
            return *s;
    return NULL;
}
