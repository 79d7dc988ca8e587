/* Boulders: rigid discs made of boundary particles, moved by the fluid (GMD eq. 10-11) and by contacts
 * (contact_solver.h); their state is a boulder_set (boulder_set.h). */
#ifndef SURGE_BOULDERS_H
#define SURGE_BOULDERS_H

#include <math.h>
#include <stddef.h>

#include "boulders/boulder_set.h"
#include "precision.h"
#include "surge/params.h"
#include "surge/sim.h"

typedef struct surge_sim surge_sim;

int boulders_define(surge_sim *sim, char *err, size_t err_len);   /* the discs of the case, before the walls */
int boulders_particle_count(const surge_sim *sim);
int boulders_particles_of(const surge_sim *sim, int disc);   /* the particles of one disc */
/* Appends disc particles to the wall arrays from index first (ids too); ghost offsets follow the discs. */
void boulders_create_particles(surge_sim *sim, int first);
int boulders_cover(const surge_sim *sim, double x, double y); /* a fluid particle here would sit in a disc, or in a
                                                               gap beside one narrower than twice the contact distance */
int boulders_fluid_within(const surge_sim *sim, int i, double reach_m); /* fluid within reach of its surface */
/* Distance (m) from (x, y) to the nearest wall face of the domain on the fluid's side; INFINITY without walls */
double boulders_wall_face_distance_m(const surge_params *p, double x, double y);
/* Whether (x, y), nearest_m and second_m from the surfaces of its two nearest discs, lies where the nearest disc leaves
 * less room to the next face (the second disc or a wall) than twice the contact distance (boulders_cover) */
int boulders_room_too_narrow(const surge_sim *sim, double x, double y, double nearest_m, double second_m);
void boulders_place_particles(surge_sim *sim);                /* positions and velocities from the discs */
void boulders_index_particles(surge_sim *sim); /* by_disc, after the walls are sorted or read (boulder_set.h) */
/* The mDBC ghost offset wall particle k of a disc has when the disc's orientation is angle. */
void boulders_ghost_offset(const surge_sim *sim, int k, double angle, real *gdx, real *gdy);
/* eq. 10 from the walls' states and the fluid's records (after boundary_update), the pressures taken relative to
 * reference_pa[disc] (NULL: 0). Called by every thread of a parallel region: its loops are shared among them. */
void boulders_fluid_forces(surge_sim *sim, const double *reference_pa);
/* After boulders_fluid_forces and interaction_compute, on one thread: the reactions to the face repulsion */
void boulders_take_face_reactions(surge_sim *sim);
/* Fills the discs' cos_angle and sin_angle from their angles (scratch; writes through the const set's arrays). */
void boulders_orient(const boulder_set *b);
/* Velocity of the disc's surface where wall particle k's ghost is mirrored (the no-slip target), at the orientation of
 * the last boulders_orient. */
void boulders_surface_velocity(const surge_sim *sim, int k, double *vx, double *vy);
/* Disc i's state at the step's start: kept, and taken back */
void boulders_save_step_start(boulder_set *b, int i);
void boulders_restore_step_start(boulder_set *b, int i);
void boulders_restore(surge_sim *sim);                        /* back to the step start (roll-back) */
/* The discs' full step from the start, through the contact solver's sub-steps, from the accelerations in ax, ay,
 * alpha, with the lubrication films (contacts.lubrication) when with_lubrication; the disc particles follow. -1 when
 * the contact solver runs out of memory. */
int boulders_advance_with_contacts(surge_sim *sim, double dt_s, int with_lubrication);
/* Adds the last advance's contact impulses to *sum, the bed's apart from the other walls' */
void boulders_add_contact_impulses(const surge_sim *sim, surge_contact_impulses *sum);
/* The lubrication films of the discs' gaps at their present positions (contacts.lubrication; contact_solver_films) */
int boulders_films(surge_sim *sim, contact_film **films, int *count, int *capacity);
/* A disc's acceleration without the fluid: gravity on its mass; the driving force of a channel on its volume */
void boulders_own_acceleration(const surge_sim *sim, double *gx, double *gy);
/* The particles of ring k (0: the outer one) of a disc of radius r_m */
int boulders_ring_particles(double r_m, double dp_m, int ring);
/* The per-wall-particle arrays (SURGE_WALL_DISC_FIELDS) for wall_count wall particles; -1 when out of memory */
int boulders_allocate_wall_fields(boulder_set *b, int wall_count);
void boulders_free(boulder_set *b);

/* Offset of the disc particle with id from its disc's centre at orientation (cos, sin) = (c, s). */
static inline void boulders_rotated_offset(const boulder_set *b, int id, double c, double s, double *rx, double *ry)
{
    *rx = c * b->local_x[id] - s * b->local_y[id];
    *ry = s * b->local_x[id] + c * b->local_y[id];
}

#endif
