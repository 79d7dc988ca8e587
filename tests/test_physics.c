/* Physics tests against analytic references (docs/references.md). Each runs a shipped case, made cheaper through
 * overrides where that keeps the check meaningful, and prints the measured errors next to their bounds.
 * usage: test_physics NAME [profile.csv | restart DIR [CASE]] [-s section.key=value ...]
 *   NAME: hydrostatic | poiseuille | couette | film | restart | solver_failure | preconditioners; each -s is applied after the test's own overrides
 *   (-s numerics.scheme=implicit runs a test with the implicit scheme, against the same bounds). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "surge/sim.h"

#define PI 3.14159265358979323846

static int failures = 0;
static const char *extra[16];  /* the command line's -s overrides */
static int extra_count = 0;

static void expect_below(const char *what, double value, double bound)
{
    const int ok = value <= bound;
    printf("%-58s %12.4g  (bound %g)  %s\n", what, value, bound, ok ? "ok" : "FAILED");
    failures += !ok;
}

static surge_sim *load(const char *case_name, const char *const *overrides, int n)
{
    char path[1024], err[1024];
    snprintf(path, sizeof path, "%s/cases/%s", SURGE_SOURCE_DIR, case_name);
    surge_params p = surge_default_params();
    if (surge_params_load(&p, path, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        exit(2);
    }
    for (int i = 0; i < n; i++) {
        if (surge_params_override(&p, overrides[i], false, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            exit(2);
        }
    }
    for (int i = 0; i < extra_count; i++) {
        if (surge_params_override(&p, extra[i], false, err, sizeof err) != 0) {
            fprintf(stderr, "%s\n", err);
            exit(2);
        }
    }
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "%s\n", err);
        exit(2);
    }
    return sim;
}

static void run_until(surge_sim *sim, double t_end)
{
    while (surge_sim_time(sim) < t_end) {
        if (surge_sim_step(sim) != 0) {
            fprintf(stderr, "%s\n", surge_sim_health(sim)->message);
            exit(1);
        }
    }
}

/* RMS of (u - u_ref(y)) over fluid particles, relative to scale. */
static double profile_error(const surge_snapshot *s, double (*ref)(double y, double t), double t, double scale,
                            FILE *profile)
{
    double sum = 0;
    int n = 0;
    for (int i = 0; i < s->count; i++) {
        if (s->kind[i] != SURGE_KIND_FLUID)
            continue;
        const double e = s->vx_mps[i] - ref(s->y_m[i], t);
        sum += e * e;
        n++;
        if (profile)
            fprintf(profile, "%.9g,%.9g,%.9g,%.9g\n", t, s->y_m[i], (double)s->vx_mps[i], ref(s->y_m[i], t));
    }
    return sqrt(sum / n) / scale;
}

/* Plane Poiseuille start-up (Morris et al. 1997), walls at 0 and L, body force F. */
static const double CH_L = 1e-3, CH_NU = 1e-6, CH_F = 2e-4, CH_U = 2.5e-5;
static double poiseuille(double y, double t)
{
    double u = CH_F / (2 * CH_NU) * y * (CH_L - y);
    for (int n = 0; n < 200; n++) {
        const double k = 2 * n + 1;
        u -= 4 * CH_F * CH_L * CH_L / (CH_NU * PI * PI * PI * k * k * k) * sin(PI * y * k / CH_L) *
             exp(-k * k * PI * PI * CH_NU * t / (CH_L * CH_L));
    }
    return u;
}

/* Couette start-up: lid at L moving at U from t = 0. */
static double couette(double y, double t)
{
    double u = CH_U * y / CH_L;
    for (int n = 1; n < 400; n++)
        u += 2 * CH_U * ((n % 2) ? -1 : 1) / (n * PI) * sin(n * PI * y / CH_L) *
             exp(-(double)n * n * PI * PI * CH_NU * t / (CH_L * CH_L));
    return u;
}

/* The Laplacian that the viscous pair term (eq. 7) computes on a square lattice of spacing 1 for u = y^2 / 2
 * (exact value 1): the sum over neighbours of 2 (r . grad W) / (r^2 + eta^2) (u_a - u_b), quintic Wendland with
 * h = C_h sqrt(2) dp and eta^2 = 0.01 h^2. The eta^2 regularisation makes it about 1.5 % short at C_h = 1.8: a
 * steady flow driven by a body force then runs that much faster than theory. */
