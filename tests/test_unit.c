/* Unit tests: kernel normalisation and gradient, equation of state, neighbour search against brute force with
 * periodic wrap, the neighbour lists against brute force over many steps of reuse, live parameter changes, the continuity rate at the belt-wall corner, density diffusion of a
 * linear field, the threads' shares of the fluid lists, the step's phase timers, a socket that works on once its peer
 * guard (stream/src) has stopped.
 * usage: test_unit NAME (the names in main) */
#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zmq.h>

#include "peer_guard.h"
#include "physics/eos.h"
#include "sim_internal.h"
#include "boulders/boulders.h"
#include "boundaries/boundary.h"
#include "health.h"
#include "neighbours/grid.h"
#include "neighbours/neighbours.h"
#include "physics/interaction.h"
#include "physics/shifting.h"
#include "scene/scales.h"
#include "scene/scene.h"
#include "scheme/implicit/implicit.h"

static int failures = 0;

static void expect_below(const char *what, double value, double bound)
{
    const int ok = value <= bound;
    printf("%-60s %12.4g  (bound %g)  %s\n", what, value, bound, ok ? "ok" : "FAILED");
    failures += !ok;
}

/* A solver for cases/<name>, its dp changed when dp_m > 0, and boulders set by the caller's edit; NULL (the error
 * printed) when the case does not load or build. */
static surge_sim *case_sim(const char *name, double dp_m, void (*edit)(surge_params *))
{
    surge_params p = surge_default_params();
    char path[512], err[256];
    snprintf(path, sizeof path, "%s/cases/%s", SURGE_SOURCE_DIR, name);
    if (surge_params_load(&p, path, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return NULL;
    }
    if (dp_m > 0)
        p.numerics.dp_m = dp_m;
    if (edit)
        edit(&p);
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim)
        fprintf(stderr, "%s\n", err);
    return sim;
}

/* lanes_totals (lanes.h): eight quantities' lanes added by a transpose must equal, bit for bit, each quantity's lanes
 * added one by one in lane order, as the pair loops' state hashes rely on; values of mixed sign and magnitude so
 * that another order would round differently. */
static int test_lanes(void)
{
    real lanes[8][PAIR_LANES];
    unsigned state = 12345u;
    for (int q = 0; q < 8; q++)
        for (int l = 0; l < PAIR_LANES; l++) {
            state = state * 1103515245u + 12345u;
            lanes[q][l] = (real)(((double)(state >> 8) / (1 << 24) - 0.5) * pow(10.0, (double)((q + l) % 7 - 3)));
        }
    const real *const rows[8] = {lanes[0], lanes[1], lanes[2], lanes[3], lanes[4], lanes[5], lanes[6], lanes[7]};
    real total[8];
    lanes_totals(rows, total);
    int mismatched = 0, order_matters = 0;
    for (int q = 0; q < 8; q++) {
        real sequential = 0, reversed = 0;
        for (int l = 0; l < PAIR_LANES; l++)
            sequential += lanes[q][l], reversed += lanes[q][PAIR_LANES - 1 - l];
        mismatched += total[q] != sequential;
        order_matters += reversed != sequential;
    }
    printf("lanes: %d of 8 transposed totals differ from the lane-order sums; %d of 8 would differ in reverse order\n",
           mismatched, order_matters);
    expect_below("lanes: totals that differ from the lane-order sums", mismatched, 0);
    expect_below("lanes: the data can tell the order apart (8 - quantities whose reverse sum differs)",
                 8 - order_matters, 7);
    return failures;
}

static int test_kernel(void)
{
    const double h = 0.01;
    kernel2d k = kernel2d_make(h);
    /* integral over the plane: 2 pi int_0^2h W(r) r dr = 1 (midpoint rule) */
    const int n = 200000;
    double integral = 0;
    for (int i = 0; i < n; i++) {
        double r = (i + 0.5) * 2 * h / n;
        integral += 2 * SURGE_PI * kernel2d_w(&k, (real)r) * r * (2 * h / n);
    }
    expect_below("kernel: |integral of W - 1|", fabs(integral - 1), 1e-5);
    /* lattice sum at dp = h / (C_h sqrt 2), C_h = 1.8: sum W dp^2 = 1 */
    const double dp = h / (1.8 * sqrt(2.0));
    double sum = 0;
    for (int i = -10; i <= 10; i++)
        for (int j = -10; j <= 10; j++)
            sum += kernel2d_w(&k, (real)(dp * sqrt((double)(i * i + j * j)))) * dp * dp;
    expect_below("kernel: |lattice sum W dp^2 - 1| (C_h = 1.8)", fabs(sum - 1), 1e-3);
    /* gradient factor against a central difference of W */
    double worst = 0;
    for (int i = 1; i < 400; i++) {
        const double r = i * 2 * h / 400, e = 1e-3 * h;
        const double dwdr = (kernel2d_w(&k, (real)(r + e)) - kernel2d_w(&k, (real)(r - e))) / (2 * e);
        const double analytic = kernel2d_grad_factor(&k, (real)r) * r;
        worst = fmax(worst, fabs(analytic - dwdr) / (k.alpha / h));
    }
    expect_below("kernel: max |F r - dW/dr| / (alpha / h)", worst, 2e-3);
    expect_below("kernel: W(2h) (compact support)", fabs(kernel2d_w(&k, (real)(2 * h))), 0);
    expect_below("kernel: |W(0) - 7/(4 pi h^2)| / W(0)", fabs(kernel2d_w(&k, 0) / (7 / (4 * SURGE_PI * h * h)) - 1), 1e-6);
    return failures;
}

static int test_eos(void)
{
    const double rho0 = 1000, c0 = 20, b = c0 * c0 * rho0 / 7;
    expect_below("eos: P(rho0)", fabs(tait_pressure((real)rho0, (real)rho0, (real)b)), 0);
    const double p = tait_pressure((real)1010, (real)rho0, (real)b);
    const double exact = b * (pow(1.01, 7) - 1);
    expect_below("eos: |P(1.01 rho0) / B((1.01)^7 - 1) - 1|", fabs(p / exact - 1), 1e-5);
    /* dP/drho at rho0 = c0^2 */
    const double slope = (tait_pressure((real)1000.5, (real)rho0, (real)b) - tait_pressure((real)999.5, (real)rho0, (real)b));
    expect_below("eos: |dP/drho(rho0) / c0^2 - 1|", fabs(slope / (c0 * c0) - 1), 1e-3);
    expect_below("eos: |rho(P(rho)) - rho| / rho0", fabs(tait_density(exact, rho0, b) - 1010) / rho0, 1e-12);
    return failures;
}

/* Every pair within 2h found through the cell spans equals the brute-force set with minimum-image in x. */
static int test_neighbours(void)
{
    surge_params p = surge_default_params();
    p.domain.length_m = 0.1;
    p.domain.height_m = 0.05;
    p.fluid.x0_m = 0.0;
    p.fluid.x1_m = 0.1;
    p.fluid.depth_m = 0.04;
    p.walls.upstream = false;
    p.numerics.dp_m = 0.004;
    char err[256];
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    srand(12345);
    for (int a = sim->wall_count; a < sim->count; a++) { /* scatter fluid at random, some right at x = 0 and L */
        sim->x[a] = (a % 17 == 0) ? (a % 2 ? 0.0 : nextafter(0.1, 0)) : 0.1 * rand() / ((double)RAND_MAX + 1);
        sim->y[a] = 0.045 * rand() / ((double)RAND_MAX + 1);
        sim->neighbours.x_build[a] = sim->x[a], sim->neighbours.y_build[a] = sim->y[a];
    }
    grid_sort_fluid(sim);
    const double support2 = 4 * sim->derived.h_m * sim->derived.h_m, L = p.domain.length_m;
    long found = 0, expected = 0, mismatches = 0;
    const cell_grid *g = &sim->grid;
    for (int a = sim->wall_count; a < sim->count; a++) {
        int cell_count = 0;
        const int cx = grid_cell_x(g, sim->x[a]), cy = grid_cell_y(g, sim->y[a]);
        cell_span spans[2];
        const int ns = grid_row_spans(g, cx, spans);
        for (int row = cy - 1; row <= cy + 1; row++) {
            if (row < 0 || row >= g->ncy)
                continue;
            for (int s = 0; s < ns; s++) {
                const int c0 = row * g->ncx + spans[s].first_cell, c1 = row * g->ncx + spans[s].last_cell + 1;
                for (int pass = 0; pass < 2; pass++) {
                    const int *start = pass ? g->wall_start : g->fluid_start;
                    for (int b = start[c0]; b < start[c1]; b++) {
                        double dx = sim->x[a] - (sim->x[b] + spans[s].shift_x), dy = sim->y[a] - sim->y[b];
                        if (b != a && dx * dx + dy * dy < support2)
                            cell_count++;
                    }
                }
            }
        }
        int brute = 0;
        for (int b = 0; b < sim->count; b++) {
            double dx = fabs(sim->x[a] - sim->x[b]);
            dx = fmin(dx, L - dx);
            double dy = sim->y[a] - sim->y[b];
            if (b != a && dx * dx + dy * dy < support2)
                brute++;
        }
        found += cell_count;
        expected += brute;
        mismatches += cell_count != brute;
    }
    printf("neighbours: %ld pairs found through cells, %ld by brute force, %d particles\n", found, expected,
           sim->count - sim->wall_count);
    expect_below("neighbours: particles whose neighbour count differs", (double)mismatches, 0);
    expect_below("neighbours: enough pairs to mean something (1 = too few)", found < 1000, 0);
    surge_sim_destroy(sim);
    return failures;
}

/* Pairs within 2h of fluid particle a (at positions px, py) that its neighbour lists lack; mark is scratch of
 * sim->count zeros. */
static long missing_pairs(const surge_sim *sim, int a, const double *px, const double *py, int8_t *mark)
{
    const neighbour_lists *nl = &sim->neighbours;
    const int i = a - sim->wall_count;
    const double period = sim->grid.period_m, support2 = 4 * sim->derived.h_m * sim->derived.h_m;
    /* the periodic image each entry was listed at, from its offset at the build */
    const double *xb = nl->x_build;
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
        const int b = nl->fluid_index[e];
        mark[b] = (int8_t)((period > 0 ? round((xb[a] - xb[b] - nl->fluid_dx0[e]) / period) : 0) + 2);
    }
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
        const int b = nl->wall_index[e];
        mark[b] = (int8_t)((period > 0 ? round((xb[a] - xb[b] - nl->wall_dx0[e]) / period) : 0) + 2);
    }
    long missing = 0;
    for (int b = 0; b < sim->count; b++) {
        const double image = period > 0 ? round((px[a] - px[b]) / period) : 0;
        const double dx = px[a] - image * period - px[b], dy = py[a] - py[b];
        if (b != a && dx * dx + dy * dy < support2 && mark[b] != (int8_t)(image + 2))
            missing++;
    }
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
        mark[nl->fluid_index[e]] = 0;
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++)
        mark[nl->wall_index[e]] = 0;
    return missing;
}

/* Fluid within 2h of boulder particle k (positions px, py) that its list of the fluid around it lacks (the disc's
 * force, eq. 10); mark is scratch of sim->count zeros. */
static long missing_boulder_pairs(const surge_sim *sim, int k, const double *px, const double *py, int8_t *mark)
{
    const neighbour_lists *nl = &sim->neighbours;
    const double period = sim->grid.period_m, support2 = 4 * sim->derived.h_m * sim->derived.h_m;
    const double *xb = nl->x_build;
    for (int64_t e = nl->wall_fluid_first[k]; e < nl->wall_fluid_first[k + 1]; e++) {
        const int a = nl->wall_fluid_index[e];
        mark[a] = (int8_t)((period > 0 ? round((xb[k] - xb[a] - nl->wall_fluid_dx0[e]) / period) : 0) + 2);
    }
    long missing = 0;
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double image = period > 0 ? round((px[k] - px[a]) / period) : 0;
        const double dx = px[k] - image * period - px[a], dy = py[k] - py[a];
        if (dx * dx + dy * dy < support2 && mark[a] != (int8_t)(image + 2))
            missing++;
    }
    for (int64_t e = nl->wall_fluid_first[k]; e < nl->wall_fluid_first[k + 1]; e++)
        mark[nl->wall_fluid_index[e]] = 0;
    return missing;
}

/* Fluid within 2h of boulder particle k's mDBC ghost node that its ghost list lacks (positions now); mark is scratch
 * of sim->count zeros. */
static long missing_ghost_pairs(const surge_sim *sim, int k, int8_t *mark)
{
    const neighbour_lists *nl = &sim->neighbours;
    const double period = sim->grid.period_m, support2 = 4 * sim->derived.h_m * sim->derived.h_m;
    const double *xb = nl->x_build;
    for (int64_t e = nl->ghost_fluid_first[k]; e < nl->ghost_fluid_first[k + 1]; e++) {
        const int a = nl->ghost_fluid_index[e];
        const double offset = xb[k] + nl->ghost_dx_build[k] - xb[a] - nl->ghost_fluid_dx0[e];
        mark[a] = (int8_t)((period > 0 ? round(offset / period) : 0) + 2);
    }
    const double gx = sim->x[k] + sim->ghost_dx[k], gy = sim->y[k] + sim->ghost_dy[k];
    long missing = 0;
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double image = period > 0 ? round((gx - sim->x[a]) / period) : 0;
        const double dx = gx - image * period - sim->x[a], dy = gy - sim->y[a];
        if (dx * dx + dy * dy < support2 && mark[a] != (int8_t)(image + 2))
            missing++;
    }
    for (int64_t e = nl->ghost_fluid_first[k]; e < nl->ghost_fluid_first[k + 1]; e++)
        mark[nl->ghost_fluid_index[e]] = 0;
    return missing;
}

/* The neighbour lists against brute force over many steps of reuse: a periodic sheared layer with a moving,
 * spinning boulder and randomly displaced particles; every pair within 2h at the step's start and at the
 * corrector's positions (advanced half the largest time step) is listed; lists are reused; a fast particle forces
 * a build. */
