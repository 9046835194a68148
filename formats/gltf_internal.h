/* Internals of the glTF 2.0 / GLB reader (docs/inputs.md, "glTF"), shared by
 *   gltf_doc.c       the container (GLB chunks or JSON text), buffers, bufferViews and
 *                    accessors as checked tables, extensions;
 *   gltf_data.c      the bytes of a bufferView (buffers loaded on first use, meshopt streams
 *                    decoded) and accessors read as floats or indices;
 *   gltf_scene.c     the default scene's nodes, their transforms, the primitives drawn and
 *                    what they hold, and the texture;
 *   gltf_read.c      the primitives onto one sl_mesh (Draco included), the entry points.
 */
#ifndef SCANLOD_FORMATS_GLTF_INTERNAL_H
#define SCANLOD_FORMATS_GLTF_INTERNAL_H

#include <stdint.h>

#include "formats/json_read.h"
#include "formats/scan_internal.h"
#include "shim/draco_shim.h"

#define GLTF_MAX_TOKENS (1u << 22)   /* JSON values: 4 M (a few MB of tokens) */
#define GLTF_MAX_DRAWS (1u << 20)    /* primitive instances in the scene */
#define GLTF_MAX_DEPTH 64            /* node nesting */
#define GLTF_MAX_EXPANSION 64        /* drawn vertices (and triangles) per byte of input */
#define GLTF_NONE UINT32_MAX

enum gltf_component {
    GLTF_BYTE = 5120, GLTF_UNSIGNED_BYTE = 5121, GLTF_SHORT = 5122,
    GLTF_UNSIGNED_SHORT = 5123, GLTF_UNSIGNED_INT = 5125, GLTF_FLOAT = 5126
};

enum gltf_meshopt_mode { MESHOPT_ATTRIBUTES, MESHOPT_TRIANGLES, MESHOPT_INDICES };
enum gltf_meshopt_filter { MESHOPT_NONE, MESHOPT_OCTAHEDRAL, MESHOPT_QUATERNION,
                           MESHOPT_EXPONENTIAL, MESHOPT_COLOR };

typedef struct gltf_buffer {
    uint64_t byte_length;
    uint32_t uri;               /* its `uri` token; 0: the GLB's BIN chunk, or none */
    int fallback;               /* a meshopt fallback: declared, holds no data */
    int loaded;
    const unsigned char *data;  /* byte_length bytes once loaded */
    unsigned char *owned;       /* a decoded data: URI */
    void *map;                  /* an external file, mapped */
    size_t map_size;
} gltf_buffer;

typedef struct gltf_meshopt {
    uint32_t buffer;
    uint64_t offset, length;    /* the compressed stream */
    uint64_t count;
    uint32_t stride;
    int mode, filter;           /* enum gltf_meshopt_mode / _filter */
    const char *extension;      /* "EXT_meshopt_compression" or "KHR_meshopt_compression" */
} gltf_meshopt;

typedef struct gltf_view {
    uint32_t buffer;
    uint64_t offset, length;
    uint32_t stride;            /* 0: tightly packed */
    int meshopt;                /* compressed: `mo` says how */
    gltf_meshopt mo;
    unsigned char *decoded;     /* the decoded stream (length bytes), once asked for */
} gltf_view;

typedef struct gltf_sparse {
    uint64_t count;
    uint32_t index_view, value_view;
    uint64_t index_offset, value_offset;
    uint32_t index_component;
} gltf_sparse;

typedef struct gltf_accessor {
    uint32_t view;              /* GLTF_NONE: all zeros (then sparse) */
    uint64_t offset, count;
    uint32_t component;         /* enum gltf_component */
    int components;             /* 1..4 (SCALAR, VECn); 0 for matrices, not read */
    int normalized;
    gltf_sparse sparse;         /* count 0: none */
} gltf_accessor;

/* The primitives the scene draws (one per primitive per node that shows its mesh). */
typedef struct gltf_draw {
    uint32_t primitive;         /* its JSON token */
    double world[16];           /* the node's world transform, column-major */
    uint32_t position, normal, color, texcoord, indices; /* accessors or GLTF_NONE */
    uint32_t draco;             /* the KHR_draco_mesh_compression object token, or 0 */
    int mode;                   /* 0 points, 4 triangles, 5 strip, 6 fan */
    uint32_t material;          /* or GLTF_NONE */
    uint64_t vertices, triangles; /* as the accessors declare; a Draco draw's once decoded */
    sl_draco_mesh *decoded;     /* a Draco draw's stream, decoded (gltf_read.c) */
    int slot[4];                /* its attributes: position, normal, colour, texcoord; -1 */
} gltf_draw;

