/* The SPH terms of one particle pair, each written once (the pattern of SWIFT's hydro_iact.h) and used by every
 * loop that needs it: fluid-fluid and fluid-wall (interaction.c), the fluid's force on boulder particles
 * (boulders.c, whose exact momentum exchange, eq. 10, rests on using the same terms), shifting (shifting.c).
 * Notation: a the particle being updated, b its neighbour, r_ab = r_a - r_b = (dx, dy), v_ab = v_a - v_b,
 * grad_a W_ab = f r_ab (kernel.h), V_b = m / rho_b. */
#ifndef SURGE_PAIR_TERMS_H
#define SURGE_PAIR_TERMS_H

#include "precision.h"

/* Momentum, pressure: dv_a/dt += P_ab f r_ab, P_ab = -m (P_a + P_b) / (rho_a rho_b)  (eq. 7) */
static inline real pair_pressure_coef(real mass, real p_a, real p_b, real inv_rho_a, real inv_rho_b)
{
    return -mass * (p_a + p_b) * inv_rho_a * inv_rho_b;
}

/* 1 / ((rho_a + rho_b)(r^2 + eta^2)): the one division of a pair, shared by its viscous terms */
static inline real pair_viscous_denominator(real rho_a, real rho_b, real r2, real eta2)
{
    return (real)1 / ((rho_a + rho_b) * (r2 + eta2));
}

/* Momentum, laminar viscosity: dv_a/dt += V_ab v_ab, V_ab = 4 m nu f r^2 / ((rho_a + rho_b)(r^2 + eta^2))  (eq. 7),
 * inv_denominator from pair_viscous_denominator */
static inline real pair_viscous_coef(real mass, real four_nu, real f, real r2, real inv_denominator)
{
    return mass * four_nu * f * r2 * inv_denominator;
}

/* One component of the pair's acceleration of a: P_ab f r_ab + V_ab v_ab  (eq. 7) */
static inline real pair_acceleration(real pressure_coef, real f, real r_component, real viscous_coef,
                                     real v_component)
{
    return pressure_coef * f * r_component + viscous_coef * v_component;
}

/* V_b f v_ab . r_ab: the pair's part of div v (with the sign of -sum V_b v_ab . grad W), the continuity equation's
 * d rho_a/dt = rho_a sum_b V_b f v_ab . r_ab  (eq. 6); also the divergence of a shifting displacement field */
static inline real pair_divergence(real vol_f, real dvx, real dvy, real dx, real dy)
{
    return vol_f * (dvx * dx + dvy * dy);
}

/* Density diffusion, delta-SPH: the pair's part of sum_b (rho_b - rho_a - linear part) f V_b, whose negative times
 * 2 delta h c0 is added to d rho_a/dt  (eq. 6); the linear part is pair_hydrostatic_part (Fourtakas) or
 * pair_gradient_part (Antuono) */
static inline real pair_diffusion(real rho_a, real rho_b, real linear_part, real f, real vol)
{
    return (rho_b - rho_a - linear_part) * f * vol;
}

/* Fourtakas et al. (2019): the hydrostatic density difference rho0 g_n / c0^2 dy */
static inline real pair_hydrostatic_part(real rho_h_per_m, real dy)
{
    return rho_h_per_m * dy;
}

/* Antuono et al. (2010): -(grad rho_a + grad rho_b) . r_ab / 2 from the renormalised density gradients */
static inline real pair_gradient_part(real grad_x_a, real grad_y_a, real grad_x_b, real grad_y_b, real dx, real dy)
{
    return (real)-0.5 * ((grad_x_a + grad_x_b) * dx + (grad_y_a + grad_y_b) * dy);
}

/* |h v_ab . r_ab / (r^2 + eta^2)|, a speed: its largest over the pairs sets the viscous time-step limit dt_cv
 * (inv_denominator from pair_viscous_denominator) */
static inline real pair_viscous_speed(real h, real dvx, real dvy, real dx, real dy, real rho_sum,
                                      real inv_denominator)
{
    return REAL_FABS(h * (dvx * dx + dvy * dy) * rho_sum * inv_denominator);
}

/* One entry of the kernel moment M = -sum V_b f r_ab (x) r_ab (u = r_ab) or of the velocity gradient
 * G = -sum V_b f v_ab (x) r_ab (u = v_ab): -V_b f u_i r_j. M^-1 renormalises div v = tr(G M^-1) (docs/method.md),
 * and sym(G) is the strain rate of the density relaxation. */
static inline real pair_moment(real vol_f, real u_i, real r_j)
{
    return -vol_f * u_i * r_j;
}

#endif