static int test_neighbour_lists(void)
{
    surge_params p = surge_default_params();
    p.domain.length_m = 0.2, p.domain.height_m = 0.1, p.domain.periodic_x = true;
    p.fluid.x0_m = 0, p.fluid.x1_m = 0.2, p.fluid.depth_m = 0.1;
    p.walls.top = true, p.walls.upstream = false, p.walls.ramp_s = 0;
    p.walls.bottom_speed_mps = -0.5, p.walls.top_speed_mps = 0.5;
    p.body.gravity_mps2 = 0, p.body.slope_deg = 0;
    p.boulders.placement = SURGE_BOULDERS_LIST;
    snprintf(p.boulders.list_m, sizeof p.boulders.list_m, "0.1 0.05 0.0125 0.3 0 20");
    p.numerics.dp_m = 0.0025, p.numerics.ch = 1.5, p.numerics.c0_mps = 10;
    char err[256];
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    srand(2026);
    const double dp = p.numerics.dp_m;
    for (int a = sim->wall_count; a < sim->count; a++) {
        sim->x[a] += 0.15 * dp * (2.0 * rand() / RAND_MAX - 1);
        sim->y[a] += 0.15 * dp * (2.0 * rand() / RAND_MAX - 1);
    }
    const double half_dt_max = 0.5 * p.numerics.cfl * sim->derived.h_m / sim->derived.c0_mps;
    double *cx = malloc((size_t)sim->count * sizeof *cx), *cy = malloc((size_t)sim->count * sizeof *cy);
    int8_t *mark = calloc((size_t)sim->count, 1);
    long missing_start = 0, missing_corrector = 0, pairs = 0;
    const int steps = 400;
    int healthy = 1;
    for (int s = 0; s < steps && healthy; s++) {
        if (neighbours_update(sim) != 0)
            break;
        for (int k = 0; k < sim->count; k++) { /* where the corrector can see them at most: moving particles only */
            const int moves = k >= sim->wall_count || sim->boulders.of_wall[sim->id[k]] >= 0;
            cx[k] = sim->x[k] + (moves ? half_dt_max * sim->vx[k] : 0);
            cy[k] = sim->y[k] + (moves ? half_dt_max * sim->vy[k] : 0);
        }
        if (s % 20 == 0) {
            for (int a = sim->wall_count; a < sim->count; a++) {
                missing_start += missing_pairs(sim, a, sim->x, sim->y, mark);
                missing_corrector += missing_pairs(sim, a, cx, cy, mark);
            }
            for (int k = 0; k < sim->wall_count; k++)
                if (sim->boulders.of_wall[sim->id[k]] >= 0) {
                    missing_start += missing_boulder_pairs(sim, k, sim->x, sim->y, mark);
                    missing_corrector += missing_boulder_pairs(sim, k, cx, cy, mark);
                    missing_start += missing_ghost_pairs(sim, k, mark);
                }
            pairs += sim->neighbours.fluid_first[sim->count - sim->wall_count];
        }
        healthy = surge_sim_step(sim) == 0;
    }
    const int64_t builds = sim->neighbours.builds;
    printf("neighbour_lists: %d steps, %lld builds, %ld list entries checked, boulder at x = %.4f m\n", steps,
           (long long)builds, pairs, sim->boulders.x[0]);
    expect_below("neighbour_lists: the run stays healthy (1 = it did not)", !healthy, 0);
    expect_below("neighbour_lists: pairs within 2h missing at the step's start", (double)missing_start, 0);
    expect_below("neighbour_lists: pairs within 2h missing at the corrector's positions", (double)missing_corrector, 0);
    expect_below("neighbour_lists: builds per step (lists reused)", (double)builds / steps, 0.5);
    expect_below("neighbour_lists: enough builds to test reuse across builds (1 = fewer than 3)", builds < 3, 0);
    /* a particle fast enough to cross the skin in half a step forces a build at once */
    sim->vx[sim->wall_count + 7] = (real)(sim->neighbours.skin_m / half_dt_max);
    neighbours_update(sim);
    expect_below("neighbour_lists: a fast particle forces a build (1 = no build)",
                 sim->neighbours.builds != builds + 1, 0);
    free(cx);
    free(cy);
    free(mark);
    surge_sim_destroy(sim);
    return failures;
}

/* Live parameter changes between steps: accepted for live keys (and take effect), refused otherwise. */
static int test_set_param(void)
{
    surge_params p = surge_default_params();
    char err[256];
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    int rc = surge_sim_set_param(sim, "fluid.viscosity_m2ps", "0.006", err, sizeof err);
    expect_below("set_param: live viscosity accepted (rc)", rc != 0, 0);
    expect_below("set_param: |viscosity - 0.006|", fabs(surge_sim_params(sim)->fluid.viscosity_m2ps - 0.006), 0);
    rc = surge_sim_set_param(sim, "body.slope_deg", "30", err, sizeof err);
    expect_below("set_param: |gx - g sin 30deg| after a slope change", fabs(sim->gx - 9.81 * 0.5) + (rc != 0), 1e-12);
    rc = surge_sim_set_param(sim, "numerics.dp_m", "0.001", err, sizeof err);
    printf("set_param: numerics.dp_m refused with: %s\n", err);
    expect_below("set_param: non-live numerics.dp_m refused (rc == 0 is a failure)", rc == 0, 0);
    expect_below("set_param: message names why", strstr(err, "cannot change") == NULL, 0);
    rc = surge_sim_set_param(sim, "body.slope_deg", "95", err, sizeof err);
    printf("set_param: slope 95 refused with: %s\n", err);
    expect_below("set_param: out-of-range slope refused and slope unchanged",
                 (rc == 0) + fabs(surge_sim_params(sim)->body.slope_deg - 30), 0);
    rc = surge_sim_set_param(sim, "fluid.nosuch", "1", err, sizeof err);
    expect_below("set_param: unknown key refused", rc == 0, 0);
    /* the tangential film (the default) takes the measured share: the cut-off model is refused live while it is on,
     * the setting kept and the message naming the way out; with the sliding film the cut-off model is taken, and the
     * tangential film then refused */
    rc = surge_sim_set_param(sim, "contacts.lubrication_resolved", "cutoff", err, sizeof err);
    printf("set_param: lubrication_resolved = cutoff with the tangential film refused with: %s\n", err);
    expect_below("set_param: the cut-off model beside the tangential film refused and the setting kept",
                 (rc == 0) + (surge_sim_params(sim)->contacts.lubrication_resolved != SURGE_LUBRICATION_MEASURED), 0);
    expect_below("set_param: ... and the message names the sliding film",
                 strstr(err, "lubrication_tangential = sliding") == NULL, 0);
    rc = surge_sim_set_param(sim, "contacts.lubrication_tangential", "sliding", err, sizeof err) +
         surge_sim_set_param(sim, "contacts.lubrication_resolved", "cutoff", err, sizeof err);
    expect_below("set_param: the sliding film, then the cut-off model, taken (rc)", rc != 0, 0);
    rc = surge_sim_set_param(sim, "contacts.lubrication_tangential", "reynolds", err, sizeof err);
    printf("set_param: lubrication_tangential = reynolds with the cut-off model refused with: %s\n", err);
    expect_below("set_param: tangential film without the measured share refused and the setting kept",
                 (rc == 0) + (surge_sim_params(sim)->contacts.lubrication_tangential != SURGE_TANGENTIAL_SLIDING), 0);
    expect_below("set_param: ... and the message names what it needs",
                 strstr(err, "lubrication_resolved = measured") == NULL, 0);
    /* the films' share: the scheme's own, and live the other scheme's, which the contact settings then read */
    expect_below("set_param: the explicit scheme starts with its own film share",
                 sim->film_share != scheme_explicit.film_share, 0);
    rc = surge_sim_set_param(sim, "contacts.lubrication_share", "implicit", err, sizeof err);
    expect_below("set_param: lubrication_share = implicit with the cut-off model refused", rc == 0, 0);
    rc = surge_sim_set_param(sim, "contacts.lubrication_resolved", "measured", err, sizeof err) +
         surge_sim_set_param(sim, "contacts.lubrication_share", "implicit", err, sizeof err);
    expect_below("set_param: lubrication_share = implicit with the measured film taken, and the share the implicit "
                 "scheme's", (rc != 0) + (sim->film_share != scheme_implicit.film_share), 0);
    rc = surge_sim_set_param(sim, "contacts.lubrication_share", "scheme", err, sizeof err);
    expect_below("set_param: lubrication_share = scheme gives the explicit scheme's own back",
                 (rc != 0) + (sim->film_share != scheme_explicit.film_share), 0);
    surge_sim_set_param(sim, "contacts.lubrication_resolved", "cutoff", err, sizeof err);
    /* a viscosity inside its range that would hold the step under the collapse limit (h^2 / nu) is refused before
     * it applies, naming why; one that keeps the step above it is taken */
    surge_sim_set_param(sim, "body.slope_deg", "0", err, sizeof err);
    expect_below("set_param: a first step (rc)", surge_sim_step(sim) != 0, 0);
    const double nu = surge_sim_params(sim)->fluid.viscosity_m2ps;
    rc = surge_sim_set_param(sim, "fluid.viscosity_m2ps", "99", err, sizeof err);
    printf("set_param: viscosity 99 refused with: %s\n", err);
    expect_below("set_param: a viscosity that collapses the time step refused (rc == 0 is a failure)", rc == 0, 0);
    expect_below("set_param: ... and the viscosity unchanged", fabs(surge_sim_params(sim)->fluid.viscosity_m2ps - nu), 0);
    expect_below("set_param: ... and the message names the collapse", strstr(err, "collapsed time step") == NULL, 0);
    rc = surge_sim_set_param(sim, "fluid.viscosity_m2ps", "0.05", err, sizeof err);
    expect_below("set_param: a tenfold viscosity accepted (rc)", rc != 0, 0);
    expect_below("set_param: ... and the next step healthy (rc)", surge_sim_step(sim) != 0, 0);
    surge_sim_destroy(sim);
    /* the implicit scheme's bound: its body-force limit force_cfl sqrt(h / g), which sets its first step at rest */
    p.numerics.scheme = SURGE_SCHEME_IMPLICIT;
    if (!(sim = surge_sim_create(&p, err, sizeof err))) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    expect_below("set_param: an implicit first step (rc)", surge_sim_step(sim) != 0, 0);
    rc = surge_sim_set_param(sim, "implicit.force_cfl", "0.0001", err, sizeof err);
    printf("set_param: implicit.force_cfl 0.0001 refused with: %s\n", err);
    expect_below("set_param: an implicit step bound 4000 times shorter refused (rc == 0 is a failure)", rc == 0, 0);
    rc = surge_sim_set_param(sim, "implicit.force_cfl", "0.2", err, sizeof err);
    expect_below("set_param: half the implicit step bound accepted (rc)", rc != 0, 0);
    surge_sim_destroy(sim);
    return failures;
}

/* The belt-upstream-wall corner (docs/method.md): fluid at rest on a belt moving under a fixed wall has no
 * velocity divergence, since the belt moves along its own face. The density rate of the fluid within 3 dp of the
 * corner must stay near zero with either continuity form. When the bed under the wall was fixed, its jump from
 * the belt's velocity read as a compression of 0.098 u_b/dp there (8e-5 now), which spread the particles apart
 * over seconds (docs/validation/freydier.md). */
static int test_corner_continuity(void)
{
    for (int renormalised = 0; renormalised <= 1; renormalised++) {
        surge_params p = surge_default_params();
        p.domain.length_m = 0.12;
        p.domain.height_m = 0.04;
        p.domain.periodic_x = true;
        p.walls.left = p.walls.right = p.walls.top = false;
        p.walls.bottom = p.walls.upstream = true;
        p.walls.upstream_x_m = 0.012;
        p.walls.upstream_height_m = 0.03;
        p.walls.bottom_speed_mps = -0.075;
        p.walls.ramp_s = 0;
        p.fluid.x0_m = 0.012;
        p.fluid.x1_m = 0.072;
        p.fluid.depth_m = 0.016;
        p.numerics.dp_m = 0.001;
        p.numerics.continuity_correction = renormalised;
        char err[256];
        surge_sim *sim = surge_sim_create(&p, err, sizeof err);
        if (!sim) {
            fprintf(stderr, "%s\n", err);
            return 1;
        }
        boundary_wall_speeds(sim, 1.0);
        if (neighbours_update(sim) != 0)
            return 1;
        interaction_prepare(sim);
        boundary_update(sim);
        interaction_compute(sim, 0);
        const double dp = p.numerics.dp_m, strain_scale = fabs(p.walls.bottom_speed_mps) / dp;
        double corner = 0, bulk = 0;
        int corner_count = 0, bulk_count = 0;
        for (int a = sim->wall_count; a < sim->count; a++) {
            const double rate = fabs(sim->drho[a] / sim->rho[a]) / strain_scale;
            if (sim->x[a] - p.walls.upstream_x_m < 3 * dp && sim->y[a] < 3 * dp)
                corner = fmax(corner, rate), corner_count++;
            else if (sim->x[a] - p.walls.upstream_x_m > 10 * dp && sim->x[a] < p.fluid.x1_m - 10 * dp)
                bulk = fmax(bulk, rate), bulk_count++;
        }
        expect_below("corner_continuity: no fluid in the corner or the bulk (1 = none)",
                     corner_count == 0 || bulk_count == 0, 0);
        expect_below("corner_continuity: bulk rate / (u_b/dp)", bulk, 0.01);
        printf("corner_continuity (%s): max |drho/dt| / (rho u_b / dp) = %.2e within 3 dp of the corner, "
               "%.2e in the bulk\n", renormalised ? "renormalised" : "plain", corner, bulk);
        expect_below(renormalised ? "corner_continuity: renormalised, corner rate / (u_b/dp)"
                                  : "corner_continuity: plain, corner rate / (u_b/dp)", corner, 0.01);
        surge_sim_destroy(sim);
    }
    return failures;
}

/* A 2 cm layer on a no-slip bed, periodic over 0.1 m, dp = 5 mm: the scene of the single-particle tests below */
static surge_params small_bed_params(void)
{
    surge_params p = surge_default_params();
    p.domain.length_m = 0.1;
    p.domain.height_m = 0.05;
    p.domain.periodic_x = true;
    p.walls.left = p.walls.right = p.walls.top = p.walls.upstream = false;
    p.walls.bottom = true;
    p.fluid.x0_m = 0;
    p.fluid.x1_m = 0.1;
    p.fluid.depth_m = 0.02;
    p.numerics.dp_m = 0.005;
    return p;
}

/* The walls' no-penetration term read at the face (boundary.c): the ghost node's approach carried to the face by
 * the rate a volume-keeping flow has along the normal. On a flat bed under a 16 dp layer, for every bed particle
 * away from the periodic seam, (a) a volume-keeping stagnation flow onto the bed, v = (a (x - xc), -a y), reads no
 * approach (the fluid at the face does not move toward it: a thinning layer), and (b) a pure compression toward the
 * bed, v = (0, -k y), reads the ghost node's approach k y_ghost: the fluid's own compression is not carried, as the
 * full gradient would (it read 0 there and fed pressure waves near a belt). Both fields are linear, which the
 * first-order interpolation holds exactly where the kernel is full. */
