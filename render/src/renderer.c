/* Rendering alongside the solver: a thread with its own canvas, fed by a mailbox (see surge/render.h). */
#define _POSIX_C_SOURCE 200809L
#include "surge/platform.h"
#include "surge/render.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "png_io.h"
#include "surge/mailbox.h"

struct surge_renderer {
    surge_renderer_def def;
    char frames_dir[4096];
    surge_canvas *canvas;
    surge_movie *movie;
    surge_mailbox *mailbox;
    pthread_t thread;
    atomic_int finishing;
    double next_frame_s; /* solver thread: simulated time of the next frame due */
    /* renderer thread */
    uint64_t last_sequence, frames_drawn, movie_frames, movie_frames_before_restart;
    uint64_t first_frame_number; /* 0, or after the frames already in the folder (continue_frames) */
    FILE *index;                 /* frames.csv: frame,step,time_s of each PNG written */
    double draw_s, encode_s;
    char error[1024]; /* the first failure; later frames are not attempted */
};

static int write_file(const char *path, const uint8_t *data, size_t len, char *err, size_t err_len)
{
    char tmp[4300];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    int ok = f && fwrite(data, 1, len, f) == len;
    ok = (f == NULL || fclose(f) == 0) && ok && rename(tmp, path) == 0;
    if (!ok) {
        snprintf(err, err_len, "cannot write the frame '%.900s': %s", path, strerror(errno));
        remove(tmp);
        return -1;
    }
    return 0;
}

/* Draws one frame and writes it everywhere it goes; frames skipped since the previous one repeat the
 * previous image in the movie, so the movie keeps simulated time. */
static int render_frame(surge_renderer *r, const surge_frame *f)
{
    char *err = r->error;
    const size_t err_len = sizeof r->error;
    if (r->movie && r->frames_drawn > 0)
        for (uint64_t k = r->last_sequence + 1; k < f->sequence; k++, r->movie_frames++)
            if (surge_movie_add(r->movie, surge_canvas_pixels(r->canvas), err, err_len) != 0)
                return -1;
    const double t0 = surge_wall_clock_s();
    const uint8_t *rgba = surge_canvas_draw(r->canvas, &f->snap, &f->params);
    const double t1 = surge_wall_clock_s();
    r->draw_s += t1 - t0;
    if (!rgba) {
        snprintf(err, err_len, "cannot draw the frame of step %lld", (long long)f->diag.step);
        return -1;
    }
    r->frames_drawn++;
    r->last_sequence = f->sequence;
    if (r->frames_dir[0] || r->def.on_frame) {
        uint8_t *png = NULL;
        size_t len = 0;
        if (surge_canvas_png(r->canvas, &png, &len, err, err_len) != 0)
            return -1;
        int rc = 0;
        if (r->frames_dir[0]) {
            char path[4200];
            snprintf(path, sizeof path, "%s/frame_%06llu.png", r->frames_dir,
                     (unsigned long long)(r->first_frame_number + f->sequence - 1));
            rc = write_file(path, png, len, err, err_len);
            if (rc == 0 && (fprintf(r->index, "%llu,%lld,%.17g\n", (unsigned long long)(r->first_frame_number +
                            f->sequence - 1), (long long)f->diag.step, f->diag.time_s) < 0 || fflush(r->index) != 0)) {
                snprintf(err, err_len, "cannot write '%.900s/frames.csv': %s", r->frames_dir, strerror(errno));
                rc = -1;
            }
        }
        if (rc == 0 && r->def.on_frame)
            r->def.on_frame(png, len, f->diag.step, f->diag.time_s, r->def.user);
        free(png);
        if (rc != 0)
            return -1;
    }
    if (r->movie) {
        if (surge_movie_add(r->movie, rgba, err, err_len) != 0)
            return -1;
        r->movie_frames++;
    }
    r->encode_s += surge_wall_clock_s() - t1;
    return 0;
}

static void *renderer_main(void *arg)
{
    surge_renderer *r = arg;
    if (surge_canvas_bind(r->canvas) != 0) {
        snprintf(r->error, sizeof r->error, "cannot make the OSMesa context current in the renderer thread");
        return NULL;
    }
    for (;;) {
        const int finishing = atomic_load(&r->finishing); /* before the take: see publisher_main */
        const surge_frame *f = surge_mailbox_take(r->mailbox, 0.1);
        if (f && !r->error[0])
            render_frame(r, f);
        else if (!f && finishing)
            return NULL;
    }
}

