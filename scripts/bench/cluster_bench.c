/* The clustering method in-process (docs/clustering.md quotes it; bench_cluster.sh drives
 * it): cluster_bench IN.ply (--max-error E | --triangles N) [--passes P]
 * [--intermediates M] [--repeat R] [-o PREFIX]
 * reads and cleans IN as the range stage does, then runs sl_cluster_simplify R times
 * (default 5) and prints one JSON object: the level's and intermediates' triangles and
 * bounds, and the wall time of each run (median, min, max), process start-up and reading
 * excluded. With -o the level is written to PREFIX.ply and the intermediates to
 * PREFIX_J.ply (positions only), for `scanlod compare`.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "formats/ply.h"
#include "stages/cluster/cluster.h"
#include "stages/range/range.h"

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static int write_ply(const char *path, uint64_t nv, const float *pos, const uint32_t *source,
                     const float *all, uint64_t nt, const uint32_t *tri)
{
    sl_mesh m;
    sl_mesh_init(&m);
    m.vertex_count = nv;
    m.triangle_count = nt;
    m.positions = malloc((nv ? nv : 1) * 12);
    m.triangles = malloc((nt ? nt : 1) * 12);
    for (uint64_t v = 0; v < nv; v++)
        memcpy(m.positions + 3 * v, pos ? pos + 3 * v : all + 3 * (uint64_t)source[v], 12);
    memcpy(m.triangles, tri, nt * 12);
    sl_error err;
    sl_error_init(&err);
    int rc = sl_ply_write(path, &m, &err);
    if (rc)
        fprintf(stderr, "cluster_bench: %s: %s\n", path, err.message);
    sl_mesh_release(&m);
    return rc;
}

/* The level as its own mesh (the vertices it uses). */
static int write_level(const char *path, const sl_pointset *ps, const sl_cluster_level *l)
{
    uint32_t *map = malloc(ps->count * sizeof *map), *src = malloc(ps->count * sizeof *src);
    uint32_t *tri = malloc((l->triangle_count ? l->triangle_count : 1) * 12);
    memset(map, 0xff, ps->count * sizeof *map);
    for (uint64_t i = 0; i < 3 * l->triangle_count; i++)
        map[l->triangles[i]] = 0;
    uint64_t used = 0;
    for (uint64_t v = 0; v < ps->count; v++)
        if (map[v] != UINT32_MAX) {
            src[used] = (uint32_t)v;
            map[v] = (uint32_t)used++;
        }
    for (uint64_t i = 0; i < 3 * l->triangle_count; i++)
        tri[i] = map[l->triangles[i]];
    int rc = write_ply(path, used, NULL, src, ps->positions, l->triangle_count, tri);
    free(map);
    free(src);
    free(tri);
    return rc;
}

