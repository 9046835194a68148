/* Plain marching cubes over the samples (Lorensen & Cline 1987, the triangulation paper 1
 * section 2.1 relies on), as a reference: the distance variants are measured with it
 * (docs/samples-stage.md), and the merge stage's finest level can be checked against it.
 *
 * Every cube of the leaf grid whose 8 corners are samples is triangulated with the
 * runtime's 256-case table (runtime/mc_cube.h: generated from one pairing rule per face,
 * so same-level neighbours agree and the surface has no holes between cubes). Vertices
 * sit at the linear zero crossing of their grid edge and are shared: one per edge.
 */
#include <stdlib.h>
#include <string.h>

#include "runtime/mc_cube.h"
#include "stages/samples/samples_internal.h"

typedef struct mc_out {
    sl_mesh *mesh;
    uint64_t vertex_cap, triangle_cap;
    uint32_t *edge_vertex; /* 3 * samples: vertex on the edge from sample i along axis a */
} mc_out;

static int grow(void **array, uint64_t *cap, uint64_t need, size_t item)
{
    if (need <= *cap)
        return 1;
    uint64_t c = *cap ? *cap * 2 : 1024;
    while (c < need)
        c *= 2;
    void *p = realloc(*array, c * item);
    if (!p)
        return 0;
    *array = p;
    *cap = c;
    return 1;
}

/* The vertex on edge `e` of the cube whose corners are samples idx[0..8); 0 on no memory. */
static int edge_vertex(const sl_vdb_samples *s, const uint64_t idx[8], int e, mc_out *o,
                       uint32_t *vertex)
{
    int a = sl_mc_edge_axis(e), c0 = sl_mc_edge_c0(e), c1 = sl_mc_edge_c1(e);
    uint64_t slot = 3 * idx[c0] + (uint64_t)a;
    if (o->edge_vertex[slot] == UINT32_MAX) {
        sl_mesh *m = o->mesh;
        if (m->vertex_count >= UINT32_MAX - 1 ||
            !grow((void **)&m->positions, &o->vertex_cap, m->vertex_count + 1, 3 * sizeof(float)))
            return 0;
        double d0 = s->distance[idx[c0]], d1 = s->distance[idx[c1]], t = d0 / (d0 - d1);
        for (int k = 0; k < 3; k++) {
            double g = s->coords[3 * idx[c0] + k] + (k == a ? t : 0.0);
            m->positions[3 * m->vertex_count + k] = (float)(s->origin[k] + s->leaf_size * g);
        }
        o->edge_vertex[slot] = (uint32_t)m->vertex_count++;
    }
    *vertex = o->edge_vertex[slot];
    return 1;
}

static int cube(const sl_vdb_samples *s, const uint64_t *keys, uint64_t i,
                const sl_mc_triangles *table, mc_out *o)
{
    uint64_t idx[8];
    int mask = 0;
    for (int c = 0; c < 8; c++) {
        uint64_t key = keys[i] + sl_vertex_key(c & 1, (c >> 1) & 1, (c >> 2) & 1);
        int64_t at = c == 0 ? 0 : sl_find_key(keys + i, s->count - i, key);
        if (at < 0)
            return 1; /* not every corner is a sample: not a cube of the grid */
        idx[c] = i + (uint64_t)at;
        mask |= (s->distance[idx[c]] < 0) << c;
    }
    const sl_mc_triangles *t = &table[mask];
    sl_mesh *m = o->mesh;
    if (!grow((void **)&m->triangles, &o->triangle_cap, m->triangle_count + t->count,
              3 * sizeof(uint32_t)))
        return 0;
    for (int k = 0; k < t->count; k++)
        for (int j = 0; j < 3; j++)
            if (!edge_vertex(s, idx, t->points[k][j], o, &m->triangles[3 * m->triangle_count + 3 * k + j]))
                return 0;
    m->triangle_count += t->count;
    return 1;
}

int sl_samples_marching_cubes(const sl_vdb_samples *s, sl_mesh *out, sl_error *err)
{
    sl_mesh_init(out);
    const sl_mc_triangles *table = sl_mc_uniform_table();
    uint64_t *keys = malloc(s->count * sizeof *keys + 1);
    mc_out o = {out, 0, 0, malloc(3 * s->count * sizeof(uint32_t) + 1)};
    int ok = keys && o.edge_vertex;
    for (uint64_t i = 0; ok && i < s->count; i++) {
        for (int k = 0; k < 3; k++)
            if (s->coords[3 * i + k] < 0 || s->coords[3 * i + k] >= (int32_t)SL_COORD_LIMIT - 1) {
                free(keys), free(o.edge_vertex);
                return sl_error_set(err, SL_E_LIMIT, 0, NULL,
                                    "marching cubes: coordinate outside [0, 2^20 - 1)");
            }
        keys[i] = sl_vertex_key((uint32_t)s->coords[3 * i], (uint32_t)s->coords[3 * i + 1],
                                 (uint32_t)s->coords[3 * i + 2]);
        o.edge_vertex[3 * i] = o.edge_vertex[3 * i + 1] = o.edge_vertex[3 * i + 2] = UINT32_MAX;
    }
    for (uint64_t i = 0; ok && i < s->count; i++)
        ok = cube(s, keys, i, table, &o);
    free(keys), free(o.edge_vertex);
    if (!ok) {
        sl_mesh_release(out);
        return sl_error_set(err, SL_E_NOMEM, 0, NULL, "marching cubes: out of memory");
    }
    return SL_OK;
}
