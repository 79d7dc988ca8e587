/* The renderer on synthetic snapshots: PNG frames decoded with libpng must show each particle in the colour the
 * map gives for its value, at its place and size (the particles style); the fluid as a continuous field with a
 * clean surface (the field style); background, walls, belt and colour bar where they belong; the slope turns the
 * picture; the follow view keeps the surge's body; boulders are solid discs; bad settings give clear errors.
 *
 * usage: test_render GROUP WORK_DIR   (GROUP: colours, slope, errors, boulders, ranges, field) */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "surge/params.h"
#include "surge/render.h"
#include "surge/snapshot.h"

static int failures = 0;

static void check(const char *name, int ok, const char *detail)
{
    printf("%s: %s%s%s\n", name, ok ? "ok" : "FAILED", ok ? "" : "\n    ", ok ? "" : detail);
    failures += !ok;
}

typedef struct image {
    int width, height;
    uint8_t *rgb;
} image;

/* Writes the canvas's PNG to path and reads it back with libpng (the round trip the users' tools make). */
static int png_round_trip(surge_canvas *canvas, const char *path, image *out)
{
    uint8_t *png;
    size_t len;
    char err[256];
    if (surge_canvas_png(canvas, &png, &len, err, sizeof err) != 0)
        return -1;
    FILE *f = fopen(path, "wb");
    fwrite(png, 1, len, f);
    fclose(f);
    free(png);
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&img, path))
        return -1;
    img.format = PNG_FORMAT_RGB;
    out->width = (int)img.width;
    out->height = (int)img.height;
    out->rgb = malloc(PNG_IMAGE_SIZE(img));
    if (!png_image_finish_read(&img, NULL, out->rgb, 0, NULL))
        return -1;
    return 0;
}

static const uint8_t *pixel(const image *im, double x, double y)
{
    int px = (int)floor(x), py = (int)floor(y);
    px = px < 0 ? 0 : (px >= im->width ? im->width - 1 : px);
    py = py < 0 ? 0 : (py >= im->height ? im->height - 1 : py);
    return im->rgb + 3 * ((size_t)py * (size_t)im->width + (size_t)px);
}

static int near_rgb(const uint8_t *a, const uint8_t *b, int tolerance)
{
    for (int k = 0; k < 3; k++)
        if (abs((int)a[k] - (int)b[k]) > tolerance)
            return 0;
    return 1;
}

/* A 10 x 4 block of fluid particles over 3 wall rows (the bottom one moving: the belt), dp = 1 cm.
 * Fluid particle k has speed k / 39 m/s (vx only), so the speeds span [0, 1]. */
static void synthetic(surge_snapshot *s)
{
    const double dp = 0.01;
    surge_snapshot_reserve(s, 40 + 30);
    int n = 0;
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 10; i++, n++) {
            s->x_m[n] = (i + 0.5) * dp;
            s->y_m[n] = (j + 0.5) * dp;
            s->vx_mps[n] = (float)(n / 39.0);
            s->vy_mps[n] = 0;
            s->kind[n] = SURGE_KIND_FLUID;
        }
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 10; i++, n++) {
            s->x_m[n] = (i + 0.5) * dp;
            s->y_m[n] = -(j + 0.5) * dp;
            s->vx_mps[n] = j == 2 ? -0.5f : 0.0f;
            s->vy_mps[n] = 0;
            s->kind[n] = j == 2 ? SURGE_KIND_MOVING_WALL : SURGE_KIND_WALL;
        }
    for (int k = 0; k < n; k++) {
        s->density_kgpm3[k] = 1000;
        s->pressure_pa[k] = 0;
        s->id[k] = k;
    }
    s->time_s = 1.25;
    s->step = 100;
}

static surge_params synthetic_params(void)
{
    surge_params p = surge_default_params();
    p.numerics.dp_m = 0.01;
    p.render.width_px = 800;
    p.render.height_px = 450;
    p.render.field = SURGE_FIELD_SPEED;
    p.render.color_min = 0;
    p.render.color_max = 1;
    p.render.view = SURGE_VIEW_WHOLE;
    return p;
}

