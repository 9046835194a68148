/* Reading a scan in any of the formats museums hold them in: one entry point for the range
 * stage, the export, and the commands (docs/inputs.md).
 *
 *   format  names                 reader
 *   ply     .ply                  formats/ply*.c (ascii and binary, every PLY feature)
 *   obj     .obj (+ .mtl)         formats/obj_read.c, obj_mtl.c
 *   stl     .stl                  formats/stl_read.c (ascii and binary)
 *   off     .off                  formats/off_read.c (OFF, COFF, NOFF, CNOFF, STOFF, ...)
 *   xyz     .xyz, .pts            formats/xyz_read.c (point text, columns decide the meaning)
 *   gltf    .gltf (+ .bin, images) formats/gltf_*.c (glTF 2.0, Draco, meshopt, quantised)
 *   glb     .glb                  formats/gltf_*.c
 * The format is chosen by the file's magic where it has one (PLY's "ply", GLB's "glTF",
 * binary STL's size, an OFF header) and by its name otherwise; a name no reader knows but
 * whose bytes are numeric columns (a `.txt` export) reads as XYZ (sl_scan_read only: a
 * collection's walk takes files by name, sl_scan_format_of, and `.txt` is not one).
 *
 * Every reader promises what the PLY reader promises: element counts are checked against
 * the bytes of the file with overflow-checked arithmetic before anything is allocated, and
 * bounded by sl_scan_limits; every triangle index is < vertex_count; non-finite
 * coordinates are kept (the range stage counts and drops them); a failure is one sl_error
 * naming the file and the cause (SL_E_BADINPUT, SL_E_LIMIT or SL_E_UNSUPPORTED; SL_E_NOMEM,
 * SL_E_INTERRUPTED, SL_E_IO as usual), never a crash, with `out` left empty. What a reader
 * cannot use but need not fail for (a missing MTL or texture image, an extension that
 * only changes looks) is a warning in out->warnings.
 *
 * Thread safety: reentrant; no global state.
 */
#ifndef SCANLOD_FORMATS_SCAN_READ_H
#define SCANLOD_FORMATS_SCAN_READ_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "formats/ply.h"
#include "geometry/mesh.h"

typedef struct sl_scan_limits {
    uint64_t max_header_bytes;  /* PLY header, glTF JSON text: default 1 MiB / 64 MiB (below) */
    uint64_t max_vertices;      /* default 2^31 (what the triangles' uint32 indices reach) */
    uint64_t max_faces;         /* triangles after fan triangulation; PLY: face rows.
                                   Default 2^31 */
    uint32_t max_face_corners;  /* corners of one polygon: default 1024 */
} sl_scan_limits;

sl_scan_limits sl_scan_default_limits(void);
/* The PLY reader's share of them. */
sl_ply_limits sl_scan_ply_limits(const sl_scan_limits *limits);

/* What a file declares or holds, without its body where the format allows (`scanlod plan`,
 * `inspect`). Counts are exact for formats with a header (PLY, OFF, binary STL, glTF: the
 * accessors) and counted by a quick pass over the lines for the text formats without one
 * (OBJ, ascii STL, XYZ). */
typedef struct sl_scan_info {
    char format[8];              /* "ply", "obj", ... as in the table above */
    char detail[1024];           /* one line: "binary STL, header 'solid ...'", PLY elements */
    uint64_t declared_vertices;  /* the vertices the mesh will have (glTF: after instancing) */
    uint64_t declared_faces;     /* PLY and OFF: faces as declared; others: triangles */
    int has_normals, has_colors, has_texcoords;
    sl_ply_info ply;             /* for a PLY, what sl_ply_read_info says */
} sl_scan_info;

/* Reads `path` into `out` (initialised here; release with sl_mesh_release). `limits`,
 * `info` and `progress` may be NULL. Files beside it (an MTL, glTF buffers, texture
 * images) are looked up in the directory of `path`, never outside it. */
int sl_scan_read(const char *path, const sl_scan_limits *limits, sl_mesh *out,
                 sl_scan_info *info, sl_progress *progress, sl_error *err);

/* The header and size facts of `path` as sl_scan_read would find them, reading as little of
 * the body as the format allows (see sl_scan_info). */
int sl_scan_read_info(const char *path, const sl_scan_limits *limits, sl_scan_info *info,
                      sl_error *err);

/* The same from memory (fuzzing, tests): `name` is used in messages and, when `format` is
 * NULL, to choose the reader; `dir` is where files beside it are looked for (NULL: none;
 * an MTL or image is then a warning, an external glTF buffer an error). */
int sl_scan_read_memory(const void *data, size_t size, const char *name, const char *format,
                        const char *dir, const sl_scan_limits *limits, sl_mesh *out,
                        sl_scan_info *info, sl_error *err);

/* The format a file name says it is ("ply", "obj", "stl", "off", "xyz", "pts", "gltf",
 * "glb"; case-insensitive suffix), or NULL for a name that is not a scan format (a .mtl,
 * .bin, .jpg, .txt: the files that come with scans). */
const char *sl_scan_format_of(const char *path);

/* The suffixes sl_scan_format_of knows (".ply", ".obj", ...), NULL-terminated: what a
 * collection's input walk takes as items. */
const char *const *sl_scan_suffixes(void);

/* A file named inside a scan (a texture, an MTL, a glTF buffer or image): NAME relative
 * to `dir`, the input's directory, into `out`. -1 for an absolute name or one with a `..`
 * component (a scan must not make us read outside its folder), -2 when the path does not
 * fit; 0 otherwise. (sl_ply_texture_path, under the name every format uses.) */
int sl_scan_sibling_path(const char *dir, const char *name, char *out, size_t size);

/* The directory part of `path` into `dir` ("." when there is none). */
void sl_scan_directory_of(const char *path, char *dir, size_t size);

#endif
