/* Resolution and cost, from the scene as built: warnings when the flow depth holds fewer than 15 particles (the
 * paper's minimum) or a disc's radius fewer than 4 dp; the memory and the time a simulated second will take,
 * estimated from the list sizes and the throughput measured in docs/performance.md. `check` prints them with its
 * report (verbose), `run` with its messages. */
#include "cli.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>

#define SURGE_PI_CLI 3.14159265358979323846

static void warn_coarse_resolution(FILE *out, const surge_params *p, const surge_derived *d)
{
    const double dp = p->numerics.dp_m;
    const double depth_particles = p->fluid.depth_m / dp;
    if (d->fluid_count > 0 && depth_particles < 15)
        fprintf(out, "surge: note: the fluid's depth (%g m) holds %.1f particles at dp = %g m, fewer than the 15 "
                        "that velocity profiles and fronts need (GMD 2025); dp <= %g m gives 15\n",
                p->fluid.depth_m, depth_particles, dp, p->fluid.depth_m / 15);
    if (d->boulder_count > 0 && d->smallest_boulder_radius_m < 4 * dp)
        fprintf(out, "surge: warning: the smallest disc's radius (%g m) is %.1f dp, fewer than 4: its surface is "
                        "too coarse for the fluid's forces on it; dp <= %g m gives 4\n",
                d->smallest_boulder_radius_m, d->smallest_boulder_radius_m / dp, d->smallest_boulder_radius_m / 4);
    if (d->boulder_count > 0 && p->numerics.scheme == SURGE_SCHEME_IMPLICIT && d->smallest_boulder_radius_m < 2.5 * dp)
        fprintf(out, "surge: warning: the implicit scheme with discs under 2.5 dp in radius (the smallest here is "
                        "%.1f dp): its incompressible step gives the fluid squeezed under a coarse disc no room, and "
                        "the debris surge stopped at dp = 0.066 m (1.5 dp) where it ran at 0.04 m (2.5 dp) "
                        "(docs/validation/debris_surge.md, \"The implicit scheme with discs\"); dp <= %g m gives 2.5\n",
                d->smallest_boulder_radius_m / dp, d->smallest_boulder_radius_m / 2.5);
}

/* The implicit scheme's steps that let a mode under the free surface grow: a short fixed step, a small CFL. */
static void warn_implicit_step(FILE *out, const surge_params *p, const surge_derived *d)
{
    const double dp = p->numerics.dp_m;
    /* a fixed step shorter than the scheme's own at rest: the still tank's free surface does not stay at rest
     * there (docs/validation/stability.md, "Short steps in a thin fluid") */
    const double dt_rest = surge_implicit_dt_s(p, d->h_m, p->body.gravity_mps2, 0.0);
    if (p->numerics.dt_fixed_s > 0 && p->numerics.dt_fixed_s < dt_rest)
        fprintf(out, "surge: warning: numerics.dt_fixed_s = %g s is shorter than the implicit scheme's own step at "
                "rest (%.3g s, implicit.force_cfl): in the still tank, at fixed steps under about half of it "
                "(nu dt / dp^2 = %.3g here) a mode of the incremental projection under the free surface grows "
                "and the fluid does not stay at rest (docs/validation/stability.md, \"Short steps in a thin "
                "fluid\"); leave the step to the scheme (0) or use the explicit scheme\n",
                p->numerics.dt_fixed_s, dt_rest,
                p->fluid.viscosity_m2ps * p->numerics.dt_fixed_s / (dp * dp));
    const double default_cfl = surge_default_params().implicit.cfl;
    if (p->implicit.cfl < default_cfl)
        fprintf(out, "surge: warning: implicit.cfl = %g is below its default %g: the same mode grows where the "
                "flow's speed sets the step (the debris surge at dp = 0.04 m stopped at 5.7 s with 60 discs and "
                "0.1, at 0.52 s without discs and 0.05; docs/validation/stability.md, \"Short steps in a thin "
                "fluid\")\n", p->implicit.cfl, default_cfl);
}

/* The implicit scheme's step follows the flow's speed; its cost per step follows the solves' iterations, so only
 * the memory, the step and the solvers are said. */
