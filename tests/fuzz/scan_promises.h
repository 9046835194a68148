/* What every scan reader promises on any input (formats/scan_read.h), checked by the
 * libFuzzer targets fuzz_{obj,stl,off,xyz,gltf}.c and by the corpus replay in every build
 * (tests/unit/test_fuzz_corpus.c): a success is a mesh whose every triangle index is in
 * range and whose strings are terminated; a failure is exactly one bad-input, limit or
 * unsupported error with a message naming the file, and an empty mesh. Header-only. */
#ifndef SCANLOD_TESTS_FUZZ_SCAN_PROMISES_H
#define SCANLOD_TESTS_FUZZ_SCAN_PROMISES_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "formats/scan_read.h"

/* NULL when `rc`, `err` and `m` keep the promises for a read of `name`, else what broke. */
static inline const char *scan_outcome_broken(int rc, const sl_error *err, const sl_mesh *m,
                                              const char *name)
{
    if (rc != 0) {
        if (rc != err->code)
            return "the returned code is not the recorded one";
        if (rc != SL_E_BADINPUT && rc != SL_E_LIMIT && rc != SL_E_UNSUPPORTED)
            return "an error of another class than bad input";
        if (!err->message[0] || strcmp(err->file, name))
            return "the error does not name the file and a cause";
        if (m->vertex_count || m->positions || m->triangles || m->texture_data)
            return "a failed read left a mesh";
        return NULL;
    }
    if ((m->vertex_count && !m->positions) || (m->triangle_count && !m->triangles))
        return "counts without arrays";
    for (uint64_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->triangles[i] >= m->vertex_count)
            return "a triangle index out of range";
    if (!memchr(m->texture_file, 0, sizeof m->texture_file) ||
        !memchr(m->texture_mime, 0, sizeof m->texture_mime) ||
        !memchr(m->warnings, 0, sizeof m->warnings) || !memchr(m->format, 0, sizeof m->format) ||
        !m->format[0])
        return "an unterminated string";
    if (!m->texture_data && m->texture_size)
        return "a texture size without its bytes";
    return NULL;
}

/* One fuzz input through the reader of `format` from memory (no folder beside it). */
static inline void scan_fuzz_one(const uint8_t *data, size_t size, const char *name,
                                 const char *format)
{
    sl_mesh m;
    sl_scan_info info;
    sl_error err;
    sl_error_init(&err);
    int rc = sl_scan_read_memory(data, size, name, format, NULL, NULL, &m, &info, &err);
    if (scan_outcome_broken(rc, &err, &m, name) ||
        !memchr(info.detail, 0, sizeof info.detail))
        abort();
    sl_mesh_release(&m);
}

#endif
