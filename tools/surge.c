/* surge: the command-line program. Wires the solver (sim/) to its outputs; later the stream and renderer. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <limits.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "surge/params.h"
#include "surge/run.h"
#include "surge/sim.h"

extern const char surge_default_case_text[]; /* cases/demo.ini, embedded at build time */

enum { EXIT_OK = 0, EXIT_UNHEALTHY = 1, EXIT_USAGE = 2, EXIT_IO = 3, EXIT_INTERRUPTED = 4 };

static volatile sig_atomic_t stop_requested = 0;
static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static const char *usage_main =
    "usage: surge COMMAND [options]\n"
    "\n"
    "A 2D weakly-compressible SPH simulator of viscous debris-flow surges.\n"
    "\n"
    "commands:\n"
    "  run [CASE]        run a case file (no CASE: the default demo scene, cases/demo.ini)\n"
    "  check CASE        validate a case file without running it\n"
    "  params            print the parameter reference (Markdown)\n"
    "\n"
    "'surge COMMAND --help' describes each command.\n"
    "exit status: 0 done, 1 stopped by the health monitor, 2 bad input, 3 output error, 4 interrupted\n";

static const char *usage_run =
    "usage: surge run [CASE] [-s section.key=value ...] [-o OUTDIR] [--threads N]\n"
    "       surge run --restart CHECKPOINT [-s section.key=value ...] [-o OUTDIR] [--threads N]\n"
    "\n"
    "Runs CASE (default: the demo scene) and writes to OUTDIR (default: runs/<case name>):\n"
    "  params.ini       the full resolved parameter set\n"
    "  snap_*.vtp       particle snapshots (VTK PolyData), listed with their times in run.pvd for ParaView\n"
    "  diagnostics.csv  time series (energy, max speed, density deviation, fluid volume...)\n"
    "  checkpoint.bin   state to continue from with --restart (final, and every output.checkpoint_interval_s)\n"
    "  last_good.vtp    only when the health monitor stopped the run: the last healthy state\n"
    "\n"
    "options:\n"
    "  -s section.key=value  override a parameter (repeatable; see 'surge params')\n"
    "  -o OUTDIR             output folder (created if missing)\n"
    "  --threads N           OpenMP threads (default: all cores)\n"
    "  --restart FILE        continue from a checkpoint; only live parameters may be overridden (time.end_s...)\n"
    "                        and the output goes to the checkpoint's folder unless -o is given\n"
    "Ctrl-C stops at the next step and writes a checkpoint.\n";

static const char *usage_check =
    "usage: surge check CASE [-s section.key=value ...]\n"
    "\n"
    "Reads and validates CASE (with overrides) and builds its scene without running it; prints the derived\n"
    "quantities (h, c0, particle counts) or the first error with file:line.\n";

static const char *usage_params =
    "usage: surge params\n\nPrints the parameter reference (the source of docs/parameters.md).\n";

static int wants_help(int argc, char **argv)
{
    for (int i = 0; i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h"))
            return 1;
    return 0;
}

typedef struct cli {
    const char *case_path;
    const char *restart_path;
    const char *output_dir;
    const char *overrides[256];
    int override_count;
    int threads;
} cli;

static int parse_int(const char *text, int lo, int hi, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (end == text || *end != '\0' || errno || v < lo || v > hi)
        return -1;
    *out = (int)v;
    return 0;
}

static int parse_cli(int argc, char **argv, cli *c, int allow_run_options)
{
    memset(c, 0, sizeof *c);
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        const int has_value = i + 1 < argc;
        if (!strcmp(a, "-s") || !strcmp(a, "--set")) {
            if (!has_value) {
                fprintf(stderr, "surge: %s needs section.key=value\n", a);
                return -1;
            }
            if (c->override_count == (int)(sizeof c->overrides / sizeof c->overrides[0])) {
                fprintf(stderr, "surge: too many -s overrides (at most 256)\n");
                return -1;
            }
            c->overrides[c->override_count++] = argv[++i];
        } else if (allow_run_options && !strcmp(a, "-o")) {
            if (!has_value || argv[i + 1][0] == '\0') {
                fprintf(stderr, "surge: -o needs an output folder\n");
                return -1;
            }
            c->output_dir = argv[++i];
        } else if (allow_run_options && !strcmp(a, "--threads")) {
            if (!has_value || parse_int(argv[i + 1], 1, 1024, &c->threads) != 0) {
                fprintf(stderr, "surge: --threads needs an integer in [1, 1024], got '%s'\n",
                        has_value ? argv[i + 1] : "");
                return -1;
            }
            i++;
        } else if (allow_run_options && !strcmp(a, "--restart")) {
            if (!has_value) {
                fprintf(stderr, "surge: --restart needs a checkpoint file\n");
                return -1;
            }
            c->restart_path = argv[++i];
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "surge: unknown option '%s' (see --help)\n", a);
            return -1;
        } else if (!c->case_path) {
            c->case_path = a;
        } else {
            fprintf(stderr, "surge: unexpected argument '%s' (one case file at most)\n", a);
            return -1;
        }
    }
    if (c->restart_path && c->case_path) {
        fprintf(stderr, "surge: give either a CASE or --restart CHECKPOINT, not both\n");
        return -1;
    }
    return 0;
}

/* Loads the case (or the default scene) and applies overrides. */
static int load_case(const cli *c, surge_params *p)
{
    char err[1024];
    *p = surge_default_params();
    int rc = c->case_path ? surge_params_load(p, c->case_path, err, sizeof err)
                          : surge_params_load_text(p, surge_default_case_text, "cases/demo.ini (built in)", err,
                                                   sizeof err);
    for (int i = 0; rc == 0 && i < c->override_count; i++)
        rc = surge_params_override(p, c->overrides[i], false, err, sizeof err);
    if (rc == 0)
        rc = surge_params_validate(p, err, sizeof err);
    if (rc != 0) {
        fprintf(stderr, "surge: %s\n", err);
        return -1;
    }
    return 0;
}

