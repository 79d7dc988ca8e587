/* The implicit scheme (numerics.scheme = implicit): an incompressible projection with implicit viscosity for slow
 * viscous flows, whose time step follows the flow's own speed instead of the speed of sound (docs/method.md,
 * "The implicit scheme"). An incremental pressure-correction step (Goda 1979; Cummins & Rudman 1999 for SPH) from
 * t_n, everything evaluated at the step's start positions:
 *  1. v* = v_n + dt (g - grad p_n / rho0 + nu lap v*): backward-Euler viscosity with the last step's pressure (so a
 *     fluid at rest stays at rest), no-slip walls by their mDBC mirror 2 v_wall - v_ghost;
 *  2. -lap phi = -(rho0/dt) div v*, phi = 0 on free-surface particles and, at a wall particle, phi_w = phi_ghost
 *     with the wall's normal velocity in div v* (the Neumann condition that leaves no velocity through the wall);
 *     then, with the same operator, -lap psi = alpha rho0 (rho_k/rho0 - 1)/dt^2, the rest-density correction (the
 *     source after Asai et al. 2012), which moves the particles and not their velocities;
 *  3. v_n+1 = v* - dt grad phi / rho0, p_n+1 = p_n + phi, r_n+1 = r_n + dt v_n+1 - dt^2 grad psi / rho0 + the
 *     shift.
 * The pair coefficients of a step are computed once into arrays along the neighbour lists; the solves (BiCGSTAB,
 * matrix-free) then only gather, preconditioned by the diagonal or by a multigrid V-cycle on a sparse stand-in of
 * the operator (implicit.preconditioner). Every particle gathers in list order and every dot
 * product sums in fixed blocks, so the results do not depend on the thread count. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"
#include "scene/scales.h"
#include "boulders/boulders.h"
#include "boulders/lubrication.h"
#include "boundaries/boundary.h"
#include "health.h"
#include "neighbours/neighbours.h"
#include "physics/interaction.h"
#include "physics/shifting.h"

/* dt = min(cfl h / u_max, force_cfl sqrt(h / |g|)) from the velocities at the step's start */
static double implicit_dt(const surge_sim *sim)
{
    const surge_params *p = &sim->params;
    if (p->numerics.dt_fixed_s > 0)
        return p->numerics.dt_fixed_s;
    double max_v2 = 0;
    #pragma omp parallel for schedule(static) reduction(max : max_v2) if (wide(sim))
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double v2 = (double)sim->vx[a] * sim->vx[a] + (double)sim->vy[a] * sim->vy[a];
        max_v2 = v2 > max_v2 ? v2 : max_v2;
    }
    /* a disc's surface moves with it, but its spin moves no fluid where none is within a kernel of it (a dry disc
     * rolling on the belt ahead of the front; its touches are the contact solver's, which is implicit) */
    const boulder_set *b = &sim->boulders;
    const double h = sim->derived.h_m, g = sqrt(sim->gx * sim->gx + sim->gy * sim->gy);
    for (int i = 0; i < b->count; i++) {
        const double v = sqrt(b->vx[i] * b->vx[i] + b->vy[i] * b->vy[i]), surface = v + fabs(b->omega[i]) * b->radius[i];
        if (surface * surface > max_v2)
            max_v2 = boulders_fluid_within(sim, i, 2.0 * h) ? surface * surface : fmax(max_v2, v * v);
    }
    const double dt = surge_implicit_dt_s(p, h, g, sqrt(max_v2));
    if (isfinite(dt))
        return dt;
    /* no gravity and at rest: the walls' speeds set the scale */
    return p->implicit.cfl * h / fmax(fabs(p->walls.bottom_speed_mps) + fabs(p->walls.top_speed_mps), 1e-12);
}

static void fail_solve(surge_sim *sim, const char *what, int iterations, double residual, double t_n)
{
    sim->health = (surge_health){.check = SURGE_CHECK_SOLVER, .particle_id = -1, .step = sim->step + 1,
                                 .time_s = t_n, .value = residual};
    snprintf(sim->health.message, sizeof sim->health.message,
             "health check failed: %s at step %lld, t = %.9g s (the %s solve reached a relative residual of %.3g "
             "in %d iterations; implicit.max_iterations = %d, tolerance %g; try a smaller implicit.cfl)",
             surge_health_check_name(SURGE_CHECK_SOLVER), (long long)sim->step + 1, t_n, what, residual,
             iterations, sim->params.implicit.max_iterations,
             what[0] == 'v' ? sim->params.implicit.viscous_tolerance
             : what[0] == 'r' ? sim->params.implicit.density_tolerance : sim->params.implicit.pressure_tolerance);
}

/* Fluid particle i's per-lane partial sums of the velocity gradient G = -sum_b V_b f v_ab (x) r_ab and of its
 * Laplacian weights (lanes.h), added in lane order at the end */
typedef struct gradient_lanes {
    double xx[PAIR_LANES], xy[PAIR_LANES], yx[PAIR_LANES], yy[PAIR_LANES], w[PAIR_LANES];
} gradient_lanes;

/* The pairs of list entries from..to of a fluid particle with velocity (vxa, vya): its fluid list (neighbours at
 * sim->vx, vy) or (walls) its wall list (walls at wall_x, wall_y) */
static inline __attribute__((always_inline)) void gradient_pairs(const surge_sim *sim, double vxa, double vya,
                                                                 int64_t from, int64_t to, int walls, gradient_lanes *s)
{
    const implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int32_t *restrict index = walls ? nl->wall_index : nl->fluid_index;
    const real *restrict gx = walls ? w->wall_gx : w->fluid_gx, *restrict gy = walls ? w->wall_gy : w->fluid_gy;
    const real *restrict weight = walls ? w->wall_w : w->fluid_w;
    for (int64_t e0 = from; e0 < to; e0 += PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            const int b = index[e];
            const double dvx = vxa - (walls ? w->wall_x[b] : sim->vx[b]), dvy = vya - (walls ? w->wall_y[b] : sim->vy[b]);
            s->xx[l] -= dvx * gx[e], s->xy[l] -= dvx * gy[e];
            s->yx[l] -= dvy * gx[e], s->yy[l] -= dvy * gy[e];
            s->w[l] += weight[e];
        }
}