static void group_colours(const char *work)
{
    surge_snapshot s = {0};
    synthetic(&s);
    surge_params p = synthetic_params();
    p.render.style = SURGE_STYLE_PARTICLES; /* each particle's own colour, at its place */
    char err[512], path[4096], detail[512];
    surge_canvas *canvas = surge_canvas_create(p.render.width_px, p.render.height_px, NULL, err, sizeof err);
    if (!canvas) {
        check("colours: canvas", 0, err);
        return;
    }
    const int drawn = surge_canvas_draw(canvas, &s, &p) != NULL;
    snprintf(path, sizeof path, "%s/synthetic.png", work);
    image im;
    if (!drawn || png_round_trip(canvas, path, &im) != 0) {
        check("colours: draw and PNG round trip", 0, path);
        return;
    }
    const surge_canvas_layout *l = surge_canvas_last_layout(canvas);
    check("colours: PNG has the frame size", im.width == 800 && im.height == 450, "");
    snprintf(detail, sizeof detail, "radius %.2f px", l->radius_px);
    check("colours: discs are dp across at the view's scale",
          fabs(l->radius_px - 0.5 * 0.01 * l->scale_px_per_m) < 1e-9 && l->radius_px > 8, detail);

    /* every fluid particle: its centre and a point 0.6 radius out have the map's colour for its speed; a point
     * just outside the block's top row is background */
    int wrong = 0;
    for (int k = 0; k < 40; k++) {
        const double cx = l->plot_x0 + (s.x_m[k] - l->world_x0_m) * l->scale_px_per_m;
        const double cy = l->plot_y1 - (s.y_m[k] - l->world_y0_m) * l->scale_px_per_m;
        uint8_t expected[3];
        surge_colormap_rgb(SURGE_COLORMAP_VIRIDIS, s.vx_mps[k], 0, 1, expected);
        if (!near_rgb(pixel(&im, cx, cy), expected, 1) ||
            !near_rgb(pixel(&im, cx + 0.6 * l->radius_px, cy), expected, 1)) {
            if (!wrong)
                snprintf(detail, sizeof detail, "particle %d at (%.1f, %.1f) px: (%d,%d,%d), expected (%d,%d,%d)", k,
                         cx, cy, pixel(&im, cx, cy)[0], pixel(&im, cx, cy)[1], pixel(&im, cx, cy)[2], expected[0],
                         expected[1], expected[2]);
            wrong++;
        }
    }
    check("colours: each particle has the viridis colour of its speed at its place", wrong == 0, detail);
    const uint8_t white[3] = {255, 255, 255}, grey[3] = {150, 150, 150}, belt[3] = {205, 110, 40};
    const double top_y = l->plot_y1 - (0.04 + 0.5 * 0.01 - l->world_y0_m) * l->scale_px_per_m;
    const double mid_x = l->plot_x0 + (0.05 - l->world_x0_m) * l->scale_px_per_m;
    check("colours: background above the fluid is white", near_rgb(pixel(&im, mid_x, top_y - 2 * l->radius_px), white, 0)
                                                              && near_rgb(pixel(&im, l->plot_x0 + 3, l->plot_y0 + 3), white, 0), "");
    const double wall_y = l->plot_y1 - (-0.005 - l->world_y0_m) * l->scale_px_per_m;
    const double belt_y = l->plot_y1 - (-0.025 - l->world_y0_m) * l->scale_px_per_m;
    check("colours: fixed wall grey, belt orange-brown",
          near_rgb(pixel(&im, mid_x, wall_y), grey, 1) && near_rgb(pixel(&im, mid_x, belt_y), belt, 1), "");
    /* the colour bar: bottom = color_min, top = color_max, middle = the middle of the map */
    const double bar_x = 0.5 * (l->colorbar_x0 + l->colorbar_x1);
    const int bar_h = l->colorbar_y1 - l->colorbar_y0;
    uint8_t lo[3], hi[3], mid[3];
    surge_colormap_rgb(SURGE_COLORMAP_VIRIDIS, 0, 0, 1, lo);
    surge_colormap_rgb(SURGE_COLORMAP_VIRIDIS, 1, 0, 1, hi);
    surge_colormap_rgb(SURGE_COLORMAP_VIRIDIS, 0.5, 0, 1, mid);
    /* the maps themselves, against matplotlib's published end colours (independent of our generated table) */
    uint8_t c_lo[3], c_hi[3];
    surge_colormap_rgb(SURGE_COLORMAP_CIVIDIS, 0, 0, 1, c_lo);
    surge_colormap_rgb(SURGE_COLORMAP_CIVIDIS, 1, 0, 1, c_hi);
    const uint8_t viridis_lo[3] = {68, 1, 84}, viridis_hi[3] = {253, 231, 37};
    const uint8_t cividis_lo[3] = {0, 34, 78}, cividis_hi[3] = {254, 232, 56};
    check("colours: viridis and cividis end at matplotlib's colours",
          near_rgb(lo, viridis_lo, 0) && near_rgb(hi, viridis_hi, 0) && near_rgb(c_lo, cividis_lo, 0) &&
              near_rgb(c_hi, cividis_hi, 0), "");
    check("colours: colour bar right of the plot runs from color_min (bottom) to color_max (top)",
          l->colorbar_x0 > l->plot_x1 && near_rgb(pixel(&im, bar_x, l->colorbar_y1 - 1.5), lo, 3) &&
              near_rgb(pixel(&im, bar_x, l->colorbar_y0 + 1.5), hi, 3) &&
              near_rgb(pixel(&im, bar_x, l->colorbar_y0 + 0.5 * bar_h), mid, 3), "");
    int ink = 0; /* the time label above the plot: some dark pixels */
    for (int y = 0; y < l->plot_y0; y++)
        for (int x = l->plot_x0; x < l->plot_x0 + 100; x++)
            ink += pixel(&im, x, y)[0] < 100;
    check("colours: a label is drawn above the plot", ink > 20, "");

    /* another field and map: x velocity relative to the belt (-0.5 m/s) on cividis */
    p.render.field = SURGE_FIELD_VX_REL;
    p.render.colormap = SURGE_COLORMAP_CIVIDIS;
    p.render.color_min = 0.5;
    p.render.color_max = 1.5;
    surge_canvas_draw(canvas, &s, &p);
    snprintf(path, sizeof path, "%s/synthetic_vx_rel.png", work);
    image im2;
    png_round_trip(canvas, path, &im2);
    l = surge_canvas_last_layout(canvas);
    const int k = 25;
    const double cx = l->plot_x0 + (s.x_m[k] - l->world_x0_m) * l->scale_px_per_m;
    const double cy = l->plot_y1 - (s.y_m[k] - l->world_y0_m) * l->scale_px_per_m;
    uint8_t expected[3];
    surge_colormap_rgb(SURGE_COLORMAP_CIVIDIS, s.vx_mps[k] + 0.5, 0.5, 1.5, expected);
    check("colours: vx_rel on cividis subtracts the belt speed", near_rgb(pixel(&im2, cx, cy), expected, 1), "");

    /* a fluid at rest, automatic range: the speed bar starts at 0 (it read -0.5..0.5) */
    p.render.field = SURGE_FIELD_SPEED;
    p.render.color_min = p.render.color_max = 0;
    for (int32_t i = 0; i < s.count; i++)
        s.vx_mps[i] = s.vy_mps[i] = 0;
    surge_canvas_draw(canvas, &s, &p);
    l = surge_canvas_last_layout(canvas);
    snprintf(detail, sizeof detail, "range %g..%g", l->color_min, l->color_max);
    check("colours: a fluid at rest gets the speed range 0..1, not a negative speed", l->color_min == 0 &&
          l->color_max == 1, detail);
    free(im.rgb);
    free(im2.rgb);
    surge_canvas_destroy(canvas);
    surge_snapshot_free(&s);
}

