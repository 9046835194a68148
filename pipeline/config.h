/* Configuration: INI files (libinih) + `-s section.key=value` overrides.
 *
 * Every option is declared once, in a table next to the code that reads it (the engine's
 * [run]/[queue] tables in pipeline/engine_options.c, each stage's table in its folder):
 * name, type, default, range, help. sl_config_load() validates everything in one place:
 * an unknown section or key, a value of the wrong type or out of range gives one error
 * "FILE:LINE: ..." (SL_E_CONFIG, exit 78). The reference file config/reference.ini is
 * generated from the same tables (`scanlod config-reference`) and a test keeps it equal.
 *
 * Paths: a relative PATH value in a file is relative to that file's directory; in a
 * `-s` override or a default, relative to the current directory. Stored absolute,
 * without "." segments or repeated slashes; ".." is kept (symlinks resolve as the
 * kernel does).
 *
 * Errors: on failure sl_error has code SL_E_CONFIG, `file` holds the place
 * ("FILE:LINE", "-s section.key=value", or FILE for a missing required option) and
 * `message` the rest, so sl_error_format() prints the one line a user sees, e.g.
 * "site.ini:12: [range] k: 0 is out of range [1, 64]". A default that fails its own
 * validation is a bug in a table: SL_E_INTERNAL.
 *
 * Values are canonicalised before they are stored and hashed: BOOL -> "true"/"false",
 * INT -> decimal, DOUBLE -> "%.17g", LIST -> words trimmed and joined by ",", PATH ->
 * absolute; so `yes` vs `on` or `8` vs `08` is not a change.
 *
 * The hash a stage is keyed on covers exactly the options of its own section, by their
 * resolved values (defaults included), so a comment or a key of another stage never
 * triggers recompute.
 */
#ifndef SCANLOD_PIPELINE_CONFIG_H
#define SCANLOD_PIPELINE_CONFIG_H

#include <stdint.h>
#include <stdio.h>

#include "core/error.h"

typedef enum sl_option_type {
    SL_OPT_BOOL,   /* true/false, yes/no, on/off, 1/0 */
    SL_OPT_INT,    /* 64-bit signed, range [min, max] */
    SL_OPT_DOUBLE, /* finite, range [min, max] */
    SL_OPT_STRING,
    SL_OPT_PATH,   /* resolved to an absolute path */
    SL_OPT_ENUM,   /* one of `choices` ("a|b|c") */
    SL_OPT_LIST    /* comma-separated words, each checked like an INT/DOUBLE range if
                      min < max, else one of `choices` if given, else free text */
} sl_option_type;

typedef struct sl_option {
    const char *section;
    const char *name;
    sl_option_type type;
    const char *default_value; /* text; NULL = required (no default) */
    double min, max;           /* INT/DOUBLE/LIST ranges, inclusive; checked only if
                                  min < max (0, 0 = unbounded) */
    const char *choices;       /* ENUM, and LIST elements when set */
    const char *help;          /* one or more sentences; shown in reference.ini */
} sl_option;

/* A table ends with an entry whose name is NULL. */
#define SL_OPTION_END {NULL, NULL, SL_OPT_STRING, NULL, 0, 0, NULL, NULL}

typedef struct sl_config sl_config;

/* `tables` is a NULL-terminated array of option tables; they must outlive `*out` (the
 * config points into them). `path` may be NULL (defaults and overrides only; required
 * options then fail). `overrides` are "section.key=value" texts (the `-s` arguments),
 * applied after the file in order, so a later one wins. On error *out is NULL. */
int sl_config_load(sl_config **out, const sl_option *const *tables, const char *path,
                   const char *const *overrides, int override_count, sl_error *err);
void sl_config_free(sl_config *cfg);

/* Resolved values; the option must exist in the tables and have the getter's type
 * (else abort: a programming bug). sl_config_string works for every type and returns
 * the canonical text (LIST: "a,b,c"). */
const char *sl_config_string(const sl_config *cfg, const char *section, const char *name);
int64_t sl_config_int(const sl_config *cfg, const char *section, const char *name);
double sl_config_double(const sl_config *cfg, const char *section, const char *name);
int sl_config_bool(const sl_config *cfg, const char *section, const char *name);

/* Hash of the resolved values of every option in `section` (canonical text, xxh3-64):
 * XXH3-64 of the lines "section.name=value\n" in table order. A section without
 * options hashes the empty text. */
uint64_t sl_config_section_hash(const sl_config *cfg, const char *section);
/* The config file it came from ("" if none). */
const char *sl_config_path(const sl_config *cfg);
/* Where the value of [section] name came from, for an error about it, also one that only
 * a check across keys finds (two budgets with one name, lod_percents = 20,20, a budget
 * named ../x): into `buf`, "FILE:LINE" when the config file set it ("museum.ini:12",
 * FILE as given to sl_config_load), "-s section.name" when an override did (the last
 * one for the key wins, as for the value), or FILE alone when the key is at its default
 * ("(no config file)" without one). Returns which of these it is. The option must be
 * declared (else abort: a bug, as for the getters). Thread-safe (reads only). */
typedef enum sl_config_origin_kind {
    SL_CONFIG_FROM_FILE = 1,
    SL_CONFIG_FROM_OVERRIDE,
    SL_CONFIG_FROM_DEFAULT
} sl_config_origin_kind;
sl_config_origin_kind sl_config_origin(const sl_config *cfg, const char *section,
                                       const char *name, char *buf, size_t size);
/* The same, its kind dropped (older name). */
void sl_config_where(const sl_config *cfg, const char *section, const char *name, char *buf,
                     size_t size);
/* A config error about the value of [section] name found by a check across keys:
 * SL_E_CONFIG with the key's origin as the file and "[section] name: " before the
 * message, so sl_error_format prints the one line a user sees, e.g.
 * "museum.ini:12: [export] budgets: two levels named thumb" or
 * "-s export.budgets: [export] budgets: ...". Returns SL_E_CONFIG. */
int sl_config_key_error(sl_error *err, const sl_config *cfg, const char *section,
                        const char *name, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

/* Writes the commented reference file for `tables`: every option with its help, type,
 * range and default, grouped by section in order of first appearance. Deterministic. */
void sl_config_write_reference(FILE *out, const sl_option *const *tables);

/* Every option table of the program ([run], [queue], then each of `stages`' in order),
 * NULL-terminated, in `tables` (room for SL_MAX_OPTION_TABLES + 1). Defined by the engine
 * (pipeline/engine_options.c); `stages` is a NULL-terminated sl_stage list. */
#define SL_MAX_OPTION_TABLES 35
struct sl_stage;
void sl_all_option_tables(const struct sl_stage *const *stages,
                          const sl_option *tables[SL_MAX_OPTION_TABLES + 1]);

#endif
