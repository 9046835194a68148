/* Thumbnails: a small deterministic software rasteriser for preview images of a mesh.
 *
 * View: orthographic, from azimuth 30 degrees and elevation 20 degrees around the +Y axis
 * (glTF's and the Stanford scans' up), looking at the mesh; the projected extent of the
 * referenced vertices is fitted into the image with a 6% margin on each side and centred.
 * Shading (docs/glb.md): Lambert in linear light from a key light above-left of the
 * camera plus a weak light from the camera and an ambient term, two-sided (a face seen
 * from its back is shaded as if it faced the camera: scans are often open); vertex
 * normals when given (oriented like their face), else face normals; vertex colours when
 * given, else a neutral clay colour; a light grey background; the silhouette and depth
 * edges darkened; 3x3 supersampling (2x2 or 1x1 for very large images) box-filtered;
 * the result encoded sRGB.
 *
 * Deterministic: same mesh and size give the same pixels on any machine and thread count
 * (one serial z-buffer pass, ties kept by the lower triangle index).
 * Thread safety: reentrant; no global state.
 */
#ifndef SCANLOD_GEOMETRY_RASTER_H
#define SCANLOD_GEOMETRY_RASTER_H

#include "core/error.h"
#include "geometry/mesh.h"

#define SL_THUMBNAIL_MAX_SIDE 4096

/* Renders `m` into `rgba` (OUT: width * height * 4 floats, sRGB-encoded in [0, 1], row 0
 * at the top, alpha 1). Sides in [1, SL_THUMBNAIL_MAX_SIDE]. Rejects what
 * sl_mesh_check_writable() (geometry/mesh.h) rejects; SL_E_NOMEM when the sample buffers cannot be allocated. */
int sl_render_thumbnail(const sl_mesh *m, int width, int height, float *rgba,
                        sl_error *err);

/* Renders a `size` x `size` thumbnail and writes it to `path` through OpenImageIO
 * (shim/oiio_shim.h: the format follows the extension, PNG as 8-bit RGBA; written
 * atomically). */
int sl_write_thumbnail(const char *path, const sl_mesh *m, int size, sl_error *err);

#endif
