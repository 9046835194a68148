/* scanlod: scan archives to level-of-detail models. Dispatches to cli/cmd_*.c. */
#include <stdio.h>
#include <string.h>

#include "cli/commands.h"
#include "core/error.h"
#include "shim/cxx_runtime.h"
#include "shim/oiio_shim.h"

typedef struct command {
    const char *name;
    int (*fn)(int argc, char **argv);
    const char *summary;
} command;

static const command commands[] = {
    {"run", sl_cmd_run, "convert a whole collection, resumably"},
    {"worker", sl_cmd_worker, "one worker pulling from the shared queues (cluster)"},
    {"status", sl_cmd_status, "per stage: ready / claimed / done / failed / quarantined"},
    {"plan", sl_cmd_plan, "before a run: expected peak memory, time and disk per item"},
    {"verify", sl_cmd_verify, "check every commit record against its files"},
    {"inspect", sl_cmd_inspect, "what a file holds, validated"},
    {"extract", sl_cmd_extract, "any level of detail from a built model (.slod), O(m)"},
    {"simplify", sl_cmd_simplify, "one mesh simplified by a paper's method (segment: paper 3, cluster: paper 2)"},
    {"compare", sl_cmd_compare, "Hausdorff and RMS distance between two meshes"},
    {"config-reference", sl_cmd_config_reference, "print the commented reference config"},
};

static void usage(FILE *out)
{
    fprintf(out, "usage: scanlod [--version] [--help] COMMAND [ARGS]\n\ncommands:\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(out, "  %-17s %s\n", commands[i].name, commands[i].summary);
    fprintf(out, "\n`scanlod COMMAND --help` for each; docs/ for the design.\n");
}

int main(int argc, char **argv)
{
    sl_cxx_terminate_install(); /* an uncaught std::bad_alloc is out of memory (exit 75) */
    if (argc < 2) {
        usage(stderr);
        return SL_EXIT_USAGE;
    }
    if (!strcmp(argv[1], "--version") || !strcmp(argv[1], "version")) {
        printf("scanlod %s\n", SCANLOD_VERSION);
        /* Loads the image module (shim/oiio_loader.c), which nothing else does up front:
         * where it came from, or that images are unavailable. */
        const char *module, *version, *why = sl_oiio_module_info(&module, &version);
        if (!why)
            printf("images: OpenImageIO %s (%s)\n", version, module);
        else
            printf("images: unavailable (textures, thumbnails and image files fail): the "
                   "OpenImageIO module scanlod-oiio.so did not load: %s\n", why);
        return SL_EXIT_OK;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(stdout);
        return SL_EXIT_OK;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name))
            return commands[i].fn(argc - 1, argv + 1);
    fprintf(stderr, "scanlod: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return SL_EXIT_USAGE;
}