static double no_penetration_error(int compression)
{
    surge_params p = small_bed_params(); /* a 0.1 m bed at rest under a 16 dp layer */
    p.walls.bottom_speed_mps = 0;
    p.fluid.depth_m = 0.016;
    p.numerics.dp_m = 0.001;
    char err[256];
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "%s\n", err);
        return INFINITY;
    }
    const double rate_per_s = 2.0, xc = 0.05;
    for (int a = sim->wall_count; a < sim->count; a++) {
        sim->rho[a] = (real)sim->rho0;
        sim->vx[a] = (real)(compression ? 0.0 : rate_per_s * (sim->x[a] - xc));
        sim->vy[a] = (real)(-rate_per_s * sim->y[a]);
    }
    double largest = 0;
    if (neighbours_update(sim) == 0) {
        interaction_prepare(sim);
        boundary_update(sim);
        int checked = 0;
        for (int b = 0; b < sim->wall_count; b++) {
            if (fabs(sim->x[b] - xc) > 0.02 || sim->y[b] > 0)
                continue;
            const double ghost_y_m = sim->y[b] + sim->ghost_dy[b];
            const double expected_mps = compression ? rate_per_s * ghost_y_m : 0.0;
            const double read_mps = sim->wall_cont_vy[b] - sim->vy[b];
            largest = fmax(largest, fabs(read_mps - expected_mps) / (rate_per_s * ghost_y_m));
            checked++;
        }
        if (checked == 0)
            largest = INFINITY;
    } else
        largest = INFINITY;
    surge_sim_destroy(sim);
    return largest;
}

static int test_no_penetration_face(void)
{
    expect_below("no_penetration_face: volume-keeping stagnation flow, |read - 0| / (rate y_ghost)",
                 no_penetration_error(0), 1e-4);
    expect_below("no_penetration_face: compression, |read - rate y_ghost| / (rate y_ghost)", no_penetration_error(1),
                 1e-4);
    return failures;
}

/* The wall treatment's contact and shift rules (docs/method.md, Walls): a fluid particle put 0.1 dp above
 * the bed face and thrown at it at 0.5 m/s leaves the step with no velocity toward the face, and a shift that would
 * carry it further in stops at the repulsion's reach. Without the rules (reach 0) the same particle keeps
 * approaching. */
static double contact_rule_case(double reach_dp, double *shift_room_m, double *shift_y_m, double *gap_m)
{
    surge_params p = small_bed_params();
    p.walls.face_repulsion_reach_dp = reach_dp;
    char err[256];
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "%s\n", err);
        return NAN;
    }
    int bed = -1, a = -1; /* the top bed particle nearest x = 0.05 m, and the lowest fluid particle above it */
    for (int b = 0; b < sim->wall_count; b++)
        if (bed < 0 || sim->y[b] > sim->y[bed] + 1e-9 ||
            (fabs(sim->y[b] - sim->y[bed]) < 1e-9 && fabs(sim->x[b] - 0.05) < fabs(sim->x[bed] - 0.05)))
            bed = b;
    for (int f = sim->wall_count; f < sim->count; f++)
        if (fabs(sim->x[f] - sim->x[bed]) < 1e-9 && (a < 0 || sim->y[f] < sim->y[a]))
            a = f;
    const double dp = p.numerics.dp_m; /* the bed's face is y = 0, its top row at -dp/2 */
    sim->y[a] = 0.1 * dp;
    sim->vy[a] = -0.5f;
    const int32_t id = sim->id[a];
    surge_sim_step(sim);
    for (int f = sim->wall_count; f < sim->count; f++) /* the build may have re-sorted the fluid */
        if (sim->id[f] == id)
            a = f;
    const double vy = sim->vy[a];
    *gap_m = sim->face_gap_m[a];
    /* a shift toward the bed as large as shifting allows: set the concentration gradient and shift again */
    sim->near_surface[a] = 0;
    sim->div_r[a] = 2;
    sim->grad_c_x[a] = 0;
    sim->grad_c_y[a] = 1e6f;
    shifting_compute(sim, sim->dt_s);
    *shift_room_m = fmax(0.0, sim->face_gap_m[a] - reach_dp * dp);
    *shift_y_m = sim->shift_y[a];
    surge_sim_destroy(sim);
    return vy;
}

/* The health monitor stops an explicit run at a particle faster than the speed of sound, naming it and the check,
 * and passes one just below it. */
static int test_health_speed(void)
{
    surge_params p = small_bed_params();
    char err[256];
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    const int a = sim->wall_count + (sim->count - sim->wall_count) / 2;
    const double c0 = sim->derived.c0_mps;
    sim->vx[a] = (real)(0.99 * c0);
    const int below = health_check(sim);
    sim->vx[a] = (real)(1.01 * c0);
    const int above = health_check(sim);
    const surge_health *h = &sim->health;
    printf("health_speed: c0 = %.4g m/s; at 0.99 c0 the check returns %d; at 1.01 c0 %d: %s\n", c0, below, above,
           h->message);
    expect_below("health_speed: a particle at 0.99 c0 passes (1 = stopped)", below != 0, 0);
    expect_below("health_speed: at 1.01 c0 the speed check stops the run (1 = it does not)",
                 !(above != 0 && h->check == SURGE_CHECK_SPEED && h->particle_id == sim->id[a] &&
                   strstr(h->message, "speed of sound") != NULL), 0);
    sim->params.numerics.scheme = SURGE_SCHEME_IMPLICIT; /* no speed of sound there */
    sim->scheme = scheme_of(&sim->params);
    expect_below("health_speed: the implicit scheme is not held to c0 (1 = stopped)", health_check(sim) != 0, 0);
    surge_sim_destroy(sim);
    return failures;
}

static int test_wall_contact_rules(void)
{
    double room, shift_y, gap, room_off, shift_off, gap_off;
    const double vy = contact_rule_case(0.25, &room, &shift_y, &gap);
    const double vy_off = contact_rule_case(0.0, &room_off, &shift_off, &gap_off);
    printf("wall_contact_rules: thrown at the bed at 0.5 m/s from 0.1 dp: with the rules vy = %.3g m/s after the "
           "step (gap %.3g m), the largest shift toward the bed %.3g m (room %.3g m); without: vy = %.3g m/s, "
           "shift %.3g m\n", vy, gap, shift_y, room, vy_off, shift_off);
    expect_below("wall_contact_rules: velocity toward the face after the step (m/s)", -vy, 1e-6);
    expect_below("wall_contact_rules: a shift goes no closer than the reach (m past the room)", -shift_y - room, 1e-9);
    expect_below("wall_contact_rules: the particle stays outside the face (m inside)", -gap, 0);
    expect_below("wall_contact_rules: without the rules it keeps approaching (1 = it does not)", vy_off < -0.1 ? 0 : 1,
                 0.5);
    return failures;
}

/* The same rules at a disc's face (no fluid into a boulder either): a fluid particle put 0.1 dp outside a
 * disc and thrown at its centre at 0.5 m/s leaves the step with no velocity toward the disc's face, still outside
 * it, and the disc takes the push's reaction. */
static int test_disc_contact_rules(void)
{
    surge_sim *sim = case_sim("boulder_settling.ini", 0, NULL);
    if (!sim)
        return 1;
    const surge_params p = sim->params;
    const boulder_set *b = &sim->boulders;
    const double dp = p.numerics.dp_m, cx = b->x[0], cy = b->y[0], r = b->radius[0];
    int a = -1; /* the fluid particle nearest the point 1 dp above the disc's top */
    for (int f = sim->wall_count; f < sim->count; f++)
        if (a < 0 || hypot(sim->x[f] - cx, sim->y[f] - cy - r - dp) < hypot(sim->x[a] - cx, sim->y[a] - cy - r - dp))
            a = f;
    sim->x[a] = cx;
    sim->y[a] = cy + r + 0.1 * dp;
    sim->vy[a] = -0.5f;
    const int32_t id = sim->id[a];
    surge_sim_step(sim);
    for (int f = sim->wall_count; f < sim->count; f++)
        if (sim->id[f] == id)
            a = f;
    const double gap = hypot(sim->x[a] - b->x[0], sim->y[a] - b->y[0]) - b->radius[0];
    const double approach = sim->vy[a] - b->vy[0]; /* the particle is straight above the centre */
    /* the reaction: the disc's force with and without the particle's push */
    const int pushed = sim->face_disc[a] == 0;
    boulders_fluid_forces(sim, NULL);
    boulders_take_face_reactions(sim);
    const double fy_with = b->fy[0];
    sim->face_disc[a] = -1;
    boulders_fluid_forces(sim, NULL);
    boulders_take_face_reactions(sim);
    const double reaction = fy_with - b->fy[0], expected = -sim->mass * sim->face_push_y[a];
    printf("disc_contact_rules: thrown at a disc at 0.5 m/s from 0.1 dp: after the step vy - v_disc = %.3g m/s, "
           "gap %.3g m (%.2f dp); push %.3g m/s2 outward, reaction on the disc %.4g N/m (expected %.4g)\n",
           approach, gap, gap / dp, (double)sim->face_push_y[a], reaction, expected);
    expect_below("disc_contact_rules: velocity toward the disc's face after the step (m/s)", -approach, 1e-6);
    expect_below("disc_contact_rules: the particle stays outside the disc (m inside)", -gap, 0);
    expect_below("disc_contact_rules: the disc pushes it (1 = no push recorded)", pushed && sim->face_push_y[a] > 0 ? 0 : 1,
                 0.5);
    expect_below("disc_contact_rules: the disc takes the reaction (relative error)",
                 fabs(reaction - expected) / fabs(expected), 1e-9);
    surge_sim_destroy(sim);
    return failures;
}

/* The implicit scheme's rule in a wedge: a disc resting 0.6 dp above the bed leaves no room for a particle at the
 * contact reach (0.45 dp) from both faces. A fluid particle put 0.1 dp above the bed under the disc's flank and thrown
 * at the bed at 0.5 m/s leaves the step off both faces by half the gap (0.3 dp) less a rounding, not approaching
 * the bed; a second step, which starts in reach of both faces, leaves it approaching neither. Kept off the nearest face
 * (the bed) alone it ends at the reach, 0.45 dp up, and 0.18 dp from the disc. */
static void wedge_edit(surge_params *p)
{
    p->numerics.scheme = SURGE_SCHEME_IMPLICIT;
    snprintf(p->boulders.list_m, sizeof p->boulders.list_m, "0.05 %.10g 0.0125", 0.0125 + 0.6 * p->numerics.dp_m);
}

/* One step of the wedge scene; the index of particle id after it, or -1 (the scene destroyed) when the step fails */
static int wedge_step(surge_sim *sim, int32_t id, const char *which)
{
    if (surge_sim_step(sim) != 0) {
        fprintf(stderr, "implicit_wedge: %s failed: %s\n", which, sim->health.message);
        surge_sim_destroy(sim);
        return -1;
    }
    for (int f = sim->wall_count; f < sim->count; f++)
        if (sim->id[f] == id)
            return f;
    fprintf(stderr, "implicit_wedge: after %s the particle is gone\n", which);
    surge_sim_destroy(sim);
    return -1;
}

static int test_implicit_wedge(void)
{
    surge_sim *sim = case_sim("boulder_settling.ini", 0, wedge_edit);
    if (!sim)
        return 1;
    const boulder_set *b = &sim->boulders;
    const double dp = sim->params.numerics.dp_m, px = b->x[0] + 0.5 * dp, py = 0.1 * dp;
    int a = -1; /* the fluid particle nearest the point */
    for (int f = sim->wall_count; f < sim->count; f++)
        if (a < 0 || hypot(sim->x[f] - px, sim->y[f] - py) < hypot(sim->x[a] - px, sim->y[a] - py))
            a = f;
    sim->x[a] = px;
    sim->y[a] = py;
    sim->vy[a] = -0.5f;
    const int32_t id = sim->id[a];
    if ((a = wedge_step(sim, id, "the step")) < 0)
        return 1;
    const double dx = sim->x[a] - b->x[0], dy = sim->y[a] - b->y[0], distance = hypot(dx, dy);
    const double disc_gap = distance - b->radius[0], bed_gap = sim->y[a];
    const double disc_approach = -((sim->vx[a] - b->vx[0]) * dx + (sim->vy[a] - b->vy[0]) * dy) / distance;
    printf("implicit_wedge: the disc %.3f dp above the bed; after the step the particle %.3f dp above the bed and "
           "%.3f dp off the disc, approaching the bed at %.3g m/s and the disc at %.3g m/s (its face was out of reach "
           "at the step's start)\n",
           (b->y[0] - b->radius[0]) / dp, bed_gap / dp, disc_gap / dp, (double)-sim->vy[a], disc_approach);
    expect_below("implicit_wedge: off the bed by half the gap, less 0.05 dp (dp short)", 0.25 - bed_gap / dp, 0);
    expect_below("implicit_wedge: off the disc by half the gap, less 0.05 dp (dp short)", 0.25 - disc_gap / dp, 0);
    expect_below("implicit_wedge: velocity toward the bed after the step (m/s)", (double)-sim->vy[a], 1e-6);
    /* in reach of the disc's face from the step's start on, the velocity rule holds there too */
    if ((a = wedge_step(sim, id, "the second step")) < 0)
        return 1;
    const double ex = sim->x[a] - b->x[0], ey = sim->y[a] - b->y[0], d2 = hypot(ex, ey);
    const double approach2 = -((sim->vx[a] - b->vx[0]) * ex + (sim->vy[a] - b->vy[0]) * ey) / d2;
    printf("implicit_wedge: after a second step %.3f dp above the bed and %.3f dp off the disc, approaching the bed at "
           "%.3g m/s and the disc at %.3g m/s\n", sim->y[a] / dp, (d2 - b->radius[0]) / dp, (double)-sim->vy[a],
           approach2);
    expect_below("implicit_wedge: second step, off both faces by half the gap less 0.05 dp (dp short)",
                 fmax(0.25 - sim->y[a] / dp, 0.25 - (d2 - b->radius[0]) / dp), 0);
    expect_below("implicit_wedge: second step, velocity toward the bed (m/s)", (double)-sim->vy[a], 1e-6);
    expect_below("implicit_wedge: second step, velocity toward the disc's face (m/s)", approach2, 1e-6);
    surge_sim_destroy(sim);
    return failures;
}

/* A fluid particle behind the upstream wall (come round the periodic channel: the 60-disc debris surge carried four
 * there; fluid clinging to a caught disc went round and, knocked toward the wall at 0.95 m/s, ended a 28-disc run at
 * 42.08 s when it reached 0.03 mm into the wall's back), thrown at the wall's back at 5 m/s. The wall-face repulsion
 * must not take it for a particle deep past the front face and push it through the wall (it did: 9,943 m/s in one
 * step, docs/validation/debris_surge.md), and the wall's back face (scene.c) must stop it: without one, it stopped
 * the run in the sixth step (rho/rho0 1.105 as it met the back of the front layers, checked). 0.25 s of the debris
 * surge at dp = 0.1 m. */
