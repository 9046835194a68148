/* What a scan's geometry says about the octree its run will build, for `scanlod plan`'s
 * cost model (cli/plan.c): the model's memory and time lines are fitted on surfaces with
 * about 1.56 samples per triangle (the calibration tori; real scans 1.2-2.2), and a scan
 * of thin slivers or a triangle soup needs many times that (issue 34 item 5). */
#ifndef SCANLOD_CLI_PLAN_SHAPE_H
#define SCANLOD_CLI_PLAN_SHAPE_H

#include <stdint.h>

#include "formats/scan_read.h"
#include "pipeline/config.h"
#include "pipeline/stage.h"

/* Samples per input triangle of the calibration tori (scripts/bench/gen_surface). */
#define SL_PLAN_SAMPLES_PER_TRIANGLE 1.56
/* Meshes above this many triangles are planned from their header alone: reading one costs
 * the plan as much memory as the range stage (and a big scan of normal triangles is what
 * the lines were fitted on). */
#define SL_PLAN_SHAPE_MAX_TRIANGLES 2000000u

typedef struct sl_plan_shape {
    int read;          /* 1: the estimate comes from the geometry; 0: header only */
    double leaf;       /* the leaf size the samples stage will choose (world units) */
    double samples;    /* expected samples (grid vertices of the band) */
    double ratio;      /* samples / (SL_PLAN_SAMPLES_PER_TRIANGLE * triangles); 1 unread */
    double scattered;  /* share of the samples from open borders and small pieces (0..1):
                          they cost the later stages more per sample (sign changes) */
} sl_plan_shape;

/* The shape of the mesh at `path` (header `info`; the method's `count` stages, which read
 * `cfg`, must include range and samples): read and measured when it has triangles, at most
 * SL_PLAN_SHAPE_MAX_TRIANGLES; else (a point cloud, a huge or unreadable file, another
 * method) out->read = 0 and ratio 1. Takes about the range stage's time and memory. */
void sl_plan_shape_of(const char *path, const sl_scan_info *info, const sl_stage *const *stages,
                      int count, const sl_config *cfg, sl_plan_shape *out);

#endif
