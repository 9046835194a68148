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

#include "geometry/ply.h"

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

/* double -> float without the undefined out-of-range conversion (saturates to inf). */
static inline float sl_ply_to_float(double v)
{
    return v > 3.4028234663852886e38 ? __builtin_inff()
           : v < -3.4028234663852886e38 ? -__builtin_inff() : (float)v;
}
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

/* Number parsers for ascii PLY. They parse one token starting at p (no leading
 * whitespace) that must end at `end` or at whitespace, and return the position after it,
 * or NULL when the token is not a number of that kind. Floats equal strtof/strtod of the
 * token (a fast exact path for up to 19 significant digits, strtof/strtod otherwise). */
const char *sl_ply_parse_float(const char *p, const char *end, float *out);
const char *sl_ply_parse_double(const char *p, const char *end, double *out);
const char *sl_ply_parse_int(const char *p, const char *end, int64_t *out);

/* How many of the 8 bytes at p are leading ASCII digits (0..8), and their value: eight
 * characters at a time (SWAR, the method of Lemire's fast_float). Reads 8 bytes. */
static inline int sl_ply_digits8(const char *p, uint64_t *value)
{
    uint64_t v;
    __builtin_memcpy(&v, p, sizeof v);
#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    v = __builtin_bswap64(v); /* first character in the low byte */
#endif
    uint64_t nondigit = ((v + 0x4646464646464646ull) | (v - 0x3030303030303030ull)) &
                        0x8080808080808080ull;
    int n = nondigit ? __builtin_ctzll(nondigit) / 8 : 8;
    if (n == 0)
        return 0;
    if (n < 8) /* keep the n digits, as the last ones of "000..." */
        v = v << (8 * (8 - n)) | (0x3030303030303030ull >> (8 * n));
    v -= 0x3030303030303030ull;
    v = v * 10 + (v >> 8);
    *value = (((v & 0x000000FF000000FFull) * 0x000F424000000064ull) +
              (((v >> 16) & 0x000000FF000000FFull) * 0x0000271000000001ull)) >> 32;
    return n;
}

/* sl_ply_parse_int inline, for the ascii hot loops: [sign] 1..18 digits. */
static inline const char *sl_ply_scan_int(const char *p, const char *end, int64_t *out)
{
    int neg = 0;
    uint64_t v = 0;
    if (p < end && (*p == '-' || *p == '+'))
        neg = *p++ == '-';
    const char *start = p;
    if (end - p > 19) /* no end checks needed: at most 20 bytes are looked at */
        while ((unsigned)(*p - '0') < 10u && p - start < 19)
            v = v * 10 + (uint64_t)(*p++ - '0');
    else
        while (p < end && (unsigned)(*p - '0') < 10u)
            v = v * 10 + (uint64_t)(*p++ - '0');
    if (p == start || p - start > 18 ||
        (p < end && *p != ' ' && (unsigned)(*p - '\t') >= 5u))
        return NULL;
    *out = neg ? -(int64_t)v : (int64_t)v;
    return p;
}

/* Where a float vertex role goes in the mesh (positions, normals, texcoords) with its
 * stride in floats, or NULL (colours, camera, arrays the mesh does not have). */
float *sl_ply_float_column(sl_mesh *m, int role, size_t *stride);

#endif
