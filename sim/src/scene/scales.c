/* The scene's scales from its parameters alone: the speeds c0 is derived from, and where the upstream wall ends. */
#include <math.h>

#include "physics/kernel.h"
#include "scene/scales.h"

void scene_body_acceleration(const surge_params *p, double *gx_mps2, double *gy_mps2)
{
    const double theta = p->body.slope_deg * SURGE_PI / 180.0;
    *gx_mps2 = p->body.gravity_mps2 * sin(theta) + p->body.force_x_mps2;
    *gy_mps2 = -p->body.gravity_mps2 * cos(theta);
}

/* The hydrostatic head's speed sqrt(g_n H) over the fluid's depth (a closed channel: its height): c0 = 10 times it
 * keeps the hydrostatic density variation rho0 g_n H / (rho0 c0^2) within 1 %. */
double scene_head_speed(const surge_params *p)
{
    const double g_normal = p->body.gravity_mps2 * cos(p->body.slope_deg * SURGE_PI / 180.0);
    const double head_m = p->walls.top ? p->domain.height_m : p->fluid.depth_m;
    return sqrt(fabs(g_normal) * head_m);
}

/* The largest speed the scene can be expected to reach, from its own scales (docs/method.md). */
double scene_expected_speed(const surge_params *p)
{
    const double theta = p->body.slope_deg * SURGE_PI / 180.0;
    const double g_normal = p->body.gravity_mps2 * cos(theta);
    const double drive = p->body.gravity_mps2 * sin(theta) + p->body.force_x_mps2;
    const double depth = p->fluid.depth_m, nu = p->fluid.viscosity_m2ps;
    double u = fmax(fabs(p->walls.bottom_speed_mps), fabs(p->walls.top_speed_mps));
    if (p->walls.top) {
        /* closed channel: Poiseuille centre-line speed */
        if (nu > 0)
            u = fmax(u, fabs(drive) * p->domain.height_m * p->domain.height_m / (8.0 * nu));
    } else {
        /* free surface: collapse of the block (sqrt(2 g h)) and the surface speed of a film of this depth relative
         * to the bed (g_x h^2 / (2 nu); none without viscosity) */
        const double fall_mps = sqrt(2.0 * fabs(g_normal) * depth);
        const double film_mps = nu > 0 ? drive * depth * depth / (2.0 * nu) : 0.0;
        u = fmax(u, fall_mps);
        /* the film's surface speed in the walls' frame, the bed's speed added: a surge held on an upstream belt
         * moves at the difference (the debris surge: |-3.5 + 6.0| m/s) */
        if (nu > 0)
            u = fmax(u, fabs(p->walls.bottom_speed_mps + film_mps));
        /* discs ride near the surface and fall off the front: one lands on the bed with the film's surface speed
         * along it and its fall across it, and crushes the fluid under it; the two are added, not combined as a
         * vector, under which 1 of 10 runs stopped on that crush (docs/method.md, "c0"; the debris surge:
         * 6.03 + 5.20 = 11.23 m/s) */
        if (p->boulders.placement != SURGE_BOULDERS_NONE)
            u = fmax(u, fabs(film_mps) + fall_mps);
    }
    return u;
}

/* The speed whose square, times c0_factor^2, holds the viscous pressures of a flow of speed u over a length L within
 * the density variation the factor allows: rho0 nu u / L / (rho0 c0^2) <= 1 / c0_factor^2 gives c0 >= c0_factor
 * sqrt(nu u / L) (Morris, Fox and Zhu 1997, J. Comput. Phys. 136, the viscous term of their estimate of c0^2). With
 * discs, L is the smallest disc's radius, over which the flow around it and through the gaps between discs varies;
 * 0 without discs, where the flow's own scales above bound the viscous pressures. */
double scene_viscous_speed(const surge_params *p, double speed_mps, double smallest_disc_radius_m)
{
    const double nu = p->fluid.viscosity_m2ps;
    if (!(nu > 0) || !(speed_mps > 0) || !(smallest_disc_radius_m > 0) || !isfinite(smallest_disc_radius_m))
        return 0.0;
    return sqrt(nu * speed_mps / smallest_disc_radius_m);
}

double scene_upstream_back_m(const surge_params *p)
{
    const double dp = p->numerics.dp_m, front_back_m = p->walls.upstream_x_m - p->walls.layers * dp;
    const long room = lround(floor(front_back_m / dp + 1e-9));
    return front_back_m - (room < p->walls.layers ? (room > 0 ? room : 0) : p->walls.layers) * dp;
}
