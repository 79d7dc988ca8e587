/* Rates of change of the fluid particles: continuity with density diffusion (GMD eq. 6; Fourtakas' form or
 * Antuono's), momentum with pressure, laminar viscosity and body force (eq. 7), plus what the time step and
 * shifting need. */
#include <math.h>

#include "physics/eos.h"
#include "physics/pair_terms.h"
#include "sim_internal.h"
#include "neighbours/neighbours.h"
#include "physics/interaction.h"

void interaction_prepare(surge_sim *sim)
{
    const int tait = !sim->scheme->incompressible; /* the pressure from the density (else the scheme's solve) */
    const neighbour_lists *nl = &sim->neighbours;
    const real rho0 = (real)sim->rho0, b = (real)sim->b_pa;
    /* one loop, one barrier: the walls' displacements (discs), then the fluid's with its state (after the surface
     * flags of the predictor pass); the walls' pressures follow their mDBC densities (boundary_update) */
    #pragma omp for schedule(static)
    for (int i = neighbours_first_moving(sim); i < sim->count; i++) {
        neighbours_track_particle(sim, i);
        if (i >= sim->wall_count) {
            if (tait) {
                sim->pressure[i] = tait_pressure(sim->rho[i], rho0, b);
                sim->inv_rho[i] = (real)1 / sim->rho[i];
            }
            sim->pair_state[i] = (pair_state){nl->moved_x[i], nl->moved_y[i], sim->vx[i], sim->vy[i], sim->rho[i],
                                              sim->inv_rho[i], sim->pressure[i], (real)sim->surface[i]};
        }
    }
}

/* Antuono et al. (2010) renormalised density gradient over the fluid neighbours,
 * <grad rho>_a = M_a^-1 sum_b (rho_b - rho_a) grad_a W_ab V_b, exact for a linear density field even where the
 * kernel is truncated. Where M is nearly singular (an isolated particle) the gradient is taken as zero. */
static void compute_density_gradient(surge_sim *sim)
{
    const neighbour_lists *nl = &sim->neighbours;
    const real grad_coef = sim->kernel.grad_coef, inv_h = sim->kernel.inv_h, mass = (real)sim->mass;
    const real support2 = sim->kernel.support2;
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const real *restrict rho = sim->rho, *restrict inv_rho = sim->inv_rho;
    #pragma omp for schedule(static)
    for (int a = sim->wall_count; a < sim->count; a++) {
        const real rhoa = rho[a], mxa = moved_x[a], mya = moved_y[a];
        real m_xx = 0, m_xy = 0, m_yy = 0, sum_x = 0, sum_y = 0;
        const int i = a - sim->wall_count;
        #pragma omp simd reduction(+ : m_xx, m_xy, m_yy, sum_x, sum_y)
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
            const int b = nl->fluid_index[e];
            const real dx = nl->fluid_dx0[e] + (mxa - moved_x[b]), dy = nl->fluid_dy0[e] + (mya - moved_y[b]);
            const real r2 = dx * dx + dy * dy;
            const real f = r2 < support2 && r2 > 0 ? kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2)) : 0;
            const real vf = mass * inv_rho[b] * f;
            m_xx += pair_moment(vf, dx, dx), m_xy += pair_moment(vf, dx, dy), m_yy += pair_moment(vf, dy, dy);
            sum_x -= pair_moment(vf, rho[b] - rhoa, dx), sum_y -= pair_moment(vf, rho[b] - rhoa, dy);
        }
        const real det = m_xx * m_yy - m_xy * m_xy;
        const real inv_det = det > (real)0.25 ? (real)1 / det : 0;
        sim->grad_rho_x[a] = inv_det * (m_yy * sum_x - m_xy * sum_y);
        sim->grad_rho_y[a] = inv_det * (m_xx * sum_y - m_xy * sum_x);
    }
}

/* What one evaluation's pair loops take from the scene, constant over the particles */
typedef struct pair_constants {
    real grad_coef, inv_h, alpha, mass, eta2, h, support2, four_nu, rho_h_per_m;
} pair_constants;

/* The sums a fluid particle gathers over its neighbours (eq. 6, 7 and what the time step, shifting, the
 * renormalisation and the relaxation need) */
