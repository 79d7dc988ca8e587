/* surge render: a finished run's snapshots drawn as PNG frames and/or a movie. */
#include "cli.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "surge/platform.h"
#include "surge/render.h"
#include "surge/run_folder.h"
#include "surge/vtk_output.h"

static const char *usage_render =
    "usage: surge render RUN_DIR [--frames DIR] [--movie FILE] [-s render.key=value ...] [--font FILE]\n"
    "                    [--overwrite]\n"
    "\n"
    "Renders every snapshot listed in RUN_DIR/run.pvd with the run's parameters (RUN_DIR/params.ini) and\n"
    "the overrides, as PNG frames (frame_NNNNNN.png, one per snapshot, listed in frames.csv) and/or a movie\n"
    "at render.movie_fps.\n"
    "With -s render.frame_interval_s=T, one snapshot per T of simulated time instead (the first at or after\n"
    "each multiple of T). Without --frames or --movie, frames go to RUN_DIR/frames.\n";

enum { PATH_BYTES = 4200 };

/* A rendering of the run in c.case_path (RUN_DIR) and what it holds open. */
typedef struct render_job {
    cli c;
    surge_params p;         /* the run's parameters with the render overrides */
    surge_pvd *pvd;         /* RUN_DIR/run.pvd */
    size_t *drawn, count;   /* the snapshots to draw, as indices into pvd */
    surge_canvas *canvas;
    surge_movie *movie;     /* NULL: no movie */
    surge_snapshot snap;
    char frames_dir[PATH_BYTES]; /* the default frames folder, RUN_DIR/frames */
    char err[1024];
} render_job;

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

/* A RUN_DIR, no run options, and only render.key=value overrides; 0, or -1 with the message printed. */
static int check_render_options(const cli *c)
{
    if (!c->case_path) {
        fprintf(stderr, "surge: render needs a RUN_DIR (a folder written by surge run)\n%s", usage_render);
        return -1;
    }
    if (c->publish[0] || c->control[0] || c->restart_path || c->replay_path || c->threads || c->output_dir) {
        fprintf(stderr, "surge: render takes only --frames, --movie, --font, --overwrite and -s render.key=value\n");
        return -1;
    }
    for (int i = 0; i < c->override_count; i++)
        if (!override_sets(c->overrides[i], "render.", 1)) {
            fprintf(stderr, "surge: render: '-s %s': only render.key=value can be set here (the run's other "
                            "parameters are what it was run with)\n", c->overrides[i]);
            return -1;
        }
    return 0;
}

/* The snapshots to draw: all, or with render.frame_interval_s on the command line one per interval. */
static void select_snapshots(render_job *job)
{
    int every_interval = 0;
    for (int i = 0; i < job->c.override_count; i++)
        every_interval |= override_sets(job->c.overrides[i], "render.frame_interval_s", 0);
    const double interval_s = job->p.render.frame_interval_s;
    double next_frame_s = -INFINITY;
    for (size_t i = 0; i < surge_pvd_count(job->pvd); i++) {
        const double t = surge_pvd_time_s(job->pvd, i);
        if (every_interval && t < next_frame_s)
            continue;
        job->drawn[job->count++] = i;
        next_frame_s = (floor(t / interval_s + 1e-9) + 1.0) * interval_s;
    }
}

/* The run's parameters (with the overrides) and its list of snapshots; EXIT_OK or the exit status. */
static int read_run(render_job *job)
{
    char path[PATH_BYTES];
    cli with_params = job->c;
    snprintf(path, sizeof path, "%s/params.ini", job->c.case_path);
    with_params.case_path = path;
    if (load_case(&with_params, &job->p) != 0)
        return EXIT_USAGE;
    snprintf(path, sizeof path, "%s/run.pvd", job->c.case_path);
    job->pvd = surge_pvd_read(path, job->err, sizeof job->err);
    if (!job->pvd) {
        fprintf(stderr, "surge: %s\n", job->err);
        return EXIT_USAGE;
    }
    if (surge_pvd_count(job->pvd) == 0) {
        fprintf(stderr, "surge: %s lists no snapshot: nothing to render\n", path);
        return EXIT_USAGE;
    }
    job->drawn = malloc((surge_pvd_count(job->pvd) + 1) * sizeof *job->drawn);
    if (!job->drawn) {
        fprintf(stderr, "surge: out of memory\n");
        return EXIT_IO;
    }
    select_snapshots(job);
    return EXIT_OK;
}

