/* Internals of the OBJ reader shared by obj_read.c (the two passes over the OBJ) and
 * obj_mtl.c (materials, the texture, and per-corner attributes onto the mesh).
 */
#ifndef SCANLOD_FORMATS_OBJ_INTERNAL_H
#define SCANLOD_FORMATS_OBJ_INTERNAL_H

#include <stdint.h>

#include "formats/scan_internal.h"

#define OBJ_MAX_MATERIALS 256  /* distinct `usemtl` names; later ones share the last slot */
#define OBJ_MAX_MTLLIBS 8      /* MTL files named by `mtllib` */
#define OBJ_NONE UINT32_MAX    /* a corner without a texture coordinate or normal */

/* What the first pass counts (every count bounded by the lines of the file). */
typedef struct obj_counts {
    uint64_t v, vt, vn, faces, triangles;
    uint64_t materials_lines;  /* usemtl lines */
    int v_columns;             /* numbers on the first `v` line (3, 4, 6 or 7) */
    int freeform;              /* curves or surfaces (not read) */
} obj_counts;

typedef struct obj_material {
    char name[128];
    char map_kd[256];          /* the texture, relative to the OBJ's directory; "" if none */
    int defined;               /* a `newmtl` of that name was found */
} obj_material;

typedef struct obj_reader {
    const scan_src *s;
    sl_mesh *m;
    obj_counts n;
    uint64_t nv, nvt, nvn;     /* read so far (negative indices count back from these) */
    float *vt, *vn;            /* 2 * n.vt, 3 * n.vn as read */
    float *rgb;                /* 3 * n.v vertex colours as written, once one is seen */
    uint64_t colored;          /* vertices with a colour */
    uint64_t tri_cap;
    uint32_t *corner_vt, *corner_vn; /* 3 per triangle: vt / vn index or OBJ_NONE */
    uint16_t *tri_material;    /* per triangle: index into materials, or OBJ_MAX_MATERIALS */
    obj_material *materials;   /* OBJ_MAX_MATERIALS, the `usemtl` names in first-use order */
    uint32_t material_count, current;
    char mtllib[OBJ_MAX_MTLLIBS][256];
    int mtllib_count, mtl_read;
    uint32_t *poly;            /* one face: 3 indices per corner */
    uint64_t poly_cap;
} obj_reader;

/* The first pass: counts of every kind of line (scan_read_info's facts, and the sizes the
 * second pass allocates). */
int obj_count(const scan_src *s, obj_counts *n);

/* The index of the material named by the rest of the line [p, eol) (trimmed; names
 * compare on their first 127 bytes), or -1. */
int obj_material_find(const obj_reader *r, const char *p, const char *eol);

/* After the second pass: the MTL files, the texture, texture coordinates per corner,
 * normals and colours per vertex onto r->m; warnings for what is missing. */
int obj_finish(obj_reader *r);

#endif
