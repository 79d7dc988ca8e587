/* Neighbour lists with a skin (Verlet lists): each fluid particle's fluid and wall neighbours within 2h + skin,
 * built from the cell grid and reused while no particle can have moved more than skin/2 since the build, so that
 * every pair within 2h at either force evaluation of a step is in the list (docs/method.md, "Neighbour lists").
 * Between builds the particles keep their order and positions are not wrapped into the period (the lists hold
 * each pair's periodic image); a build wraps them, sorts by cell and records the build positions. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"
#include "boulders/boulders.h"
#include "neighbours/grid.h"
#include "neighbours/neighbours.h"

/* What a pass over fluid particle i's lists costs, in list entries: its fluid and wall entries and a part of its own
 * (the lane totals, the wall-face search, the writes), counted as PARTICLE_COST_ENTRIES entries; cost_before(i) is
 * the total of particles 0 .. i-1. */
#define PARTICLE_COST_ENTRIES 8
static int64_t cost_before(const neighbour_lists *nl, int i)
{
    return nl->fluid_first[i] + nl->wall_first[i] + (int64_t)PARTICLE_COST_ENTRIES * i;
}

/* The first fluid particle (0 .. count) whose cost_before reaches target. */
static int first_at_cost(const neighbour_lists *nl, int count, int64_t target)
{
    int low = 0, high = count;
    while (low < high) {
        const int mid = low + (high - low) / 2;
        if (cost_before(nl, mid) < target)
            low = mid + 1;
        else
            high = mid;
    }
    return low;
}

void neighbours_fluid_share(const surge_sim *sim, int *begin, int *end)
{
    const neighbour_lists *nl = &sim->neighbours;
    const int count = sim->count - sim->wall_count;
    const int64_t threads = omp_get_num_threads(), t = omp_get_thread_num(), total = cost_before(nl, count);
    *begin = sim->wall_count + first_at_cost(nl, count, total * t / threads);
    *end = sim->wall_count + first_at_cost(nl, count, total * (t + 1) / threads);
}

int neighbours_init(surge_sim *sim, char *err, size_t err_len)
{
    neighbour_lists *nl = &sim->neighbours;
    nl->skin_m = sim_neighbour_skin_m(sim);
    const size_t n = (size_t)sim->count, nf = (size_t)(sim->count - sim->wall_count);
    nl->x_build = malloc((n + 1) * sizeof *nl->x_build);
    nl->y_build = malloc((n + 1) * sizeof *nl->y_build);
    nl->fluid_first = calloc(nf + 1, sizeof *nl->fluid_first);
    nl->wall_first = calloc(nf + 1, sizeof *nl->wall_first);
    nl->wall_fluid_first = calloc((size_t)sim->wall_count + 1, sizeof *nl->wall_fluid_first);
    nl->ghost_fluid_first = calloc((size_t)sim->wall_count + 1, sizeof *nl->ghost_fluid_first);
    nl->solid_first = calloc((size_t)sim->wall_count + 1, sizeof *nl->solid_first);
    nl->ghost_dx_build = calloc((size_t)sim->wall_count + 1, sizeof *nl->ghost_dx_build);
    nl->ghost_dy_build = calloc((size_t)sim->wall_count + 1, sizeof *nl->ghost_dy_build);
    nl->moved_x = calloc(n + 1, sizeof *nl->moved_x);
    nl->moved_y = calloc(n + 1, sizeof *nl->moved_y);
    if (!nl->x_build || !nl->y_build || !nl->fluid_first || !nl->wall_first || !nl->wall_fluid_first || !nl->moved_x ||
        !nl->ghost_fluid_first || !nl->ghost_dx_build || !nl->ghost_dy_build || !nl->solid_first ||
        !nl->moved_y) {
        snprintf(err, err_len, "out of memory for the neighbour lists of %zu particles", n);
        return -1;
    }
    memcpy(nl->x_build, sim->x, n * sizeof *nl->x_build);
    memcpy(nl->y_build, sim->y, n * sizeof *nl->y_build);
    nl->valid = 0;
    return 0;
}

