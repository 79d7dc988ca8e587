/* Packing the fluid around the discs before the first step, where boulders.pack_fluid asks (docs/boulders.md,
 * "Placement").
 *
 * The fluid starts on a square lattice less the sites inside a disc (boulders_cover): the right number of particles
 * for the room the discs leave, but unevenly spaced next to a circle, with some sites closer to its surface than the
 * contact distance. Each pass moves every particle whose kernel sees a disc and no free surface down the gradient of
 * its kernel sum, dr = -beta h^2 grad C with C = sum_b V_b W_ab over fluid, walls and discs (the shift of Lind et al.
 * 2012, J. Comput. Phys. 231, used as a packing as by Colagrossi et al. 2012, Comput. Phys. Commun. 183), at most a
 * tenth of a spacing a pass; then every particle, at a free surface too, out to the contact distance from every disc.
 * A move that would bring a particle within that distance of a wall's face, or leave it in a gap narrower than two
 * contact distances (where boulders_cover leaves no site), is not taken. A lattice's gradient is 0:
 * the fluid away from the discs stays where it was. Each pass reads the positions before it (the same at any thread
 * count). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"
#include "boulders/boulders.h"
#include "boulders/placement.h"
#include "neighbours/neighbours.h"
#include "scene/scene.h"

enum { PACK_PASSES = 50 };
static const double PACK_BETA = 0.5;           /* the shift's coefficient, of h^2 */
static const double PACK_LARGEST_STEP_DP = 0.1; /* the largest move a pass, in spacings */

/* Adds particle a's kernel gradient sum over list entries [from, to) (neighbour j = index[e], r_a - r_j at the build
 * dx0, dy0) to *gx, *gy; returns whether a disc's particle lies within the kernel's support */
static int gradient_sum(const surge_sim *sim, int a, int64_t from, int64_t to, const int32_t *index, const real *dx0,
                        const real *dy0, double *gx, double *gy)
{
    const neighbour_lists *nl = &sim->neighbours;
    int disc_seen = 0;
    for (int64_t e = from; e < to; e++) {
        const int j = index[e];
        const real rx = dx0[e] + (nl->moved_x[a] - nl->moved_x[j]), ry = dy0[e] + (nl->moved_y[a] - nl->moved_y[j]);
        const real r2 = rx * rx + ry * ry;
        if (r2 < sim->kernel.support2 && r2 > 0) {
            const double f = kernel2d_grad_factor(&sim->kernel, (real)sqrt((double)r2));
            *gx += f * rx, *gy += f * ry;
            disc_seen |= j < sim->wall_count && sim->boulders.of_wall[sim->id[j]] >= 0;
        }
    }
    return disc_seen;
}

/* Particle a's (fluid index i) move down its kernel sum's gradient; 0 where its kernel sees no disc */
static void pack_move(const surge_sim *sim, int i, double *mx, double *my)
{
    const neighbour_lists *nl = &sim->neighbours;
    const int a = sim->wall_count + i;
    double gx = 0, gy = 0;
    gradient_sum(sim, a, nl->fluid_first[i], nl->fluid_first[i + 1], nl->fluid_index, nl->fluid_dx0, nl->fluid_dy0,
                 &gx, &gy);
    const int near_disc = gradient_sum(sim, a, nl->wall_first[i], nl->wall_first[i + 1], nl->wall_index,
                                       nl->wall_dx0, nl->wall_dy0, &gx, &gy);
    *mx = *my = 0;
    if (!near_disc)
        return;
    const double dp = sim->params.numerics.dp_m, h = sim->derived.h_m, volume = sim->mass / sim->rho0;
    double sx = -PACK_BETA * h * h * volume * gx, sy = -PACK_BETA * h * h * volume * gy;
    const double length = sqrt(sx * sx + sy * sy), largest = PACK_LARGEST_STEP_DP * dp;
    if (length > largest)
        sx *= largest / length, sy *= largest / length;
    *mx = sx, *my = sy;
}

/* The next disc (after list entry *e, not the last one returned) with a particle in fluid particle i's wall list;
 * -1 at the list's end */
static int next_disc(const surge_sim *sim, int i, int64_t *e, int *last)
{
    const neighbour_lists *nl = &sim->neighbours;
    for (; *e < nl->wall_first[i + 1]; ++*e) {
        const int disc = sim->boulders.of_wall[sim->id[nl->wall_index[*e]]];
        if (disc >= 0 && disc != *last)
            return *last = disc;
    }
    return -1;
}

