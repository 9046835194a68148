/* Fixtures shared by the stage tests: a scan through the range stage, and byte equality
 * of two artifact files by the engine's own hash. */
#ifndef SCANLOD_TESTS_STAGE_FIXTURES_H
#define SCANLOD_TESTS_STAGE_FIXTURES_H

#include <sys/stat.h>

#include "core/hash.h"
#include "core/json.h"
#include "stages/range/range.h"

/* points.slpts of `ply` (range stage defaults, 2 threads) into dir. */
static inline int fixture_range_points(const char *ply, const char *dir)
{
    sl_range_config rcfg = sl_range_default_config();
    sl_json j;
    sl_json_init(&j, 0);
    sl_json_object_begin(&j, NULL);
    sl_stage_io io = {.item = "item", .source_path = ply, .out_dir = dir, .report = &j,
                      .threads = 2};
    sl_error err;
    sl_error_init(&err);
    mkdir(dir, 0755);
    int rc = sl_range_stage.run(&rcfg, &io, &err);
    sl_json_release(&j);
    return rc;
}

/* Same size (> 0) and XXH3-128 (the engine's own output hash). */
static inline int fixture_same_file(const char *a, const char *b)
{
    sl_hash ha, hb;
    uint64_t na = 0, nb = 0;
    sl_error err;
    sl_error_init(&err);
    return sl_hash_file(a, &ha, &na, &err) == SL_OK && sl_hash_file(b, &hb, &nb, &err) == SL_OK &&
           na == nb && na > 0 && sl_hash_equal(ha, hb);
}

#endif
