/* The stage contract's helpers (stage.h): finding an earlier stage's artifacts, the path
 * of an artifact file, a safe point, and a stage's default config. */
#include "pipeline/stage.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *sl_stage_dir(const sl_stage_io *io, const char *name)
{
    for (const struct sl_stage_dir_entry *u = io->upstream; u && u->stage; u++)
        if (strcmp(u->stage, name) == 0)
            return u->dir;
    return NULL;
}

int sl_stage_path(char path[PATH_MAX], const char *dir, const char *name, sl_error *err)
{
    int n = snprintf(path, PATH_MAX, "%s/%s", dir, name);
    if (n < 0 || n >= PATH_MAX)
        return sl_error_set(err, SL_E_STORAGE, ENAMETOOLONG, dir, "path too long for '%s'",
                            name);
    return 0;
}

int sl_stage_step(const sl_stage_io *io, const char *phase, double fraction, sl_error *err)
{
    if (sl_progress_step(io->progress, phase, fraction))
        return sl_error_set(err, SL_E_INTERRUPTED, 0, NULL, "interrupted");
    return 0;
}

void sl_stage_default_config(const sl_stage *stage, void *out, size_t size)
{
    const sl_option *tables[8] = {stage->options};
    int n = 1;
    for (const sl_option *const *t = stage->shared_options; t && *t && n < 7; t++)
        tables[n++] = *t;
    tables[n] = NULL;
    sl_config *cfg = NULL;
    void *config = NULL;
    sl_error err;
    sl_error_init(&err);
    if (sl_config_load(&cfg, tables, NULL, NULL, 0, &err) == 0 &&
        stage->configure(cfg, &config, &err) == 0) {
        memcpy(out, config, size);
        if (stage->release_config)
            stage->release_config(config);
        else
            free(config);
        sl_config_free(cfg);
        return;
    }
    /* The defaults come from the stage's own table: failing them is a bug in it. */
    char line[1024];
    sl_error_format(&err, line, sizeof line);
    fprintf(stderr, "scanlod: the %s stage's defaults fail: %s\n", stage->name, line);
    abort();
}