/* Automatic colour ranges and frame heights (pictures): round ranges that grow but never shrink while a run
 * renders, and a frame fitted to a long thin scene. */
static void group_ranges(const char *work)
{
    (void)work;
    char detail[256], err[512];
    double lo = 0.000433, hi = 0.0805;
    surge_render_round_range(&lo, &hi);
    double lo2 = -0.37, hi2 = 1.2e5, lo3 = 997.2, hi3 = 1003.9;
    surge_render_round_range(&lo2, &hi2);
    surge_render_round_range(&lo3, &hi3);
    snprintf(detail, sizeof detail, "%g..%g, %g..%g, %g..%g", lo, hi, lo2, hi2, lo3, hi3);
    check("ranges: a range widens to its round tick step (0.000433..0.0805 -> 0..0.1)",
          lo == 0 && fabs(hi - 0.1) < 1e-12 && lo2 == -2e4 && fabs(hi2 - 1.2e5) < 1e-6 && fabs(lo3 - 997) < 1e-9 &&
              fabs(hi3 - 1004) < 1e-9, detail);

    surge_snapshot s = {0};
    synthetic(&s); /* fluid speeds 0..1 m/s */
    surge_params p = synthetic_params();
    p.render.color_min = p.render.color_max = 0;
    surge_canvas *canvas = surge_canvas_create(p.render.width_px, p.render.height_px, NULL, err, sizeof err);
    if (!canvas) {
        check("ranges: canvas", 0, err);
        return;
    }
    double ranges[3][2];
    const float scale[3] = {0.083f, 0.05f, 0.13f}; /* the flow speeds up, slows, speeds up past the range */
    for (int frame = 0; frame < 3; frame++) {
        for (int k = 0; k < 40; k++)
            s.vx_mps[k] = (float)(scale[frame] * k / 39.0);
        surge_canvas_draw(canvas, &s, &p);
        ranges[frame][0] = surge_canvas_last_layout(canvas)->color_min;
        ranges[frame][1] = surge_canvas_last_layout(canvas)->color_max;
    }
    snprintf(detail, sizeof detail, "%g..%g, %g..%g, %g..%g", ranges[0][0], ranges[0][1], ranges[1][0], ranges[1][1],
             ranges[2][0], ranges[2][1]);
    check("ranges: a live automatic range is round, holds when the flow slows and grows when it leaves it",
          ranges[0][0] == 0 && fabs(ranges[0][1] - 0.1) < 1e-12 && ranges[1][0] == 0 &&
              ranges[1][1] == ranges[0][1] && ranges[2][0] == 0 && fabs(ranges[2][1] - 0.14) < 1e-12, detail);

    /* what drives the flow, drawn: a gravity arrow in the plot's top right corner, a belt arrow under its right end;
     * neither without gravity and belt */
    int ink_with[2] = {0, 0}, ink_without[2] = {0, 0};
    for (int drivers = 1; drivers >= 0; drivers--) {
        p.body.gravity_mps2 = drivers ? 9.81 : 0;
        p.body.slope_deg = 10;
        p.walls.bottom = true;
        p.walls.bottom_speed_mps = drivers ? -1 : 0;
        const uint8_t *rgba = surge_canvas_draw(canvas, &s, &p);
        const surge_canvas_layout *l = surge_canvas_last_layout(canvas);
        const int size = p.render.height_px / 36, w = p.render.width_px;
        int *ink = drivers ? ink_with : ink_without;
        for (int y = l->plot_y0 + 2; y < l->plot_y0 + 3 * size && rgba; y++)
            for (int x = l->plot_x1 - 5 * size; x < l->plot_x1 - 2; x++)
                ink[0] += rgba[4 * ((size_t)y * w + x)] < 60;
        for (int y = p.render.height_px - 2 * size; y < p.render.height_px && rgba; y++)
            for (int x = l->plot_x1 - 6 * size; x < l->plot_x1; x++)
                ink[1] += rgba[4 * ((size_t)y * w + x)] < 60;
    }
    snprintf(detail, sizeof detail, "dark pixels: gravity corner %d (%d without), belt corner %d (%d without)",
             ink_with[0], ink_without[0], ink_with[1], ink_without[1]);
    check("ranges: gravity and belt arrows are drawn when they drive the flow, not otherwise",
          ink_with[0] > 10 && ink_with[1] > 10 && ink_without[0] == 0 && ink_without[1] == 0, detail);
    surge_canvas_destroy(canvas);

    /* a bed 100 dp long and 3 dp deep, not periodic, under a block 4 dp deep: a flat frame, the same with or without
     * the fluid */
    p.domain.periodic_x = false;
    surge_snapshot bed = {0};
    surge_snapshot_reserve(&bed, 300 + 40);
    int n = 0;
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 100; i++, n++) {
            bed.x_m[n] = (i + 0.5) * 0.01;
            bed.y_m[n] = -(j + 0.5) * 0.01;
            bed.kind[n] = SURGE_KIND_WALL;
        }
    const int walls_only = surge_render_fitted_height_px(1280, &bed, &p);
    for (int k = 0; k < 40; k++, n++) {
        bed.x_m[n] = s.x_m[k];
        bed.y_m[n] = s.y_m[k] + 0.5; /* fluid thrown high above the bed does not change the frame */
        bed.kind[n] = SURGE_KIND_FLUID;
    }
    bed.count = n;
    const int with_fluid = surge_render_fitted_height_px(1280, &bed, &p);
    p.render.view = SURGE_VIEW_FIXED;
    p.render.view_x0_m = 0;
    p.render.view_x1_m = 0.1;
    const int fixed_window = surge_render_fitted_height_px(1280, &bed, &p);
    snprintf(detail, sizeof detail, "whole %d px (walls only %d), fixed 0.1 m window %d px", with_fluid, walls_only,
             fixed_window);
    check("ranges: a long thin scene gets a flat frame (a fifth of the width), a short window a taller one, "
          "even heights", walls_only == 256 && with_fluid == 256 && fixed_window > 256 && fixed_window % 2 == 0, detail);
    surge_snapshot_free(&bed);
    surge_snapshot_free(&s);
}

