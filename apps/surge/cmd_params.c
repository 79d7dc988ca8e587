/* surge params: the parameter reference. */
#include "cli.h"

#include <stdio.h>

static const char *usage_params =
    "usage: surge params\n\nPrints the parameter reference (the source of docs/parameters.md).\n";

int command_params(int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        fputs(usage_params, stdout);
        return EXIT_OK;
    }
    if (argc > 0) {
        fprintf(stderr, "surge: params takes no arguments\n");
        return EXIT_USAGE;
    }
    surge_params_write_reference(stdout);
    return EXIT_OK;
}
