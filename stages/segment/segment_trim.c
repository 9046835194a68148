/* Boundary trimming (paper 3, section 3.2, equation 2).
 *
 * Candidates are the two-segment vertices (on exactly two segments, once; corners never
 * go, paper: "when the boundary vertex is common to only two segments"), whose angle
 * between their two boundary edges is within delta_b of 180 degrees.
 *
 * Paper mode: the angle is taken at the vertex's own neighbours and every candidate goes
 * (the paper's experiment). Applied to a gently curved boundary this removes every vertex
 * of it, however long the curve, since each single angle is nearly straight.
 *
 * Error mode (the levels): a chain between two fixed vertices is simplified like a
 * Douglas-Peucker polyline: a stretch a..b of the chain is replaced by the segment a-b
 * when the squared distances of the vertices between to it sum to at most max_error^2
 * (a sum, like the interior's scores, segment_refine.c: what counts is the RMS) and each
 * passes equation 2 measured against a and b (the vertices it is then between);
 * otherwise it is split at its farthest vertex (or, if only the angles fail, at the one
 * furthest from straight) and both halves are tried again. So a removed vertex is both
 * near the new boundary and on a nearly straight stretch of it, whatever the spacing.
 *
 * Both sides of a chain see the same decision: a chain is trimmed once, and only when
 * both of its segments may be (a kept segment keeps its triangles, so its boundary must
 * stay). Chains are disjoint in their two-segment vertices: parallel over chains.
 */
#include <math.h>
#include <stdlib.h>

#include "stages/segment/segment_internal.h"

/* Squared distance from p to the segment a-b, and the angle a-p-b in degrees. */
static void measure(const float *a, const float *b, const float *p, double *d2, double *angle)
{
    double ab[3], ap[3], pa[3], pb[3];
    seg_sub(b, a, ab);
    seg_sub(p, a, ap);
    seg_sub(a, p, pa);
    seg_sub(b, p, pb);
    double l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    double t = l2 > 0 ? (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double r[3] = {ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2]};
    *d2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    double la = sqrt(pa[0] * pa[0] + pa[1] * pa[1] + pa[2] * pa[2]);
    double lb = sqrt(pb[0] * pb[0] + pb[1] * pb[1] + pb[2] * pb[2]);
    double c = la > 0 && lb > 0 ? (pa[0] * pb[0] + pa[1] * pb[1] + pa[2] * pb[2]) / (la * lb) : -1;
    *angle = acos(c > 1 ? 1 : c < -1 ? -1 : c) * (180.0 / M_PI);
}

static void trim_paper(const sl_segment_model *m, const uint32_t *v, uint32_t n,
                       double delta_b, uint8_t *kept)
{
    for (uint32_t i = 1; i + 1 < n; i++) {
        double d2, angle;
        measure(m->positions + 3 * (uint64_t)v[i - 1], m->positions + 3 * (uint64_t)v[i + 1],
                m->positions + 3 * (uint64_t)v[i], &d2, &angle);
        kept[v[i]] = !(fabs(180.0 - angle) <= delta_b);
    }
}

/* Douglas-Peucker with equation 2 as a second acceptance test; an explicit stack. */
static void trim_error(const sl_segment_model *m, const uint32_t *v, uint32_t n,
                       const seg_trim_params *p, uint32_t *stack, uint8_t *kept)
{
    double e2 = p->max_error * p->max_error;
    uint32_t top = 0;
    stack[top++] = 0;
    stack[top++] = n - 1;
    for (uint32_t i = 1; i + 1 < n; i++)
        kept[v[i]] = 0;
    while (top) {
        uint32_t b = stack[--top], a = stack[--top];
        if (b - a < 2)
            continue;
        const float *pa = m->positions + 3 * (uint64_t)v[a], *pb = m->positions + 3 * (uint64_t)v[b];
        uint32_t far = SEG_NONE, bent = SEG_NONE;
        double bent_a = p->delta_b, sum = 0, far_d = -1;
        for (uint32_t i = a + 1; i < b; i++) {
            double d2, angle;
            measure(pa, pb, m->positions + 3 * (uint64_t)v[i], &d2, &angle);
            sum += d2;
            if (d2 > far_d) {
                far_d = d2;
                far = i;
            }
            if (fabs(180.0 - angle) > bent_a) {
                bent_a = fabs(180.0 - angle);
                bent = i;
            }
        }
        uint32_t split = sum > e2 ? far : bent; /* too far in sum, or too bent */
        if (split == SEG_NONE)
            continue;
        kept[v[split]] = 1;
        stack[top++] = a;
        stack[top++] = split;
        stack[top++] = split;
        stack[top++] = b;
    }
}

