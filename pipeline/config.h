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
 * `-s` override, relative to the current directory.
 *
 * The hash a stage is keyed on covers exactly the options of its own section, by their
 * resolved values (defaults included), so a comment or a key of another stage never
 * triggers recompute.
 */
#ifndef SCANLOD_PIPELINE_CONFIG_H
#define SCANLOD_PIPELINE_CONFIG_H

#include <stdint.h>
#include <stdio.h>

#include "pipeline/error.h"

typedef enum sl_option_type {
    SL_OPT_BOOL,   /* true/false, yes/no, on/off, 1/0 */
    SL_OPT_INT,    /* 64-bit signed, range [min, max] */
    SL_OPT_DOUBLE, /* finite, range [min, max] */
    SL_OPT_STRING,
    SL_OPT_PATH,   /* resolved to an absolute path */
    SL_OPT_ENUM,   /* one of `choices` ("a|b|c") */
    SL_OPT_LIST    /* comma-separated words, each checked like an INT/DOUBLE range if
                      min < max, else free text */
} sl_option_type;

typedef struct sl_option {
    const char *section;
    const char *name;
    sl_option_type type;
    const char *default_value; /* text; NULL = required (no default) */
    double min, max;           /* INT/DOUBLE/LIST ranges, inclusive */
    const char *choices;       /* ENUM only */
    const char *help;          /* one or more sentences; shown in reference.ini */
} sl_option;

/* A table ends with an entry whose name is NULL. */
#define SL_OPTION_END {NULL, NULL, SL_OPT_STRING, NULL, 0, 0, NULL, NULL}

typedef struct sl_config sl_config;

/* `tables` is a NULL-terminated array of option tables. `path` may be NULL (defaults and
 * overrides only; required options then fail). */
int sl_config_load(sl_config **out, const sl_option *const *tables, const char *path,
                   const char *const *overrides, int override_count, sl_error *err);
void sl_config_free(sl_config *cfg);

/* Resolved values; the option must exist in the tables (else abort: a programming bug). */
const char *sl_config_string(const sl_config *cfg, const char *section, const char *name);
int64_t sl_config_int(const sl_config *cfg, const char *section, const char *name);
double sl_config_double(const sl_config *cfg, const char *section, const char *name);
int sl_config_bool(const sl_config *cfg, const char *section, const char *name);

/* Hash of the resolved values of every option in `section` (canonical text, xxh3-64). */
uint64_t sl_config_section_hash(const sl_config *cfg, const char *section);
/* The config file it came from ("" if none). */
const char *sl_config_path(const sl_config *cfg);

/* Writes the commented reference file for `tables`. */
void sl_config_write_reference(FILE *out, const sl_option *const *tables);

#endif