int main(int argc, char **argv)
{
    const char *in_path = NULL, *prefix = NULL;
    sl_cluster_config cfg = sl_cluster_default_config();
    sl_cluster_target target = {0, 0, 0};
    int repeat = 5;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int more = i + 1 < argc;
        if (!strcmp(a, "--max-error") && more)
            target.max_error = atof(argv[++i]);
        else if (!strcmp(a, "--triangles") && more)
            target.triangles = strtoull(argv[++i], NULL, 10);
        else if (!strcmp(a, "--passes") && more)
            cfg.passes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--intermediates") && more)
            target.intermediates = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--slab-share") && more)
            cfg.slab_share = atof(argv[++i]);
        else if (!strcmp(a, "--max-angle") && more)
            cfg.max_angle = atof(argv[++i]);
        else if (!strcmp(a, "--repeat") && more)
            repeat = atoi(argv[++i]);
        else if (!strcmp(a, "-o") && more)
            prefix = argv[++i];
        else if (a[0] != '-' && !in_path)
            in_path = a;
        else {
            fprintf(stderr, "usage: cluster_bench IN.ply (--max-error E | --triangles N) "
                            "[--passes P] [--intermediates M] [--repeat R] [-o PREFIX]\n");
            return 64;
        }
    }
    if (!in_path || repeat < 1 || repeat > 1000) {
        fprintf(stderr, "cluster_bench: needs IN.ply and --repeat in [1, 1000]\n");
        return 64;
    }
    sl_error err;
    sl_error_init(&err);
    sl_mesh mesh;
    sl_mesh_init(&mesh);
    sl_pointset ps;
    sl_range_counts counts;
    sl_range_config rcfg = sl_range_default_config();
    if (sl_ply_read(in_path, NULL, &mesh, NULL, NULL, &err) ||
        sl_range_points_from_mesh(&rcfg, &mesh, NULL, &ps, &counts, NULL, &err)) {
        fprintf(stderr, "cluster_bench: %s: %s\n", in_path, err.message);
        return 65;
    }
    sl_mesh_release(&mesh);
    sl_cluster_input in = {ps.count, ps.positions, ps.triangle_count, ps.triangles, 0, 0, 0};
    double *t = malloc((size_t)repeat * sizeof *t), *cpu = malloc((size_t)repeat * sizeof *cpu);
    sl_cluster_level l;
    memset(&l, 0, sizeof l);
    for (int r = 0; r < repeat; r++) {
        sl_cluster_level_release(&l);
        double t0 = seconds(), c0 = cpu_seconds();
        if (sl_cluster_simplify(&cfg, &in, &target, &l, NULL, &err)) {
            fprintf(stderr, "cluster_bench: %s: %s\n", in_path, err.message);
            return 70;
        }
        t[r] = seconds() - t0;
        cpu[r] = cpu_seconds() - c0;
    }
    qsort(t, (size_t)repeat, sizeof *t, cmp_double);
    qsort(cpu, (size_t)repeat, sizeof *cpu, cmp_double);
    /* The bound a one-pass level was made with (a budget's search finds one): its pass's
     * tolerance plus the rounding margin cluster_simplify.c takes off it, so that
     * --max-error with it makes the same level. */
    double big = 0.0;
    for (uint64_t i = 0; i < 3 * ps.triangle_count; i++)
        for (int k = 0; k < 3; k++)
            big = fmax(big, fabs(ps.positions[3 * (uint64_t)ps.triangles[i] + k]));
    double used = l.pass_count == 1 ? (l.pass[0].tolerance + ldexp(big, -20)) / l.diagonal : 0.0;
    printf("{\"input\":\"%s\",\"input_triangles\":%llu,\"triangles\":%llu,\"bound\":%.9g,"
           "\"max_error_used\":%.17g,"
           "\"reached\":%s,\"search_steps\":%u,\"passes\":%u,\"clusters\":%u,"
           "\"seconds_median\":%.6f,\"seconds_min\":%.6f,\"seconds_max\":%.6f,"
           "\"cpu_seconds_median\":%.6f,\"repeat\":%d,"
           "\"intermediates\":[",
           in_path, (unsigned long long)ps.triangle_count, (unsigned long long)l.triangle_count,
           l.bound_fraction, used, l.reached ? "true" : "false", l.search_steps, l.pass_count,
           l.pass_count ? l.pass[0].clusters : 0, t[repeat / 2], t[0], t[repeat - 1], cpu[repeat / 2], repeat);
    for (uint32_t j = 0; j < l.intermediate_count; j++)
        printf("%s{\"triangles\":%llu,\"bound\":%.9g}", j ? "," : "",
               (unsigned long long)l.intermediates[j].triangle_count,
               l.intermediates[j].bound / l.diagonal);
    printf("]}\n");
    int rc = 0;
    if (prefix) {
        char path[4096];
        snprintf(path, sizeof path, "%s.ply", prefix);
        rc |= write_level(path, &ps, &l);
        for (uint32_t j = 0; j < l.intermediate_count; j++) {
            const sl_cluster_intermediate *m = &l.intermediates[j];
            snprintf(path, sizeof path, "%s_%u.ply", prefix, j + 1);
            rc |= write_ply(path, m->vertex_count, m->positions, NULL, NULL, m->triangle_count,
                            m->triangles);
        }
    }
    sl_cluster_level_release(&l);
    sl_pointset_release(&ps);
    free(t);
    free(cpu);
    return rc ? 74 : 0;
}
