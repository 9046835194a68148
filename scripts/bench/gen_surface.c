/* gen_surface: a synthetic large input for the cost-growth benchmark (issue 3), and the
 * hostile shapes of the plan's memory model (issue 34 item 5).
 *
 *   gen_surface --triangles N -o out.ply [--noise A] [--seed S] [--aspect R | --soup]
 *
 * A torus (major radius 1, tube radius 0.35) whose tube radius is displaced by
 * deterministic multi-frequency noise: a sum of NOISE_TERMS waves sin(m u + n v + phase)
 * with integer frequencies (so the surface closes up exactly in both directions),
 * amplitudes falling as 1/frequency, phases from a fixed-seed generator. The grid is
 * nu x nv quads with nu / nv = 1 / 0.35, the ratio of the two circumferences, so the
 * triangles are close to right isosceles; each quad is two triangles, so the count is
 * 2 nu nv, the closest such to N. The mesh is closed, manifold and watertight.
 *
 * Written as binary little-endian PLY row by row through stdio's buffer: memory is
 * O(nv), not O(N). Each wave is separable (sin(a + b) = sin a cos b + cos a sin b), so a
 * vertex costs NOISE_TERMS multiply-adds once a row's and the columns' tables are made.
 * --aspect R: the same torus cut into R times fewer rows and more columns, so that each
 * triangle is R times longer around the ring than across the tube: slivers. The points'
 * spacing, and so the octree's leaf, follows the short side, and the surface needs about
 * R times the samples of the plain torus of as many triangles.
 *
 * --soup: N triangles that share no vertex, each an equilateral of edge 0.3 d (d the
 * spacing of N points in the cube [-1, 1]^3) at a random place and orientation: nothing
 * connects them, so each is a small island of the octree's band, and their points'
 * spacing is their edge.
 *
 * Prints one JSON line: {"triangles":..,"vertices":..,"seconds":..}.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define NOISE_TERMS 24
#define MAJOR_RADIUS 1.0
#define TUBE_RADIUS 0.35

typedef struct wave {
    int m, n;         /* integer frequencies along u and v */
    double amplitude; /* fraction of the tube radius */
    double phase;
} wave;

static uint64_t next_random(uint64_t *state)
{
    uint64_t x = (*state += 0x9e3779b97f4a7c15ull);
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

static void make_waves(wave *w, double noise, uint64_t seed)
{
    uint64_t state = seed;
    double norm = 0.0;
    for (int k = 0; k < NOISE_TERMS; k++) {
        /* Frequencies 2..~200 around the ring, 1..~70 around the tube, geometric. */
        double f = pow(1.25, k);
        w[k].m = 2 + (int)(f * (1 + next_random(&state) % 3));
        w[k].n = 1 + (int)(f * 0.35 * (1 + next_random(&state) % 3));
        if (next_random(&state) & 1)
            w[k].n = -w[k].n;
        w[k].amplitude = 1.0 / f;
        w[k].phase = (double)(next_random(&state) >> 11) * 0x1.0p-53 * 2.0 * M_PI;
        norm += w[k].amplitude;
    }
    for (int k = 0; k < NOISE_TERMS; k++)
        w[k].amplitude *= noise / norm; /* |displacement| <= noise * tube radius */
}

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}

static void put_f32(unsigned char *p, float f)
{
    uint32_t v;
    memcpy(&v, &f, sizeof v);
    put_u32(p, v);
}

static int usage(void)
{
    fputs("usage: gen_surface --triangles N -o out.ply [--noise A] [--seed S] [--aspect R | --soup]\n"
          "  A noisy closed torus with about N triangles (binary PLY); noise A is the\n"
          "  largest displacement as a fraction of the tube radius (default 0.15); its\n"
          "  triangles R times longer than wide (--aspect, default 1); or a soup of N\n"
          "  triangles that share no vertex (--soup).\n",
          stderr);
    return 64;
}