/* runs/<case file name without folder and extension> */
static void default_output_dir(const char *case_path, char *out, size_t len)
{
    const char *base = case_path ? strrchr(case_path, '/') : NULL;
    base = base ? base + 1 : (case_path ? case_path : "demo.ini");
    size_t n = strcspn(base, ".");
    snprintf(out, len, "runs/%.*s", (int)n, base);
}

static int command_run(int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        fputs(usage_run, stdout);
        return EXIT_OK;
    }
    cli c;
    if (parse_cli(argc, argv, &c, 1) != 0)
        return EXIT_USAGE;
    const int threads = c.threads > 0 ? c.threads : omp_get_num_procs();
    omp_set_num_threads(threads);
    char err[1024], outdir[4096];
    surge_sim *sim = NULL;
    if (c.restart_path) {
        sim = surge_sim_checkpoint_read(c.restart_path, c.overrides, c.override_count, err, sizeof err);
        if (!sim) {
            fprintf(stderr, "surge: %s\n", err);
            return EXIT_USAGE;
        }
        if (c.output_dir) {
            snprintf(outdir, sizeof outdir, "%s", c.output_dir);
        } else {
            const char *slash = strrchr(c.restart_path, '/');
            snprintf(outdir, sizeof outdir, "%.*s", slash ? (int)(slash - c.restart_path) : 1,
                     slash ? c.restart_path : ".");
        }
    } else {
        surge_params p;
        if (load_case(&c, &p) != 0)
            return EXIT_USAGE;
        sim = surge_sim_create(&p, err, sizeof err);
        if (!sim) {
            fprintf(stderr, "surge: %s\n", err);
            return EXIT_USAGE;
        }
        if (c.output_dir)
            snprintf(outdir, sizeof outdir, "%s", c.output_dir);
        else
            default_output_dir(c.case_path, outdir, sizeof outdir);
    }
    const surge_derived *d = surge_sim_derived(sim);
    fprintf(stderr, "surge: %s%s -> %s: %d fluid + %d wall particles, h = %.4g m, c0 = %.4g m/s, %d threads\n",
            c.restart_path ? "restart from " : "", c.restart_path ? c.restart_path
                                                   : (c.case_path ? c.case_path : "default scene (cases/demo.ini)"),
            outdir, d->fluid_count, d->wall_count, d->h_m, d->c0_mps, threads);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    surge_run_options opt = surge_default_run_options();
    opt.output_dir = outdir;
    opt.threads = threads;
    opt.restarted = c.restart_path != NULL;
    opt.stop = &stop_requested;
    surge_run_result r = surge_run(sim, &opt, err, sizeof err);
    const uint64_t hash = surge_sim_state_hash(sim);
    surge_sim_destroy(sim);
    switch (r) {
    case SURGE_RUN_FINISHED:
        fprintf(stderr, "surge: done, state hash %016llx, outputs in %s\n", (unsigned long long)hash, outdir);
        return EXIT_OK;
    case SURGE_RUN_UNHEALTHY:
        fprintf(stderr, "surge: %s\nsurge: last good state written to %s/last_good.vtp and %s/checkpoint.bin\n",
                err, outdir, outdir);
        return EXIT_UNHEALTHY;
    case SURGE_RUN_INTERRUPTED:
        fprintf(stderr, "surge: interrupted; checkpoint written to %s/checkpoint.bin\n", outdir);
        return EXIT_INTERRUPTED;
    case SURGE_RUN_IO_ERROR:
        fprintf(stderr, "surge: %s\n", err);
        return EXIT_IO;
    }
    return EXIT_IO;
}

static int command_check(int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        fputs(usage_check, stdout);
        return EXIT_OK;
    }
    cli c;
    if (parse_cli(argc, argv, &c, 0) != 0)
        return EXIT_USAGE;
    if (!c.case_path) {
        fprintf(stderr, "surge: check needs a CASE file\n%s", usage_check);
        return EXIT_USAGE;
    }
    surge_params p;
    if (load_case(&c, &p) != 0)
        return EXIT_USAGE;
    char err[1024];
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "surge: %s: %s\n", c.case_path, err);
        return EXIT_USAGE;
    }
    const surge_derived *d = surge_sim_derived(sim);
    printf("%s: ok: %d fluid + %d wall particles, h = %.6g m, c0 = %.6g m/s (expected speed %.4g m/s)\n",
           c.case_path, d->fluid_count, d->wall_count, d->h_m, d->c0_mps, d->expected_speed_mps);
    surge_sim_destroy(sim);
    return EXIT_OK;
}

int main(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        fputs(usage_main, argc < 2 ? stderr : stdout);
        return argc < 2 ? EXIT_USAGE : EXIT_OK;
    }
    if (!strcmp(argv[1], "run"))
        return command_run(argc - 2, argv + 2);
    if (!strcmp(argv[1], "check"))
        return command_check(argc - 2, argv + 2);
    if (!strcmp(argv[1], "params")) {
        if (wants_help(argc - 2, argv + 2)) {
            fputs(usage_params, stdout);
            return EXIT_OK;
        }
        if (argc > 2) {
            fprintf(stderr, "surge: params takes no arguments\n");
            return EXIT_USAGE;
        }
        surge_params_write_reference(stdout);
        return EXIT_OK;
    }
    fprintf(stderr, "surge: unknown command '%s'\n%s", argv[1], usage_main);
    return EXIT_USAGE;
}
