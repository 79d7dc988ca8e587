/* surge: the command-line program. Wires the solver (sim/) to its outputs, the state publisher and the control
 * socket (stream/) and the renderer (render/); each command is in its own file (cmd_*.c). */
#define _XOPEN_SOURCE 700 /* POSIX 2008: setenv, execv */
#include "cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

static const char *usage_main =
    "usage: surge COMMAND [options]\n"
    "\n"
    "A 2D weakly-compressible SPH simulator of viscous debris-flow surges.\n"
    "\n"
    "commands:\n"
    "  run [CASE]        run a case file (no CASE: the default demo scene, cases/demo.ini); can publish its\n"
    "                    state over ZeroMQ and take commands on a control socket\n"
    "  render RUN_DIR    render a finished run's snapshots as PNG frames and/or a movie\n"
    "  check CASE        validate a case file without running it\n"
    "  params            print the parameter reference (Markdown)\n"
    "  version           print the program (its commit, compiler and vector extensions) and the machine\n"
    "  keygen NAME       make a CURVE key pair for the live links: NAME.key (secret) and NAME.pub\n"
    "\n"
    "'surge COMMAND --help' describes each command.\n"
    "exit status: 0 done, 1 stopped by the health monitor, 2 bad input, 3 output error, 4 interrupted\n";

/* While they wait at a barrier, libgomp's threads spin (OMP_WAIT_POLICY and GOMP_SPINCOUNT unset: about 300,000
 * times before they sleep), which on cores shared with other work starves the thread the others wait for: a run that
 * takes minutes can take hours. libgomp reads the variables before main, so a run with neither set executes itself
 * again, once, with OMP_WAIT_POLICY=PASSIVE (docs/performance.md, "Waiting threads", measures the choices). */
static void prefer_passive_wait(char **argv)
{
    if (getenv("OMP_WAIT_POLICY") || getenv("GOMP_SPINCOUNT") || setenv("OMP_WAIT_POLICY", "PASSIVE", 1) != 0)
        return;
    execv("/proc/self/exe", argv);
    unsetenv("OMP_WAIT_POLICY"); /* no /proc: go on with libgomp's default */
}

/* The soft limit on open files up to the hard one: each connection to the control or publisher socket takes a
 * file descriptor, and a table filled by idle connections (1,024 on many machines) made the next snapshot write
 * fail. */
static void raise_open_file_limit(void)
{
    struct rlimit limit;
    if (getrlimit(RLIMIT_NOFILE, &limit) == 0 && limit.rlim_cur < limit.rlim_max) {
        limit.rlim_cur = limit.rlim_max;
        setrlimit(RLIMIT_NOFILE, &limit);
    }
}

static const struct {
    const char *name;
    int (*run)(int argc, char **argv);
} commands[] = {
    {"run", command_run},         {"check", command_check},     {"render", command_render},
    {"keygen", command_keygen},   {"params", command_params},   {"version", command_version},
    {"--version", command_version},
};

int main(int argc, char **argv)
{
    if (argc >= 2 && (!strcmp(argv[1], "run") || !strcmp(argv[1], "render")))
        prefer_passive_wait(argv);
    raise_open_file_limit();
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        fputs(usage_main, argc < 2 ? stderr : stdout);
        return argc < 2 ? EXIT_USAGE : EXIT_OK;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name))
            return commands[i].run(argc - 2, argv + 2);
    fprintf(stderr, "surge: unknown command '%s'\n%s", argv[1], usage_main);
    return EXIT_USAGE;
}