typedef struct particle_sums {
    real acc_x, acc_y, diffusion, visc_speed_mps, kernel_w; /* kernel_w: sum_b W_ab, not the particle itself */
    real grad_c_x, grad_c_y;
    /* kernel moment M and velocity gradient G (pair_moment): -tr G is the plain div v (pair_divergence summed),
     * tr M the free-surface indicator div r */
    real m_xx, m_xy, m_yy, g_xx, g_xy, g_yx, g_yy;
    int near_surface, near_boulder;
} particle_sums;

/* Fluid particle a's fluid neighbours: pressure, viscosity, continuity, density diffusion (Antuono's form when
 * antuono), moments; in the predictor's pass the viscous speed (the time step), in the corrector's what shifting and
 * the relaxation need. antuono and corrector are constants the compiler specialises on. Pairs beyond 2h (the skin)
 * are masked, not skipped, so that the loop vectorises; each particle sums its own pairs, lane l taking entries
 * l, l + PAIR_LANES, ... in list order and the lanes added in order, whatever the thread count. */
static inline __attribute__((always_inline)) void fluid_pairs(const surge_sim *sim, const pair_constants *c, int a,
                                                              int antuono, int corrector, particle_sums *out)
{
    const neighbour_lists *nl = &sim->neighbours;
    const int32_t *restrict index = nl->fluid_index;
    const real *restrict dx0 = nl->fluid_dx0, *restrict dy0 = nl->fluid_dy0;
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const real *restrict vx = sim->vx, *restrict vy = sim->vy, *restrict rho = sim->rho;
    const real *restrict inv_rho = sim->inv_rho, *restrict pres = sim->pressure;
    const real *restrict grad_rho_x = sim->grad_rho_x, *restrict grad_rho_y = sim->grad_rho_y;
    const pair_state *restrict st = sim->pair_state;
    const real grad_coef = c->grad_coef, inv_h = c->inv_h, alpha = c->alpha, mass = c->mass, eta2 = c->eta2;
    const real h = c->h, support2 = c->support2, four_nu = c->four_nu, rho_h_per_m = c->rho_h_per_m;
    const real mxa = moved_x[a], mya = moved_y[a], vxa = vx[a], vya = vy[a], rhoa = rho[a], pa = pres[a];
    const real inv_rhoa = inv_rho[a], grad_xa = grad_rho_x[a], grad_ya = grad_rho_y[a];
    /* one partial sum per lane, added up in lane order at the end (the lists hold whole vectors, neighbours.c) */
    real acc_x[PAIR_LANES] = {0}, acc_y[PAIR_LANES] = {0}, diffusion[PAIR_LANES] = {0}, visc_speed_mps[PAIR_LANES] = {0};
    real kernel_w[PAIR_LANES] = {0}, grad_c_x[PAIR_LANES] = {0}, grad_c_y[PAIR_LANES] = {0};
    real m_xx[PAIR_LANES] = {0}, m_xy[PAIR_LANES] = {0}, m_yy[PAIR_LANES] = {0};
    real g_xx[PAIR_LANES] = {0}, g_xy[PAIR_LANES] = {0}, g_yx[PAIR_LANES] = {0}, g_yy[PAIR_LANES] = {0};
    real surface_neighbours[PAIR_LANES] = {0}; /* how many surface particles within 2h (surface is 0 or 1) */
    const int i = a - sim->wall_count;
    const int64_t first = nl->fluid_first[i], last = nl->fluid_first[i + 1];
    for (int64_t e0 = first; e0 < last; e0 += PAIR_LANES) {
        lanes_vector field[PAIR_LANES];
        lanes_gather_records(st, index + e0, field); /* field[q][l]: lane l's neighbour's q-th field (pair_state) */
        #pragma omp simd simdlen(PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            const int b = index[e];
            const real nb_vx = field[PAIR_VX][l], nb_vy = field[PAIR_VY][l], nb_rho = field[PAIR_RHO][l], nb_inv_rho = field[PAIR_INV_RHO][l];
            const real nb_pressure = field[PAIR_PRESSURE][l], nb_surface = field[PAIR_SURFACE][l];
            const real dx = dx0[e] + (mxa - field[PAIR_MOVED_X][l]), dy = dy0[e] + (mya - field[PAIR_MOVED_Y][l]); /* r_ab */
            const real r2 = dx * dx + dy * dy;
            const int inside = r2 < support2 && r2 > 0;
            const real r = REAL_SQRT(r2);
            const real f = inside ? kernel2d_grad_factor_inside(grad_coef, inv_h, r) : 0; /* grad_a W = f r_ab */
            const real vol = mass * nb_inv_rho, vf = vol * f;
            const real dvx = vxa - nb_vx, dvy = vya - nb_vy;
            const real pressure_coef = pair_pressure_coef(mass, pa, nb_pressure, inv_rhoa, nb_inv_rho);
            const real inv_denominator = pair_viscous_denominator(rhoa, nb_rho, r2, eta2);
            const real viscous_coef = pair_viscous_coef(mass, four_nu, f, r2, inv_denominator);
            acc_x[l] += pair_acceleration(pressure_coef, f, dx, viscous_coef, dvx);
            acc_y[l] += pair_acceleration(pressure_coef, f, dy, viscous_coef, dvy);
            m_xx[l] += pair_moment(vf, dx, dx), m_xy[l] += pair_moment(vf, dx, dy), m_yy[l] += pair_moment(vf, dy, dy);
            g_xx[l] += pair_moment(vf, dvx, dx), g_xy[l] += pair_moment(vf, dvx, dy);
            g_yx[l] += pair_moment(vf, dvy, dx), g_yy[l] += pair_moment(vf, dvy, dy);
            const real linear_part = antuono ? pair_gradient_part(grad_xa, grad_ya, grad_rho_x[b], grad_rho_y[b], dx, dy)
                                             : pair_hydrostatic_part(rho_h_per_m, dy);
            diffusion[l] -= pair_diffusion(rhoa, nb_rho, linear_part, f, vol);
            if (!corrector) {
                const real speed = inside ? pair_viscous_speed(h, dvx, dvy, dx, dy, rhoa + nb_rho, inv_denominator) : 0;
                visc_speed_mps[l] = speed > visc_speed_mps[l] ? speed : visc_speed_mps[l];
            } else {
                grad_c_x[l] += vf * dx;
                grad_c_y[l] += vf * dy;
                surface_neighbours[l] += inside ? nb_surface : 0;
                kernel_w[l] += inside ? kernel2d_w_inside(alpha, inv_h, r) : 0;
            }
        }
    }
    /* the lanes' totals, each added in lane order (lanes.h) */
    const real zero[PAIR_LANES] = {0};
    const real *const first_eight[8] = {acc_x, acc_y, diffusion, kernel_w, grad_c_x, grad_c_y, m_xx, m_xy};
    const real *const last_six[8] = {m_yy, g_xx, g_xy, g_yx, g_yy, surface_neighbours, zero, zero};
    real total[16];
    lanes_totals(first_eight, total);
    lanes_totals(last_six, total + 8);
    particle_sums sums = {total[0], total[1], total[2], 0, total[3], total[4], total[5], total[6], total[7],
                          total[8], total[9], total[10], total[11], total[12], total[13] > 0, 0};
    for (int l = 0; l < PAIR_LANES; l++)
        sums.visc_speed_mps = visc_speed_mps[l] > sums.visc_speed_mps ? visc_speed_mps[l] : sums.visc_speed_mps;
    *out = sums;
}

