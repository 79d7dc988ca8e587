/* What `surge check` says of a scene for the explicit scheme: its longest step and the wall time a simulated second
 * takes. */
#include <math.h>
#include <stdio.h>

#include "scheme/explicit/explicit.h"

/* The explicit scheme's longest step, and the wall time a simulated second takes at the measured throughput. */
void explicit_check_report(const surge_sim *sim, FILE *out, int verbose, double entries, double bytes)
{
    const surge_params *p = &sim->params;
    const surge_derived *d = &sim->derived;
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

