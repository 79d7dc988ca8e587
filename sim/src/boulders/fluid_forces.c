/* The fluid's forces and torques on the discs (eq. 10). */
#include <math.h>
#include <string.h>

#include "sim_internal.h"
#include "boulders/boulders.h"
#include "neighbours/neighbours.h"
#include "physics/pair_terms.h"

/* eq. 7's pressure term between disc particle k and the particles of walls and other discs in its list (lists.h),
 * pressures relative to reference: the force on k added to fx, fy */
static void solid_pressure_force(const surge_sim *sim, int k, real reference, real *fx, real *fy)
{
    const neighbour_lists *nl = &sim->neighbours;
    const real grad_coef = sim->kernel.grad_coef, inv_h = sim->kernel.inv_h, support2 = sim->kernel.support2;
    const real mass = (real)sim->mass, pk = sim->pressure[k] - reference, inv_rhok = sim->inv_rho[k];
    real sum_x = 0, sum_y = 0;
    for (int64_t e = nl->solid_first[k]; e < nl->solid_first[k + 1]; e++) {
        const int j = nl->solid_index[e];
        real dx, dy; /* r_k - r_j */
        const real r2 = neighbours_solid_offset(nl, k, e, &dx, &dy);
        if (!(r2 < support2))
            continue;
        const real f = kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2));
        const real pressure_coef = pair_pressure_coef(mass, pk, sim->pressure[j] - reference, inv_rhok, sim->inv_rho[j]);
        sum_x += pressure_coef * f * dx, sum_y += pressure_coef * f * dy;
    }
    *fx += mass * sum_x;
    *fy += mass * sum_y;
}

/* eq. 10's pair terms on disc particle k (the wall-index k of a disc's particle): its force into sim->ax, sim->ay
 * (wall entries are free scratch), its viscous coupling into spin_coupling */
static inline __attribute__((always_inline)) void disc_particle_force(surge_sim *sim, int k, const double *reference_pa)
{
    boulder_set *b = &sim->boulders;
    const neighbour_lists *nl = &sim->neighbours;
    const real grad_coef = sim->kernel.grad_coef, inv_h = sim->kernel.inv_h;
    const real mass = (real)sim->mass, eta2 = (real)sim->eta2, support2 = sim->kernel.support2;
    const real four_nu = (real)(4.0 * sim->params.fluid.viscosity_m2ps);
    const real *restrict rho = sim->rho, *restrict inv_rho = sim->inv_rho, *restrict pres = sim->pressure;
    const pair_state *restrict st = sim->pair_state;
    const int solid_pressure = sim->params.contacts.solid_pressure;
    real *restrict fx = sim->ax, *restrict fy = sim->ay;
    const real mxk = nl->moved_x[k], myk = nl->moved_y[k], rhok = rho[k], pk = pres[k], inv_rhok = inv_rho[k];
    const real wall_vx = sim->wall_vx[k], wall_vy = sim->wall_vy[k];
    const real reference = reference_pa ? (real)reference_pa[b->of_wall[sim->id[k]]] : 0;
    const int32_t *restrict index = nl->wall_fluid_index;
    const real *restrict dx0 = nl->wall_fluid_dx0, *restrict dy0 = nl->wall_fluid_dy0;
    /* one partial sum per lane over the padded list, fluid records transposed (as in interaction.c) */
    real sum_x[PAIR_LANES] = {0}, sum_y[PAIR_LANES] = {0}, sum_viscous[PAIR_LANES] = {0};
    for (int64_t e0 = nl->wall_fluid_first[k]; e0 < nl->wall_fluid_first[k + 1]; e0 += PAIR_LANES) {
        lanes_vector field[PAIR_LANES];
        lanes_gather_records(st, index + e0, field); /* field[q][l]: lane l's fluid neighbour's q-th field (pair_state) */
        #pragma omp simd simdlen(PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            /* r_a - r_k, as the fluid's wall loop has it (interaction.c) */
            const real dx = -(dx0[e] + (mxk - field[PAIR_MOVED_X][l])), dy = -(dy0[e] + (myk - field[PAIR_MOVED_Y][l]));
            const real r2 = dx * dx + dy * dy;
            const real f = r2 < support2 ? kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2)) : 0;
            /* the terms of the fluid particle a's acceleration by k (interaction.c's wall loop); none beyond 2h */
            const real pressure_coef = pair_pressure_coef(mass, field[PAIR_PRESSURE][l] - reference, pk - reference, field[PAIR_INV_RHO][l],
                                                          inv_rhok);
            const real inv_denominator = pair_viscous_denominator(field[PAIR_RHO][l], rhok, r2, eta2);
            const real viscous_coef = pair_viscous_coef(mass, four_nu, f, r2, inv_denominator);
            sum_x[l] += pair_acceleration(pressure_coef, f, dx, viscous_coef, field[PAIR_VX][l] - wall_vx);
            sum_y[l] += pair_acceleration(pressure_coef, f, dy, viscous_coef, field[PAIR_VY][l] - wall_vy);
            sum_viscous[l] += viscous_coef;
        }
    }
    const real zero[PAIR_LANES] = {0};
    const real *const lanes[8] = {sum_x, sum_y, sum_viscous, zero, zero, zero, zero, zero};
    real total[8];
    lanes_totals(lanes, total);
    fx[k] = -mass * total[0];
    fy[k] = -mass * total[1];
    b->spin_coupling[k] = total[2];
    if (solid_pressure)
        solid_pressure_force(sim, k, reference, &fx[k], &fy[k]);
}

