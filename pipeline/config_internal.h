/* What config.c (slots, files, overrides) and config_value.c (one value's text) share. */
#ifndef SCANLOD_PIPELINE_CONFIG_INTERNAL_H
#define SCANLOD_PIPELINE_CONFIG_INTERNAL_H

#include <stdint.h>

#include "pipeline/config.h"

#define CAUSE_MAX 512 /* bytes of a failure's cause */

/* Writes the cause of a failure into `cause` (CAUSE_MAX bytes); returns -1. */
int sl_config_because(char *cause, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* The canonical text of `raw` as a value of `o` (config.h: BOOL -> "true"/"false", INT ->
 * decimal, ...), malloc'd into *text, with the number in *i (INT, BOOL) or *d (DOUBLE);
 * `base` is the absolute directory a relative PATH resolves against. 0, or -1 with the
 * reason in `cause` (not a number, out of range, not a choice, out of memory...). */
int sl_config_parse_value(const sl_option *o, const char *raw, const char *base, char **text,
                          int64_t *i, double *d, char *cause);

/* The absolute directory holding `file` (as named: a symlinked file is not followed),
 * against `cwd`; malloc'd, or NULL with the reason in `cause`. */
char *sl_config_directory_of(const char *file, const char *cwd, char *cause);

#endif
