/* surge: the command-line program. Wires the solver (sim/) to its outputs, the state publisher and the control
 * socket (stream/) and the renderer (render/). */
#define _XOPEN_SOURCE 700 /* POSIX 2008 and realpath */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/resource.h>
#include <unistd.h>

#include <zmq.h>

#include "surge/platform.h"
#include "surge/control.h"
#include "surge/curve.h"
#include "surge/journal.h"
#include "surge/params.h"
#include "surge/publisher.h"
#include "surge/render.h"
#include "surge/run.h"
#include "surge/run_folder.h"
#include "surge/sim.h"
#include "surge/vtk_output.h"

extern const char surge_default_case_text[]; /* cases/demo.ini, embedded at build time */

enum { EXIT_OK = 0, EXIT_UNHEALTHY = 1, EXIT_USAGE = 2, EXIT_IO = 3, EXIT_INTERRUPTED = 4 };
enum { ENDPOINT_BYTES = 256 };
#define SURGE_PI_CLI 3.14159265358979323846

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
    "  render RUN_DIR    render a finished run's snapshots as PNG frames and/or a movie\n"
    "  check CASE        validate a case file without running it\n"
    "  params            print the parameter reference (Markdown)\n"
    "  version           print the program (its commit, compiler and vector extensions) and the machine\n"
    "  keygen NAME       make a CURVE key pair for the live links: NAME.key (secret) and NAME.pub\n"
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
    "  -o OUTDIR             output folder (created if missing; default runs/<case name>). A folder that holds\n"
    "                        an earlier run is refused; without -o the run goes to a fresh runs/<case name>-N\n"
    "  --overwrite           replace the earlier run in OUTDIR (its files only) and the frames in --frames DIR\n"
    "  --threads N           OpenMP threads (default: all cores)\n"
    "  --restart FILE        continue from a checkpoint; only live parameters may be overridden (time.end_s...)\n"
    "                        and the output goes to the checkpoint's folder unless -o is given\n"
    "\n"
    "rendering while it runs (settings: the [render] parameters, e.g. -s render.field=vx_rel):\n"
    "  --frames DIR          a PNG every render.frame_interval_s of simulated time (frame_NNNNNN.png)\n"
    "  --movie FILE          an MP4 movie of the same frames (the ffmpeg program; H.264 when available); after\n"
    "                        --restart with the --frames DIR of the first run, it starts with that run's frames\n"
    "  --font FILE           TrueType font for the labels (default DejaVu Sans)\n"
    "  The renderer never holds the solver back: a frame it is too busy to draw is skipped (reported at the\n"
    "  end; the movie repeats the previous image so that its time stays right).\n"
    "\n"
    "live state and control (docs/protocol.md; a bare PORT means tcp://127.0.0.1:PORT):\n"
    "  --publish ENDPOINT    publish topics state, bodies and stats (and frame, when rendering) on a ZeroMQ\n"
    "                        PUB socket\n"
    "  --publish-every N     at most once every N steps (default 1)\n"
    "  --publish-hz F        and at most F times per wall-clock second (default 30; 0: no limit)\n"
    "  --publish-hwm N       messages queued per subscriber before newer ones are dropped (default 4)\n"
    "  --control ENDPOINT    accept JSON commands (get, set, pause, step, snapshot, stop...) on a ROUTER\n"
    "                        socket; applied commands are journaled in OUTDIR/control.jsonl\n"
    "  --paused              with --control: wait for 'resume' or 'step' before the first step\n"
    "  --replay JOURNAL      apply a control.jsonl's parameter changes and stop at the same steps again\n"
    "  --curve-key FILE      secure both sockets with ZeroMQ's CURVE: the run's key (NAME.key, surge keygen)\n"
    "  --curve-clients PATH  and admit only the clients whose public key (a .pub file, or each *.pub in a\n"
    "                        folder) is listed; required for a --control reachable from other machines\n"
    "Without keys the sockets have no authentication: bind them to 127.0.0.1 (the default; a --control\n"
    "elsewhere is refused) or reach them through an SSH tunnel.\n"
    "Ctrl-C stops at the next step and writes a checkpoint.\n";

static const char *usage_check =
    "usage: surge check CASE [-s section.key=value ...]\n"
    "\n"
    "Reads and validates CASE (with overrides) and builds its scene without running it; prints the derived\n"
    "quantities (h, c0, particle counts) or the first error with file:line.\n";

static const char *usage_render =
    "usage: surge render RUN_DIR [--frames DIR] [--movie FILE] [-s render.key=value ...] [--font FILE]\n"
    "                    [--overwrite]\n"
    "\n"
    "Renders every snapshot listed in RUN_DIR/run.pvd with the run's parameters (RUN_DIR/params.ini) and\n"
    "the overrides, as PNG frames (frame_NNNNNN.png, one per snapshot) and/or a movie at render.movie_fps.\n"
    "With -s render.frame_interval_s=T, one snapshot per T of simulated time instead (the first at or after\n"
    "each multiple of T). Without --frames or --movie, frames go to RUN_DIR/frames.\n";

static const char *usage_keygen =
    "usage: surge keygen NAME\n\n"
    "Makes a CURVE key pair (ZeroMQ's certificate format, as pyzmq's zmq.auth reads it): NAME.key holds the\n"
    "secret key (file mode 0600; keep it private) and NAME.pub the public key to hand to peers. Existing files\n"
    "are never replaced. A run takes its own NAME.key with --curve-key and its clients' .pub files with\n"
    "--curve-clients; a client takes its own .key and the run's .pub (docs/protocol.md).\n";

static const char *usage_version =
    "usage: surge version\n\nPrints the program (its git commit, compiler and the vector extensions it was built for)\n"
    "and the machine (CPU, processors, AVX2 and AVX-512), as every run's params.ini records them.\n";
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
    int publish_remote, control_remote; /* the endpoint can be reached from other machines */
    const char *curve_key_path;         /* --curve-key: the run's secret key file (CURVE on both sockets) */
    const char *curve_clients_path;     /* --curve-clients: the allowed clients' .pub file or folder */
    const char *replay_path;
    surge_publisher_def publisher;
    int paused;
    const char *frames_dir;
    const char *movie_path;
    const char *font_path;
    int overwrite; /* --overwrite: replace an earlier run's files and frames */
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

