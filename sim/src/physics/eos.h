/* Tait equation of state (GMD eq. 3). */
#ifndef SURGE_EOS_H
#define SURGE_EOS_H

#include <math.h>

#include "precision.h"

/* Tait: P = B ((rho/rho0)^gamma - 1), B = c0^2 rho0 / gamma, gamma = 7  (eq. 3) */
static inline real tait_pressure(real rho, real rho0, real b_pa)
{
    real ratio = rho / rho0;
    real r2 = ratio * ratio;
    real r3 = r2 * ratio;
    return b_pa * (r3 * r3 * ratio - (real)1);
}

/* Inverse of tait_pressure. */
static inline double tait_density(double p_pa, double rho0, double b_pa)
{
    return rho0 * pow(1.0 + p_pa / b_pa, 1.0 / 7.0);
}

#endif
