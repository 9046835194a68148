/* `scanlod simplify`'s methods (cmd_simplify.c): one entry per paper's method, each in its
 * own file (simplify_segment.c: paper 3, simplify_cluster.c: paper 2). Internal to cli/. */
#ifndef SCANLOD_CLI_SIMPLIFY_H
#define SCANLOD_CLI_SIMPLIFY_H

#include <stdint.h>

#include "core/error.h"
#include "core/json.h"
#include "core/progress.h"
#include "stages/range/range.h"

/* What every method gets: the cleaned mesh and the size asked for. */
typedef struct simplify_job {
    const char *input;   /* for messages */
    const sl_pointset *mesh;
    uint64_t triangles;  /* > 0: budget */
    double ratio;        /* > 0: budget as a fraction of the input's triangles */
    double max_error;    /* > 0: bound, fraction of the bounding-box diagonal */
    int strict;          /* refuse open boundaries, non-manifold edges, degenerate faces */
    int has_output;      /* -o was given (options that write beside it need one) */
} simplify_job;

/* A mesh with its own vertices, written beside the output (OUT_1.ply, ...). */
typedef struct simplify_extra {
    uint64_t vertex_count, triangle_count;
    const float *positions;
    const uint32_t *source;    /* the cleaned mesh's vertex each one is (its colour) */
    const uint32_t *triangles;
} simplify_extra;

/* What a method gives back: triangles in the cleaned mesh's points, and its figures. */
typedef struct simplify_output {
    uint64_t triangle_count;
    const uint32_t *triangles;
    uint32_t extra_count;
    simplify_extra *extras;
    const uint32_t *segment_of_input; /* optional: a segment id per input triangle */
    uint32_t segment_count;
    sl_json figures;           /* the method's own figures (an open object's members) */
    void *state;               /* the method's, freed by its release */
} simplify_output;

typedef struct simplify_method {
    const char *name;
    const char *options_help;
    void (*reset)(void); /* the method's options to their defaults */
    /* Parses argv[*i] (and its value) if it is one of the method's options: 1 taken,
     * 0 not the method's, -1 a bad value (message printed). */
    int (*parse)(int argc, char **argv, int *i);
    /* After parsing, with the job's common options: 0, or a usage message printed and -1. */
    int (*check)(const simplify_job *job);
    int (*run)(const simplify_job *job, simplify_output *out, sl_progress *progress,
               sl_error *err);
    void (*release)(simplify_output *out);
} simplify_method;

extern const simplify_method sl_simplify_segment, sl_simplify_cluster;

double sl_simplify_seconds_now(void);
/* A finite number from text: 0, or -1. */
int sl_simplify_parse_double(const char *text, double *out);
/* A whole number in [lo, hi] from argv[++*i]; -1 (message printed) otherwise. */
int sl_simplify_parse_count(int argc, char **argv, int *i, double lo, double hi, double *out);

#endif