/* A ZeroMQ endpoint, or a bare port meaning loopback; *remote tells whether other machines can reach it. */
static int parse_endpoint(const char *option, const char *text, char *out, int *remote)
{
    int port;
    *remote = 0;
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
    /* this machine only: a local socket file, or TCP on loopback; any other transport (tcp elsewhere, pgm, epgm,
     * norm, udp, ws...) can be reached from other machines */
    *remote = !(!strncmp(text, "ipc://", 6) || !strncmp(text, "inproc://", 9) || !strncmp(text, "tcp://127.", 10) ||
                !strncmp(text, "tcp://localhost:", 16) || !strncmp(text, "tcp://[::1]:", 12));
    return 0;
}

/* Who may reach the sockets: with CURVE keys, only the allowed clients, from anywhere; without, whoever can
 * reach the endpoint, so nobody elsewhere may steer a run and a remote publisher is warned about (issue #24). */
static int check_endpoint_security(const cli *c)
{
    if (!c->curve_key_path != !c->curve_clients_path) {
        fprintf(stderr, "surge: %s needs %s too: the run's secret key and the allowed clients' public keys go "
                        "together (docs/protocol.md, \"Steering from another machine\")\n",
                c->curve_key_path ? "--curve-key" : "--curve-clients",
                c->curve_key_path ? "--curve-clients" : "--curve-key");
        return -1;
    }
    if (c->curve_key_path && !c->publish[0] && !c->control[0]) {
        fprintf(stderr, "surge: --curve-key secures --publish and --control; neither is given\n");
        return -1;
    }
    if (c->curve_key_path)
        return 0;
    if (c->control_remote) {
        fprintf(stderr, "surge: --control %s can be reached from other machines and has no authentication: refused. "
                        "Give it CURVE keys (--curve-key and --curve-clients; `surge keygen` makes them), or bind it to "
                        "loopback (a bare port does) and reach it through an SSH tunnel (docs/protocol.md)\n",
                c->control);
        return -1;
    }
    if (c->publish_remote)
        fprintf(stderr, "surge: warning: --publish %s is not bound to loopback and has no authentication, so anyone "
                        "who can reach it can read the state; --curve-key and --curve-clients admit only the clients "
                        "you name (docs/protocol.md)\n", c->publish);
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
            const int publish = !strcmp(a, "--publish");
            if (!has_value || parse_endpoint(a, argv[i + 1], publish ? c->publish : c->control,
                                             publish ? &c->publish_remote : &c->control_remote) != 0) {
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
        } else if (allow_run_options && (!strcmp(a, "--frames") || !strcmp(a, "--movie") || !strcmp(a, "--font"))) {
            if (!has_value || argv[i + 1][0] == '\0') {
                fprintf(stderr, "surge: %s needs a %s\n", a, !strcmp(a, "--frames") ? "folder" : "file name");
                return -1;
            }
            *(!strcmp(a, "--frames") ? &c->frames_dir : !strcmp(a, "--movie") ? &c->movie_path : &c->font_path) =
                argv[++i];
        } else if (allow_run_options && (!strcmp(a, "--curve-key") || !strcmp(a, "--curve-clients"))) {
            if (!has_value || argv[i + 1][0] == '\0') {
                fprintf(stderr, "surge: %s needs a %s\n", a,
                        !strcmp(a, "--curve-key") ? "key file (NAME.key from surge keygen)"
                                                   : "public key file or a folder of *.pub files");
                return -1;
            }
            *(!strcmp(a, "--curve-key") ? &c->curve_key_path : &c->curve_clients_path) = argv[++i];
        } else if (allow_run_options && !strcmp(a, "--paused")) {
            c->paused = 1;
        } else if (allow_run_options && !strcmp(a, "--overwrite")) {
            c->overwrite = 1;
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
    return allow_run_options ? check_endpoint_security(c) : 0;
}

/* An error found after the case parsed (a rule across parameters, the scene it builds) names the set of
 * parameters it came from. */
static void print_case_error(const cli *c, const char *err)
{
    fprintf(stderr, "surge: %s%s: %s\n", c->case_path ? c->case_path : "cases/demo.ini (built in)",
            c->override_count ? " with the -s overrides" : "", err);
}

/* A periodic channel's particles tile its period, so dp must divide domain.length_m. A dp that does not is moved
 * to the nearest that does when that moves it by 1 % or less, and the move is said: changing dp alone then never
 * fails (issue #25; the debris surge's 33 m refused dp = 0.035, 0.045 and 0.08 m). A larger move is left to the
 * validation's error, which names both numbers. */
static void fit_dp_to_period(surge_params *p)
{
    const double dp = p->numerics.dp_m, length_m = p->domain.length_m;
    if (!p->domain.periodic_x || !(dp > 0) || !(length_m > 0))
        return;
    const double spacings = length_m / dp, whole = round(spacings);
    if (fabs(spacings - whole) <= 1e-6 || whole < 1 || fabs(spacings / whole - 1) > 0.01)
        return;
    p->numerics.dp_m = length_m / whole;
    fprintf(stderr, "surge: note: numerics.dp_m = %g m does not divide the periodic domain.length_m = %g m (%.6g "
                    "spacings); using dp = %.9g m (%.0f spacings, %.2g %% %s) so that the particles tile the period\n",
            dp, length_m, spacings, p->numerics.dp_m, whole, 100 * fabs(p->numerics.dp_m / dp - 1),
            p->numerics.dp_m < dp ? "finer" : "coarser");
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
    if (rc != 0) {
        fprintf(stderr, "surge: %s\n", err);
        return -1;
    }
    fit_dp_to_period(p);
    if (surge_params_validate(p, err, sizeof err) != 0) {
        print_case_error(c, err);
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
    surge_renderer *renderer;
    surge_curve_server *curve; /* NULL: the sockets have no security */
    const char *movie_path; /* NULL: no movie */
    char replay_error[1024]; /* set when a journal entry could not be replayed */
} live_links;

/* Renderer thread: rendered frames also go out on the stream. */
static void publish_rendered_frame(const uint8_t *png, size_t png_len, int64_t step, double time_s, void *user)
{
    surge_publisher_post_png(user, png, png_len, step, time_s);
}

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
    if (l->renderer)
        surge_renderer_offer(l->renderer, sim);
    return requests;
}

/* render.height_px = 0: the height fitted to the scene, from the run's state (sim) or a saved snapshot (path). */
static int fit_frame_height(surge_params *p, const surge_sim *sim, const char *path, char *err, size_t err_len)
{
    if (p->render.height_px > 0)
        return 0;
    surge_snapshot snap = {0};
    const int rc = sim ? (surge_sim_snapshot(sim, &snap) == 0 ? 0 : (snprintf(err, err_len, "out of memory"), -1))
                       : surge_vtp_read(path, &snap, err, err_len);
    if (rc == 0) {
        p->render.height_px = surge_render_fitted_height_px(p->render.width_px, &snap, p);
        fprintf(stderr, "surge: frames %d x %d px (height fitted to the scene; render.height_px sets it)\n",
                p->render.width_px, p->render.height_px);
    }
    surge_snapshot_free(&snap);
    return rc;
}

static int open_live_links(const cli *c, const char *outdir, const surge_sim *sim, live_links *l)
{
    char err[1024], path[4200];
    memset(l, 0, sizeof *l);
    if (c->replay_path && !(l->replay = surge_replay_load(c->replay_path, err, sizeof err)))
        goto fail;
    if (c->control[0] || c->replay_path) {
        snprintf(path, sizeof path, "%s/control.jsonl", outdir);
        const long long resume_step = c->restart_path ? (long long)surge_sim_step_count(sim) : -1;
        if (!(l->journal = surge_journal_open(path, resume_step, err, sizeof err)))
            goto fail;
    }
    if (c->publish[0] || c->control[0])
        l->zmq_context = zmq_ctx_new();
    if (c->curve_key_path) {
        if (!(l->curve = surge_curve_server_start(l->zmq_context, c->curve_key_path, c->curve_clients_path, err,
                                                  sizeof err)))
            goto fail;
        fprintf(stderr, "surge: CURVE security: %d allowed client key%s (%s)\n", surge_curve_allowed_count(l->curve),
                surge_curve_allowed_count(l->curve) == 1 ? "" : "s", c->curve_clients_path);
    }
    if (c->control[0]) {
        surge_control_def def = surge_default_control_def();
        def.endpoint = c->control;
        def.curve = l->curve;
        def.start_paused = c->paused;
        if (!(l->control = surge_control_start(l->zmq_context, &def, l->journal, err, sizeof err)))
            goto fail;
    }
    if (c->publish[0]) {
        surge_publisher_def def = c->publisher;
        def.endpoint = c->publish;
        def.curve = l->curve;
        if (!(l->publisher = surge_publisher_start(l->zmq_context, &def, err, sizeof err)))
            goto fail;
    }
    if (c->frames_dir || c->movie_path) {
        surge_renderer_def def = {.frames_dir = c->frames_dir, .movie_path = c->movie_path, .font_path = c->font_path,
                                  .continue_frames = c->restart_path != NULL, .resume_time_s = surge_sim_time(sim)};
        if (l->publisher) {
            def.on_frame = publish_rendered_frame;
            def.user = l->publisher;
        }
        surge_params render_params = *surge_sim_params(sim);
        if (fit_frame_height(&render_params, sim, NULL, err, sizeof err) != 0 ||
            !(l->renderer = surge_renderer_start(&def, &render_params, err, sizeof err)))
            goto fail;
        l->movie_path = c->movie_path;
    }
    return 0;
fail:
    fprintf(stderr, "surge: %s\n", err);
    return -1;
}

/* Returns -1 when the renderer failed (its message printed). */
static int close_live_links(live_links *l, const surge_sim *sim)
{
    int rc = 0;
    if (l->renderer) {
        surge_render_report r;
        char err[1024];
        rc = surge_renderer_finish(l->renderer, &r, err, sizeof err);
        if (rc != 0)
            fprintf(stderr, "surge: rendering failed: %s\n", err);
        fprintf(stderr, "surge: rendered %llu of %llu frames due (%llu skipped while the renderer was busy), "
                        "%.1f ms per frame drawing, %.1f ms encoding\n",
                (unsigned long long)r.frames_drawn, (unsigned long long)r.frames_due,
                (unsigned long long)(r.frames_due - r.frames_drawn), r.frames_drawn ? 1e3 * r.draw_s / r.frames_drawn : 0,
                r.frames_drawn ? 1e3 * r.encode_s / r.frames_drawn : 0);
        if (l->movie_path && r.movie_frames_before_restart > 0)
            fprintf(stderr, "surge: movie %s: %llu frames (%llu of them drawn before the restart)\n", l->movie_path,
                    (unsigned long long)r.movie_frames, (unsigned long long)r.movie_frames_before_restart);
        else if (l->movie_path)
            fprintf(stderr, "surge: movie %s: %llu frames\n", l->movie_path, (unsigned long long)r.movie_frames);
    }
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
    if (l->curve && surge_curve_refused_count(l->curve) > 0)
        fprintf(stderr, "surge: refused %ld connection%s whose client key was not allowed\n",
                surge_curve_refused_count(l->curve), surge_curve_refused_count(l->curve) == 1 ? "" : "s");
    surge_curve_server_stop(l->curve);
    if (l->zmq_context)
        zmq_ctx_term(l->zmq_context);
    return rc;
}

/* Density diffusion relaxes pressure over the kernel scale. Around a boulder of radius r in a very viscous fluid
 * that lets the flow carry a divergence of about delta (h/r) nu / (c0 r) of its strain rate, and the suspension
 * loses its extra viscosity (docs/validation/poiseuille_loaded.md). Warns where the estimate passes 5 %. */
static void warn_diffusive_compressibility(const surge_sim *sim)
{
    const surge_params *p = surge_sim_params(sim);
    const surge_derived *d = surge_sim_derived(sim);
    if (d->boulder_count == 0 || !(p->numerics.density_diffusion > 0))
        return;
    const double radius_m = d->smallest_boulder_radius_m;
    const double estimate =
        p->numerics.density_diffusion * (d->h_m / radius_m) * p->fluid.viscosity_m2ps / (d->c0_mps * radius_m);
    if (estimate > 0.05)
        fprintf(stderr, "surge: warning: density diffusion lets the fluid compress around the boulders: "
                        "delta (h/r) nu / (c0 r) = %.2g with r = %.4g m, c0 = %.4g m/s (above 0.05); set "
                        "numerics.density_diffusion = 0 or raise numerics.c0_mps\n",
                estimate, radius_m, d->c0_mps);
}

/* Refuses (-1) to write into a folder that holds earlier outputs (belongs) unless --overwrite, which removes them;
 * what names the outputs and hint says how else to go on. */
static int claim_folder(const char *folder, int (*belongs)(const char *name), int overwrite, const char *what,
                        const char *hint)
{
    char example[256], err[1024];
    const int count = surge_folder_count(folder, belongs, example, sizeof example, err, sizeof err);
    if (count < 0) {
        fprintf(stderr, "surge: %s\n", err);
        return -1;
    }
    if (count == 0)
        return 0;
    if (!overwrite) {
        fprintf(stderr, "surge: %s already holds %s (%d files, e.g. %s); nothing was written. %s, or add --overwrite "
                        "to replace them\n", folder, what, count, example, hint);
        return -1;
    }
    const int removed = surge_folder_clear(folder, belongs, err, sizeof err);
    if (removed < 0) {
        fprintf(stderr, "surge: --overwrite: %s\n", err);
        return -1;
    }
    fprintf(stderr, "surge: --overwrite: removed %d files of %s from %s\n", removed, what, folder);
    return 0;
}

/* The default output folder, or the first of folder-2, folder-3, ... that holds no earlier run. */
static int fresh_default_folder(char *folder, size_t len)
{
    char base[4096], err[1024];
    snprintf(base, sizeof base, "%s", folder);
    for (int n = 1; n < 10000; n++) {
        if (n > 1 && snprintf(folder, len, "%s-%d", base, n) >= (int)len) {
            fprintf(stderr, "surge: the output folder name %s is too long\n", base);
            return -1;
        }
        const int count = surge_folder_count(folder, surge_is_run_file, NULL, 0, err, sizeof err);
        if (count < 0) {
            fprintf(stderr, "surge: %s\n", err);
            return -1;
        }
        if (count == 0) {
            if (n > 1)
                fprintf(stderr, "surge: %s holds an earlier run; this one goes to %s (-o chooses the folder, "
                                "--overwrite replaces)\n", base, folder);
            return 0;
        }
    }
    fprintf(stderr, "surge: %s-2 ... %s-9999 all hold runs; choose a folder with -o\n", base, base);
    return -1;
}

/* Whether two paths name the same existing folder. */
static int same_folder(const char *a, const char *b)
{
    char ra[PATH_MAX], rb[PATH_MAX];
    return realpath(a, ra) && realpath(b, rb) && !strcmp(ra, rb);
}

/* The folder part of a file path ("." when it has none). */
static void folder_of(const char *path, char *folder, size_t len)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(folder, len, ".");
    else
        snprintf(folder, len, "%.*s", slash == path ? 1 : (int)(slash - path), path);
}

