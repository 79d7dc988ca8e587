/* Boulders: rigid discs made of boundary particles, moved by the fluid (GMD eq. 10-11) and by contacts
 * (contact_solver.h); their state is a boulder_set (boulder_set.h). */
#ifndef SURGE_BOULDERS_H
#define SURGE_BOULDERS_H

#include <stddef.h>

#include "boulders/boulder_set.h"
#include "precision.h"

typedef struct surge_sim surge_sim;

int boulders_define(surge_sim *sim, char *err, size_t err_len);   /* the discs of the case, before the walls */
int boulders_particle_count(const surge_sim *sim);
int boulders_particles_of(const surge_sim *sim, int disc);   /* the particles of one disc */
/* Appends disc particles to the wall arrays from index first (ids too); ghost offsets follow the discs. */
void boulders_create_particles(surge_sim *sim, int first);
int boulders_cover(const surge_sim *sim, double x, double y); /* a fluid particle here would sit in a disc */
void boulders_place_particles(surge_sim *sim);                /* positions and velocities from the discs */
/* The mDBC ghost offset wall particle k of a disc has when the disc's orientation is angle. */
void boulders_ghost_offset(const surge_sim *sim, int k, double angle, real *gdx, real *gdy);
/* eq. 10, after interaction_compute; the pressures taken relative to reference_pa[disc] (NULL: 0) */
void boulders_fluid_forces(surge_sim *sim, const double *reference_pa);
/* Fills the discs' cos_angle and sin_angle from their angles (scratch; writes through the const set's arrays). */
void boulders_orient(const boulder_set *b);
/* Velocity of the disc's surface where wall particle k's ghost is mirrored (the no-slip target), at the orientation of
 * the last boulders_orient. */
void boulders_surface_velocity(const surge_sim *sim, int k, double *vx, double *vy);
void boulders_predict(surge_sim *sim, double half_dt_s);      /* saves the step start, moves to the half step */
int boulders_correct(surge_sim *sim, double dt_s);            /* full step from the start, with contacts */
void boulders_restore(surge_sim *sim);                        /* back to the step start (roll-back) */
/* the implicit scheme's full step from the fluid forces, with added_mass (implicit.added_mass) */
int boulders_advance_implicit(surge_sim *sim, double dt_s, double added_mass);
void boulders_restore_implicit(surge_sim *sim);               /* roll-back of boulders_advance_implicit */
/* each disc's wetted fraction: the mean over its outer ring of wetness (per wall particle, 0 dry to 1 wet) */
void boulders_wetted_fraction(surge_sim *sim, const real *wetness);
void boulders_free(boulder_set *b);

#endif
