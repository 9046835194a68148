/* The output file a command is told to write (-o FILE), checked before anything is read. */
#ifndef SCANLOD_CLI_CLI_OUTPUT_H
#define SCANLOD_CLI_CLI_OUTPUT_H

/* Whether `path`'s folder exists and is a folder, so the file can be created there. When
 * not, one line "scanlod COMMAND: FLAG PATH: ..." naming the folder and SL_EXIT_USAGE (a
 * command line naming a place that is not there; docs/exit-codes.md), before any input
 * is read; else 0. Writing may still fail later with its own class: a full disk 75, a
 * read-only or foreign folder 74. */
int sl_cli_check_output(const char *command, const char *flag, const char *path);

#endif