static double lattice_laplacian_factor(double ch)
{
    const double h = ch * sqrt(2.0), eta2 = 0.01 * h * h, alpha = 7 / (4 * PI * h * h);
    const int reach = (int)ceil(2 * h);
    double sum = 0;
    for (int i = -reach; i <= reach; i++)
        for (int j = -reach; j <= reach; j++) {
            const double r = hypot(i, j), q = r / h;
            if (r == 0 || q >= 2)
                continue;
            const double dwdr = -alpha * 5 * q * pow(1 - q / 2, 3) / h;
            sum += 2 * r * dwdr / (r * r + eta2) * (-(double)j * j / 2);
        }
    return sum;
}

/* Least-squares amplitude a of u = a u_ref(y) over the fluid particles of a snapshot. */
static double profile_amplitude(const surge_snapshot *s, double (*ref)(double y, double t), double t)
{
    double uu = 0, ur = 0;
    for (int i = 0; i < s->count; i++) {
        if (s->kind[i] != SURGE_KIND_FLUID)
            continue;
        const double r = ref(s->y_m[i], t);
        ur += s->vx_mps[i] * r;
        uu += r * r;
    }
    return ur / uu;
}

/* The channel's start-up against the analytic profile at 0.1 s and 1 s (steady_only: at 1 s alone, for steps so
 * long that 0.1 s is one backward-Euler step, whose error is first order in the step) */
static int test_channel(int poiseuille_flow, const char *profile_path, int steady_only)
{
    FILE *profile = profile_path ? fopen(profile_path, "w") : NULL;
    surge_sim *sim = load(poiseuille_flow ? "poiseuille.ini" : "couette.ini", NULL, 0);
    surge_snapshot snap = {0};
    const double times[2] = {0.1, 1.0};
    const double bounds[2] = {0.02, 0.02};
    for (int k = steady_only; k < 2; k++) {
        run_until(sim, times[k]);
        surge_sim_snapshot(sim, &snap);
        const double e = profile_error(&snap, poiseuille_flow ? poiseuille : couette, snap.time_s,
                                       poiseuille_flow ? CH_F * CH_L * CH_L / (8 * CH_NU) : CH_U, profile);
        char what[128];
        snprintf(what, sizeof what, "%s: L2 error / u_max at t = %.3f s", poiseuille_flow ? "poiseuille" : "couette",
                 snap.time_s);
        expect_below(what, e, bounds[k]);
    }
    if (poiseuille_flow) {
        /* steady: the flow is faster than theory by the viscous operator's lattice factor, and by nothing else */
        const double factor = lattice_laplacian_factor(surge_sim_params(sim)->numerics.ch);
        const double amplitude = profile_amplitude(&snap, poiseuille, snap.time_s);
        printf("poiseuille: steady amplitude %.5f, 1 / lattice Laplacian factor %.5f\n", amplitude, 1 / factor);
        expect_below("poiseuille: |amplitude x lattice factor - 1| at steady state", fabs(amplitude * factor - 1),
                     0.005);
    }
    surge_snapshot_free(&snap);
    surge_sim_destroy(sim);
    if (profile)
        fclose(profile);
    return failures;
}

static int test_hydrostatic(void)
{
    surge_sim *sim = load("still_tank.ini", NULL, 0);
    const surge_params *p = surge_sim_params(sim);
    const double depth = p->fluid.depth_m, g = p->body.gravity_mps2, rho0 = p->fluid.density_kgpm3;
    const double dp = p->numerics.dp_m;
    /* where p = 0: the fluid's top, half a spacing above the top row (the explicit scheme: its particles' density
     * says so); the implicit scheme holds p = 0 on the top row itself (docs/method.md, "The free surface"), half a
     * spacing lower, which puts its bottom pressure 0.5 dp / H low (2.6 % in this tank) */
    const double H = p->numerics.scheme == SURGE_SCHEME_IMPLICIT ? depth - 0.5 * dp : depth;
    const double volume0 = surge_sim_diagnostics(sim).fluid_volume_m2;
    run_until(sim, 1.0);
    surge_diagnostics d = surge_sim_diagnostics(sim);
    surge_snapshot s = {0};
    surge_sim_snapshot(sim, &s);
    /* pressure of the fluid particles in the lowest layer against rho0 g (H - y), within 0.5 % */
    double sum_p = 0, sum_ref = 0, worst = 0;
    int n = 0;
    for (int i = 0; i < s.count; i++) {
        if (s.kind[i] != SURGE_KIND_FLUID || s.y_m[i] > dp)
            continue;
        const double ref = rho0 * g * (H - s.y_m[i]);
        sum_p += s.pressure_pa[i];
        sum_ref += ref;
        worst = fmax(worst, fabs(s.pressure_pa[i] / ref - 1));
        n++;
    }
    printf("hydrostatic: %d particles in the bottom layer, t = %.3f s\n", n, s.time_s);
    expect_below("hydrostatic: |mean bottom pressure / (rho g (H - y)) - 1|", fabs(sum_p / sum_ref - 1), 0.005);
    expect_below("hydrostatic: worst bottom-layer particle pressure error", worst, 0.02);
    printf("hydrostatic: p = 0 taken %g m above the bed (the fluid's top %g m)\n", H, depth);
    expect_below("hydrostatic: max speed / sqrt(g H)", d.max_speed_mps / sqrt(g * H), 0.01);
    expect_below("hydrostatic: |fluid volume / initial - 1|", fabs(d.fluid_volume_m2 / volume0 - 1), 0.01);
    surge_snapshot_free(&s);
    surge_sim_destroy(sim);
    return failures;
}