void neighbours_free(neighbour_lists *nl)
{
    void *arrays[] = {nl->x_build, nl->y_build, nl->moved_x, nl->moved_y, nl->fluid_first, nl->fluid_index,
                      nl->fluid_dx0, nl->fluid_dy0, nl->wall_first, nl->wall_index, nl->wall_dx0, nl->wall_dy0,
                      nl->wall_fluid_first, nl->wall_fluid_index, nl->wall_fluid_dx0, nl->wall_fluid_dy0,
                      nl->ghost_fluid_first, nl->ghost_fluid_index, nl->ghost_fluid_dx0, nl->ghost_fluid_dy0,
                      nl->ghost_dx_build, nl->ghost_dy_build, nl->solid_first, nl->solid_index, nl->solid_dx0,
                      nl->solid_dy0};
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
        free(arrays[i]);
    memset(nl, 0, sizeof *nl);
}

/* Grows a list's arrays to hold at least need entries (by half again, so that growth is rare). */
static int reserve(int32_t **index, real **dx0, real **dy0, size_t *capacity, size_t need)
{
    if (need <= *capacity)
        return 0;
    const size_t grown = need + need / 2 + 64;
    int32_t *i = realloc(*index, grown * sizeof *i);
    if (!i)
        return -1;
    *index = i;
    real *x = realloc(*dx0, grown * sizeof *x);
    if (!x)
        return -1;
    *dx0 = x;
    real *y = realloc(*dy0, grown * sizeof *y);
    if (!y)
        return -1;
    *dy0 = y;
    *capacity = grown;
    return 0;
}

/* Counts the neighbours of one kind within reach2 of the point (xa, ya), build positions, cell by cell in the grid's
 * order, skipping particle self, and writes the first room of them to index, dx0, dy0 (room 0: counts only). Every
 * candidate is written to the next free entry and kept by moving past it: about a third of a cell block's candidates
 * are in reach, in no order a branch could predict (with a branch the writing pass took 9 % of an implicit step, the
 * counting pass 1 %). A candidate is written only while there is room: once the list is full the rest are out of
 * reach. */
static int scan(const surge_sim *sim, const neighbour_ranges *r, double xa, double ya, int self, double reach2,
                int room, int32_t *restrict index, real *restrict dx0, real *restrict dy0)
{
    const double *restrict xb = sim->neighbours.x_build, *restrict yb = sim->neighbours.y_build;
    int count = 0;
    for (int k = 0; k < r->count; k++) {
        const double xa_shifted = xa - r->shift_x[k];
        const int skip = r->shift_x[k] == 0 ? self : -1;
        for (int b = r->begin[k]; b < r->end[k]; b++) {
            const double dx = xa_shifted - xb[b], dy = ya - yb[b];
            if (count < room)
                index[count] = b, dx0[count] = (real)dx, dy0[count] = (real)dy;
            count += (dx * dx + dy * dy < reach2) & (b != skip);
        }
    }
    return count;
}

/* Every list is padded to a multiple of PAIR_LANES entries, so that the pair loops over it (interaction.c,
 * boundary.c) run whole vectors and no scalar remainder: the padding repeats the list's first neighbour at
 * r_ab = (2 reach, 0), beyond the kernel's support however far the particles move before the next build (skin/2
 * each), where every loop masks or skips it. */
static int padded(int count)
{
    return (count + PAIR_LANES - 1) / PAIR_LANES * PAIR_LANES;
}

/* scan()'s writing pass over the list's entries (its length from the counting pass), then the padding */
static void scan_padded(const surge_sim *sim, const neighbour_ranges *r, double xa, double ya, int self, double reach2,
                        int entries, int32_t *index, real *dx0, real *dy0)
{
    const int count = scan(sim, r, xa, ya, self, reach2, entries, index, dx0, dy0);
    const real beyond_m = (real)(2.0 * sqrt(reach2));
    for (int e = count; e < entries; e++)
        index[e] = index[0], dx0[e] = beyond_m, dy0[e] = 0;
}

