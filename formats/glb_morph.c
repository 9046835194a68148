/* A GLB's morph target (glb.h, docs/morphing.md): targets[0].POSITION, the displacement
 * from each vertex as a viewer decodes it to where the caller says it goes.
 *
 * glTF 2.0 section 3.7.2.2 (morph targets): a target's POSITION holds displacements, with
 * min/max; KHR_mesh_quantization lets them be (normalized or not) bytes and shorts. In a
 * quantised file the displacement is in steps of the positions' own grid: the target
 * point is rounded to the grid the vertex itself is on, so weight 1 lands where the
 * coarser level's vertex would land, within the same half step. In a Draco file the
 * decoded vertices (whose order and count Draco chose) are the base: each takes the
 * target of the nearest vertex given, which is its own vertex moved by at most the
 * quantisation bound (vertices closer than that to each other are one place anyway).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "formats/glb_internal.h"
#include "geometry/kdtree.h"

/* The grid coordinates of vertex i in the quantised POSITION view. */
static void grid_position(const glb_view *v, uint64_t i, long q[3])
{
    const unsigned char *p = v->data + (uint64_t)v->stride * i;
    for (int k = 0; k < 3; k++)
        q[k] = v->stride == 8 ? (long)(p[2 * k] | p[2 * k + 1] << 8) : (long)p[k];
}

/* Displacements in grid steps; *shorts = 0 when one does not fit a SHORT. */
static void grid_displacements(const glb_doc *d, const sl_mesh *m, double *disp, int *shorts)
{
    const glb_view *v = &d->views[d->accessors[0].view];
    const float *t = d->opt->morph_positions;
    *shorts = 1;
    for (uint64_t i = 0; i < m->vertex_count; i++) {
        long q[3];
        grid_position(v, i, q);
        for (int k = 0; k < 3; k++) {
            double exact = ((double)t[3 * i + k] - d->translation[k]) / d->scale - q[k];
            double steps = round(exact);
            *shorts &= fabs(steps) <= 32767;
            disp[3 * i + k] = steps;
        }
    }
    if (*shorts)
        return;
    for (uint64_t i = 0; i < m->vertex_count; i++) { /* float steps, unrounded */
        long q[3];
        grid_position(v, i, q);
        for (int k = 0; k < 3; k++)
            disp[3 * i + k] = (float)(((double)t[3 * i + k] - d->translation[k]) / d->scale - q[k]);
    }
}

/* Base positions (as decoded, world) and the target of each: float files. */
static void float_displacements(const glb_doc *d, const sl_mesh *m, double *disp)
{
    const float *t = d->opt->morph_positions;
    for (uint64_t i = 0; i < 3 * m->vertex_count; i++)
        disp[i] = (float)(t[i] - m->positions[i]);
}

static int draco_displacements(const glb_doc *d, const sl_mesh *m, double *disp,
                               uint32_t *source, sl_error *err)
{
    sl_kdtree *tree = NULL;
    int rc = sl_kdtree_build(&tree, m->positions, m->vertex_count, err);
    if (rc)
        return rc;
    const float *t = d->opt->morph_positions, *base = d->decoded_positions;
    for (uint64_t i = 0; i < d->stats.vertices; i++) {
        float d2;
        uint32_t j = sl_kdtree_nearest(tree, base + 3 * i, &d2);
        source[i] = j;
        for (int k = 0; k < 3; k++)
            disp[3 * i + k] = (float)(t[3 * (uint64_t)j + k] - base[3 * i + k]);
    }
    sl_kdtree_free(tree);
    return 0;
}

/* The view and accessor of `disp` (count x 3), as SHORT (stride 8) or FLOAT (stride 12). */
static int add_target(glb_doc *d, const double *disp, uint64_t count, int shorts, sl_error *err)
{
    uint32_t stride = shorts ? 8 : 12;
    unsigned char *data = calloc(count ? count : 1, stride);
    if (!data)
        return sl_error_nomem(err, NULL, "GLB: out of memory for the morph target");
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i = 0; i < count; i++)
        for (int k = 0; k < 3; k++) {
            double v = disp[3 * i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
            unsigned char *p = data + (uint64_t)stride * i;
            if (shorts) {
                uint16_t u = (uint16_t)(int16_t)v;
                p[2 * k] = (unsigned char)u, p[2 * k + 1] = (unsigned char)(u >> 8);
            } else {
                float f = (float)v;
                memcpy(p + 4 * k, &f, 4); /* little-endian hosts only, as the positions */
            }
        }
    int view = glb_add_view(d, data, (uint64_t)stride * count, stride, count, GLTF_ARRAY_BUFFER,
                            "ATTRIBUTES");
    glb_accessor *a = glb_add_accessor(d, "POSITION", view, shorts ? GLTF_SHORT : GLTF_FLOAT,
                                       "VEC3", 0, count);
    a->morph = 1;
    a->has_bounds = 1;
    for (int k = 0; k < 3; k++)
        a->min[k] = lo[k], a->max[k] = hi[k];
    d->quantized |= shorts;
    d->stats.morph = 1;
    return 0;
}

/* How far weight 1 lands from the target given, on the values a viewer decodes. */
static double landing_error(const glb_doc *d, const sl_mesh *m, const double *disp,
                            const uint32_t *source)
{
    const float *t = d->opt->morph_positions;
    int grid = d->node_transform && d->opt->compression != SL_GLB_DRACO;
    const glb_view *v = grid ? &d->views[d->accessors[0].view] : NULL;
    uint64_t count = source ? d->stats.vertices : m->vertex_count;
    double worst2 = 0;
    for (uint64_t i = 0; i < count; i++) {
        long q[3] = {0, 0, 0};
        if (grid)
            grid_position(v, i, q);
        const float *target = t + 3 * (uint64_t)(source ? source[i] : i);
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            double base = source ? d->decoded_positions[3 * i + k] : m->positions[3 * i + k];
            double at = grid ? (q[k] + disp[3 * i + k]) * d->scale + d->translation[k]
                             : base + disp[3 * i + k];
            d2 += (at - target[k]) * (at - target[k]);
        }
        worst2 = d2 > worst2 ? d2 : worst2;
    }
    return sqrt(worst2);
}

int glb_morph_target(glb_doc *d, const sl_mesh *m, sl_error *err)
{
    int draco = d->opt->compression == SL_GLB_DRACO;
    uint64_t count = draco ? d->stats.vertices : m->vertex_count;
    double *disp = malloc(3 * (count ? count : 1) * sizeof *disp);
    uint32_t *source = draco ? malloc((count ? count : 1) * sizeof *source) : NULL;
    if (!disp || (draco && !source)) {
        free(disp), free(source);
        return sl_error_nomem(err, NULL, "GLB: out of memory for the morph target");
    }
    int rc = 0, shorts = 0;
    if (draco)
        rc = draco_displacements(d, m, disp, source, err);
    else if (d->node_transform)
        grid_displacements(d, m, disp, &shorts);
    else
        float_displacements(d, m, disp);
    if (rc == 0)
        rc = add_target(d, disp, count, shorts, err);
    if (rc == 0)
        d->stats.morph_error_max = landing_error(d, m, disp, source);
    free(disp), free(source);
    return rc;
}
