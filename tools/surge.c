/* surge: the command-line program. Wires the solver (sim/) to its outputs, the state publisher and the control
 * socket (stream/). */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <limits.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zmq.h>

#include "surge/control.h"
#include "surge/journal.h"
#include "surge/params.h"
#include "surge/publisher.h"
#include "surge/run.h"
#include "surge/sim.h"

extern const char surge_default_case_text[]; /* cases/demo.ini, embedded at build time */

enum { EXIT_OK = 0, EXIT_UNHEALTHY = 1, EXIT_USAGE = 2, EXIT_IO = 3, EXIT_INTERRUPTED = 4 };
enum { ENDPOINT_BYTES = 256 };

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
    "  run [CASE]        run a case file (no CASE: the default demo scene, cases/demo.ini); can publish its\n"
    "                    state over ZeroMQ and take commands on a control socket\n"
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
    "\n"
    "live state and control (docs/protocol.md; a bare PORT means tcp://127.0.0.1:PORT):\n"
    "  --publish ENDPOINT    publish topics state, bodies and stats on a ZeroMQ PUB socket\n"
    "  --publish-every N     at most once every N steps (default 1)\n"
    "  --publish-hz F        and at most F times per wall-clock second (default 30; 0: no limit)\n"
    "  --publish-hwm N       messages queued per subscriber before newer ones are dropped (default 4)\n"
    "  --control ENDPOINT    accept JSON commands (get, set, pause, step, snapshot, stop...) on a ROUTER\n"
    "                        socket; applied commands are journaled in OUTDIR/control.jsonl\n"
    "  --paused              with --control: wait for 'resume' or 'step' before the first step\n"
    "  --replay JOURNAL      apply a control.jsonl's parameter changes and stop at the same steps again\n"
    "The sockets have no authentication: bind to 127.0.0.1 (the default) and reach them through an SSH\n"
    "tunnel from elsewhere.\n"
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
    char publish[ENDPOINT_BYTES];
    char control[ENDPOINT_BYTES];
    const char *replay_path;
    surge_publisher_def publisher;
    int paused;
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

static int parse_real(const char *text, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || errno || !(v >= lo && v <= hi))
        return -1;
    *out = v;
    return 0;
}

/* A ZeroMQ endpoint, or a bare port meaning loopback. Warns when it is reachable from other machines. */
static int parse_endpoint(const char *option, const char *text, char *out)
{
    int port;
    if (parse_int(text, 1, 65535, &port) == 0) {
        snprintf(out, ENDPOINT_BYTES, "tcp://127.0.0.1:%d", port);
        return 0;
    }
    if (strlen(text) >= ENDPOINT_BYTES || !strstr(text, "://")) {
        fprintf(stderr, "surge: %s needs an endpoint such as tcp://127.0.0.1:5555 or ipc:///tmp/surge, or a port; "
                        "got '%s'\n", option, text);
        return -1;
    }
    snprintf(out, ENDPOINT_BYTES, "%s", text);
    if (!strncmp(text, "tcp://", 6) && strncmp(text, "tcp://127.", 10) && strncmp(text, "tcp://localhost:", 16) &&
        strncmp(text, "tcp://[::1]:", 12))
        fprintf(stderr, "surge: warning: %s %s is not bound to loopback; it has no authentication, so anyone who "
                        "can reach it can %s (see docs/protocol.md)\n", option, text,
                !strcmp(option, "--control") ? "steer and stop the run" : "read the state");
    return 0;
}

