/* The discs' velocities as unknowns of the implicit scheme's solves (docs/method.md, "Boulders in the implicit
 * scheme"). Disc d's unknowns U_d = (Vx, Vy, R Omega) follow the fluid's velocities in the viscous solve's vector
 * (from 2 nf + 3 d); a disc particle k's no-slip mirror is its disc's surface velocity u_k = V + Omega x s_k, s_k the
 * point of the disc's surface on k's mirror line (as boundary.c).
 *  - Viscous solve: the fluid's rows are implicit_viscous_operator's with u_k from U; a disc's rows are
 *    m V - dt F(v, U) = m V_n + dt (m g + F_p(p_n)) and I Omega - dt (T(v, U) - c Omega) = I Omega_n + dt T_p(p_n),
 *    F the sum of the reactions to the momentum the disc's particles give the fluid in the operator,
 *    m_a nu w_ak (v_a - v_k) per pair (v_k = 2 u_k - v_ghost), so that the exchange balances to round-off, T their
 *    torque about the centre (levers r_k, as eq. 10), c Omega the viscous torque the pair form misses.
 *  - Pressure correction: -lap phi + (rho0/dt) d(div v*)/dU . dU(phi) = -(rho0/dt) div v*, dU = dt (F_p(phi)/m,
 *    R^2 (T_p(phi)/R)/I): a disc's change of velocity enters the divergence through its particles' mirrored velocities,
 *    and the pressure's force F_p (eq. 10's pair form, relative to the mean of the disc's particles) changes the
 *    disc's velocity within the same solve: the monolithic system with the discs' rows eliminated (its Schur
 *    complement), so the unknowns stay one a fluid particle and the preconditioner the fluid's. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"
#include "boulders/boulders.h"
#include "neighbours/neighbours.h"

/* The disc a wall particle belongs to, -1 for a fixed wall */
static inline int disc_of(const surge_sim *sim, int kw)
{
    return sim->wall_of[kw] == WALL_BOULDER ? sim->boulders.of_wall[sim->id[kw]] : -1;
}

/* How the pressure row of fluid particle i sees disc d's velocity U_d through disc particle kw (list entry e), over
 * rho0/dt: the divergence of v* takes the particle's mirrored velocity (wall_neumann_offsets), whose change with its
 * surface velocity u_k is P u_k, P the projection on the ghost's offset g where the ghost is wet (the normal part;
 * less the Neumann offset's weight) and the identity where dry; div v = tr(G M^-1) with G's wall terms
 * V_k f (v_k - v_a) (x) r_ak gives c = M^-1 V_k f r_ak, so d(div)/du_k = P c; the Neumann offset
 * immersion rho0/dt (u_k . g) adds the wall's operator weight times immersion g. With u_k = V + Omega x s_k, into
 * row[0..2] as the derivatives by Vx, Vy and R Omega */
static void divergence_row(const surge_sim *sim, int i, int64_t e, int kw, double *row)
{
    const implicit_work *w = implicit_of(sim);
    const double gx = w->wall_gx[e], gy = w->wall_gy[e];
    const double cx = w->minv_xx[i] * gx + w->minv_xy[i] * gy, cy = w->minv_xy[i] * gx + w->minv_yy[i] * gy;
    double bx = cx, by = cy;
    if (!w->dry[kw]) {
        const double immersed = sim->params.implicit.wall_neumann_offset * w->immersion[kw];
        const double ox = sim->ghost_dx[kw], oy = sim->ghost_dy[kw];
        const double normal = (1.0 - immersed) * (cx * ox + cy * oy) / (ox * ox + oy * oy);
        const double offset = immersed > 0 ? -pressure_wall_weight(w, i, e, kw) * immersed : 0.0;
        bx = (normal + offset) * ox, by = (normal + offset) * oy;
    }
    const double radius = sim->boulders.radius[disc_of(sim, kw)];
    row[0] = bx, row[1] = by, row[2] = (w->surface_x[kw] * by - w->surface_y[kw] * bx) / radius;
}

