/* The measured squeeze film (contacts.lubrication_resolved = measured; lubrication.h): out of line, so that the
 * cut-off model's arithmetic, inline in the contact solver, compiles as it did. */
#include "lubrication.h"

#include <math.h>

/* Near contact alpha - tanh alpha -> alpha^3 / 3 and alpha^2 -> 2 h0 / R: the film's 3 sqrt(2) pi mu (R / h0)^(3/2) */
double lubrication_exact_damping(double viscosity_pa_s, double radius_m, double gap_m)
{
    const double e = gap_m / radius_m, alpha = log1p(e + sqrt(e * (2.0 + e)));
    const double a2 = alpha * alpha; /* alpha - tanh alpha by its series where the difference cancels */
    const double denominator =
        alpha < 0.1 ? alpha * a2 * (1.0 / 3.0 - a2 * (2.0 / 15.0 - a2 * (17.0 / 315.0 - a2 * 62.0 / 2835.0)))
                    : alpha - tanh(alpha);
    return 4.0 * 3.14159265358979323846 * viscosity_pa_s / denominator;
}

double lubrication_resolved_share(const lubrication_share *share, double gap_over_h)
{
    if (!(gap_over_h < LUBRICATION_RESOLVED_END))
        return 1.0;
    const double at = fmax(gap_over_h, 0.0) / LUBRICATION_RESOLVED_STEP;
    const int k = (int)at;
    return share->at[k] + (at - k) * (share->at[k + 1] - share->at[k]);
}

double lubrication_tangential_damping(const lubrication_share *share, double viscosity_pa_s, double radius_m,
                                      double gap_m, double kernel_h_m, double min_gap_m)
{
    if (!(viscosity_pa_s > 0) || !(radius_m > 0) || !(gap_m < LUBRICATION_RESOLVED_END * kernel_h_m))
        return 0.0;
    const double gap = fmax(gap_m, min_gap_m), e = gap / radius_m, alpha = log1p(e + sqrt(e * (2.0 + e)));
    return (1.0 - lubrication_resolved_share(share, gap / kernel_h_m)) * 2.0 * 3.14159265358979323846 * viscosity_pa_s *
           (1.0 / tanh(alpha) - 1.0);
}

double lubrication_measured_damping(const lubrication_share *share, double viscosity_pa_s, double radius_m,
                                    double gap_m, double kernel_h_m, double min_gap_m)
{
    if (!(viscosity_pa_s > 0) || !(radius_m > 0) || !(gap_m < LUBRICATION_RESOLVED_END * kernel_h_m))
        return 0.0;
    const double gap = fmax(gap_m, min_gap_m);
    return (1.0 - lubrication_resolved_share(share, gap / kernel_h_m)) *
           lubrication_exact_damping(viscosity_pa_s, radius_m, gap);
}
