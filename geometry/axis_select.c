/* Median selection along an axis (see axis_select.h). */
#include "geometry/axis_select.h"

static inline int record_less(const sl_axis_record *a, const sl_axis_record *b, int axis)
{
    if (a->p[axis] != b->p[axis])
        return a->p[axis] < b->p[axis];
    return a->index < b->index;
}

static inline void record_swap(sl_axis_record *a, sl_axis_record *b)
{
    sl_axis_record t = *a;
    *a = *b;
    *b = t;
}

void sl_axis_select(sl_axis_record *r, uint64_t n, uint64_t k, int axis)
{
    uint64_t lo = 0, hi = n - 1;
    while (hi > lo) {
        uint64_t mid = lo + (hi - lo) / 2;
        if (record_less(&r[mid], &r[lo], axis))
            record_swap(&r[mid], &r[lo]);
        if (record_less(&r[hi], &r[lo], axis))
            record_swap(&r[hi], &r[lo]);
        if (record_less(&r[hi], &r[mid], axis))
            record_swap(&r[hi], &r[mid]);
        sl_axis_record pivot = r[mid];
        uint64_t i = lo, j = hi;
        for (;;) {
            while (record_less(&r[i], &pivot, axis))
                i++;
            while (record_less(&pivot, &r[j], axis))
                j--;
            if (i >= j)
                break;
            record_swap(&r[i], &r[j]);
            i++;
            j--;
        }
        /* r[lo..j] <= pivot <= r[j+1..hi] */
        if (k <= j)
            hi = j;
        else
            lo = j + 1;
    }
}

int sl_axis_widest(const sl_axis_record *r, uint64_t n)
{
    float lo[3] = {r[0].p[0], r[0].p[1], r[0].p[2]}, hi[3] = {lo[0], lo[1], lo[2]};
    for (uint64_t i = 1; i < n; i++)
        for (int a = 0; a < 3; a++) {
            if (r[i].p[a] < lo[a])
                lo[a] = r[i].p[a];
            if (r[i].p[a] > hi[a])
                hi[a] = r[i].p[a];
        }
    int axis = 0;
    for (int a = 1; a < 3; a++)
        if (hi[a] - lo[a] > hi[axis] - lo[axis])
            axis = a;
    return axis;
}
