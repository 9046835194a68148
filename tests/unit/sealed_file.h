/* Artifacts as a producer with a bug would write them: some bytes changed, then sealed (the
 * envelope's body size and checksum put right, core/artifact.h) so that what refuses them
 * is the reader's own checks behind the checksum, not the checksum. */
#ifndef SCANLOD_TESTS_SEALED_FILE_H
#define SCANLOD_TESTS_SEALED_FILE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "core/artifact.h"
#include "core/atomicfile.h"

/* The file's bytes with `spare` writable bytes after them (a body to grow), or NULL. */
static unsigned char *sealed_file_bytes(const char *path, size_t spare, size_t *size)
{
    char *data = NULL;
    sl_error err;
    sl_error_init(&err);
    *size = 0;
    if (sl_read_file(path, (uint64_t)1 << 32, &data, size, &err))
        return NULL;
    unsigned char *grown = realloc(data, *size + spare + 1);
    if (!grown)
        free(data);
    return grown;
}

/* Writes `size` of `bytes` to path, sealed when `seal` (a copy: bytes stay as given).
 * 0, or -1 when the file could not be written. */
static int sealed_file_write(const char *path, const unsigned char *bytes, size_t size, int seal)
{
    unsigned char *b = malloc(size ? size : 1);
    if (!b)
        return -1;
    memcpy(b, bytes, size);
    if (seal && size >= SL_ARTIFACT_HEADER_SIZE) {
        uint64_t body = size - SL_ARTIFACT_HEADER_SIZE;
        sl_put_u64(b + 16, body);
        sl_put_u64(b + 24, XXH3_64bits(b + SL_ARTIFACT_HEADER_SIZE, body));
    }
    FILE *f = fopen(path, "wb");
    int ok = f && fwrite(b, 1, size, f) == size;
    if (f && fclose(f))
        ok = 0;
    free(b);
    return ok ? 0 : -1;
}

#endif