/* Uniform film on an incline (GMD 2025 eq. 12): u(y) = g sin(theta) (2 H y - y^2) / (2 nu). */
static double film_g_sin, film_h, film_nu;
static double film(double y, double t)
{
    (void)t;
    return film_g_sin * (2 * film_h * y - y * y) / (2 * film_nu);
}

static int test_film(void)
{
    /* 20 particles in depth, one tenth of the benchmark's length; steady after a few H^2/nu = 1.25 s */
    const char *overrides[] = {"numerics.dp_m=0.0125", "domain.length_m=0.25", "fluid.x1_m=0.25", "numerics.ch=1.3",
                               "walls.layers=0"};
    surge_sim *sim = load("incline_film.ini", overrides, 5);
    const surge_params *p = surge_sim_params(sim);
    film_g_sin = p->body.gravity_mps2 * sin(p->body.slope_deg * PI / 180);
    film_h = p->fluid.depth_m;
    film_nu = p->fluid.viscosity_m2ps;
    const double volume0 = surge_sim_diagnostics(sim).fluid_volume_m2;
    run_until(sim, 3.0);
    surge_snapshot s = {0};
    surge_sim_snapshot(sim, &s);
    const double u_surface = film(film_h, 0);
    expect_below("film: L2 error of u(y) / surface speed at t = 3 s", profile_error(&s, film, s.time_s, u_surface, NULL),
                 0.03);
    surge_diagnostics d = surge_sim_diagnostics(sim);
    expect_below("film: |fluid volume / initial - 1|", fabs(d.fluid_volume_m2 / volume0 - 1), 0.01);
    expect_below("film: max density deviation", d.max_density_deviation, 0.02);
    surge_snapshot_free(&s);
    surge_sim_destroy(sim);
    return failures;
}

