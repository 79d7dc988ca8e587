/* Random sequential placement of discs (placement.h). */
#include <math.h>

#include "boulders/placement.h"

double placement_wrap_dx(double dx, double period_m)
{
    return period_m > 0 ? dx - period_m * floor(dx / period_m + 0.5) : dx;
}

int placement_sequential(const double *radii_m, int n, double gap_m, double period_m, int wrap, placement_draw draw,
                         void *context, unsigned short rng[3], long max_tries, double *x_m, double *y_m)
{
    long tries = 0;
    for (int i = 0; i < n; i++) {
        const double r = radii_m[i];
        int placed = 0;
        while (!placed && tries < max_tries) {
            tries++;
            double x, y;
            if (draw(context, r, rng, &x, &y) != 0)
                continue;
            placed = 1;
            for (int j = 0; j < i && placed; j++) {
                const double dx = placement_wrap_dx(x - x_m[j], period_m), dy = y - y_m[j];
                const double reach = r + radii_m[j] + gap_m;
                placed = dx * dx + dy * dy >= reach * reach;
            }
            if (placed) {
                x_m[i] = wrap && period_m > 0 ? x - period_m * floor(x / period_m) : x;
                y_m[i] = y;
            }
        }
        if (!placed)
            return i;
    }
    return n;
}
