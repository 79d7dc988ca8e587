/* Quintic Wendland kernel (GMD eq. 9), 2D. */
#ifndef SURGE_KERNEL_H
#define SURGE_KERNEL_H

#include <math.h>

#include "precision.h"

#define SURGE_PI 3.14159265358979323846

typedef struct kernel2d {
    real h;          /* smoothing length */
    real inv_h;
    real support2;   /* (2h)^2 */
    real alpha;      /* 7 / (4 pi h^2) */
    real grad_coef;  /* -5 alpha / h^2: grad_a W = grad_coef (1 - q/2)^3 r_ab */
} kernel2d;

static inline kernel2d kernel2d_make(double h)
{
    kernel2d k;
    double alpha = 7.0 / (4.0 * SURGE_PI * h * h);
    k.h = (real)h;
    k.inv_h = (real)(1.0 / h);
    k.support2 = (real)(4.0 * h * h);
    k.alpha = (real)alpha;
    k.grad_coef = (real)(-5.0 * alpha / (h * h));
    return k;
}

/* W(q) = alpha (1 - q/2)^4 (2q + 1), q = r/h in [0, 2]  (eq. 9), for r already known to lie within 2h, from the
 * kernel's constants (hot loops) */
static inline real kernel2d_w_inside(real alpha, real inv_h, real r)
{
    const real q = r * inv_h;
    const real t = (real)1 - (real)0.5 * q;
    const real t2 = t * t;
    return alpha * t2 * t2 * ((real)2 * q + (real)1);
}

/* W at any distance (zero beyond 2h) */
static inline real kernel2d_w(const kernel2d *k, real r)
{
    return r * k->inv_h >= (real)2 ? 0 : kernel2d_w_inside(k->alpha, k->inv_h, r);
}

/* F such that grad_a W_ab = F r_ab, r_ab = r_a - r_b: F = -5 alpha (1 - q/2)^3 / h^2 (zero beyond 2h). */
static inline real kernel2d_grad_factor(const kernel2d *k, real r)
{
    real q = r * k->inv_h;
    if (q >= (real)2)
        return 0;
    real t = (real)1 - (real)0.5 * q;
    return k->grad_coef * t * t * t;
}

/* The same for r already known to lie within 2h, from the kernel's constants (hot loops). */
static inline real kernel2d_grad_factor_inside(real grad_coef, real inv_h, real r)
{
    const real t = (real)1 - (real)0.5 * r * inv_h;
    return grad_coef * t * t * t;
}

#endif
