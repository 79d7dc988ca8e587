/* The implicit scheme's multigrid hierarchies: held over steps, rebuilt when they age or their solves slow. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"

/* Whether this step's pressure (or viscous) solves use the multigrid (implicit.preconditioner) */
int implicit_multigrid(const surge_sim *sim, bool viscous)
{
    return surge_implicit_uses_amg(&sim->params, sim->count - sim->wall_count, viscous);
}

/* The multigrid hierarchy of a system (which: MULTIGRID_VISCOUS or _PRESSURE; what names it) for this step's solves:
 * the held one while it is younger than implicit.multigrid_rebuild_steps and its solve has not slowed, else one
 * built on the sparse stand-in of assemble_sparse (its arguments after which); a health failure (with the reason)
 * when it cannot be built */
int implicit_multigrid_setup(surge_sim *sim, int which, const char *what, const double *diag, const real *fluid_coef,
                           double fluid_scale, const real *wall_coef, double wall_scale, int honour_fixed)
{
    implicit_work *w = implicit_of(sim);
    held_multigrid *m = &w->multigrid[which];
    char reason[160] = "";
    phase_end(sim, &sim->phase_times.assembly_s); /* what came before; from here the multigrid's phase */
    if (!m->amg)
        m->amg = amg_create(reason, sizeof reason, multigrid_blocks(which), sim->params.implicit.multigrid_parts);
    const int first = sim->wall_count, nf = sim->count - first;
    w->amg = m->amg;
    const int slowed = m->base_iterations >= 0 &&
                       m->last_iterations > m->base_iterations + (m->base_iterations / 2 > 2 ? m->base_iterations / 2 : 2);
    if (m->amg && amg_rows(m->amg) == nf && sim->step - m->built_step < sim->params.implicit.multigrid_rebuild_steps &&
        !slowed && amg_follow(m->amg, sim->id + first, nf) == 0) {
        phase_end(sim, &sim->phase_times.multigrid_s);
        return 0;
    }
    if (m->amg && implicit_assemble_sparse(sim, diag, fluid_coef, fluid_scale, wall_coef, wall_scale, honour_fixed) != 0)
        snprintf(reason, sizeof reason, "out of memory for the %s matrix's sparse stand-in", what);
    else if (m->amg && amg_setup(m->amg, nf, w->matrix_first, w->matrix_col, w->matrix_val, sim->id + first,
                                 sim->count) != 0)
        snprintf(reason, sizeof reason, "hypre could not build the multigrid hierarchy of the %s matrix", what);
    phase_end(sim, &sim->phase_times.multigrid_s);
    if (!reason[0]) {
        m->built_step = sim->step, m->base_iterations = -1;
        return 0;
    }
    sim->health = (surge_health){.check = SURGE_CHECK_SOLVER, .particle_id = -1, .step = sim->step + 1,
                                 .time_s = sim->time_s};
    snprintf(sim->health.message, sizeof sim->health.message, "health check failed: %s at step %lld, t = %.9g s (%s)",
             surge_health_check_name(SURGE_CHECK_SOLVER), (long long)sim->step + 1, sim->time_s, reason);
    return -1;
}

/* Records a solve's iterations with the hierarchy of which (the first after its build is its base) */
void implicit_multigrid_record(surge_sim *sim, int which, int iterations)
{
    held_multigrid *m = &implicit_of(sim)->multigrid[which];
    if (m->base_iterations < 0)
        m->base_iterations = iterations;
    m->last_iterations = iterations;
}

/* A solve of a pressure operator op (phi's, coupled to the discs or not, or psi's; linear, the walls' Neumann offsets
 * being on the right-hand side) from x = 0 or (from_guess) the guess in x, by the preconditioner the parameters
 * choose */
int implicit_pressure_solve(surge_sim *sim, affine_operator op, int from_guess, double tolerance, double *residual)
{
    const int nf = sim->count - sim->wall_count, max_iterations = sim->params.implicit.max_iterations;
    implicit_of(sim)->vcycle_blocks = implicit_of(sim)->vcycle_honours_fixed = implicit_of(sim)->pressure_by_multigrid;
    const int iterations = implicit_solve(sim, op, nf, from_guess ? LINEAR_FROM_GUESS : LINEAR_FROM_ZERO, tolerance,
                                          max_iterations, residual);
    implicit_of(sim)->vcycle_blocks = implicit_of(sim)->vcycle_honours_fixed = 0;
    return iterations;
}
