/* Particle shifting (shifting.c). */
#ifndef SURGE_SHIFTING_H
#define SURGE_SHIFTING_H

typedef struct surge_sim surge_sim;

/* shifting.c: this step's shifting displacements and their divergence (after the corrector's pass; worksharing) */
void shifting_compute(surge_sim *sim, double dt_s);

#endif