/* true_slope: the bed descends to the right by the slope angle. */
static void group_slope(const char *work)
{
    surge_snapshot s = {0};
    synthetic(&s);
    surge_params p = synthetic_params();
    p.render.style = SURGE_STYLE_PARTICLES; /* the end particles' own colours mark the row */
    p.body.slope_deg = 20;
    char err[512], path[4096], detail[256];
    surge_canvas *canvas = surge_canvas_create(p.render.width_px, p.render.height_px, NULL, err, sizeof err);
    if (!canvas) {
        check("slope: canvas", 0, err);
        return;
    }
    double angle_deg[2];
    for (int tilted = 0; tilted < 2; tilted++) {
        p.render.true_slope = tilted;
        surge_canvas_draw(canvas, &s, &p);
        snprintf(path, sizeof path, "%s/slope_%d.png", work, tilted);
        image im;
        png_round_trip(canvas, path, &im);
        /* the first and the last particle of the bottom fluid row have colours no other particle has: the
         * centroids of their exactly-coloured pixels give the row's direction in the image */
        double cx[2] = {0, 0}, cy[2] = {0, 0}, n[2] = {0, 0};
        for (int e = 0; e < 2; e++) {
            uint8_t rgb[3];
            surge_colormap_rgb(SURGE_COLORMAP_VIRIDIS, s.vx_mps[e ? 9 : 0], 0, 1, rgb);
            for (int y = 0; y < im.height; y++)
                for (int x = 0; x < im.width; x++)
                    if (near_rgb(pixel(&im, x, y), rgb, 0)) {
                        cx[e] += x + 0.5, cy[e] += y + 0.5, n[e]++;
                    }
        }
        angle_deg[tilted] = n[0] > 0 && n[1] > 0
                                ? atan2(cy[1] / n[1] - cy[0] / n[0], cx[1] / n[1] - cx[0] / n[0]) * 180 / 3.14159265358979
                                : NAN;
        free(im.rgb);
    }
    snprintf(detail, sizeof detail, "row direction %.2f deg flat, %.2f deg tilted (image y down; expected 0 and 20)",
             angle_deg[0], angle_deg[1]);
    check("slope: the bed runs along the image when flat and falls 20 deg to the right when tilted",
          fabs(angle_deg[0]) < 0.5 && fabs(angle_deg[1] - 20) < 0.5, detail);
    surge_canvas_destroy(canvas);
    surge_snapshot_free(&s);
}

