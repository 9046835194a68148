/* The table the OpenImageIO module (scanlod-oiio.so, built from oiio_shim.cpp) exports,
 * and nothing else: oiio_loader.c dlopen()s the module the first time an image is read,
 * written or encoded, so a process that never touches an image never loads OpenImageIO
 * and the 260 libraries it pulls in (about 0.26 s of CPU at every start otherwise;
 * docs/architecture.md, "Images load on demand"). */
#ifndef SCANLOD_SHIM_OIIO_MODULE_H
#define SCANLOD_SHIM_OIIO_MODULE_H

#include <stddef.h>
#include <stdint.h>

#include "shim/oiio_shim.h"

#define SL_OIIO_MODULE_VERSION 2
#define SL_OIIO_MODULE_SYMBOL "sl_oiio_module_api"

typedef struct sl_oiio_api {
    int version;                 /* SL_OIIO_MODULE_VERSION */
    const char *library_version; /* OpenImageIO's, e.g. "2.4.7" */
    int (*read)(const char *path, uint64_t max_pixels, sl_image *out, sl_error *err);
    int (*read_memory)(const void *data, size_t size, const char *mime_type, const char *name,
                       uint64_t max_pixels, sl_image *out, sl_error *err);
    int (*write)(const char *path, int width, int height, int channels, const float *pixels,
                 sl_error *err);
    int (*encode)(const char *format, int width, int height, int channels, const float *pixels,
                  int quality, void **out, size_t *out_size, sl_error *err);
} sl_oiio_api;

#ifdef __cplusplus
extern "C" {
#endif
typedef const sl_oiio_api *(*sl_oiio_api_fn)(void);
#ifdef __cplusplus
}
#endif
#endif
