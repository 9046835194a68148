/* Plane fitting: weighted total least squares by the eigenvectors of the covariance
 * (cyclic Jacobi rotations, Golub and Van Loan, "Matrix Computations", 8.5), or the
 * paper's z = a x + b y + d by its normal equations (Kim, Yun, Lee, paper 3, equations
 * 4-6), solved in centred coordinates so that a patch far from the origin loses no digits.
 * Both pass over the points twice: the centroid first, then the centred moments.
 */
#include "geometry/plane_fit.h"

#include <math.h>
#include <string.h>

#include "geometry/predicates.h"
#include "geometry/vec3.h"

static void point(const float *positions, const uint32_t *index, uint64_t k, double p[3])
{
    uint64_t i = index ? index[k] : k;
    for (int a = 0; a < 3; a++)
        p[a] = positions[3 * i + a];
}

static void normalize3(double a[3])
{
    double len = sqrt(sl_dot3(a, a));
    for (int k = 0; k < 3; k++)
        a[k] /= len;
}

/* Weighted centroid and centred second moments (divided by the total weight). */
static int moments(const float *positions, const uint32_t *index, uint64_t count,
                   const double *weights, double centroid[3], double cov[3][3], sl_error *err)
{
    if (count == 0)
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "plane fit of no points");
    double total = 0, sum[3] = {0, 0, 0};
    for (uint64_t k = 0; k < count; k++) {
        double p[3], w = weights ? weights[k] : 1.0;
        point(positions, index, k, p);
        if (!(w >= 0 && isfinite(w)) || !isfinite(p[0] + p[1] + p[2]))
            return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                                "plane fit: point %llu has weight %g at (%g, %g, %g)",
                                (unsigned long long)k, w, p[0], p[1], p[2]);
        total += w;
        for (int a = 0; a < 3; a++)
            sum[a] += w * p[a];
    }
    if (!(total > 0))
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL, "plane fit: total weight is zero");
    for (int a = 0; a < 3; a++)
        centroid[a] = sum[a] / total;
    memset(cov, 0, 9 * sizeof cov[0][0]);
    for (uint64_t k = 0; k < count; k++) {
        double p[3], w = weights ? weights[k] : 1.0;
        point(positions, index, k, p);
        for (int a = 0; a < 3; a++)
            p[a] -= centroid[a];
        for (int a = 0; a < 3; a++)
            for (int b = a; b < 3; b++)
                cov[a][b] += w * p[a] * p[b];
    }
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++)
            cov[b][a] = cov[a][b] /= total;
    return SL_OK;
}

/* One Jacobi rotation in the (p, q) plane that zeroes a[p][q]; accumulates it in vec. */
static void rotate(double a[3][3], double vec[3][3], int p, int q)
{
    double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
    double t = fabs(theta) > 1e150 ? 0.5 / theta
                                   : (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
    double c = 1 / sqrt(t * t + 1), s = t * c;
    for (int k = 0; k < 3; k++) { /* a = a J, then a = J^T a, vec = vec J */
        double akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq, a[k][q] = s * akp + c * akq;
    }
    for (int k = 0; k < 3; k++) {
        double apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk, a[q][k] = s * apk + c * aqk;
    }
    for (int k = 0; k < 3; k++) {
        double vkp = vec[k][p], vkq = vec[k][q];
        vec[k][p] = c * vkp - s * vkq, vec[k][q] = s * vkp + c * vkq;
    }
    a[p][q] = a[q][p] = 0; /* exactly, not by rounding */
}

/* Eigen-decomposition of a symmetric 3x3 matrix: values ascending, vectors as the matching
 * columns of vec. Cyclic Jacobi converges quadratically; 50 sweeps is far more than the
 * 5-6 it takes to reach rounding level. */
static void eigen_symmetric(double a[3][3], double values[3], double vec[3][3])
{
    static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    memset(vec, 0, 9 * sizeof vec[0][0]);
    vec[0][0] = vec[1][1] = vec[2][2] = 1;
    for (int sweep = 0; sweep < 50; sweep++) {
        double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= 1e-36 * diag || off == 0)
            break;
        for (int r = 0; r < 3; r++)
            if (a[pairs[r][0]][pairs[r][1]] != 0)
                rotate(a, vec, pairs[r][0], pairs[r][1]);
    }
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (a[order[j]][order[j]] < a[order[i]][order[i]]) {
                int t = order[i];
                order[i] = order[j], order[j] = t;
            }
    double sorted[3][3];
    for (int i = 0; i < 3; i++) {
        values[i] = a[order[i]][order[i]];
        for (int k = 0; k < 3; k++)
            sorted[k][i] = vec[k][order[i]];
    }
    memcpy(vec, sorted, sizeof sorted);
}

