/* Benchmark: particle-steps per second on the incline-film scene (cases/incline_film.ini), 0.1 s of flow from
 * rest. With no configuration option it runs its sweep, C_h = 1.0 (4 wall layers) and 1.8 (automatic layers) on 1
 * and 2 threads; with --ch, --threads or --layers it runs that one configuration, so that an outside harness
 * (bench/ab_bench.py) can time it. Prints one line per configuration containing "particle-steps/s", the ratio
 * of each to the first, and the accuracy reached: the RMS error of the fluid's x velocity against the analytic
 * start-up of the film, relative to the steady surface speed; then the seconds and share of the steps' time of each
 * phase of the step the run went through (surge_phase_times; docs/performance.md, "Where a step's time goes").
 * Usage: surge-bench [CASE] [--end-s T] [--ch C] [--threads N] [--layers L] [-s NAME=VALUE]... */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "surge/platform.h"
#include "surge/sim.h"

#define MAX_OVERRIDES 32

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

#ifndef SURGE_BENCH_WITHOUT_PHASE_TIMES /* bench/ab_bench.py builds this file against commits without the timers */
/* The phases of surge_phase_times in the order they are printed */
static const struct {
    const char *name;
    size_t offset;
} phases[] = {
    {"neighbours", offsetof(surge_phase_times, neighbours_s)},
    {"interaction", offsetof(surge_phase_times, interaction_s)},
    {"boundary", offsetof(surge_phase_times, boundary_s)},
    {"discs", offsetof(surge_phase_times, discs_s)},
    {"contacts", offsetof(surge_phase_times, contacts_s)},
    {"geometry", offsetof(surge_phase_times, geometry_s)},
    {"surface", offsetof(surge_phase_times, surface_s)},
    {"assembly", offsetof(surge_phase_times, assembly_s)},
    {"multigrid", offsetof(surge_phase_times, multigrid_s)},
    {"viscous_solve", offsetof(surge_phase_times, viscous_solve_s)},
    {"pressure_solve", offsetof(surge_phase_times, pressure_solve_s)},
    {"disc_coupling", offsetof(surge_phase_times, disc_coupling_s)},
    {"update", offsetof(surge_phase_times, update_s)},
    {"other", offsetof(surge_phase_times, other_s)},
};

/* The run's phases: seconds and share of the steps' time, one line each, the phases it did not go through left out
 * (other always printed) */
static void print_phases(const surge_sim *sim)
{
    surge_phase_times t;
    surge_sim_phase_times(sim, &t);
    printf("  phases over %lld steps, %.6f s:\n", (long long)t.steps, t.total_s);
    for (size_t k = 0; k < sizeof phases / sizeof phases[0]; k++) {
        const double seconds = *(const double *)((const char *)&t + phases[k].offset);
        if (seconds > 0 || !strcmp(phases[k].name, "other"))
            printf("    %-15s %12.6f s %6.1f %%\n", phases[k].name, seconds,
                   t.total_s > 0 ? 100 * seconds / t.total_s : 0.0);
    }
}
#endif

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct bench_config {
    const char *case_path;
    double end_s;
    const char *ch, *layers;  /* parameter values as text */
    int threads;
    const char *overrides[MAX_OVERRIDES];
    int override_count;
} bench_config;

static int set_param(surge_params *p, const char *name, const char *value)
{
    char assignment[256], err[1024];
    snprintf(assignment, sizeof assignment, "%s=%s", name, value);
    if (surge_params_override(p, assignment, false, err, sizeof err) != 0) {
        fprintf(stderr, "surge-bench: %s\n", err);
        return -1;
    }
    return 0;
}

/* Runs one configuration and prints its line; first_rate (0 on the first call) is the sweep's reference. */
static int run_one(const bench_config *c, double *first_rate)
{
    char err[1024];
    surge_params p = surge_default_params();
    if (surge_params_load(&p, c->case_path, err, sizeof err) != 0) {
        fprintf(stderr, "surge-bench: %s\n", err);
        return 2;
    }
    if (set_param(&p, "numerics.ch", c->ch) != 0 || set_param(&p, "walls.layers", c->layers) != 0)
        return 2;
    for (int i = 0; i < c->override_count; i++) {
        if (surge_params_override(&p, c->overrides[i], false, err, sizeof err) != 0) {
            fprintf(stderr, "surge-bench: -s %s: %s\n", c->overrides[i], err);
            return 2;
        }
    }
    p.time.end_s = c->end_s;
    omp_set_num_threads(c->threads);
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "surge-bench: %s\n", err);
        return 2;
    }
    const surge_derived *d = surge_sim_derived(sim);
    const double start = now_s();
    while (surge_sim_time(sim) < c->end_s) {
        if (surge_sim_step(sim) != 0) {
            fprintf(stderr, "surge-bench: %s\n", surge_sim_health(sim)->message);
            surge_sim_destroy(sim);
            return 1;
        }
    }
    const double wall = now_s() - start;
    const double steps = (double)surge_sim_step_count(sim);
    const double rate = steps * d->fluid_count / wall;
    if (*first_rate == 0)
        *first_rate = rate;
    printf("C_h = %s, %d thread%s: %d fluid + %d wall particles, %.0f steps in %.2f s: %.3f million "
           "particle-steps/s (fluid particles; %.3f million counting walls), ratio %.2f; "
           "velocity error vs analytic start-up %.5f; state hash %016llx\n",
           c->ch, c->threads, c->threads > 1 ? "s" : "", d->fluid_count, d->wall_count, steps, wall, rate / 1e6,
           steps * (d->fluid_count + d->wall_count) / wall / 1e6, rate / *first_rate, film_error(sim),
           (unsigned long long)surge_sim_state_hash(sim));