/* The step's start: its dt (`share` of the limits' when the step is taken again), the walls' velocities at its end (backward Euler; the discs' are unknowns of the solves),
 * the walls' normals and depths (the contact rule), the step's geometry, and the fluid's state saved for the
 * roll-back. The displacements since the list build (interaction_prepare) are the geometry's phase, up to the barrier
 * that ends their loop */
static double begin_step(surge_sim *sim, double share)
{
    surge_phase_times *t = &sim->phase_times;
    phase_begin(sim);
    const double dt = share * implicit_dt(sim);
    sim->dt_s = dt;
    if (sim->step == 0 && sim->first_dt_s == 0)
        sim->first_dt_s = dt;
    phase_end(sim, &t->update_s);
    boundary_wall_speeds(sim, sim->time_s + dt);
    phase_begin(sim);
    #pragma omp parallel
    {
        interaction_prepare(sim);
        #pragma omp master
        phase_end(sim, &t->geometry_s);
        boundary_update(sim);
    }
    phase_end(sim, &t->boundary_s);
    implicit_geometry(sim);
    implicit_assemble_pressure(sim); /* the pressure's operator, for the relaxation of p_n and the projection */
    phase_end(sim, &t->assembly_s);
    implicit_mirror_velocities(sim);
    phase_end(sim, &t->boundary_s);
    if (sim->boulders.count > 0) {
        implicit_discs_prepare(sim);
        phase_end(sim, &t->disc_coupling_s);
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = sim->wall_count; a < sim->count; a++)
        fields_save_step_start(sim, a);
    phase_end(sim, &t->update_s);
    return dt;
}

/* Step 1's system: the right-hand side v_n + dt (g - grad p / rho0), p the last step's pressure p_n on the step's first
 * pass (w->pressure_n as the last pass left it on the others), the first guess v_n plus the last change (a slow
 * flow's is much the same from step to step) and the diagonal 1 + dt nu sum_b w_ab */
static void viscous_system(surge_sim *sim, double dt, int first_pass)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int first = sim->wall_count, nf = sim->count - first;
    const double rho0 = sim->rho0, dt_nu = dt * sim->params.fluid.viscosity_m2ps;
    const double *by_id = w->pressure_by_id;
    if (first_pass) {
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < nf; i++)
            w->pressure_n[i] = w->fixed[i] ? 0.0 : by_id[sim->id[first + i]];
    }
    /* the walls' p: the fluid's at the ghost node continued by the body force's hydrostatic gradient rho0 g */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < first; kw++)
        w->neumann_pa[kw] = -rho0 * (sim->gx * sim->ghost_dx[kw] + sim->gy * sim->ghost_dy[kw]);
    const double relaxation = sim->params.implicit.pressure_relaxation;
    if (w->any_imaged && relaxation > 0)
        implicit_relax_pressure(sim, w->pressure_n, w->neumann_pa, relaxation);
    implicit_wall_pressures(sim, w->pressure_n, w->neumann_pa);
    implicit_pressure_gradient(sim, w->pressure_n);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        double lane_w[PAIR_LANES] = {0}; /* per-lane partial sums (lanes.h) */
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++)
                lane_w[l] += w->fluid_w[e + l];
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++)
                lane_w[l] += w->wall_w[e + l];
        const double sum_w = lanes_total(lane_w);
        w->rhs[i] = sim->vx_n[a] + dt * (sim->gx - w->grad_x[i] / rho0);
        w->rhs[nf + i] = sim->vy_n[a] + dt * (sim->gy - w->grad_y[i] / rho0);
        w->x[i] = sim->vx_n[a] + w->dvx_by_id[sim->id[a]], w->x[nf + i] = sim->vy_n[a] + w->dvy_by_id[sim->id[a]];
        w->diag[i] = w->diag[nf + i] = 1.0 + dt_nu * sum_w;
    }
    phase_end(sim, &sim->phase_times.assembly_s);
    if (sim->boulders.count > 0) { /* p_n's walls are still in w->wall_x */
        implicit_discs_viscous_system(sim, dt);
        phase_end(sim, &sim->phase_times.disc_coupling_s);
    }
}

/* 1. v* = v_n + dt (g - grad p_n / rho0 + nu lap v*): backward-Euler viscosity with the last step's pressure, into
 * the fluid's velocities, the discs' velocities solved with them (disc_coupling.c) into w->disc_velocity; -1 with the
 * health set when the solve fails */
static int viscous_predict(surge_sim *sim, double dt, int first_pass)
{
    implicit_work *w = implicit_of(sim);
    const surge_params *prm = &sim->params;
    const int first = sim->wall_count, nf = sim->count - first, n = 2 * nf + w->disc_rows;
    const double dt_nu = dt * prm->fluid.viscosity_m2ps;
    viscous_system(sim, dt, first_pass);
    if (w->film_blocks.singular) { /* not expected: each block is its diagonal plus dt M^-1 K, K >= 0 in the normal */
        sim->health = (surge_health){.check = SURGE_CHECK_SOLVER, .particle_id = -1, .step = sim->step + 1,
                                     .time_s = sim->time_s};
        snprintf(sim->health.message, sizeof sim->health.message,
                 "health check failed: %s at step %lld, t = %.9g s (LAPACK found the rows of discs joined by "
                 "lubrication films singular; contacts.lubrication = false runs without them)",
                 surge_health_check_name(SURGE_CHECK_SOLVER), (long long)sim->step + 1, sim->time_s);
        return -1;
    }
    if (dt_nu > 0) {
        /* by multigrid: one hierarchy for both components (the walls mirror each component on its own) */
        const int by_multigrid = implicit_multigrid(sim, true);
        if (by_multigrid &&
            implicit_multigrid_setup(sim, MULTIGRID_VISCOUS, "viscous", w->diag, w->fluid_w, -dt_nu, w->wall_w, dt_nu, 0)) {
            w->viscous_iterations = -2, w->viscous_residual = 0;
            return -1;
        }
        phase_end(sim, &sim->phase_times.assembly_s);
        double residual = 0;
        w->vcycle_blocks = by_multigrid ? 2 : 0;
        const affine_operator op = w->disc_rows > 0 ? implicit_coupled_viscous_operator : implicit_viscous_operator;
        const int iterations = implicit_solve(sim, op, n, AFFINE, prm->implicit.viscous_tolerance,
                                              prm->implicit.max_iterations, &residual);
        w->vcycle_blocks = 0;
        if (by_multigrid && first_pass) /* the hierarchy's rebuild rule reads the step's first solve */
            implicit_multigrid_record(sim, MULTIGRID_VISCOUS, iterations);
        w->viscous_iterations = iterations, w->viscous_residual = residual;
        if (iterations < 0) {
            fail_solve(sim, "viscous", prm->implicit.max_iterations, residual, sim->time_s);
            return -1;
        }
    } else { /* no viscosity: the operator is the identity */
        memcpy(w->x, w->rhs, (size_t)n * sizeof *w->x);
        w->viscous_iterations = 0, w->viscous_residual = 0;
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        sim->vx[a] = (real)w->x[i], sim->vy[a] = (real)w->x[nf + i];
        w->dvx_by_id[sim->id[a]] = w->x[i] - sim->vx_n[a], w->dvy_by_id[sim->id[a]] = w->x[nf + i] - sim->vy_n[a];
    }
    phase_end(sim, &sim->phase_times.viscous_solve_s);
    if (w->disc_rows > 0) {
        memcpy(w->disc_velocity, w->x + 2 * nf, (size_t)w->disc_rows * sizeof *w->x);
        implicit_discs_mirror(sim, w->disc_velocity);
        phase_end(sim, &sim->phase_times.disc_coupling_s);
    }
    return 0;
}

