/* Small 3-vector helpers on double[3], shared by the geometry code (one copy, inline). */
#ifndef SCANLOD_GEOMETRY_VEC3_H
#define SCANLOD_GEOMETRY_VEC3_H

static inline double sl_dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void sl_cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

#endif