#ifndef SURGE_BENCH_WITHOUT_PHASE_TIMES
    print_phases(sim);
#endif
    fflush(stdout);
    surge_sim_destroy(sim);
    return 0;
}

static int usage_error(const char *what)
{
    fprintf(stderr, "surge-bench: %s (surge-bench --help)\n", what);
    return 2;
}

int main(int argc, char **argv)
{
    bench_config c = {.case_path = SURGE_SOURCE_DIR "/cases/incline_film.ini", .end_s = 0.1};
    const char *ch = NULL, *layers = NULL;
    int threads = 0;
    for (int i = 1; i < argc; i++) {
        const int has_value = i + 1 < argc;
        if (!strcmp(argv[i], "--end-s") && has_value) {
            char *end = NULL;
            c.end_s = strtod(argv[++i], &end);
            if (end == argv[i] || *end != '\0' || !(c.end_s > 0) || !isfinite(c.end_s))
                return usage_error("--end-s needs a positive time in seconds");
        } else if (!strcmp(argv[i], "--threads") && has_value) {
            char *end = NULL;
            const long n = strtol(argv[++i], &end, 10);
            if (end == argv[i] || *end != '\0' || n < 1 || n > 1024)
                return usage_error("--threads needs a whole number from 1 to 1024");
            threads = (int)n;
        } else if (!strcmp(argv[i], "--ch") && has_value) {
            ch = argv[++i];
        } else if (!strcmp(argv[i], "--layers") && has_value) {
            layers = argv[++i];
        } else if (!strcmp(argv[i], "-s") && has_value) {
            if (c.override_count == MAX_OVERRIDES)
                return usage_error("too many -s options");
            c.overrides[c.override_count++] = argv[++i];
        } else if (!strcmp(argv[i], "--help")) {
            printf("usage: surge-bench [CASE] [--end-s T] [--ch C] [--threads N] [--layers L] [-s NAME=VALUE]...\n"
                   "(default CASE: cases/incline_film.ini, T = 0.1 s; with none of --ch, --threads, --layers the\n"
                   "sweep C_h 1.0 with 4 wall layers and 1.8 with the automatic number, on 1 and 2 threads)\n");
            return 0;
        } else if (argv[i][0] != '-') {
            c.case_path = argv[i];
        } else {
            char what[300];
            snprintf(what, sizeof what, "unknown option or missing value: '%s'", argv[i]);
            return usage_error(what);
        }
    }
    double first_rate = 0;
    printf("# surge-bench: %s, %.3g s of flow from rest\n", c.case_path, c.end_s);
#ifndef SURGE_BENCH_WITHOUT_BUILD_INFO /* bench/ab_bench.py builds this file against commits older than 87303e8 */
    char machine[512];
    surge_machine_description(machine, sizeof machine);
    printf("# program: %s\n# machine: %s\n", surge_build_description(), machine);
#endif
    if (ch || threads || layers) {
        c.ch = ch ? ch : "1.8";
        c.layers = layers ? layers : (!strcmp(c.ch, "1.0") ? "4" : "0");
        c.threads = threads ? threads : 1;
        return run_one(&c, &first_rate);
    }
    const char *ch_values[] = {"1.0", "1.8"};
    const char *layer_values[] = {"4", "0"}; /* 4 layers as specified at C_h = 1.0; automatic (6) at 1.8 */
    const int thread_values[] = {1, 2};
    for (int k = 0; k < 2; k++) {
        for (int t = 0; t < 2; t++) {
            c.ch = ch_values[k], c.layers = layer_values[k], c.threads = thread_values[t];
            const int status = run_one(&c, &first_rate);
            if (status != 0)
                return status;
        }
    }
    return 0;
}