/* A movie file's folder must exist and be writable before the run starts, not when the first frame is encoded;
 * and, unless replacing is allowed, no movie may be there already. 0, or -1 with the message printed. */
static int claim_movie(const char *movie_path, int may_replace)
{
    char folder[4096];
    folder_of(movie_path, folder, sizeof folder);
    if (access(folder, W_OK) != 0) {
        fprintf(stderr, "surge: --movie %s: its folder %s %s\n", movie_path, folder,
                errno == ENOENT ? "does not exist" : "is not writable");
        return -1;
    }
    if (!may_replace && access(movie_path, F_OK) == 0) {
        fprintf(stderr, "surge: the movie %s exists; nothing was written. Choose another --movie file, or add "
                        "--overwrite to replace it\n", movie_path);
        return -1;
    }
    return 0;
}

/* Resolution and cost, from the scene as built (issue #24): warnings when the flow depth holds fewer than 15
 * particles (the paper's minimum) or a disc's radius fewer than 4 dp; the memory and the time a simulated second
 * will take, estimated from the list sizes and the throughput measured in docs/performance.md. */
static void report_resolution(const surge_sim *sim, int verbose)
{
    const surge_params *p = surge_sim_params(sim);
    const surge_derived *d = surge_sim_derived(sim);
    const double dp = p->numerics.dp_m, h = d->h_m;
    const double depth_particles = p->fluid.depth_m / dp;
    FILE *out = verbose ? stdout : stderr; /* check: with its report; run: with its messages */
    if (d->fluid_count > 0 && depth_particles < 15)
        fprintf(out, "surge: note: the fluid's depth (%g m) holds %.1f particles at dp = %g m, fewer than the 15 "
                        "that velocity profiles and fronts need (GMD 2025); dp <= %g m gives 15\n",
                p->fluid.depth_m, depth_particles, dp, p->fluid.depth_m / 15);
    if (d->boulder_count > 0 && d->smallest_boulder_radius_m < 4 * dp)
        fprintf(out, "surge: warning: the smallest disc's radius (%g m) is %.1f dp, fewer than 4: its surface is "
                        "too coarse for the fluid's forces on it; dp <= %g m gives 4\n",
                d->smallest_boulder_radius_m, d->smallest_boulder_radius_m / dp, d->smallest_boulder_radius_m / 4);
    if (d->boulder_count > 0 && p->numerics.scheme == SURGE_SCHEME_IMPLICIT && d->smallest_boulder_radius_m < 2.5 * dp)
        fprintf(out, "surge: warning: the implicit scheme with discs under 2.5 dp in radius (the smallest here is "
                        "%.1f dp): its incompressible step gives the fluid squeezed under a coarse disc no room, and "
                        "the debris surge stopped at dp = 0.066 m (1.5 dp) where it ran at 0.04 m (2.5 dp) "
                        "(docs/validation/debris_surge.md, \"The implicit scheme with discs\"); dp <= %g m gives 2.5\n",
                d->smallest_boulder_radius_m / dp, d->smallest_boulder_radius_m / 2.5);
    /* list entries per fluid particle: the particles within 2h + skin (the implicit scheme's lists have none); 12
     * bytes each, about 200 bytes of state */
    const double skin_h = p->numerics.scheme == SURGE_SCHEME_IMPLICIT ? 0.0 : p->numerics.neighbour_skin_h;
    const double reach = (2.0 + skin_h) * h;
    const double entries = SURGE_PI_CLI * reach * reach / (dp * dp);
    const double bytes = d->fluid_count * (12 * entries + 200) + d->wall_count * (6 * entries + 150);
    double dt = p->numerics.dt_fixed_s;
    if (!(dt > 0)) {
        dt = h / d->c0_mps;
        if (p->numerics.viscous_dt_limit && p->fluid.viscosity_m2ps > 0)
            dt = fmin(dt, h * h / p->fluid.viscosity_m2ps);
        dt *= p->numerics.cfl;
    }
    if (p->numerics.scheme == SURGE_SCHEME_IMPLICIT) {
        /* the implicit scheme's step follows the flow's speed; its cost per step follows the solves' iterations */
        const double g = p->body.gravity_mps2, u = d->expected_speed_mps;
        double dt_implicit = p->numerics.dt_fixed_s;
        if (!(dt_implicit > 0))
            dt_implicit = surge_implicit_dt_s(p, h, g, u);
        /* a fixed step shorter than the scheme's own at rest: the still tank's free surface does not stay at rest
         * there (docs/validation/stability.md, "Short steps in a thin fluid") */
        const double dt_rest = surge_implicit_dt_s(p, h, g, 0.0);
        if (p->numerics.dt_fixed_s > 0 && p->numerics.dt_fixed_s < dt_rest)
            fprintf(out, "surge: warning: numerics.dt_fixed_s = %g s is shorter than the implicit scheme's own step at "
                    "rest (%.3g s, implicit.force_cfl): in the still tank, at fixed steps under about half of it "
                    "(nu dt / dp^2 = %.3g here) a mode of the incremental projection under the free surface grows "
                    "and the fluid does not stay at rest (docs/validation/stability.md, \"Short steps in a thin "
                    "fluid\"); leave the step to the scheme (0) or use the explicit scheme\n",
                    p->numerics.dt_fixed_s, dt_rest,
                    p->fluid.viscosity_m2ps * p->numerics.dt_fixed_s / (dp * dp));
        const double default_cfl = surge_default_params().implicit.cfl;
        if (p->implicit.cfl < default_cfl)
            fprintf(out, "surge: warning: implicit.cfl = %g is below its default %g: the same mode grows where the "
                    "flow's speed sets the step (the debris surge at dp = 0.04 m stopped at 5.7 s with 60 discs and "
                    "0.1, at 0.52 s without discs and 0.05; docs/validation/stability.md, \"Short steps in a thin "
                    "fluid\")\n", p->implicit.cfl, default_cfl);
        const bool amg = surge_implicit_uses_amg(p, d->fluid_count, false);
        const bool viscous_amg = surge_implicit_uses_amg(p, d->fluid_count, true);
        if (verbose || bytes > 4e9)
            fprintf(out, "%sestimated memory %.3g MB (%.0f list entries per fluid particle); implicit scheme: dt = %.3g "
                    "s at the scene's expected speed %.3g m/s (it follows the flow's own speed: longer where the flow "
                    "is slower); pressure solves by %s, viscous solves by %s (implicit.preconditioner = %s); the cost "
                    "per step follows the linear solves' iterations (diagnostics.csv), not estimated here\n",
                    verbose ? "  " : "surge: ", bytes / 1e6, entries, dt_implicit, u,
                    amg ? "BiCGSTAB with hypre's BoomerAMG" : "matrix-free Jacobi-preconditioned BiCGSTAB",
                    viscous_amg ? "BiCGSTAB with hypre's BoomerAMG" : "matrix-free Jacobi-preconditioned BiCGSTAB",
                    p->implicit.preconditioner == SURGE_PRECONDITIONER_AUTO
                        ? "auto: amg for the pressure from 2,500 fluid particles, for the viscous solve from 10,000"
                        : (amg ? "amg" : "jacobi"));
        return;
    }
    /* seconds per particle-step on 2 threads of the 2-core EPYC VM, fitted to the benchmark at C_h 1.0 and 1.8; a
     * wall particle counts as a fluid one: in the debris surge a step costs about the same per wall particle (a disc's
     * mDBC sums, forces and face search) as per fluid particle (docs/performance.md, "What surge check's estimate
     * counts") */
    const double per_particle_step_s = 1.37e-7 + 4.43e-9 * entries;
    const double particle_steps = d->fluid_count / dt;
    const double wall_time_s = (double)(d->fluid_count + d->wall_count) / dt * per_particle_step_s;
    if (verbose || bytes > 4e9)
        fprintf(out,
                "%sestimated memory %.3g MB (%.0f list entries per fluid particle); at most %.3g steps and %.3g "
                "fluid particle-steps per simulated second (dt <= %.3g s), about %.3g s of wall time per simulated "
                "second on 2 cores, wall particles counted as fluid ones (docs/performance.md)\n",
                verbose ? "  " : "surge: ", bytes / 1e6, entries, 1 / dt, particle_steps, dt, wall_time_s);
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
            folder_of(c.restart_path, outdir, sizeof outdir);
        }
    } else {
        surge_params p;
        if (load_case(&c, &p) != 0)
            return EXIT_USAGE;
        sim = surge_sim_create(&p, err, sizeof err);
        if (!sim) {
            print_case_error(&c, err);
            return EXIT_USAGE;
        }
        if (c.output_dir)
            snprintf(outdir, sizeof outdir, "%s", c.output_dir);
        else
            default_output_dir(c.case_path, outdir, sizeof outdir);
    }
    /* never over an earlier run without being asked; a restart continues its run in the checkpoint's folder */
    char checkpoint_dir[4096] = "";
    if (c.restart_path)
        folder_of(c.restart_path, checkpoint_dir, sizeof checkpoint_dir);
    const int continuing = c.restart_path && same_folder(outdir, checkpoint_dir);
    int claimed = 0;
    if (!continuing) {
        if (!c.output_dir && !c.restart_path && !c.overwrite)
            claimed = fresh_default_folder(outdir, sizeof outdir);
        else
            claimed = claim_folder(outdir, surge_is_run_file, c.overwrite, "an earlier run",
                                   c.restart_path ? "Choose another folder with -o"
                                                  : "Choose another folder with -o, or continue that run with "
                                                    "--restart FOLDER/checkpoint.bin");
    }
    if (claimed == 0 && c.frames_dir && !c.restart_path)
        claimed = claim_folder(c.frames_dir, surge_is_frame_file, c.overwrite, "frames of an earlier run",
                               "Choose another --frames folder");
    if (claimed == 0 && c.movie_path) /* a restart rewrites its movie with the frames before it */
        claimed = claim_movie(c.movie_path, c.overwrite || c.restart_path);
    if (claimed != 0) {
        surge_sim_destroy(sim);
        return EXIT_USAGE;
    }
    const surge_derived *d = surge_sim_derived(sim);
    fprintf(stderr, "surge: %s%s -> %s: %d fluid + %d wall particles, h = %.4g m, c0 = %.4g m/s, %d thread%s\n",
            c.restart_path ? "restart from " : "", c.restart_path ? c.restart_path
                                                   : (c.case_path ? c.case_path : "default scene (cases/demo.ini)"),
            outdir, d->fluid_count, d->wall_count, d->h_m, d->c0_mps, threads, threads == 1 ? "" : "s");
    warn_diffusive_compressibility(sim);
    report_resolution(sim, 0);
    live_links links;
    if (open_live_links(&c, outdir, sim, &links) != 0) {
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
    if (links.publisher || links.control || links.replay || links.renderer) {
        opt.at_step_boundary = at_step_boundary;
        opt.user = &links;
    }
    surge_run_result r = surge_run(sim, &opt, err, sizeof err);
    const int render_failed = close_live_links(&links, sim) != 0;
    const uint64_t hash = surge_sim_state_hash(sim);
    surge_sim_destroy(sim);
    if (links.replay_error[0]) {
        fprintf(stderr, "surge: %s\nsurge: the run stopped there; its outputs are in %s\n", links.replay_error, outdir);
        return EXIT_USAGE;
    }
    if (render_failed && (r == SURGE_RUN_FINISHED || r == SURGE_RUN_STOPPED))
        return EXIT_IO;
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
                        "%s/checkpoint.bin (continue with surge run --restart %s/checkpoint.bin)\n",
                (unsigned long long)hash, outdir, outdir);
        return EXIT_OK;
    case SURGE_RUN_INTERRUPTED:
        fprintf(stderr, "surge: interrupted; checkpoint written to %s/checkpoint.bin; continue with\n"
                        "  surge run --restart %s/checkpoint.bin\n", outdir, outdir);
        return EXIT_INTERRUPTED;
    case SURGE_RUN_IO_ERROR:
        fprintf(stderr, "surge: %s\n", err);
        return EXIT_IO;
    }
    return EXIT_IO;
}

