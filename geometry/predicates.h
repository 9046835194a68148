/* Robust 2D predicates on doubles: orientation and incircle, exact in sign.
 *
 * Every predicate answers the sign of a determinant of its exact inputs, as if computed
 * with real numbers: no rounding can make collinear points look turned, or a point just
 * outside a circle look inside. The constrained Delaunay triangulation (geometry/cdt.h)
 * relies on that: its combinatorics are only consistent if every answer is.
 *
 * How (docs/mesh-toolkit.md has the proofs): a floating-point evaluation with Shewchuk's
 * a-priori error bound decides almost every call; only when the bound cannot certify the
 * sign (nearly or exactly degenerate input) does an exact evaluation run: in plain doubles
 * when the coordinate differences are exact and narrow enough that no operation rounds
 * (grids), else in floating-point expansion arithmetic, or in big integers when one call's
 * coordinates span more binary orders of magnitude than expansions hold without underflow.
 *
 * Domain: every finite double, including subnormals, huge values and mixtures of both.
 * A NaN or infinite coordinate makes the answer 0 (callers check finiteness first).
 * Thread safety: pure functions, no state; any number of threads.
 * Cost: the filtered path is a handful of flops; the exact paths are 10-1000 times slower
 * and run only on (near-)degenerate input.
 */
#ifndef SCANLOD_GEOMETRY_PREDICATES_H
#define SCANLOD_GEOMETRY_PREDICATES_H

/* The sign of det | ax-cx  ay-cy ; bx-cx  by-cy |: +1 when a, b, c turn
 * counter-clockwise (c lies left of the directed line a->b), -1 when clockwise, 0 when
 * the three points are collinear (or two coincide). */
int sl_orient2d(const double a[2], const double b[2], const double c[2]);

/* The sign of the lifted 4x4 determinant: +1 when d lies strictly inside the circle
 * through a, b, c and a, b, c are counter-clockwise, -1 when strictly outside, 0 when d is
 * on the circle. For clockwise a, b, c the sign is reversed; for collinear a, b, c it is
 * the side of the line d lies on (the "circle" is then a half-plane). */
int sl_incircle(const double a[2], const double b[2], const double c[2], const double d[2]);

/* The same answers without the floating-point filter: always the exact evaluation
 * (plain doubles when provably exact, expansions, or big integers for a wide exponent
 * range). For tests and measurements. */
int sl_orient2d_exact(const double a[2], const double b[2], const double c[2]);
int sl_incircle_exact(const double a[2], const double b[2], const double c[2],
                      const double d[2]);

/* Reference evaluation in big integers only (every coordinate as an integer multiple of
 * the smallest binary unit among them): slow, simple, exact for all finite input. The
 * exact path falls back on it; tests check the two exact methods against each other. */
int sl_orient2d_bigint(const double a[2], const double b[2], const double c[2]);
int sl_incircle_bigint(const double a[2], const double b[2], const double c[2],
                       const double d[2]);

#endif
