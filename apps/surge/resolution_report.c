/* Resolution and cost, from the scene as built: warnings when the flow depth holds fewer than 15 particles (the
 * paper's minimum) or a disc's radius fewer than 4 dp; the memory and the time a simulated second will take,
 * estimated from the list sizes and the throughput measured in docs/performance.md. `check` prints them with its
 * report (verbose), `run` with its messages. */
#include "cli.h"

#include <stdio.h>

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
}

void report_resolution(const surge_sim *sim, int verbose)
{
    FILE *out = verbose ? stdout : stderr;
    warn_coarse_resolution(out, surge_sim_params(sim), surge_sim_derived(sim));
    surge_sim_check_report(sim, out, verbose);
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