/* Draws one snapshot into the frames folder and/or the movie. */
static int render_snapshot(surge_canvas *canvas, const surge_snapshot *snap, const surge_params *p,
                           const char *frames_dir, size_t index, surge_movie *movie, char *err, size_t err_len)
{
    const uint8_t *rgba = surge_canvas_draw(canvas, snap, p);
    if (!rgba) {
        snprintf(err, err_len, "cannot draw the snapshot of step %lld", (long long)snap->step);
        return -1;
    }
    if (frames_dir) {
        uint8_t *png;
        size_t len;
        char path[4200];
        snprintf(path, sizeof path, "%s/frame_%06zu.png", frames_dir, index);
        if (surge_canvas_png(canvas, &png, &len, err, err_len) != 0)
            return -1;
        FILE *f = fopen(path, "wb");
        const int ok = f && fwrite(png, 1, len, f) == len;
        if ((f && fclose(f) != 0) || !ok) {
            snprintf(err, err_len, "cannot write '%.900s': %s", path, strerror(errno));
            free(png);
            return -1;
        }
        free(png);
    }
    return movie ? surge_movie_add(movie, rgba, err, err_len) : 0;
}

/* Whether the -s assignment names the parameter name (or, with prefix, one that starts with it), spaces around the
 * name allowed as surge_params_override allows them */
