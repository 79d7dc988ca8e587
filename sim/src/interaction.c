/* Rates of change of the fluid particles: continuity with density diffusion (GMD eq. 6; Fourtakas' form or
 * Antuono's), momentum with pressure, laminar viscosity and body force (eq. 7), plus what the time step and
 * shifting need. */
#include <math.h>

#include "eos.h"
#include "pair_terms.h"
#include "sim_internal.h"

static void compute_pressure(surge_sim *sim)
{
    const real rho0 = (real)sim->rho0, b = (real)sim->b_pa;
    #pragma omp parallel for schedule(static)
    for (int i = 0; i < sim->count; i++) {
        sim->pressure[i] = tait_pressure(sim->rho[i], rho0, b);
        sim->inv_rho[i] = (real)1 / sim->rho[i];
    }
}

/* Antuono et al. (2010) renormalised density gradient over the fluid neighbours,
 * <grad rho>_a = M_a^-1 sum_b (rho_b - rho_a) grad_a W_ab V_b, exact for a linear density field even where the
 * kernel is truncated. Where M is nearly singular (an isolated particle) the gradient is taken as zero. */
static void compute_density_gradient(surge_sim *sim)
{
    const neighbour_lists *nl = &sim->neighbours;
    const double period = sim->grid.period_m;
    const real grad_coef = sim->kernel.grad_coef, inv_h = sim->kernel.inv_h, mass = (real)sim->mass;
    const real support2 = sim->kernel.support2;
    const double *restrict x = sim->x, *restrict y = sim->y;
    const real *restrict rho = sim->rho, *restrict inv_rho = sim->inv_rho;
    #pragma omp parallel for schedule(static)
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double xa = x[a], ya = y[a];
        const real rhoa = rho[a];
        real m_xx = 0, m_xy = 0, m_yy = 0, sum_x = 0, sum_y = 0;
        const int i = a - sim->wall_count;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
            const int b = nl->fluid_index[e];
            const real dx = (real)(xa - nl->fluid_image[e] * period - x[b]), dy = (real)(ya - y[b]);
            const real r2 = dx * dx + dy * dy;
            if (r2 >= support2 || r2 == 0)
                continue;
            const real vf = mass * inv_rho[b] * kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2));
            m_xx -= vf * dx * dx, m_xy -= vf * dx * dy, m_yy -= vf * dy * dy;
            sum_x += (rho[b] - rhoa) * vf * dx, sum_y += (rho[b] - rhoa) * vf * dy;
        }
        const real det = m_xx * m_yy - m_xy * m_xy;
        const real inv_det = det > (real)0.25 ? (real)1 / det : 0;
        sim->grad_rho_x[a] = inv_det * (m_yy * sum_x - m_xy * sum_y);
        sim->grad_rho_y[a] = inv_det * (m_xx * sum_y - m_xy * sum_x);
    }
}