void seg_trim_chains(const sl_segment_model *m, const seg_trim_params *p,
                     const uint8_t *trimmable, const uint8_t *chain_level, uint8_t *kept)
{
    int64_t nc = m->chain_count;
#pragma omp parallel
    {
        uint32_t cap = 0, *stack = NULL;
#pragma omp for schedule(dynamic, 64)
        for (int64_t c = 0; c < nc; c++) {
            const uint32_t *v = m->chain_vertices + m->chain_start[c];
            uint32_t n = m->chain_start[c + 1] - m->chain_start[c];
            int trim = trimmable[m->chain_segments[c][0]] && trimmable[m->chain_segments[c][1]] &&
                       chain_level[c] < SEG_CHAIN_KEEP;
            if (!trim) {
                for (uint32_t i = 1; i + 1 < n; i++)
                    kept[v[i]] = 1;
                continue;
            }
            if (p->paper) {
                trim_paper(m, v, n, p->delta_b, kept);
                continue;
            }
            if (2 * n + 4 > cap) { /* the stack holds at most 2 (n - 1) + 2 entries */
                uint32_t *s = realloc(stack, (2 * (size_t)n + 4) * sizeof *s);
                if (!s) { /* keep the chain as it is */
                    for (uint32_t i = 1; i + 1 < n; i++)
                        kept[v[i]] = 1;
                    continue;
                }
                stack = s;
                cap = 2 * n + 4;
            }
            seg_trim_params q = *p;
            q.max_error = p->max_error / (double)(1u << (2 * chain_level[c]));
            trim_error(m, v, n, &q, stack, kept);
        }
        free(stack);
    }
}

double seg_chain_residual(const sl_segment_model *m, const uint8_t *kept)
{
    int64_t nc = m->chain_count;
    double total = 0;
    /* per chain in parallel, summed in chain order (fixed blocks: deterministic) */
    enum { BLOCK = 256 };
    int64_t blocks = (nc + BLOCK - 1) / BLOCK;
    double *sums = calloc(blocks ? (size_t)blocks : 1, sizeof *sums);
    if (!sums)
        return 0;
#pragma omp parallel for schedule(dynamic, 1)
    for (int64_t b = 0; b < blocks; b++) {
        double sum = 0;
        for (int64_t c = b * BLOCK; c < nc && c < (b + 1) * BLOCK; c++) {
            const uint32_t *v = m->chain_vertices + m->chain_start[c];
            uint32_t n = m->chain_start[c + 1] - m->chain_start[c], a = 0;
            for (uint32_t i = 1; i < n; i++) {
                if (i + 1 < n && !kept[v[i]])
                    continue;
                for (uint32_t j = a + 1; j < i; j++) { /* removed between kept a and i */
                    double d2, angle;
                    measure(m->positions + 3 * (uint64_t)v[a], m->positions + 3 * (uint64_t)v[i],
                            m->positions + 3 * (uint64_t)v[j], &d2, &angle);
                    sum += d2;
                }
                a = i;
            }
        }
        sums[b] = sum;
    }
    for (int64_t b = 0; b < blocks; b++)
        total += sums[b];
    free(sums);
    return total;
}
