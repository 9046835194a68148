/* extern "C" shim around OpenImageIO (C++). Every entry point catches every exception
 * and turns OIIO's per-thread geterror() into an sl_error naming the file.
 * OIIO's own thread pool is set to 1 thread: we call it from inside OpenMP regions, as
 * OIIO's docs ask of applications with their own threads.
 * OpenImageIO lives in a module loaded on the first call (oiio_loader.c, oiio_module.h):
 * a process that touches no image does not pay for loading it. When the module cannot be
 * loaded every call here fails with SL_E_INTERNAL and a message naming what was tried.
 */
#ifndef SCANLOD_SHIM_OIIO_SHIM_H
#define SCANLOD_SHIM_OIIO_SHIM_H

#include <stdint.h>

#include "core/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sl_image {
    int width, height, channels; /* channels as stored in `pixels` */
    float *pixels;               /* width * height * channels, row 0 = top */
} sl_image;

/* Loads the module now (optional: the first image call does it). */
void sl_oiio_init(void);
/* Loads the module: NULL and its path and OpenImageIO's version in *path, *version; or
 * why it did not load (the paths tried and dlerror()) and NULLs. */
const char *sl_oiio_module_info(const char **path, const char **version);

/* Reads any image OIIO knows, converted to float, at most max_pixels pixels
 * (SL_E_LIMIT beyond; checked from the header before reading). */
int sl_image_read(const char *path, uint64_t max_pixels, sl_image *out, sl_error *err);

/* The same from an encoded image in memory (a texture embedded in a glTF/GLB): `mime_type`
 * ("image/jpeg", "image/png", ...; NULL or "" to guess from the bytes' signature) picks
 * the decoder, `name` (may be NULL) names the image in messages. SL_E_UNSUPPORTED for a
 * type OpenImageIO cannot decode from memory. */
int sl_image_read_memory(const void *data, size_t size, const char *mime_type, const char *name,
                         uint64_t max_pixels, sl_image *out, sl_error *err);

/* Writes `pixels` (float, width*height*channels) to `path`; the format follows the
 * extension (.exr as half/float, .png as 8-bit). Written to a temp name in the same
 * directory, fsynced and renamed (nothing partial is ever visible). */
int sl_image_write(const char *path, int width, int height, int channels, const float *pixels,
                   sl_error *err);

/* Encodes `pixels` (float in [0, 1], values as stored: sRGB stays sRGB) as an 8-bit image
 * in memory: `format` "jpg" (at `quality` 1..100) or "png". *out (OUT) is malloc'd,
 * *out_size bytes; free() it. SL_E_INTERNAL when OpenImageIO cannot, SL_E_NOMEM. */
int sl_image_encode(const char *format, int width, int height, int channels, const float *pixels,
                    int quality, void **out, size_t *out_size, sl_error *err);

void sl_image_release(sl_image *img);

#ifdef __cplusplus
}
#endif
#endif