static int test_behind_wall(void)
{
    surge_sim *sim = case_sim("debris_surge.ini", 0.1, NULL);
    if (!sim)
        return 1;
    const surge_params p = sim->params;
    const double dp = p.numerics.dp_m, back_face_m = scene_upstream_back_m(&p);
    int a = -1; /* the fluid particle nearest the point 0.2 dp behind the wall's back face, 0.18 m above the belt */
    for (int f = sim->wall_count; f < sim->count; f++)
        if (a < 0 || hypot(sim->x[f] - back_face_m, sim->y[f] - 0.18) < hypot(sim->x[a] - back_face_m, sim->y[a] - 0.18))
            a = f;
    sim->x[a] = back_face_m - 0.2 * dp;
    sim->y[a] = 0.18;
    const double thrown_mps = 5.0;
    sim->vx[a] = (real)thrown_mps;
    sim->vy[a] = 0;
    const int32_t id = sim->id[a];
    int stepped = 1;
    double nearest_m = 1e9, fastest_mps = 0; /* its closest approach to the back face, its largest speed */
    while (stepped && sim->time_s < 0.25) {
        stepped = surge_sim_step(sim) == 0;
        for (int f = sim->wall_count; f < sim->count; f++)
            if (sim->id[f] == id)
                a = f;
        nearest_m = fmin(nearest_m, back_face_m - sim->x[a]);
        fastest_mps = fmax(fastest_mps, hypot(sim->vx[a], sim->vy[a]));
    }
    printf("behind_wall: a particle 0.2 dp behind the upstream wall's back face (x = %.3f m) at %g m/s toward it: "
           "over %.3f s (%ld steps) it came %.3f dp from the face at most, its largest speed %.3g m/s; now v = "
           "(%.4g, %.4g) m/s; %s\n", back_face_m, thrown_mps, sim->time_s, (long)sim->step, nearest_m / dp, fastest_mps,
           (double)sim->vx[a], (double)sim->vy[a], stepped ? "healthy" : sim->health.message);
    expect_below("behind_wall: the steps are healthy (1 = not)", stepped ? 0 : 1, 0.5);
    expect_below("behind_wall: its largest speed after the first step (m/s)", fastest_mps, thrown_mps);
    expect_below("behind_wall: it stays behind the back face (m past it at most)", -nearest_m, 0);
    expect_below("behind_wall: the back face is a wall's width behind the front one (m off)",
                 fabs(p.walls.upstream_x_m - back_face_m - 2 * p.walls.layers * dp), 1e-9);
    surge_sim_destroy(sim);
    return failures;
}

/* A layer at rest whose density varies linearly with depth, but not hydrostatically (twice the hydrostatic
 * gradient): Antuono's diffusion term must vanish at every fluid particle, the free-surface and bed rows included
 * (its renormalised gradient is exact for a linear field), while Fourtakas' term, which subtracts only the
 * hydrostatic part, diffuses it where the kernel is truncated. With v = 0 the continuity rate is the diffusion. */
static int test_diffusion_linear(void)
{
    double largest_rate[2] = {0, 0};
    for (int form = SURGE_DIFFUSION_FOURTAKAS; form <= SURGE_DIFFUSION_ANTUONO; form++) {
        surge_params p = surge_default_params();
        p.domain.length_m = 0.06;
        p.domain.height_m = 0.04;
        p.domain.periodic_x = true;
        p.walls.left = p.walls.right = p.walls.top = p.walls.upstream = false;
        p.walls.bottom = true;
        p.fluid.x0_m = 0;
        p.fluid.x1_m = 0.06;
        p.fluid.depth_m = 0.016;
        p.numerics.dp_m = 0.001;
        p.numerics.density_diffusion_form = form;
        char err[256];
        surge_sim *sim = surge_sim_create(&p, err, sizeof err);
        if (!sim) {
            fprintf(stderr, "%s\n", err);
            return 1;
        }
        for (int a = sim->wall_count; a < sim->count; a++) {
            sim->vx[a] = sim->vy[a] = 0;
            sim->rho[a] = (real)(sim->rho0 + 2 * sim->rho_h_per_m * (p.fluid.depth_m - sim->y[a]));
        }
        if (neighbours_update(sim) != 0)
            return 1;
        interaction_prepare(sim);
        boundary_update(sim);
        interaction_compute(sim, 0);
        for (int a = sim->wall_count; a < sim->count; a++)
            largest_rate[form] = fmax(largest_rate[form], fabs(sim->drho[a]));
        surge_sim_destroy(sim);
    }
    printf("diffusion_linear: max |drho/dt| = %.3e (fourtakas), %.3e (antuono) kg m^-3 s^-1\n", largest_rate[0],
           largest_rate[1]);
    expect_below("diffusion_linear: fourtakas diffuses the non-hydrostatic part (1 = no)", largest_rate[0] == 0, 0);
    expect_below("diffusion_linear: antuono / fourtakas max rate", largest_rate[1] / largest_rate[0], 1e-2);
    return failures;
}

static void sixty_graded_discs(surge_params *p)
{
    p->boulders.placement = SURGE_BOULDERS_GRADED;
    p->boulders.count = 60;
    p->boulders.seed = 1;
    p->boulders.density_ratio = 0.9;
}

/* The face search as it was written before it was vectorised (46bfcab): one entry at a time, a disc's face once per
 * run of its particles, in double. The oracle for test_face_search. */
static wall_face reference_wall_face(const surge_sim *sim, int a, real search_m, int *near_boulder)
{
    const neighbour_lists *nl = &sim->neighbours;
    const boulder_set *bs = &sim->boulders;
    const real half_dp = (real)(0.5 * sim->params.numerics.dp_m), support2 = sim->kernel.support2;
    wall_face face = {search_m, 0, 0, 0, -1, -1};
    int last_disc = -1;
    const int i = a - sim->wall_count;
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
        const int b = nl->wall_index[e];
        const real dx = nl->wall_dx0[e] + (nl->moved_x[a] - nl->moved_x[b]);
        const real dy = nl->wall_dy0[e] + (nl->moved_y[a] - nl->moved_y[b]);
        const real r2 = dx * dx + dy * dy;
        if (r2 >= support2)
            continue;
        if (sim->wall_of[b] == WALL_BOULDER) {
            *near_boulder = 1;
            const int disc = bs->of_wall[sim->id[b]];
            if (search_m > 0 && disc != last_disc) {
                double ddx = sim->x[a] - bs->x[disc];
                ddx -= sim->grid.period_m * floor(ddx / sim->grid.period_m + 0.5);
                const double ddy = sim->y[a] - bs->y[disc], distance = sqrt(ddx * ddx + ddy * ddy);
                const double gap = distance - bs->radius[disc];
                if (gap < face.gap_m && distance > 0)
                    face = (wall_face){(real)gap, (real)(ddx / distance), (real)(ddy / distance),
                                       (real)(bs->vx[disc] * ddx / distance + bs->vy[disc] * ddy / distance), -1, disc};
            }
            last_disc = disc;
            continue;
        }
        const real along = dx * sim->wall_nx[b] + dy * sim->wall_ny[b];
        if (search_m > 0 && along > -half_dp && r2 - along * along < half_dp * half_dp &&
            along - sim->wall_depth_m[b] < face.gap_m)
            face = (wall_face){along - sim->wall_depth_m[b], sim->wall_nx[b], sim->wall_ny[b],
                               sim->vx[b] * sim->wall_nx[b] + sim->vy[b] * sim->wall_ny[b], b, -1};
    }
    return face;
}

static void sixty_graded_discs_c0(surge_params *p)
{
    sixty_graded_discs(p);
    p->numerics.c0_mps = 110;
}

/* The automatic c0 of the debris surge (docs/method.md, "c0"): the fluid alone, 10 x the block's collapse speed
 * sqrt(2 g_n H); with discs, 10 x the speeds at which a disc falling off the front lands on the bed added, the
 * film's surface speed g_x H^2/(2 nu) along it and sqrt(2 g_n H) across it; a case's own c0 is kept. */
static void twenty_eight_graded_discs(surge_params *p)
{
    sixty_graded_discs(p);
    p->boulders.count = 28;
}

static void twenty_eight_graded_discs_unpacked(surge_params *p)
{
    twenty_eight_graded_discs(p);
    p->boulders.pack_fluid = 0;
}

static int test_c0_discs(void)
{
    surge_sim *fluid = case_sim("debris_surge.ini", 0.1, NULL);
    surge_sim *discs = case_sim("debris_surge.ini", 0.066, twenty_eight_graded_discs);
    surge_sim *fixed = case_sim("debris_surge.ini", 0.066, sixty_graded_discs_c0);
    if (!fluid || !discs || !fixed)
        return 1;
    const surge_params *p = &fluid->params;
    const double theta = p->body.slope_deg * SURGE_PI / 180.0, depth = p->fluid.depth_m;
    const double fall = sqrt(2.0 * p->body.gravity_mps2 * cos(theta) * depth);
    const double along = p->body.gravity_mps2 * sin(theta) * depth * depth / (2.0 * p->fluid.viscosity_m2ps);
    const double want_fluid = 10.0 * fall, want_discs = 10.0 * (along + fall);
    printf("c0_discs: fluid alone %.4f m/s (want %.4f), 28 discs %.4f m/s (want %.4f), the case's own %.4f m/s\n",
           fluid->derived.c0_mps, want_fluid, discs->derived.c0_mps, want_discs, fixed->derived.c0_mps);
    expect_below("c0_discs: fluid alone, |c0 / (10 sqrt(2 g_n H)) - 1|", fabs(fluid->derived.c0_mps / want_fluid - 1),
                 1e-9);
    expect_below("c0_discs: with discs, |c0 / (10 (film surface speed + fall speed)) - 1|",
                 fabs(discs->derived.c0_mps / want_discs - 1), 1e-9);
    expect_below("c0_discs: numerics.c0_mps = 110 is kept, |c0 - 110| m/s", fabs(fixed->derived.c0_mps - 110), 1e-12);
    /* the case packs the fluid around its discs (boulders.pack_fluid = true): it keeps the lattice sites next to the
     * discs that the unpacked build leaves out */
    surge_sim *unpacked = case_sim("debris_surge.ini", 0.066, twenty_eight_graded_discs_unpacked);
    if (!unpacked)
        return 1;
    printf("c0_discs: 28 discs, fluid particles %d packed (the case's default), %d unpacked\n", discs->derived.fluid_count,
           unpacked->derived.fluid_count);
    expect_below("c0_discs: the case packs its fluid (pack_fluid false)", discs->params.boulders.pack_fluid ? 0 : 1, 0);
    expect_below("c0_discs: packed fluid particles less unpacked (negative: the sites next to the discs kept)",
                 unpacked->derived.fluid_count - discs->derived.fluid_count, -1);
    surge_sim_destroy(unpacked);
    surge_sim_destroy(fluid);
    surge_sim_destroy(discs);
    surge_sim_destroy(fixed);
    return failures;
}

/* boulders_orient's table is fresh wherever it is read: after every disc is turned by hand, boundary_update (no-slip
 * targets) and boulders_place_particles (positions) give what cos and sin of the new angles give, to round-off.
 * Without the refresh both would still use the angles of the last call. */
static int test_disc_orientation(void)
{
    surge_sim *sim = case_sim("debris_surge.ini", 0.066, sixty_graded_discs_c0);
    if (!sim)
        return 1;
    for (int n = 0; n < 20; n++)
        if (surge_sim_step(sim) != 0)
            return 1;
    boulder_set *b = &sim->boulders;
    if (neighbours_update(sim) != 0)
        return 1;
    interaction_prepare(sim);
    boundary_update(sim);
    for (int i = 0; i < b->count; i++)
        b->angle[i] += 0.3 + 0.01 * i;
    boundary_update(sim); /* refreshes the table for boulders_surface_velocity */
    double worst_velocity = 0, worst_position = 0;
    int particles = 0;
    for (int k = 0; k < sim->wall_count; k++) {
        const int id = sim->id[k], i = b->of_wall[id];
        if (i < 0)
            continue;
        const double c = cos(b->angle[i]), s = sin(b->angle[i]);
        const double rx = c * b->local_x[id] - s * b->local_y[id], ry = s * b->local_x[id] + c * b->local_y[id];
        const double to_surface = b->radius[i] / sqrt(rx * rx + ry * ry);
        double vx, vy;
        boulders_surface_velocity(sim, k, &vx, &vy);
        worst_velocity = fmax(worst_velocity, hypot(vx - (b->vx[i] - b->omega[i] * ry * to_surface),
                                                    vy - (b->vy[i] + b->omega[i] * rx * to_surface)));
        particles++;
    }
    boulders_place_particles(sim);
    for (int k = 0; k < sim->wall_count; k++) {
        const int id = sim->id[k], i = b->of_wall[id];
        if (i < 0)
            continue;
        const double c = cos(b->angle[i]), s = sin(b->angle[i]);
        const double ry = s * b->local_x[id] + c * b->local_y[id];
        worst_position = fmax(worst_position, fabs(sim->y[k] - (b->y[i] + ry)));
    }
    printf("disc_orientation: %d disc particles, largest velocity difference %.3g m/s, position %.3g m\n", particles,
           worst_velocity, worst_position);
    expect_below("disc_orientation: disc particles checked (at least 1000; minus the count)", 1000 - particles, 0);
    expect_below("disc_orientation: surface velocity against cos and sin of the turned angle (m/s)", worst_velocity,
                 1e-12);
    expect_below("disc_orientation: position against cos and sin of the turned angle (m)", worst_position, 1e-12);
    surge_sim_destroy(sim);
    return failures;
}

/* interaction_wall_face (whole vectors, each lane's nearest candidate, the chosen face recomputed) against the
 * scalar search it replaced, on the 60-disc debris surge after 0.2 s: the same face (gap, normal, wall speed, wall
 * particle or disc) and the same near-boulder flag for every fluid particle, with disc faces and bed faces among
 * them. A near-tie within float round-off may in principle differ; on this scene none does. */
static int test_face_search(void)
{
    surge_sim *sim = case_sim("debris_surge.ini", 0.066, sixty_graded_discs_c0);
    if (!sim)
        return 1;
    while (sim->time_s < 0.2)
        if (surge_sim_step(sim) != 0) {
            fprintf(stderr, "face_search: %s\n", sim->health.message);
            return 1;
        }
    if (neighbours_update(sim) != 0)
        return 1;
    interaction_prepare(sim);
    boundary_update(sim);
    const real search_m = (real)sim->params.numerics.dp_m;
    int differ = 0, disc_faces = 0, wall_faces = 0, near = 0;
    for (int a = sim->wall_count; a < sim->count; a++) {
        int near_new = 0, near_old = 0;
        const wall_face f = interaction_wall_face(sim, a, search_m, &near_new);
        const wall_face g = reference_wall_face(sim, a, search_m, &near_old);
        if (f.gap_m != g.gap_m || f.nx != g.nx || f.ny != g.ny || f.vn_mps != g.vn_mps || f.wall != g.wall ||
            f.disc != g.disc || near_new != near_old) {
            if (differ < 5)
                printf("face_search: particle %d: gap %.9g / %.9g, wall %d / %d, disc %d / %d, near %d / %d\n", a,
                       (double)f.gap_m, (double)g.gap_m, f.wall, g.wall, f.disc, g.disc, near_new, near_old);
            differ++;
        }
        disc_faces += g.disc >= 0, wall_faces += g.wall >= 0, near += near_old;
    }
    printf("face_search: %d fluid particles, %d with a disc face, %d with a wall face, %d near a disc; %d differ\n",
           sim->count - sim->wall_count, disc_faces, wall_faces, near, differ);
    expect_below("face_search: particles whose face differs from the scalar search", differ, 0.5);
    expect_below("face_search: disc faces found (at least 20; minus the count)", 20 - disc_faces, 0);
    expect_below("face_search: bed faces found (at least 100; minus the count)", 100 - wall_faces, 0);
    surge_sim_destroy(sim);
    return failures;
}