void interaction_compute(surge_sim *sim, int corrector)
{
    compute_pressure(sim);
    const int antuono = sim->params.numerics.density_diffusion_form == SURGE_DIFFUSION_ANTUONO;
    if (antuono)
        compute_density_gradient(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const double period = sim->grid.period_m;
    const real grad_coef = sim->kernel.grad_coef, inv_h = sim->kernel.inv_h;
    const real mass = (real)sim->mass, eta2 = (real)sim->eta2, h = sim->kernel.h;
    const real support2 = sim->kernel.support2;
    const real four_nu = (real)(4.0 * sim->params.fluid.viscosity_m2ps);
    const real ddt_coef = (real)(2.0 * sim->params.numerics.density_diffusion * sim->derived.h_m * sim->derived.c0_mps);
    const real rho_h_per_m = (real)sim->rho_h_per_m;
    const real gx = (real)sim->gx, gy = (real)sim->gy;
    const double *restrict x = sim->x, *restrict y = sim->y;
    const real *restrict vx = sim->vx, *restrict vy = sim->vy, *restrict rho = sim->rho;
    const real *restrict inv_rho = sim->inv_rho, *restrict pres = sim->pressure;
    const real *restrict wall_vx = sim->wall_vx, *restrict wall_vy = sim->wall_vy;
    const real *restrict cont_vx = sim->wall_cont_vx, *restrict cont_vy = sim->wall_cont_vy;
    const real *restrict grad_rho_x = sim->grad_rho_x, *restrict grad_rho_y = sim->grad_rho_y;
    const uint8_t *restrict surface = sim->surface, *restrict wall_of = sim->wall_of;
    /* relaxation of the density toward the kernel sum in the bulk: kappa per unit strain (corrector pass only) */
    const real relax_per_strain = corrector ? (real)sim->params.numerics.density_relaxation : 0;
    const real alpha = sim->kernel.alpha, inv_lattice_sum = (real)(1.0 / sim->lattice_kernel_sum);
    /* wall-face repulsion (docs/method.md): none beyond face_reach_m from the face, 0.1 c0^2 / dp at the face */
    const real half_dp = (real)(0.5 * sim->params.numerics.dp_m);
    const real face_reach_m = (real)(sim->params.walls.face_repulsion_reach_dp * sim->params.numerics.dp_m);
    const real face_search_m = face_reach_m > 0 ? (real)sim->params.numerics.dp_m : 0;
    const real face_stiffness = (real)(0.1 * sim->derived.c0_mps * sim->derived.c0_mps / sim->params.numerics.dp_m);
    const real *restrict wall_nx = sim->wall_nx, *restrict wall_ny = sim->wall_ny, *restrict wall_depth_m = sim->wall_depth_m;

    /* Each particle gathers over its neighbours in a fixed order, so results do not depend on the thread count.
     * (A branch-free, vectorised form of these loops measured 2x slower: most candidates lie beyond 2h.) */
    #pragma omp parallel for schedule(static)
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double xa = x[a], ya = y[a];
        const real vxa = vx[a], vya = vy[a], rhoa = rho[a], pa = pres[a], inv_rhoa = inv_rho[a];
        real acc_x = 0, acc_y = 0, div_v = 0, diffusion = 0, visc_speed_mps = 0;
        real kernel_sum = mass * alpha; /* sum_b m W_ab, the particle itself included */
        real face_m = face_search_m, face_nx = 0, face_ny = 0; /* the nearest wall face straight below, its normal */
        int face_b = -1;
        real grad_c_x = 0, grad_c_y = 0, div_r = 0;
        pair_moments moments = {0};
        int near_surface = surface[a], near_boulder = 0;
        const int i = a - sim->wall_count;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
            const int b = nl->fluid_index[e];
            const real dx = (real)(xa - nl->fluid_image[e] * period - x[b]), dy = (real)(ya - y[b]);
            const real r2 = dx * dx + dy * dy;
            if (r2 >= support2 || r2 == 0)
                continue;
            const real f = kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2)); /* grad_a W = f r_ab */
            const real vol = mass * inv_rho[b], vf = vol * f;
            const real dvx = vxa - vx[b], dvy = vya - vy[b];
            const real pressure_coef = pair_pressure_coef(mass, pa, pres[b], inv_rhoa, inv_rho[b]);
            const real viscous_coef = pair_viscous_coef(mass, four_nu, f, r2, rhoa, rho[b], eta2);
            acc_x += pair_acceleration(pressure_coef, f, dx, viscous_coef, dvx);
            acc_y += pair_acceleration(pressure_coef, f, dy, viscous_coef, dvy);
            div_v += pair_divergence(vf, dvx, dvy, dx, dy);
            pair_add_moments(&moments, vf, dx, dy, dvx, dvy);
            const real linear_part = antuono ? pair_gradient_part(grad_rho_x[a], grad_rho_y[a], grad_rho_x[b],
                                                                  grad_rho_y[b], dx, dy)
                                             : pair_hydrostatic_part(rho_h_per_m, dy);
            diffusion -= pair_diffusion(rhoa, rho[b], linear_part, f, vol);
            const real speed = pair_viscous_speed(h, dvx, dvy, dx, dy, r2, eta2);
            visc_speed_mps = speed > visc_speed_mps ? speed : visc_speed_mps;
            grad_c_x += vf * dx;
            grad_c_y += vf * dy;
            div_r -= vf * r2;
            near_surface |= surface[b];
            if (relax_per_strain > 0)
                kernel_sum += mass * kernel2d_w_inside(alpha, inv_h, REAL_SQRT(r2));
        }
        /* wall neighbours: mDBC pressure; no-slip velocity in the viscous term, wall velocity in
         * continuity; no density diffusion across the wall */
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
            const int b = nl->wall_index[e];
            const real dx = (real)(xa - nl->wall_image[e] * period - x[b]), dy = (real)(ya - y[b]);
            const real r2 = dx * dx + dy * dy;
            if (r2 >= support2)
                continue;
            const real f = kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2));
            const real vol = mass * inv_rho[b], vf = vol * f;
            const real pressure_coef = pair_pressure_coef(mass, pa, pres[b], inv_rhoa, inv_rho[b]);
            const real viscous_coef = pair_viscous_coef(mass, four_nu, f, r2, rhoa, rho[b], eta2);
            const real nsx = vxa - wall_vx[b], nsy = vya - wall_vy[b];
            acc_x += pair_acceleration(pressure_coef, f, dx, viscous_coef, nsx);
            acc_y += pair_acceleration(pressure_coef, f, dy, viscous_coef, nsy);
            /* distance to the face of the wall particle straight below (within dp/2 of its normal line); not
             * a boulder's, whose disc would have to take the reaction */
            const real along = dx * wall_nx[b] + dy * wall_ny[b];
            if (face_search_m > 0 && r2 - along * along < half_dp * half_dp && along - wall_depth_m[b] < face_m &&
                wall_of[b] != WALL_BOULDER) {
                face_m = along - wall_depth_m[b];
                face_nx = wall_nx[b], face_ny = wall_ny[b], face_b = b;
            }
            const real wdx = vxa - cont_vx[b], wdy = vya - cont_vy[b];
            div_v += pair_divergence(vf, wdx, wdy, dx, dy);
            pair_add_moments(&moments, vf, dx, dy, wdx, wdy);
            const real speed = pair_viscous_speed(h, nsx, nsy, dx, dy, r2, eta2);
            visc_speed_mps = speed > visc_speed_mps ? speed : visc_speed_mps;
            grad_c_x += vf * dx;
            grad_c_y += vf * dy;
            div_r -= vf * r2;
            near_boulder |= wall_of[b] == WALL_BOULDER;
            if (relax_per_strain > 0)
                kernel_sum += mass * kernel2d_w_inside(alpha, inv_h, REAL_SQRT(r2));
        }
        if (face_m < face_reach_m) { /* closer to a wall face than a particle at rest sits: pushed back along its
                                      * normal; the step's update takes away any velocity toward it (sim.c) */
            const real depth = (face_reach_m - face_m) / face_reach_m;
            acc_x += face_stiffness * depth * depth * face_nx;
            acc_y += face_stiffness * depth * depth * face_ny;
        }
        if (corrector) {
            sim->face_nx[a] = face_nx, sim->face_ny[a] = face_ny, sim->face_gap_m[a] = face_m;
            sim->face_vn_mps[a] = face_b >= 0 ? vx[face_b] * face_nx + vy[face_b] * face_ny : 0;
        }
        sim->ax[a] = acc_x + gx;
        sim->ay[a] = acc_y + gy;
        const pair_moments *mo = &moments;
        const real det = mo->m_xx * mo->m_yy - mo->m_xy * mo->m_xy;
        if (sim->params.numerics.continuity_correction && det > (real)0.25) {
            /* div v = tr(G M^-1): exact for linear velocity fields even with a truncated kernel */
            const real inv = (real)1 / det;
            div_v = -inv * (mo->g_xx * mo->m_yy - mo->g_xy * mo->m_xy - mo->g_yx * mo->m_xy + mo->g_yy * mo->m_xx);
        }
        sim->drho[a] = rhoa * div_v + ddt_coef * diffusion;
        /* full kernel support, and no boulder's particles (their spacing along a curved surface is not the fluid's):
         * the kernel sum is the density the spacing says */
        if (relax_per_strain > 0 && !near_surface && !near_boulder) {
            /* at the rate kappa |2D|, D = sym(G) the strain rate (M = I in the bulk): where the fluid deforms, since
             * deformation is what moves spacing and density apart; a fluid at rest keeps its densities */
            const real shear = mo->g_xy + mo->g_yx;
            const real strain_rate = REAL_SQRT((real)2 * (mo->g_xx * mo->g_xx + mo->g_yy * mo->g_yy) + shear * shear);
            sim->drho[a] += relax_per_strain * strain_rate * (kernel_sum * inv_lattice_sum - rhoa);
        }
        sim->visc_speed_mps[a] = visc_speed_mps;
        sim->div_r[a] = div_r;
        sim->grad_c_x[a] = grad_c_x;
        sim->grad_c_y[a] = grad_c_y;
        if (corrector) /* surface[] is set at the end of the predictor pass, after this step's sort */
            sim->near_surface[a] = (uint8_t)near_surface;
    }
    if (!corrector) {
        const real threshold = (real)sim->params.shifting.surface_threshold;
        #pragma omp parallel for schedule(static)
        for (int a = sim->wall_count; a < sim->count; a++)
            sim->surface[a] = sim->div_r[a] < threshold;
    }
}