static void group_errors(const char *work)
{
    char err[512] = "", path[4096];
    surge_canvas *c = surge_canvas_create(0, 100, NULL, err, sizeof err);
    check("errors: a zero-width frame is refused by name", !c && strstr(err, "0 x 100"), err);
    c = surge_canvas_create(100000, 100, NULL, err, sizeof err);
    check("errors: an absurd frame size is refused", !c && strstr(err, "16..8192"), err);
    c = surge_canvas_create(64, 64, "/nonexistent/font.ttf", err, sizeof err);
    check("errors: a missing font is named", !c && strstr(err, "/nonexistent/font.ttf"), err);
    surge_params p = synthetic_params();
    surge_renderer_def def = {.frames_dir = "/proc/surge_cannot_write_here"};
    surge_renderer *r = surge_renderer_start(&def, &p, err, sizeof err);
    check("errors: an unwritable frames folder is named", !r && strstr(err, "/proc/surge_cannot_write_here"), err);
    snprintf(path, sizeof path, "%s/no/such/folder/movie.mp4", work);
    surge_renderer_def movie_def = {.movie_path = path};
    r = surge_renderer_start(&movie_def, &p, err, sizeof err);
    check("errors: a movie in a missing folder is named", !r && strstr(err, "movie.mp4"), err);
}