/* Where a list's searches start: fluid particle a's build position; for wall particle a, its mDBC ghost node, or
 * for a boulder's particle the particle itself (wrapped into the period). */
static void search_point(const surge_sim *sim, int a, double *xs, double *ys)
{
    const neighbour_lists *nl = &sim->neighbours;
    if (a >= sim->wall_count) {
        *xs = nl->x_build[a], *ys = nl->y_build[a];
        return;
    }
    const int boulder = sim->wall_of[a] == WALL_BOULDER;
    *xs = surge_sim_wrapped_x(sim, nl->x_build[a] + (boulder ? 0 : sim->ghost_dx[a]));
    *ys = nl->y_build[a] + (boulder ? 0 : sim->ghost_dy[a]);
}

/* Counts (fill = 0: into first[k + 1]) or writes (fill = 1: from first[k]) the fluid within reach of the point
 * (xs, ys), list k of one of the wall particles' lists. */
static void list_fluid_around(surge_sim *sim, double xs, double ys, double reach2, int fill, int64_t *first, int k,
                              int32_t *index, real *dx0, real *dy0)
{
    neighbour_ranges fluid;
    grid_neighbour_ranges(&sim->grid, sim->grid.fluid_start, xs, ys, &fluid);
    if (!fill)
        first[k + 1] = padded(scan(sim, &fluid, xs, ys, -1, reach2, 0, NULL, NULL, NULL));
    else
        scan_padded(sim, &fluid, xs, ys, -1, reach2, (int)(first[k + 1] - first[k]), index + first[k], dx0 + first[k],
                    dy0 + first[k]);
}

/* Counts (fill = 0: into solid_first[k + 1]) or writes (fill = 1: from solid_first[k]) boulder particle k's list of the
 * particles of fixed walls and of other discs within reach of (xs, ys), its build position, in the grid's order */
static void list_solids_around(surge_sim *sim, int k, double xs, double ys, double reach2, int fill)
{
    neighbour_lists *nl = &sim->neighbours;
    const int32_t *of_wall = sim->boulders.of_wall;
    const int disc = of_wall[sim->id[k]];
    neighbour_ranges walls;
    grid_neighbour_ranges(&sim->grid, sim->grid.wall_start, xs, ys, &walls);
    int64_t e = fill ? nl->solid_first[k] : 0;
    for (int r = 0; r < walls.count; r++) {
        const double x_shifted = xs - walls.shift_x[r];
        for (int j = walls.begin[r]; j < walls.end[r]; j++) {
            const double dx = x_shifted - nl->x_build[j], dy = ys - nl->y_build[j];
            if (!(dx * dx + dy * dy < reach2) || of_wall[sim->id[j]] == disc)
                continue;
            if (fill)
                nl->solid_index[e] = j, nl->solid_dx0[e] = (real)dx, nl->solid_dy0[e] = (real)dy;
            e++;
        }
    }
    if (!fill)
        nl->solid_first[k + 1] = e;
}

/* Counts (fill = 0) or writes (fill = 1) the lists of particle a (a fluid particle's fluid and wall lists, or a
 * wall particle's lists of the fluid around it and, for a boulder's, around its ghost). */