typedef struct gltf_doc {
    const scan_src *s;
    sl_mesh *m;                 /* warnings go here (NULL for the info alone) */
    sl_jdoc j;
    int glb;
    const unsigned char *bin;   /* the GLB's BIN chunk */
    uint64_t bin_size;
    gltf_buffer *buffers;
    gltf_view *views;
    gltf_accessor *accessors;
    uint32_t buffer_count, view_count, accessor_count;
    /* tokens of the top-level arrays, and of each of their items */
    uint32_t meshes, nodes, materials, textures, images, scenes;
    uint32_t *mesh_tok, *node_tok, *material_tok, *texture_tok, *image_tok;
    uint32_t mesh_count, node_count, material_count, texture_count, image_count;
    gltf_draw *draws;
    uint64_t draw_count;
    uint32_t texture_image;     /* the image the mesh carries, or GLTF_NONE */
    int texcoord_set;           /* its TEXCOORD_n */
    uint32_t texture_material;  /* the material it comes from */
    int uv_transform_set;       /* KHR_texture_transform on its textureInfo: */
    double uv_transform[6];     /* u' = t0 u + t2 v + t4, v' = t1 u + t3 v + t5 */
} gltf_doc;

/* gltf_doc.c */
int gltf_open(gltf_doc *g, const scan_src *s, sl_mesh *warnings_to);
void gltf_close(gltf_doc *g);
int gltf_error(const gltf_doc *g, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void gltf_warn(const gltf_doc *g, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* A member that must be an index below `limit` when present: 1 and *out, 0 when absent;
 * a present bad value records an error naming `where` and returns it (negative). */
int gltf_index(const gltf_doc *g, uint32_t object, const char *key, uint64_t limit,
               const char *where, uint32_t *out);
int gltf_component_size(uint32_t component);

/* gltf_data.c */
/* Whether string token `uri` is a data: URI. */
int gltf_is_data_uri(const gltf_doc *g, uint32_t uri);
/* A base64 data: URI decoded into *out (malloc'd, *size bytes), its media type into mime. */
int gltf_data_uri(const gltf_doc *g, uint32_t uri, unsigned char **out, uint64_t *size,
                  char *mime, size_t mime_size, const char *where);
/* A relative URI as a file name: JSON escapes and %XX escapes decoded. */
void gltf_uri_name(const gltf_doc *g, uint32_t uri, char *out, size_t size);
/* The bytes of bufferView v (its buffer loaded, or its meshopt stream decoded). */
int gltf_view_bytes(gltf_doc *g, uint32_t v, const unsigned char **data, uint64_t *size);
/* Whether accessor `a` can be read: its elements inside its view (the view's buffer
 * loaded, a meshopt stream decoded), or, without a view, no more elements than the file
 * has bytes. What is checked before the mesh is allocated from the accessors' counts. */
int gltf_check_accessor(gltf_doc *g, uint32_t a, const char *what);
/* Accessor `a` as `want` floats per element (its components first, normalised as glTF
 * says; missing ones 0) into out[count * want]. `what` names it in messages. */
int gltf_read_floats(gltf_doc *g, uint32_t a, int want, float *out, const char *what);
/* Index accessor `a` into out[count], each checked < `vertices`. */
int gltf_read_indices(gltf_doc *g, uint32_t a, uint64_t vertices, uint32_t *out);
/* Raw values of one component type (a Draco stream's) to floats, as an accessor of that
 * type and normalisation reads. */
void gltf_convert(const unsigned char *src, uint32_t component, int normalized, int components,
                  uint64_t stride, uint64_t count, int want, float *out);

/* gltf_scene.c */
/* The draws of the default scene, their counts, and the texture (g->draws ...). */
int gltf_plan(gltf_doc *g);

/* gltf_read.c: the draws onto the mesh. */
int gltf_fill(gltf_doc *g, sl_mesh *m);

#endif