/* A fluid particle's cost in a pass over its lists, as neighbours_fluid_share counts it (entries plus 8). */
static int64_t pass_cost(const surge_sim *sim, int a)
{
    const neighbour_lists *nl = &sim->neighbours;
    const int i = a - sim->wall_count;
    return nl->fluid_first[i + 1] - nl->fluid_first[i] + nl->wall_first[i + 1] - nl->wall_first[i] + 8;
}

/* neighbours_fluid_share on the 60-disc debris surge (whose discs' wall entries bunch near the front): for 1, 2, 3
 * and 7 threads the shares tile the fluid in order, and no share costs more than an even split plus one particle;
 * an even split by particle count, as before, is shown for comparison. */
static int test_fluid_share(void)
{
    surge_sim *sim = case_sim("debris_surge.ini", 0.066, sixty_graded_discs);
    if (!sim)
        return 1;
    if (neighbours_update(sim) != 0)
        return 1;
    int64_t total = 0, largest = 0;
    for (int a = sim->wall_count; a < sim->count; a++)
        total += pass_cost(sim, a), largest = pass_cost(sim, a) > largest ? pass_cost(sim, a) : largest;
    const int counts[] = {1, 2, 3, 7};
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        const int threads = counts[k];
        int begin[8] = {0}, end[8] = {0}, got = 0;
        #pragma omp parallel num_threads(threads)
        {
            const int t = omp_get_thread_num();
            neighbours_fluid_share(sim, &begin[t], &end[t]);
            #pragma omp single
            got = omp_get_num_threads();
        }
        int gaps = got != threads || begin[0] != sim->wall_count || end[threads - 1] != sim->count;
        double worst = 0, worst_even = 0;
        for (int t = 0; t < threads; t++) {
            gaps += t > 0 && begin[t] != end[t - 1];
            int64_t cost = 0, cost_even = 0;
            for (int a = begin[t]; a < end[t]; a++)
                cost += pass_cost(sim, a);
            const int nf = sim->count - sim->wall_count;
            for (int a = sim->wall_count + (int)((int64_t)nf * t / threads);
                 a < sim->wall_count + (int)((int64_t)nf * (t + 1) / threads); a++)
                cost_even += pass_cost(sim, a);
            worst = fmax(worst, (double)(cost - total / threads) / (double)largest);
            worst_even = fmax(worst_even, (double)(cost_even - total / threads) / (double)largest);
        }
        char what[128];
        snprintf(what, sizeof what, "fluid_share: %d threads, shares not tiling the fluid", threads);
        expect_below(what, gaps, 0);
        snprintf(what, sizeof what, "fluid_share: %d threads, largest share over even (particles' cost; by count %.1f)",
                 threads, worst_even);
        expect_below(what, worst, 1.0);
    }
    surge_sim_destroy(sim);
    return failures;
}

/* What separates two clumped particles in the implicit scheme (docs/method.md, "The implicit scheme", step 3): two
 * neighbours of the still tank (C_h 1.3) moved from dp to (1 - 2 squeeze) dp apart, N rows under the free surface,
 * then stepped 16 times; returns their distance over dp (-1: the run failed). */
static void implicit_tank(surge_params *p)
{
    p->numerics.scheme = SURGE_SCHEME_IMPLICIT;
    p->numerics.ch = 1.3;
}

#define EXPLICIT_CLUMP_STEPS 200

static double clumped_pair_distance_in(void (*scheme)(surge_params *), int steps, double anti_clumping,
                                       int shifting_form, double rows_down, double squeeze)
{
    surge_sim *sim = case_sim("still_tank.ini", 0, scheme);
    if (!sim)
        return -1;
    sim->params.implicit.anti_clumping = anti_clumping;
    sim->params.shifting.surface_anti_clumping = anti_clumping;
    sim->params.shifting.form = shifting_form;
    const double dp = sim->params.numerics.dp_m;
    /* the particle nearest the middle of the tank, rows_down under the top row, and its right-hand neighbour */
    double top = -1e9;
    for (int k = sim->wall_count; k < sim->count; k++)
        top = fmax(top, sim->y[k]);
    int a = -1, b = -1;
    for (int k = sim->wall_count; k < sim->count; k++)
        if (fabs(sim->y[k] - top + rows_down * dp) < 0.25 * dp && fabs(sim->x[k] - 0.2 + 0.5 * dp) < 0.25 * dp)
            a = k;
    for (int k = sim->wall_count; k < sim->count; k++)
        if (a >= 0 && fabs(sim->y[k] - sim->y[a]) < 0.25 * dp && fabs(sim->x[k] - sim->x[a] - dp) < 0.25 * dp)
            b = k;
    if (a < 0 || b < 0) {
        surge_sim_destroy(sim);
        return -1;
    }
    const int32_t id_a = sim->id[a], id_b = sim->id[b];
    sim->x[a] += squeeze * dp, sim->x[b] -= squeeze * dp;
    for (int n = 0; n < steps; n++)
        if (surge_sim_step(sim) != 0) {
            printf("%s\n", surge_sim_health(sim)->message);
            surge_sim_destroy(sim);
            return -1;
        }
    for (int k = sim->wall_count; k < sim->count; k++)
        a = sim->id[k] == id_a ? k : a, b = sim->id[k] == id_b ? k : b;
    const double distance = hypot(sim->x[a] - sim->x[b], sim->y[a] - sim->y[b]) / dp;
    surge_sim_destroy(sim);
    return distance;
}

static double clumped_pair_distance(double anti_clumping, int shifting_form, double rows_down, double squeeze)
{
    return clumped_pair_distance_in(implicit_tank, 16, anti_clumping, shifting_form, rows_down, squeeze);
}

/* The explicit scheme's tank: C_h 1.3 as the implicit one's, its own time step */
static void explicit_tank(surge_params *p)
{
    p->numerics.ch = 1.3;
}

/* The explicit scheme keeps Lind's shift out of the free-surface layer, where a pair crowded together then stays so;
 * shifting.surface_anti_clumping must part it in the layer's third row, whose kernel is nearly full (in the top two
 * rows the truncated kernel sum stays below the rest lattice's even for the crowded pair, and nothing acts).
 * Numbers in docs/method.md. */
static int test_explicit_surface_clump(void)
{
    const double with = clumped_pair_distance_in(explicit_tank, EXPLICIT_CLUMP_STEPS, 1.0, SURGE_SHIFT_LIND, 2, 0.2);
    const double without = clumped_pair_distance_in(explicit_tank, EXPLICIT_CLUMP_STEPS, 0.0, SURGE_SHIFT_LIND, 2, 0.2);
    printf("explicit_surface_clump: third row, %d steps from 0.6 dp: %.4f dp with surface_anti_clumping 1, %.4f dp "
           "without\n", EXPLICIT_CLUMP_STEPS, with, without);
    expect_below("explicit_surface_clump: 0.77 - distance / dp with surface_anti_clumping 1", 0.77 - with, 0);
    expect_below("explicit_surface_clump: 0.08 - (with - without) / dp", 0.08 - (with - without), 0);
    return failures;
}

/* In the top row (pressure 0, the kernel sum truncated) only the shift along the surface separates the pair: with
 * it they must be back near dp, without it they stay at 0.6 dp (as they did before 2026-11-26, when the projection
 * on the particle's own grad C left no shift). Two rows down, with shifting off, the compressed particles' shift
 * (implicit.anti_clumping) must open the pair faster than the rest-density solve alone. Measured numbers in
 * docs/method.md. */
static int test_implicit_clump(void)
{
    const double top_with = clumped_pair_distance(1.0, SURGE_SHIFT_LIND, 0, 0.2);
    const double top_without = clumped_pair_distance(1.0, SURGE_SHIFT_NONE, 0, 0.2);
    printf("implicit_clump: top row, 16 steps from 0.6 dp: %.4f dp with Lind's shift, %.4f dp without\n", top_with,
           top_without);
    expect_below("implicit_clump: top row, 0.9 - distance / dp with Lind's shift", 0.9 - top_with, 0);
    const double below_with = clumped_pair_distance(1.0, SURGE_SHIFT_NONE, 2, 0.2);
    const double below_without = clumped_pair_distance(0.0, SURGE_SHIFT_NONE, 2, 0.2);
    printf("implicit_clump: 2 rows down, no Lind shift, 16 steps from 0.6 dp: %.4f dp with anti_clumping 1, %.4f "
           "dp with 0\n", below_with, below_without);
    expect_below("implicit_clump: 2 rows down, 0.02 - (with - without anti_clumping) / dp",
                 0.02 - (below_with - below_without), 0);
    /* a gap within a kernel of the surface (the second row, shifting off): the rest-density source, measured there
     * against the flat surface's kernel sum at that depth, must start to close it (1.349 dp after 16 steps; 1.401
     * when a deficit there did not count) */
    const double gap = clumped_pair_distance(1.0, SURGE_SHIFT_NONE, 1, -0.2);
    printf("implicit_clump: second row, no Lind shift, 16 steps from 1.4 dp: %.4f dp\n", gap);
    expect_below("implicit_clump: second row, distance / dp - 1.38", gap - 1.38, 0);
    return failures;
}

#define PROJECTION_WHOLE_BOUND 0.07
#define PROJECTION_INNER_BOUND 0.10
#define PROJECTION_WHOLE_BOUND_FINE 0.03
#define PROJECTION_INNER_BOUND_FINE 0.045
#define REST_DENSITY_STEPS 10
#define REST_DENSITY_BOUND 0.005

/* The still tank (0.4 m x 0.2 m of fluid, dp 1 cm, C_h 1.8) for the implicit scheme's projection alone: no gravity,
 * no viscosity, no shift, no rest-density solve, a fixed step short enough that the particles stay put */
static void projection_tank(surge_params *p)
{
    p->numerics.scheme = SURGE_SCHEME_IMPLICIT;
    p->body.gravity_mps2 = 0;
    p->numerics.c0_mps = 10; /* no gravity to derive it from; the implicit scheme does not step by it */
    p->fluid.viscosity_m2ps = 0;
    p->shifting.form = SURGE_SHIFT_NONE;
    p->implicit.density_correction = 0;
    p->numerics.dt_fixed_s = 1e-3;
}

/* The tank's wall faces: the fluid's left edge and bottom (dp/2 outside its first particles) */
static void tank_faces(const surge_sim *sim, double *x0, double *y0)
{
    const double dp = sim->params.numerics.dp_m;
    *x0 = *y0 = 1e9;
    for (int k = sim->wall_count; k < sim->count; k++)
        *x0 = fmin(*x0, sim->x[k] - 0.5 * dp), *y0 = fmin(*y0, sim->y[k] - 0.5 * dp);
}

/* The projection: a velocity field with a known divergence, v = curl(s) + (0, A y), in the open tank
 * (walls at x = 0, L and y = 0, the free surface at y = H), with s = S sin(pi x / L) sin(pi y / (2H)), whose curl is
 * divergence-free and has no velocity through the walls, and (0, A y), whose divergence is A and which the walls
 * also let be. The projection with phi = 0 on the free surface and no flux through the walls takes away the
 * gradient part exactly: (0, A y) = grad(A (y^2 - H^2) / 2). One step must leave the curl alone. */
static int projection_errors(double dp_m, double *whole, double *inner_part)
{
    surge_sim *sim = case_sim("still_tank.ini", dp_m, projection_tank);
    if (!sim)
        return -1;
    const double length = sim->params.fluid.x1_m - sim->params.fluid.x0_m, depth = sim->params.fluid.depth_m;
    const double stretch = 1.0, swirl = 0.1 * length / SURGE_PI; /* A (1/s); S (m^2/s): the curl's peak 0.1 m/s */
    double x0, y0;
    tank_faces(sim, &x0, &y0);
    for (int k = sim->wall_count; k < sim->count; k++) {
        const double x = sim->x[k] - x0, y = sim->y[k] - y0;
        sim->vx[k] = (real)(swirl * sin(SURGE_PI * x / length) * SURGE_PI / (2 * depth) * cos(SURGE_PI * y / (2 * depth)));
        sim->vy[k] = (real)(-swirl * SURGE_PI / length * cos(SURGE_PI * x / length) * sin(SURGE_PI * y / (2 * depth)) +
                            stretch * y);
    }
    if (surge_sim_step(sim) != 0) {
        printf("implicit_projection: %s\n", surge_sim_health(sim)->message);
        surge_sim_destroy(sim);
        return -1;
    }
    /* the error against the curl alone, over the whole fluid and 3 dp in from the walls and the surface */
    double error2 = 0, inner_error2 = 0, curl2 = 0, inner_curl2 = 0, gradient2 = 0;
    int count = 0, inner = 0;
    for (int k = sim->wall_count; k < sim->count; k++) {
        const double x = sim->x[k] - x0, y = sim->y[k] - y0;
        const double cx = swirl * sin(SURGE_PI * x / length) * SURGE_PI / (2 * depth) * cos(SURGE_PI * y / (2 * depth));
        const double cy = -swirl * SURGE_PI / length * cos(SURGE_PI * x / length) * sin(SURGE_PI * y / (2 * depth));
        const double e2 = (sim->vx[k] - cx) * (sim->vx[k] - cx) + (sim->vy[k] - cy) * (sim->vy[k] - cy);
        error2 += e2, curl2 += cx * cx + cy * cy, gradient2 += stretch * y * stretch * y, count++;
        if (x > 3 * dp_m && x < length - 3 * dp_m && y > 3 * dp_m && y < depth - 3 * dp_m)
            inner_error2 += e2, inner_curl2 += cx * cx + cy * cy, inner++;
    }
    *whole = sqrt(error2 / gradient2), *inner_part = sqrt(inner_error2 / inner_curl2);
    printf("implicit_projection: dp %g m, %d fluid particles: rms of the curl %.4g m/s, of the gradient part %.4g "
           "m/s; after one step the rms error %.4g m/s over the fluid, %.4g m/s 3 dp inside\n", dp_m, count,
           sqrt(curl2 / count), sqrt(gradient2 / count), sqrt(error2 / count), sqrt(inner_error2 / inner));
    surge_sim_destroy(sim);
    return 0;
}

