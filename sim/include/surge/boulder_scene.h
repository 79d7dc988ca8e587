/* The boulders of a debris-flow surge as data (GMD 2025 Sect. 3.3, Fig. 6): sizes drawn from a grading curve,
 * centres drawn log-normally behind the front and uniformly over the depth, without overlap, from a seed; and
 * the disc list as CSV, which a run writes next to its outputs (boulders.csv) and a case loads back
 * (boulders.placement = file). Usable without building a simulation (docs/boulders.md). */
#ifndef SURGE_BOULDER_SCENE_H
#define SURGE_BOULDER_SCENE_H
#include <stddef.h>

#include "surge/params.h"

typedef struct surge_disc {
    double x_m, y_m, r_m;
    double vx_mps, vy_mps, omega_radps;
} surge_disc;

/* A grading curve: diameters (m, increasing) and the fraction passing at each (non-decreasing, in [0, 1]). */
typedef struct surge_grading surge_grading;

/* Reads a CSV with the header diameter_m,fraction_passing (lines starting with # are comments); path NULL or ""
 * gives the built-in stand-in curve (docs/boulders.md). NULL with the file, line and problem in err. */
surge_grading *surge_grading_load(const char *path, char *err, size_t err_len);
void surge_grading_free(surge_grading *grading);
/* Fraction passing at diameter d (linear between the curve's points, 0 below and 1 above them). */
double surge_grading_passing(const surge_grading *grading, double diameter_m);
/* The diameter at which the curve truncated to [d_min, d_max] reaches u in [0, 1] (inverse CDF sampling);
 * NaN when the curve holds nothing in that range. */
double surge_grading_inverse(const surge_grading *grading, double d_min_m, double d_max_m, double u);

/* The discs of placement = graded for the parameters (grading_file, count or solid_fraction, diameter bounds,
 * front_median_m, front_sigma, min_gap_m, seed; the fluid block and the domain). Largest first, each drawn
 * until it overlaps no other disc and keeps min_gap (0: one dp) from the bed, the free surface of the initial
 * block and the block's ends. Returns the count (discs malloc'd), or -1 with err, e.g. when the discs cannot
 * fit. */
int surge_boulders_generate(const surge_params *params, surge_disc **discs, char *err, size_t err_len);

/* The disc list as CSV: header x_m,y_m,r_m,vx_mps,vy_mps,omega_radps, one disc per row, values that read back
 * exactly. Reading accepts the three or the six columns, # comment lines; errors name file and line. */
int surge_discs_write_csv(const char *path, const surge_disc *discs, int count, char *err, size_t err_len);
int surge_discs_read_csv(const char *path, surge_disc **discs, char *err, size_t err_len);
#endif