/* One past the highest N of the frame_N.png files already in path (0 in an empty folder). */
static uint64_t next_frame_number(const char *path)
{
    uint64_t next = 0;
    DIR *dir = opendir(path);
    if (!dir)
        return 0;
    for (struct dirent *e; (e = readdir(dir)) != NULL;) {
        unsigned long long n = 0;
        char tail[8] = "";
        if (sscanf(e->d_name, "frame_%llu%7s", &n, tail) == 2 && strcmp(tail, ".png") == 0 && n + 1 > next)
            next = n + 1;
    }
    closedir(dir);
    return next;
}

/* frames.csv rows to keep on restart: those drawn at or before the restart's time; the PNGs of the others are
 * removed, and the last kept frame's number and time are noted. */
typedef struct frame_index_trim {
    const char *frames_dir;
    double resume_time_s;
    long long last_kept_frame;
    double last_kept_time_s;
} frame_index_trim;

static int keep_frame_row(const char *line, void *context)
{
    frame_index_trim *trim = context;
    unsigned long long frame;
    long long step;
    double time_s;
    if (sscanf(line, "%llu,%lld,%lf", &frame, &step, &time_s) != 3)
        return 1; /* the header */
    if (time_s <= trim->resume_time_s) {
        if ((long long)frame > trim->last_kept_frame)
            trim->last_kept_frame = (long long)frame, trim->last_kept_time_s = time_s;
        return 1;
    }
    char path[4200];
    snprintf(path, sizeof path, "%s/frame_%06llu.png", trim->frames_dir, frame);
    remove(path);
    return 0;
}

/* Opens frames.csv for appending; on a restart first drops what the interrupted run drew after its checkpoint.
 * Sets the first frame number and, where frames.csv lists kept frames, the next frame's time. */
static int open_frame_index(surge_renderer *r, const surge_params *params, char *err, size_t err_len)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/frames.csv", r->frames_dir);
    if (r->def.continue_frames) {
        frame_index_trim trim = {r->frames_dir, r->def.resume_time_s, -1, 0};
        if (surge_file_keep_lines(path, keep_frame_row, &trim, err, err_len) != 0)
            return -1;
        r->first_frame_number = next_frame_number(r->frames_dir); /* frames.csv may not list older frames */
        if (trim.last_kept_frame >= 0) {
            const double interval = params->render.frame_interval_s;
            r->next_frame_s = (floor(trim.last_kept_time_s / interval + 1e-9) + 1.0) * interval;
        }
    } else if (remove(path) != 0 && errno != ENOENT) {
        snprintf(err, err_len, "cannot replace '%s': %s", path, strerror(errno));
        return -1;
    }
    r->index = fopen(path, "a");
    if (!r->index || fseek(r->index, 0, SEEK_END) != 0 ||
        (ftell(r->index) == 0 && fprintf(r->index, "frame,step,time_s\n") < 0)) {
        snprintf(err, err_len, "cannot write '%s': %s", path, strerror(errno));
        return -1;
    }
    return 0;
}

/* A restarted run's movie starts with the frames the interrupted run drew up to its checkpoint: the PNGs that
 * frames.csv lists (after the trim), in order. A number missing between two listed frames (skipped while the
 * renderer was busy) repeats the previous image, as it did live, so the movie keeps simulated time. With movie
 * NULL, only checks that each listed PNG can be read and has this run's size (before the movie is started). */
static int replay_kept_frames(surge_renderer *r, surge_movie *movie, int width, int height, char *err,
                              size_t err_len)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/frames.csv", r->frames_dir);
    FILE *index = fopen(path, "r");
    uint8_t *rgba = movie ? malloc((size_t)width * (size_t)height * 4) : NULL;
    if (!index || (movie && !rgba)) {
        snprintf(err, err_len, "cannot read '%s': %s", path, index ? "out of memory" : strerror(errno));
        if (index)
            fclose(index);
        free(rgba);
        return -1;
    }
    long long previous = -1;
    int rc = 0;
    char line[256];
    while (rc == 0 && fgets(line, sizeof line, index)) {
        unsigned long long frame;
        long long step;
        double time_s;
        if (sscanf(line, "%llu,%lld,%lf", &frame, &step, &time_s) != 3)
            continue; /* the header */
        if ((long long)frame <= previous) {
            snprintf(err, err_len, "'%s': frame %llu listed after frame %lld, so the movie cannot be continued "
                     "(render the whole movie from the PNGs, or use a new --frames folder)", path, frame, previous);
            rc = -1;
            break;
        }
        for (long long k = previous + 1; movie && previous >= 0 && k < (long long)frame && rc == 0; k++)
            if ((rc = surge_movie_add(movie, rgba, err, err_len)) == 0)
                r->movie_frames++;
        char png[4200];
        snprintf(png, sizeof png, "%s/frame_%06llu.png", r->frames_dir, frame);
        if (rc == 0 && (rc = surge_png_read_rgba(png, width, height, rgba, err, err_len)) == 0 && movie &&
            (rc = surge_movie_add(movie, rgba, err, err_len)) == 0)
            r->movie_frames++;
        previous = (long long)frame;
    }
    fclose(index);
    free(rgba);
    r->movie_frames_before_restart = r->movie_frames;
    return rc;
}

