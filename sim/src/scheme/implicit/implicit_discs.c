/* The implicit scheme's disc step, its accelerations from the fluid's forces after the fluid's step. */
#include "scheme/implicit/implicit.h"
#include "boulders/boulders.h"

/* The implicit scheme's disc step (docs/method.md, "Boulders in the implicit scheme"). The fluid forces come from a
 * fluid step that saw the discs at their velocity at the step's start, so the fluid's answer to a disc's change of
 * velocity lags a step. Its added mass m_a answers the last step's acceleration, m a_n+1 = F - m_a a_n, which grows
 * when m_a > m (a disc lighter than the fluid); its drag c answers the velocity, m a_n+1 = F* - c v_n, which
 * overshoots when c dt > 2 m (a step longer than the disc's drag time). The disc is stepped with
 * (m + m~ + k dt) a_n+1 = F + m g + m~ a_n: the same steady answer; the added mass's lag factor (m~ - m_a) / (m + m~),
 * below 1 in size for m_a < m + 2 m~; the drag as backward Euler, F(v_n+1) = F - k (v_n+1 - v_n), stable for
 * k > c / 2. m~ = added_mass rho0 pi r^2 of wetted disc; k, the drag with the fluid held still
 * (boulders_fluid_forces): 1.2-1.3 c at 5 particles a radius, more at finer ones (slower to settle, not unstable). */
int implicit_discs_advance(surge_sim *sim, double dt_s, double added_mass)
{
    boulder_set *b = &sim->boulders;
    double gx, gy;
    boulders_own_acceleration(sim, &gx, &gy);
    for (int i = 0; i < b->count; i++) {
        boulders_save_step_start(b, i);
        const double mass = b->mass[i];
        const double extra = added_mass * sim->rho0 * SURGE_PI * b->radius[i] * b->radius[i] * b->wetted[i];
        const double inertia = mass + extra + b->drag_stiffness[i] * dt_s;
        b->ax[i] = (b->fx[i] + mass * gx + extra * b->step_ax[i]) / inertia;
        b->ay[i] = (b->fy[i] + mass * gy + extra * b->step_ay[i]) / inertia;
        b->alpha[i] = b->torque[i] * b->inv_inertia[i] + b->spin_damping[i] * b->omega_forces[i];
    }
    if (boulders_advance_with_contacts(sim, dt_s) != 0)
        return -1;
    for (int i = 0; i < b->count; i++) {
        b->step_ax_n[i] = b->step_ax[i], b->step_ay_n[i] = b->step_ay[i];
        b->step_ax[i] = (b->vx[i] - b->vx_n[i]) / dt_s;
        b->step_ay[i] = (b->vy[i] - b->vy_n[i]) / dt_s;
    }
    return 0;
}

void implicit_discs_restore(surge_sim *sim)
{
    boulder_set *b = &sim->boulders;
    for (int i = 0; i < b->count; i++)
        b->step_ax[i] = b->step_ax_n[i], b->step_ay[i] = b->step_ay_n[i];
    boulders_restore(sim);
}