/* A boulder of 24 particles on a ring of radius 4 cm around (0.1, 0.1) m turned by 90 degrees, in a 1 cm bed of
 * fluid: the particles above the centre carry the orientation mark, those below the boulder colour. */
static void group_boulders(const char *work)
{
    surge_snapshot s = {0};
    const int ring = 24, fluid = 20;
    surge_snapshot_reserve(&s, ring + fluid);
    surge_snapshot_reserve_boulders(&s, 1);
    for (int k = 0; k < ring + fluid; k++) {
        const double phi = 2 * 3.14159265358979323846 * k / ring;
        s.x_m[k] = k < ring ? 0.1 + 0.04 * cos(phi) : 0.01 * (k - ring) + 0.005;
        s.y_m[k] = k < ring ? 0.1 + 0.04 * sin(phi) : 0.005;
        s.vx_mps[k] = s.vy_mps[k] = 0;
        s.density_kgpm3[k] = 1000;
        s.pressure_pa[k] = 0;
        s.kind[k] = k < ring ? SURGE_KIND_BOULDER : SURGE_KIND_FLUID;
        s.id[k] = k;
    }
    s.boulders.x_m[0] = 0.1, s.boulders.y_m[0] = 0.1, s.boulders.radius_m[0] = 0.045;
    s.boulders.angle_rad[0] = 0.5 * 3.14159265358979323846;
    s.boulders.vx_mps[0] = s.boulders.vy_mps[0] = s.boulders.omega_radps[0] = 0;
    surge_params p = synthetic_params();
    p.domain.periodic_x = false;
    char err[512], path[4096];
    surge_canvas *canvas = surge_canvas_create(p.render.width_px, p.render.height_px, NULL, err, sizeof err);
    image im;
    snprintf(path, sizeof path, "%s/boulder.png", work);
    if (!canvas || !surge_canvas_draw(canvas, &s, &p) || png_round_trip(canvas, path, &im) != 0) {
        check("boulders: draw and PNG round trip", 0, err);
        return;
    }
    const surge_canvas_layout *l = surge_canvas_last_layout(canvas);
    const uint8_t mark[3] = {235, 235, 235}, body[3] = {95, 80, 70};
    const double x = l->plot_x0 + (0.1 - l->world_x0_m) * l->scale_px_per_m;
    const double top = l->plot_y1 - (0.14 - l->world_y0_m) * l->scale_px_per_m;
    const double bottom = l->plot_y1 - (0.06 - l->world_y0_m) * l->scale_px_per_m;
    const double side = l->plot_x0 + (0.14 - l->world_x0_m) * l->scale_px_per_m;
    const double mid = l->plot_y1 - (0.1 - l->world_y0_m) * l->scale_px_per_m;
    check("boulders: the spoke in the direction of the disc's angle carries the mark",
          near_rgb(pixel(&im, x, 0.5 * (top + mid)), mark, 1), "");
    check("boulders: opposite and beside the spoke the disc has the boulder colour",
          near_rgb(pixel(&im, x, bottom), body, 1) && near_rgb(pixel(&im, side, mid), body, 1), "");
    /* a solid disc: its centre and points half a radius out off the spoke are the body's colour (they lie between
     * the ring's particles), and its rim carries the darker outline */
    const double r_px = 0.045 * l->scale_px_per_m;
    int solid = near_rgb(pixel(&im, x + 2, mid), body, 1);
    for (int k = 0; k < 8; k++) {
        const double phi = 3.14159265358979 * (2 * k + 1) / 8;
        solid = solid && near_rgb(pixel(&im, x + 0.5 * r_px * cos(phi), mid + 0.5 * r_px * sin(phi)), body, 1);
    }
    const uint8_t *rim = pixel(&im, x - r_px + 1.5, mid + 0.5);
    check("boulders: the disc is filled, with a darker outline at its rim",
          solid && rim[0] < 60, "");
    surge_canvas_destroy(canvas);
    surge_snapshot_free(&s);
}

