/* Mesh output for viewers: binary glTF 2.0 (.glb) and Wavefront OBJ.
 *
 * Both writers read an sl_mesh (positions, triangles, and normals and colours when given;
 * often a view of someone else's arrays, sl_mesh_view(): nothing is copied or freed) and
 * write through the atomic-write helper, so nothing is visible at
 * `path` until the file is complete and durable (core/atomicfile.h).
 *
 * What a .glb holds (docs/glb.md): one scene, one node, one mesh with one TRIANGLES
 * primitive; POSITION (float VEC3 with exact min/max), NORMAL (float VEC3, written unit
 * length) and COLOR_0 (unsigned byte VEC4, normalized) when given; indices as
 * UNSIGNED_SHORT when vertex_count < 65536, else UNSIGNED_INT; one matte double-sided
 * material (glTF's default material is fully metallic, which renders scans dark);
 * asset.generator "scanlod"; the caller's `extras_json` (may be NULL) as the mesh's
 * `extras`.
 * The files pass the Khronos glTF validator with 0 errors (tests/export/test_glb.sh).
 *
 * Rejected, with nothing written:
 *   - a mesh with 0 triangles or 0 vertices: SL_E_BADINPUT "nothing to write" (glTF
 *     accessors need count >= 1, and an item without surface has no useful GLB);
 *   - a non-finite position: SL_E_BADINPUT (min/max and every viewer would break);
 *   - an index >= vertex_count: SL_E_INTERNAL (whoever built the mesh has a bug);
 *   - a file that would exceed the GLB's 32-bit length: SL_E_LIMIT;
 *   - extras_json that is not a {...} object text: SL_E_INTERNAL.
 * A NORMAL of zero length or with a non-finite component is written as (0, 0, 1), because
 * glTF requires unit normals; the writers never change positions or indices.
 *
 * Thread safety: reentrant; no global state.
 */
#ifndef SCANLOD_GEOMETRY_GLB_H
#define SCANLOD_GEOMETRY_GLB_H

#include <stdint.h>

#include "core/error.h"
#include "geometry/mesh.h"

/* What the writers read of `m`: positions (world), triangles (counter-clockwise seen from
 * outside), normals (any length; written unit) and colours (RGBA, sRGB) when not NULL.
 * The checks every writer of a mesh for viewers needs (GLB, OBJ, thumbnails): at least
 * one triangle, finite positions, indices in range. `path` names the file in messages
 * (may be NULL). */
int sl_mesh_check_writable(const sl_mesh *m, const char *path, sl_error *err);

/* `extras_json`: a JSON object text ("{...}") for mesh.extras, or NULL. */
int sl_glb_write(const char *path, const sl_mesh *m, const char *extras_json, sl_error *err);

/* OBJ: `v x y z [r g b]` (colours as floats in [0, 1], the common extension that
 * MeshLab and Blender read), `vn` when normals are given, faces 1-based (`f a//a ...` with
 * normals). extras_json is written as a `#` comment line when it has no line break.
 * Rejects what sl_glb_write rejects, except the 32-bit size limit. */
int sl_obj_write(const char *path, const sl_mesh *m, const char *extras_json, sl_error *err);

#endif