/* The frames folder (RUN_DIR/frames without --frames or --movie) and the movie, claimed and the folder made;
 * EXIT_OK or the exit status. */
static int prepare_outputs(render_job *job)
{
    cli *c = &job->c;
    if (!c->frames_dir && !c->movie_path) {
        snprintf(job->frames_dir, sizeof job->frames_dir, "%s/frames", c->case_path);
        c->frames_dir = job->frames_dir;
    }
    int claimed = c->frames_dir ? claim_folder(c->frames_dir, surge_is_frame_file, c->overwrite, "frames",
                                               "Choose another --frames folder") : 0;
    if (claimed == 0 && c->movie_path)
        claimed = claim_movie(c->movie_path, c->overwrite);
    if (claimed != 0)
        return EXIT_USAGE;
    if (c->frames_dir && surge_make_folders(c->frames_dir, "the frames", job->err, sizeof job->err) != 0) {
        fprintf(stderr, "surge: %s\n", job->err);
        return EXIT_IO;
    }
    return EXIT_OK;
}

/* The canvas (its height fitted to the first snapshot unless set) and the movie; EXIT_OK or the exit status. */
static int open_canvas(render_job *job)
{
    char path[PATH_BYTES];
    surge_params *p = &job->p;
    if (surge_pvd_count(job->pvd) > 0) {
        snprintf(path, sizeof path, "%s/%s", job->c.case_path, surge_pvd_file(job->pvd, 0));
        if (fit_frame_height(p, NULL, path, job->err, sizeof job->err) != 0) {
            fprintf(stderr, "surge: %s\n", job->err);
            return EXIT_USAGE;
        }
    }
    job->canvas = surge_canvas_create(p->render.width_px, p->render.height_px, job->c.font_path, job->err,
                                      sizeof job->err);
    if (!job->canvas ||
        (job->c.movie_path && !(job->movie = surge_movie_open(job->c.movie_path, p->render.width_px,
                                                              p->render.height_px, p->render.movie_fps, job->err,
                                                              sizeof job->err)))) {
        fprintf(stderr, "surge: %s\n", job->err);
        return EXIT_IO;
    }
    return EXIT_OK;
}

/* Whether the run wrote its boulders next to its snapshots (runs with boulders only). */
static int has_boulder_files(const char *run_dir)
{
    char path[PATH_BYTES];
    snprintf(path, sizeof path, "%s/boulders.pvd", run_dir);
    FILE *boulders_pvd = fopen(path, "r");
    if (!boulders_pvd)
        return 0;
    fclose(boulders_pvd);
    return 1;
}

/* An automatic colour range is the range of all the frames, so that a colour means one value all through the
 * movie (each frame's own range, as a live run must use, changed meanings). EXIT_OK or EXIT_USAGE. */
static int fix_colour_range(render_job *job)
{
    surge_params *p = &job->p;
    if (p->render.color_max > p->render.color_min)
        return EXIT_OK;
    char path[PATH_BYTES];
    int rc = EXIT_OK;
    double low = INFINITY, high = -INFINITY;
    for (size_t i = 0; i < job->count && rc == EXIT_OK; i++) {
        snprintf(path, sizeof path, "%s/%s", job->c.case_path, surge_pvd_file(job->pvd, job->drawn[i]));
        const surge_canvas_layout *l = NULL;
        if (surge_vtp_read(path, &job->snap, job->err, sizeof job->err) != 0)
            rc = EXIT_USAGE;
        else if ((l = surge_canvas_layout_only(job->canvas, &job->snap, p)) != NULL && isfinite(l->field_min))
            low = fmin(low, l->field_min), high = fmax(high, l->field_max);
    }
    if (high > low) {
        surge_render_round_range(&low, &high);
        p->render.color_min = low;
        p->render.color_max = high;
        fprintf(stderr, "surge: colour range %.4g .. %.4g over all %zu frames (set render.color_min and "
                        "render.color_max to choose it)\n", low, high, job->count);
    }
    return rc;
}

/* Draws one snapshot into the frames folder, listed in its frames.csv (frame,step,time_s, as a live run writes
 * it), and/or the movie. */
