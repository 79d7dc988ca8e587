/* Precision of per-particle state (velocity, density) and of pair arithmetic. Positions are always double.
 * Float by default, as the fastest GPU SPH codes do; -DSURGE_DOUBLE_PAIRS builds everything in double, which the
 * precision test compares against. */
#ifndef SURGE_PRECISION_H
#define SURGE_PRECISION_H

#include <math.h>

#ifdef SURGE_DOUBLE_PAIRS
typedef double real;
#define REAL_SQRT sqrt
#define REAL_FABS fabs
#else
typedef float real;
#define REAL_SQRT sqrtf
#define REAL_FABS fabsf
#endif

#endif