/* Step 2's wall conditions: each wall's mirrored velocity for div v* and its Neumann offset on phi */
static void wall_neumann_offsets(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const double rho0 = sim->rho0, offset_weight = sim->params.implicit.wall_neumann_offset;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        /* the wall's own velocity: only its normal part matters, and the belt-wall corner's (mirrored through the
         * corner point, its normal slanted) is the fixed upstream wall's, not the belt's */
        const double wall_vx = w->mirror_vx[kw], wall_vy = w->mirror_vy[kw];
        double gvx = wall_vx, gvy = wall_vy;
        if (!w->dry[kw])
            ghost_velocity(sim, kw, &gvx, &gvy);
        /* a wall whose ghost node lies inside the fluid: the wall's phi is the ghost's plus the inhomogeneous
         * Neumann offset, so that -(dt/rho0) dphi/dn takes the normal velocity at the wall's face away, that at the
         * ghost less half the ghost's distance times its normal strain (the first-order interpolation's gradient:
         * a flow that turns at the wall has none to take away, a column moving into it all of its own), and
         * continuity sees the normal velocity continued linearly through the face, (v_g - v_w).n - |g| strain;
         * where the free surface or a contact line cuts the ghost's kernel (its velocity extrapolated from a few
         * particles), and by default everywhere (implicit.wall_neumann_offset 0): the wall's own normal velocity in
         * the divergence, no offset; in between by the immersion (docs/method.md, "Walls": without the offset the
         * first column against a wall sits compressed and below the bulk's pressure) */
        const double immersed = offset_weight * w->immersion[kw];
        const double glen2 = (double)sim->ghost_dx[kw] * sim->ghost_dx[kw] + (double)sim->ghost_dy[kw] * sim->ghost_dy[kw];
        const double into = ((gvx - wall_vx) * sim->ghost_dx[kw] + (gvy - wall_vy) * sim->ghost_dy[kw]) / glen2;
        const double strain = immersed > 0 ? ghost_normal_strain(sim, kw) : 0.0;
        w->wall_x[kw] = gvx - ((1.0 - immersed) * into + immersed * strain) * sim->ghost_dx[kw];
        w->wall_y[kw] = gvy - ((1.0 - immersed) * into + immersed * strain) * sim->ghost_dy[kw];
        w->neumann_pa[kw] = -immersed * rho0 / dt * (into - 0.5 * strain) * glen2;
    }
}

/* div v* = tr(G M^-1) at fluid particle i, G from the fluid's velocities and the walls' mirrored ones (w->wall_x,
 * wall_y), with the images beyond the free surface where its kernel reaches it; its Laplacian weights' sum into
 * sum_w */
static double velocity_divergence(const surge_sim *sim, int i, double *sum_w)
{
    const implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int a = sim->wall_count + i;
    const double vxa = sim->vx[a], vya = sim->vy[a];
    gradient_lanes lanes;
    memset(&lanes, 0, sizeof lanes);
    gradient_pairs(sim, vxa, vya, nl->fluid_first[i], nl->fluid_first[i + 1], 0, &lanes);
    gradient_pairs(sim, vxa, vya, nl->wall_first[i], nl->wall_first[i + 1], 1, &lanes);
    double g[4] = {lanes_total(lanes.xx), lanes_total(lanes.xy), lanes_total(lanes.yx), lanes_total(lanes.yy)};
    *sum_w = lanes_total(lanes.w);
    if (w->imaged[i]) /* a full kernel with the images beyond the free surface */
        implicit_image_velocity_gradient(sim, i, g);
    return g[0] * w->minv_xx[i] + (g[1] + g[2]) * w->minv_xy[i] + g[3] * w->minv_yy[i];
}

/* The kernel sum the rest-density correction holds the fluid to, over the lattice's: 1 where a free surface takes up
 * a change of volume; in a closed domain (a channel between plates) the mean over the particles whose kernel sees no
 * disc. There the fluid's volume is fixed, and once the shift has let it into the room a placement leaves around the
 * discs the bulk reads some tenths of a per cent short of the lattice everywhere, which no displacement can mend:
 * held to 1, that shortfall, counted in the bulk but not next to a disc (projection_sources), raised psi over every
 * disc and drove the fluid off it, 0.5-2 dp a step along a plate out of the wedge under a disc placed 0.8 dp from it
 * in the loaded channel (r/dp 6), until the emptied wedge read as a free surface and the run stopped on a particle
 * at 0.897 rho0 (docs/method.md, "Closed domains"). Where the fluid is packed around the discs
 * (boulders.pack_fluid) the mean over every particle: their kernel sums next to a disc read as the bulk's. A serial
 * sum: the same at any thread count */
