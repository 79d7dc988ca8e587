/* The packed records a neighbour brings to the pair loops, one vector each. */
#ifndef SURGE_RECORDS_H
#define SURGE_RECORDS_H

#include <stddef.h>

#include "physics/lanes.h"
#include "precision.h"

/* What a fluid neighbour brings to the pair loops, packed in one 32-byte record (8 floats) a particle: the loop's
 * loads of a neighbour touch one cache line instead of eight arrays (interaction.c fills it at each evaluation;
 * docs/performance.md) */
typedef struct pair_state {
    real moved_x, moved_y, vx, vy, rho, inv_rho, pressure, surface;
} pair_state;
_Static_assert(sizeof(pair_state) == PAIR_LANES * sizeof(real), "the pair loop loads a record as one vector");
/* A pair_state's fields by position, as lanes_gather_records hands them out */
enum { PAIR_MOVED_X, PAIR_MOVED_Y, PAIR_VX, PAIR_VY, PAIR_RHO, PAIR_INV_RHO, PAIR_PRESSURE, PAIR_SURFACE };
_Static_assert(offsetof(pair_state, surface) == PAIR_SURFACE * sizeof(real) &&
               offsetof(pair_state, rho) == PAIR_RHO * sizeof(real), "pair_state's field positions");

/* What a wall neighbour brings to the fluid's wall pair loop, packed the same way (boundary.c fills it with the
 * wall's mDBC state): its displacement since the build, density, pressure, the no-slip velocity of the viscous term
 * and the velocity of the continuity term */
typedef struct wall_pair_state {
    real moved_x, moved_y, rho, pressure, noslip_vx, noslip_vy, cont_vx, cont_vy;
} wall_pair_state;
_Static_assert(sizeof(wall_pair_state) == PAIR_LANES * sizeof(real), "the pair loop loads a record as one vector");
/* A wall_pair_state's fields by position */
enum { WALL_PAIR_MOVED_X, WALL_PAIR_MOVED_Y, WALL_PAIR_RHO, WALL_PAIR_PRESSURE, WALL_PAIR_NOSLIP_VX, WALL_PAIR_NOSLIP_VY,
       WALL_PAIR_CONT_VX, WALL_PAIR_CONT_VY };
_Static_assert(offsetof(wall_pair_state, cont_vy) == WALL_PAIR_CONT_VY * sizeof(real) &&
               offsetof(wall_pair_state, pressure) == WALL_PAIR_PRESSURE * sizeof(real), "wall_pair_state's positions");

/* What a wall neighbour brings to the wall-face search (interaction_wall_face), packed likewise (boundary.c): a fixed
 * wall particle its normal and its depth below the face, disc -1; a disc's particle its disc, the disc's radius in
 * reach_m and its own offset from the disc's centre */
typedef struct wall_face_state {
    real moved_x, moved_y, nx, ny, reach_m, disc, centre_dx, centre_dy;
} wall_face_state;
_Static_assert(sizeof(wall_face_state) == PAIR_LANES * sizeof(real), "the search loads a record as one vector");
/* A wall_face_state's fields by position */
enum { FACE_MOVED_X, FACE_MOVED_Y, FACE_NX, FACE_NY, FACE_REACH, FACE_DISC, FACE_CENTRE_DX, FACE_CENTRE_DY };
_Static_assert(offsetof(wall_face_state, disc) == FACE_DISC * sizeof(real) &&
               offsetof(wall_face_state, centre_dy) == FACE_CENTRE_DY * sizeof(real), "wall_face_state's positions");

#endif
