/* The implicit scheme's disc step: the coupled solves' velocities (disc_coupling.c) through the contact solver. */
#include "scheme/implicit/implicit.h"
#include "boulders/boulders.h"

/* The discs' step (docs/method.md, "Boulders in the implicit scheme"): each disc ends the fluid's step at the
 * velocity the coupled solves gave it, U_n+1, less the reaction of the contact rule's velocity changes of fluid
 * particles on its face (-m_a dv_a / m each; radial, no torque). The contact solver's sub-steps then take it from U_n
 * to there at the constant acceleration (U_n+1 - U_n) / dt, with their impulses; the viscous torque and the
 * lubrication films are in the solves (films.c), so the sub-steps damp no spin and add no film. */
int implicit_discs_advance(surge_sim *sim, double dt_s)
{
    implicit_work *w = implicit_of(sim);
    boulder_set *b = &sim->boulders;
    double *velocity = w->disc_velocity;
    for (int a = sim->wall_count; a < sim->count; a++) { /* in index order: the same sums whatever the thread count */
        if (sim->face_disc[a] >= 0) {
            const int d = sim->face_disc[a];
            velocity[3 * d] -= dt_s * sim->mass * b->inv_mass[d] * sim->face_push_x[a];
            velocity[3 * d + 1] -= dt_s * sim->mass * b->inv_mass[d] * sim->face_push_y[a];
        }
        if (w->other_face[a - sim->wall_count].disc >= 0) { /* and of a push off a second face, in a wedge */
            const int i = a - sim->wall_count, d = w->other_face[i].disc;
            velocity[3 * d] -= dt_s * sim->mass * b->inv_mass[d] * w->other_push_x[i];
            velocity[3 * d + 1] -= dt_s * sim->mass * b->inv_mass[d] * w->other_push_y[i];
        }
    }
    for (int d = 0; d < b->count; d++) {
        boulders_save_step_start(b, d);
        b->ax[d] = (velocity[3 * d] - b->vx[d]) / dt_s;
        b->ay[d] = (velocity[3 * d + 1] - b->vy[d]) / dt_s;
        b->alpha[d] = (velocity[3 * d + 2] / b->radius[d] - b->omega[d]) / dt_s;
        b->spin_damping[d] = 0;
    }
    return boulders_advance_with_contacts(sim, dt_s, 0);
}