/* The step's disc geometry: each disc particle's surface point and lever, the fluid's list entries that are disc
 * particles and how their pressure rows see the disc's velocity (divergence_row), each disc's spin drag c (the
 * viscous pair force's Laplacian form carries mu (grad v) n, not mu (grad v + grad v^T) n; the missing part is a
 * torque -mu Omega (r . n) per unit of wetted surface, summed over the outer ring by how wet each ghost node is, as
 * boulders_fluid_forces has it), and the disc particles' density at rho0 (the scheme holds it; shifting reads it) */
void implicit_discs_prepare(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    boulder_set *b = &sim->boulders;
    const int nf = sim->count - sim->wall_count;
    const double dp = sim->params.numerics.dp_m, mu = sim->rho0 * sim->params.fluid.viscosity_m2ps;
    w->disc_rows = 3 * b->count;
    memset(w->spin_drag, 0, (size_t)b->count * sizeof *w->spin_drag);
    for (int kw = 0; kw < sim->wall_count; kw++) {
        const int d = disc_of(sim, kw);
        w->surface_x[kw] = w->surface_y[kw] = w->lever_x[kw] = w->lever_y[kw] = 0;
        if (d < 0)
            continue;
        double rx, ry;
        boulders_rotated_offset(b, sim->id[kw], b->cos_angle[d], b->sin_angle[d], &rx, &ry);
        const double lever = sqrt(rx * rx + ry * ry), radius = b->radius[d];
        w->surface_x[kw] = rx * radius / lever, w->surface_y[kw] = ry * radius / lever;
        w->lever_x[kw] = rx, w->lever_y[kw] = ry;
        if (lever > radius - dp) { /* the outer ring; r . n = radius */
            const double arc = 2 * SURGE_PI * radius / boulders_ring_particles(radius, dp, 0);
            w->spin_drag[d] += mu * radius * arc * fmin(1.0, (double)sim->ghost_fluid_sum[kw]);
        }
        sim->rho[kw] = (real)sim->rho0, sim->inv_rho[kw] = (real)(1.0 / sim->rho0);
    }
    size_t n = 0;
    for (int i = 0; i < nf; i++) {
        w->disc_entry_fluid_first[i] = (int64_t)n;
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++)
            if (disc_of(sim, nl->wall_index[e]) >= 0 && (w->wall_w[e] != 0 || w->wall_gx[e] != 0 || w->wall_gy[e] != 0))
                w->disc_entry[n] = e, w->disc_entry_fluid[n] = i, n++;
    }
    w->disc_entry_fluid_first[nf] = (int64_t)n;
    w->disc_entries = n;
    /* grouped by disc, in fluid order within each (a counting sort): a disc's sums over them add as a loop over all
     * the entries would */
    int64_t *by_disc_first = w->disc_entry_disc_first;
    memset(by_disc_first, 0, ((size_t)b->count + 1) * sizeof *by_disc_first);
    for (size_t q = 0; q < n; q++)
        by_disc_first[disc_of(sim, nl->wall_index[w->disc_entry[q]]) + 1]++;
    for (int d = 0; d < b->count; d++)
        by_disc_first[d + 1] += by_disc_first[d];
    for (size_t q = 0; q < n; q++)
        w->disc_entry_by_disc[by_disc_first[disc_of(sim, nl->wall_index[w->disc_entry[q]])]++] = (int64_t)q;
    for (int d = b->count; d > 0; d--) /* by_disc_first[d] now holds the end of disc d: shift back to beginnings */
        by_disc_first[d] = by_disc_first[d - 1];
    by_disc_first[0] = 0;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (size_t q = 0; q < n; q++)
        divergence_row(sim, w->disc_entry_fluid[q], w->disc_entry[q], nl->wall_index[w->disc_entry[q]],
                       w->disc_divergence + 3 * q);
}

/* Each disc particle's no-slip mirror velocity from its disc's unknowns U: u_k = V + Omega x s_k */
void implicit_discs_mirror(surge_sim *sim, const double *disc_velocity)
{
    implicit_work *w = implicit_of(sim);
    const boulder_set *b = &sim->boulders;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int e = 0; e < b->by_disc_first[b->count]; e++) {
        const int kw = b->in_order[e], d = b->of_wall[sim->id[kw]];
        const double omega = disc_velocity[3 * d + 2] / b->radius[d];
        w->mirror_vx[kw] = disc_velocity[3 * d] - omega * w->surface_y[kw];
        w->mirror_vy[kw] = disc_velocity[3 * d + 1] + omega * w->surface_x[kw];
    }
}

