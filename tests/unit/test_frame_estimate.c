/* The frame estimate (geometry/frame_estimate.h): the footprint rule for up and the
 * diagonal rule for units on shapes whose answer is known, and, with SCANLOD_SHARED_DATA,
 * its accuracy on the shared scans whose up axis is known (docs/metadata.md, "Frames":
 * the table printed here is the one quoted there). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/ply.h"
#include "geometry/frame_estimate.h"
#include "tests/check.h"

/* A cone standing on its disc: base at the lowest `axis` value, apex above, radius r,
 * height h, scaled by `scale`. Its footprint is the whole disc: up = axis. */
static void cone(sl_mesh *m, int axis, double r, double h, double scale)
{
    enum { RIM = 64, RINGS = 16 };
    sl_mesh_init(m);
    m->vertex_count = RIM * RINGS + 1;
    m->positions = calloc(3 * m->vertex_count, sizeof *m->positions);
    for (int ring = 0; ring < RINGS; ring++)
        for (int i = 0; i < RIM; i++) {
            double t = ring / (double)RINGS, a = 2 * M_PI * i / RIM;
            float *q = m->positions + 3 * (ring * RIM + i);
            double up = h * t, rr = r * (1 - t);
            double c[3] = {rr * cos(a), rr * sin(a), up}; /* z up, then permuted */
            q[0] = (float)(scale * c[axis == 0 ? 2 : 0]);
            q[1] = (float)(scale * c[axis == 1 ? 2 : axis == 0 ? 0 : 1]);
            q[2] = (float)(scale * c[axis == 2 ? 2 : 1]);
        }
    float *apex = m->positions + 3 * RIM * RINGS;
    apex[axis] = (float)(scale * h);
}

static void synthetic(void)
{
    sl_error err;
    sl_error_init(&err);
    sl_frame_estimate f;
    for (int axis = 0; axis < 3; axis++) {
        sl_mesh m;
        cone(&m, axis, 0.1, 0.3, 1.0);
        CHECK(sl_frame_estimate_compute(&m, &f, &err) == 0);
        CHECK_MSG(f.best == 2 * axis, "cone on axis %d: best %s", axis,
                  sl_frame_direction_name(f.best));
        CHECK(f.up == (axis == 2 ? 'z' : 'y')); /* on its side (x): y, glTF's default */
        CHECK(!strcmp(f.units, "m"));
        sl_mesh_release(&m);
    }
    sl_mesh m;
    cone(&m, 2, 100, 300, 1.0); /* the same cone in millimetres */
    CHECK(sl_frame_estimate_compute(&m, &f, &err) == 0);
    CHECK(f.up == 'z' && !strcmp(f.units, "mm"));
    CHECK_NEAR(f.diagonal, sqrt(200.0 * 200 + 200 * 200 + 300 * 300), 1.0);
    sl_mesh_release(&m);
    sl_mesh flat; /* one point: nothing to judge */
    sl_mesh_init(&flat);
    float one[3] = {1, 2, 3};
    flat.vertex_count = 1, flat.positions = one;
    CHECK(sl_frame_estimate_compute(&flat, &f, &err) == SL_E_BADINPUT);
}

/* The shared scans whose up axis is known (looked at in both frames; the CAD parts
 * fandisk and rocker_arm and the fossil usnm_1145291 have none). */
static void shared(const char *dir)
{
    static const struct { const char *file; char up; } known[] = {
        {"armadillo_86kf.ply", 'y'}, {"bun_zipper.ply", 'y'}, {"bun_zipper_res2.ply", 'y'},
        {"bun_zipper_res3.ply", 'y'}, {"bun_zipper_res4.ply", 'y'}, {"cow.ply", 'y'},
        {"dragon_100kf.ply", 'y'}, {"dragon_rangescan.ply", 'y'},
        {"dragon_vrip_res3.ply", 'y'}, {"happy_buddha_100kf.ply", 'y'},
        {"happy_buddha_rangescan.ply", 'y'}, {"horse.ply", 'z'}, {"igea.ply", 'y'},
        {"lee_perry_smith_head.ply", 'y'}, {"lucy_100kf.ply", 'y'}, {"nefertiti.ply", 'z'},
        {"nefertiti_igd_copy.ply", 'y'},
    };
    int right = 0, n = (int)(sizeof known / sizeof known[0]);
    printf("%-28s %4s %5s %10s %7s %7s  %s\n", "scan", "up", "est", "diagonal", "+y", "+z",
           "units");
    for (int i = 0; i < n; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, known[i].file);
        sl_mesh m;
        sl_mesh_init(&m);
        sl_error err;
        sl_error_init(&err);
        sl_frame_estimate f;
        int rc = sl_ply_read(path, NULL, &m, NULL, NULL, &err);
        if (rc == 0)
            rc = sl_frame_estimate_compute(&m, &f, &err);
        CHECK_MSG(rc == 0, "%s: %s", path, err.message);
        if (rc == 0) {
            right += f.up == known[i].up;
            printf("%-28s %4c %5c %10.4g %7.3f %7.3f  %s%s\n", known[i].file, known[i].up,
                   f.up, f.diagonal, f.support[2], f.support[4], f.units,
                   f.up == known[i].up ? "" : "   WRONG");
        }
        sl_mesh_release(&m);
    }
    printf("up right on %d of %d shared scans\n", right, n);
    CHECK_MSG(right == n, "%d of %d", right, n);
    /* nefertiti: the bust is 495 mm tall; the estimate must read millimetres. */
    char path[4096];
    snprintf(path, sizeof path, "%s/nefertiti.ply", dir);
    sl_mesh m;
    sl_mesh_init(&m);
    sl_error err;
    sl_error_init(&err);
    sl_frame_estimate f;
    if (sl_ply_read(path, NULL, &m, NULL, NULL, &err) == 0 &&
        sl_frame_estimate_compute(&m, &f, &err) == 0)
        CHECK(f.up == 'z' && !strcmp(f.units, "mm"));
    sl_mesh_release(&m);
}

int main(void)
{
    synthetic();
    const char *dir = getenv("SCANLOD_SHARED_DATA");
    if (dir && dir[0])
        shared(dir);
    else
        printf("no SCANLOD_SHARED_DATA: the shared scans' accuracy is not measured\n");
    return check_report();
}
