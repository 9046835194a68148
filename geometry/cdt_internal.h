/* The triangulation the CDT builds (geometry/cdt.c inserts points, cdt_constrain.c
 * inserts loop edges): triangles with neighbour links, in one array whose slots the
 * constraint insertion reuses. Private to geometry/cdt*.c.
 *
 * Vertices 0 .. n-1 are the input points, n .. n+2 the corners of a bounding "super"
 * triangle that contains them all strictly; every triangle is counter-clockwise.
 */
#ifndef SCANLOD_GEOMETRY_CDT_INTERNAL_H
#define SCANLOD_GEOMETRY_CDT_INTERNAL_H

#include <stdint.h>

#include "geometry/cdt.h"

#define CDT_NONE UINT32_MAX

/* Edge i of a triangle is the one opposite v[i]; it runs v[i+1] -> v[i+2]. */
typedef struct cdt_tri {
    uint32_t v[3];
    uint32_t n[3];  /* n[i]: the triangle across edge i, CDT_NONE outside the super triangle */
    uint8_t flags;  /* bit i: edge i is a loop edge; bit 3 + i: the loop runs along it in
                       the triangle's own direction (the triangle is on the loop's left);
                       bit 6: in the cavity of the loop edge being inserted */
} cdt_tri;

#define CDT_CONSTRAINED(i) (1u << (i))
#define CDT_FORWARD(i) (8u << (i))
#define CDT_IN_CAVITY 0x40u

typedef struct cdt_work {
    uint32_t n;            /* input points */
    double *xy;            /* 2 * (n + 3): input points, then the super triangle's corners */
    cdt_tri *tri;
    uint32_t tri_count;    /* slots in use */
    uint32_t *vt;          /* per vertex: a triangle that has it, CDT_NONE if not inserted */
    uint32_t *rep;         /* per input point: itself, or the lower point it was merged into */
    uint64_t rng;          /* the walk's deterministic coin */
    uint32_t *stack;       /* scratch (legalisation, flood fill), tri capacity entries */
    uint32_t *crossed;     /* constraint insertion scratch, tri capacity entries */
    uint64_t split_edges;
    sl_cdt_report *report;
    sl_error *err;
} cdt_work;

static inline const double *cdt_xy(const cdt_work *w, uint32_t v)
{
    return w->xy + 2 * (uint64_t)v;
}

/* The index (0..2) of vertex v in triangle t, or 3 if absent. */
static inline int cdt_index_of(const cdt_tri *t, uint32_t v)
{
    return t->v[0] == v ? 0 : t->v[1] == v ? 1 : t->v[2] == v ? 2 : 3;
}

/* Records a refusal in w->report and w->err; returns SL_E_BADINPUT. */
int cdt_refuse(cdt_work *w, int problem, uint32_t a, uint32_t b, uint32_t c, uint32_t d,
               const char *fmt, ...) __attribute__((format(printf, 7, 8)));

/* Inserts every loop edge of `in` (indices already checked) as a constrained edge. */
int cdt_insert_loops(cdt_work *w, const sl_cdt_input *in);

#endif
