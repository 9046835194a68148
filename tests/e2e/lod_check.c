/* The LOD model of a real scan, from the outside of the pipeline: at every expansion count
 * K (or at SAMPLES counts spread over the array, the first and last included), no two
 * neighbouring frontier cells differ by 2 or more levels, the accumulation table equals the
 * triangles actually generated, no edge is in more than two triangles, and -- for a closed
 * input -- every edge is in exactly two. Prints one summary line and "N passed, N failed".
 *
 * Usage: lod_check MODEL.slod [SAMPLES] [--closed]   (SAMPLES 0 = every K) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/lod_io.h"
#include "tests/unit/mesh_checks.h"

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: lod_check MODEL.slod [SAMPLES] [--closed]\n");
        return 2;
    }
    uint32_t samples = argc > 2 ? (uint32_t)strtoul(argv[2], NULL, 10) : 0;
    int closed = argc > 3 && strcmp(argv[3], "--closed") == 0;
    sl_lod_model m;
    sl_error err;
    sl_error_init(&err);
    if (sl_lod_model_read(argv[1], &m, &err) != 0) {
        fprintf(stderr, "lod_check: %s: %s\n", argv[1], err.message);
        return 1;
    }
    uint32_t e = m.expansion_count, count = samples && samples < e + 1 ? samples : e + 1;
    uint64_t mismatched = 0, gaps = 0, cracked = 0, crowded = 0, checked = 0;
    for (uint32_t i = 0; i < count; i++) {
        /* evenly spread, first and last included */
        uint32_t k = count == e + 1 ? i : (uint32_t)((uint64_t)i * e / (count - 1));
        sl_lod_mesh mesh;
        if (sl_lod_generate(&m, k, &mesh, NULL) != 0) {
            fprintf(stderr, "lod_check: out of memory at K=%u\n", k);
            return 1;
        }
        if (mesh.triangle_count != m.accumulation[k] && mismatched++ < 3)
            fprintf(stderr, "K=%u: accumulation %llu, generated %llu\n", k,
                    (unsigned long long)m.accumulation[k], (unsigned long long)mesh.triangle_count);
        if (level_gap(&m, k) && gaps++ < 3)
            fprintf(stderr, "K=%u: neighbouring frontier cells 2+ levels apart\n", k);
        uint64_t over = 0, bad = mesh.triangle_count ? edge_census(&mesh, &over) : 0;
        bad = closed ? bad : 0;
        if (bad && cracked++ < 3)
            fprintf(stderr, "K=%u: %llu edges not in exactly two triangles\n", k,
                    (unsigned long long)bad);
        if (over && crowded++ < 3)
            fprintf(stderr, "K=%u: %llu edges in three or more triangles\n", k,
                    (unsigned long long)over);
        checked++;
        sl_lod_mesh_release(&mesh);
    }
    printf("%s: %llu of %u expansion counts checked: %llu accumulation mismatches, %llu with "
           "level gaps, %llu with edges of 3+ triangles, %llu with open edges%s\n", argv[1],
           (unsigned long long)checked, e + 1, (unsigned long long)mismatched,
           (unsigned long long)gaps, (unsigned long long)crowded, (unsigned long long)cracked,
           closed ? "" : " (not checked: open input)");
    int failed = (mismatched > 0) + (gaps > 0) + (crowded > 0) + (cracked > 0);
    printf("%d passed, %d failed\n", 4 - failed, failed);
    sl_lod_model_release(&m);
    return failed != 0;
}
