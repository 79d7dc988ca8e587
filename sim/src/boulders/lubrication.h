/* The lubrication force of a thin fluid gap between two discs, or a disc and a wall, in 2D (per metre of width).
 * Reynolds' equation for the squeeze film, d/dx (h^3 dp/dx) = 12 mu dh/dt, with the gap near its narrowest point
 * h(x) = h0 + x^2 / (2 R), R = r_a r_b / (r_a + r_b) (a wall: R = r), gives the pressure p = 6 mu U R / h(x)^2 and
 * the normal force F = 3 sqrt(2) pi mu U (R / h0)^(3/2) for the approach speed U (docs/boulders.md, "Lubrication").
 * The SPH resolves the film down to about a particle spacing, so only the part above the force at the cut-off gap is
 * added: c(h) = 3 sqrt(2) pi mu [(R / max(h, h_min))^(3/2) - (R / h_c)^(3/2)] for h < h_c, F = -c U.
 * Sliding: with the surfaces moving past each other at U_t, Couette flow in the gap and the pressure that keeps its
 * flux the same along it give each surface the shear force 2 sqrt(2) pi mu U_t (R / h0)^(1/2), which on a disc the
 * pressure on its curved face cancels: a torque 2 sqrt(2) pi mu U_t r (R / h0)^(1/2) about its centre and no force
 * at this order (docs/boulders.md, "Lubrication"); its unresolved part is taken the same way. */
#ifndef SURGE_LUBRICATION_H
#define SURGE_LUBRICATION_H

#include <math.h>

/* The squeeze film's force per unit approach speed (N s m^-2 per metre of width) at gap h0: 3 sqrt(2) pi mu
 * (R / h0)^(3/2) */
static inline double lubrication_film_damping(double viscosity_pa_s, double radius_m, double gap_m)
{
    const double ratio = radius_m / gap_m;
    return 3.0 * sqrt(2.0) * 3.14159265358979323846 * viscosity_pa_s * ratio * sqrt(ratio);
}

/* The sliding film's shear force per unit relative surface speed at gap h0: 2 sqrt(2) pi mu (R / h0)^(1/2) */
static inline double lubrication_sliding_film_damping(double viscosity_pa_s, double radius_m, double gap_m)
{
    return 2.0 * sqrt(2.0) * 3.14159265358979323846 * viscosity_pa_s * sqrt(radius_m / gap_m);
}

/* The part of a film's damping the SPH does not resolve: 0 at and beyond the cut-off gap, the film's value less its
 * value at the cut-off below it, the gap taken at least min_gap_m */
static inline double lubrication_unresolved(double (*film)(double, double, double), double viscosity_pa_s,
                                            double radius_m, double gap_m, double cutoff_m, double min_gap_m)
{
    if (!(gap_m < cutoff_m) || !(viscosity_pa_s > 0) || !(radius_m > 0))
        return 0.0;
    return film(viscosity_pa_s, radius_m, fmax(gap_m, min_gap_m)) - film(viscosity_pa_s, radius_m, cutoff_m);
}

/* The squeeze film's unresolved part */
static inline double lubrication_damping(double viscosity_pa_s, double radius_m, double gap_m, double cutoff_m,
                                         double min_gap_m)
{
    return lubrication_unresolved(lubrication_film_damping, viscosity_pa_s, radius_m, gap_m, cutoff_m, min_gap_m);
}

/* The exact Stokes resistance of a cylinder of radius R approaching a plane at gap h0 (per unit approach speed and
 * metre of width): 4 pi mu / (alpha - tanh alpha), cosh alpha = 1 + h0 / R (Jeffrey & Onishi 1981); near contact
 * the squeeze film's 3 sqrt(2) pi mu (R / h0)^(3/2). A pair of discs takes its reduced radius R. (lubrication.c) */
double lubrication_exact_damping(double viscosity_pa_s, double radius_m, double gap_m);

/* The share of the exact resistance a scheme resolves at gap h0 = x h (h the kernel's smoothing length), measured
 * with a disc settling onto the bed (docs/boulders.md, "What the SPH resolves of a squeeze film"): a table at x = 0,
 * LUBRICATION_RESOLVED_STEP, ..., LUBRICATION_RESOLVED_END that each scheme holds (time_scheme's film_share),
 * linear between its points and 1 from x = LUBRICATION_RESOLVED_END on */