static double rest_kernel_ratio(const surge_sim *sim, int free_surface)
{
    const implicit_work *w = implicit_of(sim);
    const int nf = sim->count - sim->wall_count;
    if (free_surface)
        return 1.0;
    double sum = 0;
    int counted = 0;
    const int packed = sim->params.boulders.pack_fluid;
    for (int i = 0; i < nf; i++)
        if (packed || !w->near_disc[i])
            sum += w->kernel_ratio[i], counted++;
    return counted > 0 ? sum / counted : 1.0;
}

/* Step 2's sources: -(rho0/dt) div v* for phi and the rest-density source for psi (the spacing read against
 * rest_ratio), the diagonal and phi's first guess (the last step's: a steady flow's is much the same from step to
 * step) */
static void projection_sources(surge_sim *sim, double dt, double rest_ratio)
{
    implicit_work *w = implicit_of(sim);
    const int first = sim->wall_count, nf = sim->count - first;
    const double rho0 = sim->rho0, alpha = sim->params.implicit.density_correction;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        double sum_w;
        const double div_v = w->divergence[i] = velocity_divergence(sim, i, &sum_w);
        /* near the surface the kernel sum is truncated: it is read against a flat surface's at the particle's depth;
         * where that cannot be read (a partly dry wall in reach), a deficit is not an expansion and only an excess
         * counts (clumped particles, which nothing else pushes apart where the pressure is near 0). So next to a
         * disc, where the placement's cut leaves gaps (the default); where the fluid is packed around the discs
         * (boulders.pack_fluid) both: there its kernel sums scatter about the bulk's (0.986 +- 0.009 at phi 0.5,
         * r/dp 4), and an excess alone, a source of one sign, pushed the fluid off the discs into the wedge under
         * one 0.2 dp above a plate until a particle there read 1.137 rho0 (phi 0.3, r/dp 4, step 4) */
        const double compression = w->near_disc[i] && !sim->params.boulders.pack_fluid
                                       ? fmax(0.0, w->kernel_ratio[i] / rest_ratio - 1.0)
                                   : !sim->near_surface[a] ? w->kernel_ratio[i] / rest_ratio - 1.0
                                   : w->expected_ratio[i] > 0 ? w->kernel_ratio[i] / w->expected_ratio[i] - 1.0
                                   : fmax(0.0, w->kernel_ratio[i] - 1.0);
        w->density_rhs[i] = w->fixed[i] ? 0.0 : alpha * rho0 * compression / (dt * dt);
        w->rhs[i] = w->fixed[i] ? 0.0 : -rho0 / dt * div_v;
        w->diag[i] = w->fixed[i] || sum_w <= 0 ? 1.0 : sum_w;
        w->x[i] = w->fixed[i] ? 0.0 : w->phi_by_id[sim->id[a]];
    }
}

/* 2. The correction phi: -lap phi = -(rho0/dt) div v*, the discs' velocities moved by phi's force within the solve
 * (disc_coupling.c), into w->x and phi_by_id; -1 with the health set when the multigrid cannot be built or the solve
 * fails */
static int project(surge_sim *sim, double dt, int first_pass)
{
    implicit_work *w = implicit_of(sim);
    const surge_params *prm = &sim->params;
    const int first = sim->wall_count, nf = sim->count - first;
    surge_phase_times *t = &sim->phase_times;
    wall_neumann_offsets(sim, dt);
    phase_end(sim, &t->boundary_s);
    /* without a free surface (a closed channel) the pressure is fixed only up to a constant: the singular matrix
     * defeats the multigrid's coarsest level, and the matrix-free solve takes it (docs/method.md) */
    int free_surface = w->any_imaged;
    for (int i = 0; i < nf && !free_surface; i++)
        free_surface = w->fixed[i];
    w->free_surface = free_surface;
    projection_sources(sim, dt, rest_kernel_ratio(sim, free_surface));
    /* ... and, with a disc, need not be consistent either: the ghosts' normal velocities over a disc need not sum to
     * zero. There the fluid takes the explicit scheme's compressibility, -lap phi + phi/(c0 dt)^2 (the Tait equation
     * of state linearised, p = c0^2 (rho - rho0)): a source the incompressible equation cannot meet becomes a
     * uniform pressure instead of a solve that does not converge (docs/method.md, "Closed domains") */
    const double closed_kappa = free_surface ? 0.0 : 1.0 / (sim->derived.c0_mps * sim->derived.c0_mps * dt * dt);
    if (!free_surface) /* the operator's diagonal once a step (the passes share it), the preconditioner's each pass */
        for (int i = 0; i < nf; i++)
            w->pressure_diag[i] += first_pass ? closed_kappa : 0.0, w->diag[i] += closed_kappa;
    w->pressure_by_multigrid = implicit_multigrid(sim, false) && free_surface;
    if (w->pressure_by_multigrid &&
        implicit_multigrid_setup(sim, MULTIGRID_PRESSURE, "pressure", w->pressure_diag, w->fluid_pc, 1.0, w->wall_pc, 1.0, 1))
        return -1;
    if (prm->implicit.wall_neumann_offset > 0)
        implicit_wall_offsets_to_rhs(sim, w->neumann_pa);
    phase_end(sim, &t->assembly_s);
    double residual = 0;
    const affine_operator op = w->disc_rows > 0 ? implicit_coupled_pressure_operator : implicit_pressure_operator;
    const int iterations = implicit_pressure_solve(sim, op, 1, prm->implicit.pressure_tolerance, &residual);
    if (w->pressure_by_multigrid && first_pass)
        implicit_multigrid_record(sim, MULTIGRID_PRESSURE, iterations);
    w->pressure_iterations = iterations, w->pressure_residual = residual;
    if (iterations < 0) {
        fail_solve(sim, "pressure", prm->implicit.max_iterations, residual, sim->time_s);
        return -1;
    }
    if (!free_surface) { /* the uniform part is no flow: the fluid's mean pressure keeps its start value */
        const double mean = implicit_dot(w, w->x, NULL, nf) / nf;
        for (int i = 0; i < nf; i++)
            w->x[i] -= mean;
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++)
        w->phi_by_id[sim->id[first + i]] = w->x[i];
    phase_end(sim, &t->pressure_solve_s);
    if (w->disc_rows > 0) {
        implicit_discs_pressure_answer(sim, dt);
        phase_end(sim, &t->disc_coupling_s);
    }
    return 0;
}