/* At dp = 1 cm (20 rows) and 5 mm (40 rows); the errors must fall with dp */
static int test_implicit_projection(void)
{
    double whole[2], inner[2];
    for (int k = 0; k < 2; k++)
        if (projection_errors(k ? 0.005 : 0.01, &whole[k], &inner[k]) != 0)
            return 1;
    expect_below("implicit_projection: dp 1 cm, rms error / rms gradient part", whole[0], PROJECTION_WHOLE_BOUND);
    expect_below("implicit_projection: dp 1 cm, rms error / rms curl, 3 dp inside", inner[0], PROJECTION_INNER_BOUND);
    expect_below("implicit_projection: dp 5 mm, rms error / rms gradient part", whole[1], PROJECTION_WHOLE_BOUND_FINE);
    expect_below("implicit_projection: dp 5 mm, rms error / rms curl, 3 dp inside", inner[1], PROJECTION_INNER_BOUND_FINE);
    return failures;
}

/* The rest-density solve: the tank's fluid squeezed to 0.95 of its spacing in depth (its kernel sum 5 %
 * above the lattice's; squeezed sideways too it would leave a void along the side walls), at rest and without
 * gravity, must come back to the rest density and to its depth; the solve moves the particles and leaves the
 * velocity alone. */
static void squeezed_tank(surge_params *p)
{
    p->numerics.scheme = SURGE_SCHEME_IMPLICIT;
    p->body.gravity_mps2 = 0;
    p->numerics.c0_mps = 10; /* no gravity to derive it from; the implicit scheme does not step by it */
    p->numerics.dt_fixed_s = 1e-3;
}

static int rest_density_run(double dp_m)
{
    surge_sim *sim = case_sim("still_tank.ini", dp_m, squeezed_tank);
    if (!sim)
        return 1;
    const double dp = sim->params.numerics.dp_m, depth = sim->params.fluid.depth_m, squeeze = 0.95;
    double x0, y0;
    tank_faces(sim, &x0, &y0);
    for (int k = sim->wall_count; k < sim->count; k++)
        sim->y[k] = y0 + squeeze * (sim->y[k] - y0);
    double first_excess = 0, excess = 0, top = 0, largest_speed = 0;
    for (int n = 0; n < REST_DENSITY_STEPS; n++) {
        if (surge_sim_step(sim) != 0) {
            printf("implicit_rest_density: %s\n", surge_sim_health(sim)->message);
            surge_sim_destroy(sim);
            return 1;
        }
        /* the density the spacing says (rho0 times the kernel sum over the lattice's) off the free surface */
        excess = 0;
        for (int k = sim->wall_count; k < sim->count; k++)
            if (!sim->near_surface[k])
                excess = fmax(excess, fabs(sim->rho[k] / sim->rho0 - 1));
        first_excess = n == 0 ? excess : first_excess;
    }
    for (int k = sim->wall_count; k < sim->count; k++) {
        top = fmax(top, sim->y[k] - y0);
        largest_speed = fmax(largest_speed, hypot(sim->vx[k], sim->vy[k]));
    }
    printf("implicit_rest_density: dp %g m: largest |rho / rho0 - 1| off the surface %.4f at the first step, %.4f "
           "after %d; top row %.4f dp under the depth (0.5 at rest), largest speed %.3g m/s\n", dp, first_excess,
           excess, REST_DENSITY_STEPS, (depth - top) / dp, largest_speed);
    expect_below("implicit_rest_density: first step's |rho / rho0 - 1|, 0.03 - it (squeezed)", 0.03 - first_excess, 0);
    expect_below("implicit_rest_density: |rho / rho0 - 1| at the end", excess, REST_DENSITY_BOUND);
    expect_below("implicit_rest_density: |top row's depth - (depth - dp/2)| / dp", fabs((depth - top) / dp - 0.5), 0.2);
    expect_below("implicit_rest_density: largest speed (m/s; the solve moves, it does not push)", largest_speed, 1e-9);
    surge_sim_destroy(sim);
    return 0;
}

/* At dp = 1 cm (20 rows) and 5 mm (40 rows) */
static int test_implicit_rest_density(void)
{
    if (rest_density_run(0.01) != 0 || rest_density_run(0.005) != 0)
        return 1;
    return failures;
}

/* implicit.preconditioner = auto: the pressure by the multigrid from 2,500 fluid particles, the viscous solve
 * (which starts from v_n) from 10,000 (docs/method.md, "Linear solvers"); amg and jacobi take both */
static int test_implicit_auto(void)
{
    surge_params p = surge_default_params();
    p.implicit.preconditioner = SURGE_PRECONDITIONER_AUTO;
    const struct { int fluid; bool viscous, amg; } cases[] = {
        {2499, false, false}, {2500, false, true}, {18361, false, true}, {4591, true, false},
        {9999, true, false}, {10000, true, true}, {18361, true, true}, {73442, true, true}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char what[96];
        snprintf(what, sizeof what, "implicit_auto: %d fluid particles, %s solve, amg wanted %d", cases[k].fluid,
                 cases[k].viscous ? "viscous" : "pressure", cases[k].amg);
        expect_below(what, surge_implicit_uses_amg(&p, cases[k].fluid, cases[k].viscous) != cases[k].amg, 0.5);
    }
    p.implicit.preconditioner = SURGE_PRECONDITIONER_AMG;
    expect_below("implicit_auto: amg takes the small viscous solve", !surge_implicit_uses_amg(&p, 100, true), 0.5);
    p.implicit.preconditioner = SURGE_PRECONDITIONER_JACOBI;
    expect_below("implicit_auto: jacobi keeps the large pressure solve", surge_implicit_uses_amg(&p, 100000, false), 0.5);
    return failures;
}

/* The implicit scheme's time step: the smaller of the advective limit cfl h / u_max and the body-force limit
 * force_cfl sqrt(h / g), each with its own coefficient (the Freydier front at dp 0.25 mm, C_h 1.8: h = 0.636 mm) */
static int test_implicit_dt(void)
{
    surge_params p = surge_default_params();
    p.implicit.cfl = 0.25, p.implicit.force_cfl = 0.35;
    const double h = 0.636e-3, g = 9.81;
    expect_below("implicit_dt: the belt's speed, the advective limit 0.25 h / u (relative error)",
                 fabs(surge_implicit_dt_s(&p, h, g, 0.0725) / (0.25 * h / 0.0725) - 1), 1e-12);
    expect_below("implicit_dt: slow, the body-force limit 0.35 sqrt(h / g) (relative error)",
                 fabs(surge_implicit_dt_s(&p, h, g, 0.01) / (0.35 * sqrt(h / g)) - 1), 1e-12);
    expect_below("implicit_dt: no gravity, the advective limit (relative error)",
                 fabs(surge_implicit_dt_s(&p, h, 0, 0.01) / (0.25 * h / 0.01) - 1), 1e-12);
    expect_below("implicit_dt: neither speed nor gravity is unbounded (1 = bounded)",
                 isfinite(surge_implicit_dt_s(&p, h, 0, 0)) != 0, 0.5);
    p.implicit.force_cfl = 0.1;
    expect_below("implicit_dt: force_cfl alone moves the body-force limit (relative error)",
                 fabs(surge_implicit_dt_s(&p, h, g, 0.01) / (0.1 * sqrt(h / g)) - 1), 1e-12);
    return failures;
}

/* Three discs thrown through a weightless viscous slab, periodic, without walls (test_boulders.py's momentum scene),
 * with the implicit scheme */
static void thrown_discs_implicit(surge_params *p)
{
    p->numerics.scheme = SURGE_SCHEME_IMPLICIT;
    p->walls.bottom = p->walls.top = false;
    p->domain.height_m = 0.2;
    p->fluid.viscosity_m2ps = 0.002;
    p->boulders.density_ratio = 1.5;
    char err[160];
    surge_param_set(p, surge_param_find("boulders.list_m"),
                    "0.195 0.05 0.0125 0.04 0.005 0, 0.08 0.05 0.0125 -0.01 0 0.5, 0.10 0.02 0.0125 0 -0.01 0", err,
                    sizeof err);
}

/* The coupled viscous operator (docs/method.md, "Boulders in the implicit scheme") exchanges momentum between the fluid
 * and the discs exactly: applied to any fluid and disc velocities x in a scene without fixed walls, the momentum of
 * its answer, sum_a m_a out_a + sum_d m_d out_d (the discs' Vx, Vy rows), is that of x, to round-off: each disc's
 * rows take the reaction of what its particles give the fluid's rows, pair by pair, and the fluid's pairs are
 * symmetric. The bound is round-off against the momentum the operator moves (sum of |m (out - x)|). */
static int test_implicit_disc_momentum(void)
{
    surge_sim *sim = case_sim("boulder_couette.ini", 0, thrown_discs_implicit);
    if (!sim || surge_sim_step(sim) != 0)
        return 1;
    const implicit_work *w = implicit_of(sim);
    const int nf = sim->count - sim->wall_count, n = 2 * nf + w->disc_rows;
    double *x = malloc((size_t)n * sizeof *x), *out = malloc((size_t)n * sizeof *out);
    uint32_t state = 12345u; /* a fixed pseudo-random field (xorshift), 0.01 m/s in size */
    for (int q = 0; q < n; q++) {
        state ^= state << 13, state ^= state >> 17, state ^= state << 5;
        x[q] = 0.01 * ((double)state / 4294967296.0 - 0.5);
    }
    implicit_coupled_viscous_operator(sim, x, out);
    double change[2] = {0, 0}, moved[2] = {0, 0}, discs_moved = 0;
    for (int c = 0; c < 2; c++) {
        for (int i = 0; i < nf; i++)
            change[c] += sim->mass * (out[c * nf + i] - x[c * nf + i]),
                moved[c] += fabs(sim->mass * (out[c * nf + i] - x[c * nf + i]));
        for (int d = 0; d < sim->boulders.count; d++) {
            const double m = sim->boulders.mass[d], dq = out[2 * nf + 3 * d + c] - x[2 * nf + 3 * d + c];
            change[c] += m * dq, moved[c] += fabs(m * dq), discs_moved += fabs(m * dq);
        }
    }
    printf("implicit_disc_momentum: %d fluid particles, %d discs: momentum change (%.3e, %.3e) of (%.3e, %.3e) moved "
           "(kg m/s per m), %.3e of it by the discs' rows\n", nf, sim->boulders.count, change[0], change[1], moved[0],
           moved[1], discs_moved);
    expect_below("implicit_disc_momentum: the discs' rows take part (1 = they do not)", discs_moved > 0 ? 0 : 1, 0);
    expect_below("implicit_disc_momentum: |x momentum change| / momentum moved", fabs(change[0]) / moved[0], 1e-12);
    expect_below("implicit_disc_momentum: |y momentum change| / momentum moved", fabs(change[1]) / moved[1], 1e-12);
    free(x);
    free(out);
    surge_sim_destroy(sim);
    return failures;
}

/* The momentum scene's discs with the second one moved to 0.3 dp from the first, along 30 degrees: a lubrication
 * film between them (the cut-off is 1 dp) */
static void film_discs_implicit(surge_params *p)
{
    thrown_discs_implicit(p);
    const double r = 0.0125, centre = 2 * r + 0.3 * p->numerics.dp_m;
    char list[160], err[160];
    snprintf(list, sizeof list, "0.195 0.05 0.0125 0.04 0.005 0, 0.08 0.05 0.0125 -0.01 0 0.5, %.9f %.9f 0.0125 0 -0.01 0",
             0.08 + centre * cos(SURGE_PI / 6), 0.05 + centre * sin(SURGE_PI / 6));
    surge_param_set(p, surge_param_find("boulders.list_m"), list, err, sizeof err);
}

/* The lubrication films in the implicit scheme's solves (sim/src/scheme/implicit/films.c): two discs 0.3 dp apart in
 * a weightless slab. The coupled viscous operator still balances momentum to round-off with the film's forces in the
 * discs' rows; and the pressure correction's block solve inverts I + dt M^-1 K for the K that the rows' forces use:
 * for any disc velocities x, solving and then applying I + dt M^-1 K (through implicit_film_forces) gives x back. */
static int test_implicit_films(void)
{
    surge_sim *sim = case_sim("boulder_couette.ini", 0, film_discs_implicit);
    if (!sim || surge_sim_step(sim) != 0)
        return 1;
    const implicit_work *w = implicit_of(sim);
    const boulder_set *b = &sim->boulders;
    printf("implicit_films: %d films, %d blocks\n", w->film_count, w->film_blocks.count);
    expect_below("implicit_films: a film between the close discs (1 = none)", w->film_count >= 1 ? 0 : 1, 0);
    const int nf = sim->count - sim->wall_count, n = 2 * nf + w->disc_rows;
    double *x = malloc((size_t)n * sizeof *x), *out = malloc((size_t)n * sizeof *out);
    uint32_t state = 2024u;
    for (int q = 0; q < n; q++) {
        state ^= state << 13, state ^= state >> 17, state ^= state << 5;
        x[q] = 0.01 * ((double)state / 4294967296.0 - 0.5);
    }
    implicit_coupled_viscous_operator(sim, x, out);
    double change[2] = {0, 0}, moved[2] = {0, 0};
    for (int c = 0; c < 2; c++) {
        for (int i = 0; i < nf; i++)
            change[c] += sim->mass * (out[c * nf + i] - x[c * nf + i]),
                moved[c] += fabs(sim->mass * (out[c * nf + i] - x[c * nf + i]));
        for (int d = 0; d < b->count; d++) {
            const double dq = b->mass[d] * (out[2 * nf + 3 * d + c] - x[2 * nf + 3 * d + c]);
            change[c] += dq, moved[c] += fabs(dq);
        }
    }
    printf("implicit_films: momentum change (%.3e, %.3e) of (%.3e, %.3e) moved\n", change[0], change[1], moved[0],
           moved[1]);
    expect_below("implicit_films: |x momentum change| / momentum moved", fabs(change[0]) / moved[0], 1e-12);
    expect_below("implicit_films: |y momentum change| / momentum moved", fabs(change[1]) / moved[1], 1e-12);
    const int rows = w->disc_rows;
    double *u = malloc((size_t)rows * sizeof *u), *force = calloc((size_t)rows, sizeof *force);
    memcpy(u, x + 2 * nf, (size_t)rows * sizeof *u);
    implicit_films_solve(sim, FILMS_PRESSURE, u);
    implicit_film_forces(sim, u, force);
    double error = 0, size = 0, changed = 0;
    for (int q = 0; q < rows; q++) {
        const int d = q / 3;
        const double dt_over_mass = q % 3 < 2 ? sim->dt_s * b->inv_mass[d]
                                              : sim->dt_s * b->inv_inertia[d] * b->radius[d] * b->radius[d];
        error = fmax(error, fabs(u[q] - dt_over_mass * force[q] - x[2 * nf + q]));
        size = fmax(size, fabs(x[2 * nf + q]));
        changed = fmax(changed, fabs(u[q] - x[2 * nf + q]));
    }
    printf("implicit_films: block solve then I + dt M^-1 K: largest error %.3e of %.3e (the solve changed it by up to "
           "%.3e)\n", error, size, changed);
    expect_below("implicit_films: the solve changes the close discs' velocities (relative)", changed > 1e-3 * size ? 0 : 1,
                 0);
    expect_below("implicit_films: (I + dt M^-1 K) solve(x) = x (relative)", error / size, 1e-10);
    free(u);
    free(force);
    free(x);
    free(out);
    surge_sim_destroy(sim);
    return failures;
}

