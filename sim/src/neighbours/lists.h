/* The neighbour lists' layout (neighbours.c builds them). */
#ifndef SURGE_NEIGHBOUR_LISTS_H
#define SURGE_NEIGHBOUR_LISTS_H

#include <stddef.h>
#include <stdint.h>

#include "precision.h"

/* Each fluid particle's neighbours within 2h + skin at the last build (neighbours.c): fluid particle a = wall_count
 * + i has the fluid neighbours fluid_index[fluid_first[i] .. fluid_first[i+1]) and the wall neighbours
 * wall_index[wall_first[i] .. wall_first[i+1]), in cell order, each with r_a - r_b at the build (periodic image
 * included) in *_dx0, *_dy0. Between builds r_a - r_b = dx0 + (moved_a - moved_b), all in pair precision: no
 * periodic images, no large coordinates. Wall particle k has the fluid around it in
 * wall_fluid_index[wall_fluid_first[k] .. wall_fluid_first[k+1]): for a wall that does not move, the fluid within
 * 2h + skin of its mDBC ghost node, with r_ghost - r_j at the build in wall_fluid_dx0, wall_fluid_dy0; for a
 * boulder's particle, the fluid within 2h + skin of the particle (its force on the disc, eq. 10), with r_k - r_j,
 * and, in the ghost_fluid lists below, the fluid around its ghost node, which turns with the disc. Every list is
 * padded to a multiple of 8 entries with copies of its first neighbour placed beyond the kernel's support
 * (neighbours.c): every loop must mask or skip pairs beyond 2h, as the skin already requires. */
typedef struct neighbour_lists {
    double skin_m;
    int valid;                 /* 0: build at the next step */
    int64_t builds;
    double *x_build, *y_build; /* every particle's position at the build (the arrays are sorted by its cells) */
    real *moved_x, *moved_y;   /* every particle's displacement since the build (neighbours_track) */
    int64_t *fluid_first, *wall_first, *wall_fluid_first;
    int32_t *fluid_index, *wall_index, *wall_fluid_index;
    real *fluid_dx0, *fluid_dy0, *wall_dx0, *wall_dy0, *wall_fluid_dx0, *wall_fluid_dy0;
    size_t fluid_capacity, wall_capacity, wall_fluid_capacity;
    /* a boulder's particle k: the fluid within 2h + skin of its ghost node at the build,
     * ghost_fluid_index[ghost_fluid_first[k] .. ghost_fluid_first[k+1]) with r_ghost - r_j in ghost_fluid_dx0/dy0, and
     * the ghost's offset from the particle then (ghost_dx_build, ghost_dy_build; the disc's angle_build) */
    int64_t *ghost_fluid_first;
    int32_t *ghost_fluid_index;
    real *ghost_fluid_dx0, *ghost_fluid_dy0, *ghost_dx_build, *ghost_dy_build;
    size_t ghost_fluid_capacity;
    /* a boulder's particle k: the particles of fixed walls and of other discs within 2h + skin of it at the build,
     * solid_index[solid_first[k] .. solid_first[k+1]) with r_k - r_j in solid_dx0/dy0 (not padded: its loops are
     * scalar; boulders/fluid_forces.c) */
    int64_t *solid_first;
    int32_t *solid_index;
    real *solid_dx0, *solid_dy0;
    size_t solid_capacity;
} neighbour_lists;

#endif
