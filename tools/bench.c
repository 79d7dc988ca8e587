/* Benchmark: particle-steps per second on the incline-film scene (cases/incline_film.ini), 0.1 s of flow from
 * rest, at C_h = 1.0 and 1.8 on 1 and 2 threads. Prints one line per configuration containing
 * "particle-steps/s", the ratio of each to the first, and the accuracy reached: the RMS error of the fluid's x
 * velocity against the analytic start-up of the film, relative to the steady surface speed.
 * Usage: surge-bench [CASE] [--end-s T] */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "surge/sim.h"

/* Start-up of a film from rest under g sin(theta), no-slip bed at y = 0, free surface at y = H:
 * u = (G/nu)(H y - y^2/2) - sum 16 G H^2 / (nu pi^3 k^3) sin(k pi y / 2H) exp(-k^2 pi^2 nu t / 4H^2), k = 2n+1. */
static double film_startup(double y, double t, double G, double H, double nu)
{
    const double pi = 3.14159265358979323846;
    double u = G / nu * (H * y - 0.5 * y * y);
    for (int n = 0; n < 400; n++) {
        const double k = 2 * n + 1;
        u -= 16 * G * H * H / (nu * pi * pi * pi * k * k * k) * sin(k * pi * y / (2 * H)) *
             exp(-k * k * pi * pi * nu * t / (4 * H * H));
    }
    return u;
}

/* RMS of the fluid's x velocity against the start-up solution, relative to its final surface speed G H^2/(2 nu). */
static double film_error(const surge_sim *sim)
{
    const surge_params *p = surge_sim_params(sim);
    const double G = p->body.gravity_mps2 * sin(p->body.slope_deg * 3.14159265358979323846 / 180);
    const double H = p->fluid.depth_m, nu = p->fluid.viscosity_m2ps;
    surge_snapshot s = {0};
    surge_sim_snapshot(sim, &s);
    double sum = 0;
    int n = 0;
    for (int i = 0; i < s.count; i++) {
        if (s.kind[i] != SURGE_KIND_FLUID)
            continue;
        const double e = s.vx_mps[i] - film_startup(s.y_m[i], s.time_s, G, H, nu);
        sum += e * e;
        n++;
    }
    surge_snapshot_free(&s);
    return sqrt(sum / n) / (G * H * H / (2 * nu));
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    const char *case_path = SURGE_SOURCE_DIR "/cases/incline_film.ini";
    double end_s = 0.1;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--end-s") && i + 1 < argc) {
            char *end = NULL;
            end_s = strtod(argv[++i], &end);
            if (end == argv[i] || *end != '\0' || !(end_s > 0) || !isfinite(end_s)) {
                fprintf(stderr, "surge-bench: --end-s needs a positive time in seconds\n");
                return 2;
            }
        } else if (!strcmp(argv[i], "--help")) {
            printf("usage: surge-bench [CASE] [--end-s T]\n(default CASE: cases/incline_film.ini, T = 0.1 s)\n");
            return 0;
        } else if (argv[i][0] != '-') {
            case_path = argv[i];
        } else {
            fprintf(stderr, "surge-bench: unknown option '%s'\n", argv[i]);
            return 2;
        }
    }
    const char *ch_values[] = {"1.0", "1.8"};
    const char *layer_values[] = {"4", "0"}; /* 4 layers as specified at C_h = 1.0; automatic (6) at 1.8 */
    const int thread_values[] = {1, 2};
    double first_rate = 0;
    printf("# surge-bench: %s, %.3g s of flow from rest\n", case_path, end_s);
    for (int c = 0; c < 2; c++) {
        for (int t = 0; t < 2; t++) {
            char err[1024];
            surge_params p = surge_default_params();
            if (surge_params_load(&p, case_path, err, sizeof err) != 0) {
                fprintf(stderr, "surge-bench: %s\n", err);
                return 2;
            }
            char ch[64], layers[64];
            snprintf(ch, sizeof ch, "numerics.ch=%s", ch_values[c]);
            snprintf(layers, sizeof layers, "walls.layers=%s", layer_values[c]);
            if (surge_params_override(&p, ch, false, err, sizeof err) != 0 ||
                surge_params_override(&p, layers, false, err, sizeof err) != 0) {
                fprintf(stderr, "surge-bench: %s\n", err);
                return 2;
            }
            p.time.end_s = end_s;
            omp_set_num_threads(thread_values[t]);
            surge_sim *sim = surge_sim_create(&p, err, sizeof err);
            if (!sim) {
                fprintf(stderr, "surge-bench: %s\n", err);
                return 2;
            }
            const surge_derived *d = surge_sim_derived(sim);
            const double start = now_s();
            while (surge_sim_time(sim) < end_s) {
                if (surge_sim_step(sim) != 0) {
                    fprintf(stderr, "surge-bench: %s\n", surge_sim_health(sim)->message);
                    return 1;
                }
            }
            const double wall = now_s() - start;
            const double steps = (double)surge_sim_step_count(sim);
            const double rate = steps * d->fluid_count / wall;
            if (first_rate == 0)
                first_rate = rate;
            printf("C_h = %s, %d thread%s: %d fluid + %d wall particles, %.0f steps in %.2f s: %.3f million "
                   "particle-steps/s (fluid particles; %.3f million counting walls), ratio %.2f; "
                   "velocity error vs analytic start-up %.4f\n",
                   ch_values[c], thread_values[t], thread_values[t] > 1 ? "s" : "", d->fluid_count, d->wall_count,
                   steps, wall, rate / 1e6, steps * (d->fluid_count + d->wall_count) / wall / 1e6, rate / first_rate,
                   film_error(sim));
            fflush(stdout);
            surge_sim_destroy(sim);
        }
    }
    return 0;
}
