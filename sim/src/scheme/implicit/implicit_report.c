/* What `surge check` says of a scene for the implicit scheme: discs too coarse for its step, steps that let a mode
 * under the free surface grow, and its step, solvers and memory. */
#include <stdbool.h>
#include <stdio.h>

#include "scheme/implicit/implicit.h"

/* The implicit scheme's steps that let a mode under the free surface grow where the kernels under it are cut off
 * (implicit.surface_images = 0): a short fixed step, a small CFL. With the surface's mirror images (the default)
 * the still tank stays at rest at any step (docs/validation/stability.md, "Short steps in a thin fluid"). */
static void warn_implicit_step(FILE *out, const surge_params *p, const surge_derived *d)
{
    if (p->implicit.surface_images)
        return;
    const double dp = p->numerics.dp_m;
    /* a fixed step shorter than the scheme's own at rest: the still tank's free surface does not stay at rest
     * there */
    const double dt_rest = surge_implicit_dt_s(p, d->h_m, p->body.gravity_mps2, 0.0);
    if (p->numerics.dt_fixed_s > 0 && p->numerics.dt_fixed_s < dt_rest)
        fprintf(out, "surge: warning: numerics.dt_fixed_s = %g s is shorter than the implicit scheme's own step at "
                "rest (%.3g s, implicit.force_cfl): in the still tank, at fixed steps under about half of it "
                "(nu dt / dp^2 = %.3g here) with implicit.surface_images = 0 a mode of the incremental projection "
                "under the free surface grows and the fluid does not stay at rest (docs/validation/stability.md, "
                "\"Short steps in a thin fluid\"); leave the step to the scheme (0) or the surface's images on "
                "(1)\n",
                p->numerics.dt_fixed_s, dt_rest,
                p->fluid.viscosity_m2ps * p->numerics.dt_fixed_s / (dp * dp));
    const double default_cfl = surge_default_params().implicit.cfl;
    if (p->implicit.cfl < default_cfl)
        fprintf(out, "surge: warning: implicit.cfl = %g is below its default %g: with implicit.surface_images = 0 "
                "the same mode grows where the flow's speed sets the step (the debris surge at dp = 0.04 m stopped "
                "at 5.7 s with 60 discs and 0.1, at 0.52 s without discs and 0.05; docs/validation/stability.md, "
                "\"Short steps in a thin fluid\")\n", p->implicit.cfl, default_cfl);
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
                "is slower); pressure solves by %s, viscous solves by %s%s (implicit.preconditioner = %s); the cost "
                "per step follows the linear solves' iterations (diagnostics.csv), not estimated here\n",
                verbose ? "  " : "surge: ", bytes / 1e6, entries, dt_implicit, u,
                amg ? "BiCGSTAB with hypre's BoomerAMG" : "matrix-free Jacobi-preconditioned BiCGSTAB",
                viscous_amg ? "BiCGSTAB with hypre's BoomerAMG" : "matrix-free Jacobi-preconditioned BiCGSTAB",
                (amg || viscous_amg) && p->implicit.multigrid_parts > 1 ? ", each hierarchy in parts" : "",
                p->implicit.preconditioner == SURGE_PRECONDITIONER_AUTO
                    ? "auto: amg for the pressure from 2,500 fluid particles, for the viscous solve from 10,000"
                    : (amg ? "amg" : "jacobi"));
}

void implicit_check_report(const surge_sim *sim, FILE *out, int verbose, double entries, double bytes)
{
    const surge_params *p = &sim->params;
    const surge_derived *d = &sim->derived;
    const double dp = p->numerics.dp_m;
    if (d->boulder_count > 0 && d->smallest_boulder_radius_m < 2.5 * dp)
        fprintf(out, "surge: warning: the implicit scheme with discs under 2.5 dp in radius (the smallest here is "
                        "%.1f dp): its incompressible step gives the fluid squeezed under a coarse disc no room, and "
                        "the debris surge stopped at dp = 0.066 m (1.5 dp) where it ran at 0.04 m (2.5 dp) "
                        "(docs/validation/debris_surge.md, \"Known failures\"); dp <= %g m gives 2.5\n",
                d->smallest_boulder_radius_m / dp, d->smallest_boulder_radius_m / 2.5);
    warn_implicit_step(out, p, d);
    report_implicit_cost(out, verbose, p, d, entries, bytes);
}
