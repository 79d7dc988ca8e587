/* Particle shifting (workshop paper Sect. II-D, V-B), applied with the corrector, and the density change that
 * keeps each particle's density consistent with the spacing the shift leaves (docs/method.md, "Particle
 * shifting"). */
#include <math.h>

#include "physics/pair_terms.h"
#include "sim_internal.h"
#include "neighbours/neighbours.h"
#include "physics/shifting.h"

/* The displacement of fluid particle a, from the concentration gradient of the corrector's pass. */
static void shift_displacement(const surge_sim *sim, int a, double dt, double *sx, double *sy)
{
    const surge_params *p = &sim->params;
    *sx = *sy = 0;
    double coef;
    switch (p->shifting.form) {
    case SURGE_SHIFT_VELOCITY: /* dr = -A h |u| dt grad C, none on the free surface */
        if (sim->div_r[a] < p->shifting.surface_threshold)
            return;
        coef = p->shifting.velocity_coefficient * sim->derived.h_m * dt *
               sqrt((double)sim->vx[a] * sim->vx[a] + (double)sim->vy[a] * sim->vy[a]);
        break;
    case SURGE_SHIFT_LIND: /* dr = -(A_L/2) h c0 dt grad C; within the free-surface layer only where crowded */
        if (sim->scheme->incompressible) { /* no speed of sound: below */
            coef = 0.5 * p->shifting.lind_coefficient * sim->derived.h_m * sim->derived.h_m;
            break;
        }
        coef = 0.5 * p->shifting.lind_coefficient;
        if (sim->near_surface[a] || sim->div_r[a] < p->shifting.surface_threshold) {
            /* min(A_L/2, 2 w (k - 1)) with k the kernel ratio: the implicit scheme's anti-clumping shift
             * 2 w (k - 1) h^2 grad C with c0 dt for its h, as in Lind's form; zero at rest spacing or wider */
            const double crowding = (double)sim->kernel_ratio[a] - 1.0;
            if (!(crowding > 0 && p->shifting.surface_anti_clumping > 0))
                return;
            coef = fmin(coef, 2.0 * p->shifting.surface_anti_clumping * crowding);
        }
        coef = coef * sim->derived.h_m * sim->derived.c0_mps * dt;
        break;
    default: return;
    }
    double dx = -coef * sim->grad_c_x[a], dy = -coef * sim->grad_c_y[a];
    if (sim->scheme->incompressible && p->shifting.form == SURGE_SHIFT_LIND && sim->near_surface[a]) {
        /* an incompressible scheme's Lind form (Lind et al. 2012): dr = -(A_L/2) h^2 grad C per step, and in the
         * free-surface layer only along the surface, where nothing else keeps the particles apart (their pressure is 0).
         * The surface's normal is the neighbours' grad C averaged: the particle's own is the shift's direction, so
         * projecting on it would leave nothing */
        const double along = dx * sim->surface_nx[a] + dy * sim->surface_ny[a];
        dx -= along * sim->surface_nx[a], dy -= along * sim->surface_ny[a];
    }
    const double max_shift = p->shifting.max_shift_dp * p->numerics.dp_m;
    const double len = sqrt(dx * dx + dy * dy);
    if (len > max_shift) {
        dx *= max_shift / len;
        dy *= max_shift / len;
    }
    /* no closer to a wall face than the reach of its repulsion: a shift does not carry fluid into a wall */
    const double toward_face_m = -(dx * sim->face_nx[a] + dy * sim->face_ny[a]);
    const double room_m = fmax(0.0, sim->face_gap_m[a] - sim_contact_reach_m(sim));
    if (toward_face_m > room_m) {
        dx += (toward_face_m - room_m) * sim->face_nx[a];
        dy += (toward_face_m - room_m) * sim->face_ny[a];
    }
    *sx = dx;
    *sy = dy;
}

/* The relative volume change each shift causes, div(dr)_a = -sum_b V_b (dr_a - dr_b).grad_a W_ab over fluid and
 * wall neighbours (walls do not shift): the same sum by which the shift changes the particle's kernel sum
 * sum_b m W_ab, so a density that takes it on follows the spacing (mass is carried with the particles). */
static void shift_divergence(surge_sim *sim)
{
    neighbours_track(sim); /* the discs have moved to the end of the step */
    const neighbour_lists *nl = &sim->neighbours;
    const real grad_coef = sim->kernel.grad_coef, inv_h = sim->kernel.inv_h, mass = (real)sim->mass;
    const real support2 = sim->kernel.support2;
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const real *restrict inv_rho = sim->inv_rho, *restrict sx = sim->shift_x, *restrict sy = sim->shift_y;
    int begin, end;
    neighbours_fluid_share(sim, &begin, &end);
    for (int a = begin; a < end; a++) {
        const real sxa = sx[a], sya = sy[a], mxa = moved_x[a], mya = moved_y[a];
        real sum = 0;
        const int i = a - sim->wall_count;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
            const int b = nl->fluid_index[e];
            const real dx = nl->fluid_dx0[e] + (mxa - moved_x[b]), dy = nl->fluid_dy0[e] + (mya - moved_y[b]);
            const real r2 = dx * dx + dy * dy;
            if (r2 >= support2 || r2 == 0)
                continue;
            const real f = kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2));
            sum += pair_divergence(mass * inv_rho[b] * f, sxa - sx[b], sya - sy[b], dx, dy);
        }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
            const int b = nl->wall_index[e];
            const real dx = nl->wall_dx0[e] + (mxa - moved_x[b]), dy = nl->wall_dy0[e] + (mya - moved_y[b]);
            const real r2 = dx * dx + dy * dy;
            if (r2 >= support2)
                continue;
            const real f = kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2));
            sum += pair_divergence(mass * inv_rho[b] * f, sxa, sya, dx, dy);
        }
        sim->shift_div[a] = -sum;
    }
    #pragma omp barrier
}

void shifting_compute(surge_sim *sim, double dt_s)
{
    const int first = sim->wall_count, n = sim->count;
    #pragma omp for schedule(static)
    for (int a = first; a < n; a++) {
        double sx, sy;
        shift_displacement(sim, a, dt_s, &sx, &sy);
        sim->shift_x[a] = (real)sx;
        sim->shift_y[a] = (real)sy;
        sim->shift_div[a] = 0;
    }
    if (sim->params.shifting.form != SURGE_SHIFT_NONE && sim->params.shifting.consistent_density)
        shift_divergence(sim);
}
