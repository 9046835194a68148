/* Mesh output for viewers: binary glTF 2.0 (.glb) and Wavefront OBJ.
 *
 * Both writers read an sl_mesh (positions, triangles, and normals, colours and texture
 * coordinates when given; often a view of someone else's arrays, sl_mesh_view(): nothing
 * is copied or freed) and write through the atomic-write helper, so nothing is visible at
 * `path` until the file is complete and durable (core/atomicfile.h).
 *
 * What a .glb holds (docs/glb.md): one scene, one node, one mesh with one TRIANGLES
 * primitive; POSITION, NORMAL (written unit length) and COLOR_0 (the mesh's sRGB bytes
 * converted to linear, as glTF defines vertex colours) when given, TEXCOORD_0 (v flipped:
 * glTF's origin is the image's top left) when given with an image; indices as UNSIGNED_SHORT when the vertex
 * count < 65536, else UNSIGNED_INT; one matte double-sided material, with the given image
 * as its baseColorTexture; asset.generator "scanlod"; the caller's `extras_json` (may be
 * NULL) as the mesh's `extras`. Per sl_glb_options:
 *   - quantize: KHR_mesh_quantization. Positions on a uniform integer grid over the
 *     bounding box (the node's translation and uniform scale dequantise them), normals as
 *     signed normalized integers, texture coordinates in [0, 1] as unsigned normalized;
 *   - compression MESHOPT: EXT_meshopt_compression on every vertex stream and the
 *     indices (index codec version 1; normals through the octahedral filter when
 *     quantized), an uncompressed-size fallback buffer without data;
 *   - compression DRACO: KHR_draco_mesh_compression (edgebreaker; Draco quantises float
 *     attributes to the same bits itself); the accessors describe the decoded mesh, whose
 *     vertex count and order Draco may change;
 *   - morph_positions: one morph target (POSITION displacements), see below.
 * The files pass the Khronos glTF validator with 0 errors and 0 warnings
 * (tests/export/test_gltf_validator.sh; it cannot look inside compressed streams, so the
 * tests also decode them).
 *
 * Rejected, with nothing written:
 *   - a mesh with 0 triangles or 0 vertices: SL_E_BADINPUT "nothing to write" (glTF
 *     accessors need count >= 1, and an item without surface has no useful GLB);
 *   - a non-finite position: SL_E_BADINPUT (min/max and every viewer would break);
 *   - an index >= vertex_count: SL_E_INTERNAL (whoever built the mesh has a bug);
 *   - a file that would exceed the GLB's 32-bit length: SL_E_LIMIT;
 *   - extras_json that is not a {...} object text, bits out of range: SL_E_INTERNAL.
 * A NORMAL of zero length or with a non-finite component is written as (0, 0, 1), because
 * glTF requires unit normals; a non-finite texture coordinate as 0.
 *
 * Thread safety: reentrant; no global state (meshoptimizer's index codec version is set
 * to 1 before every use, the only value this code ever sets).
 */
#ifndef SCANLOD_GEOMETRY_GLB_H
#define SCANLOD_GEOMETRY_GLB_H

#include <stdint.h>

#include "core/error.h"
#include "geometry/mesh.h"

enum sl_glb_compression { SL_GLB_UNCOMPRESSED = 0, SL_GLB_MESHOPT = 1, SL_GLB_DRACO = 2 };

/* How a GLB is encoded. Bits are per component. */
typedef struct sl_glb_options {
    int compression;   /* enum sl_glb_compression */
    int quantize;      /* KHR_mesh_quantization (uncompressed and meshopt files; a Draco
                          stream is always quantised, to the same bits) */
    int position_bits; /* 8..16: grid step = largest bounding-box extent / (2^bits - 1) */
    int normal_bits;   /* 4..16: <= 8 stored as bytes, else shorts */
    int color_bits;    /* 8..16: 8 stored as bytes, else shorts holding that precision */
    int texcoord_bits; /* 8..16: shorts holding that precision (uv in [0, 1]) */
    /* The base colour texture: an encoded JPEG, PNG or WebP image embedded in the file and
     * used with the mesh's texcoords. NULL or no texcoords: none. A WebP image is the
     * texture's EXT_texture_webp source; with a fallback (a JPEG of it) the texture's core
     * source is the fallback and the extension is used, not required; without one it is
     * required. */
    const void *image;
    uint64_t image_size;
    const char *image_mime_type; /* "image/jpeg", "image/png" or "image/webp" */
    const void *fallback_image;  /* with image/webp: its JPEG, or NULL */
    uint64_t fallback_image_size;
    /* One morph target (docs/morphing.md): where each vertex of the mesh goes at weight 1
     * (3 floats per vertex, the mesh's frame), or NULL for none. Written as the primitive's
     * targets[0].POSITION, a displacement: float in float files; in quantised files
     * integer steps of the positions' own grid (SHORT, float when a displacement exceeds
     * 32767 steps); in Draco files float displacements from the decoded positions, stored
     * beside the Draco stream (KHR_draco_mesh_compression compresses no targets), each
     * decoded vertex taking the target of the nearest vertex given. The mesh's default
     * weight is 0: a viewer that ignores targets draws the mesh as given. */
    const float *morph_positions;
} sl_glb_options;

/* Float attributes, no compression: the plainest file, what sl_glb_write(.., NULL, ..)
 * writes. */
sl_glb_options sl_glb_default_options(void);

/* What the file holds, and how far its quantised attributes are from the mesh given
 * (measured on the values a viewer decodes: for Draco the decoded stream, each decoded
 * vertex against the nearest vertex given). Distances in the mesh's units. */
typedef struct sl_glb_stats {
    uint64_t bytes;                /* file size */
    uint64_t vertices, triangles;  /* as the file describes them */
    double position_step;          /* quantisation grid step; 0 = float positions */
    double position_bound;         /* sqrt(3)/2 x step: no vertex moves further */
    double position_error_max, position_error_rms; /* measured vertex displacement */
    double normal_error_max_deg;   /* largest angle between a written and a given normal */
    double color_error_max;        /* largest |decoded -> sRGB - given|, in 1/255 steps */
    int morph;                     /* the file has a morph target */
    double morph_error_max;        /* largest distance, decoded vertex + decoded displacement
                                      to the target given (world) */
    uint64_t morph_added_triangles; /* the export's morph refinement (morph_refine.h): */
    uint64_t morph_unresolved;      /* triangles it added, those it left spanning, */
    uint64_t morph_torn_triangles;  /* those it tore, and the widest tear at weight 1 */
    double morph_tear_max;          /* (metres, glTF frame) */
    double morph_unresolved_max;    /* how far the spanning ones stand off the coarser
                                       surface at weight 1 (metres, glTF frame) */
} sl_glb_stats;

/* `extras_json`: a JSON object text ("{...}") for mesh.extras, or NULL. `options`: NULL
 * for sl_glb_default_options(). `stats` (OUT, may be NULL). */
int sl_glb_write(const char *path, const sl_mesh *m, const char *extras_json,
                 const sl_glb_options *options, sl_glb_stats *stats, sl_error *err);

/* OBJ: `v x y z [r g b]` (colours as floats in [0, 1], the common extension that
 * MeshLab and Blender read), `vn` when normals are given, faces 1-based (`f a//a ...` with
 * normals). extras_json is written as a `#` comment line when it has no line break.
 * Rejects what sl_glb_write rejects, except the 32-bit size limit. */
int sl_obj_write(const char *path, const sl_mesh *m, const char *extras_json, sl_error *err);

#endif
