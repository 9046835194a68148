/* range stage (paper 1, section 4 "range data from PLY"; docs/range-stage.md, "Decisions").
 *
 * A scan (PLY, OBJ + MTL, STL, OFF, XYZ/PTS, glTF/GLB through formats/scan_read.h; + its
 * texture image) -> an oriented, optionally coloured point set:
 *   - meshes: vertices that faces reference, exact-duplicate positions welded first,
 *     degenerate faces and non-finite coordinates dropped; normals are the area-weighted
 *     mean of adjacent face normals (paper) or the file's own ([range] normals = file);
 *   - raw range scans with a scanner grid (Stanford `range_grid`) are triangulated along
 *     the grid first, then treated as meshes;
 *   - point clouds without faces: normals by local PCA over the k nearest neighbours,
 *     oriented towards the scanner viewpoint when the file states one, else by
 *     propagation over a minimum spanning tree of the kNN graph;
 *   - colours from the vertex colours, else sampled from the texture image (a file, or
 *     embedded in a GLB) through OpenImageIO;
 *   - optionally ([range] range_images = true) six range images (depth + normal, one per
 *     axis direction) written as EXR.
 * Output: `points.slpts` (format in docs/formats.md) in the artifact directory.
 */
#ifndef SCANLOD_STAGES_RANGE_H
#define SCANLOD_STAGES_RANGE_H

#include <stdint.h>

#include "core/error.h"
#include "core/progress.h"
#include "geometry/mesh.h"
#include "formats/scan_read.h"
#include "pipeline/stage.h"

#define SL_POINTSET_FILE "points.slpts"
#define SL_POINTSET_FORMAT_VERSION 3u

extern const sl_stage sl_range_stage;

/* The oriented point set the range stage writes and the samples stage reads. */
typedef struct sl_pointset {
    uint64_t count;
    float *positions; /* 3 * count, world */
    float *normals;   /* 3 * count, unit length */
    uint8_t *colors;  /* 4 * count RGBA, or NULL */
    float *texcoords; /* 2 * count (u, v as the input's, v up): a textured input whose
                         points each have one texture coordinate, else NULL */
    float bbox_min[3], bbox_max[3];
    double mean_spacing; /* mean nearest-neighbour distance (world units) */
    uint32_t normal_source; /* enum sl_normal_source */
    uint64_t triangle_count; /* the input's kept triangles (0 for point clouds) */
    uint32_t *triangles;     /* 3 * triangle_count point indices, wound like the normals
                                (outwards on a closed mesh); NULL for point clouds */
} sl_pointset;

enum sl_normal_source {
    SL_NORMALS_FACES = 0,       /* area-weighted face normals */
    SL_NORMALS_FILE = 1,        /* the file's own */
    SL_NORMALS_PCA_VIEWPOINT = 2,
    SL_NORMALS_PCA_PROPAGATED = 3,
    SL_NORMALS_RANGE_GRID = 4   /* faces from the scanner grid */
};
const char *sl_normal_source_name(uint32_t source);

/* The resolved [range] section (options: stages/range/range_stage.c). */
typedef struct sl_range_config {
    int normals_from_file;         /* [range] normals = file: the file's vertex normals */
    uint32_t knn;                  /* neighbours for PCA normals and their propagation */
    double grid_max_edge_factor;   /* grid triangles with an edge longer than this times the
                                      median grid-neighbour distance are skipped */
    int range_images;              /* also write six axis-aligned range images (EXR) */
    int range_image_size;          /* their width = height, pixels */
    sl_scan_limits limits;         /* the scan readers' limits */
    double max_nonfinite_fraction; /* above this fraction of non-finite vertices: bad input */
    int colors;                    /* 0: none; 1: auto (vertex colours, else texture) */
} sl_range_config;

/* The section at its option table's defaults (sl_stage_default_config). */
sl_range_config sl_range_default_config(void);

/* What the stage saw and did; every dropped element is counted by reason. For meshes
 * input_vertices = points + welded + unreferenced + nonfinite_vertices. */
typedef struct sl_range_counts {
    uint64_t input_vertices, input_faces;
    uint64_t points;
    uint64_t welded;               /* finite vertices merged into an identical earlier one */
    uint64_t unreferenced;         /* finite, not welded, used by no kept face (meshes) */
    uint64_t nonfinite_vertices;   /* a NaN/Inf coordinate */
    uint64_t nonfinite_faces;      /* faces dropped because a corner is non-finite */
    uint64_t degenerate_faces;     /* repeated corner after welding, or zero area */
    uint64_t polygons_triangulated;/* by the reader (fan) */
    uint64_t grid_triangles;       /* triangles made along the scanner grid */
    uint64_t grid_long_edges;      /* grid triangles skipped: an edge > grid_max_edge */
    double grid_max_edge;          /* world units; 0 when no grid */
    int grid_flipped;              /* grid winding flipped to face the scanner */
    uint64_t normal_fallbacks;     /* file normal zero/non-finite (or zero face-normal sum) */
    int normals_flipped;           /* face normals pointed inwards (an inside-out mesh) and
                                      were all flipped */
    uint64_t pca_components;       /* connected components of the kNN graph (propagation) */
    uint64_t texture_warnings;     /* texture missing or unreadable, or no texcoords */
    char texture_warning[320];     /* the first such warning, "" if none */
    uint64_t colors_unsampled;     /* points that got no colour sample (grey) */
    uint32_t normal_source;        /* enum sl_normal_source */
    const char *color_source;      /* "none", "vertex", "texture" */
    const char *texcoord_source;   /* "none", "vertices", "corners": the points' texcoords */
    uint64_t texcoord_seams;       /* corners whose point has another texcoord (or none) */
} sl_range_counts;

/* The stage's work on an in-memory mesh: `mesh` is consumed (its arrays may be changed or
 * taken; release it afterwards as usual). Textures named by mesh->texture_file are looked
 * up in `texture_dir` (NULL: no texture). OUT: *out (release with sl_pointset_release;
 * out->triangles holds the kept triangles in point indices, wound like the normals) and
 * *counts. Returns 0, SL_E_BADINPUT (nothing usable, too many non-finite vertices),
 * SL_E_NOMEM or SL_E_INTERRUPTED. */
int sl_range_points_from_mesh(const sl_range_config *cfg, sl_mesh *mesh, const char *texture_dir,
                              sl_pointset *out, sl_range_counts *counts, sl_progress *progress,
                              sl_error *err);

/* Writes the six range images (docs/range-stage.md) of `ps` into `dir`; its triangles are
 * rasterised, or for a point cloud its points splatted. */
int sl_range_images_write(const char *dir, const sl_pointset *ps, int size,
                          sl_progress *progress, sl_error *err);

int sl_pointset_write(const char *path, const sl_pointset *ps, sl_error *err);
/* Validates magic, versions, sizes (against the file size) and checksum. */
int sl_pointset_read(const char *path, sl_pointset *out, sl_error *err);
void sl_pointset_release(sl_pointset *ps);

#endif
