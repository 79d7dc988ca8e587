/* Building and keeping the neighbour lists (neighbours.c); their layout is in lists.h. */
#ifndef SURGE_NEIGHBOURS_H
#define SURGE_NEIGHBOURS_H

#include "sim_internal.h"

int neighbours_init(surge_sim *sim, char *err, size_t err_len); /* build positions = positions; no lists yet */
void neighbours_free(neighbour_lists *nl);
/* At the start of a step: rebuilds (wraps positions into the period, sorts, lists) when a particle may come
 * within skin/2 of leaving its list's reach by the corrector's evaluation; -1 when out of memory. */
int neighbours_update(surge_sim *sim);
/* Sorts by the build positions as they are and builds the lists (restarts: the same lists as the saved run). */
int neighbours_adopt_build_positions(surge_sim *sim);
/* Worksharing functions: their loops are `omp for`, to be called by every thread of a parallel region (one force
 * evaluation shares one region: scheme/explicit/explicit_step.c); called outside one, they run on the calling thread
 * alone. */
/* Every particle's displacement since the build: before each force evaluation (positions changed). */
void neighbours_track(surge_sim *sim);
/* The fluid particles [begin, end) that the calling thread of a parallel region takes in a pass over the fluid's lists:
 * contiguous shares of equal cost (list entries plus a part per particle), so that the thread with the bed's wall
 * entries does not leave the other waiting; outside a region, all of them. The pass ends with `omp barrier`. Each
 * particle sums its own pairs, so results do not depend on the shares. */
void neighbours_fluid_share(const surge_sim *sim, int *begin, int *end);
/* The first particle that moves: walls move only when there are discs */
static inline int neighbours_first_moving(const surge_sim *sim)
{
    return sim->boulders.count > 0 ? 0 : sim->wall_count;
}
/* One particle's displacement since the build */
static inline void neighbours_track_particle(surge_sim *sim, int a)
{
    neighbour_lists *nl = &sim->neighbours;
    nl->moved_x[a] = (real)(sim->x[a] - nl->x_build[a]);
    nl->moved_y[a] = (real)(sim->y[a] - nl->y_build[a]);
}

/* Boulder particle k's entry e of its list of wall particles and other discs' (lists.h): r_k - r_j now into dx, dy;
 * returns its square */
static inline real neighbours_solid_offset(const neighbour_lists *nl, int k, int64_t e, real *dx, real *dy)
{
    const int j = nl->solid_index[e];
    *dx = nl->solid_dx0[e] + (nl->moved_x[k] - nl->moved_x[j]);
    *dy = nl->solid_dy0[e] + (nl->moved_y[k] - nl->moved_y[j]);
    return *dx * *dx + *dy * *dy;
}

#endif