/* The rest-density correction's displacement -dt^2 grad psi / rho0, plus a shift where the kernel sum says
 * compressed, -2 w (rho_k/rho0 - 1) h^2 grad C with grad C = sum_b V_b grad W_ab (walls by their wetness): zero on a
 * regular lattice and where the spacing is at rest or wider, it pushes apart particles that have closed on each
 * other, also on the free surface, where psi is 0 (docs/method.md) */
static void density_displacements(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    const double rho0 = sim->rho0, h = sim->derived.h_m, anti_clumping = sim->params.implicit.anti_clumping;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const double compression = fmax(0.0, w->kernel_ratio[i] - 1.0);
        double sx = 0, sy = 0;
        if (compression > 0) {
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
                sx += w->fluid_gx[e], sy += w->fluid_gy[e];
            for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
                const double wet = w->wetness[nl->wall_index[e]];
                sx += wet * w->wall_gx[e], sy += wet * w->wall_gy[e];
            }
        }
        const double shift = 2.0 * anti_clumping * compression * h * h;
        w->density_dx[i] = -dt * dt / rho0 * w->grad_x[i] - shift * sx;
        w->density_dy[i] = -dt * dt / rho0 * w->grad_y[i] - shift * sy;
    }
}

/* 2b. The rest-density correction psi, -lap psi = alpha rho0 (rho_k/rho0 - 1)/dt^2 with the same operator, moves
 * the particles by -dt^2 grad psi / rho0 and leaves their velocities alone: a spacing error is not a flow, and in one
 * equation with the divergence its kicks were 0.34 u_max in Poiseuille's start-up (docs/method.md). phi stays in
 * w->x; -1 with the health set when the solve fails */
static int rest_density(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const surge_params *prm = &sim->params;
    const int first = sim->wall_count, nf = sim->count - first;
    if (!(prm->implicit.density_correction > 0)) {
        memset(w->density_dx, 0, (size_t)nf * sizeof *w->density_dx);
        memset(w->density_dy, 0, (size_t)nf * sizeof *w->density_dy);
        return 0;
    }
    memcpy(w->phi_saved, w->x, (size_t)nf * sizeof *w->x);
    memcpy(w->rhs, w->density_rhs, (size_t)nf * sizeof *w->x);
    /* from the last step's psi: a spacing error the last step left is corrected again */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++)
        w->x[i] = w->fixed[i] ? 0.0 : w->psi_by_id[sim->id[first + i]];
    double residual = 0;
    const int iterations = implicit_pressure_solve(sim, implicit_pressure_operator, 1, prm->implicit.density_tolerance,
                                                   &residual);
    if (iterations < 0) {
        fail_solve(sim, "rest-density", prm->implicit.max_iterations, residual, sim->time_s);
        return -1;
    }
    w->pressure_iterations += iterations;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++)
        w->psi_by_id[sim->id[first + i]] = w->x[i];
    implicit_wall_pressures(sim, w->x, NULL);
    implicit_pressure_gradient(sim, w->x);
    density_displacements(sim, dt);
    memcpy(w->x, w->phi_saved, (size_t)nf * sizeof *w->x);
    return 0;
}

/* With discs, between passes of the viscous and pressure solves, the update p <- p + phi - rho0 nu (div v* - div v_n+1)
 * (Uzawa's iteration on the step's coupled velocity-pressure system, preconditioned as Cahouet and Chabard's: the
 * Laplacian's inverse for the inertia, rho0 nu for the viscosity; the rotational update of Timmermans et al. 1996). The incremental
 * step alone builds the pressure a disc's stresslet needs by about 1/(dt nu k^2) of it a step, k the disc's scale
 * (docs/method.md, "Boulders in the implicit scheme"). The divergence taken is the part the projection removes,
 * div v* - div(v* - dt grad phi / rho0): the rest, which alternates from particle to particle and which no pressure's
 * gradient meets, would add to p at every pass (over-relaxed by 1.5, the update set the debris surge's thin films
 * between discs and the belt jetting). Particles whose kernel reaches the free surface take none: there the iteration
 * diverged next to a disc at the surge's front by the belt (1.1-1.2 times a pass, a jet within 0.1 s), and their
 * pressure is held by the surface's images. Into w->divergence; its root mean square (Pa) */
static double disc_pressure_update(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const int first = sim->wall_count, nf = sim->count - first;
    const double rho0 = sim->rho0, mu = rho0 * sim->params.fluid.viscosity_m2ps;
    double *v_star = w->rhs, *removed = w->divergence; /* the projection's sources are spent */
    implicit_wall_pressures(sim, w->x, w->neumann_pa);
    implicit_pressure_gradient(sim, w->x);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        v_star[i] = sim->vx[a], v_star[nf + i] = sim->vy[a];
        sim->vx[a] = (real)(sim->vx[a] - dt / rho0 * w->grad_x[i]);
        sim->vy[a] = (real)(sim->vy[a] - dt / rho0 * w->grad_y[i]);
    }
    wall_neumann_offsets(sim, dt); /* the walls' mirrors of v_n+1, the discs' at their corrected velocities */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        double sum_w;
        removed[i] -= velocity_divergence(sim, i, &sum_w);
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++)
        sim->vx[first + i] = (real)v_star[i], sim->vy[first + i] = (real)v_star[nf + i];
    /* without a free surface the pressure is fixed up to a constant: the update's mean is removed, as phi's */
    double mean = 0;
    if (!w->free_surface) {
        for (int i = 0; i < nf; i++)
            mean += w->x[i] - mu * removed[i];
        mean /= nf;
    }
    double update2 = 0;
    for (int i = 0; i < nf; i++) { /* in index order: the same sum whatever the thread count */
        removed[i] = w->fixed[i] || sim->near_surface[first + i] ? 0.0 : w->x[i] - mu * removed[i] - mean;
        update2 += removed[i] * removed[i];
    }
    return sqrt(update2 / nf);
}

