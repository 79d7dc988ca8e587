/* Random sequential placement of discs, shared by the random placement (boulders.c) and the debris surge's graded one
 * (boulder_scene.c). */
#ifndef SURGE_PLACEMENT_H
#define SURGE_PLACEMENT_H

/* Draws a candidate centre for a disc of radius r_m: 0, or -1 for a draw outside the region (it counts as a try) */
typedef int (*placement_draw)(void *context, double r_m, unsigned short rng[3], double *x_m, double *y_m);

/* Places the discs of radii_m[0..n) (largest first), each at the first candidate draw() gives that overlaps none placed
 * before it with gap_m between (x periodic when period_m > 0), within max_tries draws in all; a centre is stored
 * wrapped into the period when wrap is set. Returns how many were placed (n: all). */
int placement_sequential(const double *radii_m, int n, double gap_m, double period_m, int wrap, placement_draw draw,
                         void *context, unsigned short rng[3], long max_tries, double *x_m, double *y_m);

/* dx brought into [-period/2, period/2) when period_m > 0 */
double placement_wrap_dx(double dx, double period_m);

#endif