/* Creates the frames folder and checks that files can be written into it. */
static int make_folder(const char *path, char *err, size_t err_len)
{
    if (surge_make_folders(path, "the frames", err, err_len) != 0)
        return -1;
    char probe[4200];
    snprintf(probe, sizeof probe, "%s/.surge_write_test", path);
    FILE *f = fopen(probe, "wb");
    if (!f) {
        snprintf(err, err_len, "cannot write into the frames folder '%s': %s", path, strerror(errno));
        return -1;
    }
    fclose(f);
    remove(probe);
    return 0;
}

surge_renderer *surge_renderer_start(const surge_renderer_def *def, const surge_params *params, char *err,
                                     size_t err_len)
{
    surge_renderer *r = calloc(1, sizeof *r);
    if (!r) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    r->def = *def;
    if (def->frames_dir) {
        if (strlen(def->frames_dir) >= sizeof r->frames_dir - 32) {
            snprintf(err, err_len, "frames folder name too long");
            free(r);
            return NULL;
        }
        snprintf(r->frames_dir, sizeof r->frames_dir, "%s", def->frames_dir);
    }
    r->next_frame_s = -INFINITY;
    const int w = params->render.width_px, h = params->render.height_px;
    const int replay = def->frames_dir && def->movie_path && def->continue_frames;
    if ((def->frames_dir && (make_folder(def->frames_dir, err, err_len) != 0 ||
                             open_frame_index(r, params, err, err_len) != 0)) ||
        (replay && replay_kept_frames(r, NULL, w, h, err, err_len) != 0) ||
        !(r->canvas = surge_canvas_create(w, h, def->font_path, err, err_len)) ||
        (def->movie_path && !(r->movie = surge_movie_open(def->movie_path, w, h, params->render.movie_fps, err,
                                                          err_len))) ||
        (replay && replay_kept_frames(r, r->movie, w, h, err, err_len) != 0)) {
        char ignored[256];
        if (r->movie)
            surge_movie_close(r->movie, ignored, sizeof ignored);
        surge_canvas_destroy(r->canvas);
        if (r->index)
            fclose(r->index);
        free(r);
        return NULL;
    }
    r->mailbox = surge_mailbox_create();
    if (!r->mailbox || pthread_create(&r->thread, NULL, renderer_main, r) != 0) {
        snprintf(err, err_len, "cannot start the renderer thread");
        char ignored[256];
        if (r->movie)
            surge_movie_close(r->movie, ignored, sizeof ignored);
        surge_mailbox_destroy(r->mailbox);
        surge_canvas_destroy(r->canvas);
        if (r->index)
            fclose(r->index);
        free(r);
        return NULL;
    }
    return r;
}

void surge_renderer_offer(surge_renderer *r, const surge_sim *sim)
{
    const double t = surge_sim_time(sim);
    if (t < r->next_frame_s)
        return;
    const double interval = surge_sim_params(sim)->render.frame_interval_s;
    if (surge_mailbox_post(r->mailbox, sim, 0, 0) == 0)
        r->next_frame_s = (floor(t / interval + 1e-9) + 1.0) * interval;
}

int surge_renderer_finish(surge_renderer *r, surge_render_report *report, char *err, size_t err_len)
{
    atomic_store(&r->finishing, 1);
    surge_mailbox_close(r->mailbox);
    pthread_join(r->thread, NULL);
    int rc = 0;
    if (r->error[0]) {
        snprintf(err, err_len, "%s", r->error);
        rc = -1;
    }
    char movie_err[1024];
    if (r->movie && surge_movie_close(r->movie, movie_err, sizeof movie_err) != 0 && rc == 0) {
        snprintf(err, err_len, "%s", movie_err);
        rc = -1;
    }
    if (report) {
        report->frames_due = surge_mailbox_posted(r->mailbox);
        report->frames_drawn = r->frames_drawn;
        report->movie_frames = r->movie_frames;
        report->movie_frames_before_restart = r->movie_frames_before_restart;
        report->draw_s = r->draw_s;
        report->encode_s = r->encode_s;
    }
    if (r->index && fclose(r->index) != 0 && rc == 0) {
        snprintf(err, err_len, "cannot write '%.900s/frames.csv': %s", r->frames_dir, strerror(errno));
        rc = -1;
    }
    surge_mailbox_destroy(r->mailbox);
    surge_canvas_destroy(r->canvas);
    free(r);
    return rc;
}
