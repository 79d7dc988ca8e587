/* The explicit scheme's disc step: the symplectic scheme's, the half-step force moving the discs over the full step
 * from its start, inside the contact solver's sub-steps. */
#include <math.h>

#include "scheme/explicit/explicit.h"
#include "boulders/boulders.h"

void explicit_discs_predict(surge_sim *sim, double half_dt_s)
{
    boulder_set *b = &sim->boulders;
    const double period = sim->grid.period_m;
    const double gx = sim->gx - sim->params.body.force_x_mps2, gy = sim->gy;
    const double force_x = sim->params.body.force_x_mps2 / sim->params.boulders.density_ratio;
    for (int i = 0; i < b->count; i++) {
        boulders_save_step_start(b, i);
        b->x[i] += half_dt_s * b->vx[i];
        if (period > 0)
            b->x[i] -= period * floor(b->x[i] / period);
        b->y[i] += half_dt_s * b->vy[i];
        b->angle[i] += half_dt_s * b->omega[i];
        b->vx[i] += half_dt_s * (b->fx[i] * b->inv_mass[i] + gx + force_x);
        b->vy[i] += half_dt_s * (b->fy[i] * b->inv_mass[i] + gy);
        /* the viscous torque's linear part in omega implicitly (spin_damping) */
        b->omega[i] = (b->omega[i] + half_dt_s * (b->torque[i] * b->inv_inertia[i] +
                                                   b->spin_damping[i] * b->omega_forces[i])) /
                      (1 + half_dt_s * b->spin_damping[i]);
    }
    boulders_place_particles(sim);
}

int explicit_discs_correct(surge_sim *sim, double dt_s)
{
    boulder_set *b = &sim->boulders;
    double gx, gy;
    boulders_own_acceleration(sim, &gx, &gy);
    for (int i = 0; i < b->count; i++) {
        boulders_restore_step_start(b, i);
        b->ax[i] = b->fx[i] * b->inv_mass[i] + gx;
        b->ay[i] = b->fy[i] * b->inv_mass[i] + gy;
        b->alpha[i] = b->torque[i] * b->inv_inertia[i] + b->spin_damping[i] * b->omega_forces[i];
    }
    return boulders_advance_with_contacts(sim, dt_s, 1);
}

/* The reaction of the contact rule (explicit_step.c) on a disc's face: each fluid particle it stopped approaching the
 * face gives the disc -m_a dv_a / m (face_push, dv_a / dt; radial, no torque), as in the implicit scheme
 * (implicit_discs.c). Summed in index order: the same whatever the thread count. The disc's particles then take the
 * disc's new velocity, as a restart places them (checkpoint.c), so that a restarted run repeats this one. */
void explicit_discs_take_contact_reactions(surge_sim *sim, double dt_s)
{
    boulder_set *b = &sim->boulders;
    int pushed = 0;
    for (int a = sim->wall_count; a < sim->count; a++)
        if (sim->face_disc[a] >= 0) {
            const int d = sim->face_disc[a];
            b->vx[d] -= dt_s * sim->mass * b->inv_mass[d] * sim->face_push_x[a];
            b->vy[d] -= dt_s * sim->mass * b->inv_mass[d] * sim->face_push_y[a];
            pushed = 1;
        }
    if (pushed)
        boulders_place_particles(sim);
}
