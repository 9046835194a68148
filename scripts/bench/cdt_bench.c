/* Constrained Delaunay triangulation throughput (docs/mesh-toolkit.md quotes it):
 * cdt_bench [N [KIND]] triangulates four polygons (or only KIND) of about N points
 * (default 100000) and prints the best of 3 wall times for each:
 *   boundary: a star-shaped polygon whose N vertices are all on its one loop;
 *   interior: a star-shaped loop of N/10 vertices, N/5 random holes' worth of small
 *             holes and the rest random interior points;
 *   grid:     a sqrt(N) x sqrt(N) integer grid inside a square loop that only has its
 *             corners (every boundary grid point splits a loop edge; every grid square is
 *             cocircular: the exact predicates decide almost every test);
 *   circle:   N points on a circle (rounded: nearly cocircular), the polygon through them.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "geometry/cdt.h"

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static double uniform(void)
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

typedef struct input {
    uint32_t n, loops, nidx;
    double *xy;
    uint32_t start[8], *idx;
} input;

static void star(input *in, uint32_t m, double cx, double cy, double size, int clockwise)
{
    uint32_t first = in->n;
    for (uint32_t k = 0; k < m; k++) {
        double a = (k + 0.8 * uniform()) * 2 * M_PI / m, r = size * (0.7 + 0.3 * uniform());
        in->xy[2 * in->n] = cx + r * cos(a), in->xy[2 * in->n + 1] = cy + r * sin(a);
        in->n++;
    }
    for (uint32_t k = 0; k < m; k++)
        in->idx[in->nidx++] = first + (clockwise ? m - 1 - k : k);
    in->start[++in->loops] = in->nidx;
}

static void make(input *in, int kind, uint32_t n)
{
    in->xy = malloc(2 * (size_t)(n + 8) * sizeof *in->xy);
    in->idx = malloc((size_t)(n + 8) * sizeof *in->idx);
    in->n = in->loops = in->nidx = 0;
    in->start[0] = 0;
    if (kind == 0) {
        star(in, n, 0, 0, 1, 0);
    } else if (kind == 1) {
        star(in, n / 10, 0, 0, 1, 0);
        for (int h = 0; h < 4; h++)
            star(in, n / 50, 0.3 * cos(h * M_PI / 2), 0.3 * sin(h * M_PI / 2), 0.1, 1);
        while (in->n < n) {
            double x = 1.4 * uniform() - 0.7, y = 1.4 * uniform() - 0.7;
            int in_hole = 0;
            for (int h = 0; h < 4; h++)
                in_hole |= hypot(x - 0.3 * cos(h * M_PI / 2), y - 0.3 * sin(h * M_PI / 2)) < 0.12;
            if (!in_hole)
                in->xy[2 * in->n] = x, in->xy[2 * in->n + 1] = y, in->n++;
        }
    } else if (kind == 2) {
        uint32_t side = (uint32_t)sqrt((double)n);
        for (uint32_t i = 0; i < side; i++)
            for (uint32_t j = 0; j < side; j++)
                in->xy[2 * in->n] = i, in->xy[2 * in->n + 1] = j, in->n++;
        uint32_t c[4] = {0, (side - 1) * side, side * side - 1, side - 1};
        for (int k = 0; k < 4; k++)
            in->idx[in->nidx++] = c[k];
        in->start[++in->loops] = in->nidx;
    } else {
        for (uint32_t k = 0; k < n; k++) {
            in->xy[2 * in->n] = cos(2 * M_PI * k / n), in->xy[2 * in->n + 1] = sin(2 * M_PI * k / n);
            in->idx[in->nidx++] = in->n++;
        }
        in->start[++in->loops] = in->nidx;
    }
}

int main(int argc, char **argv)
{
    uint32_t n = argc > 1 ? (uint32_t)strtoul(argv[1], NULL, 10) : 100000;
    const char *names[4] = {"boundary", "interior", "grid", "circle"};
    for (int kind = 0; kind < 4; kind++) {
        if (argc > 2 && strcmp(argv[2], names[kind]) != 0)
            continue;
        input in;
        make(&in, kind, n);
        sl_cdt_input ci = {in.n, in.xy, in.loops, in.start, in.idx};
        double best = 1e30;
        uint64_t triangles = 0;
        for (int rep = 0; rep < 3; rep++) {
            sl_cdt_result *r = NULL;
            sl_error err;
            sl_error_init(&err);
            double t0 = seconds();
            int rc = sl_cdt_triangulate(&ci, 0, &r, NULL, &err);
            double dt = seconds() - t0;
            if (rc) {
                fprintf(stderr, "%s: %s\n", names[kind], err.message);
                return 1;
            }
            triangles = r->triangle_count;
            best = dt < best ? dt : best;
            sl_cdt_free(r);
        }
        printf("%-9s %7u points %7u loop points -> %7llu triangles: %7.1f ms\n", names[kind],
               in.n, in.nidx, (unsigned long long)triangles, best * 1e3);
        free(in.xy);
        free(in.idx);
    }
    return 0;
}