/* The update disc_pressure_update left in w->divergence, into the pressure */
static void disc_pressure_apply(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++)
        w->pressure_n[i] += w->divergence[i];
}

/* 3. v_n+1 = v* - dt grad phi / rho0 (into w->x), p_n+1 = p_n + phi, the walls' pressure for the outputs */
static void correct_velocities(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const int first = sim->wall_count, nf = sim->count - first;
    const double rho0 = sim->rho0;
    double *by_id = w->pressure_by_id;
    implicit_wall_pressures(sim, w->x, w->neumann_pa);
    implicit_pressure_gradient(sim, w->x);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        const double p_new = w->fixed[i] ? 0.0 : w->pressure_n[i] + w->x[i];
        by_id[sim->id[a]] = p_new;
        sim->pressure[a] = (real)p_new;
        w->pressure_n[i] = p_new;
        w->x[i] = sim->vx[a] - dt / rho0 * w->grad_x[i];
        w->x[nf + i] = sim->vy[a] - dt / rho0 * w->grad_y[i];
        /* the density the spacing says (an output and the health check's; the scheme holds rho0): in the bulk the
         * kernel sum's; near the surface or a disc, where the sum is truncated, only an excess over the lattice's
         * full sum (a void's border closing while on the free surface reads up to 1.17; docs/method.md) */
        sim->rho[a] = (real)(sim->near_surface[a] || w->near_disc[i] ? rho0 * fmax(1.0, w->kernel_ratio[i])
                                                                     : rho0 * w->kernel_ratio[i]);
    }
    /* the walls' pressure for the outputs: p_n+1 continued hydrostatically, as the next step takes it */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < first; kw++)
        sim->pressure[kw] = (real)(w->dry[kw] ? 0.0 : ghost_value(sim, kw, w->pressure_n) -
                                   rho0 * (sim->gx * sim->ghost_dx[kw] + sim->gy * sim->ghost_dy[kw]));
}

/* The least change (lambda_1 n_1 + lambda_2 n_2, lambdas >= 0) that brings the velocity (vx, vy) into n_1.v >= c_1
 * and n_2.v >= c_2, the unit normals of two faces (a projection onto two half-planes). Returns the multipliers; faces
 * nearly back to back take the first face's projection alone. */
static void keep_off_two_faces(double *vx, double *vy, double n1x, double n1y, double c1, double n2x, double n2y,
                               double c2, double *lambda1, double *lambda2)
{
    const double r1 = c1 - (n1x * *vx + n1y * *vy), r2 = c2 - (n2x * *vx + n2y * *vy), g = n1x * n2x + n1y * n2y;
    double l1 = 0, l2 = 0;
    if (r1 > 0 && r2 - r1 * g <= 0)
        l1 = r1;
    else if (r2 > 0 && r1 - r2 * g <= 0)
        l2 = r2;
    else if (r1 > 0 || r2 > 0) {
        const double det = 1 - g * g;
        if (det > 1e-3)
            l1 = fmax(0.0, (r1 - g * r2) / det), l2 = fmax(0.0, (r2 - g * r1) / det);
        else
            l1 = fmax(0.0, r1);
    }
    *vx += l1 * n1x + l2 * n2x, *vy += l1 * n1y + l2 * n2y;
    *lambda1 = l1, *lambda2 = l2;
}

/* The contact rule on velocities: within reach of a wall face, no approach to it (the explicit scheme's contact rule;
 * docs/method.md); a disc takes the reaction. The fluid's velocities become v_n+1 */
static void contact_velocities(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const int first = sim->wall_count, nf = sim->count - first;
    /* a particle the contact rule on positions left at the reach is in contact: its gap, read back in single
     * precision, may come out a rounding either side of the reach */
    const double contact_m = sim_contact_reach_m(sim) + CONTACT_ROUNDING_DP * sim->params.numerics.dp_m;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        double vx1 = w->x[i], vy1 = w->x[nf + i];
        const double approach_mps = vx1 * sim->face_nx[a] + vy1 * sim->face_ny[a] - sim->face_vn_mps[a];
        const int contact = sim->face_gap_m[a] < contact_m && approach_mps < 0;
        const wall_face *other = &w->other_face[i];
        const double other_approach_mps = vx1 * other->nx + vy1 * other->ny - other->vn_mps;
        if (other->gap_m < contact_m && other_approach_mps - (contact ? approach_mps * (other->nx * sim->face_nx[a] +
                                                              other->ny * sim->face_ny[a]) : 0.0) < 0) {
            /* in a wedge, within reach of two faces: no approach to either. The solids take the particle's change of
             * momentum, l_nearest n_nearest + l_other n_other, each its own push less the part the two have in common,
             * and that part, common (n_nearest + n_other), half each. That part squeezes the particle between the
             * faces: between faces nearly back to back its multipliers grow as 1/(1 - cos^2) while their sum stays
             * small, and given to each solid whole it kicked two discs 0.9 dp apart apart at 0.06-0.19 m/s in one step
             * (loaded channel, r/dp 3, phi 0.5), a force no fluid carries: the pressure solve carries the gap's */
            double l_nearest, l_other;
            keep_off_two_faces(&vx1, &vy1, sim->face_nx[a], sim->face_ny[a],
                               sim->face_gap_m[a] < contact_m ? sim->face_vn_mps[a] : -INFINITY, other->nx, other->ny,
                               other->vn_mps, &l_nearest, &l_other);
            const double common = fmin(l_nearest, l_other);
            const double shared_x = 0.5 * common * (sim->face_nx[a] + other->nx);
            const double shared_y = 0.5 * common * (sim->face_ny[a] + other->ny);
            sim->face_push_x[a] = (real)(((l_nearest - common) * sim->face_nx[a] + shared_x) / dt);
            sim->face_push_y[a] = (real)(((l_nearest - common) * sim->face_ny[a] + shared_y) / dt);
            w->other_push_x[i] = (real)(((l_other - common) * other->nx + shared_x) / dt);
            w->other_push_y[i] = (real)(((l_other - common) * other->ny + shared_y) / dt);
        } else {
            w->other_push_x[i] = 0, w->other_push_y[i] = 0;
            if (contact)
                vx1 -= approach_mps * sim->face_nx[a], vy1 -= approach_mps * sim->face_ny[a];
            sim->face_push_x[a] = (real)(contact ? -approach_mps * sim->face_nx[a] / dt : 0.0);
            sim->face_push_y[a] = (real)(contact ? -approach_mps * sim->face_ny[a] / dt : 0.0);
        }
        sim->vx[a] = (real)vx1, sim->vy[a] = (real)vy1;
    }
}

