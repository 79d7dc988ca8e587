/* The explicit scheme: weakly-compressible SPH (GMD 2025 Sect. 2), symplectic position-Verlet stepping with a
 * variable time step at the speed of sound (workshop paper eq. 5, 7), shifting and the boulders' coupling. */
#include <math.h>
#include <string.h>

#include "scheme/explicit/explicit.h"
#include "scheme/scheme.h"
#include "boulders/boulders.h"
#include "boulders/lubrication.h"
#include "boundaries/boundary.h"
#include "health.h"
#include "neighbours/neighbours.h"
#include "physics/interaction.h"
#include "physics/shifting.h"

/* dt = C_CFL min(dt_f, dt_cv, dt_nu)  (workshop paper eq. 7), from the largest acceleration squared and viscous
 * speed over the fluid (reduced in explicit_step's predictor region) */
static double variable_dt(const surge_sim *sim, double max_acc2, double max_visc_mps)
{
    const surge_params *p = &sim->params;
    if (p->numerics.dt_fixed_s > 0)
        return p->numerics.dt_fixed_s;
    const double h = sim->derived.h_m, c0 = sim->derived.c0_mps;
    double dt = h / (c0 + max_visc_mps);             /* dt_cv */
    if (max_acc2 > 0)
        dt = fmin(dt, sqrt(h / sqrt(max_acc2)));     /* dt_f */
    if (p->numerics.viscous_dt_limit && p->fluid.viscosity_m2ps > 0)
        dt = fmin(dt, h * h / p->fluid.viscosity_m2ps); /* dt_nu */
    return p->numerics.cfl * dt;
}

/* One force evaluation (the predictor's or the corrector's): displacements since the list build, the walls' mDBC
 * state, the fluid's rates and the fluid's forces on the discs, in one parallel region (waking the threads once, not
 * four times), then the reactions to the face repulsion on the discs. The phases split at the barriers that end
 * interaction_prepare's and boundary_update's loops: the master thread reads the clock as it leaves each (the records
 * and the pair loops are the interaction's, the walls' states the boundary's), and as it ends its share of the pair
 * loops (the discs' forces after it are the discs'). */
static void evaluate_rates(surge_sim *sim, int corrector)
{
    surge_phase_times *t = &sim->phase_times;
    const int discs = sim->boulders.count > 0;
    #pragma omp parallel
    {
        interaction_prepare(sim);
        #pragma omp master
        phase_end(sim, &t->interaction_s);
        boundary_update(sim);
        #pragma omp master
        phase_end(sim, &t->boundary_s);
        interaction_compute(sim, corrector);
        if (discs) { /* a thread done with its fluid takes up the discs' particles at once */
            #pragma omp master
            phase_end(sim, &t->interaction_s);
            boulders_fluid_forces(sim, NULL);
        }
    }
    if (discs) {
        boulders_take_face_reactions(sim);
        phase_end(sim, &t->discs_s);
    } else
        phase_end(sim, &t->interaction_s);
}

/* The step's end at t_n + dt: its time, step count and the walls' speeds, then the health check; a failed check takes
 * the state back to the step's start (-1) */
static int end_step(surge_sim *sim, double t_n, double dt)
{
    sim->time_s = t_n + dt;
    sim->dt_s = dt;
    sim->step++;
    boundary_wall_speeds(sim, sim->time_s);

    phase_begin(sim);
    const int healthy = health_check(sim);
    phase_end(sim, &sim->phase_times.update_s);
    if (healthy != 0) {
        fields_restore_step_start(sim);
        boulders_restore(sim);
        sim->time_s = t_n;
        sim->step--;
        boundary_wall_speeds(sim, t_n);
        return -1;
    }
    return 0;
}

