/* `scanlod config-reference`: prints the commented reference of every option
 * (config/reference.ini is this output; a test keeps the two equal). */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "cli/commands.h"
#include "core/error.h"
#include "pipeline/config.h"
#include "stages/registry.h"

static const char usage[] =
    "usage: scanlod config-reference\n"
    "\n"
    "Prints every config option with its help, type, range and default, as a commented\n"
    "INI file (the content of config/reference.ini) on stdout.\n";

int sl_cmd_config_reference(int argc, char **argv)
{
    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        fputs(usage, stdout);
        return SL_EXIT_OK;
    }
    if (argc > 1) {
        fprintf(stderr, "scanlod config-reference: unexpected argument '%s'\n%s", argv[1], usage);
        return SL_EXIT_USAGE;
    }
    const sl_option *tables[SL_MAX_OPTION_TABLES + 1];
    sl_all_option_tables(sl_stage_registry(), tables);
    sl_config_write_reference(stdout, tables);
    if (fflush(stdout) != 0 || ferror(stdout)) { /* e.g. a full disk behind `> file` */
        fprintf(stderr, "scanlod config-reference: writing stdout: %s\n", strerror(errno));
        return SL_EXIT_IOERR;
    }
    return SL_EXIT_OK;
}