/* Vertices of row i (u = 2 pi i / nu) into buf, 12 bytes each. */
static void write_row(unsigned char *buf, uint64_t i, uint64_t nu, uint64_t nv,
                      const wave *w, const double *col_sin, const double *col_cos)
{
    double u = 2.0 * M_PI * (double)i / (double)nu;
    double row_sin[NOISE_TERMS], row_cos[NOISE_TERMS];
    for (int k = 0; k < NOISE_TERMS; k++) {
        row_sin[k] = w[k].amplitude * sin(w[k].m * u + w[k].phase);
        row_cos[k] = w[k].amplitude * cos(w[k].m * u + w[k].phase);
    }
    for (uint64_t j = 0; j < nv; j++) {
        double v = 2.0 * M_PI * (double)j / (double)nv, noise = 0.0;
        for (int k = 0; k < NOISE_TERMS; k++)
            noise += row_sin[k] * col_cos[j * NOISE_TERMS + k] +
                     row_cos[k] * col_sin[j * NOISE_TERMS + k];
        double rho = TUBE_RADIUS * (1.0 + noise), ring = MAJOR_RADIUS + rho * cos(v);
        put_f32(buf + 12 * j, (float)(ring * cos(u)));
        put_f32(buf + 12 * j + 4, (float)(ring * sin(u)));
        put_f32(buf + 12 * j + 8, (float)(rho * sin(v)));
    }
}

/* The two triangles of quad (i, j) in row i, 13 bytes each (count + 3 indices); the
 * winding makes the normals point out of the tube. */
static void write_quads(unsigned char *buf, uint64_t i, uint64_t nu, uint64_t nv)
{
    uint64_t i1 = (i + 1) % nu;
    for (uint64_t j = 0; j < nv; j++) {
        uint64_t j1 = (j + 1) % nv;
        uint32_t c00 = (uint32_t)(i * nv + j), c10 = (uint32_t)(i1 * nv + j);
        uint32_t c11 = (uint32_t)(i1 * nv + j1), c01 = (uint32_t)(i * nv + j1);
        uint32_t tri[6] = {c00, c10, c11, c00, c11, c01};
        unsigned char *p = buf + 26 * j;
        for (int t = 0; t < 2; t++) {
            p[13 * t] = 3;
            for (int c = 0; c < 3; c++)
                put_u32(p + 13 * t + 1 + 4 * c, tri[3 * t + c]);
        }
    }
}

static int generate(FILE *f, uint64_t nu, uint64_t nv, double noise, uint64_t seed)
{
    wave w[NOISE_TERMS];
    make_waves(w, noise, seed);
    double *col_sin = malloc(nv * NOISE_TERMS * sizeof *col_sin);
    double *col_cos = malloc(nv * NOISE_TERMS * sizeof *col_cos);
    unsigned char *buf = malloc(26 * nv);
    if (!col_sin || !col_cos || !buf) {
        free(col_sin);
        free(col_cos);
        free(buf);
        errno = ENOMEM;
        return -1;
    }
    for (uint64_t j = 0; j < nv; j++)
        for (int k = 0; k < NOISE_TERMS; k++) {
            double a = w[k].n * 2.0 * M_PI * (double)j / (double)nv;
            col_sin[j * NOISE_TERMS + k] = sin(a);
            col_cos[j * NOISE_TERMS + k] = cos(a);
        }
    fprintf(f,
            "ply\nformat binary_little_endian 1.0\n"
            "comment scanlod gen_surface: noisy torus, noise %g, seed %llu\n"
            "element vertex %llu\nproperty float x\nproperty float y\nproperty float z\n"
            "element face %llu\nproperty list uchar int vertex_indices\nend_header\n",
            noise, (unsigned long long)seed, (unsigned long long)(nu * nv),
            (unsigned long long)(2 * nu * nv));
    int ok = 1;
    for (uint64_t i = 0; i < nu && ok; i++) {
        write_row(buf, i, nu, nv, w, col_sin, col_cos);
        ok = fwrite(buf, 12, nv, f) == nv;
    }
    for (uint64_t i = 0; i < nu && ok; i++) {
        write_quads(buf, i, nu, nv);
        ok = fwrite(buf, 26, nv, f) == nv;
    }
    free(col_sin);
    free(col_cos);
    free(buf);
    return ok ? 0 : -1;
}

/* A unit vector from two uniform numbers (Marsaglia's method, without rejection). */
static void random_direction(uint64_t *state, double d[3])
{
    double z = 2.0 * ((double)(next_random(state) >> 11) * 0x1.0p-53) - 1.0;
    double a = 2.0 * M_PI * ((double)(next_random(state) >> 11) * 0x1.0p-53);
    double r = sqrt(1.0 - z * z);
    d[0] = r * cos(a);
    d[1] = r * sin(a);
    d[2] = z;
}

