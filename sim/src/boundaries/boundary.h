/* The walls: mDBC ghost nodes, no-slip and no-penetration velocities, the moving walls' speeds (boundary.c). */
#ifndef SURGE_BOUNDARY_H
#define SURGE_BOUNDARY_H

typedef struct surge_sim surge_sim;

/* boundary.c: mDBC density and no-slip velocity of wall particles (worksharing); where the scheme is not
 * incompressible also their Tait pressure and 1/density (an incompressible scheme solves for its own) */
void boundary_update(surge_sim *sim);
/* boundary.c: the moving walls' speeds at time_s (the start ramp), and the particles' kinds that follow them */
void boundary_wall_speeds(surge_sim *sim, double time_s);

#endif
