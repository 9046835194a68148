/* extern "C" shim around Google's Draco (C++, Debian libdraco-dev 1.5.5): the triangle-mesh
 * encoder and decoder that KHR_draco_mesh_compression (glTF, Draco bitstream 2.2) needs.
 *
 * Encoding: edgebreaker, the given speed (0 smallest .. 10 fastest; gltf-transform uses 5),
 * each float attribute quantised to its `bits` (Draco quantises over the attribute's own
 * bounding cube: step = largest extent / (2^bits - 1)); integer attributes are lossless.
 * Draco may reorder vertices and faces and split vertices at non-manifold places: what a
 * file describes is the *decoded* mesh, so sl_draco_decode is part of writing one (the
 * glTF accessors' counts and POSITION min/max come from it).
 *
 * Every entry point catches every exception and returns an sl_error. Reentrant.
 */
#ifndef SCANLOD_SHIM_DRACO_SHIM_H
#define SCANLOD_SHIM_DRACO_SHIM_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

#ifdef __cplusplus
extern "C" {
#endif

enum sl_draco_semantic { SL_DRACO_POSITION, SL_DRACO_NORMAL, SL_DRACO_COLOR, SL_DRACO_TEXCOORD };
enum sl_draco_type {
    SL_DRACO_F32, SL_DRACO_U8, SL_DRACO_U16,
    SL_DRACO_I8, SL_DRACO_I16, SL_DRACO_U32, /* what a file's stream may hold (decoding) */
    SL_DRACO_ANY = -1 /* decoding: the attribute's own type, set by sl_draco_decode */
};

#define SL_DRACO_MAX_ATTRIBUTES 4

typedef struct sl_draco_attribute {
    int semantic;    /* enum sl_draco_semantic */
    int type;        /* enum sl_draco_type of `data` (the decoded type is the same) */
    int components;  /* 1..4 */
    int normalized;  /* integer types: the values are normalized (glTF accessor flag) */
    int bits;        /* float types: quantisation bits (1..30); ignored for integers */
    void *data;      /* vertex_count * components values, tightly packed */
    int unique_id;   /* OUT of sl_draco_encode: the id glTF's extension names it by */
} sl_draco_attribute;

typedef struct sl_draco_mesh {
    uint64_t vertex_count, triangle_count;
    uint32_t *triangles;                              /* 3 * triangle_count */
    int attribute_count;
    sl_draco_attribute attributes[SL_DRACO_MAX_ATTRIBUTES];
} sl_draco_mesh;

/* Encodes `m` (attributes with data; at most SL_DRACO_MAX_ATTRIBUTES, vertex and triangle
 * counts below 2^31) into *out (OUT: malloc'd, *out_size bytes; free()). Sets each
 * attribute's unique_id. SL_E_NOMEM, SL_E_LIMIT or SL_E_INTERNAL (Draco's message). */
int sl_draco_encode(sl_draco_mesh *m, int speed, void **out, size_t *out_size, sl_error *err);

/* Decodes `data` into `out` (OUT): the attributes named by out->attributes[i].unique_id,
 * type and components (the caller fills those and attribute_count before the call; data
 * is allocated here). A type of SL_DRACO_ANY or 0 components take the stream's own (set
 * on return; a type outside enum sl_draco_type is refused), and `normalized` is set from
 * the stream. SL_E_CORRUPT when the bytes are not a Draco mesh or an attribute is missing
 * or of another type. Release with sl_draco_mesh_release. */
int sl_draco_decode(const void *data, size_t size, sl_draco_mesh *out, sl_error *err);

/* Frees what sl_draco_decode allocated (triangles and attribute data). */
void sl_draco_mesh_release(sl_draco_mesh *m);

#ifdef __cplusplus
}
#endif
#endif
