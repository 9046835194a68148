/* The texture of a scan as sl_scan_read found it (sl_mesh.texture_file or .texture_data),
 * decoded: one place for the range stage, which samples it into point colours, and the
 * export, which bakes it into the levels' atlases (docs/inputs.md, "Textures").
 */
#ifndef SCANLOD_FORMATS_SCAN_TEXTURE_H
#define SCANLOD_FORMATS_SCAN_TEXTURE_H

#include <stddef.h>
#include <stdint.h>

#include "geometry/mesh.h"
#include "shim/oiio_shim.h"

/* Whether `m` names or holds a texture image. */
int sl_scan_has_texture(const sl_mesh *m);

/* How messages name it: the file name, or "embedded image/jpeg (N bytes)". */
const char *sl_scan_texture_name(const sl_mesh *m, char *buf, size_t size);

/* Decodes the texture of `m` into `img` (release with sl_image_release): its file, named
 * relative to `dir` (the input's folder; absolute and `..` names are refused), or its
 * embedded bytes; at most `max_pixels`. 1 when read; 0 with the reason in `why` ("texture
 * NAME: ...") when there is none or it cannot be read: a texture is a warning of the item,
 * never its failure. */
int sl_scan_texture_read(const sl_mesh *m, const char *dir, uint64_t max_pixels, sl_image *img,
                         char *why, size_t why_size);

#endif