/* Fluid particle a's wall neighbours, added to s: mDBC pressure; the no-slip velocity in the viscous term, the
 * wall's (with no penetration) in continuity; no density diffusion across the wall (passes as in fluid_pairs). */
static inline __attribute__((always_inline)) void wall_pairs(const surge_sim *sim, const pair_constants *c, int a,
                                                             int corrector, particle_sums *s)
{
    const neighbour_lists *nl = &sim->neighbours;
    const int32_t *restrict index = nl->wall_index;
    const real *restrict dx0 = nl->wall_dx0, *restrict dy0 = nl->wall_dy0;
    const real *restrict rho = sim->rho, *restrict inv_rho = sim->inv_rho, *restrict pres = sim->pressure;
    const wall_pair_state *restrict st = sim->wall_state;
    const real grad_coef = c->grad_coef, inv_h = c->inv_h, alpha = c->alpha, mass = c->mass, eta2 = c->eta2;
    const real h = c->h, support2 = c->support2, four_nu = c->four_nu;
    const real mxa = nl->moved_x[a], mya = nl->moved_y[a], vxa = sim->vx[a], vya = sim->vy[a], rhoa = rho[a];
    const real pa = pres[a], inv_rhoa = inv_rho[a];
    const int i = a - sim->wall_count;
    const int64_t first = nl->wall_first[i], last = nl->wall_first[i + 1];
    if (first == last)
        return;
    real acc_x[PAIR_LANES] = {0}, acc_y[PAIR_LANES] = {0}, visc_speed_mps[PAIR_LANES] = {0};
    real kernel_w[PAIR_LANES] = {0}, grad_c_x[PAIR_LANES] = {0}, grad_c_y[PAIR_LANES] = {0};
    real m_xx[PAIR_LANES] = {0}, m_xy[PAIR_LANES] = {0}, m_yy[PAIR_LANES] = {0};
    real g_xx[PAIR_LANES] = {0}, g_xy[PAIR_LANES] = {0}, g_yx[PAIR_LANES] = {0}, g_yy[PAIR_LANES] = {0};
    for (int64_t e0 = first; e0 < last; e0 += PAIR_LANES) {
        lanes_vector field[PAIR_LANES];
        lanes_gather_records(st, index + e0, field); /* field[q][l]: lane l's wall neighbour's q-th field (wall_pair_state) */
        #pragma omp simd simdlen(PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            const real rho_b = field[WALL_PAIR_RHO][l], pressure_b = field[WALL_PAIR_PRESSURE][l];
            const real inv_rho_b = (real)1 / rho_b; /* the bits of inv_rho[b] (boundary_update) */
            const real dx = dx0[e] + (mxa - field[WALL_PAIR_MOVED_X][l]), dy = dy0[e] + (mya - field[WALL_PAIR_MOVED_Y][l]);
            const real r2 = dx * dx + dy * dy;
            const int inside = r2 < support2;
            const real r = REAL_SQRT(r2);
            const real f = inside ? kernel2d_grad_factor_inside(grad_coef, inv_h, r) : 0;
            const real vf = mass * inv_rho_b * f;
            const real pressure_coef = pair_pressure_coef(mass, pa, pressure_b, inv_rhoa, inv_rho_b);
            const real inv_denominator = pair_viscous_denominator(rhoa, rho_b, r2, eta2);
            const real viscous_coef = pair_viscous_coef(mass, four_nu, f, r2, inv_denominator);
            const real nsx = vxa - field[WALL_PAIR_NOSLIP_VX][l], nsy = vya - field[WALL_PAIR_NOSLIP_VY][l];
            acc_x[l] += pair_acceleration(pressure_coef, f, dx, viscous_coef, nsx);
            acc_y[l] += pair_acceleration(pressure_coef, f, dy, viscous_coef, nsy);
            const real wdx = vxa - field[WALL_PAIR_CONT_VX][l], wdy = vya - field[WALL_PAIR_CONT_VY][l];
            m_xx[l] += pair_moment(vf, dx, dx), m_xy[l] += pair_moment(vf, dx, dy), m_yy[l] += pair_moment(vf, dy, dy);
            g_xx[l] += pair_moment(vf, wdx, dx), g_xy[l] += pair_moment(vf, wdx, dy);
            g_yx[l] += pair_moment(vf, wdy, dx), g_yy[l] += pair_moment(vf, wdy, dy);
            if (!corrector) {
                const real speed = inside ? pair_viscous_speed(h, nsx, nsy, dx, dy, rhoa + rho_b, inv_denominator) : 0;
                visc_speed_mps[l] = speed > visc_speed_mps[l] ? speed : visc_speed_mps[l];
            } else {
                grad_c_x[l] += vf * dx;
                grad_c_y[l] += vf * dy;
                kernel_w[l] += inside ? kernel2d_w_inside(alpha, inv_h, r) : 0;
            }
        }
    }
    const real zero[PAIR_LANES] = {0};
    const real *const first_eight[8] = {acc_x, acc_y, kernel_w, grad_c_x, grad_c_y, m_xx, m_xy, m_yy};
    const real *const last_four[8] = {g_xx, g_xy, g_yx, g_yy, zero, zero, zero, zero};
    real total[16];
    lanes_totals(first_eight, total);
    lanes_totals(last_four, total + 8);
    s->acc_x += total[0], s->acc_y += total[1], s->kernel_w += total[2];
    s->grad_c_x += total[3], s->grad_c_y += total[4];
    s->m_xx += total[5], s->m_xy += total[6], s->m_yy += total[7];
    s->g_xx += total[8], s->g_xy += total[9], s->g_yx += total[10], s->g_yy += total[11];
    for (int l = 0; l < PAIR_LANES; l++)
        s->visc_speed_mps = visc_speed_mps[l] > s->visc_speed_mps ? visc_speed_mps[l] : s->visc_speed_mps;
}

