/* PLY reader and writer.
 *
 * Reads ascii, binary_little_endian and binary_big_endian PLY 1.0: every scalar type
 * (char..double and int8..float64), properties in any order, unknown elements and
 * properties skipped, face lists of any count type and index type (polygons are
 * fan-triangulated), vertex colours (uchar or float), normals, per-vertex texture
 * coordinates (u/v, s/t, texture_u/texture_v) or per-face `texcoord` lists, the
 * `comment TextureFile NAME` convention, a scanner viewpoint (`element camera` with
 * view_px/py/pz, or `obj_info`/`comment viewpoint X Y Z`) and Stanford `range_grid`.
 *
 * Hostile input: every count is checked against the bytes that remain in the file with
 * overflow-checked arithmetic *before* anything is allocated; header size and line
 * length, element counts and list lengths are bounded by sl_ply_limits; indices must be
 * < vertex_count. Any failure is one sl_error naming the file, the element/line and the
 * cause (SL_E_BADINPUT or SL_E_LIMIT), never a crash. Non-finite coordinates are kept (the
 * range stage counts and drops them). After the last element an ascii file may hold only
 * whitespace; a binary file must end exactly there (extra bytes mean the header does not
 * describe the body: SL_E_BADINPUT). Faces with fewer than 3 corners are dropped and
 * counted; repeated indices are kept (degenerate faces are the range stage's business).
 *
 * Thread safety: reentrant; no global state.
 */
#ifndef SCANLOD_GEOMETRY_PLY_H
#define SCANLOD_GEOMETRY_PLY_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/mesh.h"

typedef struct sl_ply_limits {
    uint64_t max_header_bytes;  /* default 1 MiB */
    uint64_t max_vertices;      /* default 2^31 */
    uint64_t max_faces;         /* default 2^31 */
    uint32_t max_face_corners;  /* default 1024 */
} sl_ply_limits;

sl_ply_limits sl_ply_default_limits(void);

typedef enum sl_ply_format {
    SL_PLY_ASCII = 0,
    SL_PLY_BINARY_LE = 1,
    SL_PLY_BINARY_BE = 2
} sl_ply_format;

/* What the header declares (for `scanlod inspect` and the report). */
typedef struct sl_ply_info {
    sl_ply_format format;
    uint64_t header_bytes;
    uint64_t declared_vertices;
    uint64_t declared_faces;
    int element_count;          /* all elements, including skipped ones */
    char elements[1024];        /* "vertex 35947 (x y z confidence intensity); face 69451 ..." */
    int has_normals, has_colors, has_texcoords, has_face_texcoords, has_range_grid;
} sl_ply_info;

/* Reads `path` into `out` (initialised by the callee; release with sl_mesh_release).
 * `limits` and `progress` may be NULL. `info` may be NULL. */
int sl_ply_read(const char *path, const sl_ply_limits *limits, sl_mesh *out, sl_ply_info *info,
                sl_progress *progress, sl_error *err);

/* Only the header of `path` (nothing of the body is read: a pre-flight look at a scan of
 * any size, `scanlod plan`); the counts are validated against the file's size as by
 * sl_ply_read. */
int sl_ply_read_info(const char *path, const sl_ply_limits *limits, sl_ply_info *info,
                     sl_error *err);

/* The same from memory (fuzzing, tests); `name` is used in messages. */
int sl_ply_read_memory(const void *data, size_t size, const char *name,
                       const sl_ply_limits *limits, sl_mesh *out, sl_ply_info *info,
                       sl_error *err);

/* The texture file a PLY names (`comment TextureFile NAME`, sl_mesh.texture_file): NAME
 * relative to `dir`, the PLY's directory, into `out`. -1 for an absolute name or one with
 * a `..` component (a scan must not make us read outside its folder), -2 when the path
 * does not fit; 0 otherwise. */
int sl_ply_texture_path(const char *dir, const char *name, char *out, size_t size);

/* Writes a binary little-endian PLY with positions, and normals/colours when present,
 * through the atomic-write helper (nothing visible at `path` until complete). */
int sl_ply_write(const char *path, const sl_mesh *mesh, sl_error *err);

#endif
