/* A scan's frame when nobody says it (docs/metadata.md, "Frames"): which axis is up and
 * what unit the coordinates are in, estimated from the geometry alone. Used only when
 * neither the collection manifest, the config nor the file gives them; the estimate is
 * flagged wherever it is shown.
 *
 * Up: a museum object rests on a base. For each of the six axis directions d, the
 * footprint of the scan standing on d's lowest end is the 2D convex hull of its points
 * within FRAME_SLAB (2 %) of the extent from that end, projected along d, as a share of
 * the bounding box's cross-section there (`support`). Up is +y or +z, whichever has the
 * larger support (y on a tie: glTF's convention); a side (x) or an upside-down direction
 * that supports it better is reported, not chosen (the export cannot rotate by it).
 * Measured on the shared scans with a known up: 17 of 17 right (docs/metadata.md).
 *
 * Units: from the bounding-box diagonal D, for museum objects 2 cm to 20 m across: D >= 20
 * reads as millimetres (20 mm to 20 m), below as metres (2 cm to 20 m). Centimetres and
 * inches overlap both ranges, so they are never guessed.
 */
#ifndef SCANLOD_GEOMETRY_FRAME_ESTIMATE_H
#define SCANLOD_GEOMETRY_FRAME_ESTIMATE_H

#include "core/error.h"
#include "geometry/mesh.h"

#define SL_FRAME_SLAB 0.02          /* the footprint's depth, a share of the extent */
#define SL_FRAME_MM_DIAGONAL 20.0   /* a diagonal at least this reads as millimetres */

typedef struct sl_frame_estimate {
    char up;            /* 'y' or 'z' */
    char units[4];      /* "mm" or "m" */
    double diagonal;    /* of the bounding box, in the file's units */
    /* Footprint share per direction: +x, -x, +y, -y, +z, -z (the lowest end of the
     * direction is the base: +z = standing on its smallest z). */
    double support[6];
    int best;           /* the direction with the largest support, 0..5 */
} sl_frame_estimate;

/* Estimates from `m`'s points (a mesh's vertices or a point set); SL_E_BADINPUT when it
 * has no finite extent to judge, SL_E_NOMEM. Deterministic. */
int sl_frame_estimate_compute(const sl_mesh *m, sl_frame_estimate *out, sl_error *err);

/* "+y" etc. for direction index 0..5. */
const char *sl_frame_direction_name(int direction);

#endif