/* A block of fluid 1 m long and 0.2 m deep (dp 2 cm) on a 3-row bed, every particle moving at 0.5 m/s, with
 * `ahead` more particles at x = 3 m (carried ahead of the surge). */
static void surge_block(surge_snapshot *s, int ahead)
{
    const double dp = 0.02;
    surge_snapshot_reserve(s, 500 + 3 * 200 + ahead);
    int n = 0;
    for (int j = 0; j < 10; j++)
        for (int i = 0; i < 50; i++, n++) {
            s->x_m[n] = (i + 0.5) * dp, s->y_m[n] = (j + 0.5) * dp, s->kind[n] = SURGE_KIND_FLUID;
        }
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 200; i++, n++) {
            s->x_m[n] = (i + 0.5) * dp, s->y_m[n] = -(j + 0.5) * dp, s->kind[n] = SURGE_KIND_WALL;
        }
    for (int k = 0; k < ahead; k++, n++) {
        s->x_m[n] = 3 + k * dp, s->y_m[n] = 0.5 * dp, s->kind[n] = SURGE_KIND_FLUID;
    }
    for (int k = 0; k < n; k++) {
        s->vx_mps[k] = s->kind[k] == SURGE_KIND_FLUID ? 0.5f : 0.0f;
        s->vy_mps[k] = 0;
        s->density_kgpm3[k] = 1000;
        s->pressure_pa[k] = 0;
        s->id[k] = k;
    }
    s->count = n;
}

/* The field style: the block is one colour with no background inside it and a clean surface; the follow view keeps
 * the block's front at 3/4 of its width with particles far ahead; a periodic whole view fits the fluid, not the
 * period. */