/* r_n+1 = r_n + dt v_n+1 + the rest-density, close-pair and shifting displacements, with the contact rule on
 * positions: a step that would end closer to the nearest wall face than its reach ends at the reach (the explicit
 * scheme's face repulsion acts over many small steps; one large step needs the constraint itself; docs/method.md) */
static void move_particles(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const int first = sim->wall_count, n = sim->count, nf = n - first;
    if (sim->params.implicit.pair_distance_dp > 0)
        implicit_part_close_pairs(sim);
    else {
        memset(w->pair_dx, 0, (size_t)nf * sizeof *w->pair_dx);
        memset(w->pair_dy, 0, (size_t)nf * sizeof *w->pair_dy);
    }
    #pragma omp parallel
    shifting_compute(sim, dt);
    /* Lind's shift is a displacement a step (shifting.c); in the free-surface layer, below the scheme's own step at
     * rest, it is taken in proportion, so that a shorter step does not shift the surface more in a second (at 1 ms,
     * a twentieth of the still tank's own step, the full shift each step set its surface rippling; docs/method.md,
     * "The shift under the surface") */
    const double rest_step_s = surge_implicit_dt_s(&sim->params, sim->derived.h_m, sqrt(sim->gx * sim->gx + sim->gy * sim->gy), 0.0);
    const double shift_share = isfinite(rest_step_s) ? fmin(1.0, dt / rest_step_s) : 1.0;
    const double face_reach_m = sim_contact_reach_m(sim), dp = sim->params.numerics.dp_m;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = first; a < n; a++) {
        if (sim->near_surface[a])
            sim->shift_x[a] *= (real)shift_share, sim->shift_y[a] *= (real)shift_share;
        double dx = dt * sim->vx[a] + sim->shift_x[a] + w->density_dx[a - first] + w->pair_dx[a - first];
        double dy = dt * sim->vy[a] + sim->shift_y[a] + w->density_dy[a - first] + w->pair_dy[a - first];
        const double gap_after = sim->face_gap_m[a] + dx * sim->face_nx[a] + dy * sim->face_ny[a] -
                                 dt * sim->face_vn_mps[a];
        const wall_face *other = &w->other_face[a - first];
        const double other_after = other->gap_m + dx * other->nx + dy * other->ny - dt * other->vn_mps;
        const double cosine = sim->face_nx[a] * other->nx + sim->face_ny[a] * other->ny;
        const double nearest_push = fmax(0.0, face_reach_m - gap_after);
        if (other->gap_m < dp && sim->face_gap_m[a] < dp && other_after + nearest_push * cosine < face_reach_m) {
            /* in the gap between two solids, within reach of the other one, or brought there by the push off the
             * nearest: kept off each by the reach, or, where the gap is narrower than two reaches, half the gap
             * (alternate projections onto the two faces) */
            const double keep = fmin(face_reach_m, 0.5 * (gap_after + other_after));
            double near_after = gap_after, far_after = other_after;
            for (int round = 0; round < 4 && keep > 0; round++) {
                if (near_after < keep) {
                    const double push = keep - near_after;
                    dx += push * sim->face_nx[a], dy += push * sim->face_ny[a];
                    near_after = keep, far_after += push * cosine;
                }
                if (far_after < keep) {
                    const double push = keep - far_after;
                    dx += push * other->nx, dy += push * other->ny;
                    far_after = keep, near_after += push * cosine;
                }
            }
        } else if (sim->face_gap_m[a] < dp && gap_after < face_reach_m)
            dx += (face_reach_m - gap_after) * sim->face_nx[a], dy += (face_reach_m - gap_after) * sim->face_ny[a];
        sim->x[a] = sim->x_n[a] + dx;
        sim->y[a] = sim->y_n[a] + dy;
    }
}

/* Back to the step's start after a failure: the fluid, the discs where they moved, time, step and the walls */
static void roll_back(surge_sim *sim, double t_n, int64_t step_n, int discs_moved)
{
    fields_restore_step_start(sim);
    if (discs_moved)
        boulders_restore(sim);
    sim->time_s = t_n;
    sim->step = step_n;
    boundary_wall_speeds(sim, t_n);
}

/* The step at `share` of its length: 0, or 1 where it ends compressed past the density bound or a solve failed (a
 * step to take again shorter), or -1 (the run stops); rolled back to its start unless 0 */
