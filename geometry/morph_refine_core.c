/* The state the morph refinement's steps share (morph_refine_core.h): a vertex's
 * coarser members, room for the vertices and triangles, and adding a vertex. */
#include <stdlib.h>
#include <string.h>

#include "geometry/morph_refine_core.h"

int mr_nomem(sl_error *err)
{
    return sl_error_set(err, SL_E_NOMEM, 0, NULL, "morph refinement: out of memory");
}

/* The coarser triangles (around the corners of coarser triangle h) point p lies in. */
int mr_members_of(const refine *R, const double p[3], uint32_t h, uint32_t *out)
{
    int n = 0;
    for (int k = 0; k < 3; k++) {
        uint32_t cv = R->c->triangles[3 * (uint64_t)h + k];
        for (uint32_t i = R->ring_start[cv]; i < R->ring_start[cv + 1]; i++) {
            uint32_t g = R->ring[i];
            int seen = 0;
            for (int j = 0; j < n && !seen; j++)
                seen = out[j] == g;
            if (!seen && n < MEMBERS_MAX && mr_lies_in(R, p, g))
                out[n++] = g;
        }
    }
    return n;
}

/* Keeps vertex v's members (m, n) for mr_members; 0, or -1 out of memory. */
int mr_members_keep(refine *R, uint32_t v, const uint32_t *m, int n)
{
    if (R->members_n + (uint64_t)n > R->members_cap) {
        uint64_t cap = 2 * R->members_cap + (uint64_t)n + 1024;
        uint32_t *p = realloc(R->members_pool, cap * sizeof *p);
        if (!p)
            return -1;
        R->members_pool = p, R->members_cap = cap;
    }
    memcpy(R->members_pool + R->members_n, m, (size_t)n * sizeof *m);
    R->members_at[v] = R->members_n << 8 | (uint64_t)n;
    R->members_n += (uint64_t)n;
    return 0;
}

int mr_reserve(refine *R, uint64_t vertices, uint64_t triangles, sl_error *err)
{
    sl_morph_refined *r = R->r;
    if (vertices > UINT32_MAX)
        return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                            "morph refinement: more than 2^32 - 1 vertices");
    if (vertices > R->vcap) {
        uint64_t cap = vertices + vertices / 2 + 64;
        float *p = realloc(r->positions, cap * 12), *t = p ? realloc(r->targets, cap * 12) : NULL;
        if (p)
            r->positions = p;
        if (t)
            r->targets = t;
        uint32_t *s = t ? realloc(r->source, cap * 12) : NULL;
        if (s)
            r->source = s;
        float *w = s ? realloc(r->weight, cap * 12) : NULL;
        if (w)
            r->weight = w;
        uint32_t *h = w ? realloc(R->hint, cap * 4) : NULL;
        if (h)
            R->hint = h;
        uint64_t *at = h ? realloc(R->members_at, cap * sizeof *at) : NULL;
        if (!at)
            return mr_nomem(err);
        R->members_at = at;
        R->vcap = cap;
    }
    if (triangles > R->tcap) {
        uint64_t cap = triangles + triangles / 2 + 64;
        uint32_t *t = realloc(r->triangles, cap * 12);
        if (!t)
            return mr_nomem(err);
        r->triangles = t;
        R->tcap = cap;
    }
    return 0;
}

/* Adds the vertex sum_k f[k] * (vertex v[k]) of the level's triangle they lie in, with
 * target `t` (in coarser triangle `hint`). Sources merge by level vertex. */
uint32_t mr_add_vertex(refine *R, int count, const uint32_t *v, const double *f,
                           const double t[3], uint32_t hint)
{
    sl_morph_refined *r = R->r;
    uint32_t id[9];
    double w[9];
    int n = 0;
    for (int i = 0; i < count; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t s = r->source[3 * (uint64_t)v[i] + k];
            double x = f[i] * r->weight[3 * (uint64_t)v[i] + k];
            if (x == 0)
                continue;
            int j = 0;
            while (j < n && id[j] != s)
                j++;
            if (j == n)
                id[n] = s, w[n++] = 0;
            w[j] += x;
        }
    while (n > 3) { /* not on one level triangle (cannot happen): keep the heaviest three */
        int low = 0;
        for (int j = 1; j < n; j++)
            low = w[j] < w[low] ? j : low;
        id[low] = id[n - 1], w[low] = w[n - 1], n--;
    }
    double sum = 0, p[3] = {0, 0, 0};
    for (int j = 0; j < n; j++)
        sum += w[j];
    uint64_t i = r->vertex_count++;
    for (int j = 0; j < 3; j++) {
        r->source[3 * i + j] = j < n ? id[j] : id[0];
        r->weight[3 * i + j] = j < n ? (float)(w[j] / sum) : 0.0f;
        for (int k = 0; k < 3 && j < n; k++)
            p[k] += w[j] / sum * R->level->positions[3 * (uint64_t)id[j] + k];
    }
    for (int k = 0; k < 3; k++)
        r->positions[3 * i + k] = (float)p[k], r->targets[3 * i + k] = (float)t[k];
    R->hint[i] = hint;
    uint32_t m[MEMBERS_MAX];
    double q[3] = {r->targets[3 * i], r->targets[3 * i + 1], r->targets[3 * i + 2]};
    if (mr_members_keep(R, (uint32_t)i, m, mr_members_of(R, q, hint, m)))
        R->failed = 1, R->members_at[i] = 0; /* reported by the round that made it */
    return (uint32_t)i;
}

int mr_cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

int mr_vertex_rings(const uint32_t *triangles, uint64_t triangle_count, uint64_t vertex_count,
                    uint32_t **start_out, uint32_t **ring_out)
{
    uint32_t *start = calloc(vertex_count + 2, sizeof *start);
    uint32_t *ring = malloc((3 * triangle_count + 1) * sizeof *ring);
    *start_out = start, *ring_out = ring;
    if (!start || !ring)
        return -1;
    for (uint64_t i = 0; i < 3 * triangle_count; i++)
        start[triangles[i] + 2]++;
    for (uint64_t v = 0; v < vertex_count; v++)
        start[v + 2] += start[v + 1];
    for (uint64_t i = 0; i < 3 * triangle_count; i++)
        ring[start[triangles[i] + 1]++] = (uint32_t)(i / 3);
    return 0;
}