/* The face of disc i if it is nearer to fluid particle a than face: the disc's circle, its outward normal through
 * the particle, and the disc's velocity along it (turning adds none). */
static void disc_face(const surge_sim *sim, int a, int i, wall_face *face)
{
    const boulder_set *b = &sim->boulders;
    const double period = sim->grid.period_m;
    double dx = sim->x[a] - b->x[i];
    if (period > 0)
        dx -= period * floor(dx / period + 0.5);
    const double dy = sim->y[a] - b->y[i], distance = sqrt(dx * dx + dy * dy);
    const double gap = distance - b->radius[i];
    if (gap < face->gap_m && distance > 0) {
        const double nx = dx / distance, ny = dy / distance;
        *face = (wall_face){(real)gap, (real)nx, (real)ny, (real)(b->vx[i] * nx + b->vy[i] * ny), -1, i};
    }
}

/* The wall face that entry e of fluid particle a's wall list gives (the candidate interaction_wall_face chose) */
static void entry_face(const surge_sim *sim, int a, int64_t e, wall_face *face)
{
    const neighbour_lists *nl = &sim->neighbours;
    const int b = nl->wall_index[e];
    if (sim->wall_of[b] == WALL_BOULDER) {
        disc_face(sim, a, sim->boulders.of_wall[sim->id[b]], face);
        return;
    }
    const real dx = nl->wall_dx0[e] + (nl->moved_x[a] - nl->moved_x[b]);
    const real dy = nl->wall_dy0[e] + (nl->moved_y[a] - nl->moved_y[b]);
    const real along = dx * sim->wall_nx[b] + dy * sim->wall_ny[b];
    *face = (wall_face){along - sim->wall_depth_m[b], sim->wall_nx[b], sim->wall_ny[b],
                        sim->vx[b] * sim->wall_nx[b] + sim->vy[b] * sim->wall_ny[b], b, -1};
}