/* eq. 10's pressure part, linear in the pressure: per disc the force and torque over R (about the centre, levers
 * r_k) of the fluid's pressures p (by fluid index; free-surface particles at 0) and the walls'
 * in w->wall_x, the pair sum m_a m_k (p_a + p_k) f r_ak / rho0^2 of the explicit scheme, each pressure taken relative
 * to the mean of the disc's own particles: a uniform pressure exerts no force on a closed surface, but the pair sum
 * around a disc on an irregular arrangement does not vanish; with contacts.solid_pressure, the same pair term with the
 * particles of walls and other discs in reach (boulders_fluid_forces). Into force (3 per disc: Fx, Fy and T/R, N/m) */
static void disc_pressure_forces(surge_sim *sim, const double *p, double *force)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const boulder_set *b = &sim->boulders;
    const int first = sim->wall_count;
    const real grad_coef = sim->kernel.grad_coef, inv_h = sim->kernel.inv_h, support2 = sim->kernel.support2;
    const double scale = sim->mass * sim->mass / (sim->rho0 * sim->rho0);
    double *reference = w->disc_reference_pa;
    #pragma omp parallel if (wide(sim))
    {
        /* each disc's sums over its particles in ascending index order (by_disc): the same whatever the thread count */
        #pragma omp for schedule(static)
        for (int d = 0; d < b->count; d++) {
            double sum = 0;
            for (int q = b->by_disc_first[d]; q < b->by_disc_first[d + 1]; q++)
                sum += w->wall_x[b->by_disc[q]];
            reference[d] = sum / boulders_particles_of(sim, d);
        }
        #pragma omp for schedule(dynamic, 1)
        for (int d = 0; d < b->count; d++) {
            double force_x = 0, force_y = 0, torque = 0;
            for (int q = b->by_disc_first[d]; q < b->by_disc_first[d + 1]; q++) {
                const int kw = b->by_disc[q];
                const double pk = w->wall_x[kw] - reference[d];
                double fx = 0, fy = 0;
                for (int64_t e = nl->wall_fluid_first[kw]; e < nl->wall_fluid_first[kw + 1]; e++) {
                    const int a = nl->wall_fluid_index[e];
                    /* r_a - r_k, as boulders_fluid_forces has it */
                    const real dx = -(nl->wall_fluid_dx0[e] + (nl->moved_x[kw] - nl->moved_x[a]));
                    const real dy = -(nl->wall_fluid_dy0[e] + (nl->moved_y[kw] - nl->moved_y[a]));
                    const real r2 = dx * dx + dy * dy;
                    if (!(r2 < support2))
                        continue;
                    const double f = kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2));
                    const double pa = (w->fixed[a - first] ? 0.0 : p[a - first]) - reference[d];
                    fx += (pa + pk) * f * dx, fy += (pa + pk) * f * dy;
                }
                if (sim->params.contacts.solid_pressure) /* the particles of walls and other discs in reach (fluid_forces.c) */
                    for (int64_t e = nl->solid_first[kw]; e < nl->solid_first[kw + 1]; e++) {
                        const int j = nl->solid_index[e], other = disc_of(sim, j);
                        real dx, dy; /* r_k - r_j */
                        const real r2 = neighbours_solid_offset(nl, kw, e, &dx, &dy);
                        if (!(r2 < support2))
                            continue;
                        const double f = kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2));
                        /* between two discs, one reference for both sides: the pair's forces stay equal and opposite */
                        const double shared = other < 0 ? reference[d] : 0.5 * (reference[d] + reference[other]);
                        const double pair = (w->wall_x[j] - shared) + (w->wall_x[kw] - shared);
                        fx -= pair * f * dx, fy -= pair * f * dy;
                    }
                force_x += scale * fx, force_y += scale * fy;
                torque += scale * (w->lever_x[kw] * fy - w->lever_y[kw] * fx) / b->radius[d];
            }
            force[3 * d] = force_x, force[3 * d + 1] = force_y, force[3 * d + 2] = torque;
        }
    }
}

