/* The collection manifest (docs/metadata.md): a museum's metadata beside its scans, one row
 * per item, as CSV (manifest.csv: a header row naming the columns) or JSON (manifest.json:
 * an array of objects, or an object whose keys are the files).
 *
 * Columns: file (the item id: the scan's path relative to [run] input, suffix kept),
 * title, accession, units (mm|cm|m|in|ft), up (y|z), credit, licence, description. Any
 * column but `file` may be missing or empty. A malformed manifest (a broken quote, a
 * column nobody knows, a unit that is not one, a file named twice, text that is not
 * UTF-8) is refused as a whole with SL_E_CONFIG naming "FILE:LINE": the run stops before
 * any work (exit 78), as for a bad config key, rather than publishing pages with some
 * rows silently dropped.
 *
 * Not thread-safe to load; lookups only read.
 */
#ifndef SCANLOD_PIPELINE_MANIFEST_H
#define SCANLOD_PIPELINE_MANIFEST_H

#include <stddef.h>

#include "core/error.h"
#include "core/hash.h"
#include "pipeline/stage.h"

#define SL_MANIFEST_MAX_BYTES (64u << 20) /* a catalogue of a million objects fits */
#define SL_MANIFEST_MAX_CELL (64u << 10)  /* one description: 64 KiB of text */

enum sl_manifest_field {
    SL_MF_FILE,
    SL_MF_TITLE,
    SL_MF_ACCESSION,
    SL_MF_UNITS,
    SL_MF_UP,
    SL_MF_CREDIT,
    SL_MF_LICENCE,
    SL_MF_DESCRIPTION,
    SL_MF_COUNT
};

typedef struct sl_manifest_row {
    char *field[SL_MF_COUNT]; /* malloc'd, "" when empty */
    int line;                 /* where the row starts in the file (1-based) */
    char where[80];           /* "NAME:LINE", NAME the file's base name */
    sl_item_metadata meta;    /* the fields as a stage reads them (pointers into field) */
    sl_hash hash;             /* of every field but `file` (what a stage reads) */
} sl_manifest_row;

typedef struct sl_manifest {
    char path[4096];
    sl_manifest_row *rows; /* sorted by file once loaded */
    size_t count, capacity;
} sl_manifest;

/* Reads and checks the manifest at `path` (by its suffix: .json is JSON, anything else
 * CSV); SL_E_CONFIG with err->file "PATH:LINE" when it is malformed, SL_E_STORAGE when it
 * cannot be read. On failure *m holds nothing (released). */
int sl_manifest_load(sl_manifest *m, const char *path, sl_error *err);
void sl_manifest_release(sl_manifest *m);

/* The row of item `item`, or NULL. */
const sl_manifest_row *sl_manifest_find(const sl_manifest *m, const char *item);

/* The column a header name means (any case, surrounding blanks ignored; "license" and
 * "accession number" are accepted too), or -1. */
int sl_manifest_column(const char *name, size_t len);

/* For the parsers (manifest_csv.c, manifest_json.c): adds one row whose cells are
 * `cells[c]` (length `lens[c]`; NULL = no such cell) for each column c, starting at
 * `line`; checks and copies them. SL_E_CONFIG naming the line when a cell is wrong. */
int sl_manifest_add_row(sl_manifest *m, const char *const cells[SL_MF_COUNT],
                        const size_t lens[SL_MF_COUNT], int line, sl_error *err);
/* A config error about line `line` of the manifest: SL_E_CONFIG, err->file "PATH:LINE". */
int sl_manifest_error(const sl_manifest *m, int line, sl_error *err, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* manifest.c: sorts the rows for lookups, refuses a file named twice (which row would be
 * meant?), and gives each row its view for stages and its hash. */
int sl_manifest_finish_rows(sl_manifest *m, sl_error *err);
/* manifest_csv.c, manifest_json.c: the text cut into rows (sl_manifest_add_row). */
int sl_manifest_parse_csv(sl_manifest *m, const char *text, size_t size, sl_error *err);
int sl_manifest_parse_json(sl_manifest *m, const char *text, size_t size, sl_error *err);

#endif