static void list_particle(surge_sim *sim, int a, double reach2, int fill)
{
    neighbour_lists *nl = &sim->neighbours;
    double xs, ys;
    search_point(sim, a, &xs, &ys);
    if (a < sim->wall_count) {
        list_fluid_around(sim, xs, ys, reach2, fill, nl->wall_fluid_first, a, nl->wall_fluid_index,
                          nl->wall_fluid_dx0, nl->wall_fluid_dy0);
        if (sim->wall_of[a] != WALL_BOULDER) {
            if (!fill)
                nl->ghost_fluid_first[a + 1] = nl->solid_first[a + 1] = 0;
            return;
        }
        list_solids_around(sim, a, xs, ys, reach2, fill);
        /* a boulder's ghost node as it was at the disc's build orientation */
        real gdx, gdy;
        boulders_ghost_offset(sim, a, sim->boulders.angle_build[sim->boulders.of_wall[sim->id[a]]], &gdx, &gdy);
        nl->ghost_dx_build[a] = gdx, nl->ghost_dy_build[a] = gdy;
        list_fluid_around(sim, surge_sim_wrapped_x(sim, nl->x_build[a] + gdx), nl->y_build[a] + gdy, reach2, fill,
                          nl->ghost_fluid_first, a, nl->ghost_fluid_index, nl->ghost_fluid_dx0, nl->ghost_fluid_dy0);
        return;
    }
    const int i = a - sim->wall_count;
    neighbour_ranges fluid, walls;
    grid_fluid_and_wall_ranges(&sim->grid, xs, ys, &fluid, &walls);
    if (!fill) {
        nl->fluid_first[i + 1] = padded(scan(sim, &fluid, xs, ys, a, reach2, 0, NULL, NULL, NULL));
        nl->wall_first[i + 1] = padded(scan(sim, &walls, xs, ys, -1, reach2, 0, NULL, NULL, NULL));
        return;
    }
    const int64_t ef = nl->fluid_first[i], ew = nl->wall_first[i];
    scan_padded(sim, &fluid, xs, ys, a, reach2, (int)(nl->fluid_first[i + 1] - ef), nl->fluid_index + ef,
                nl->fluid_dx0 + ef, nl->fluid_dy0 + ef);
    scan_padded(sim, &walls, xs, ys, -1, reach2, (int)(nl->wall_first[i + 1] - ew), nl->wall_index + ew,
                nl->wall_dx0 + ew, nl->wall_dy0 + ew);
}

static void prefix_sum(int64_t *first, int n)
{
    first[0] = 0;
    for (int i = 0; i < n; i++)
        first[i + 1] += first[i];
}

/* The particles a thread lists at a time: handed out as the threads come, as a wall particle's lists (the fluid
 * around it, none deep in a wall) cost far less than a fluid particle's and the walls come first */
#define LIST_CHUNK 256

/* The lists from the build positions, which the arrays are sorted by (grid_sort_*). */
static int build_lists(surge_sim *sim)
{
    neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count, nw = sim->wall_count;
    const double reach = 2.0 * sim->derived.h_m + nl->skin_m, reach2 = reach * reach;
    #pragma omp parallel for schedule(dynamic, LIST_CHUNK)
    for (int a = 0; a < sim->count; a++)
        list_particle(sim, a, reach2, 0);
    prefix_sum(nl->fluid_first, nf);
    prefix_sum(nl->wall_first, nf);
    prefix_sum(nl->wall_fluid_first, nw);
    prefix_sum(nl->ghost_fluid_first, nw);
    prefix_sum(nl->solid_first, nw);
    if (reserve(&nl->fluid_index, &nl->fluid_dx0, &nl->fluid_dy0, &nl->fluid_capacity, (size_t)nl->fluid_first[nf]) ||
        reserve(&nl->wall_index, &nl->wall_dx0, &nl->wall_dy0, &nl->wall_capacity, (size_t)nl->wall_first[nf]) ||
        reserve(&nl->wall_fluid_index, &nl->wall_fluid_dx0, &nl->wall_fluid_dy0, &nl->wall_fluid_capacity,
                (size_t)nl->wall_fluid_first[nw]) ||
        reserve(&nl->ghost_fluid_index, &nl->ghost_fluid_dx0, &nl->ghost_fluid_dy0, &nl->ghost_fluid_capacity,
                (size_t)nl->ghost_fluid_first[nw]) ||
        reserve(&nl->solid_index, &nl->solid_dx0, &nl->solid_dy0, &nl->solid_capacity, (size_t)nl->solid_first[nw]))
        return -1;
    #pragma omp parallel for schedule(dynamic, LIST_CHUNK)
    for (int a = 0; a < sim->count; a++)
        list_particle(sim, a, reach2, 1);
    nl->valid = 1;
    nl->builds++;
    return 0;
}