static void report_implicit_cost(FILE *out, int verbose, const surge_params *p, const surge_derived *d,
                                 double entries, double bytes)
{
    const double u = d->expected_speed_mps;
    double dt_implicit = p->numerics.dt_fixed_s;
    if (!(dt_implicit > 0))
        dt_implicit = surge_implicit_dt_s(p, d->h_m, p->body.gravity_mps2, u);
    const bool amg = surge_implicit_uses_amg(p, d->fluid_count, false);
    const bool viscous_amg = surge_implicit_uses_amg(p, d->fluid_count, true);
    if (verbose || bytes > 4e9)
        fprintf(out, "%sestimated memory %.3g MB (%.0f list entries per fluid particle); implicit scheme: dt = %.3g "
                "s at the scene's expected speed %.3g m/s (it follows the flow's own speed: longer where the flow "
                "is slower); pressure solves by %s, viscous solves by %s (implicit.preconditioner = %s); the cost "
                "per step follows the linear solves' iterations (diagnostics.csv), not estimated here\n",
                verbose ? "  " : "surge: ", bytes / 1e6, entries, dt_implicit, u,
                amg ? "BiCGSTAB with hypre's BoomerAMG" : "matrix-free Jacobi-preconditioned BiCGSTAB",
                viscous_amg ? "BiCGSTAB with hypre's BoomerAMG" : "matrix-free Jacobi-preconditioned BiCGSTAB",
                p->implicit.preconditioner == SURGE_PRECONDITIONER_AUTO
                    ? "auto: amg for the pressure from 2,500 fluid particles, for the viscous solve from 10,000"
                    : (amg ? "amg" : "jacobi"));
}

/* The explicit scheme's longest step, and the wall time a simulated second takes at the measured throughput. */
static void report_explicit_cost(FILE *out, int verbose, const surge_params *p, const surge_derived *d,
                                 double entries, double bytes)
{
    const double h = d->h_m;
    double dt = p->numerics.dt_fixed_s;
    if (!(dt > 0)) {
        dt = h / d->c0_mps;
        if (p->numerics.viscous_dt_limit && p->fluid.viscosity_m2ps > 0)
            dt = fmin(dt, h * h / p->fluid.viscosity_m2ps);
        dt *= p->numerics.cfl;
    }
    /* seconds per particle-step on 2 threads of the 2-core EPYC VM, fitted to the benchmark at C_h 1.0 and 1.8; a
     * wall particle counts as a fluid one: in the debris surge a step costs about the same per wall particle (a disc's
     * mDBC sums, forces and face search) as per fluid particle (docs/performance.md, "What surge check's estimate
     * counts") */
    const double per_particle_step_s = 1.37e-7 + 4.43e-9 * entries;
    const double particle_steps = d->fluid_count / dt;
    const double wall_time_s = (double)(d->fluid_count + d->wall_count) / dt * per_particle_step_s;
    if (verbose || bytes > 4e9)
        fprintf(out,
                "%sestimated memory %.3g MB (%.0f list entries per fluid particle); at most %.3g steps and %.3g "
                "fluid particle-steps per simulated second (dt <= %.3g s), about %.3g s of wall time per simulated "
                "second on 2 cores, wall particles counted as fluid ones (docs/performance.md)\n",
                verbose ? "  " : "surge: ", bytes / 1e6, entries, 1 / dt, particle_steps, dt, wall_time_s);
}

void report_resolution(const surge_sim *sim, int verbose)
{
    const surge_params *p = surge_sim_params(sim);
    const surge_derived *d = surge_sim_derived(sim);
    const double dp = p->numerics.dp_m, h = d->h_m;
    FILE *out = verbose ? stdout : stderr;
    warn_coarse_resolution(out, p, d);
    /* list entries per fluid particle: the particles within 2h + skin (the implicit scheme's lists have none); 12
     * bytes each, about 200 bytes of state */
    const double skin_h = p->numerics.scheme == SURGE_SCHEME_IMPLICIT ? 0.0 : p->numerics.neighbour_skin_h;
    const double reach = (2.0 + skin_h) * h;
    const double entries = SURGE_PI_CLI * reach * reach / (dp * dp);
    const double bytes = d->fluid_count * (12 * entries + 200) + d->wall_count * (6 * entries + 150);
    if (p->numerics.scheme == SURGE_SCHEME_IMPLICIT) {
        warn_implicit_step(out, p, d);
        report_implicit_cost(out, verbose, p, d, entries, bytes);
    } else {
        report_explicit_cost(out, verbose, p, d, entries, bytes);
    }
}

/* Density diffusion relaxes pressure over the kernel scale. Around a boulder of radius r in a very viscous fluid
 * that lets the flow carry a divergence of about delta (h/r) nu / (c0 r) of its strain rate, and the suspension
 * loses its extra viscosity (docs/validation/poiseuille_loaded.md). Warns where the estimate passes 5 %. */
void warn_diffusive_compressibility(const surge_sim *sim)
{
    const surge_params *p = surge_sim_params(sim);
    const surge_derived *d = surge_sim_derived(sim);
    if (d->boulder_count == 0 || !(p->numerics.density_diffusion > 0))
        return;
    const double radius_m = d->smallest_boulder_radius_m;
    const double estimate =
        p->numerics.density_diffusion * (d->h_m / radius_m) * p->fluid.viscosity_m2ps / (d->c0_mps * radius_m);
    if (estimate > 0.05)
        fprintf(stderr, "surge: warning: density diffusion lets the fluid compress around the boulders: "
                        "delta (h/r) nu / (c0 r) = %.2g with r = %.4g m, c0 = %.4g m/s (above 0.05); set "
                        "numerics.density_diffusion = 0 or raise numerics.c0_mps\n",
                estimate, radius_m, d->c0_mps);
}
