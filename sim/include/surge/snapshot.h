/* The one narrow interface between the solver and its consumers (files, stream, renderer).
 * A snapshot is an owned copy of the particle state at a step boundary, in fixed types that do not
 * depend on the solver's internal precision. */
#ifndef SURGE_SNAPSHOT_H
#define SURGE_SNAPSHOT_H

#include <stdint.h>

typedef enum surge_particle_kind {
    SURGE_KIND_FLUID = 0,
    SURGE_KIND_WALL = 1,        /* fixed wall */
    SURGE_KIND_MOVING_WALL = 2, /* wall with a prescribed velocity (belt, lid) */
    SURGE_KIND_BOULDER = 3,     /* boundary particle of a boulder (a rigid disc) */
} surge_particle_kind;

/* The boulders (rigid discs), structure of arrays, in creation order. */
typedef struct surge_boulder_state {
    int32_t count;
    double *x_m, *y_m;    /* centre of mass */
    double *angle_rad;    /* orientation, counter-clockwise from the initial one */
    double *vx_mps, *vy_mps;
    double *omega_radps;  /* counter-clockwise */
    double *radius_m;
    /* the forces on each disc, means over the last step (N per metre of width): the fluid's (pressure and viscous
     * stress; the implicit scheme's with the lubrication films its solves carry), the lubrication films' that the
     * contact solver takes (the explicit scheme's), and the contacts' of the walls and of the other discs. With the
     * disc's own weight (and a channel's drive) they sum to its mass times its acceleration. NaN where not known:
     * before the first step of a simulation or of its continuation, in a file written without them. */
    double *fluid_fx_npm, *fluid_fy_npm, *film_fx_npm, *film_fy_npm;
    double *wall_contact_fx_npm, *wall_contact_fy_npm, *disc_contact_fx_npm, *disc_contact_fy_npm;
    int32_t capacity;
} surge_boulder_state;

typedef struct surge_snapshot {
    int64_t step;
    double time_s;
    double dt_s;
    int32_t count;        /* particles, fluid and wall */
    double *x_m;          /* position, along the (tilted) bed */
    double *y_m;          /* position, normal to the bed */
    float *vx_mps;
    float *vy_mps;
    float *density_kgpm3;
    float *pressure_pa;
    uint8_t *kind;        /* surge_particle_kind */
    int32_t *id;          /* stable particle id, 0..count-1 at creation */
    int32_t capacity;     /* allocated length of the arrays */
    surge_boulder_state boulders;
} surge_snapshot;

/* Resizes the arrays to hold count particles (keeps the allocation when large enough). Returns 0 on success. */
int surge_snapshot_reserve(surge_snapshot *snap, int32_t count);
/* The same for count boulders. */
int surge_snapshot_reserve_boulders(surge_snapshot *snap, int32_t count);
void surge_snapshot_free(surge_snapshot *snap);

#endif
