/* Levels as artifacts: what every method's stage writes, the refine stage reads and writes,
 * and the export stage publishes (docs/levels.md, docs/formats.md "Levels").
 *
 * A level list is a folder of artifact files in a stage's output:
 *   levels.sllst       the list: the input's size, then one record per level in the ladder's
 *                      order (intermediate models after the level they lead to), no geometry;
 *   NAME.sllvl         one level's mesh: positions, optional colours, texture coordinates and
 *                      input vertex of each vertex, and its triangles.
 * One file per mesh, so a writer holds one level at a time and a reader loads one when it
 * needs it (the export holds a level and the next coarser one, not the whole ladder).
 * Both files use core/artifact.h's envelope; readers check every count against the bytes
 * there are before allocating, every index against its range, every name as a file stem.
 */
#ifndef SCANLOD_LEVELS_LEVEL_H
#define SCANLOD_LEVELS_LEVEL_H

#include <stdint.h>

#include "core/error.h"
#include "levels/ladder.h"

#define SL_LEVEL_LIST_FILE "levels.sllst"
#define SL_LEVEL_MESH_SUFFIX ".sllvl"
#define SL_LEVEL_METHOD_SIZE 16

enum sl_level_flags {
    SL_LEVEL_INTERMEDIATE = 1u << 0, /* paper 2's intermediate model, not a rung */
    SL_LEVEL_REACHED = 1u << 1,      /* the rung's count was met (within 1 %, or below it) */
    SL_LEVEL_CLAMPED = 1u << 2,      /* the rung asked for the input's triangles or more */
    SL_LEVEL_SCAN = 1u << 3,         /* the scan itself: the input's vertices and triangles */
    SL_LEVEL_PROVEN = 1u << 4,       /* `bound` is proven (paper 2), not an estimate */
    SL_LEVEL_REFINED = 1u << 5,      /* collapsed and/or fitted by the refine stage */
};

/* One level: a record and, once read or made, its mesh. */
typedef struct sl_level {
    char name[SL_LEVEL_NAME_SIZE];  /* file stem; intermediates "LEVEL.morphJ" */
    char from[SL_LEVEL_NAME_SIZE];  /* the finer level it was made from, "" for the input */
    char method[SL_LEVEL_METHOD_SIZE]; /* what made it: scan, octree, segment, cluster */
    uint32_t flags;                 /* enum sl_level_flags */
    sl_rung rung;                   /* what it was asked as (intermediates: their level's) */
    uint64_t budget;                /* the triangles the rung asked for at this input (0:
                                       an expansions rung) */
    double bound;                   /* world: Hausdorff bound to the input (0: none) */
    double bound_fraction;          /* bound / the input's diagonal */
    uint32_t expansions;            /* octree: the cut's k (expansions of the LOD array) */
    uint32_t unpatched_cells;       /* octree: cells the crack patching could not close */

    /* The mesh; arrays malloc'd (NULL until read), released by sl_level_release. */
    uint64_t vertex_count;
    float *positions;     /* 3 * vertex_count, world */
    uint8_t *colors;      /* 4 * vertex_count RGBA (sRGB), or NULL */
    float *texcoords;     /* 2 * vertex_count (u, v; v up as in the input file), or NULL */
    uint32_t *source;     /* vertex_count: the input point each vertex is or came from, or
                             NULL (octree cuts) */
    uint64_t triangle_count;
    uint32_t *triangles;  /* 3 * triangle_count, into the vertices */
} sl_level;

typedef struct sl_level_list {
    uint64_t input_triangles; /* the input's (range stage's) triangles, 0 for a point set */
    uint64_t input_points;    /* its points */
    double diagonal;          /* world: the input's bounding-box diagonal */
    uint32_t model_expansions; /* the octree model's LOD array length (0: no model) */
    uint64_t model_triangles;  /* its finest level's triangles */
    uint32_t count;
    sl_level *levels;          /* records (meshes not read) */
} sl_level_list;

/* Frees the mesh arrays (the record stays). */
void sl_level_release_mesh(sl_level *lv);
/* Frees every level's mesh and the list; zeroes it. */
void sl_level_list_release(sl_level_list *list);

/* Writes lv's mesh to DIR/NAME.sllvl. */
int sl_level_write_mesh(const char *dir, const sl_level *lv, sl_error *err);
/* Reads lv->name's mesh from DIR into lv (its arrays must be NULL). Counts must agree with
 * the record's when the record has them (nonzero). `max_source` > 0: every source index
 * must be below it. */
int sl_level_read_mesh(const char *dir, sl_level *lv, uint64_t max_source, sl_error *err);

/* Writes DIR/levels.sllst (records only). */
int sl_level_list_write(const char *dir, const sl_level_list *list, sl_error *err);
/* Reads DIR/levels.sllst (records only; meshes NULL). */
int sl_level_list_read(const char *dir, sl_level_list *out, sl_error *err);
/* 1 when DIR holds a level list. */
int sl_level_list_present(const char *dir);

/* A level's mesh made of some of a point set's points: the points `triangles` (point
 * indices, 3 * triangle_count) use, in point order, with their positions, colours and
 * texture coordinates (`colors`, `texcoords` may be NULL) and their point index as
 * `source`; the triangles renumbered.
 * The record is left as it is. 0, or SL_E_NOMEM (then nothing is held). */
int sl_level_from_points(sl_level *lv, uint64_t point_count, const float *positions,
                         const uint8_t *colors, const float *texcoords, uint64_t triangle_count,
                         const uint32_t *triangles, sl_error *err);

/* Copies the record of `from` (not its mesh) into `to`. */
void sl_level_copy_record(sl_level *to, const sl_level *from);

#endif