static int render_snapshot(surge_canvas *canvas, const surge_snapshot *snap, const surge_params *p,
                           const char *frames_dir, size_t index_number, surge_movie *movie, char *err, size_t err_len)
{
    const uint8_t *rgba = surge_canvas_draw(canvas, snap, p);
    if (!rgba) {
        snprintf(err, err_len, "cannot draw the snapshot of step %lld", (long long)snap->step);
        return -1;
    }
    if (frames_dir) {
        uint8_t *png;
        size_t len;
        char path[PATH_BYTES];
        snprintf(path, sizeof path, "%s/frame_%06zu.png", frames_dir, index_number);
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
        snprintf(path, sizeof path, "%s/frames.csv", frames_dir);
        FILE *index = fopen(path, index_number == 0 ? "w" : "a");
        const int listed = index && (index_number > 0 || fputs("frame,step,time_s\n", index) >= 0) &&
                           fprintf(index, "%zu,%lld,%.17g\n", index_number, (long long)snap->step, snap->time_s) > 0;
        if ((index && fclose(index) != 0) || !listed) {
            snprintf(err, err_len, "cannot write '%.900s': %s", path, strerror(errno));
            return -1;
        }
    }
    return movie ? surge_movie_add(movie, rgba, err, err_len) : 0;
}

/* Reads and draws each chosen snapshot, with the boulders written next to it for their orientation marks;
 * EXIT_OK or the exit status. */
static int draw_snapshots(render_job *job, int has_boulders)
{
    char path[PATH_BYTES];
    const char *run_dir = job->c.case_path;
    for (size_t i = 0; i < job->count; i++) {
        const char *file = surge_pvd_file(job->pvd, job->drawn[i]);
        snprintf(path, sizeof path, "%s/%s", run_dir, file);
        if (surge_vtp_read(path, &job->snap, job->err, sizeof job->err) != 0)
            return EXIT_USAGE;
        if (has_boulders && strncmp(file, "snap_", 5) == 0 &&
            (snprintf(path, sizeof path, "%s/boulders_%s", run_dir, file + 5),
             surge_vtp_read_boulders(path, &job->snap, job->err, sizeof job->err) != 0))
            return EXIT_USAGE;
        if (render_snapshot(job->canvas, &job->snap, &job->p, job->c.frames_dir, i, job->movie, job->err,
                            sizeof job->err) != 0)
            return EXIT_IO;
    }
    return EXIT_OK;
}

/* The colour range, the frames and the movie, and what was rendered, said; EXIT_OK or the exit status. */
static int render_run(render_job *job)
{
    const cli *c = &job->c;
    const double start = surge_wall_clock_s();
    const int has_boulders = has_boulder_files(c->case_path);
    int rc = fix_colour_range(job);
    if (rc == EXIT_OK)
        rc = draw_snapshots(job, has_boulders);
    if (rc != EXIT_OK)
        fprintf(stderr, "surge: %s\n", job->err);
    if (job->movie && surge_movie_close(job->movie, job->err, sizeof job->err) != 0) {
        fprintf(stderr, "surge: %s\n", job->err);
        rc = rc == EXIT_OK ? EXIT_IO : rc;
    }
    job->movie = NULL;
    const double elapsed = surge_wall_clock_s() - start;
    if (rc == EXIT_OK)
        fprintf(stderr, "surge: rendered %zu snapshots of %s in %.1f s (%.1f frames/s)%s%s%s%s\n", job->count,
                c->case_path, elapsed, elapsed > 0 ? job->count / elapsed : 0,
                c->frames_dir ? ": frames in " : "", c->frames_dir ? c->frames_dir : "",
                c->movie_path ? ", movie " : "", c->movie_path ? c->movie_path : "");
    return rc;
}

/* Frees what the job holds; its movie is closed by render_run or was never opened. */
static void close_render_job(render_job *job)
{
    free(job->drawn);
    surge_snapshot_free(&job->snap);
    surge_canvas_destroy(job->canvas);
    surge_pvd_close(job->pvd);
}

int command_render(int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        fputs(usage_render, stdout);
        return EXIT_OK;
    }
    render_job job;
    memset(&job, 0, sizeof job);
    if (parse_cli(argc, argv, &job.c, 1) != 0 || check_render_options(&job.c) != 0)
        return EXIT_USAGE;
    int rc = read_run(&job);
    if (rc == EXIT_OK)
        rc = prepare_outputs(&job);
    if (rc == EXIT_OK)
        rc = open_canvas(&job);
    if (rc == EXIT_OK)
        rc = render_run(&job);
    close_render_job(&job);
    return rc;
}