static int override_sets(const char *assignment, const char *name, int prefix)
{
    const char *eq = strchr(assignment, '=');
    if (!eq)
        return 0;
    while (assignment < eq && isspace((unsigned char)*assignment))
        assignment++;
    while (eq > assignment && isspace((unsigned char)eq[-1]))
        eq--;
    const size_t len = (size_t)(eq - assignment), want = strlen(name);
    return prefix ? len >= want && strncmp(assignment, name, want) == 0
                  : len == want && strncmp(assignment, name, want) == 0;
}

static int command_render(int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        fputs(usage_render, stdout);
        return EXIT_OK;
    }
    cli c;
    if (parse_cli(argc, argv, &c, 1) != 0)
        return EXIT_USAGE;
    if (!c.case_path) {
        fprintf(stderr, "surge: render needs a RUN_DIR (a folder written by surge run)\n%s", usage_render);
        return EXIT_USAGE;
    }
    if (c.publish[0] || c.control[0] || c.restart_path || c.replay_path || c.threads || c.output_dir) {
        fprintf(stderr, "surge: render takes only --frames, --movie, --font, --overwrite and -s render.key=value\n");
        return EXIT_USAGE;
    }
    for (int i = 0; i < c.override_count; i++)
        if (!override_sets(c.overrides[i], "render.", 1)) {
            fprintf(stderr, "surge: render: '-s %s': only render.key=value can be set here (the run's other "
                            "parameters are what it was run with)\n", c.overrides[i]);
            return EXIT_USAGE;
        }
    char path[4200], err[1024], frames_dir[4200];
    cli with_params = c;
    snprintf(path, sizeof path, "%s/params.ini", c.case_path);
    with_params.case_path = path;
    surge_params p;
    if (load_case(&with_params, &p) != 0)
        return EXIT_USAGE;
    snprintf(path, sizeof path, "%s/run.pvd", c.case_path);
    surge_pvd *pvd = surge_pvd_read(path, err, sizeof err);
    if (!pvd) {
        fprintf(stderr, "surge: %s\n", err);
        return EXIT_USAGE;
    }
    /* the snapshots to draw: all, or with render.frame_interval_s on the command line one per interval */
    size_t count = 0;
    size_t *drawn = malloc((surge_pvd_count(pvd) + 1) * sizeof *drawn);
    if (!drawn) {
        fprintf(stderr, "surge: out of memory\n");
        surge_pvd_close(pvd);
        return EXIT_IO;
    }
    int every_interval = 0;
    for (int i = 0; i < c.override_count; i++)
        every_interval |= override_sets(c.overrides[i], "render.frame_interval_s", 0);
    const double interval_s = p.render.frame_interval_s;
    double next_frame_s = -INFINITY;
    for (size_t i = 0; i < surge_pvd_count(pvd); i++) {
        const double t = surge_pvd_time_s(pvd, i);
        if (every_interval && t < next_frame_s)
            continue;
        drawn[count++] = i;
        next_frame_s = (floor(t / interval_s + 1e-9) + 1.0) * interval_s;
    }
    if (!c.frames_dir && !c.movie_path) {
        snprintf(frames_dir, sizeof frames_dir, "%s/frames", c.case_path);
        c.frames_dir = frames_dir;
    }
    int claimed = c.frames_dir ? claim_folder(c.frames_dir, surge_is_frame_file, c.overwrite, "frames",
                                              "Choose another --frames folder") : 0;
    if (claimed == 0 && c.movie_path)
        claimed = claim_movie(c.movie_path, c.overwrite);
    if (claimed != 0) {
        surge_pvd_close(pvd);
        free(drawn);
        return EXIT_USAGE;
    }
    if (c.frames_dir && surge_make_folders(c.frames_dir, "the frames", err, sizeof err) != 0) {
        fprintf(stderr, "surge: %s\n", err);
        surge_pvd_close(pvd);
        free(drawn);
        return EXIT_IO;
    }
    if (surge_pvd_count(pvd) > 0) {
        snprintf(path, sizeof path, "%s/%s", c.case_path, surge_pvd_file(pvd, 0));
        if (fit_frame_height(&p, NULL, path, err, sizeof err) != 0) {
            fprintf(stderr, "surge: %s\n", err);
            surge_pvd_close(pvd);
            free(drawn);
            return EXIT_USAGE;
        }
    }
    surge_canvas *canvas = surge_canvas_create(p.render.width_px, p.render.height_px, c.font_path, err, sizeof err);
    surge_movie *movie = NULL;
    if (!canvas || (c.movie_path && !(movie = surge_movie_open(c.movie_path, p.render.width_px, p.render.height_px,
                                                                 p.render.movie_fps, err, sizeof err)))) {
        fprintf(stderr, "surge: %s\n", err);
        surge_canvas_destroy(canvas);
        surge_pvd_close(pvd);
        free(drawn);
        return EXIT_IO;
    }
    surge_snapshot snap = {0};
    int rc = EXIT_OK;
    const double start = surge_wall_clock_s();
    snprintf(path, sizeof path, "%s/boulders.pvd", c.case_path);
    FILE *boulders_pvd = fopen(path, "r"); /* written by runs with boulders only */
    const int has_boulders = boulders_pvd != NULL;
    if (boulders_pvd)
        fclose(boulders_pvd);
    /* an automatic colour range is the range of all the frames, so that a colour means one value all through the
     * movie (each frame's own range, as a live run must use, changed meanings; issue #24) */
    if (!(p.render.color_max > p.render.color_min)) {
        double low = INFINITY, high = -INFINITY;
        for (size_t i = 0; i < count && rc == EXIT_OK; i++) {
            snprintf(path, sizeof path, "%s/%s", c.case_path, surge_pvd_file(pvd, drawn[i]));
            const surge_canvas_layout *l = NULL;
            if (surge_vtp_read(path, &snap, err, sizeof err) != 0)
                rc = EXIT_USAGE;
            else if ((l = surge_canvas_layout_only(canvas, &snap, &p)) != NULL && isfinite(l->field_min))
                low = fmin(low, l->field_min), high = fmax(high, l->field_max);
        }
        if (high > low) {
            surge_render_round_range(&low, &high);
            p.render.color_min = low;
            p.render.color_max = high;
            fprintf(stderr, "surge: colour range %.4g .. %.4g over all %zu frames (set render.color_min and "
                            "render.color_max to choose it)\n", low, high, count);
        }
    }
    for (size_t i = 0; i < count && rc == EXIT_OK; i++) {
        const char *file = surge_pvd_file(pvd, drawn[i]);
        snprintf(path, sizeof path, "%s/%s", c.case_path, file);
        if (surge_vtp_read(path, &snap, err, sizeof err) != 0) {
            rc = EXIT_USAGE;
        } else if (has_boulders && strncmp(file, "snap_", 5) == 0 &&
                   (snprintf(path, sizeof path, "%s/boulders_%s", c.case_path, file + 5),
                    surge_vtp_read_boulders(path, &snap, err, sizeof err) != 0)) {
            rc = EXIT_USAGE; /* the boulders written next to the snapshot, for their orientation marks */
        } else if (render_snapshot(canvas, &snap, &p, c.frames_dir, i, movie, err, sizeof err) != 0) {
            rc = EXIT_IO;
        }
    }
    if (rc != EXIT_OK)
        fprintf(stderr, "surge: %s\n", err);
    if (movie && surge_movie_close(movie, err, sizeof err) != 0) {
        fprintf(stderr, "surge: %s\n", err);
        rc = rc == EXIT_OK ? EXIT_IO : rc;
    }
    const double elapsed = surge_wall_clock_s() - start;
    if (rc == EXIT_OK)
        fprintf(stderr, "surge: rendered %zu snapshots of %s in %.1f s (%.1f frames/s)%s%s%s%s\n", count, c.case_path,
                elapsed, elapsed > 0 ? count / elapsed : 0, c.frames_dir ? ": frames in " : "",
                c.frames_dir ? c.frames_dir : "", c.movie_path ? ", movie " : "", c.movie_path ? c.movie_path : "");
    free(drawn);
    surge_snapshot_free(&snap);
    surge_canvas_destroy(canvas);
    surge_pvd_close(pvd);
    return rc;
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
        print_case_error(&c, err);
        return EXIT_USAGE;
    }
    const surge_derived *d = surge_sim_derived(sim);
    const surge_params *resolved = surge_sim_params(sim);
    const char *c0_from = resolved->numerics.c0_mps > 0 ? "set by numerics.c0_mps"
                          : d->c0_mps > resolved->numerics.c0_factor * d->expected_speed_mps ? "set by the head"
                                                                                             : "set by the speed";
    printf("%s: ok: %d fluid + %d wall particles, h = %.6g m, c0 = %.6g m/s (%s; expected speed %.4g m/s; "
           "c0_factor x the hydrostatic head's speed sqrt(g H): %.4g m/s, 1 %% density at factor 10)\n", c.case_path,
           d->fluid_count, d->wall_count, d->h_m, d->c0_mps, c0_from, d->expected_speed_mps, d->head_c0_mps);
    report_resolution(sim, 1);
    warn_diffusive_compressibility(sim);
    surge_sim_destroy(sim);
    return EXIT_OK;
}

