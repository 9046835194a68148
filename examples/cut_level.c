/* A viewer's use of the scanlod runtime, whole: open a built model, pick a level by
 * triangle budget, size the buffers, cut the mesh into them, use it. Build against an
 * installed scanlod (docs/api.md):
 *
 *   cc cut_level.c $(pkg-config --cflags --libs scanlod) -o cut_level
 *   ./cut_level model.slod 20000
 *
 * Prints the level's expansion count, triangle and vertex counts and the mesh's bounding
 * box; exit 1 with one line on stderr when the model cannot be opened or cut. */
#include <float.h>
#include <stdio.h>
#include <stdlib.h>

#include <scanlod/scanlod.h>

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: cut_level MODEL.slod TRIANGLES\n");
        return 2;
    }
    scanlod_model *model;
    char error[512];
    if (scanlod_model_open(argv[1], &model, error, sizeof error) != 0) {
        fprintf(stderr, "cut_level: %s\n", error);
        return 1;
    }
    uint32_t k = scanlod_expansions_for_triangles(model, strtoull(argv[2], NULL, 10));
    scanlod_mesh_bound bound = scanlod_extract_bound(model, k);
    /* Sized for this k; a viewer that reuses them sizes them for the finest k it cuts. */
    float *positions = malloc((bound.vertices + 1) * 3 * sizeof *positions);
    float *normals = malloc((bound.vertices + 1) * 3 * sizeof *normals);
    uint8_t *colors = malloc((bound.vertices + 1) * 4);
    uint32_t *indices = malloc((bound.triangles + 1) * 3 * sizeof *indices);
    scanlod_mesh_bound mesh;
    int rc = !positions || !normals || !colors || !indices ||
             scanlod_extract(model, k, positions, normals, colors, indices, &mesh) != 0;
    if (rc)
        fprintf(stderr, "cut_level: %s: out of memory or a damaged model\n", argv[1]);
    else {
        float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
        for (uint64_t v = 0; v < mesh.vertices; v++)
            for (int a = 0; a < 3; a++) {
                float x = positions[3 * v + a];
                lo[a] = x < lo[a] ? x : lo[a];
                hi[a] = x > hi[a] ? x : hi[a];
            }
        printf("k=%u of %u: %llu triangles, %llu vertices, box (%g %g %g)-(%g %g %g)\n", k,
               scanlod_model_expansions(model), (unsigned long long)mesh.triangles,
               (unsigned long long)mesh.vertices, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    }
    free(positions);
    free(normals);
    free(colors);
    free(indices);
    scanlod_model_free(model);
    return rc;
}