/* Vertices 3t..3t+2 of soup triangle t into buf (36 bytes). */
static void soup_triangle(uint64_t *state, double edge, unsigned char *buf)
{
    double c[3], u[3], n[3], v[3];
    for (int k = 0; k < 3; k++)
        c[k] = 2.0 * ((double)(next_random(state) >> 11) * 0x1.0p-53) - 1.0;
    random_direction(state, n);
    random_direction(state, u); /* made perpendicular to n below */
    double dot = u[0] * n[0] + u[1] * n[1] + u[2] * n[2], len = 0;
    for (int k = 0; k < 3; k++)
        len += (u[k] - dot * n[k]) * (u[k] - dot * n[k]);
    len = sqrt(len) > 1e-9 ? sqrt(len) : 1.0;
    for (int k = 0; k < 3; k++)
        u[k] = (u[k] - dot * n[k]) / len;
    v[0] = n[1] * u[2] - n[2] * u[1];
    v[1] = n[2] * u[0] - n[0] * u[2];
    v[2] = n[0] * u[1] - n[1] * u[0];
    double r = edge / sqrt(3.0); /* circumradius */
    for (int i = 0; i < 3; i++) {
        double a = 2.0 * M_PI * i / 3.0;
        for (int k = 0; k < 3; k++)
            put_f32(buf + 12 * i + 4 * k, (float)(c[k] + r * (cos(a) * u[k] + sin(a) * v[k])));
    }
}

static int generate_soup(FILE *f, uint64_t triangles, uint64_t seed)
{
    uint64_t state = seed;
    double edge = 0.3 * cbrt(8.0 / (double)triangles);
    fprintf(f,
            "ply\nformat binary_little_endian 1.0\n"
            "comment scanlod gen_surface: triangle soup, edge %g, seed %llu\n"
            "element vertex %llu\nproperty float x\nproperty float y\nproperty float z\n"
            "element face %llu\nproperty list uchar int vertex_indices\nend_header\n",
            edge, (unsigned long long)seed, (unsigned long long)(3 * triangles),
            (unsigned long long)triangles);
    unsigned char buf[36];
    int ok = 1;
    for (uint64_t t = 0; t < triangles && ok; t++) {
        soup_triangle(&state, edge, buf);
        ok = fwrite(buf, 36, 1, f) == 1;
    }
    for (uint64_t t = 0; t < triangles && ok; t++) {
        buf[0] = 3;
        for (int c = 0; c < 3; c++)
            put_u32(buf + 1 + 4 * c, (uint32_t)(3 * t + (uint64_t)c));
        ok = fwrite(buf, 13, 1, f) == 1;
    }
    return ok ? 0 : -1;
}

int main(int argc, char **argv)
{
    uint64_t triangles = 0, seed = 1;
    double noise = 0.15, aspect = 1.0;
    int soup = 0;
    const char *out = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--soup")) {
            soup = 1;
            continue;
        }
        if (i + 1 >= argc)
            return usage();
        if (!strcmp(argv[i], "--triangles"))
            triangles = strtoull(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--noise"))
            noise = strtod(argv[++i], NULL);
        else if (!strcmp(argv[i], "--seed"))
            seed = strtoull(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--aspect"))
            aspect = strtod(argv[++i], NULL);
        else if (!strcmp(argv[i], "-o"))
            out = argv[++i];
        else
            return usage();
    }
    /* 2^31 triangles keeps every vertex index below 2^31 (PLY `int`). */
    if (!out || triangles < 32 || triangles > (1ull << 31) || !(noise >= 0.0 && noise < 0.9) ||
        !(aspect >= 1.0 && aspect <= 1000.0) || (soup && aspect != 1.0))
        return usage();

    uint64_t quads = triangles / 2;
    /* x / 1.0 is x: the plain torus keeps its bytes. */
    uint64_t nu = (uint64_t)llround(sqrt((double)quads * MAJOR_RADIUS / TUBE_RADIUS / aspect));
    nu = nu < 3 ? 3 : nu;
    uint64_t nv = (uint64_t)llround((double)quads / (double)nu);
    nv = nv < 3 ? 3 : nv;

    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    FILE *f = fopen(out, "wb");
    int failed = !f || (soup ? generate_soup(f, triangles, seed) : generate(f, nu, nv, noise, seed)) != 0;
    int saved = errno;
    if (f && fclose(f) != 0 && !failed) {
        failed = 1;
        saved = errno;
    }
    if (failed) {
        fprintf(stderr, "gen_surface: %s: %s\n", out, strerror(saved));
        return 74;
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    printf("{\"triangles\":%llu,\"vertices\":%llu,\"seconds\":%.3f}\n",
           (unsigned long long)(soup ? triangles : 2 * nu * nv),
           (unsigned long long)(soup ? 3 * triangles : nu * nv),
           (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec));
    return 0;
}
