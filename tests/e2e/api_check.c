/* Uses only the public runtime API (include/scanlod/scanlod.h) on a model built by
 * `scanlod run`: every level it is asked for has exactly the triangle count the model
 * promises, indices are in range, and the requests by budget/percent/error agree with
 * their definitions. Prints "N passed, N failed". Usage: api_check MODEL.slod */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "scanlod/scanlod.h"

static int passed, failed;
#define EXPECT(cond)                                                                    \
    do {                                                                                \
        if (cond)                                                                       \
            passed++;                                                                   \
        else {                                                                          \
            failed++;                                                                   \
            fprintf(stderr, "api_check: failed: %s (line %d)\n", #cond, __LINE__);      \
        }                                                                               \
    } while (0)

static void check_level(scanlod_model *m, uint32_t k)
{
    scanlod_mesh_bound bound = scanlod_extract_bound(m, k);
    float *positions = malloc((bound.vertices + 1) * 3 * sizeof(float));
    float *normals = malloc((bound.vertices + 1) * 3 * sizeof(float));
    uint8_t *colors = malloc((bound.vertices + 1) * 4);
    uint32_t *indices = malloc((bound.triangles + 1) * 3 * sizeof(uint32_t));
    scanlod_mesh_bound written;
    EXPECT(scanlod_extract(m, k, positions, normals, colors, indices, &written) == 0);
    EXPECT(written.triangles == scanlod_model_triangles(m, k));
    EXPECT(written.vertices <= bound.vertices);
    int in_range = 1, finite = 1;
    for (uint64_t i = 0; i < 3 * written.triangles; i++)
        in_range &= indices[i] < written.vertices;
    for (uint64_t i = 0; i < 3 * written.vertices; i++)
        finite &= isfinite(positions[i]) && isfinite(normals[i]);
    EXPECT(in_range);
    EXPECT(finite);
    free(positions);
    free(normals);
    free(colors);
    free(indices);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: api_check MODEL.slod\n");
        return 2;
    }
    char error[512];
    scanlod_model *m;
    EXPECT(scanlod_model_open("/nonexistent/model.slod", &m, error, sizeof error) != 0);
    EXPECT(m == NULL);
    if (scanlod_model_open(argv[1], &m, error, sizeof error) != 0) {
        fprintf(stderr, "api_check: %s\n", error);
        return 1;
    }
    uint32_t e = scanlod_model_expansions(m);
    EXPECT(e > 0);
    uint64_t finest = scanlod_model_triangles(m, e);
    EXPECT(finest > 0);
    for (int p = 0; p <= 100; p += 10)
        check_level(m, scanlod_expansions_for_percent(m, p));
    uint64_t budget = finest / 2;
    uint32_t k = scanlod_expansions_for_triangles(m, budget);
    EXPECT(scanlod_model_triangles(m, k) <= budget);
    EXPECT(k == e || scanlod_model_triangles(m, k + 1) > budget || k + 1 <= e);
    uint32_t k100 = scanlod_expansions_for_percent(m, 100); /* the finest mesh, maybe early */
    EXPECT(k100 <= e && scanlod_model_triangles(m, k100) == finest);
    EXPECT(scanlod_expansions_for_percent(m, 50) <= k100);
    EXPECT(scanlod_expansions_for_error(m, 0) == e || scanlod_model_triangles(m, e) == finest);
    float lo[3], hi[3];
    scanlod_model_bounds(m, lo, hi);
    EXPECT(lo[0] < hi[0] && lo[1] < hi[1] && lo[2] < hi[2]);
    scanlod_model_free(m);
    printf("%d passed, %d failed\n", passed, failed);
    return failed != 0;
}