void neighbours_track(surge_sim *sim)
{
    #pragma omp for schedule(static)
    for (int a = neighbours_first_moving(sim); a < sim->count; a++)
        neighbours_track_particle(sim, a);
}

int neighbours_adopt_build_positions(surge_sim *sim)
{
    grid_sort_fluid(sim);
    if (sim->boulders.count > 0) {
        grid_sort_walls(sim);
        boulders_index_particles(sim);
    }
    return build_lists(sim);
}

/* The farthest any particle can be from its build position at the last force evaluation of the coming step: its
 * distance now plus the scheme's look-ahead at its speed (the explicit scheme's corrector: half the largest time
 * step, dt <= C_CFL h / c0; the implicit scheme evaluates at the step's start: none); a boulder's particles: the
 * disc's speed plus omega times its radius. */
static double largest_excursion(const surge_sim *sim)
{
    const neighbour_lists *nl = &sim->neighbours;
    const double half_dt = sim->list_lookahead_s;
    double largest = 0;
    #pragma omp parallel for schedule(static) reduction(max : largest)
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double dx = sim->x[a] - nl->x_build[a], dy = sim->y[a] - nl->y_build[a];
        const double speed = sqrt((double)sim->vx[a] * sim->vx[a] + (double)sim->vy[a] * sim->vy[a]);
        const double excursion = sqrt(dx * dx + dy * dy) + half_dt * speed;
        largest = excursion > largest ? excursion : largest;
    }
    const boulder_set *b = &sim->boulders;
    if (b->count > 0) {
        #pragma omp parallel for schedule(static) reduction(max : largest)
        for (int e = 0; e < b->by_disc_first[b->count]; e++) {
            const int k = b->in_order[e], i = b->of_wall[sim->id[k]];
            const double dx = sim->x[k] - nl->x_build[k], dy = sim->y[k] - nl->y_build[k];
            const double speed = sqrt(b->vx[i] * b->vx[i] + b->vy[i] * b->vy[i]) + fabs(b->omega[i]) * b->radius[i];
            largest = fmax(largest, sqrt(dx * dx + dy * dy) + half_dt * speed);
            /* its ghost node turns with the disc, at most |omega| (R + |ghost offset|) faster */
            const double gx = dx + (sim->ghost_dx[k] - nl->ghost_dx_build[k]);
            const double gy = dy + (sim->ghost_dy[k] - nl->ghost_dy_build[k]);
            const double ghost_offset = sqrt((double)sim->ghost_dx[k] * sim->ghost_dx[k] +
                                             (double)sim->ghost_dy[k] * sim->ghost_dy[k]);
            largest = fmax(largest, sqrt(gx * gx + gy * gy) + half_dt * (speed + fabs(b->omega[i]) * ghost_offset));
        }
    }
    return largest;
}

int neighbours_update(surge_sim *sim)
{
    neighbour_lists *nl = &sim->neighbours;
    if (nl->valid && nl->skin_m > 0 && !(largest_excursion(sim) >= 0.5 * nl->skin_m))
        return 0;
    const double period = sim->grid.period_m;
    const int moving_walls = sim->boulders.count > 0;
    const int from = moving_walls ? 0 : sim->wall_count;
    /* the particles have moved less than a period since the last build; a boulder's particles too, which must sort
     * into the cell they are in (one past the period sat in the last cell, and the fluid beyond that cell missed
     * it) */
    if (period > 0) {
        #pragma omp parallel for schedule(static)
        for (int a = from; a < sim->count; a++) {
            if (sim->x[a] >= period)
                sim->x[a] -= period;
            else if (sim->x[a] < 0)
                sim->x[a] += period;
        }
    }
    for (int i = 0; i < sim->boulders.count; i++) /* the discs' ghosts are listed where they are now */
        sim->boulders.angle_build[i] = sim->boulders.angle[i];
    memcpy(nl->x_build + from, sim->x + from, (size_t)(sim->count - from) * sizeof *sim->x);
    memcpy(nl->y_build + from, sim->y + from, (size_t)(sim->count - from) * sizeof *sim->y);
    return neighbours_adopt_build_positions(sim);
}