/* While they wait at a barrier, libgomp's threads spin (OMP_WAIT_POLICY unset: about 300,000 times before they
 * sleep), which on cores shared with other work starves the thread the others wait for: a run that takes minutes
 * can take hours (issue #24). libgomp reads the variable before main, so a run without the user's own setting
 * executes itself again, once, with OMP_WAIT_POLICY=PASSIVE (docs/performance.md measures both). */
static void prefer_passive_wait(char **argv)
{
    if (getenv("OMP_WAIT_POLICY") || setenv("OMP_WAIT_POLICY", "PASSIVE", 1) != 0)
        return;
    execv("/proc/self/exe", argv);
    unsetenv("OMP_WAIT_POLICY"); /* no /proc: go on with libgomp's default */
}

/* The soft limit on open files up to the hard one: each connection to the control or publisher socket takes a
 * file descriptor, and a table filled by idle connections (1,024 on many machines) made the next snapshot write
 * fail (issue #24, D2). */
static void raise_open_file_limit(void)
{
    struct rlimit limit;
    if (getrlimit(RLIMIT_NOFILE, &limit) == 0 && limit.rlim_cur < limit.rlim_max) {
        limit.rlim_cur = limit.rlim_max;
        setrlimit(RLIMIT_NOFILE, &limit);
    }
}

