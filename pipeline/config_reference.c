/* The commented reference file (config/reference.ini), generated from the option tables
 * so the documentation of a key cannot drift from its declaration (see config.h). The
 * layout follows redis.conf: a header on the format, then per section every option as
 * comment lines (help, type, range, "required") followed by `key = default`.
 */
#include "pipeline/config.h"

#include <string.h>

#define REFERENCE_WIDTH 88

static const char reference_header[] =
    "# scanlod configuration reference\n"
    "#\n"
    "# Every option scanlod reads, with its meaning, type, range and default. Generated\n"
    "# from the option tables by `scanlod config-reference`; do not edit by hand (a test\n"
    "# keeps this file equal to that output). Copy the keys you need into a collection\n"
    "# config; everything you leave out takes the default shown here.\n"
    "#\n"
    "# Format: INI. `[section]` headers, `key = value` lines, comments on lines of their\n"
    "# own starting with `;` or `#`, or after a value following ` ;`. Indentation is\n"
    "# ignored and a value never continues on the next line. Lines longer than libinih's\n"
    "# buffer (198 characters in Debian's build) are refused: give such values with -s.\n"
    "#\n"
    "# Validation: an unknown section or key, a key given twice, a value of the wrong type\n"
    "# or out of range is an error naming file:line, and scanlod exits with 78 before\n"
    "# doing any work. Options marked `required` have no default.\n"
    "#\n"
    "# Paths: a relative path is relative to the folder of the file it is written in;\n"
    "# given with -s, or as a default, relative to the current directory.\n"
    "#\n"
    "# Overrides: `-s section.key=value` on the command line (repeatable) is applied after\n"
    "# the file and validated the same way; the last one for a key wins.\n"
    "#\n"
    "# Resume: each stage's results are keyed on the values of its own section only, so\n"
    "# changing a key reruns that stage and those after it, and nothing else.\n";

/* Help text as `# ` comment lines wrapped at REFERENCE_WIDTH; "\n" in it breaks a line. */
static void write_wrapped(FILE *out, const char *text)
{
    int col = 0;
    for (const char *p = text; *p;) {
        if (*p == ' ' || *p == '\n') {
            if (*p++ == '\n' && col)
                fputc('\n', out), col = 0;
            continue;
        }
        int n = (int)strcspn(p, " \n");
        if (col && col + 1 + n > REFERENCE_WIDTH)
            fputc('\n', out), col = 0;
        col += fprintf(out, col ? " %.*s" : "# %.*s", n, p);
        p += n;
    }
    if (col)
        fputc('\n', out);
}

static void write_type(FILE *out, const sl_option *o)
{
    static const char *const names[] = {
        [SL_OPT_BOOL] = "bool (true/false, yes/no, on/off, 1/0)",
        [SL_OPT_INT] = "integer",
        [SL_OPT_DOUBLE] = "number",
        [SL_OPT_STRING] = "text",
        [SL_OPT_PATH] = "path",
        [SL_OPT_ENUM] = "one of",
        [SL_OPT_LIST] = "comma-separated list",
    };
    fprintf(out, "# type: %s", names[o->type]);
    if (o->type == SL_OPT_ENUM)
        fprintf(out, " %s", o->choices ? o->choices : "");
    if (o->type == SL_OPT_LIST && o->choices)
        fprintf(out, " of %s", o->choices);
    int ranged = o->type == SL_OPT_INT || o->type == SL_OPT_DOUBLE || o->type == SL_OPT_LIST;
    if (ranged && o->min < o->max)
        fprintf(out, ", %srange [%.17g, %.17g]", o->type == SL_OPT_LIST ? "each number in " : "",
                o->min, o->max);
    fputs(o->default_value ? "\n" : "; required\n", out);
}

static void write_option(FILE *out, const sl_option *o)
{
    const char *d = o->default_value;
    fputc('\n', out);
    write_wrapped(out, o->help ? o->help : "");
    write_type(out, o);
    if (!d) {
        fprintf(out, "; %s =\n", o->name);
    } else if (o->type == SL_OPT_PATH && d[0] != '/') {
        /* Written here it would resolve against this file's folder, not the current
         * directory as the default does: so it stays a comment. */
        fprintf(out, "# default: %s, in the current directory\n; %s = %s\n", d, o->name, d);
    } else {
        fprintf(out, "%s =%s%s\n", o->name, d[0] ? " " : "", d);
    }
}

/* Has an option before `o` (walking the tables in order) the same section? */
static int section_seen_before(const sl_option *const *tables, const sl_option *o)
{
    for (const sl_option *const *t = tables; *t; t++)
        for (const sl_option *p = *t; p->name; p++) {
            if (p == o)
                return 0;
            if (!strcmp(p->section, o->section))
                return 1;
        }
    return 0;
}

void sl_config_write_reference(FILE *out, const sl_option *const *tables)
{
    fputs(reference_header, out);
    for (const sl_option *const *t = tables; t && *t; t++)
        for (const sl_option *o = *t; o->name; o++) {
            if (section_seen_before(tables, o))
                continue;
            fprintf(out, "\n[%s]\n", o->section);
            for (const sl_option *const *u = t; *u; u++)
                for (const sl_option *q = u == t ? o : *u; q->name; q++)
                    if (!strcmp(q->section, o->section))
                        write_option(out, q);
        }
}
