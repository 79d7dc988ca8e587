/* surge-render-bench: frames per second of the renderer on synthetic snapshots.
 *
 *   surge-render-bench [WIDTH HEIGHT [FRAMES]]      default 1920 1080 20
 *
 * For 20,000 and 200,000 particles (a block of fluid, 5:1 wide, on three wall rows, speeds varying across it)
 * it times drawing a frame (OpenGL on OSMesa plus the overlays) and drawing plus PNG encoding, and prints frames
 * per second for each. The solver's slowdown while rendering is measured by bench/render_bench.py. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "surge/platform.h"
#include "surge/render.h"

static void block(surge_snapshot *s, int fluid_count, double dp)
{
    const int columns = (int)sqrt(5.0 * fluid_count), rows = fluid_count / columns;
    surge_snapshot_reserve(s, rows * columns + 3 * columns);
    int n = 0;
    for (int j = -3; j < rows; j++)
        for (int i = 0; i < columns; i++, n++) {
            s->x_m[n] = (i + 0.5) * dp;
            s->y_m[n] = (j + 0.5) * dp;
            s->vx_mps[n] = j < 0 ? (j == -3 ? -0.1f : 0.0f) : (float)(0.2 * (j + 0.5) / rows * (1 + 0.1 * sin(i * 0.05)));
            s->vy_mps[n] = 0;
            s->density_kgpm3[n] = 1000;
            s->pressure_pa[n] = 0;
            s->kind[n] = j < 0 ? (j == -3 ? SURGE_KIND_MOVING_WALL : SURGE_KIND_WALL) : SURGE_KIND_FLUID;
            s->id[n] = n;
        }
    s->count = n;
    s->time_s = 1.0;
}

/* A whole number from the command line, or -1 for anything else ("12x", "", "1e3"). */
static int whole_number(const char *text)
{
    char *end = NULL;
    const long value = strtol(text, &end, 10);
    return end == text || *end != '\0' || value < 0 || value > 1000000 ? -1 : (int)value;
}

int main(int argc, char **argv)
{
    const int width = argc > 2 ? whole_number(argv[1]) : 1920, height = argc > 2 ? whole_number(argv[2]) : 1080;
    const int frames = argc > 3 ? whole_number(argv[3]) : 20;
    if (width < 16 || height < 16 || frames < 1 || width > 16384 || height > 16384) {
        fprintf(stderr, "usage: surge-render-bench [WIDTH HEIGHT [FRAMES]]\n");
        return 2;
    }
    char err[512];
    surge_canvas *canvas = surge_canvas_create(width, height, NULL, err, sizeof err);
    if (!canvas) {
        fprintf(stderr, "surge-render-bench: %s\n", err);
        return 1;
    }
    printf("surge-render-bench: %d x %d, %d frames each, whole view\n", width, height, frames);
    printf("%10s %16s %22s %14s\n", "particles", "draw frames/s", "draw+PNG frames/s", "PNG kB/frame");
    const int sizes[] = {20000, 200000};
    for (int k = 0; k < 2; k++) {
        surge_snapshot s = {0};
        block(&s, sizes[k], 0.001);
        surge_params p = surge_default_params();
        p.numerics.dp_m = 0.001;
        surge_canvas_draw(canvas, &s, &p); /* warm-up */
        double t0 = surge_wall_clock_s();
        for (int f = 0; f < frames; f++)
            surge_canvas_draw(canvas, &s, &p);
        const double draw_s = (surge_wall_clock_s() - t0) / frames;
        size_t bytes = 0;
        t0 = surge_wall_clock_s();
        for (int f = 0; f < frames; f++) {
            uint8_t *png;
            size_t len;
            surge_canvas_draw(canvas, &s, &p);
            if (surge_canvas_png(canvas, &png, &len, err, sizeof err) != 0) {
                fprintf(stderr, "surge-render-bench: %s\n", err);
                return 1;
            }
            bytes = len;
            free(png);
        }
        const double png_s = (surge_wall_clock_s() - t0) / frames;
        printf("%10d %16.1f %22.1f %14.0f\n", s.count, 1 / draw_s, 1 / png_s, bytes / 1e3);
        surge_snapshot_free(&s);
    }
    surge_canvas_destroy(canvas);
    return 0;
}
