/* The health monitor: every step, every fluid particle and every boulder, the checks of surge_health_check. */
#include <math.h>
#include <stdio.h>

#include "sim_internal.h"
#include "scene/scales.h"
#include "health.h"

/* The first check that particle a fails, with the offending value. */
static surge_health_check check_particle(const surge_sim *sim, int a, double *value)
{
    const surge_params *p = &sim->params;
    const double dp = p->numerics.dp_m, L = p->domain.length_m, H = p->domain.height_m;
    const double wall_depth = p->walls.layers * dp;
    const double x = surge_sim_wrapped_x(sim, sim->x[a]), y = sim->y[a];
    if (!isfinite(x) || !isfinite(y) || !isfinite(sim->vx[a]) || !isfinite(sim->vy[a]) || !isfinite(sim->rho[a])) {
        *value = !isfinite(x) ? x : !isfinite(y) ? y : !isfinite(sim->vx[a]) ? sim->vx[a]
               : !isfinite(sim->vy[a]) ? sim->vy[a] : sim->rho[a];
        return SURGE_CHECK_NOT_FINITE;
    }
    /* weakly-compressible SPH holds only well below c0: a particle past it is a blow-up, caught in the step it
     * happens (a disc-laden surge's particle went from 4 to 2141 m/s in one step at c0 = 78 m/s, 2026-11-25) */
    const double speed2 = (double)sim->vx[a] * sim->vx[a] + (double)sim->vy[a] * sim->vy[a];
    if (!sim->scheme->incompressible && speed2 > sim->derived.c0_mps * sim->derived.c0_mps) {
        *value = sqrt(speed2);
        return SURGE_CHECK_SPEED;
    }
    const double ratio = sim->rho[a] / sim->rho0;
    if (fabs(ratio - 1.0) > p->health.max_density_deviation) {
        *value = ratio;
        return SURGE_CHECK_DENSITY;
    }
    *value = y;
    if ((p->walls.bottom && y < -dp) || (p->walls.top && y > H + dp))
        return SURGE_CHECK_CROSSED_WALL;
    *value = x;
    if ((p->walls.left && x < -dp) || (p->walls.right && x > L + dp))
        return SURGE_CHECK_CROSSED_WALL;
    if (p->walls.upstream && y < p->walls.upstream_height_m && x < p->walls.upstream_x_m - dp) {
        /* inside the wall, more than dp past its front face or (where it has one) its back face */
        const double back_m = scene_upstream_back_m(p);
        if (x > back_m + (back_m < p->walls.upstream_x_m - wall_depth ? dp : 0))
            return SURGE_CHECK_CROSSED_WALL;
    }
    *value = y;
    if (y < -wall_depth || y > H + (p->walls.top ? wall_depth : 0.0))
        return SURGE_CHECK_LEFT_DOMAIN;
    *value = x;
    if (!p->domain.periodic_x && (x < (p->walls.left ? -wall_depth : 0.0) || x > L + (p->walls.right ? wall_depth : 0.0)))
        return SURGE_CHECK_LEFT_DOMAIN;
    return SURGE_HEALTHY;
}

const char *surge_health_check_name(surge_health_check c)
{
    switch (c) {
    case SURGE_HEALTHY: return "healthy";
    case SURGE_CHECK_NOT_FINITE: return "non-finite value (NaN/Inf)";
    case SURGE_CHECK_DENSITY: return "density far from rho0";
    case SURGE_CHECK_LEFT_DOMAIN: return "particle left the domain";
    case SURGE_CHECK_CROSSED_WALL: return "particle crossed a wall";
    case SURGE_CHECK_DT_COLLAPSE: return "time step collapsed";
    case SURGE_CHECK_OUT_OF_MEMORY: return "out of memory";
    case SURGE_CHECK_SOLVER: return "linear solve did not converge";
    case SURGE_CHECK_SPEED: return "particle faster than the speed of sound c0";
    }
    return "?";
}