wall_face interaction_wall_face(const surge_sim *sim, int a, real search_m, int *near_boulder)
{
    const neighbour_lists *nl = &sim->neighbours;
    const real half_dp = (real)(0.5 * sim->params.numerics.dp_m), support2 = sim->kernel.support2;
    const int32_t *restrict index = nl->wall_index;
    const real *restrict dx0 = nl->wall_dx0, *restrict dy0 = nl->wall_dy0;
    const wall_face_state *restrict st = sim->face_state;
    const real mxa = nl->moved_x[a], mya = nl->moved_y[a];
    wall_face face = {search_m, 0, 0, 0, -1, -1};
    const int i = a - sim->wall_count;
    /* Whole vectors over the padded list (records transposed as in fluid_pairs): in each lane the candidate with the
     * smallest gap, the first in list order among equals. A fixed wall's candidate is its face, for a particle on its
     * side of the wall particle (or within dp/2 behind its centre: one behind the wall, come round a periodic channel,
     * is not pushed through the whole wall) within dp/2 of the particle's normal line; a disc's is the disc's circle,
     * its gap here in float from the particle's offset, and exactly (disc_face, in double) for the one chosen. */
    real best_gap[PAIR_LANES];
    int64_t best_entry[PAIR_LANES];
    int32_t boulder[PAIR_LANES];
    for (int l = 0; l < PAIR_LANES; l++)
        best_gap[l] = search_m, best_entry[l] = -1, boulder[l] = 0;
    for (int64_t e0 = nl->wall_first[i]; e0 < nl->wall_first[i + 1]; e0 += PAIR_LANES) {
        lanes_vector field[PAIR_LANES];
        lanes_gather_records(st, index + e0, field); /* field[q][l]: lane l's wall neighbour's q-th field (wall_face_state) */
        #pragma omp simd simdlen(PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            const real dx = dx0[e] + (mxa - field[FACE_MOVED_X][l]), dy = dy0[e] + (mya - field[FACE_MOVED_Y][l]);
            const real r2 = dx * dx + dy * dy;
            const int inside = r2 < support2, disc = field[FACE_DISC][l] >= 0;
            const real along = dx * field[FACE_NX][l] + dy * field[FACE_NY][l];
            const real cx = dx + field[FACE_CENTRE_DX][l], cy = dy + field[FACE_CENTRE_DY][l];
            const real gap = disc ? REAL_SQRT(cx * cx + cy * cy) - field[FACE_REACH][l] : along - field[FACE_REACH][l];
            const int candidate = inside & (disc | ((along > -half_dp) & (r2 - along * along < half_dp * half_dp)));
            const int better = candidate & (gap < best_gap[l]);
            best_gap[l] = better ? gap : best_gap[l];
            best_entry[l] = better ? e : best_entry[l];
            boulder[l] |= inside & disc;
        }
    }
    int64_t chosen = -1;
    real chosen_gap = search_m;
    for (int l = 0; l < PAIR_LANES; l++) {
        *near_boulder |= boulder[l];
        if (best_entry[l] >= 0 && (best_gap[l] < chosen_gap || (best_gap[l] == chosen_gap && best_entry[l] < chosen)))
            chosen = best_entry[l], chosen_gap = best_gap[l];
    }
    if (search_m > 0 && chosen >= 0)
        entry_face(sim, a, chosen, &face);
    return face;
}

