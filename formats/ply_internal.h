/* Internals of the PLY reader shared by ply.c, ply_header.c, ply_body.c, ply_binary.c
 * and ply_ascii.c (not a public interface; tests may include it for the number parsers).
 *
 * The reader works on one contiguous byte range (an mmap of the file, or the caller's
 * buffer): the header parser turns the header into a table of elements and properties
 * with a *role* per property (what the mesh wants from it, or SKIP), checks every declared
 * count against the bytes after the header, and the body readers then walk the elements
 * in file order, each read bounded by the end of the range.
 */
#ifndef SCANLOD_GEOMETRY_PLY_INTERNAL_H
#define SCANLOD_GEOMETRY_PLY_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "formats/ply.h"
#include "formats/text_number.h"

/* Fixed header table sizes: real files use a handful; more is hostile or broken. */
#define PLY_MAX_ELEMENTS 64
#define PLY_MAX_PROPERTIES 512
#define PLY_NAME_MAX 64

enum ply_type {
    PLY_NONE = 0,
    PLY_INT8, PLY_UINT8, PLY_INT16, PLY_UINT16,
    PLY_INT32, PLY_UINT32, PLY_FLOAT32, PLY_FLOAT64
};

/* What the mesh takes from a property. */
enum ply_role {
    ROLE_SKIP = 0,
    ROLE_X, ROLE_Y, ROLE_Z,
    ROLE_NX, ROLE_NY, ROLE_NZ,
    ROLE_RED, ROLE_GREEN, ROLE_BLUE, ROLE_ALPHA,
    ROLE_U, ROLE_V,
    ROLE_INDICES,       /* face vertex_indices / vertex_index */
    ROLE_TEXCOORD,      /* face texcoord list */
    ROLE_VIEW_X, ROLE_VIEW_Y, ROLE_VIEW_Z, /* camera view_px/py/pz */
    ROLE_GRID_INDICES,  /* range_grid vertex_indices */
    ROLE_COUNT_
};

enum ply_kind { KIND_OTHER = 0, KIND_VERTEX, KIND_FACE, KIND_CAMERA, KIND_GRID };

typedef struct ply_property {
    char name[PLY_NAME_MAX]; /* truncated copy for messages and `inspect` */
    uint8_t type;            /* scalar type, or the item type of a list */
    uint8_t count_type;      /* PLY_NONE for a scalar */
    uint8_t role;
    uint32_t offset;         /* byte offset in a fixed-size binary row */
} ply_property;

typedef struct ply_element {
    char name[PLY_NAME_MAX];
    uint64_t count;
    int kind;
    int header_line;
    int first_prop, nprops;  /* slice of ply_header.props */
    int fixed_row;           /* no list properties: binary rows have row_bytes bytes */
    uint64_t row_bytes;      /* binary: fixed row size (lists count as their count only) */
    uint64_t min_row_bytes;  /* smallest possible row in this format */
} ply_element;

typedef struct ply_header {
    sl_ply_format format;
    uint64_t header_bytes;
    int nelements, nprops;
    ply_element elements[PLY_MAX_ELEMENTS];
    ply_property props[PLY_MAX_PROPERTIES];
    int64_t grid_cols, grid_rows;   /* obj_info num_cols/num_rows, -1 when absent */
    int has_viewpoint;              /* from a comment/obj_info line */
    double viewpoint[3];
    char texture_file[256];
    char units[4];                  /* from `comment units NAME`, canonical ("mm"), or "" */
    char up_axis;                   /* from `comment up AXIS`: 'y', 'z', or 0 */
    /* indices into elements, -1 when absent; only the first camera/range_grid counts */
    int vertex_element, face_element, camera_element, grid_element;
    uint8_t role_seen[ROLE_COUNT_];   /* roles present in vertex/face/camera/grid */
} ply_header;

/* Parses and validates the header of data[0..size). On success h->header_bytes is the
 * offset of the body and every element count fits in the body bytes. */
int sl_ply_parse_header(const unsigned char *data, size_t size, const char *name,
                        const sl_ply_limits *lim, ply_header *h, sl_error *err);

/* Fills `info` from a parsed header. */
void sl_ply_header_info(const ply_header *h, sl_ply_info *info);

/* Whether the mesh will get normals / colours / per-vertex uv / face texcoords / grid. */
int sl_ply_wants_normals(const ply_header *h);
int sl_ply_wants_colors(const ply_header *h);
int sl_ply_wants_texcoords(const ply_header *h);
int sl_ply_wants_face_texcoords(const ply_header *h);
int sl_ply_wants_grid(const ply_header *h);

int sl_ply_type_size(int type);

const char *sl_ply_type_name(int type);

/* The body reader: cursor, target mesh, scratch for one polygon. */
typedef struct ply_reader {
    const ply_header *h;
    const char *name;
    const sl_ply_limits *lim;
    sl_error *err;
    sl_progress *progress;
    const unsigned char *data, *body, *p, *end;
    int swap;                      /* binary data in the other byte order than the host */
    sl_mesh *mesh;
    const ply_element *elem;       /* element being read (for messages) */
    uint64_t row;                  /* row being read (for messages) */
    uint64_t tri_cap;              /* capacity of mesh->triangles, in triangles */
    uint32_t *corners;             /* one polygon's indices */
    float *corner_uv;              /* one polygon's texcoord list */
    uint64_t corners_cap, corner_uv_cap, corner_uv_len;
    int have_camera;               /* bits of camera[] seen in the first camera row */
    double camera[3];
} ply_reader;

/* Reads the body after sl_ply_parse_header into r->mesh. */
int sl_ply_read_body(ply_reader *r);

/* Records an error at the reader's position ("line 12: element face row 3: ..."). */
int sl_ply_body_error(ply_reader *r, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Sinks shared by the binary and ascii readers (ply_body.c). `value` is exact for every
 * PLY scalar type (all fit a double). */
void sl_ply_store_vertex(ply_reader *r, uint64_t row, int role, int type, double value);
int sl_ply_store_list_item(ply_reader *r, int role, uint64_t i, double value);
int sl_ply_begin_list(ply_reader *r, int role, uint64_t n);
int sl_ply_end_face(ply_reader *r, uint64_t ncorners);
int sl_ply_check_index(ply_reader *r, double value, uint32_t *index);
int sl_ply_push_triangle(ply_reader *r, uint32_t a, uint32_t b, uint32_t c);
int sl_ply_tick(ply_reader *r);

/* Element readers per format. */
int sl_ply_binary_element(ply_reader *r, const ply_element *e);
int sl_ply_ascii_element(ply_reader *r, const ply_element *e);

/* Where a float vertex role goes in the mesh (positions, normals, texcoords) with its
 * stride in floats, or NULL (colours, camera, arrays the mesh does not have). */
float *sl_ply_float_column(sl_mesh *m, int role, size_t *stride);

#endif
