/* What the implicit step does after its solves: close fluid pairs parted. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"

/* Close pairs (implicit.pair_distance_dp, docs/method.md): each fluid particle closer than the distance to another
 * loses half their speed toward each other and moves half the way to the distance apart (the MPS collision model,
 * Lee et al. 2011, at restitution 0), from the step's velocities and positions, so each pair's changes are equal and
 * opposite and momentum is kept. */
void implicit_part_close_pairs(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int first = sim->wall_count, nf = sim->count - first;
    const double reach = sim->params.implicit.pair_distance_dp * sim->params.numerics.dp_m, reach2 = reach * reach;
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        double dvx = 0, dvy = 0, dx = 0, dy = 0;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
            const int b = nl->fluid_index[e];
            const double rx = nl->fluid_dx0[e] + (moved_x[a] - moved_x[b]), ry = nl->fluid_dy0[e] + (moved_y[a] - moved_y[b]);
            const double r2 = rx * rx + ry * ry;
            if (r2 >= reach2 || r2 == 0)
                continue;
            const double r = sqrt(r2), nx = rx / r, ny = ry / r;
            const double closing = ((double)sim->vx[a] - sim->vx[b]) * nx + ((double)sim->vy[a] - sim->vy[b]) * ny;
            if (closing < 0)
                dvx -= 0.5 * closing * nx, dvy -= 0.5 * closing * ny;
            dx += 0.5 * (reach - r) * nx, dy += 0.5 * (reach - r) * ny;
        }
        w->pair_dvx[i] = dvx, w->pair_dvy[i] = dvy, w->pair_dx[i] = dx, w->pair_dy[i] = dy;
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++)
        sim->vx[first + i] += (real)w->pair_dvx[i], sim->vy[first + i] += (real)w->pair_dvy[i];
}