/* The still tank (dp 1 cm) without gravity, with a disc of radius 5 dp at its centre, a step short enough that the
 * particles stay put */
#define CAVITY_DISC_X_M 0.2
#define CAVITY_DISC_Y_M 0.1
#define CAVITY_DISC_R_M 0.05
#define CAVITY_FILM_DP 3.5  /* the fluid this close to the disc's surface on its right stays, pressed onto it */
#define CAVITY_SQUEEZE 0.6  /* to this share of its thickness */
#define CAVITY_WIDTH_DP 4.0 /* the fluid beyond it, this wide, leaves */
#define CAVITY_SECTORS 16   /* of 10 degrees, from -80 to 80 degrees about the disc's centre */
static void cavity_tank(surge_params *p)
{
    p->numerics.scheme = SURGE_SCHEME_IMPLICIT;
    p->body.gravity_mps2 = 0;
    p->numerics.c0_mps = 10; /* no gravity to derive it from; the implicit scheme does not step by it */
    p->numerics.dt_fixed_s = 1e-4;
    p->domain.height_m = 0.5;
    p->health.max_density_deviation = 0.5; /* the pressed and squeezed fluid reads up to 1.2 of rho0 */
    p->boulders.placement = SURGE_BOULDERS_LIST;
    char list[96], err[160];
    snprintf(list, sizeof list, "%g %g %g", CAVITY_DISC_X_M, CAVITY_DISC_Y_M, CAVITY_DISC_R_M);
    surge_param_set(p, surge_param_find("boulders.list_m"), list, err, sizeof err);
}

/* The free surface of a cavity beside a disc: on the disc's right, the fluid 3.5-7.5 dp from its surface is moved
 * into a block well above the tank and the film left on the disc is pressed to 0.6 of its thickness, as tension
 * crowds a cavity's border where the 60-disc surge opened one (docs/method.md). The film's outermost particle in each
 * 10-degree sector borders the void; the disc's particles fill its sums, so that div r reads up to 1.45 there, above
 * the threshold 1.35. Counts the film's outermost particles and the far border's on the free surface, and the
 * particles flagged 3 dp or more from the cavity, the disc, the walls and the surface (none should be). */
static int cavity_flags(double scan_dp, int *film_flagged, int *far_flagged, int *far, int *bulk_flagged)
{
    surge_sim *sim = case_sim("still_tank.ini", 0.01, cavity_tank);
    if (!sim)
        return 1;
    sim->params.implicit.surface_scan_dp = scan_dp;
    const double dp = sim->params.numerics.dp_m, r = CAVITY_DISC_R_M, depth = sim->params.fluid.depth_m;
    const double film = CAVITY_FILM_DP * dp, cavity_end = (CAVITY_FILM_DP + CAVITY_WIDTH_DP) * dp;
    int moved = 0;
    for (int k = sim->wall_count; k < sim->count; k++) {
        const double dx = sim->x[k] - CAVITY_DISC_X_M, dy = sim->y[k] - CAVITY_DISC_Y_M, d = hypot(dx, dy) - r;
        if (dx > 0 && d > 0 && d < film) {
            const double toward = (1 - CAVITY_SQUEEZE) * d / (d + r);
            sim->x[k] -= (real)(toward * dx), sim->y[k] -= (real)(toward * dy);
        } else if (dx > 0 && d >= film && d < cavity_end) {
            sim->x[k] = (real)((moved % 30 + 5) * dp), sim->y[k] = (real)(depth + 10 * dp + (moved / 30) * dp);
            moved++;
        }
    }
    if (surge_sim_step(sim) != 0) {
        printf("implicit_cavity: %s\n", surge_sim_health(sim)->message);
        surge_sim_destroy(sim);
        return 1;
    }
    int outermost[CAVITY_SECTORS];
    double outermost_d[CAVITY_SECTORS];
    for (int q = 0; q < CAVITY_SECTORS; q++)
        outermost[q] = -1, outermost_d[q] = 0;
    *far = *far_flagged = *bulk_flagged = 0;
    for (int k = sim->wall_count; k < sim->count; k++) {
        if (sim->y[k] > depth)
            continue; /* the moved block */
        const double dx = sim->x[k] - CAVITY_DISC_X_M, dy = sim->y[k] - CAVITY_DISC_Y_M, d = hypot(dx, dy) - r;
        const int sector = (int)floor((atan2(dy, dx) * 180 / SURGE_PI + 80) / 10);
        if (dx > 0 && sector >= 0 && sector < CAVITY_SECTORS) {
            if (d < film && d > outermost_d[sector])
                outermost[sector] = k, outermost_d[sector] = d;
            if (d >= cavity_end && d < cavity_end + dp)
                (*far)++, *far_flagged += sim->surface[k];
        }
        const double wall = fmin(fmin(sim->x[k], 0.4 - sim->x[k]), fmin(sim->y[k], depth - sim->y[k]));
        if (d > cavity_end + 3 * dp && wall > 3 * dp)
            *bulk_flagged += sim->surface[k];
    }
    *film_flagged = 0;
    double div_r_low = 2, div_r_high = 0;
    for (int q = 0; q < CAVITY_SECTORS; q++) {
        *film_flagged += sim->surface[outermost[q]];
        div_r_low = fmin(div_r_low, sim->div_r[outermost[q]]), div_r_high = fmax(div_r_high, sim->div_r[outermost[q]]);
    }
    printf("implicit_cavity: scan %g dp, %d particles moved out: on the surface %d of the film's %d outermost (div r "
           "%.3f-%.3f), %d of %d on the far border, %d in the bulk\n", scan_dp, moved, *film_flagged, CAVITY_SECTORS,
           div_r_low, div_r_high, *far_flagged, *far, *bulk_flagged);
    surge_sim_destroy(sim);
    return 0;
}

static int test_implicit_cavity(void)
{
    int film, far_flagged, far, bulk, film_off, far_flagged_off, far_off, bulk_off;
    if (cavity_flags(surge_default_params().implicit.surface_scan_dp, &film, &far_flagged, &far, &bulk) != 0 ||
        cavity_flags(0, &film_off, &far_flagged_off, &far_off, &bulk_off) != 0)
        return 1;
    expect_below("implicit_cavity: the film's outermost not on the surface", CAVITY_SECTORS - film, 0);
    expect_below("implicit_cavity: the far border not on the surface", far - far_flagged, 0);
    expect_below("implicit_cavity: particles on the surface in the bulk", bulk, 0);
    /* what the scan adds: without it, part of the film's border is not on the surface */
    expect_below("implicit_cavity: without the scan, the film's outermost on the surface - (sectors - 2)",
                 film_off - (CAVITY_SECTORS - 2), 0);
    return failures;
}

/* A void beside a disc in the still tank (the cavity's tank: dp 1 cm, no gravity, a disc of radius 5 dp): the fluid
 * within 2 dp of a point 2.5 dp left of the disc's surface leaves, and the fluid up to 6 dp around the void is drawn
 * toward it by up to squeeze_dp, the most at the void's border, as the void closes (the implicit surge at phi 0.53
 * stopped on such a border, 2.5 dp from a disc, pressed to 1.17 of the lattice's kernel sum while held at p = 0;
 * docs/method.md). Counts the border's particles (the fluid within 1.2 dp of where the void's edge was), those on
 * the free surface, those whose kernel sum reaches the lattice's and how many of these are on the surface. */
#define VOID_RADIUS_DP 2.0
#define VOID_REACH_DP 6.0
#define VOID_GAP_DP 2.5
static int void_flags(double squeeze_dp, int *border, int *flagged, int *full, int *full_flagged)
{
    surge_sim *sim = case_sim("still_tank.ini", 0.01, cavity_tank);
    if (!sim)
        return 1;
    const double dp = sim->params.numerics.dp_m, depth = sim->params.fluid.depth_m;
    const double r_void = VOID_RADIUS_DP * dp, reach = VOID_REACH_DP * dp;
    const double cx = CAVITY_DISC_X_M - CAVITY_DISC_R_M - (VOID_GAP_DP + VOID_RADIUS_DP) * dp, cy = CAVITY_DISC_Y_M;
    int moved = 0;
    for (int k = sim->wall_count; k < sim->count; k++) {
        const double dx = sim->x[k] - cx, dy = sim->y[k] - cy, d = hypot(dx, dy);
        if (hypot(sim->x[k] - CAVITY_DISC_X_M, sim->y[k] - CAVITY_DISC_Y_M) < CAVITY_DISC_R_M)
            continue;
        if (d < r_void) {
            sim->x[k] = (real)((moved % 30 + 5) * dp), sim->y[k] = (real)(depth + 10 * dp + (moved / 30) * dp);
            moved++;
        } else if (d < reach) {
            const double inward = squeeze_dp * dp * sin(SURGE_PI * (d - r_void) / (reach - r_void));
            sim->x[k] -= (real)(inward * dx / d), sim->y[k] -= (real)(inward * dy / d);
        }
    }
    if (surge_sim_step(sim) != 0) {
        printf("implicit_void: %s\n", surge_sim_health(sim)->message);
        surge_sim_destroy(sim);
        return 1;
    }
    const implicit_work *w = implicit_of(sim);
    *border = *flagged = *full = *full_flagged = 0;
    double ratio_high = 0;
    for (int k = sim->wall_count; k < sim->count; k++) {
        const double d = hypot(sim->x[k] - cx, sim->y[k] - cy);
        if (sim->y[k] > depth || d > r_void + 1.2 * dp)
            continue;
        const double ratio = w->kernel_ratio[k - sim->wall_count];
        (*border)++, *flagged += sim->surface[k];
        ratio_high = fmax(ratio_high, ratio);
        if (ratio >= 1.0)
            (*full)++, *full_flagged += sim->surface[k];
    }
    printf("implicit_void: drawn in by %.2f dp: %d border particles, %d on the surface, %d with a full kernel sum (%d on "
           "the surface); largest kernel sum %.3f of the lattice's\n", squeeze_dp, *border, *flagged, *full,
           *full_flagged, ratio_high);
    surge_sim_destroy(sim);
    return 0;
}

static int test_implicit_void(void)
{
    int border, flagged, full, full_flagged;
    if (void_flags(0, &border, &flagged, &full, &full_flagged) != 0)
        return 1;
    /* the open void: its border is the free surface, most of it */
    expect_below("implicit_void: open, border particles not on the surface - border/2", (border - flagged) - border / 2, 0);
    for (double squeeze = 0.4; squeeze < 1.5; squeeze += 0.4) {
        if (void_flags(squeeze, &border, &flagged, &full, &full_flagged) != 0)
            return 1;
        expect_below("implicit_void: closing, border particles with a full kernel sum on the surface", full_flagged, 0);
    }
    return failures;
}

/* A compressed patch under the free surface (the still tank, dp 1 cm, no gravity): the fluid within 4 dp of a point
 * 2.5 dp below the surface is drawn toward it by up to squeeze_dp, so that particles within a kernel of the surface
 * (near_surface) reach kernel sums above the lattice's. The density they report (snapshots, the health check) must
 * show it: held at rho0 near the surface, a void's border closing at 1.17 of the lattice's sum went unseen until a
 * step put two particles 0.13 dp apart (docs/method.md, "Never where the kernel is full"). Returns the largest kernel
 * sum (over the lattice's) and reported |rho/rho0 - 1| near the surface and the largest reported elsewhere (0 where the
 * step stopped), and whether the health check stopped the step on the density with the bound given. */
#define PATCH_REACH_DP 4.0
#define PATCH_DEPTH_DP 2.5
static double patch_bound;
static void patch_tank(surge_params *p)
{
    cavity_tank(p);
    p->boulders.placement = SURGE_BOULDERS_NONE;
    p->health.max_density_deviation = patch_bound;
}
static int surface_patch(double squeeze_dp, double bound, double *ratio_near, double *reported_near,
                         double *reported_rest, int *stopped_on_density)
{
    patch_bound = bound;
    surge_sim *sim = case_sim("still_tank.ini", 0.01, patch_tank);
    if (!sim)
        return 1;
    const double dp = sim->params.numerics.dp_m, reach = PATCH_REACH_DP * dp;
    double top = -INFINITY, x_low = INFINITY, x_high = -INFINITY;
    for (int k = sim->wall_count; k < sim->count; k++)
        top = fmax(top, sim->y[k]), x_low = fmin(x_low, sim->x[k]), x_high = fmax(x_high, sim->x[k]);
    const double cx = 0.5 * (x_low + x_high), cy = top - PATCH_DEPTH_DP * dp;
    for (int k = sim->wall_count; k < sim->count; k++) {
        const double dx = sim->x[k] - cx, dy = sim->y[k] - cy, d = hypot(dx, dy);
        if (d > 0 && d < reach) {
            const double inward = squeeze_dp * dp * sin(SURGE_PI * d / reach);
            sim->x[k] -= (real)(inward * dx / d), sim->y[k] -= (real)(inward * dy / d);
        }
    }
    *ratio_near = *reported_near = *reported_rest = 0;
    *stopped_on_density = surge_sim_step(sim) != 0 && surge_sim_health(sim)->check == SURGE_CHECK_DENSITY;
    if (*stopped_on_density) { /* rolled back: nothing of the step to read */
        printf("implicit_surface_density: %s\n", surge_sim_health(sim)->message);
        surge_sim_destroy(sim);
        return 0;
    }
    const implicit_work *w = implicit_of(sim);
    for (int k = sim->wall_count; k < sim->count; k++) {
        const double deviation = fabs(sim->rho[k] / sim->rho0 - 1.0);
        if (sim->near_surface[k]) {
            *ratio_near = fmax(*ratio_near, w->kernel_ratio[k - sim->wall_count]);
            *reported_near = fmax(*reported_near, deviation);
        } else {
            *reported_rest = fmax(*reported_rest, deviation);
        }
    }
    printf("implicit_surface_density: drawn in by %.2f dp: near the surface largest kernel sum %.4f of the lattice's, "
           "reported |rho/rho0 - 1| %.4f; elsewhere %.4f\n", squeeze_dp, *ratio_near, *reported_near, *reported_rest);
    surge_sim_destroy(sim);
    return 0;
}

