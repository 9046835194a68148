/* -o FILE checked up front (cli_output.h). Before, `extract ... -o /nonexistent/dir/o.ply`
 * read the whole model, cut the level and then exited 75 naming a temp file
 * (".o.ply.HOST.PID.0.tmp: create failed"), while 75 means "try again": an interrupt,
 * memory or a full disk (issue 34 item 6). */
#include "cli/cli_output.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "core/error.h"

int sl_cli_check_output(const char *command, const char *flag, const char *path)
{
    char dir[PATH_MAX];
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else
        snprintf(dir, sizeof dir, "%.*s", slash == path ? 1 : (int)(slash - path), path);
    struct stat st;
    const char *why = NULL;
    if (!path[0] || (slash && !slash[1]))
        why = "names no file";
    else if (stat(dir, &st) != 0)
        why = errno == ENOENT ? "its folder does not exist" : strerror(errno);
    else if (!S_ISDIR(st.st_mode))
        why = "its folder is not a folder";
    if (!why)
        return 0;
    fprintf(stderr, "scanlod %s: %s %s: %s (%s)\n", command, flag, path, why, dir);
    return SL_EXIT_USAGE;
}
