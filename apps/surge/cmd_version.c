/* surge version: the program and the machine, as every run's params.ini records them. */
#include "cli.h"

#include <stdio.h>

#include "surge/platform.h"

static const char *usage_version =
    "usage: surge version\n\nPrints the program (its git commit, compiler and the vector extensions it was built for)\n"
    "and the machine (CPU, processors, AVX2 and AVX-512), as every run's params.ini records them.\n";

int command_version(int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        fputs(usage_version, stdout);
        return EXIT_OK;
    }
    if (argc > 0) {
        fprintf(stderr, "surge: version takes no arguments\n");
        return EXIT_USAGE;
    }
    char machine[512];
    surge_machine_description(machine, sizeof machine);
    printf("program: %s\nmachine: %s\n", surge_build_description(), machine);
    return EXIT_OK;
}
