/* The general PLY row reader, shared by the ascii and binary bodies (internal).
 *
 * A row is read property by property; a list is its count, checked for sign and against
 * the room left in the data, then its items. The encoding comes in as two functions that
 * are inlined into each format's reader (a C template: no indirect call per value):
 *   value(r, p, type, out)  reads one scalar of `type` into *out, or skips it when out is
 *                           NULL; fails at the end of the data or on a bad token;
 *   room(r, type)           how many list items of `type` the bytes left could hold.
 */
#ifndef SCANLOD_GEOMETRY_PLY_ROW_H
#define SCANLOD_GEOMETRY_PLY_ROW_H

#include "formats/ply_internal.h"

typedef int (*ply_value_fn)(ply_reader *r, const ply_property *p, int type, double *out);
typedef uint64_t (*ply_room_fn)(const ply_reader *r, int type);

#define PLY_INLINE static inline __attribute__((always_inline))
#define PLY_TICK_ROWS 0xFFFF /* progress/interrupt check every 64 Ki rows */

PLY_INLINE int ply_read_list(ply_reader *r, const ply_property *p, uint64_t *corners,
                             ply_value_fn value, ply_room_fn room)
{
    double count, v;
    int rc = value(r, p, p->count_type, &count);
    if (rc)
        return rc;
    if (count < 0)
        return sl_ply_body_error(r, SL_E_BADINPUT, "list '%s' has negative length %.0f", p->name,
                                 count);
    uint64_t n = (uint64_t)count;
    if (n > room(r, p->type))
        return sl_ply_body_error(r, SL_E_BADINPUT,
                                 "list '%s' declares %llu items but only %llu bytes remain",
                                 p->name, (unsigned long long)n,
                                 (unsigned long long)(r->end - r->p));
    if (p->role == ROLE_INDICES)
        *corners = n;
    if ((rc = sl_ply_begin_list(r, p->role, n)))
        return rc;
    for (uint64_t i = 0; i < n; i++) {
        if ((rc = value(r, p, p->type, p->role == ROLE_SKIP ? NULL : &v)))
            return rc;
        if (p->role != ROLE_SKIP && (rc = sl_ply_store_list_item(r, p->role, i, v)))
            return rc;
    }
    return 0;
}

PLY_INLINE int ply_read_row(ply_reader *r, const ply_element *e, ply_value_fn value,
                            ply_room_fn room)
{
    const ply_property *props = &r->h->props[e->first_prop];
    uint64_t corners = 0;
    double v;
    int rc;
    for (int k = 0; k < e->nprops; k++) {
        const ply_property *p = &props[k];
        if (p->count_type)
            rc = ply_read_list(r, p, &corners, value, room);
        else if (!(rc = value(r, p, p->type, p->role == ROLE_SKIP ? NULL : &v)) && p->role)
            sl_ply_store_vertex(r, r->row, p->role, p->type, v);
        if (rc)
            return rc;
    }
    return e->kind == KIND_FACE ? sl_ply_end_face(r, corners) : 0;
}

/* Every row of e. */
PLY_INLINE int ply_read_rows(ply_reader *r, const ply_element *e, ply_value_fn value,
                             ply_room_fn room)
{
    int rc;
    for (uint64_t row = 0; row < e->count; row++) {
        r->row = row;
        if ((row & PLY_TICK_ROWS) == 0 && (rc = sl_ply_tick(r)))
            return rc;
        if ((rc = ply_read_row(r, e, value, room)))
            return rc;
    }
    return 0;
}

/* A face element of one index list, read in runs of plain triangles: `run` copies up to
 * `rows` rows "3 a b c" with indices < limit into t and stops before any other row; that
 * row (a polygon, a bad index, the end of the data, a full array) goes through
 * ply_read_row, which grows the array or reports the error. */
typedef uint64_t (*ply_triangle_run_fn)(ply_reader *r, uint64_t rows, uint64_t limit, uint32_t *t);

PLY_INLINE int ply_read_triangles(ply_reader *r, const ply_element *e, uint64_t limit,
                                  ply_triangle_run_fn run, ply_value_fn value, ply_room_fn room)
{
    sl_mesh *m = r->mesh;
    uint64_t next_tick = 0;
    int rc;
    for (uint64_t row = 0; row < e->count;) {
        if (row >= next_tick) {
            r->row = row;
            if ((rc = sl_ply_tick(r)))
                return rc;
            next_tick = row + PLY_TICK_ROWS + 1;
        }
        uint64_t want = (next_tick < e->count ? next_tick : e->count) - row;
        uint64_t room_left = r->tri_cap - m->triangle_count;
        want = want < room_left ? want : room_left;
        uint64_t done = run(r, want, limit, m->triangles + 3 * m->triangle_count);
        m->triangle_count += done;
        row += done;
        if ((done == want && want > 0) || row == e->count)
            continue;
        r->row = row++;
        if ((rc = ply_read_row(r, e, value, room)))
            return rc;
    }
    return 0;
}

#endif
