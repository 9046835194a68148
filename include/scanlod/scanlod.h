/* scanlod runtime API: open a built LOD model (.slod) and cut any level of detail from it.
 *
 * For viewers and services that only display models: link libscanlod_runtime (no engine,
 * no OpenVDB/OpenImageIO). Generating a mesh of m triangles costs O(m) (paper 1, section
 * 3): all ordering and crack compensation was done when the model was built.
 *
 *   scanlod_model *model;
 *   char error[256];
 *   if (scanlod_model_open("bunny.slod", &model, error, sizeof error) != 0) { ... }
 *   uint32_t k = scanlod_expansions_for_triangles(model, 50000);
 *   scanlod_mesh_bound bound = scanlod_extract_bound(model, k);
 *   float *positions = malloc(bound.vertices * 3 * sizeof(float)); ... (caller allocates)
 *   scanlod_mesh_bound written;
 *   scanlod_extract(model, k, positions, normals, colors, indices, &written);
 *   scanlod_model_free(model);
 *
 * A level is named by its expansion count k (0 = coarsest, scanlod_model_expansions() =
 * finest); the helpers turn a triangle budget, a LOD percent or an error into k.
 * A model of format 5 (docs/formats.md) is read by prefixes: opening reads its level
 * tables only, and an extraction reads the part of the file its level needs (the file
 * stays open until scanlod_model_free). Older formats are read whole at opening.
 * Thread safety: a model may be read by many threads, but scanlod_extract uses a scratch
 * table inside the model (and may read more of the file): one extraction at a time per
 * model.
 */
#ifndef SCANLOD_SCANLOD_H
#define SCANLOD_SCANLOD_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct scanlod_model scanlod_model;

typedef struct scanlod_mesh_bound {
    uint64_t vertices;
    uint64_t triangles;
} scanlod_mesh_bound;

/* Opens and validates a model. On failure returns non-zero, *out is NULL and `error`
 * (may be NULL) gets one line naming the file and the cause. */
int scanlod_model_open(const char *path, scanlod_model **out, char *error, size_t error_size);
void scanlod_model_free(scanlod_model *model);

uint32_t scanlod_model_expansions(const scanlod_model *model);
/* Triangles of the mesh after k expansions (exact: the accumulation table). */
uint64_t scanlod_model_triangles(const scanlod_model *model, uint32_t k);
/* World-space bounding box of the finest surface: min[3], max[3]. */
void scanlod_model_bounds(const scanlod_model *model, float min[3], float max[3]);

uint32_t scanlod_expansions_for_triangles(const scanlod_model *model, uint64_t budget);
/* LOD percent as in the paper's Table 1: P % of the expansions of nodes with surface
 * below them (empty cells of the sample band are not counted); 100 gives the finest
 * mesh, at the first k that reaches it (<= scanlod_model_expansions()). */
uint32_t scanlod_expansions_for_percent(const scanlod_model *model, double percent);
uint32_t scanlod_expansions_for_error(const scanlod_model *model, double max_error);

/* Sizes the caller's buffers for scanlod_extract at k. */
scanlod_mesh_bound scanlod_extract_bound(const scanlod_model *model, uint32_t k);

/* Writes the mesh after k expansions into caller buffers sized by scanlod_extract_bound:
 * positions (3 floats per vertex), normals (3 floats per vertex, may be NULL), colors
 * (RGBA bytes per vertex, may be NULL; white when the model has no colour), indices (3 per
 * triangle, counter-clockwise seen from outside). *written (OUT) gets the counts.
 * Nothing is allocated for the mesh: it is generated into these arrays directly.
 * Returns 0, or non-zero when out of memory, when the mesh would not fit the bound (a
 * model whose accumulation table is wrong), or when the part of a format 5 file the level
 * needs cannot be read or fails its check; the arrays' contents are then unspecified and
 * *written is zero. */
int scanlod_extract(scanlod_model *model, uint32_t k, float *positions, float *normals,
                    uint8_t *colors, uint32_t *indices, scanlod_mesh_bound *written);

#ifdef __cplusplus
}
#endif
#endif