static int parse_cli(int argc, char **argv, cli *c, int allow_run_options)
{
    memset(c, 0, sizeof *c);
    c->publisher = surge_default_publisher_def();
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
        } else if (allow_run_options && (!strcmp(a, "--publish") || !strcmp(a, "--control"))) {
            if (!has_value || parse_endpoint(a, argv[i + 1], !strcmp(a, "--publish") ? c->publish : c->control) != 0) {
                if (!has_value)
                    fprintf(stderr, "surge: %s needs an endpoint or a port\n", a);
                return -1;
            }
            i++;
        } else if (allow_run_options && !strcmp(a, "--publish-every")) {
            if (!has_value || parse_int(argv[i + 1], 1, 1000000000, &c->publisher.every_steps) != 0) {
                fprintf(stderr, "surge: --publish-every needs a whole number of steps in [1, 1e9], got '%s'\n",
                        has_value ? argv[i + 1] : "");
                return -1;
            }
            i++;
        } else if (allow_run_options && !strcmp(a, "--publish-hz")) {
            if (!has_value || parse_real(argv[i + 1], 0, 1e6, &c->publisher.max_rate_hz) != 0) {
                fprintf(stderr, "surge: --publish-hz needs a rate in [0, 1e6] per second (0: no limit), got '%s'\n",
                        has_value ? argv[i + 1] : "");
                return -1;
            }
            i++;
        } else if (allow_run_options && !strcmp(a, "--publish-hwm")) {
            if (!has_value || parse_int(argv[i + 1], 1, 1000000, &c->publisher.send_hwm) != 0) {
                fprintf(stderr, "surge: --publish-hwm needs a message count in [1, 1e6], got '%s'\n",
                        has_value ? argv[i + 1] : "");
                return -1;
            }
            i++;
        } else if (allow_run_options && !strcmp(a, "--replay")) {
            if (!has_value) {
                fprintf(stderr, "surge: --replay needs a journal file (control.jsonl)\n");
                return -1;
            }
            c->replay_path = argv[++i];
        } else if (allow_run_options && !strcmp(a, "--paused")) {
            c->paused = 1;
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
    if (c->paused && !c->control[0]) {
        fprintf(stderr, "surge: --paused needs --control (nothing could resume the run)\n");
        return -1;
    }
    if (c->publish[0] && c->control[0] && !strcmp(c->publish, c->control)) {
        fprintf(stderr, "surge: --publish and --control need different endpoints\n");
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

/* The live links of a run: replayed journal, control socket and publisher, served at each step boundary. */
typedef struct live_links {
    void *zmq_context;
    surge_publisher *publisher;
    surge_control *control;
    surge_replay *replay;
    surge_journal *journal;
    char replay_error[1024]; /* set when a journal entry could not be replayed */
} live_links;

static int at_step_boundary(surge_sim *sim, void *user)
{
    live_links *l = user;
    int requests = SURGE_CONTINUE;
    if (l->replay) {
        const int replayed = surge_replay_apply(l->replay, sim, l->journal, l->replay_error, sizeof l->replay_error);
        if (replayed < 0)
            return SURGE_REQUEST_STOP;
        requests |= replayed;
    }
    if (l->control)
        requests |= surge_control_service(l->control, sim, &stop_requested);
    if (l->publisher)
        surge_publisher_offer(l->publisher, sim);
    return requests;
}

static int open_live_links(const cli *c, const char *outdir, live_links *l)
{
    char err[1024], path[4200];
    memset(l, 0, sizeof *l);
    if (c->replay_path && !(l->replay = surge_replay_load(c->replay_path, err, sizeof err)))
        goto fail;
    if (c->control[0] || c->replay_path) {
        snprintf(path, sizeof path, "%s/control.jsonl", outdir);
        if (!(l->journal = surge_journal_open(path, c->restart_path != NULL, err, sizeof err)))
            goto fail;
    }
    if (c->publish[0] || c->control[0])
        l->zmq_context = zmq_ctx_new();
    if (c->control[0]) {
        surge_control_def def = surge_default_control_def();
        def.endpoint = c->control;
        def.start_paused = c->paused;
        if (!(l->control = surge_control_start(l->zmq_context, &def, l->journal, err, sizeof err)))
            goto fail;
    }
    if (c->publish[0]) {
        surge_publisher_def def = c->publisher;
        def.endpoint = c->publish;
        if (!(l->publisher = surge_publisher_start(l->zmq_context, &def, err, sizeof err)))
            goto fail;
    }
    return 0;
fail:
    fprintf(stderr, "surge: %s\n", err);
    return -1;
}

static void close_live_links(live_links *l, const surge_sim *sim)
{
    if (l->publisher) {
        surge_publisher_report r;
        surge_publisher_finish(l->publisher, sim, &r);
        fprintf(stderr, "surge: published %llu states (%llu superseded by newer ones before sending), %llu messages, "
                        "%.1f MB\n", (unsigned long long)r.frames_posted, (unsigned long long)r.frames_superseded,
                (unsigned long long)r.messages_sent, 1e-6 * (double)r.bytes_sent);
    }
    surge_control_close(l->control);
    surge_replay_free(l->replay);
    surge_journal_close(l->journal);
    if (l->zmq_context)
        zmq_ctx_term(l->zmq_context);
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
    live_links links;
    if (open_live_links(&c, outdir, &links) != 0) {
        close_live_links(&links, sim);
        surge_sim_destroy(sim);
        return EXIT_USAGE;
    }
    if (c.publish[0])
        fprintf(stderr, "surge: publishing state, bodies and stats on %s\n", c.publish);
    if (c.control[0])
        fprintf(stderr, "surge: control socket on %s%s\n", c.control, c.paused ? " (paused: send resume or step)" : "");
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    surge_run_options opt = surge_default_run_options();
    opt.output_dir = outdir;
    opt.threads = threads;
    opt.restarted = c.restart_path != NULL;
    opt.stop = &stop_requested;
    if (links.publisher || links.control || links.replay) {
        opt.at_step_boundary = at_step_boundary;
        opt.user = &links;
    }
    surge_run_result r = surge_run(sim, &opt, err, sizeof err);
    close_live_links(&links, sim);
    const uint64_t hash = surge_sim_state_hash(sim);
    surge_sim_destroy(sim);
    if (links.replay_error[0]) {
        fprintf(stderr, "surge: %s\nsurge: the run stopped there; its outputs are in %s\n", links.replay_error, outdir);
        return EXIT_USAGE;
    }
    switch (r) {
    case SURGE_RUN_FINISHED:
        fprintf(stderr, "surge: done, state hash %016llx, outputs in %s\n", (unsigned long long)hash, outdir);
        return EXIT_OK;
    case SURGE_RUN_UNHEALTHY:
        fprintf(stderr, "surge: %s\nsurge: last good state written to %s/last_good.vtp and %s/checkpoint.bin\n",
                err, outdir, outdir);
        return EXIT_UNHEALTHY;
    case SURGE_RUN_STOPPED:
        fprintf(stderr, "surge: stopped by a control request, state hash %016llx; checkpoint written to "
                        "%s/checkpoint.bin\n", (unsigned long long)hash, outdir);
        return EXIT_OK;
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
