/* The segment stage entry (placeholder until the stage is written). */
#include "stages/segment/segment.h"

const sl_stage sl_segment_stage = {
    .name = "segment",
};
