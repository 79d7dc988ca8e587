/* The boulders' state: rigid discs made of boundary particles (boulders.h has what moves them). */
#ifndef SURGE_BOULDER_SET_H
#define SURGE_BOULDER_SET_H

#include <stdint.h>

#include "boulders/contact_solver.h"
#include "precision.h"

typedef struct boulder_set {
    int count;
    /* state: centre of mass (x wrapped into the period), orientation, velocities */
    double *x, *y, *angle, *vx, *vy, *omega;
    double *x_n, *y_n, *angle_n, *vx_n, *vy_n, *omega_n; /* at the start of the step */
    double *radius, *mass, *inv_mass, *inv_inertia;       /* per metre of width */
    double *contact_radius;  /* radius + contacts.margin_dp dp / 2: where the contact solver sees the disc's surface */
    double *fx, *fy, *torque;                             /* fluid force and torque on each disc (eq. 10) */
    double *ax, *ay, *alpha;                              /* scratch: accelerations for the contact solver */
    double *spin_damping;   /* -d(torque)/d(omega) / inertia (1/s): the viscous torque's stiffness, implicit */
    double *drag_stiffness; /* -d(force)/d(velocity) (kg/(m s)) with the fluid held still: the viscous drag's */
    double *omega_forces;   /* the omega the last fluid forces were computed with */
    double *angle_build;    /* orientation at the last neighbour-list build (where the ghosts' lists were made) */
    double *wetted;         /* the fraction of the disc's surface the fluid wets (boulders_wetted_fraction) */
    double *step_ax, *step_ay; /* implicit scheme: the disc's acceleration over the last step, (v_n+1 - v_n) / dt */
    double *step_ax_n, *step_ay_n; /* and over the one before (a rolled-back step restores them) */
    double *cos_angle, *sin_angle; /* scratch: cos and sin of angle as of the last boulders_orient (one per disc, not
                                    * one per particle: a disc's particles share them) */
    real *spin_coupling;    /* by wall index: sum over fluid neighbours of the viscous pair coefficient */
    /* by wall particle id: the disc it belongs to (-1: a fixed wall) and its offset from the centre at angle 0 */
    int32_t *of_wall;
    double *local_x, *local_y;
    contact_solver *contacts;
} boulder_set;

#endif
