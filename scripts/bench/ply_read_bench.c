/* ply_read_bench: PLY reader throughput against plain page-cache reading (issue 2).
 *
 *   ply_read_bench read FILE [RUNS]    RUNS (>= 5) alternating timings of
 *                                      (a) a read() loop in 128 KiB blocks, what cat does,
 *                                      (b) sl_ply_read of the whole file;
 *                                      prints one line: median/min/max of each, MB/s and
 *                                      vertices/s at the median.
 *   ply_read_bench to-ascii IN OUT     re-encodes IN as ascii PLY (%.9g: exact floats)
 *
 * The file is read once before timing, so every run measures the page cache, not the disk.
 */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "formats/ply.h"

#define MAX_RUNS 101

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double read_loop(const char *path)
{
    static char buf[128 << 10];
    double t0 = now();
    int fd = open(path, O_RDONLY);
    if (fd < 0) {
        perror(path);
        exit(1);
    }
    while (read(fd, buf, sizeof buf) > 0)
        ;
    close(fd);
    return now() - t0;
}

static double ply_read(const char *path, uint64_t *vertices, uint64_t *triangles)
{
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    double t0 = now();
    if (sl_ply_read(path, NULL, &m, NULL, NULL, &err) != 0) {
        char line[1600];
        fprintf(stderr, "ply_read_bench: %s\n", sl_error_format(&err, line, sizeof line));
        exit(1);
    }
    double t = now() - t0;
    *vertices = m.vertex_count;
    *triangles = m.triangle_count;
    sl_mesh_release(&m);
    return t;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static int bench(const char *path, int runs)
{
    double loop[MAX_RUNS], ply[MAX_RUNS];
    uint64_t vertices = 0, triangles = 0;
    struct stat st;
    if (stat(path, &st) != 0) {
        perror(path);
        return 1;
    }
    read_loop(path); /* warm the page cache */
    ply_read(path, &vertices, &triangles);
    for (int i = 0; i < runs; i++) {
        loop[i] = read_loop(path);
        ply[i] = ply_read(path, &vertices, &triangles);
    }
    double mb = (double)st.st_size / 1e6, lm = median(loop, runs), pm = median(ply, runs);
    printf("%s bytes=%lld vertices=%llu triangles=%llu runs=%d "
           "read_median_s=%.6f read_min_s=%.6f read_max_s=%.6f read_MBps=%.0f "
           "ply_median_s=%.6f ply_min_s=%.6f ply_max_s=%.6f ply_MBps=%.0f "
           "ply_Mvertices_per_s=%.2f ply_vs_read=%.2f\n",
           path, (long long)st.st_size, (unsigned long long)vertices,
           (unsigned long long)triangles, runs, lm, loop[0], loop[runs - 1], mb / lm, pm, ply[0],
           ply[runs - 1], mb / pm, (double)vertices / pm / 1e6, lm / pm);
    return 0;
}

static int to_ascii(const char *in, const char *out)
{
    sl_mesh m;
    sl_error err;
    sl_error_init(&err);
    if (sl_ply_read(in, NULL, &m, NULL, NULL, &err) != 0) {
        char line[1600];
        fprintf(stderr, "ply_read_bench: %s\n", sl_error_format(&err, line, sizeof line));
        return 1;
    }
    FILE *f = fopen(out, "w");
    if (!f) {
        perror(out);
        return 1;
    }
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex %llu\nproperty float x\nproperty float y\n"
               "property float z\nelement face %llu\nproperty list uchar int vertex_indices\n"
               "end_header\n", (unsigned long long)m.vertex_count,
            (unsigned long long)m.triangle_count);
    for (uint64_t i = 0; i < m.vertex_count; i++)
        fprintf(f, "%.9g %.9g %.9g\n", m.positions[3 * i], m.positions[3 * i + 1],
                m.positions[3 * i + 2]);
    for (uint64_t i = 0; i < m.triangle_count; i++)
        fprintf(f, "3 %u %u %u\n", m.triangles[3 * i], m.triangles[3 * i + 1],
                m.triangles[3 * i + 2]);
    sl_mesh_release(&m);
    return fclose(f) == 0 ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (argc >= 3 && strcmp(argv[1], "read") == 0) {
        int runs = argc > 3 ? atoi(argv[3]) : 7;
        runs = runs < 5 ? 5 : runs > MAX_RUNS ? MAX_RUNS : runs;
        return bench(argv[2], runs);
    }
    if (argc == 4 && strcmp(argv[1], "to-ascii") == 0)
        return to_ascii(argv[2], argv[3]);
    fprintf(stderr, "usage: ply_read_bench read FILE [RUNS] | to-ascii IN OUT\n");
    return 64;
}
