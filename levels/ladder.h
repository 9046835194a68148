/* The level ladder: which levels an item publishes, owned once for every method.
 *
 * A rung is one published level, asked for in one of three ways ([levels] section,
 * docs/levels.md):
 *   budgets    = thumb:2000,low:1%,...  a named level of at most N triangles, or of P % of
 *                                       the input's triangles;
 *   percents   = 20,40,...              a level "lodP" of P % of the input's triangles;
 *   expansions = 20,40,...              octree only: a level "kP" after P % of the LOD
 *                                       array's expansions (paper 1, Table 1), published as
 *                                       the paper cuts it.
 * Every method reads budgets and percents the same way: a count, or a share of the input's
 * triangles, turned into a count by sl_rung_triangles() and nowhere else. For a point set
 * (no input triangles) a share is of the finest level the method can make.
 *
 * A rung's name becomes its files' names (NAME.ply, NAME.glb) in the item's folder:
 * letters, digits, '.', '_' and '-', starting with a letter or digit; no two rungs alike.
 */
#ifndef SCANLOD_LEVELS_LADDER_H
#define SCANLOD_LEVELS_LADDER_H

#include <stdint.h>

#include "core/error.h"
#include "pipeline/config.h"

#define SL_LADDER_MAX 32
#define SL_LEVEL_NAME_SIZE 32

/* How a rung asks for its level. */
enum sl_rung_kind {
    SL_RUNG_TRIANGLES = 0,  /* at most `triangles` triangles */
    SL_RUNG_SHARE = 1,      /* `percent` % of the input's triangles */
    SL_RUNG_EXPANSIONS = 2, /* `percent` % of the octree's LOD array (paper 1, Table 1) */
};

typedef struct sl_rung {
    char name[SL_LEVEL_NAME_SIZE]; /* file stem */
    int kind;                      /* enum sl_rung_kind */
    double percent;                /* SHARE, EXPANSIONS: in [0, 100] */
    uint64_t triangles;            /* TRIANGLES: >= 1 */
} sl_rung;

typedef struct sl_ladder {
    int count;
    sl_rung rungs[SL_LADDER_MAX]; /* percents, then expansions, then budgets */
    int top_is_scan;              /* [levels] top = scan: a rung asking for the input's
                                     triangles or more is the scan itself (mesh inputs) */
    double oversample;            /* [levels] oversample: a method makes a rung's level at
                                     this many times its count, refine collapses the rest */
} sl_ladder;

/* The [levels] options, declared once here; every stage that builds or publishes levels
 * lists this table in its `shared_options` (pipeline/stage.h). */
extern const sl_option sl_ladder_options[];
/* The config sections a stage that reads the ladder lists in its `sections`. */
#define SL_LADDER_SECTION "levels"

/* The ladder of `cfg` ([levels]). SL_E_CONFIG naming the key's place (FILE:LINE or the
 * `-s`) on a malformed entry, a bad name, two rungs with one name, or too many rungs. */
int sl_ladder_read(const sl_config *cfg, sl_ladder *out, sl_error *err);

/* The same from the three list texts (tests and tools); `where` names them in errors. */
int sl_ladder_parse(const char *percents, const char *expansions, const char *budgets,
                    const char *where, sl_ladder *out, sl_error *err);

/* The triangles rung `r` asks for when the input (or, for a point set, the finest level)
 * has `input_triangles`: its count, or floor(P % of the input) but at least 1. An
 * EXPANSIONS rung asks for no count: 0. */
uint64_t sl_rung_triangles(const sl_rung *r, uint64_t input_triangles);

/* The triangles a method makes rung `r`'s level with: its count times the ladder's
 * oversample, at most the input's (a count above the input's stays what it is). */
uint64_t sl_rung_build_triangles(const sl_ladder *l, const sl_rung *r, uint64_t input_triangles);

/* 1 when `name` may name a level's files (see above). */
int sl_level_name_ok(const char *name);

#endif