int main(int argc, char **argv)
{
    if (argc >= 2 && (!strcmp(argv[1], "run") || !strcmp(argv[1], "render")))
        prefer_passive_wait(argv);
    raise_open_file_limit();
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        fputs(usage_main, argc < 2 ? stderr : stdout);
        return argc < 2 ? EXIT_USAGE : EXIT_OK;
    }
    if (!strcmp(argv[1], "run"))
        return command_run(argc - 2, argv + 2);
    if (!strcmp(argv[1], "check"))
        return command_check(argc - 2, argv + 2);
    if (!strcmp(argv[1], "render"))
        return command_render(argc - 2, argv + 2);
    if (!strcmp(argv[1], "keygen")) {
        if (wants_help(argc - 2, argv + 2)) {
            fputs(usage_keygen, stdout);
            return EXIT_OK;
        }
        if (argc != 3 || argv[2][0] == '\0' || argv[2][0] == '-') {
            fprintf(stderr, "surge: keygen needs one NAME (it writes NAME.key and NAME.pub)\n%s", usage_keygen);
            return EXIT_USAGE;
        }
        char err[1024];
        if (surge_curve_write_key_pair(argv[2], err, sizeof err) != 0) {
            fprintf(stderr, "surge: keygen: %s\n", err);
            return EXIT_IO;
        }
        printf("surge: wrote %s.key (secret, mode 0600) and %s.pub (public)\n", argv[2], argv[2]);
        return EXIT_OK;
    }
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
    if (!strcmp(argv[1], "version") || !strcmp(argv[1], "--version")) {
        if (wants_help(argc - 2, argv + 2)) {
            fputs(usage_version, stdout);
            return EXIT_OK;
        }
        if (argc > 2) {
            fprintf(stderr, "surge: version takes no arguments\n");
            return EXIT_USAGE;
        }
        char machine[512];
        surge_machine_description(machine, sizeof machine);
        printf("program: %s\nmachine: %s\n", surge_build_description(), machine);
        return EXIT_OK;
    }
    fprintf(stderr, "surge: unknown command '%s'\n%s", argv[1], usage_main);
    return EXIT_USAGE;
}
