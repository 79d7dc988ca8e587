/* Off-screen rendering of particle snapshots: OSMesa (OpenGL 3.3 core on Mesa's llvmpipe) draws the walls as
 * anti-aliased discs of their true size, the CPU the fluid as a kernel-interpolated field (or, in the particles
 * style, OpenGL each particle) and the boulders as solid discs, FreeType the labels, libpng writes frames and the
 * ffmpeg program encodes movies. Settings come from the [render] section of the parameters (surge params). */
#ifndef SURGE_RENDER_H
#define SURGE_RENDER_H

#include <stddef.h>
#include <stdint.h>

#include "surge/params.h"
#include "surge/sim.h"
#include "surge/snapshot.h"

/* The default font (Debian's fonts-dejavu-core). */
#define SURGE_DEFAULT_FONT "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"

/* ---- drawing one snapshot ---- */

typedef struct surge_canvas surge_canvas;

/* An off-screen image of width_px x height_px with its own GL context, current in the calling thread.
 * NULL with the reason in err. */
surge_canvas *surge_canvas_create(int width_px, int height_px, const char *font_path, char *err, size_t err_len);
void surge_canvas_destroy(surge_canvas *canvas);
/* Makes the canvas's context current in the calling thread (one thread at a time uses a canvas). */
int surge_canvas_bind(surge_canvas *canvas);

/* Where things landed in the last image, in pixels from the top-left corner (for tests and overlays). */
typedef struct surge_canvas_layout {
    int plot_x0, plot_y0, plot_x1, plot_y1;     /* the particle area */
    int colorbar_x0, colorbar_y0, colorbar_x1, colorbar_y1; /* bottom = color_min, top = color_max */
    double color_min, color_max;                 /* the colour range used */
    double field_min, field_max;                 /* the field's own range in the view (NaN: no fluid there) */
    double scale_px_per_m;
    double world_x0_m, world_y0_m;               /* the world point drawn at (plot_x0, plot_y1) */
    double view_x0_m, view_x1_m;                 /* the window along the bed (infinite: all of it); on a periodic
                                                    domain x is taken into it */
    double radius_px;                            /* a particle's disc (dp/2) */
} surge_canvas_layout;

/* Draws snap with the [render] settings of params (field, colour map and range, view, slope). Returns the
 * RGBA pixels, top row first, valid until the next draw; NULL when the settings do not fit the canvas. */
const uint8_t *surge_canvas_draw(surge_canvas *canvas, const surge_snapshot *snap, const surge_params *params);
const surge_canvas_layout *surge_canvas_last_layout(const surge_canvas *canvas);
/* Lays out a snapshot as surge_canvas_draw would, without drawing: its view and colour range (a movie's first pass
 * finds the range of all its frames this way). Returns the layout, NULL on failure. */
const surge_canvas_layout *surge_canvas_layout_only(surge_canvas *canvas, const surge_snapshot *snap,
                                                    const surge_params *params);
/* The last image drawn (RGBA, top row first). */
const uint8_t *surge_canvas_pixels(const surge_canvas *canvas);

/* The last image as PNG in a malloc'd buffer. Returns 0, or -1 with err. */
int surge_canvas_png(const surge_canvas *canvas, uint8_t **png, size_t *png_len, char *err, size_t err_len);

/* The frame height for render.height_px = 0 (fitted): from the bottom of the bed (the fixed walls) to a little above
 * the initial fluid block, over the view's length (a periodic whole view: the initial block's), at width_px,
 * between a fifth of the width and the width; from the parameters and walls only, so a restart gets the same size. */
int surge_render_fitted_height_px(int width_px, const surge_snapshot *snap, const surge_params *params);

/* Widens [lo, hi] to multiples of its tick step (1, 2 or 5 times a power of ten, about five intervals). */
void surge_render_round_range(double *lo, double *hi);

/* The colour a field value gets: RGB of the map's entry for (value - min) / (max - min), clamped. */
void surge_colormap_rgb(int colormap, double value, double min, double max, uint8_t rgb[3]);

/* ---- movies ---- */

typedef struct surge_movie surge_movie;

/* Starts the ffmpeg program encoding RGBA frames into path: H.264 (libx264, yuv420p) when ffmpeg has it,
 * otherwise MPEG-4 part 2. NULL with err when ffmpeg is missing or cannot start. */
surge_movie *surge_movie_open(const char *path, int width_px, int height_px, double fps, char *err, size_t err_len);
int surge_movie_add(surge_movie *movie, const uint8_t *rgba, char *err, size_t err_len);
/* Waits for ffmpeg to finish; -1 with err when it failed. Frees movie either way. */
int surge_movie_close(surge_movie *movie, char *err, size_t err_len);

/* ---- rendering alongside the solver ---- */

typedef struct surge_renderer_def {
    const char *frames_dir; /* frame_NNNNNN.png per frame, listed in frames.csv; NULL: no PNG files */
    int continue_frames;    /* a restarted run: number on after the frames already in frames_dir, not from 0 */
    double resume_time_s;   /* with continue_frames: the restart's time; frames.csv rows (and their PNGs) drawn
                               after it by the interrupted run are removed; the cadence goes on from the last kept */
    const char *movie_path; /* NULL: no movie; with continue_frames and frames_dir it starts with the kept frames */
    const char *font_path;  /* NULL: SURGE_DEFAULT_FONT */
    /* called in the renderer thread with each frame as PNG (for the stream); NULL: not needed */
    void (*on_frame)(const uint8_t *png, size_t png_len, int64_t step, double time_s, void *user);
    void *user;
} surge_renderer_def;

typedef struct surge_renderer surge_renderer;

typedef struct surge_render_report {
    uint64_t frames_due;     /* frames the cadence asked for */
    uint64_t frames_drawn;   /* rendered; the others were skipped because the renderer was busy */
    uint64_t movie_frames;   /* in the movie: a skipped frame repeats the previous image, keeping time */
    uint64_t movie_frames_before_restart; /* of those, read back from the frames folder (continue_frames) */
    double draw_s, encode_s; /* renderer-thread seconds drawing, and encoding (PNG, movie) */
} surge_render_report;

/* Checks the settings (size, folder, ffmpeg), creates the canvas and starts the renderer thread. */
surge_renderer *surge_renderer_start(const surge_renderer_def *def, const surge_params *params, char *err,
                                     size_t err_len);
/* Solver thread, at a step boundary: posts the state when a frame is due (every render.frame_interval_s of
 * simulated time). Never waits for the renderer. */
void surge_renderer_offer(surge_renderer *renderer, const surge_sim *sim);
/* Renders what is pending, stops the thread, closes the movie. Returns 0, or -1 with err (a frame or the movie
 * could not be written). report may be NULL. Frees the renderer. */
int surge_renderer_finish(surge_renderer *renderer, surge_render_report *report, char *err, size_t err_len);

#endif