static void group_field(const char *work)
{
    surge_snapshot s = {0};
    surge_block(&s, 3);
    surge_params p = synthetic_params();
    p.numerics.dp_m = 0.02;
    p.domain.periodic_x = false;
    p.render.view = SURGE_VIEW_FIXED;
    p.render.view_x0_m = 0.3;
    p.render.view_x1_m = 1.3;
    char err[512], path[4096], detail[512];
    surge_canvas *canvas = surge_canvas_create(p.render.width_px, p.render.height_px, NULL, err, sizeof err);
    image im;
    snprintf(path, sizeof path, "%s/field.png", work);
    if (!canvas || !surge_canvas_draw(canvas, &s, &p) || png_round_trip(canvas, path, &im) != 0) {
        check("field: draw and PNG round trip", 0, err);
        return;
    }
    const surge_canvas_layout *l = surge_canvas_last_layout(canvas);
    uint8_t expected[3];
    surge_colormap_rgb(SURGE_COLORMAP_VIRIDIS, 0.5, 0, 1, expected);
    /* every pixel whose centre lies inside the block, half a dp in from its edges, in the view */
    int wrong = 0, inside = 0;
    for (int y = l->plot_y0; y < l->plot_y1; y++)
        for (int x = l->plot_x0; x < l->plot_x1; x++) {
            const double X = l->world_x0_m + (x + 0.5 - l->plot_x0) / l->scale_px_per_m;
            const double Y = l->world_y0_m + (l->plot_y1 - y - 0.5) / l->scale_px_per_m;
            if (X < 0.3 || X > 1.0 - 0.01 || Y < 0.01 || Y > 0.2 - 0.01)
                continue;
            inside++;
            if (!near_rgb(pixel(&im, x, y), expected, 1) && !wrong++)
                snprintf(detail, sizeof detail, "pixel (%d, %d): (%d,%d,%d), expected (%d,%d,%d)", x, y,
                         pixel(&im, x, y)[0], pixel(&im, x, y)[1], pixel(&im, x, y)[2], expected[0], expected[1],
                         expected[2]);
        }
    check("field: the fluid is one continuous colour inside the block, no background between particles",
          inside > 1000 && wrong == 0, detail);
    /* the surface: fluid colour half a dp below the block's top, background one dp above it, all along */
    const uint8_t white[3] = {255, 255, 255};
    int ragged = 0;
    for (double X = 0.35; X < 0.95; X += 0.01) {
        const double x = l->plot_x0 + (X - l->world_x0_m) * l->scale_px_per_m;
        ragged += !near_rgb(pixel(&im, x, l->plot_y1 - (0.19 - l->world_y0_m) * l->scale_px_per_m), expected, 1) ||
                  !near_rgb(pixel(&im, x, l->plot_y1 - (0.22 - l->world_y0_m) * l->scale_px_per_m), white, 0);
    }
    snprintf(detail, sizeof detail, "%d of 60 columns without a clean surface", ragged);
    check("field: a clean surface line at the block's top", ragged == 0, detail);

    /* the follow view: the block's front (x = 1 m) at 3/4 of a 1 m window, not the 3 particles at x = 3 m */
    p.render.view = SURGE_VIEW_FOLLOW;
    p.render.view_width_m = 1;
    surge_canvas_draw(canvas, &s, &p);
    const double front_at = (1.0 - l->world_x0_m) * l->scale_px_per_m / (l->plot_x1 - l->plot_x0);
    snprintf(detail, sizeof detail, "the block's front at %.3f of the plot width", front_at);
    check("field: the follow view keeps the surge's front at 3/4 of the width with particles far ahead",
          fabs(front_at - 0.75) < 0.03, detail);

    /* a periodic whole view of a 6 m period whose fluid holds 1 m: the scale of about 1.1 m, not of the period */
    p.render.view = SURGE_VIEW_WHOLE;
    p.domain.periodic_x = true;
    p.domain.length_m = 6;
    surge_snapshot_free(&s);
    surge_block(&s, 0);
    surge_canvas_draw(canvas, &s, &p);
    const double shown_m = (l->plot_x1 - l->plot_x0) / l->scale_px_per_m;
    snprintf(detail, sizeof detail, "%.2f m shown", shown_m);
    check("field: a periodic whole view shows the part of the period the fluid holds, with a margin",
          shown_m > 1.0 && shown_m < 1.5, detail);
    free(im.rgb);
    surge_canvas_destroy(canvas);
    surge_snapshot_free(&s);
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: test_render colours|slope|errors|boulders|ranges|field WORK_DIR\n");
        return 2;
    }
    if (!strcmp(argv[1], "ranges"))
        group_ranges(argv[2]);
    else if (!strcmp(argv[1], "colours"))
        group_colours(argv[2]);
    else if (!strcmp(argv[1], "slope"))
        group_slope(argv[2]);
    else if (!strcmp(argv[1], "errors"))
        group_errors(argv[2]);
    else if (!strcmp(argv[1], "boulders"))
        group_boulders(argv[2]);
    else if (!strcmp(argv[1], "field"))
        group_field(argv[2]);
    else {
        fprintf(stderr, "unknown group '%s'\n", argv[1]);
        return 2;
    }
    printf(failures ? "%d check(s) failed\n" : "all checks passed\n", failures);
    return failures ? 1 : 0;
}
