/* The scanlod subcommands (cli/main.c dispatches). run, worker, status, verify and plan are one
 * front end of the engine and share cli/cmd_run.c; every other command has its own
 * cli/cmd_<name>.c.
 * Each takes argv after the subcommand name (argv[0] is the subcommand) and returns a
 * process exit code (enum sl_exit). */
#ifndef SCANLOD_CLI_COMMANDS_H
#define SCANLOD_CLI_COMMANDS_H

int sl_cmd_run(int argc, char **argv);     /* whole collection, resumable */
int sl_cmd_worker(int argc, char **argv);  /* one worker on the shared queues */
int sl_cmd_status(int argc, char **argv);  /* per-stage queue counts */
int sl_cmd_verify(int argc, char **argv);  /* every commit record matches its files */
int sl_cmd_plan(int argc, char **argv);    /* pre-flight estimate per item */
int sl_cmd_inspect(int argc, char **argv); /* what a PLY or .slod holds, validated */
int sl_cmd_compare(int argc, char **argv); /* fidelity: Hausdorff/RMS between meshes */
int sl_cmd_extract(int argc, char **argv); /* any LOD from a model, O(m) */
int sl_cmd_simplify(int argc, char **argv); /* one mesh, papers 2/3 */
int sl_cmd_config_reference(int argc, char **argv); /* prints config/reference.ini */

#endif
