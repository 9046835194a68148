/* Quadric error functions: the Garland-Heckbert quadric of a piece of surface, and the
 * point that minimises it (the vertex placement of dual contouring, Ju et al., "Dual
 * contouring of Hermite data", SIGGRAPH 2002; Lindstrom, "Out-of-core simplification of
 * large polygonal models", SIGGRAPH 2000, for the truncated solve).
 *
 * A quadric sums, over the planes of a surface (n . x = d, |n| = 1), weighted by the area
 * w of surface they carry, the squared distance to the plane:
 *     Q(x) = sum w (n . x - d)^2 = x^T A x - 2 b^T x + c,  A = sum w n n^T, b = sum w d n,
 *     c = sum w d^2,
 * so the quadric of a union is the sum of the quadrics and Q(x) / area is the mean squared
 * distance from x to the surface's tangent planes. It also keeps the area and the
 * area-weighted sum of the surface's points (its "mass point"), and optionally a colour.
 *
 * Frames: a quadric is stored relative to an origin of the caller's choosing (a cell's
 * corner), so the numbers stay small; sl_qef_shift moves it to another origin. All
 * functions are pure; nothing here allocates.
 */
#ifndef SCANLOD_GEOMETRY_QEF_H
#define SCANLOD_GEOMETRY_QEF_H

typedef struct sl_qef {
    double a[6];     /* A: xx, xy, xz, yy, yz, zz */
    double b[3];
    double c;
    double area;     /* sum of w */
    double mass[3];  /* sum of w * point */
} sl_qef;           /* (a caller with colours keeps their sums beside it: 32 bytes more per
                       quadric, which an uncoloured scan's merge would carry for nothing) */

/* Adds the plane through `point` with unit normal `n`, carrying area `w`. */
void sl_qef_add_plane(sl_qef *q, const double n[3], const double point[3], double w);
/* q += r (same frame). */
void sl_qef_add(sl_qef *q, const sl_qef *r);
/* Re-expresses q (relative to origin o_from) relative to o_to = o_from + t. */
void sl_qef_shift(sl_qef *q, const double t[3]);
/* Q(x) (x in q's frame); >= 0 up to rounding. */
double sl_qef_eval(const sl_qef *q, const double x[3]);

/* The minimiser of Q restricted to the directions where A is well conditioned: with
 * A = sum lambda_i u_i u_i^T, the mass point m plus the steps along the u_i whose
 * lambda_i > tau * lambda_max (tau in (0, 1): 0.02 keeps sharp edges and corners, where
 * two or three planes meet, and puts a vertex of a flat or smoothly curved piece on its
 * mass point's tangent plane), then clamped into the box [lo, hi]. Returns 1 when the
 * clamp moved it, 0 otherwise. A quadric of zero area gives the box's centre. */
int sl_qef_solve(const sl_qef *q, double tau, const double lo[3], const double hi[3],
                 double x[3] /* OUT */);

/* Eigen-decomposition of a symmetric 3x3 matrix (cyclic Jacobi): A = V diag(w) V^T, the
 * eigenvectors in V's columns. */
void sl_sym3_eigen(const double a[3][3], double w[3] /* OUT */, double v[3][3] /* OUT */);

#endif