/* The sign rule (largest component positive), the frame and the offset. */
static void finish_plane(sl_plane *out)
{
    double *n = out->normal;
    normalize3(n);
    int big = 0;
    for (int a = 1; a < 3; a++)
        if (fabs(n[a]) > fabs(n[big]))
            big = a;
    if (n[big] < 0)
        for (int a = 0; a < 3; a++)
            n[a] = -n[a];
    /* u: the normal crossed with the axis it is least aligned with. */
    int least = 0;
    for (int a = 1; a < 3; a++)
        if (fabs(n[a]) < fabs(n[least]))
            least = a;
    double axis[3] = {0, 0, 0};
    axis[least] = 1;
    sl_cross3(n, axis, out->u);
    normalize3(out->u);
    sl_cross3(n, out->u, out->v);
    normalize3(out->v);
    out->offset = sl_dot3(n, out->centroid);
}

static int fit_z_form(const double cov[3][3], sl_plane *out, sl_error *err)
{
    /* Centred normal equations: [sxx sxy; sxy syy] (a, b) = (sxz, syz); d follows. */
    double sxx = cov[0][0], sxy = cov[0][1], syy = cov[1][1];
    double det = sxx * syy - sxy * sxy;
    if (!(det > 1e-12 * sxx * syy) || !(sxx > 0) || !(syy > 0))
        return sl_error_set(err, SL_E_BADINPUT, 0, NULL,
                            "plane fit z = a x + b y + d is undefined: the points' xy "
                            "projection is (nearly) a line, the plane is vertical");
    double a = (cov[0][2] * syy - cov[1][2] * sxy) / det;
    double b = (cov[1][2] * sxx - cov[0][2] * sxy) / det;
    out->normal[0] = a, out->normal[1] = b, out->normal[2] = -1;
    return SL_OK;
}

int sl_plane_fit(const float *positions, const uint32_t *index, uint64_t count,
                 const double *weights, int method, sl_plane *out, sl_error *err)
{
    memset(out, 0, sizeof *out);
    double cov[3][3], work[3][3], vec[3][3];
    int rc = moments(positions, index, count, weights, out->centroid, cov, err);
    if (rc)
        return rc;
    memcpy(work, cov, sizeof work);
    eigen_symmetric(work, out->eigenvalues, vec);
    double top = out->eigenvalues[2];
    out->degenerate = !(out->eigenvalues[1] > 0x1p-40 * top);
    if (method == SL_PLANE_Z_FORM) {
        rc = fit_z_form(cov, out, err);
        if (rc)
            return rc;
    } else {
        for (int a = 0; a < 3; a++)
            out->normal[a] = vec[a][0];
    }
    finish_plane(out);
    double total = 0, sum = 0;
    for (uint64_t k = 0; k < count; k++) {
        double p[3], w = weights ? weights[k] : 1.0;
        point(positions, index, k, p);
        for (int a = 0; a < 3; a++)
            p[a] -= out->centroid[a];
        double d = sl_dot3(out->normal, p), d2 = d * d;
        total += w, sum += w * d2;
        if (w > 0 && d2 > out->max_dist2)
            out->max_dist2 = d2;
    }
    out->mean_dist2 = sum / total;
    return SL_OK;
}

void sl_plane_orient(sl_plane *plane, const double reference[3])
{
    if (sl_dot3(plane->normal, reference) >= 0)
        return;
    for (int a = 0; a < 3; a++) {
        plane->normal[a] = -plane->normal[a];
        plane->v[a] = -plane->v[a];
    }
    plane->offset = -plane->offset;
}

void sl_plane_project(const sl_plane *plane, const float *positions, const uint32_t *index,
                      uint64_t count, double *uv)
{
    for (uint64_t k = 0; k < count; k++) {
        double p[3];
        point(positions, index, k, p);
        for (int a = 0; a < 3; a++)
            p[a] -= plane->centroid[a];
        uv[2 * k] = sl_dot3(p, plane->u);
        uv[2 * k + 1] = sl_dot3(p, plane->v);
    }
}

uint64_t sl_plane_projection_fold(const double *uv, const uint32_t *triangles,
                                  uint64_t triangle_count)
{
    for (uint64_t t = 0; t < triangle_count; t++) {
        const uint32_t *v = triangles + 3 * t;
        if (sl_orient2d(uv + 2 * (uint64_t)v[0], uv + 2 * (uint64_t)v[1],
                        uv + 2 * (uint64_t)v[2]) <= 0)
            return t;
    }
    return UINT64_MAX;
}