static int test_implicit_surface_density(void)
{
    double ratio_near, reported_near, reported_rest;
    int stopped;
    if (surface_patch(0.3, 0.5, &ratio_near, &reported_near, &reported_rest, &stopped) != 0)
        return 1;
    expect_below("implicit_surface_density: the patch's compression near the surface, 1.05 - kernel sum", 1.05 - ratio_near, 0);
    /* the compression near the surface is reported (the density is stored in single precision) */
    expect_below("implicit_surface_density: kernel sum - 1 - reported deviation near the surface",
                 (ratio_near - 1.0) - reported_near, 1e-5);
    expect_below("implicit_surface_density: a health stop with the bound 0.5", stopped, 0);
    /* and the health check stops on it, with a bound above everything else the step reports */
    const double bound = 0.5 * (reported_rest + (ratio_near - 1.0));
    expect_below("implicit_surface_density: reported elsewhere - bound", reported_rest - bound, 0);
    if (surface_patch(0.3, bound, &ratio_near, &reported_near, &reported_rest, &stopped) != 0)
        return 1;
    expect_below("implicit_surface_density: no density stop between the two", 1 - stopped, 0);
    return failures;
}

/* The still tank (dp 1 cm) with one disc of radius 3 dp, in the fluid or 2 dp above the reach of its kernel */
#define SPIN_DISC_R_M 0.03
static void spin_tank(surge_params *p, double disc_y_m)
{
    p->numerics.scheme = SURGE_SCHEME_IMPLICIT;
    p->domain.height_m = 0.4;
    p->boulders.placement = SURGE_BOULDERS_LIST;
    char list[96], err[160];
    snprintf(list, sizeof list, "0.2 %g %g", disc_y_m, SPIN_DISC_R_M);
    surge_param_set(p, surge_param_find("boulders.list_m"), list, err, sizeof err);
}
static void spin_tank_wet(surge_params *p) { spin_tank(p, 0.1); }
static void spin_tank_dry(surge_params *p) { spin_tank(p, 0.2 + SPIN_DISC_R_M + 2 * 0.0255 + 0.02); } /* 2h, h 0.0255 */

/* The first step of the tank at rest with its disc spinning at omega (rad/s), and the smoothing length; 0 where
 * the step failed */
static double spin_step_s(void (*edit)(surge_params *), double omega_radps, double *h_m)
{
    surge_sim *sim = case_sim("still_tank.ini", 0.01, edit);
    if (!sim)
        return 0;
    *h_m = sim->derived.h_m;
    sim->boulders.omega[0] = omega_radps;
    const double dt = surge_sim_step(sim) == 0 ? sim->dt_s : 0;
    surge_sim_destroy(sim);
    return dt;
}

/* A disc's spin limits the implicit step where fluid is within a kernel of it (cfl h / (omega r), its surface
 * speed of 5 m/s the fastest motion), and not where none is: a dry disc spinning leaves the step of the tank at rest */
static int test_implicit_dry_spin(void)
{
    const double omega = 5.0 / SPIN_DISC_R_M;
    double h;
    const double wet = spin_step_s(spin_tank_wet, omega, &h), dry = spin_step_s(spin_tank_dry, omega, &h);
    const double still = spin_step_s(spin_tank_dry, 0, &h);
    const double expected_wet = surge_default_params().implicit.cfl * h / 5.0;
    printf("implicit_dry_spin: step %.6g s with the spinning disc in the fluid (cfl h / surface speed %.6g s), %.6g s "
           "with it dry, %.6g s with it dry and still\n", wet, expected_wet, dry, still);
    expect_below("implicit_dry_spin: |wet step / (cfl h / surface speed) - 1|", fabs(wet / expected_wet - 1), 1e-9);
    expect_below("implicit_dry_spin: |dry spinning step / dry still step - 1|", fabs(dry / still - 1), 0);
    expect_below("implicit_dry_spin: wet step / dry still step (the spin must bind)", wet / still, 0.2);
    return failures;
}

/* A phase of surge_phase_times by name, for the checks below */
typedef struct named_phase {
    const char *name;
    size_t offset;
} named_phase;

#define NAMED_PHASE(field) {#field, offsetof(surge_phase_times, field)}
static const named_phase phases[] = {
    NAMED_PHASE(neighbours_s), NAMED_PHASE(interaction_s), NAMED_PHASE(boundary_s), NAMED_PHASE(discs_s),
    NAMED_PHASE(contacts_s), NAMED_PHASE(geometry_s), NAMED_PHASE(surface_s), NAMED_PHASE(assembly_s),
    NAMED_PHASE(multigrid_s), NAMED_PHASE(viscous_solve_s), NAMED_PHASE(pressure_solve_s),
    NAMED_PHASE(disc_coupling_s), NAMED_PHASE(update_s),
};
#undef NAMED_PHASE
enum { PHASE_COUNT = sizeof phases / sizeof phases[0] };

static double phase_of(const surge_phase_times *t, int k)
{
    return *(const double *)((const char *)t + phases[k].offset);
}

/* The phase timers of cases/<name> with the scheme named: after a few steps every phase in exercised (a ' '-separated
 * list of names) is above zero and every other is zero, the named phases add up to no more than the total, the step
 * count is the steps taken; a reset zeroes them, and one more step counts again. No bound on any time: only which
 * are set. */
static void check_phase_times(const char *name, const char *scheme, const char *extra_setting, const char *exercised)
{
    surge_params p = surge_default_params();
    char path[512], err[256], setting[64], label[128];
    snprintf(label, sizeof label, "%s%s%s", scheme, extra_setting ? " " : "", extra_setting ? extra_setting : "");
    snprintf(path, sizeof path, "%s/cases/%s", SURGE_SOURCE_DIR, name);
    snprintf(setting, sizeof setting, "numerics.scheme=%s", scheme);
    if (surge_params_load(&p, path, err, sizeof err) != 0 ||
        surge_params_override(&p, setting, false, err, sizeof err) != 0 ||
        (extra_setting && surge_params_override(&p, extra_setting, false, err, sizeof err) != 0)) {
        fprintf(stderr, "%s\n", err);
        failures++;
        return;
    }
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        fprintf(stderr, "%s\n", err);
        failures++;
        return;
    }
    const int steps = 4;
    for (int k = 0; k < steps; k++)
        if (surge_sim_step(sim) != 0) {
            fprintf(stderr, "%s\n", surge_sim_health(sim)->message);
            failures++;
        }
    surge_phase_times t;
    surge_sim_phase_times(sim, &t);
    char what[256];
    double named_s = 0;
    for (int k = 0; k < PHASE_COUNT; k++) {
        const double seconds = phase_of(&t, k);
        named_s += seconds;
        char word[40];
        snprintf(word, sizeof word, " %s ", phases[k].name);
        char padded[200];
        snprintf(padded, sizeof padded, " %s ", exercised);
        const int expected = strstr(padded, word) != NULL;
        printf("phase_times %s %s: %-18s %.6f s\n", name, label, phases[k].name, seconds);
        snprintf(what, sizeof what, "phase_times %s %s: %s %s (1 = not)", name, label, phases[k].name,
                 expected ? "above zero" : "zero, the scheme has no such phase");
        expect_below(what, expected ? !(seconds > 0) : seconds != 0, 0);
    }
    printf("phase_times %s %s: total %.6f s, other %.6f s, %lld steps\n", name, label, t.total_s, t.other_s,
           (long long)t.steps);
    snprintf(what, sizeof what, "phase_times %s %s: named phases over the total, less 1", name, label);
    expect_below(what, named_s / t.total_s - 1, 1e-12);
    snprintf(what, sizeof what, "phase_times %s %s: |other_s - (total - named)| s", name, label);
    expect_below(what, fabs(t.other_s - (t.total_s - named_s)), 1e-12 * t.total_s);
    snprintf(what, sizeof what, "phase_times %s %s: |steps counted - steps taken|", name, label);
    expect_below(what, fabs((double)t.steps - steps), 0);
    surge_sim_reset_phase_times(sim);
    surge_sim_phase_times(sim, &t);
    double after_reset = fabs(t.total_s) + fabs(t.other_s) + fabs((double)t.steps);
    for (int k = 0; k < PHASE_COUNT; k++)
        after_reset += fabs(phase_of(&t, k));
    snprintf(what, sizeof what, "phase_times %s %s: after a reset, the sum of |every field|", name, label);
    expect_below(what, after_reset, 0);
    if (surge_sim_step(sim) != 0)
        failures++;
    surge_sim_phase_times(sim, &t);
    snprintf(what, sizeof what, "phase_times %s %s: one step after the reset counts 1 step with time (1 = not)", name,
             scheme);
    expect_below(what, !(t.steps == 1 && t.total_s > 0), 0);
    surge_sim_destroy(sim);
}

/* A disc in a closed box and the still tank without discs, with each scheme; the tank's multigrid set-up where the
 * implicit scheme is told to use it (the tank is below the size where it would choose it) */
static int test_phase_times(void)
{
    const char *implicit = "neighbours_s boundary_s geometry_s surface_s assembly_s viscous_solve_s pressure_solve_s "
                           "update_s";
    char implicit_discs[256];
    snprintf(implicit_discs, sizeof implicit_discs, "%s discs_s contacts_s disc_coupling_s", implicit);
    char implicit_multigrid[256];
    snprintf(implicit_multigrid, sizeof implicit_multigrid, "%s multigrid_s", implicit);
    check_phase_times("boulder_settling.ini", "explicit", NULL,
                      "neighbours_s interaction_s boundary_s discs_s contacts_s update_s");
    check_phase_times("boulder_settling.ini", "implicit", NULL, implicit_discs);
    check_phase_times("still_tank.ini", "explicit", NULL, "neighbours_s interaction_s boundary_s update_s");
    check_phase_times("still_tank.ini", "implicit", NULL, implicit);
    check_phase_times("still_tank.ini", "implicit", "implicit.preconditioner=amg", implicit_multigrid);
    return failures;
}

/* A socket whose peer guard has stopped takes connections as before: ZeroMQ reports them to no monitor, where a
 * monitor left without its reader would hold up the socket's I/O thread (and, on closing, lose the event's frame). */
static int test_peer_guard_stop(void)
{
    void *context = zmq_ctx_new();
    void *server = zmq_socket(context, ZMQ_ROUTER), *client = zmq_socket(context, ZMQ_DEALER);
    const int linger_ms = 0;
    zmq_setsockopt(server, ZMQ_LINGER, &linger_ms, sizeof linger_ms);
    zmq_setsockopt(client, ZMQ_LINGER, &linger_ms, sizeof linger_ms);
    char endpoint[256], err[256];
    size_t endpoint_len = sizeof endpoint;
    peer_guard *guard = NULL;
    if (zmq_bind(server, "tcp://127.0.0.1:*") != 0 ||
        zmq_getsockopt(server, ZMQ_LAST_ENDPOINT, endpoint, &endpoint_len) != 0)
        snprintf(err, sizeof err, "bind: %s", zmq_strerror(zmq_errno()));
    else
        guard = peer_guard_start(context, server, 4, 60, err, sizeof err);
    if (!guard) {
        fprintf(stderr, "%s\n", err);
        failures++;
    } else {
        peer_guard_stop(guard);
        /* the guard's end of the monitor closes in ZeroMQ's threads, after peer_guard_stop has returned */
        zmq_pollitem_t item = {.socket = server, .events = ZMQ_POLLIN};
        zmq_poll(&item, 1, 100);
        zmq_connect(client, endpoint);
        zmq_send(client, "status", 6, 0);
        expect_below("peer_guard_stop: a connection made after it delivers its request within 5 s (1 = not)",
                     zmq_poll(&item, 1, 5000) != 1, 0);
    }
    zmq_close(client);
    zmq_close(server);
    zmq_ctx_term(context);
    return failures;
}

int main(int argc, char **argv)
{
    if (argc < 2)
        return 2;
    if (!strcmp(argv[1], "implicit_dt"))
        return test_implicit_dt() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_cavity"))
        return test_implicit_cavity() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_void"))
        return test_implicit_void() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_surface_density"))
        return test_implicit_surface_density() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_dry_spin"))
        return test_implicit_dry_spin() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_disc_momentum"))
        return test_implicit_disc_momentum() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_films"))
        return test_implicit_films() ? 1 : 0;
    if (!strcmp(argv[1], "kernel"))
        return test_kernel() ? 1 : 0;
    if (!strcmp(argv[1], "eos"))
        return test_eos() ? 1 : 0;
    if (!strcmp(argv[1], "neighbours"))
        return test_neighbours() ? 1 : 0;
    if (!strcmp(argv[1], "neighbour_lists"))
        return test_neighbour_lists() ? 1 : 0;
    if (!strcmp(argv[1], "set_param"))
        return test_set_param() ? 1 : 0;
    if (!strcmp(argv[1], "corner_continuity"))
        return test_corner_continuity() ? 1 : 0;
    if (!strcmp(argv[1], "disc_contact_rules"))
        return test_disc_contact_rules() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_wedge"))
        return test_implicit_wedge() ? 1 : 0;
    if (!strcmp(argv[1], "lanes"))
        return test_lanes() ? 1 : 0;
    if (!strcmp(argv[1], "behind_wall"))
        return test_behind_wall() ? 1 : 0;
    if (!strcmp(argv[1], "explicit_surface_clump"))
        return test_explicit_surface_clump() ? 1 : 0;
    if (!strcmp(argv[1], "health_speed"))
        return test_health_speed() ? 1 : 0;
    if (!strcmp(argv[1], "wall_contact_rules"))
        return test_wall_contact_rules() ? 1 : 0;
    if (!strcmp(argv[1], "no_penetration_face"))
        return test_no_penetration_face() ? 1 : 0;
    if (!strcmp(argv[1], "diffusion_linear"))
        return test_diffusion_linear() ? 1 : 0;
    if (!strcmp(argv[1], "c0_discs"))
        return test_c0_discs() ? 1 : 0;
    if (!strcmp(argv[1], "face_search"))
        return test_face_search() ? 1 : 0;
    if (!strcmp(argv[1], "disc_orientation"))
        return test_disc_orientation() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_auto"))
        return test_implicit_auto() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_projection"))
        return test_implicit_projection() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_rest_density"))
        return test_implicit_rest_density() ? 1 : 0;
    if (!strcmp(argv[1], "implicit_clump"))
        return test_implicit_clump() ? 1 : 0;
    if (!strcmp(argv[1], "fluid_share"))
        return test_fluid_share() ? 1 : 0;
    if (!strcmp(argv[1], "phase_times"))
        return test_phase_times() ? 1 : 0;
    if (!strcmp(argv[1], "peer_guard_stop"))
        return test_peer_guard_stop() ? 1 : 0;
    return 2;
}
