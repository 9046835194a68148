/* range stage (paper 1, section 4 "range data from PLY"; ARCHITECTURE section 5 "Points").
 *
 * PLY (+ texture image) -> an oriented, optionally coloured point set:
 *   - meshes: vertices that faces reference, exact-duplicate positions welded first,
 *     degenerate faces and non-finite coordinates dropped; normals are the area-weighted
 *     mean of adjacent face normals (paper) or the file's own ([range] normals = file);
 *   - raw range scans with a scanner grid (Stanford `range_grid`) are triangulated along
 *     the grid first, then treated as meshes;
 *   - point clouds without faces: normals by local PCA over the k nearest neighbours,
 *     oriented towards the scanner viewpoint when the file states one, else by
 *     propagation over a minimum spanning tree of the kNN graph;
 *   - colours from the vertex colours, else sampled from the texture image through
 *     OpenImageIO;
 *   - optionally ([range] range_images = true) six range images (depth + normal, one per
 *     axis direction) written as EXR.
 * Output: `points.slpts` (format in docs/formats.md) in the artifact directory.
 */
#ifndef SCANLOD_STAGES_RANGE_H
#define SCANLOD_STAGES_RANGE_H

#include <stdint.h>

#include "pipeline/error.h"
#include "pipeline/stage.h"

#define SL_POINTSET_FILE "points.slpts"
#define SL_POINTSET_FORMAT_VERSION 1u

extern const sl_stage sl_range_stage;

/* The oriented point set the range stage writes and the samples stage reads. */
typedef struct sl_pointset {
    uint64_t count;
    float *positions; /* 3 * count, world */
    float *normals;   /* 3 * count, unit length */
    uint8_t *colors;  /* 4 * count RGBA, or NULL */
    float bbox_min[3], bbox_max[3];
    double mean_spacing; /* mean nearest-neighbour distance (world units) */
    uint32_t normal_source; /* enum sl_normal_source */
} sl_pointset;

enum sl_normal_source {
    SL_NORMALS_FACES = 0,       /* area-weighted face normals */
    SL_NORMALS_FILE = 1,        /* the file's own */
    SL_NORMALS_PCA_VIEWPOINT = 2,
    SL_NORMALS_PCA_PROPAGATED = 3,
    SL_NORMALS_RANGE_GRID = 4   /* faces from the scanner grid */
};
const char *sl_normal_source_name(uint32_t source);

int sl_pointset_write(const char *path, const sl_pointset *ps, sl_error *err);
/* Validates magic, versions, sizes (against the file size) and checksum. */
int sl_pointset_read(const char *path, sl_pointset *out, sl_error *err);
void sl_pointset_release(sl_pointset *ps);

#endif