wall_face interaction_other_face(const surge_sim *sim, int a, real search_m, const wall_face *nearest)
{
    const neighbour_lists *nl = &sim->neighbours;
    const real half_dp = (real)(0.5 * sim->params.numerics.dp_m), support2 = sim->kernel.support2;
    const int i = a - sim->wall_count;
    wall_face face = {search_m, 0, 0, 0, -1, -1};
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
        const int b = nl->wall_index[e];
        const real dx = nl->wall_dx0[e] + (nl->moved_x[a] - nl->moved_x[b]);
        const real dy = nl->wall_dy0[e] + (nl->moved_y[a] - nl->moved_y[b]);
        if (dx * dx + dy * dy >= support2)
            continue;
        if (sim->wall_of[b] == WALL_BOULDER) {
            const int disc = sim->boulders.of_wall[sim->id[b]];
            if (disc != nearest->disc)
                disc_face(sim, a, disc, &face);
            continue;
        }
        if (nearest->disc < 0) /* a fixed wall's face is the nearest: the other is a disc's */
            continue;
        const real along = dx * sim->wall_nx[b] + dy * sim->wall_ny[b];
        if (along > -half_dp && dx * dx + dy * dy - along * along < half_dp * half_dp &&
            along - sim->wall_depth_m[b] < face.gap_m)
            entry_face(sim, a, e, &face);
    }
    return face;
}