static int explicit_step(surge_sim *sim)
{
    const int first = sim->wall_count, n = sim->count;
    const double t_n = sim->time_s;

    const int boulders = sim->boulders.count > 0;
    surge_phase_times *t = &sim->phase_times;
    const int lists = neighbours_update(sim);
    phase_end(sim, &t->neighbours_s);
    if (lists != 0) {
        sim->health = (surge_health){.check = SURGE_CHECK_OUT_OF_MEMORY, .particle_id = -1, .step = sim->step + 1,
                                     .time_s = t_n};
        snprintf(sim->health.message, sizeof sim->health.message, "out of memory for the neighbour lists");
        return -1;
    }
    boundary_wall_speeds(sim, t_n);
    phase_begin(sim);
    evaluate_rates(sim, 0);
    /* the time step from the predictor's rates, and the predictor's half step (workshop paper eq. 5a-b), in one
     * parallel region */
    double max_acc2 = 0, max_visc_mps = 0, dt = 0;
    #pragma omp parallel
    {
        #pragma omp for schedule(static) reduction(max : max_acc2, max_visc_mps)
        for (int a = first; a < n; a++) {
            const double acc2 = (double)sim->ax[a] * sim->ax[a] + (double)sim->ay[a] * sim->ay[a];
            max_acc2 = acc2 > max_acc2 ? acc2 : max_acc2;
            max_visc_mps = sim->visc_speed_mps[a] > max_visc_mps ? sim->visc_speed_mps[a] : max_visc_mps;
        }
        #pragma omp single
        dt = variable_dt(sim, max_acc2, max_visc_mps);
        const double half = 0.5 * dt;
        #pragma omp for schedule(static)
        for (int a = first; a < n; a++) {
            fields_save_step_start(sim, a);
            sim->rho[a] = (real)(sim->rho_n[a] + half * sim->drho[a]);
            sim->vx[a] = (real)(sim->vx_n[a] + half * sim->ax[a]);
            sim->vy[a] = (real)(sim->vy_n[a] + half * sim->ay[a]);
            sim->x[a] = sim->x_n[a] + half * sim->vx_n[a]; /* wrapped into the period at list builds */
            sim->y[a] = sim->y_n[a] + half * sim->vy_n[a];
        }
    }
    if (sim->step == 0 && sim->first_dt_s == 0)
        sim->first_dt_s = dt;
    const double half = 0.5 * dt;
    phase_end(sim, &t->update_s);

    if (boulders) {
        explicit_discs_predict(sim, half);
        phase_end(sim, &t->discs_s);
    }

    /* corrector: rates at the half step, full step from the start (eq. 5c-d and the density update) */
    boundary_wall_speeds(sim, t_n + half);
    phase_begin(sim);
    evaluate_rates(sim, 1);
    if (boulders && explicit_discs_correct(sim, dt) != 0) {
        sim->health = (surge_health){.check = SURGE_CHECK_OUT_OF_MEMORY, .particle_id = -1, .step = sim->step + 1,
                                     .time_s = t_n + dt};
        snprintf(sim->health.message, sizeof sim->health.message, "out of memory in the contact solver");
        fields_restore_step_start(sim);
        boulders_restore(sim);
        return -1;
    }
    const double face_reach_m = sim_contact_reach_m(sim);
    #pragma omp parallel
    {
        shifting_compute(sim, dt);
        #pragma omp for schedule(static)
        for (int a = first; a < n; a++) {
            double vx1 = sim->vx_n[a] + dt * sim->ax[a], vy1 = sim->vy_n[a] + dt * sim->ay[a];
            /* within reach of a wall face: no approach to it (a perfectly inelastic normal contact; docs/method.md);
             * a disc's face takes the reaction (explicit_discs_take_contact_reactions) */
            const double approach_mps = vx1 * sim->face_nx[a] + vy1 * sim->face_ny[a] - sim->face_vn_mps[a];
            const int contact = sim->face_gap_m[a] < face_reach_m && approach_mps < 0;
            if (contact) {
                vx1 -= approach_mps * sim->face_nx[a];
                vy1 -= approach_mps * sim->face_ny[a];
            }
            if (sim->face_disc[a] >= 0) { /* the repulsion's push is taken (fluid_forces.c): now the rule's */
                sim->face_push_x[a] = (real)(contact ? -approach_mps * sim->face_nx[a] / dt : 0.0);
                sim->face_push_y[a] = (real)(contact ? -approach_mps * sim->face_ny[a] / dt : 0.0);
            }
            /* eps = div(v) dt (+ div(dr) of the shift) */
            const double eps = -(double)sim->drho[a] / sim->rho[a] * dt + sim->shift_div[a];
            const double sx = sim->shift_x[a], sy = sim->shift_y[a];
            sim->vx[a] = (real)vx1;
            sim->vy[a] = (real)vy1;
            sim->rho[a] = (real)(sim->rho_n[a] * (2.0 - eps) / (2.0 + eps));
            sim->x[a] = sim->x_n[a] + half * (sim->vx_n[a] + (real)vx1) + sx;
            sim->y[a] = sim->y_n[a] + half * (sim->vy_n[a] + (real)vy1) + sy;
        }
    }
    if (boulders)
        explicit_discs_take_contact_reactions(sim, dt);
    phase_end(sim, &t->update_s);
    return end_step(sim, t_n, dt);
}


static double explicit_contact_reach_dp(const surge_params *p) { return p->walls.face_repulsion_reach_dp; }
static double explicit_neighbour_skin_h(const surge_params *p) { return p->numerics.neighbour_skin_h; }

/* The corrector evaluates the forces half a step ahead, and a step is at most C_CFL h / c0 */
static double explicit_lookahead_s(const surge_sim *sim)
{
    const surge_params *p = &sim->params;
    return 0.5 * (p->numerics.dt_fixed_s > 0 ? p->numerics.dt_fixed_s
                                             : p->numerics.cfl * sim->derived.h_m / sim->derived.c0_mps);
}

/* dt <= C_CFL min(h / c0, h^2 / nu) (workshop paper eq. 7, the viscous limit where numerics.viscous_dt_limit is set) */
static double explicit_step_bound_s(const surge_sim *sim, const surge_params *p)
{
    if (p->numerics.dt_fixed_s > 0)
        return p->numerics.dt_fixed_s;
    const double h = sim->derived.h_m;
    double dt = h / sim->derived.c0_mps;
    if (p->numerics.viscous_dt_limit && p->fluid.viscosity_m2ps > 0)
        dt = fmin(dt, h * h / p->fluid.viscosity_m2ps);
    return p->numerics.cfl * dt;
}

/* A disc settling onto the bed with the films off, C_h 1.8: a/dp 4 below 1 h, a/dp 8 above, where the box's walls
 * add least (docs/boulders.md, "What the SPH resolves of a squeeze film") */
static const lubrication_share explicit_film_share = {
    {0.000, 0.131, 0.235, 0.384, 0.507, 0.611, 0.692, 0.760, 0.801, 0.841, 0.873, 0.902, 0.928,
     0.947, 0.969, 0.988, 1.000, 1.000, 1.000, 1.000, 1.000, 1.000, 1.000, 1.000, 1.000}};

const time_scheme scheme_explicit = {
    .name = "explicit",
    .film_share = &explicit_film_share,
    .contact_reach_dp = explicit_contact_reach_dp,
    .neighbour_skin_h = explicit_neighbour_skin_h,
    .lookahead_s = explicit_lookahead_s,
    .step_bound_s = explicit_step_bound_s,
    .step = explicit_step,
    .check_report = explicit_check_report,
};