/* Moves (x, y) out to reach_m from the surface of every disc that has a particle in fluid particle i's lists; returns
 * 1 where it then lies in a gap narrower than 2 reach_m between a disc and the next face (another disc, a wall), as
 * boulders_cover leaves out of the lattice */
static int keep_off_discs(const surge_sim *sim, int i, double reach_m, double *x, double *y)
{
    const boulder_set *b = &sim->boulders;
    const double period = sim->params.domain.periodic_x ? sim->params.domain.length_m : 0;
    int last = -1, disc;
    for (int64_t e = sim->neighbours.wall_first[i]; (disc = next_disc(sim, i, &e, &last)) >= 0;) {
        const double dx = placement_wrap_dx(*x - b->x[disc], period), dy = *y - b->y[disc];
        const double distance = sqrt(dx * dx + dy * dy), least = b->radius[disc] + reach_m;
        if (distance < least && distance > 0)
            *x += dx * (least / distance - 1.0), *y += dy * (least / distance - 1.0);
    }
    double nearest_m = INFINITY, second_m = INFINITY;
    last = -1;
    for (int64_t e = sim->neighbours.wall_first[i]; (disc = next_disc(sim, i, &e, &last)) >= 0;) {
        const double dx = placement_wrap_dx(*x - b->x[disc], period), dy = *y - b->y[disc];
        const double surface_m = sqrt(dx * dx + dy * dy) - b->radius[disc];
        if (surface_m < nearest_m)
            second_m = nearest_m, nearest_m = surface_m;
        else if (surface_m < second_m && surface_m > nearest_m)
            second_m = surface_m;
    }
    return boulders_room_too_narrow(sim, *x, *y, nearest_m, second_m);
}

int scene_pack_fluid(surge_sim *sim, char *err, size_t err_len)
{
    if (!sim->pack_interior)
        return 0;
    const int first = sim->wall_count, nf = sim->count - first;
    const double reach_m = sim_contact_reach_m(sim);
    double *move = malloc(2 * (size_t)nf * sizeof *move + 1);
    if (!move) {
        snprintf(err, err_len, "out of memory packing %d fluid particles", nf);
        return -1;
    }
    for (int pass = 0; pass < PACK_PASSES; pass++) {
        if (neighbours_update(sim) != 0) {
            snprintf(err, err_len, "out of memory for the neighbour lists packing %d fluid particles", nf);
            free(move);
            return -1;
        }
        neighbours_track(sim);
        #pragma omp parallel for schedule(static)
        for (int i = 0; i < nf; i++) {
            if (sim->pack_interior[sim->id[first + i] - first])
                pack_move(sim, i, move + i, move + nf + i);
            else
                move[i] = move[nf + i] = 0;
        }
        #pragma omp parallel for schedule(static)
        for (int i = 0; i < nf; i++) {
            const int a = first + i;
            const double wall_before_m = boulders_wall_face_distance_m(&sim->params, sim->x[a], sim->y[a]);
            /* the move, or else no move, each kept off the discs */
            for (int attempt = 0; attempt < 2; attempt++) {
                double x = sim->x[a] + (attempt == 0 ? move[i] : 0.0);
                double y = sim->y[a] + (attempt == 0 ? move[nf + i] : 0.0);
                if (keep_off_discs(sim, i, reach_m, &x, &y))
                    continue;
                const double wall_m = boulders_wall_face_distance_m(&sim->params, x, y);
                if (wall_m >= reach_m || wall_m >= wall_before_m) {
                    sim->x[a] = x, sim->y[a] = y;
                    break;
                }
            }
        }
    }
    free(move);
    free(sim->pack_interior);
    sim->pack_interior = NULL;
    /* the first step builds its lists where the packing left the particles */
    neighbour_lists *nl = &sim->neighbours;
    memcpy(nl->x_build, sim->x, (size_t)sim->count * sizeof *nl->x_build);
    memcpy(nl->y_build, sim->y, (size_t)sim->count * sizeof *nl->y_build);
    memset(nl->moved_x, 0, (size_t)sim->count * sizeof *nl->moved_x);
    memset(nl->moved_y, 0, (size_t)sim->count * sizeof *nl->moved_y);
    nl->valid = 0;
    return 0;
}