void interaction_compute(surge_sim *sim, int corrector)
{
    const int antuono = sim->params.numerics.density_diffusion_form == SURGE_DIFFUSION_ANTUONO;
    if (antuono)
        compute_density_gradient(sim);
    const pair_constants c = {
        .grad_coef = sim->kernel.grad_coef, .inv_h = sim->kernel.inv_h, .alpha = sim->kernel.alpha,
        .mass = (real)sim->mass, .eta2 = (real)sim->eta2, .h = sim->kernel.h, .support2 = sim->kernel.support2,
        .four_nu = (real)(4.0 * sim->params.fluid.viscosity_m2ps), .rho_h_per_m = (real)sim->rho_h_per_m};
    const real ddt_coef = (real)(2.0 * sim->params.numerics.density_diffusion * sim->derived.h_m * sim->derived.c0_mps);
    const real gx = (real)sim->gx, gy = (real)sim->gy;
    /* relaxation of the density toward the kernel sum in the bulk: kappa per unit strain (corrector pass only) */
    const real relax_per_strain = corrector ? (real)sim->params.numerics.density_relaxation : 0;
    const int relax_near_discs = sim->params.numerics.density_relaxation_near_discs;
    const real mass = c.mass, alpha = c.alpha, inv_lattice_sum = (real)(1.0 / sim->lattice_kernel_sum);
    const real inv_rho0 = (real)(1.0 / sim->rho0);
    /* wall-face repulsion (docs/method.md): none beyond face_reach_m from the face, 0.1 c0^2 / dp at the face */
    const real face_reach_m = (real)sim_contact_reach_m(sim);
    const real face_search_m = face_reach_m > 0 ? (real)sim->params.numerics.dp_m : 0;
    const real surface_threshold = (real)sim->params.shifting.surface_threshold;
    const real face_stiffness = (real)(0.1 * sim->derived.c0_mps * sim->derived.c0_mps / sim->params.numerics.dp_m);

    int begin, end;
    neighbours_fluid_share(sim, &begin, &end);
    for (int a = begin; a < end; a++) {
        particle_sums s;
        if (corrector) {
            if (antuono)
                fluid_pairs(sim, &c, a, 1, 1, &s);
            else
                fluid_pairs(sim, &c, a, 0, 1, &s);
            wall_pairs(sim, &c, a, 1, &s);
        } else {
            if (antuono)
                fluid_pairs(sim, &c, a, 1, 0, &s);
            else
                fluid_pairs(sim, &c, a, 0, 0, &s);
            wall_pairs(sim, &c, a, 0, &s);
        }
        s.near_surface |= sim->surface[a];
        const wall_face face = interaction_wall_face(sim, a, face_search_m, &s.near_boulder);
        sim->face_disc[a] = -1;
        if (face.gap_m < face_reach_m) { /* closer to a wall face than a particle at rest sits: pushed back along
                                          * its normal; the step's update takes away any velocity toward it (sim.c) */
            const real depth = (face_reach_m - face.gap_m) / face_reach_m;
            const real push_x = face_stiffness * depth * depth * face.nx, push_y = face_stiffness * depth * depth * face.ny;
            s.acc_x += push_x;
            s.acc_y += push_y;
            if (face.disc >= 0) /* the disc takes the reaction (boulders.c) */
                sim->face_disc[a] = face.disc, sim->face_push_x[a] = push_x, sim->face_push_y[a] = push_y;
        }
        if (corrector) {
            sim->face_nx[a] = face.nx, sim->face_ny[a] = face.ny, sim->face_gap_m[a] = face.gap_m;
            sim->face_vn_mps[a] = face.vn_mps;
        }
        sim->ax[a] = s.acc_x + gx;
        sim->ay[a] = s.acc_y + gy;
        const real rhoa = sim->rho[a];
        real div_v = -(s.g_xx + s.g_yy);
        const real det = s.m_xx * s.m_yy - s.m_xy * s.m_xy;
        if (sim->params.numerics.continuity_correction && det > (real)0.25) {
            /* div v = tr(G M^-1): exact for linear velocity fields even with a truncated kernel */
            const real inv = (real)1 / det;
            div_v = -inv * (s.g_xx * s.m_yy - s.g_xy * s.m_xy - s.g_yx * s.m_xy + s.g_yy * s.m_xx);
        }
        sim->drho[a] = rhoa * div_v + ddt_coef * s.diffusion;
        /* full kernel support: the kernel sum is the density the spacing says (a disc's particles, laid out at the
         * fluid's spacing, count as the fluid's unless density_relaxation_near_discs is off) */
        if (relax_per_strain > 0 && !s.near_surface && (relax_near_discs || !s.near_boulder)) {
            /* at the rate kappa |2D|, D = sym(G) the strain rate (M = I in the bulk): where the fluid deforms, since
             * deformation is what moves spacing and density apart; a fluid at rest keeps its densities */
            const real shear = s.g_xy + s.g_yx;
            const real strain_rate = REAL_SQRT((real)2 * (s.g_xx * s.g_xx + s.g_yy * s.g_yy) + shear * shear);
            const real kernel_sum = mass * (alpha + s.kernel_w); /* sum_b m W_ab, the particle itself included */
            sim->drho[a] += relax_per_strain * strain_rate * (kernel_sum * inv_lattice_sum - rhoa);
        }
        sim->div_r[a] = s.m_xx + s.m_yy;
        if (!corrector) { /* the time step follows the predictor's pass, and the surface flags (read above, and by
                           * the other particles from their pair_state copies) */
            sim->visc_speed_mps[a] = s.visc_speed_mps;
            sim->surface[a] = sim->div_r[a] < surface_threshold;
        } else { /* surface[] is set at the end of the predictor pass, after this step's sort */
            sim->grad_c_x[a] = s.grad_c_x;
            sim->grad_c_y[a] = s.grad_c_y;
            sim->near_surface[a] = (uint8_t)s.near_surface;
            sim->kernel_ratio[a] = mass * (alpha + s.kernel_w) * inv_lattice_sum * inv_rho0;
        }
    }
    #pragma omp barrier
}