/* The viscous solve's disc rows, after viscous_system: the right-hand side m V_n + dt (m g + F_p(p_n)) over m (and
 * R (I Omega_n + dt T_p(p_n)) over I), p_n's walls in w->wall_x; the first guess U_n; the diagonal, each disc
 * particle's no-slip mirror moving 2 u_k per unit of u_k */
void implicit_discs_viscous_system(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const boulder_set *b = &sim->boulders;
    const int nf = sim->count - sim->wall_count;
    const double dt_nu_m = dt * sim->params.fluid.viscosity_m2ps * sim->mass;
    double gx, gy;
    boulders_own_acceleration(sim, &gx, &gy);
    disc_pressure_forces(sim, w->pressure_n, w->disc_force);
    double *rhs = w->rhs + 2 * nf, *x = w->x + 2 * nf, *diag = w->diag + 2 * nf;
    for (int d = 0; d < b->count; d++) {
        const double radius = b->radius[d], *force = w->disc_force + 3 * d;
        rhs[3 * d] = b->vx[d] + dt * (gx + b->inv_mass[d] * force[0]);
        rhs[3 * d + 1] = b->vy[d] + dt * (gy + b->inv_mass[d] * force[1]);
        rhs[3 * d + 2] = radius * b->omega[d] + dt * radius * radius * b->inv_inertia[d] * force[2];
        x[3 * d] = b->vx[d], x[3 * d + 1] = b->vy[d], x[3 * d + 2] = radius * b->omega[d];
        diag[3 * d] = diag[3 * d + 1] = 1.0;
        diag[3 * d + 2] = 1.0 + dt * b->inv_inertia[d] * w->spin_drag[d];
    }
    for (size_t q = 0; q < w->disc_entries; q++) {
        const int64_t e = w->disc_entry[q];
        const int kw = nl->wall_index[e], d = disc_of(sim, kw);
        const double stiffness = 2.0 * dt_nu_m * w->wall_w[e];
        diag[3 * d] += b->inv_mass[d] * stiffness, diag[3 * d + 1] += b->inv_mass[d] * stiffness;
        diag[3 * d + 2] += b->inv_inertia[d] * stiffness * 0.5 * b->radius[d] * b->radius[d];
    }
    implicit_films_factor(sim, dt, diag);
}

/* The coupled viscous operator on x = (vx | vy | U): the fluid's rows with the disc particles' mirrors at u_k(U),
 * then per disc U - dt (F/m, R (T - c Omega)/I), F and T the reactions to what the disc particles give the fluid:
 * m_a nu w_ak (v_a - v_k) per pair, v_k = 2 u_k - v_ghost as the fluid's row takes it (w->wall_x, wall_y) */
void implicit_coupled_viscous_operator(surge_sim *sim, const double *x, double *out)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const boulder_set *b = &sim->boulders;
    const int nf = sim->count - sim->wall_count;
    const double *disc_x = x + 2 * nf;
    implicit_discs_mirror(sim, disc_x);
    implicit_viscous_operator(sim, x, out);
    double *force = w->disc_force;
    const double nu_m = sim->params.fluid.viscosity_m2ps * sim->mass;
    #pragma omp parallel for schedule(dynamic, 1) if (wide(sim))
    for (int d = 0; d < b->count; d++) { /* each disc's entries in fluid order: the same sums whatever the thread count */
        double force_x = 0, force_y = 0, torque = 0;
        for (int64_t t = w->disc_entry_disc_first[d]; t < w->disc_entry_disc_first[d + 1]; t++) {
            const int64_t q = w->disc_entry_by_disc[t], e = w->disc_entry[q];
            const int i = w->disc_entry_fluid[q], kw = nl->wall_index[e];
            const double fx = nu_m * w->wall_w[e] * (x[i] - w->wall_x[kw]);
            const double fy = nu_m * w->wall_w[e] * (x[nf + i] - w->wall_y[kw]);
            force_x += fx, force_y += fy;
            torque += (w->lever_x[kw] * fy - w->lever_y[kw] * fx) / b->radius[d];
        }
        force[3 * d] = force_x, force[3 * d + 1] = force_y, force[3 * d + 2] = torque;
    }
    implicit_film_forces(sim, disc_x, force);
    const double dt = sim->dt_s;
    for (int d = 0; d < b->count; d++) {
        const double *u = disc_x + 3 * d, radius = b->radius[d];
        out[2 * nf + 3 * d] = u[0] - dt * b->inv_mass[d] * force[3 * d];
        out[2 * nf + 3 * d + 1] = u[1] - dt * b->inv_mass[d] * force[3 * d + 1];
        out[2 * nf + 3 * d + 2] = u[2] + dt * b->inv_inertia[d] * (w->spin_drag[d] * u[2] - radius * radius * force[3 * d + 2]);
    }
}

