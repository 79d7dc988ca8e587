/* surge run: a case (or a checkpoint) run to its end, with its outputs, live links and rendering. */
#include "cli.h"

#include <omp.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>

#include "live_links.h"
#include "surge/platform.h"
#include "surge/run.h"
#include "surge/run_folder.h"

static const char *usage_run =
    "usage: surge run [CASE] [-s section.key=value ...] [-o OUTDIR] [--threads N]\n"
    "       surge run --restart CHECKPOINT [-s section.key=value ...] [-o OUTDIR] [--threads N]\n"
    "\n"
    "Runs CASE (default: the demo scene, a debris surge with boulders, which also writes OUTDIR/frames/ and\n"
    "OUTDIR/movie.mp4) and writes to OUTDIR (default: runs/<case name>):\n"
    "  params.ini       the full resolved parameter set\n"
    "  snap_*.vtp       particle snapshots (VTK PolyData), listed with their times in run.pvd for ParaView\n"
    "  diagnostics.csv  time series (energy, max speed, density deviation, fluid volume...)\n"
    "  checkpoint.bin   state to continue from with --restart (final, and every output.checkpoint_interval_s)\n"
    "  last_good.vtp    only when the health monitor stopped the run: the last healthy state, and\n"
    "  last_good.bin    the same as a checkpoint (checkpoint.bin keeps the last periodic one)\n"
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

static volatile sig_atomic_t stop_requested = 0;
static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

/* The solver, from the checkpoint or the case, and the folder its outputs go to; EXIT_OK or the exit status. */
static int create_simulation(const cli *c, surge_sim **sim, char *outdir, size_t len)
{
    char err[1024];
    if (c->restart_path) {
        *sim = surge_sim_checkpoint_read(c->restart_path, c->overrides, c->override_count, err, sizeof err);
        if (!*sim) {
            fprintf(stderr, "surge: %s\n", err);
            return EXIT_USAGE;
        }
        if (c->output_dir)
            snprintf(outdir, len, "%s", c->output_dir);
        else
            folder_of(c->restart_path, outdir, len);
        return EXIT_OK;
    }
    surge_params p;
    if (load_case(c, &p) != 0)
        return EXIT_USAGE;
    *sim = surge_sim_create(&p, err, sizeof err);
    if (!*sim) {
        print_case_error(c, err);
        return EXIT_USAGE;
    }
    if (c->output_dir)
        snprintf(outdir, len, "%s", c->output_dir);
    else
        default_output_dir(c->case_path, outdir, len);
    return EXIT_OK;
}

/* Never over an earlier run, its frames or its movie without being asked; a restart continues its run in the
 * checkpoint's folder. Without -o, a run goes to the first fresh runs/<case name>-N. 0, or -1 with the message
 * printed. */
static int claim_run_outputs(const cli *c, char *outdir, size_t len)
{
    char checkpoint_dir[4096] = "";
    if (c->restart_path)
        folder_of(c->restart_path, checkpoint_dir, sizeof checkpoint_dir);
    const int continuing = c->restart_path && same_folder(outdir, checkpoint_dir);
    int claimed = 0;
    if (!continuing) {
        if (!c->output_dir && !c->restart_path && !c->overwrite)
            claimed = fresh_default_folder(outdir, len);
        else
            claimed = claim_folder(outdir, surge_is_run_file, c->overwrite, "an earlier run",
                                   c->restart_path ? "Choose another folder with -o"
                                                   : "Choose another folder with -o, or continue that run with "
                                                     "--restart FOLDER/checkpoint.bin");
    }
    if (claimed == 0 && c->frames_dir && !c->restart_path)
        claimed = claim_folder(c->frames_dir, surge_is_frame_file, c->overwrite, "frames of an earlier run",
                               "Choose another --frames folder");
    if (claimed == 0 && c->movie_path) /* a restart rewrites its movie with the frames before it */
        claimed = claim_movie(c->movie_path, c->overwrite || c->restart_path);
    return claimed;
}

static void print_run_start(const cli *c, const surge_sim *sim, const char *outdir, int threads)
{
    const surge_derived *d = surge_sim_derived(sim);
    fprintf(stderr, "surge: %s%s -> %s: %d fluid + %d wall particles, h = %.4g m, c0 = %.4g m/s, %d thread%s\n",
            c->restart_path ? "restart from " : "", c->restart_path ? c->restart_path
                                                    : (c->case_path ? c->case_path : "default scene (cases/demo.ini)"),
            outdir, d->fluid_count, d->wall_count, d->h_m, d->c0_mps, threads, threads == 1 ? "" : "s");
}

/* The default scene (no case, no restart) renders its frames and movie into its run folder unless the user chose
 * where: OUTDIR/frames and OUTDIR/movie.mp4. 0, or -1 with the message printed. */