/* A run checkpointed half-way and restarted from the file ends bit-identical to the uninterrupted run. */
static int test_restart(const char *dir, const char *case_name)
{
    const char *overrides[] = {"time.end_s=0.2"};
    surge_sim *straight = load(case_name, overrides, 1);
    for (int i = 0; i < 200; i++)
        if (surge_sim_step(straight) != 0)
            return ++failures;
    surge_sim *first = load(case_name, overrides, 1);
    for (int i = 0; i < 85; i++)
        if (surge_sim_step(first) != 0)
            return ++failures;
    char path[1024], err[1024];
    snprintf(path, sizeof path, "%s/restart_test.bin", dir);
    if (surge_sim_checkpoint_write(first, path, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return ++failures;
    }
    surge_sim_destroy(first);
    surge_sim *second = surge_sim_checkpoint_read(path, NULL, 0, err, sizeof err);
    if (!second) {
        fprintf(stderr, "%s\n", err);
        return ++failures;
    }
    while (surge_sim_step_count(second) < 200)
        if (surge_sim_step(second) != 0)
            return ++failures;
    const uint64_t a = surge_sim_state_hash(straight), b = surge_sim_state_hash(second);
    printf("restart: hash uninterrupted %016llx, restarted %016llx (t = %.6f s, %.6f s)\n", (unsigned long long)a,
           (unsigned long long)b, surge_sim_time(straight), surge_sim_time(second));
    expect_below("restart: state hashes differ (0 = identical)", a != b, 0);
    /* the state moved: the check is not between two idle states */
    expect_below("restart: max speed after 200 steps is not zero (1 = zero)",
                 surge_sim_diagnostics(straight).max_speed_mps == 0, 0);
    surge_sim_destroy(straight);
    surge_sim_destroy(second);
    return failures;
}

/* The multigrid-preconditioned solves (implicit.preconditioner = amg) against the diagonal's on the Freydier front
 * (walls, the belt, the upstream wall, a free surface; dp 2 mm, C_h 1.3): both iterate on the same matrix-free
 * operators, so a step from the same start gives the same velocities to the solves' tolerances, where a solve that
 * stopped short or a preconditioner that changed the answer would differ by the velocities' own size. Over 20 steps
 * a particle on a threshold (the free-surface flag, the contact distance) can take the other branch in one run and
 * differ by a few per cent of the speed for a step or two (3 % at step 18 when written, 1.1e-3 in the root mean
 * square): the velocities after 20 steps are compared in the root mean square, more loosely. */
static double velocity_difference(const surge_snapshot *a, const surge_snapshot *b, int rms)
{
    double largest = 0, difference = 0, sum2 = 0;
    int fluid = 0;
    for (int k = 0; k < a->count; k++) {
        if (a->kind[k] != SURGE_KIND_FLUID)
            continue;
        const double d = hypot(a->vx_mps[k] - b->vx_mps[k], a->vy_mps[k] - b->vy_mps[k]);
        largest = fmax(largest, hypot(a->vx_mps[k], a->vy_mps[k]));
        difference = fmax(difference, d);
        sum2 += d * d, fluid++;
    }
    return (rms ? sqrt(sum2 / fluid) : difference) / largest;
}

#define HELD_ITERATIONS_RATIO 1.3
static int test_preconditioners(void)
{
    surge_snapshot first[3] = {{0}}, last[3] = {{0}};
    int32_t iterations[3] = {0}, viscous[3] = {0};
    long pressure_sum[3] = {0}; /* over the 20 steps */
    /* the third: amg with its hierarchies built every step, against which held ones must not cost iterations */
    const char *preconditioners[3] = {"implicit.preconditioner=jacobi", "implicit.preconditioner=amg",
                                      "implicit.preconditioner=amg"};
    const char *rebuild[3] = {"implicit.multigrid_rebuild_steps=16", "implicit.multigrid_rebuild_steps=16",
                              "implicit.multigrid_rebuild_steps=1"};
    for (int k = 0; k < 3; k++) {
        /* at the tolerance the bounds below were set at: at the default 1e-3 (since 2026-11-27) both take few
         * iterations and their ratio says less (6 against 17) */
        const char *overrides[] = {"numerics.scheme=implicit", "numerics.ch=1.3", "numerics.dp_m=0.002",
                                   "fluid.shape=lubrication", preconditioners[k], rebuild[k],
                                   "implicit.pressure_tolerance=1e-6"};
        surge_sim *sim = load("freydier_id1.ini", overrides, 7);
        for (int i = 0; i < 20; i++) {
            if (surge_sim_step(sim) != 0) {
                printf("preconditioners: %s: %s\n", preconditioners[k], surge_sim_health(sim)->message);
                surge_sim_destroy(sim);
                return ++failures;
            }
            pressure_sum[k] += surge_sim_diagnostics(sim).pressure_iterations;
            if (i == 0 && surge_sim_snapshot(sim, &first[k]) != 0) {
                surge_sim_destroy(sim);
                return ++failures;
            }
        }
        iterations[k] = surge_sim_diagnostics(sim).pressure_iterations;
        viscous[k] = surge_sim_diagnostics(sim).viscous_iterations;
        if (surge_sim_snapshot(sim, &last[k]) != 0) {
            surge_sim_destroy(sim);
            return ++failures;
        }
        surge_sim_destroy(sim);
    }
    printf("preconditioners: iterations at step 20: pressure jacobi %d, amg %d; viscous jacobi %d, amg %d\n",
           iterations[0], iterations[1], viscous[0], viscous[1]);
    /* the multigrid on its sparse stand-in must pay in iterations (46 against 9 for the pressure when written): a
     * stand-in that no longer resembles the operator still converges, only slowly */
    expect_below("preconditioners: amg's pressure iterations / jacobi's", (double)iterations[1] / iterations[0], 1.0 / 3);
    expect_below("preconditioners: amg's viscous iterations / jacobi's", (double)viscous[1] / viscous[0], 0.75);
    /* hierarchies held over 16 steps take about the iterations of ones built every step: a hierarchy that lost
     * track of its particles' order took 6.0 times as many when written. The rows under the free surface change
     * with the surface's mirror images from step to step, which a held stand-in does not follow: 1.23 on this
     * scene (1.11 with the kernels cut off under the surface, implicit.surface_images = 0) */
    printf("preconditioners: pressure iterations over 20 steps: amg held %ld, built every step %ld\n",
           pressure_sum[1], pressure_sum[2]);
    expect_below("preconditioners: pressure iterations, held hierarchies / built every step",
                 (double)pressure_sum[1] / pressure_sum[2], HELD_ITERATIONS_RATIO);
    expect_below("preconditioners: largest velocity difference / largest speed after 1 step",
                 velocity_difference(&first[0], &first[1], 0), 1e-3);
    expect_below("preconditioners: root-mean-square velocity difference / largest speed after 20 steps",
                 velocity_difference(&last[0], &last[1], 1), 1e-2);
    expect_below("preconditioners: root-mean-square velocity difference / largest speed after 20 steps, held "
                 "hierarchies against built every step", velocity_difference(&last[2], &last[1], 1), 1e-2);
    for (int k = 0; k < 3; k++)
        surge_snapshot_free(&first[k]), surge_snapshot_free(&last[k]);
    return failures;
}

/* A linear solve of the implicit scheme that cannot converge in the iterations allowed stops the step with the
 * solver check, naming the solve, and leaves the state as it was (the film, one iteration allowed). */
static int test_solver_failure(void)
{
    const char *overrides[] = {"numerics.dp_m=0.0125", "domain.length_m=0.25", "fluid.x1_m=0.25", "numerics.ch=1.3",
                               "walls.layers=0", "numerics.scheme=implicit", "implicit.max_iterations=1"};
    surge_sim *sim = load("incline_film.ini", overrides, 7);
    const uint64_t before = surge_sim_state_hash(sim);
    const int rc = surge_sim_step(sim);
    const surge_health *h = surge_sim_health(sim);
    printf("solver failure: step returned %d, check '%s': %s\n", rc, surge_health_check_name(h->check), h->message);
    expect_below("solver failure: the step was not refused (1 = not refused)", rc == 0, 0);
    expect_below("solver failure: the check is not the solver's (1 = another)", h->check != SURGE_CHECK_SOLVER, 0);
    expect_below("solver failure: the message names no solve (1 = none)",
                 !strstr(h->message, "pressure solve") && !strstr(h->message, "viscous solve"), 0);
    expect_below("solver failure: the state changed (1 = changed)", surge_sim_state_hash(sim) != before, 0);
    surge_sim_destroy(sim);
    return failures;
}

int main(int argc, char **argv)
{
    const char *positional[3] = {NULL, NULL, NULL};
    int npos = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-s") && i + 1 < argc && extra_count < 16)
            extra[extra_count++] = argv[++i];
        else if (npos < 3 && strcmp(argv[i], "-s"))
            positional[npos++] = argv[i];
        else {
            fprintf(stderr, "test_physics: unexpected argument '%s'\n", argv[i]);
            return 2;
        }
    }
    if (npos < 1) {
        fprintf(stderr, "usage: test_physics hydrostatic|poiseuille|couette|poiseuille_steady|couette_steady|film|restart [file] [-s key=value ...]\n");
        return 2;
    }
    const char *name = positional[0], *arg = positional[1];
    if (!strcmp(name, "hydrostatic"))
        return test_hydrostatic() ? 1 : 0;
    if (!strcmp(name, "poiseuille"))
        return test_channel(1, arg, 0) ? 1 : 0;
    if (!strcmp(name, "couette"))
        return test_channel(0, arg, 0) ? 1 : 0;
    if (!strcmp(name, "poiseuille_steady"))
        return test_channel(1, arg, 1) ? 1 : 0;
    if (!strcmp(name, "couette_steady"))
        return test_channel(0, arg, 1) ? 1 : 0;
    if (!strcmp(name, "film"))
        return test_film() ? 1 : 0;
    if (!strcmp(name, "solver_failure"))
        return test_solver_failure() ? 1 : 0;
    if (!strcmp(name, "preconditioners"))
        return test_preconditioners() ? 1 : 0;
    if (!strcmp(name, "restart"))
        return test_restart(arg ? arg : ".", positional[2] ? positional[2] : "belt_front.ini") ? 1 : 0;
    fprintf(stderr, "test_physics: unknown test '%s'\n", name);
    return 2;
}
