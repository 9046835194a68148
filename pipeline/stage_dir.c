/* sl_stage_dir: finding an earlier stage's artifact directory by name (stage.h). */
#include <string.h>

#include "pipeline/stage.h"

const char *sl_stage_dir(const sl_stage_io *io, const char *name)
{
    for (const struct sl_stage_dir_entry *u = io->upstream; u && u->stage; u++)
        if (strcmp(u->stage, name) == 0)
            return u->dir;
    return NULL;
}