int health_check(surge_sim *sim)
{
    surge_health *h = &sim->health;
    h->check = SURGE_HEALTHY;
    h->particle_id = -1;
    h->step = sim->step;
    h->time_s = sim->time_s;
    int first_bad = sim->count;
    #pragma omp parallel for schedule(static) reduction(min : first_bad)
    for (int a = sim->wall_count; a < sim->count; a++) {
        double v;
        if (check_particle(sim, a, &v) != SURGE_HEALTHY && a < first_bad)
            first_bad = a;
    }
    if (first_bad < sim->count) {
        h->check = check_particle(sim, first_bad, &h->value);
        h->particle_id = sim->id[first_bad];
        const char *detail = "";
        char extra[128] = "";
        if (h->check == SURGE_CHECK_DENSITY) {
            snprintf(extra, sizeof extra, "rho/rho0 = %.6g, allowed 1 +- %g", h->value,
                     sim->params.health.max_density_deviation);
            detail = extra;
        } else if (h->check == SURGE_CHECK_SPEED) {
            snprintf(extra, sizeof extra, "|v| = %.4g m/s, c0 = %.4g m/s, x = %.6g m, y = %.6g m", h->value,
                     sim->derived.c0_mps, surge_sim_wrapped_x(sim, sim->x[first_bad]), sim->y[first_bad]);
            detail = extra;
        } else {
            snprintf(extra, sizeof extra, "x = %.6g m, y = %.6g m, v = (%.4g, %.4g) m/s, rho = %.6g kg/m3",
                     surge_sim_wrapped_x(sim, sim->x[first_bad]), sim->y[first_bad], (double)sim->vx[first_bad], (double)sim->vy[first_bad],
                     (double)sim->rho[first_bad]);
            detail = extra;
        }
        snprintf(h->message, sizeof h->message, "health check failed: %s at particle %d, step %lld, t = %.9g s (%s)",
                 surge_health_check_name(h->check), h->particle_id, (long long)h->step, h->time_s, detail);
        return -1;
    }
    /* boulders: finite state, centre inside the domain (a disc through a wall is the contact solver failing) */
    const boulder_set *b = &sim->boulders;
    const double H = sim->params.domain.height_m, L = sim->params.domain.length_m;
    for (int i = 0; i < b->count; i++) {
        const int finite = isfinite(b->x[i]) && isfinite(b->y[i]) && isfinite(b->vx[i]) && isfinite(b->vy[i]) &&
                           isfinite(b->omega[i]) && isfinite(b->angle[i]);
        const int inside = b->y[i] >= 0 && (!sim->params.walls.top || b->y[i] <= H) &&
                           (sim->params.domain.periodic_x || (b->x[i] >= 0 && b->x[i] <= L));
        if (finite && inside)
            continue;
        h->check = finite ? SURGE_CHECK_LEFT_DOMAIN : SURGE_CHECK_NOT_FINITE;
        h->value = finite ? b->y[i] : b->vx[i];
        snprintf(h->message, sizeof h->message,
                 "health check failed: %s at boulder %d, step %lld, t = %.9g s (centre (%.6g, %.6g) m, v = (%.4g, "
                 "%.4g) m/s, omega = %.4g rad/s)", surge_health_check_name(h->check), i + 1, (long long)h->step,
                 h->time_s, b->x[i], b->y[i], b->vx[i], b->vy[i], b->omega[i]);
        return -1;
    }
    if (sim->params.numerics.dt_fixed_s == 0 && sim->first_dt_s > 0 &&
        sim->dt_s < sim->params.health.min_dt_ratio * sim->first_dt_s) {
        h->check = SURGE_CHECK_DT_COLLAPSE;
        h->value = sim->dt_s;
        snprintf(h->message, sizeof h->message,
                 "health check failed: %s at step %lld, t = %.9g s (dt = %.3g s, below %g x first dt %.3g s)",
                 surge_health_check_name(h->check), (long long)h->step, h->time_s, sim->dt_s, sim->params.health.min_dt_ratio,
                 sim->first_dt_s);
        return -1;
    }
    h->message[0] = '\0';
    return 0;
}