/* The velocity change dU = dt (F_p/m, R T_p/I) of the pressure field x (fluid) and w->wall_x (walls), into
 * w->disc_force */
static void pressure_velocity_change(surge_sim *sim, const double *x, double dt)
{
    implicit_work *w = implicit_of(sim);
    const boulder_set *b = &sim->boulders;
    double *change = w->disc_force;
    disc_pressure_forces(sim, x, change);
    for (int d = 0; d < b->count; d++) {
        change[3 * d] *= dt * b->inv_mass[d], change[3 * d + 1] *= dt * b->inv_mass[d];
        change[3 * d + 2] *= dt * b->inv_inertia[d] * b->radius[d] * b->radius[d];
    }
    implicit_films_solve(sim, FILMS_PRESSURE, change); /* with the films: (M + dt K) dU = dt F_p */
}

/* The coupled pressure operator: implicit_pressure_operator's -lap phi, plus (rho0/dt) times what the discs' change of
 * velocity dU(phi) adds to each row (divergence_row) */
void implicit_coupled_pressure_operator(surge_sim *sim, const double *x, double *out)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const double dt = sim->dt_s, rho0_dt = sim->rho0 / dt;
    implicit_pressure_operator(sim, x, out);
    pressure_velocity_change(sim, x, dt);
    const double *change = w->disc_force;
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        if (w->fixed[i])
            continue;
        for (int64_t q = w->disc_entry_fluid_first[i]; q < w->disc_entry_fluid_first[i + 1]; q++) {
            const double *row = w->disc_divergence + 3 * q, *du = change + 3 * disc_of(sim, nl->wall_index[w->disc_entry[q]]);
            out[i] += rho0_dt * (row[0] * du[0] + row[1] * du[1] + row[2] * du[2]);
        }
    }
}

/* After the pressure solve (phi in w->x): the discs' velocities v_n+1 = v* + dU(phi), their particles' mirrors, and
 * the contact rule's faces on discs moving with them (a disc's normal velocity V . n: turning adds none) */
void implicit_discs_pressure_answer(surge_sim *sim, double dt)
{
    implicit_work *w = implicit_of(sim);
    const boulder_set *b = &sim->boulders;
    implicit_wall_pressures(sim, w->x, NULL);
    pressure_velocity_change(sim, w->x, dt);
    for (int q = 0; q < 3 * b->count; q++)
        w->disc_velocity[q] += w->disc_force[q];
    implicit_discs_mirror(sim, w->disc_velocity);
    for (int a = sim->wall_count; a < sim->count; a++) {
        if (sim->face_disc[a] >= 0) {
            const int d = sim->face_disc[a];
            sim->face_vn_mps[a] = (real)(w->disc_velocity[3 * d] * sim->face_nx[a] +
                                         w->disc_velocity[3 * d + 1] * sim->face_ny[a]);
        }
        wall_face *other = &w->other_face[a - sim->wall_count];
        if (other->disc >= 0)
            other->vn_mps = (real)(w->disc_velocity[3 * other->disc] * other->nx +
                                   w->disc_velocity[3 * other->disc + 1] * other->ny);
    }
}
