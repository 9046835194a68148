/* The stage registry: every stage, in pipeline order (docs/architecture.md, "The flow").
 * Adding a stage: docs/adding-a-stage.md. */
#include <string.h>

#include "stages/cluster/cluster.h"
#include "stages/crack/crack.h"
#include "stages/export/export.h"
#include "stages/merge/merge.h"
#include "stages/priority/priority.h"
#include "stages/range/range.h"
#include "stages/refine/refine.h"
#include "stages/registry.h"
#include "stages/samples/samples.h"
#include "stages/segment/segment.h"

static const sl_stage *const registry[] = {
    &sl_range_stage,
    &sl_samples_stage,
    &sl_merge_stage,
    &sl_priority_stage,
    &sl_crack_stage,
    &sl_segment_stage,
    &sl_cluster_stage,
    &sl_refine_stage,
    &sl_export_stage,
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
