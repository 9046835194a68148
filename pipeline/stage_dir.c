/* sl_stage_dir: finding an earlier stage's artifact directory by name (stage.h). */
#include <string.h>

#include "pipeline/stage.h"

const char *sl_stage_dir(const sl_stage_io *io, const char *name)
{
    const sl_stage *const *registry = sl_stage_registry();
    for (int i = 0; io->upstream_dirs && io->upstream_dirs[i] && registry[i]; i++)
        if (strcmp(registry[i]->name, name) == 0)
            return io->upstream_dirs[i];
    return NULL;
}