/* Disc i's force, torque and spin stiffness: the sums over its particles in ascending index order (by_disc), the same
 * whatever the thread count */
static void disc_sums(surge_sim *sim, int i)
{
    boulder_set *b = &sim->boulders;
    const real *restrict fx = sim->ax, *restrict fy = sim->ay;
    const double mu = sim->rho0 * sim->params.fluid.viscosity_m2ps, dp = sim->params.numerics.dp_m;
    double force_x = 0, force_y = 0, torque = 0, spin_damping = 0;
    const double a = b->radius[i], arc = 2 * SURGE_PI * a / boulders_ring_particles(a, dp, 0);
    for (int e = b->by_disc_first[i]; e < b->by_disc_first[i + 1]; e++) {
        const int k = b->by_disc[e];
        double rx, ry;
        boulders_rotated_offset(b, sim->id[k], b->cos_angle[i], b->sin_angle[i], &rx, &ry);
        force_x += fx[k];
        force_y += fy[k];
        torque += rx * fy[k] - ry * fx[k];
        /* stiffness: the no-slip velocity 2 v_surface - v_ghost moves by 2 R per unit omega */
        const double lever = sqrt(rx * rx + ry * ry);
        spin_damping -= 2 * sim->mass * a * lever * b->spin_coupling[k];
        if (lever > a - dp) { /* outer ring; r . n = radius */
            const double wetted = fmin(1.0, (double)sim->ghost_fluid_sum[k]);
            torque -= mu * b->omega[i] * a * arc * wetted;
            spin_damping += mu * a * arc * wetted;
        }
    }
    b->fx[i] = force_x, b->fy[i] = force_y, b->torque[i] = torque;
    b->spin_damping[i] = spin_damping * b->inv_inertia[i];
    b->omega_forces[i] = b->omega[i];
}

/* eq. 10: the force on each disc particle is minus the pair forces it exerts on its fluid neighbours
 * (the terms of interaction.c's wall loop), so momentum is exchanged exactly.
 * The viscous pair force (Lo & Shao) is the Laplacian form: it carries the traction mu (grad v) n, not
 * mu (grad v + grad v^T) n. On a no-slip rigid surface the missing part is -mu omega x n: no net force on a
 * closed surface, but a torque -mu omega (r . n) per unit area of wetted surface, -2 mu A omega on a wholly
 * wetted disc of area A (half the torque on a spinning disc). It is added here over the outer ring, each
 * particle weighted by how wetted its ghost node is.
 * A uniform pressure exerts no force on a closed surface, but the discrete sum of (p_a + p_k) grad W around a disc
 * is not zero on an irregular arrangement: reference_pa[disc] is subtracted from the pressures, where given (the
 * implicit scheme's pressure in a closed domain carries an arbitrary constant).
 * Where a wall or another disc comes within the kernel's reach, its particles take the place of fluid particles in a
 * disc particle's support: with contacts.solid_pressure they exert eq. 7's pressure term as the fluid does (equal and
 * opposite between two discs), so that the pressure in a gap narrower than the kernel, and a uniform pressure around
 * a disc near a wall, act on the disc (docs/boulders.md, "Pressure across narrow gaps"). */
void boulders_fluid_forces(surge_sim *sim, const double *reference_pa)
{
    boulder_set *b = &sim->boulders;
    #pragma omp single nowait
    boulders_orient(b);
    /* in index order, each thread a run of consecutive disc particles (the fluid records one reads are in cache for
     * the next) */
    #pragma omp for schedule(static)
    for (int e = 0; e < b->by_disc_first[b->count]; e++)
        disc_particle_force(sim, b->in_order[e], reference_pa);
    #pragma omp for schedule(dynamic, 1)
    for (int i = 0; i < b->count; i++)
        disc_sums(sim, i);
}

/* The reaction to the face repulsion of fluid particles too close to a disc (interaction.c); radial, no torque. In
 * index order: the same sums whatever the thread count. */
void boulders_take_face_reactions(surge_sim *sim)
{
    boulder_set *b = &sim->boulders;
    for (int a = sim->wall_count; a < sim->count; a++)
        if (sim->face_disc[a] >= 0) {
            b->fx[sim->face_disc[a]] -= sim->mass * sim->face_push_x[a];
            b->fy[sim->face_disc[a]] -= sim->mass * sim->face_push_y[a];
        }
}