static int render_default_scene(cli *c, const char *outdir)
{
    if (c->case_path || c->restart_path || c->frames_dir || c->movie_path)
        return 0;
    snprintf(c->default_frames_dir, sizeof c->default_frames_dir, "%s/frames", outdir);
    snprintf(c->default_movie_path, sizeof c->default_movie_path, "%s/movie.mp4", outdir);
    c->frames_dir = c->default_frames_dir;
    c->movie_path = c->default_movie_path;
    char err[1024];
    if (surge_make_folders(outdir, "the output", err, sizeof err) != 0) {
        fprintf(stderr, "surge: %s\n", err);
        return -1;
    }
    if (claim_folder(c->frames_dir, surge_is_frame_file, c->overwrite, "frames of an earlier run",
                     "Choose another --frames folder") != 0)
        return -1;
    return claim_movie(c->movie_path, c->overwrite);
}

/* Whether outdir holds a checkpoint.bin, the periodic one a health stop leaves in place */
static int periodic_checkpoint_kept(const char *outdir)
{
    char path[4096 + 32];
    snprintf(path, sizeof path, "%.4096s/checkpoint.bin", outdir);
    FILE *f = fopen(path, "rb");
    if (f)
        fclose(f);
    return f != NULL;
}

/* How the run ended, said; returns the exit status. */
static int report_run_end(const cli *c, surge_run_result r, const char *err, const char *outdir, uint64_t hash)
{
    switch (r) {
    case SURGE_RUN_FINISHED:
        if (c->frames_dir == c->default_frames_dir) /* the main job says where its results are */
            fprintf(stderr, "surge: the movie is %s, its frames in %s; the surge's Froude number and mu_eq/mu0 are in "
                            "%s/flow.csv, the discs in %s/boulders.csv; open %s/run.pvd in ParaView\n",
                    c->default_movie_path, c->default_frames_dir, outdir, outdir, outdir);
        fprintf(stderr, "surge: done, state hash %016llx, outputs in %s\n", (unsigned long long)hash, outdir);
        return EXIT_OK;
    case SURGE_RUN_UNHEALTHY:
        fprintf(stderr, "surge: %s\nsurge: last good state written to %s/last_good.vtp and %s/last_good.bin (continue "
                        "from it with surge run --restart %s/last_good.bin and a setting that lets it through)%s\n",
                err, outdir, outdir, outdir,
                periodic_checkpoint_kept(outdir) ? "; checkpoint.bin keeps the last periodic checkpoint" : "");
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

/* Runs sim with its live links until it ends, stops or fails, and destroys it; returns the exit status. */
static int run_with_live_links(const cli *c, surge_sim *sim, const char *outdir, int threads)
{
    live_links links;
    if (open_live_links(c, outdir, sim, &stop_requested, &links) != 0) {
        close_live_links(&links, sim);
        surge_sim_destroy(sim);
        return EXIT_USAGE;
    }
    if (links.publisher)
        fprintf(stderr, "surge: publishing state, bodies and stats on %s\n", surge_publisher_endpoint(links.publisher));
    if (links.control)
        fprintf(stderr, "surge: control socket on %s%s\n", surge_control_endpoint(links.control),
                c->paused ? " (paused: send resume or step)" : "");
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    surge_run_options opt = surge_default_run_options();
    opt.output_dir = outdir;
    opt.threads = threads;
    opt.restarted = c->restart_path != NULL;
    opt.stop = &stop_requested;
    if (links.publisher || links.control || links.replay || links.renderer) {
        opt.at_step_boundary = at_step_boundary;
        opt.user = &links;
    }
    char err[1024];
    surge_run_result r = surge_run(sim, &opt, err, sizeof err);
    const int render_failed = close_live_links(&links, sim) != 0;
    const uint64_t hash = surge_sim_state_hash(sim);
    const int64_t halvings = surge_sim_diagnostics(sim).step_halvings;
    if (halvings > 0)
        fprintf(stderr, "surge: %lld times a step was taken again at half its length (implicit.step_halvings; "
                        "docs/method.md, \"Health monitor\")\n", (long long)halvings);
    surge_sim_destroy(sim);
    if (links.replay_error[0]) {
        fprintf(stderr, "surge: %s\nsurge: the run stopped there; its outputs are in %s\n", links.replay_error, outdir);
        return EXIT_USAGE;
    }
    if (render_failed && (r == SURGE_RUN_FINISHED || r == SURGE_RUN_STOPPED))
        return EXIT_IO;
    return report_run_end(c, r, err, outdir, hash);
}

int command_run(int argc, char **argv)
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
    char outdir[4096];
    surge_sim *sim = NULL;
    const int created = create_simulation(&c, &sim, outdir, sizeof outdir);
    if (created != EXIT_OK)
        return created;
    if (claim_run_outputs(&c, outdir, sizeof outdir) != 0 || render_default_scene(&c, outdir) != 0) {
        surge_sim_destroy(sim);
        return EXIT_USAGE;
    }
    print_run_start(&c, sim, outdir, threads);
    warn_diffusive_compressibility(sim);
    report_resolution(sim, 0);
    return run_with_live_links(&c, sim, outdir, threads);
}
