/* Files for the scan reader tests: a GLB around a JSON text and a BIN chunk; a file of
 * given bytes in a folder. Header-only; test code only. */
#ifndef SCANLOD_TESTS_SCAN_TEST_FILES_H
#define SCANLOD_TESTS_SCAN_TEST_FILES_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/artifact.h"

/* A GLB of `json` (padded with spaces) and `bin` (NULL: no BIN chunk; padded with zeros);
 * malloc'd, *size bytes. */
static inline unsigned char *gltf_build_glb(const char *json, const void *bin, uint32_t bin_size,
                                            size_t *size)
{
    uint32_t jl = (uint32_t)(strlen(json) + 3) / 4 * 4, bl = (bin_size + 3) / 4 * 4;
    *size = 12 + 8 + jl + (bin ? 8 + bl : 0);
    unsigned char *p = calloc(1, *size);
    memcpy(p, "glTF", 4);
    sl_put_u32(p + 4, 2), sl_put_u32(p + 8, (uint32_t)*size);
    sl_put_u32(p + 12, jl), sl_put_u32(p + 16, 0x4E4F534A);
    memset(p + 20, ' ', jl);
    memcpy(p + 20, json, strlen(json));
    if (bin) {
        sl_put_u32(p + 20 + jl, bl), sl_put_u32(p + 24 + jl, 0x004E4942);
        memcpy(p + 28 + jl, bin, bin_size);
    }
    return p;
}

/* Writes `size` bytes to DIR/NAME (removed by scan_test_remove); the path into `path`. */
static inline void scan_test_write(const char *dir, const char *name, const void *data,
                                   size_t size, char *path, size_t path_size)
{
    snprintf(path, path_size, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (f) {
        fwrite(data, 1, size, f);
        fclose(f);
    }
}

/* Removes DIR/NAME for each of the `n` names, then DIR. */
static inline void scan_test_remove(const char *dir, const char *const *names, int n)
{
    char path[1024];
    for (int i = 0; i < n; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        remove(path);
    }
    remove(dir);
}

#endif