static int implicit_attempt(surge_sim *sim, double share)
{
    implicit_work *w = implicit_of(sim);
    surge_phase_times *t = &sim->phase_times;
    const double t_n = sim->time_s;
    const int64_t step_n = sim->step;
    const int lists = neighbours_update(sim);
    phase_end(sim, &t->neighbours_s);
    if (lists != 0 || implicit_reserve_work(sim) != 0 ||
        implicit_mixing_reserve(w, sim->boulders.count > 0 ? sim->params.implicit.disc_pressure_history : 0,
                                sim->count - sim->wall_count) != 0 ||
        implicit_discs_films(sim) != 0 ||
        (share == 1.0 && sim->params.implicit.step_halvings > 0 && implicit_retry_save(sim) != 0)) {
        sim->health = (surge_health){.check = SURGE_CHECK_OUT_OF_MEMORY, .particle_id = -1, .step = step_n + 1,
                                     .time_s = t_n};
        snprintf(sim->health.message, sizeof sim->health.message, "out of memory for the implicit scheme's arrays");
        return -1;
    }
    const double dt = begin_step(sim, share);
    int discs_moved = 0, rc = 0;
    /* with discs, several passes of the viscous and pressure solves (disc_pressure_update), each pass's pressure
     * combined from the last passes' (pass_mixing.c) */
    const int passes = sim->boulders.count > 0 ? sim->params.implicit.disc_pressure_passes : 1;
    const int history = passes > 1 ? sim->params.implicit.disc_pressure_history : 0;
    int viscous_iterations = 0, pressure_iterations = 0;
    double last_update_pa = INFINITY;
    for (int pass = 1; rc == 0 && pass <= passes; pass++) {
        rc = viscous_predict(sim, dt, pass == 1);
        if (rc == 0)
            rc = project(sim, dt, pass == 1);
        if (rc != 0)
            break;
        viscous_iterations += w->viscous_iterations, pressure_iterations += w->pressure_iterations;
        if (pass == passes)
            break;
        /* an update larger than the last pass's: the iteration diverges somewhere (a disc at the free surface by the
         * belt: 1.1-1.2 times a pass, then a jet), and the step ends with this pass as one without them */
        const double update_pa = disc_pressure_update(sim, dt);
        const int diverges = !(update_pa < last_update_pa);
        if (!diverges && history > 0)
            implicit_mix_pressure(sim, pass);
        else if (!diverges)
            disc_pressure_apply(sim);
        phase_end(sim, &t->disc_coupling_s);
        if (diverges)
            break;
        last_update_pa = update_pa;
    }
    if (rc == 0) /* a failed solve's count (and code) stays as fail_solve reported it */
        w->viscous_iterations = viscous_iterations, w->pressure_iterations = pressure_iterations;
    if (rc == 0) {
        rc = rest_density(sim, dt);
        phase_end(sim, &t->pressure_solve_s);
    }
    if (rc == 0) {
        correct_velocities(sim, dt);
        contact_velocities(sim, dt);
        move_particles(sim, dt);
        phase_end(sim, &t->update_s);
        if (sim->boulders.count > 0) {
            discs_moved = 1;
            if (implicit_discs_advance(sim, dt) != 0) {
                sim->health = (surge_health){.check = SURGE_CHECK_OUT_OF_MEMORY, .particle_id = -1,
                                             .step = step_n + 1, .time_s = t_n + dt};
                snprintf(sim->health.message, sizeof sim->health.message, "out of memory in the contact solver");
                rc = -1;
            }
        }
    }
    int too_long = rc != 0 && sim->health.check == SURGE_CHECK_SOLVER;
    if (rc == 0) {
        sim->time_s = t_n + dt;
        sim->step = step_n + 1;
        phase_begin(sim);
        rc = implicit_end_compression(sim, share);
        too_long = rc != 0;
        if (rc == 0)
            rc = health_check(sim);
        phase_end(sim, &t->update_s);
    }
    if (rc != 0)
        roll_back(sim, t_n, step_n, discs_moved);
    return rc == 0 ? 0 : too_long ? 1 : -1;
}

/* A step, taken again at half the length while it is too long (step_retry.c), at most implicit.step_halvings times */
static int implicit_step(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    double share = 1.0;
    for (int halvings = 0;; halvings++, share *= 0.5) {
        const int rc = implicit_attempt(sim, share);
        if (rc <= 0)
            return rc;
        if (halvings == sim->params.implicit.step_halvings)
            return -1;
        if (implicit_retry_restore(sim) != 0) {
            sim->health = (surge_health){.check = SURGE_CHECK_OUT_OF_MEMORY, .particle_id = -1, .step = sim->step + 1,
                                         .time_s = sim->time_s};
            snprintf(sim->health.message, sizeof sim->health.message, "out of memory restoring the contact solver's "
                     "warm start for a step taken again");
            return -1;
        }
        w->step_halvings++;
    }
}

static double implicit_contact_reach_dp(const surge_params *p) { return p->implicit.contact_reach_dp; }

/* No skin: the step moves the fastest particle 0.1-0.35 h, past half of any skin, so the lists are built at every step
 * anyway, and a skin's pairs beyond the kernel's support only cost (12 % of a step on the Freydier front at 0.2 h;
 * docs/method.md) */
static double implicit_neighbour_skin_h(const surge_params *p)
{
    (void)p;
    return 0.0;
}

/* Everything is evaluated at the step's start */
static double implicit_lookahead_s(const surge_sim *sim)
{
    (void)sim;
    return 0.0;
}

/* The body-force limit at rest (the advective one only shortens it) */
static double implicit_step_bound_s(const surge_sim *sim, const surge_params *p)
{
    if (p->numerics.dt_fixed_s > 0)
        return p->numerics.dt_fixed_s;
    double gx, gy;
    scene_body_acceleration(p, &gx, &gy);
    return surge_implicit_dt_s(p, sim->derived.h_m, sqrt(gx * gx + gy * gy), 0.0);
}

static void implicit_diagnostics(const surge_sim *sim, surge_diagnostics *d)
{
    const implicit_work *w = implicit_of(sim);
    d->pressure_iterations = w->pressure_iterations, d->viscous_iterations = w->viscous_iterations;
    d->pressure_residual = w->pressure_residual, d->viscous_residual = w->viscous_residual;
    d->step_halvings = w->step_halvings;
}

/* A disc settling onto the bed with the films off, C_h 1.8: a/dp 4 below 1 h, a/dp 8 above, where the box's walls
 * add least (docs/boulders.md, "What the SPH resolves of a squeeze film") */
static const lubrication_share implicit_film_share = {
    {0.000, 0.051, 0.141, 0.230, 0.321, 0.407, 0.487, 0.551, 0.609, 0.655, 0.696, 0.730, 0.762,
     0.790, 0.817, 0.842, 0.865, 0.888, 0.909, 0.929, 0.948, 0.966, 0.983, 1.000, 1.000}};

const time_scheme scheme_implicit = {
    .name = "implicit",
    .film_share = &implicit_film_share,
    .incompressible = true,
    .reports_solves = true,
    .contact_reach_dp = implicit_contact_reach_dp,
    .neighbour_skin_h = implicit_neighbour_skin_h,
    .lookahead_s = implicit_lookahead_s,
    .step_bound_s = implicit_step_bound_s,
    .create = implicit_create,
    .destroy = implicit_destroy,
    .step = implicit_step,
    .check_report = implicit_check_report,
    .checkpoint_write = implicit_checkpoint_write,
    .checkpoint_read = implicit_checkpoint_read,
    .diagnostics = implicit_diagnostics,
};