#define LUBRICATION_RESOLVED_STEP 0.125
#define LUBRICATION_RESOLVED_POINTS 25
#define LUBRICATION_RESOLVED_END (LUBRICATION_RESOLVED_STEP * (LUBRICATION_RESOLVED_POINTS - 1))
typedef struct lubrication_share {
    double at[LUBRICATION_RESOLVED_POINTS];
} lubrication_share;
double lubrication_resolved_share(const lubrication_share *share, double gap_over_h);

/* The squeeze film's unresolved part, measured: the exact resistance less the share the scheme resolves, at the gap
 * taken at least min_gap_m; 0 from LUBRICATION_RESOLVED_END kernel lengths on */
double lubrication_measured_damping(const lubrication_share *share, double viscosity_pa_s, double radius_m,
                                    double gap_m, double kernel_h_m, double min_gap_m);

/* The tangential film (contacts.lubrication_tangential = reynolds). Reynolds' equation in a gap h(x) = h0 + x^2/(2R)
 * whose shape moves with the discs, d/dx (h^3 p'/(12 mu)) = dh/dt + d/dx (h (u_T + u_B)/2), for discs T and B on
 * either side (centres' velocities U_T, U_B along the gap's tangent t, spins Omega_T, Omega_B, surface speeds at the
 * gap u_T = U_T + r_T Omega_T, u_B = U_B - r_B Omega_B, t and the normal from B to T right-handed) gives, with
 * S = pi mu (2 R / h0)^(1/2) and V = R (U_T/r_T + U_B/r_B) - (u_T + u_B)/2 (the pressure p' = 12 mu V (4 h0/3 - h)/h^3
 * and the shear of the Couette and Poiseuille parts, integrated; docs/boulders.md, "The tangential film"):
 *   F_T = S [2V - (u_T - u_B) - 4 V R/r_T],  T_T = r_T S [2V - (u_T - u_B)],
 *   F_B = S [2V + (u_T - u_B) - 4 V R/r_B],  T_B = -r_B S [2V + (u_T - u_B)].
 * -dF/d(U, Omega) is symmetric and positive semidefinite, zero for a common translation and for the pair turning as
 * one body; by a wall at rest (r_B -> infinity) it is diagonal: F = -2 S U, T = -2 S r^2 Omega (2 S = 2 sqrt(2) pi mu
 * (R/h0)^(1/2)). This writes it into K (rows and columns U_T, Omega_T, U_B, Omega_B; wall: r_B <= 0, the last two
 * zero). */
static inline void lubrication_tangential_matrix(double S, double r_T, double r_B, double K[4][4])
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            K[i][j] = 0;
    if (!(r_B > 0)) {
        K[0][0] = 2 * S, K[1][1] = 2 * S * r_T * r_T;
        return;
    }
    const double sum = r_T + r_B, sum2 = sum * sum;
    K[0][0] = K[2][2] = 2 * S * (r_B * r_B + r_T * r_T) / sum2;
    K[0][1] = K[1][0] = 2 * S * r_T * r_T / sum;
    K[0][2] = K[2][0] = -2 * S * (r_B * (r_B - r_T) + r_T * (r_B + r_T)) / sum2;
    K[0][3] = K[3][0] = 2 * S * r_B * r_B / sum;
    K[1][1] = 2 * S * r_T * r_T;
    K[1][2] = K[2][1] = -2 * S * r_T * r_T / sum;
    K[2][3] = K[3][2] = -2 * S * r_B * r_B / sum;
    K[3][3] = 2 * S * r_B * r_B;
}

/* The tangential film's S (N s m^-2 per metre of width) less the share the scheme resolves: the exact
 * excess torque of a cylinder turning by a plane, 4 pi mu R^2 (coth alpha - 1) with cosh alpha = 1 + h0/R (Jeffery
 * 1922), over 2 R^2, which near contact is pi mu (2 R/h0)^(1/2), times 1 - s(h0/h), s the squeeze film's measured
 * share (lubrication_resolved_share; the tangential film's own share is not measured); 0 from
 * LUBRICATION_RESOLVED_END kernel lengths on, the gap taken at least min_gap_m. (lubrication.c) */
double lubrication_tangential_damping(const lubrication_share *share, double viscosity_pa_s, double radius_m,
                                      double gap_m, double kernel_h_m, double min_gap_m);

/* The sliding film's unresolved part */
static inline double lubrication_sliding_damping(double viscosity_pa_s, double radius_m, double gap_m, double cutoff_m,
                                                 double min_gap_m)
{
    return lubrication_unresolved(lubrication_sliding_film_damping, viscosity_pa_s, radius_m, gap_m, cutoff_m,
                                  min_gap_m);
}

#endif
