/* The boulders' state: rigid discs made of boundary particles (boulders.h has what moves them). */
#ifndef SURGE_BOULDER_SET_H
#define SURGE_BOULDER_SET_H

#include <stdint.h>

#include "boulders/contact_solver.h"
#include "precision.h"

/* The discs' arrays, each declared once here: the struct's members, their allocation and release, the step-start
 * copies and roll-back, the state hash and the checkpoint follow these lists (boulders.c, disc_motion.c, sim.c,
 * checkpoint.c). */

/* The discs' state, F(name, meaning): hashed and checkpointed in this order, each with a copy name_n at the start of
 * the step (the roll-back restores it) */
#define SURGE_DISC_STEP_FIELDS(F)                                                                                     \
    F(x, "centre of mass (m), wrapped into the period")                                                              \
    F(y, "centre of mass (m)")                                                                                        \
    F(angle, "orientation (rad)")                                                                                     \
    F(vx, "velocity (m/s)")                                                                                           \
    F(vy, "velocity (m/s)")                                                                                           \
    F(omega, "angular velocity (rad/s)")

/* Every other per-disc array, F(name, meaning) */
#define SURGE_DISC_FIELDS(F)                                                                                          \
    F(radius, "radius (m)")                                                                                           \
    F(mass, "mass per metre of width (kg/m)")                                                                        \
    F(inv_mass, "1 / mass")                                                                                           \
    F(inv_inertia, "1 / moment of inertia per metre of width")                                                       \
    F(contact_radius, "radius + contacts.margin_dp dp / 2: where the contact solver sees the disc's surface")        \
    F(fx, "the fluid's force on the disc (eq. 10)")                                                                  \
    F(fy, "")                                                                                                         \
    F(torque, "and its torque")                                                                                       \
    F(ax, "scratch: accelerations for the contact solver")                                                           \
    F(ay, "")                                                                                                         \
    F(alpha, "")                                                                                                      \
    F(spin_damping, "-d(torque)/d(omega) / inertia (1/s): the viscous torque's stiffness, implicit")                \
    F(omega_forces, "the omega the last fluid forces were computed with")                                            \
    F(angle_build, "orientation at the last neighbour-list build (where the ghosts' lists were made)")              \
    F(cos_angle, "scratch: cos and sin of angle as of the last boulders_orient (one per disc: its particles share")  \
    F(sin_angle, "them)")                                                                                            \
    F(step_fluid_fx, "the last step's mean forces on the disc (N/m; reported, not part of the state): the fluid's")  \
    F(step_fluid_fy, "(the implicit scheme's with the films its solves carry)")                                       \
    F(step_film_fx, "the lubrication films' the contact solver takes (the explicit scheme's)")                       \
    F(step_film_fy, "")                                                                                               \
    F(step_wall_contact_fx, "the walls' contacts'")                                                                  \
    F(step_wall_contact_fy, "")                                                                                       \
    F(step_disc_contact_fx, "the other discs' contacts'")                                                            \
    F(step_disc_contact_fy, "")

/* The per-wall-particle arrays, F(name, type, meaning) */
#define SURGE_WALL_DISC_FIELDS(F)                                                                                     \
    F(spin_coupling, real, "by wall index: sum over fluid neighbours of the viscous pair coefficient")              \
    F(of_wall, int32_t, "by wall particle id: the disc it belongs to (-1: a fixed wall)")                           \
    F(local_x, double, "by wall particle id: its offset from the disc's centre at angle 0 (m)")                     \
    F(local_y, double, "")                                                                                           \
    F(by_disc, int32_t, "the discs' particles' wall indices, disc by disc, each disc's in ascending order")          \
    F(in_order, int32_t, "the same in ascending order")

#define DISC_MEMBER(name, meaning) double *name;
#define DISC_COPY_MEMBER(name, meaning) double *name##_n;
#define WALL_DISC_MEMBER(name, type, meaning) type *name;

typedef struct boulder_set {
    int count;
    SURGE_DISC_STEP_FIELDS(DISC_MEMBER)
    SURGE_DISC_STEP_FIELDS(DISC_COPY_MEMBER)
    SURGE_DISC_FIELDS(DISC_MEMBER)
    SURGE_WALL_DISC_FIELDS(WALL_DISC_MEMBER)
    int32_t *by_disc_first; /* count + 1: disc i's particles are by_disc[by_disc_first[i] .. by_disc_first[i + 1]) */
    contact_solver *contacts;
} boulder_set;

#endif
