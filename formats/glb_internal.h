/* GLB writer internals: the document model glb_streams.c fills (bufferViews, accessors,
 * the node's dequantisation) and glb_write.c lays out and serialises. */
#ifndef SCANLOD_GEOMETRY_GLB_INTERNAL_H
#define SCANLOD_GEOMETRY_GLB_INTERNAL_H

#include <stdint.h>
#include <string.h>

#include "core/error.h"
#include "formats/glb.h"

/* glTF enums (the OpenGL values the spec reuses). */
enum {
    GLTF_TRIANGLES = 4,
    GLTF_BYTE = 5120,
    GLTF_UNSIGNED_BYTE = 5121,
    GLTF_SHORT = 5122,
    GLTF_UNSIGNED_SHORT = 5123,
    GLTF_UNSIGNED_INT = 5125,
    GLTF_FLOAT = 5126,
    GLTF_ARRAY_BUFFER = 34962,
    GLTF_ELEMENT_ARRAY_BUFFER = 34963
};

#define GLB_MAX_VIEWS 8
#define GLB_MAX_ACCESSORS 8

/* One bufferView. `data` is what a reader sees after decoding (stride x count bytes), or
 * for a meshopt stream the bytes fed to the encoder (filtered normals); `packed` is the
 * meshopt bitstream. Images and the Draco stream are stored as they are. */
typedef struct glb_view {
    unsigned char *data;
    uint64_t size;
    uint32_t stride;       /* element stride; 0 for indices, images and Draco */
    uint64_t count;        /* elements (meshopt `count`) */
    int target;            /* GLTF_ARRAY_BUFFER, GLTF_ELEMENT_ARRAY_BUFFER or 0 */
    const char *mode;      /* meshopt: "ATTRIBUTES" or "TRIANGLES"; NULL = stored plain */
    const char *filter;    /* meshopt filter ("OCTAHEDRAL") or NULL */
    unsigned char *packed;
    uint64_t packed_size;
    uint64_t offset;          /* in buffer 0 (plain) or the fallback buffer 1 (meshopt) */
    uint64_t packed_offset;   /* meshopt: in buffer 0 */
} glb_view;

typedef struct glb_accessor {
    const char *semantic;  /* "POSITION", ...; NULL for the indices */
    int view;              /* bufferView, or -1 (Draco: the data is in the extension) */
    int component;         /* GLTF_FLOAT, ... */
    const char *type;      /* "VEC3", "SCALAR", ... */
    int normalized;
    uint64_t count;
    int has_bounds;        /* POSITION: min/max */
    double min[3], max[3];
    int draco_id;          /* Draco attribute unique id, or -1 */
    int morph;             /* the primitive's targets[0] attribute `semantic` */
} glb_accessor;

typedef struct glb_doc {
    const sl_glb_options *opt;
    glb_view views[GLB_MAX_VIEWS];
    int view_count;
    glb_accessor accessors[GLB_MAX_ACCESSORS];
    int accessor_count;
    int indices;           /* accessor index of the indices */
    int image_view;        /* bufferView of the embedded image, or -1 */
    int fallback_view;     /* bufferView of a WebP image's JPEG fallback, or -1 */
    int draco_view;        /* bufferView of the Draco stream, or -1 */
    int quantized;         /* KHR_mesh_quantization is used */
    int node_transform;    /* the node dequantises positions: */
    float translation[3], scale;
    float *decoded_positions; /* Draco: the decoded mesh's positions (3 x stats.vertices) */
    sl_glb_stats stats;
} glb_doc;

/* Fills `d` from `m` per d->opt (set by the caller, with d zeroed): the streams, their
 * accessors, compression and the measured stats. SL_E_NOMEM, SL_E_INTERNAL (bits out of
 * range, an encoder failure). */
int glb_doc_build(glb_doc *d, const sl_mesh *m, sl_error *err);
void glb_doc_release(glb_doc *d);

/* The document model's builders (glb_doc.c). glb_add_view takes ownership of `data`;
 * `mode` is the meshopt mode, used in meshopt files only. */
int glb_add_view(glb_doc *d, unsigned char *data, uint64_t size, uint32_t stride,
                 uint64_t count, int target, const char *mode);
glb_accessor *glb_add_accessor(glb_doc *d, const char *semantic, int view, int component,
                               const char *type, int normalized, uint64_t count);

/* Adds the morph target of d->opt->morph_positions (glb_morph.c): after the positions
 * (quantised or not) are built, before meshopt packs the views, after Draco replaced
 * them. SL_E_NOMEM. */
int glb_morph_target(glb_doc *d, const sl_mesh *m, sl_error *err);

/* Whether the embedded image is WebP (EXT_texture_webp). */
static inline int glb_webp(const glb_doc *d)
{
    return d->opt->image_mime_type && !strcmp(d->opt->image_mime_type, "image/webp");
}

/* Linear value of an sRGB byte (IEC 61966-2-1), and its inverse on [0, 1]. */
double glb_srgb_to_linear(double srgb);
double glb_linear_to_srgb(double linear);

#endif
