/* qem_tool IN.ply OUT.ply TARGET [endpoint] [relaxed|relaxed-last] [bricks=N]: runs the quadric
 * simplifier (geometry/qem_simplify.h) on a PLY and writes the result, for the comparisons
 * of docs/simplify.md. TARGET is a triangle count, or a fraction of the input's (< 1);
 * endpoint: no optimal placement; relaxed, relaxed-last: allow_topology_change
 * SL_QEM_TOPOLOGY_RELAX, SL_QEM_TOPOLOGY_RELAX_LAST; bricks=N: by bricks of N triangles
 * (sl_qem_simplify_bricked; N < 1: that fraction of the input's).
 * Prints one line: triangles, seconds, peak memory growth, stop reason, counters. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "core/clock.h"
#include "formats/ply.h"
#include "geometry/qem_simplify.h"

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static long peak_kb(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: qem_tool IN.ply OUT.ply TARGET [endpoint] "
                        "[relaxed|relaxed-last] [bricks=N]\n");
        return 64;
    }
    sl_error err;
    sl_error_init(&err);
    sl_mesh mesh;
    if (sl_ply_read(argv[1], NULL, &mesh, NULL, NULL, &err) != 0) {
        fprintf(stderr, "qem_tool: %s: %s\n", argv[1], err.message);
        return 65;
    }
    double t = atof(argv[3]);
    sl_qem_config cfg = sl_qem_default_config();
    cfg.target_triangles = t < 1 ? (uint64_t)(t * mesh.triangle_count + 0.5) : (uint64_t)t;
    uint64_t brick = 0;
    for (int i = 4; i < argc; i++) {
        if (!strncmp(argv[i], "bricks=", 7)) {
            double b = atof(argv[i] + 7);
            brick = b < 1 ? (uint64_t)(b * mesh.triangle_count) : (uint64_t)b;
        }
        cfg.optimal_placement &= strcmp(argv[i], "endpoint") != 0;
        if (!strcmp(argv[i], "relaxed"))
            cfg.allow_topology_change = SL_QEM_TOPOLOGY_RELAX;
        if (!strcmp(argv[i], "relaxed-last"))
            cfg.allow_topology_change = SL_QEM_TOPOLOGY_RELAX_LAST;
    }
    sl_qem_mesh in = {mesh.vertex_count, mesh.positions, mesh.colors, NULL,
                      mesh.triangle_count, mesh.triangles, NULL};
    sl_qem_mesh out;
    sl_qem_stats st;
    long before = peak_kb();
    double t0 = sl_now_seconds(), c0 = cpu_seconds();
    int rc = sl_qem_simplify_bricked(&in, &cfg, brick, &out, &st, NULL, &err);
    double seconds = sl_now_seconds() - t0, cpu = cpu_seconds() - c0;
    if (rc) {
        fprintf(stderr, "qem_tool: %s\n", err.message);
        return 65;
    }
    long growth = peak_kb() - before;
    printf("%llu -> %llu triangles (target %llu) %.3f s (cpu %.3f s) %.1f B/tri stop %d "
           "collapses %llu queued %llu rejected topo %llu flip %llu shape %llu locked %llu "
           "border %llu nonmanifold %llu relaxed %llu cancelled %llu\n",
           (unsigned long long)mesh.triangle_count, (unsigned long long)out.triangle_count,
           (unsigned long long)cfg.target_triangles, seconds, cpu,
           growth * 1024.0 / (double)mesh.triangle_count, st.stop,
           (unsigned long long)st.collapses, (unsigned long long)st.queued,
           (unsigned long long)st.rejected_topology,
           (unsigned long long)st.rejected_flip, (unsigned long long)st.rejected_shape,
           (unsigned long long)st.locked_points, (unsigned long long)st.border_points,
           (unsigned long long)st.nonmanifold_points, (unsigned long long)st.relaxed_collapses,
           (unsigned long long)st.cancelled_triangles);
    sl_mesh view = sl_mesh_view(out.vertex_count, out.positions, NULL, out.colors,
                                out.triangle_count, out.triangles);
    rc = sl_ply_write(argv[2], &view, &err);
    sl_qem_mesh_release(&out);
    sl_mesh_release(&mesh);
    if (rc) {
        fprintf(stderr, "qem_tool: %s: %s\n", argv[2], err.message);
        return 74;
    }
    return 0;
}
