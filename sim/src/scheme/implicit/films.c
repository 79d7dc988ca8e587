/* The lubrication films (contacts.lubrication; boulders/lubrication.h) inside the implicit scheme's solves. The
 * films of the gaps narrower than the cut-off at the step's start act on the discs' unknowns U = (Vx, Vy, R Omega)
 * of the viscous solve and on the pressure correction's change of them, so the fluid moves with discs that the films
 * hold, not with discs a later contact step would slow (docs/method.md, "Boulders in the implicit scheme").
 *
 * A film between disc b and disc a (or a wall) reads two speeds of b's surface relative to a's, linear in U:
 * v_n = g_n . U along the normal n, v_t = g_t . U + its wall's part along t = (-n_y, n_x); its generalised force on
 * the unknowns (force and torque over R, as disc_coupling.c's rows take them) is -c_n v_n g_n - c_t v_t g_r, g_r the
 * spin entries of g_t alone (the sliding film acts through torques, contact_film), so the rows gain
 * dt M^-1 K U with K = c_n g_n g_n^T + c_t g_r g_t^T, M = (m, m, I / R^2) per disc. The discs that films join are
 * blocks; each block's rows are solved directly (LAPACK's LU): the viscous solve's preconditioner on the disc rows
 * (its diagonal without the films, plus dt M^-1 K), and the pressure correction's (M + dt K) dU = dt F_p. Blocks hold
 * at most FILM_BLOCK_DISCS discs, in disc order; a larger cluster is cut into such blocks, the films between them
 * left to the iterations (the viscous solve) or out of the correction's change (the pressure's).
 * A film with reynolds set (contacts.lubrication_tangential) takes the tangential film's symmetric K_t = J^T K J in
 * place of c_t g_r g_t^T, K lubrication_tangential_matrix's, J the map from the unknowns to (U_T, Omega_T, U_B,
 * Omega_B) along t' = (n_y, -n_x), T the film's disc b; a moving wall adds the constant 2 S (u_wall . t') t' to b's
 * force. */
#include <lapacke.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"
#include "boulders/boulders.h"
#include "boulders/lubrication.h"

#define FILM_BLOCK_DISCS 256

/* Film f's gradients by the unknowns of b (entries 0-2) and of a (3-5; zero for a wall): g_n, g_t, and the part of
 * v_n, v_t that is the wall's own velocity */
static void film_gradients(const boulder_set *b, const contact_film *f, double g_n[6], double g_t[6], double *wall_vn,
                           double *wall_vt)
{
    const double tx = -f->ny, ty = f->nx;
    g_n[0] = f->nx, g_n[1] = f->ny, g_n[2] = 0;
    g_t[0] = tx, g_t[1] = ty, g_t[2] = -f->rb / b->radius[f->b];
    if (f->a >= 0) {
        g_n[3] = -f->nx, g_n[4] = -f->ny, g_n[5] = 0;
        g_t[3] = -tx, g_t[4] = -ty, g_t[5] = -f->ra / b->radius[f->a];
        *wall_vn = *wall_vt = 0;
    } else {
        memset(g_n + 3, 0, 3 * sizeof *g_n), memset(g_t + 3, 0, 3 * sizeof *g_t);
        *wall_vn = -(f->wall_vx * f->nx + f->wall_vy * f->ny), *wall_vt = -(f->wall_vx * tx + f->wall_vy * ty);
    }
}

/* A Reynolds film's K_t (6 x 6 over the entries of film_unknown) and the generalised force of its wall's motion */
static void tangential_rows(const boulder_set *b, const contact_film *f, double k6[6][6], double wall6[6])
{
    const double tx = f->ny, ty = -f->nx;
    double J[4][6] = {{0}}, K[4][4];
    J[0][0] = tx, J[0][1] = ty, J[1][2] = 1.0 / b->radius[f->b];
    if (f->a >= 0)
        J[2][3] = tx, J[2][4] = ty, J[3][5] = 1.0 / b->radius[f->a];
    lubrication_tangential_matrix(f->sliding_damping, f->rb, f->a >= 0 ? f->ra : 0, K);
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            double sum = 0;
            for (int p = 0; p < 4; p++)
                for (int q = 0; q < 4; q++)
                    sum += J[p][i] * K[p][q] * J[q][j];
            k6[i][j] = sum;
        }
        wall6[i] = 0;
    }
    if (f->a < 0) { /* F_T = -2 S (U_T - u_wall . t') */
        const double wall_t = f->wall_vx * tx + f->wall_vy * ty;
        wall6[0] = 2 * f->sliding_damping * wall_t * tx, wall6[1] = 2 * f->sliding_damping * wall_t * ty;
    }
}

/* The unknown of entry j (0-5) of film f: disc b's three, then disc a's */
static inline int film_unknown(const contact_film *f, int j) { return 3 * (j < 3 ? f->b : f->a) + j % 3; }

/* dt / M of unknown q: dt / m for the velocities, dt R^2 / I for R Omega */
static inline double step_over_mass(const boulder_set *b, int q, double dt)
{
    const int d = q / 3;
    return q % 3 < 2 ? dt * b->inv_mass[d] : dt * b->inv_inertia[d] * b->radius[d] * b->radius[d];
}

static int grow(void **array, size_t *capacity, size_t count, size_t size)
{
    if (count <= *capacity)
        return 0;
    void *more = realloc(*array, count * size);
    if (!more)
        return -1;
    *array = more, *capacity = count;
    return 0;
}

static int find_root(int *parent, int d)
{
    while (parent[d] != d)
        d = parent[d] = parent[parent[d]];
    return d;
}

/* The step's films (boulders_films) and their blocks: the discs joined by films, in disc order, cut at
 * FILM_BLOCK_DISCS; -1 when out of memory */
int implicit_discs_films(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    film_blocks *fb = &w->film_blocks;
    const int discs = sim->boulders.count;
    w->film_count = 0, fb->count = 0, fb->factored = 0, fb->singular = 0;
    if (discs == 0)
        return 0;
    if (boulders_films(sim, &w->films, &w->film_count, &w->film_capacity) != 0 ||
        grow((void **)&fb->of_disc, &fb->disc_capacity, (size_t)discs, sizeof *fb->of_disc) != 0 ||
        grow((void **)&fb->place, &fb->place_capacity, (size_t)discs, sizeof *fb->place) != 0 ||
        grow((void **)&fb->first, &fb->first_capacity, (size_t)discs + 1, sizeof *fb->first) != 0 ||
        grow((void **)&fb->members, &fb->members_capacity, (size_t)discs, sizeof *fb->members) != 0)
        return -1;
    for (int d = 0; d < discs; d++)
        fb->place[d] = d, fb->of_disc[d] = -1;
    for (int k = 0; k < w->film_count; k++) { /* the smaller root joins the larger: the same blocks every time */
        const contact_film *f = &w->films[k];
        fb->of_disc[f->b] = 0;
        if (f->a >= 0) {
            fb->of_disc[f->a] = 0;
            const int ra = find_root(fb->place, f->a), rb = find_root(fb->place, f->b);
            if (ra != rb)
                fb->place[ra < rb ? ra : rb] = ra < rb ? rb : ra;
        }
    }
    /* clusters numbered in the order of their smallest disc */
    int *block_of_root = fb->members; /* scratch: the members follow once the clusters are counted */
    for (int d = 0; d < discs; d++)
        block_of_root[d] = -1;
    int blocks = 0;
    for (int d = 0; d < discs; d++) {
        if (fb->of_disc[d] < 0)
            continue;
        const int root = find_root(fb->place, d);
        if (block_of_root[root] < 0)
            block_of_root[root] = blocks++;
        fb->of_disc[d] = block_of_root[root];
    }
    memset(fb->first, 0, (size_t)(blocks + 1) * sizeof *fb->first);
    for (int d = 0; d < discs; d++)
        if (fb->of_disc[d] >= 0)
            fb->first[fb->of_disc[d] + 1]++;
    for (int k = 0; k < blocks; k++)
        fb->first[k + 1] += fb->first[k];
    int *fill = fb->place; /* scratch until the places are set below: the roots are no longer needed */
    memcpy(fill, fb->first, (size_t)blocks * sizeof *fill);
    for (int d = 0; d < discs; d++)
        if (fb->of_disc[d] >= 0)
            fb->members[fill[fb->of_disc[d]]++] = d;
    /* cut each cluster into blocks of at most FILM_BLOCK_DISCS discs */
    int count = 0;
    for (int k = 0; k < blocks; k++)
        count += (fb->first[k + 1] - fb->first[k] + FILM_BLOCK_DISCS - 1) / FILM_BLOCK_DISCS;
    if (grow((void **)&fb->start, &fb->start_capacity, (size_t)count + 1, sizeof *fb->start) != 0)
        return -1;
    count = 0;
    for (int k = 0; k < blocks; k++)
        for (int m = fb->first[k]; m < fb->first[k + 1]; m += FILM_BLOCK_DISCS)
            fb->start[count++] = m;
    fb->start[count] = fb->first[blocks];
    for (int k = 0; k < count; k++)
        for (int m = fb->start[k]; m < fb->start[k + 1]; m++)
            fb->of_disc[fb->members[m]] = k, fb->place[fb->members[m]] = m - fb->start[k];
    fb->count = count;
    size_t entries = 0;
    for (int k = 0; k < count; k++) {
        const size_t rows = 3 * (size_t)(fb->start[k + 1] - fb->start[k]);
        entries += rows * rows;
    }
    if (grow((void **)&fb->lu[0], &fb->lu_capacity[0], entries, sizeof *fb->lu[0]) != 0 ||
        grow((void **)&fb->lu[1], &fb->lu_capacity[1], entries, sizeof *fb->lu[1]) != 0 ||
        grow((void **)&fb->pivots[0], &fb->pivot_capacity[0], 3 * (size_t)discs, sizeof *fb->pivots[0]) != 0 ||
        grow((void **)&fb->pivots[1], &fb->pivot_capacity[1], 3 * (size_t)discs, sizeof *fb->pivots[1]) != 0 ||
        grow((void **)&fb->scratch, &fb->scratch_capacity, 3 * (size_t)discs, sizeof *fb->scratch) != 0 ||
        grow((void **)&fb->tangential, &fb->tangential_capacity, 42 * (size_t)w->film_count, sizeof *fb->tangential) != 0)
        return -1;
    for (int k = 0; k < w->film_count; k++) /* the films are the step's: their tangential rows once */
        if (w->films[k].reynolds)
            tangential_rows(&sim->boulders, &w->films[k], (double(*)[6])(fb->tangential + 42 * (size_t)k),
                            fb->tangential + 42 * (size_t)k + 36);
    return 0;
}

/* The films' generalised forces on the discs at unknowns U (disc_x), added into force (3 per disc: N/m, and N for
 * the torque over R) */
void implicit_film_forces(const surge_sim *sim, const double *disc_x, double *force)
{
    const implicit_work *w = implicit_of(sim);
    const boulder_set *b = &sim->boulders;
    for (int k = 0; k < w->film_count; k++) { /* in list order: the same sums whatever the thread count */
        const contact_film *f = &w->films[k];
        double g_n[6], g_t[6], vn, vt;
        film_gradients(b, f, g_n, g_t, &vn, &vt);
        const int sides = f->a >= 0 ? 6 : 3;
        for (int j = 0; j < sides; j++) {
            const double u = disc_x[film_unknown(f, j)];
            vn += g_n[j] * u, vt += g_t[j] * u;
        }
        if (f->reynolds) {
            const double(*k6)[6] = (const double(*)[6])(w->film_blocks.tangential + 42 * (size_t)k), *wall6 = k6[6];
            for (int i = 0; i < sides; i++) {
                double tangential = -wall6[i];
                for (int j = 0; j < sides; j++)
                    tangential += k6[i][j] * disc_x[film_unknown(f, j)];
                force[film_unknown(f, i)] -= f->normal_damping * vn * g_n[i] + tangential;
            }
            continue;
        }
        for (int j = 0; j < sides; j++)
            force[film_unknown(f, j)] -= f->normal_damping * vn * g_n[j] + (j % 3 == 2 ? f->sliding_damping * vt * g_t[j] : 0);
    }
}

/* Block k's rows of which (FILMS_VISCOUS: the disc rows' diagonal without the films, base; FILMS_PRESSURE: the
 * identity) plus dt M^-1 K, column-major, factored; -1 when LAPACK finds it singular */
static int factor_block(surge_sim *sim, int which, int k, size_t at, const double *base, double dt)
{
    implicit_work *w = implicit_of(sim);
    film_blocks *fb = &w->film_blocks;
    const boulder_set *b = &sim->boulders;
    const int first = fb->start[k], rows = 3 * (fb->start[k + 1] - first);
    double *a = fb->lu[which] + at;
    memset(a, 0, (size_t)rows * rows * sizeof *a);
    for (int m = 0; m < rows; m++) {
        const int q = 3 * fb->members[first + m / 3] + m % 3;
        a[(size_t)m * rows + m] = which == FILMS_VISCOUS ? base[q] : 1.0;
    }
    for (int f = 0; f < w->film_count; f++) {
        const contact_film *film = &w->films[f];
        const int sides = film->a >= 0 ? 6 : 3;
        int local[6], inside = 0; /* each entry's row in the block, -1 outside it */
        for (int j = 0; j < sides; j++) {
            const int d = j < 3 ? film->b : film->a;
            local[j] = fb->of_disc[d] == k ? 3 * fb->place[d] + j % 3 : -1;
            inside |= local[j] >= 0;
        }
        if (!inside)
            continue;
        double g_n[6], g_t[6], wall_vn, wall_vt;
        film_gradients(b, film, g_n, g_t, &wall_vn, &wall_vt);
        const double(*k6)[6] = (const double(*)[6])(fb->tangential + 42 * (size_t)f);
        for (int i = 0; i < sides; i++) {
            if (local[i] < 0)
                continue;
            const double scale = step_over_mass(b, film_unknown(film, i), dt);
            const double spin = i % 3 == 2 ? film->sliding_damping * g_t[i] : 0;
            for (int j = 0; j < sides; j++)
                if (local[j] >= 0)
                    a[(size_t)local[j] * rows + local[i]] +=
                        scale * (film->normal_damping * g_n[i] * g_n[j] + (film->reynolds ? k6[i][j] : spin * g_t[j]));
        }
    }
    return LAPACKE_dgetrf(LAPACK_COL_MAJOR, rows, rows, a, rows, fb->pivots[which] + 3 * first) == 0 ? 0 : -1;
}

/* The viscous solve's disc rows: at the step's first pass factors both blocks (the viscous one on diag's disc rows
 * as they are, without the films; the passes' are the same), then adds the films' part of the diagonal (K's diagonal
 * times dt / M) to diag. fb->singular: LAPACK found a block singular (the step fails, implicit_step.c) */
void implicit_films_factor(surge_sim *sim, double dt, double *diag)
{
    implicit_work *w = implicit_of(sim);
    film_blocks *fb = &w->film_blocks;
    const boulder_set *b = &sim->boulders;
    size_t at = 0;
    for (int k = 0; k < fb->count && !fb->factored; k++) {
        const size_t rows = 3 * (size_t)(fb->start[k + 1] - fb->start[k]);
        if (factor_block(sim, FILMS_VISCOUS, k, at, diag, dt) != 0 ||
            factor_block(sim, FILMS_PRESSURE, k, at, NULL, dt) != 0)
            fb->singular = 1;
        at += rows * rows;
    }
    fb->factored = fb->count > 0 && !fb->singular;
    for (int f = 0; f < w->film_count; f++) {
        const contact_film *film = &w->films[f];
        double g_n[6], g_t[6], wall_vn, wall_vt;
        film_gradients(b, film, g_n, g_t, &wall_vn, &wall_vt);
        const double(*k6)[6] = (const double(*)[6])(fb->tangential + 42 * (size_t)f);
        for (int j = 0; j < (film->a >= 0 ? 6 : 3); j++) {
            const int q = film_unknown(film, j);
            const double spin = film->reynolds ? k6[j][j] : j % 3 == 2 ? film->sliding_damping * g_t[j] * g_t[j] : 0;
            diag[q] += step_over_mass(b, q, dt) * (film->normal_damping * g_n[j] * g_n[j] + spin);
        }
    }
}

/* x (3 per disc) <- the blocks' rows of which solved for x's values; the rows of discs outside blocks unchanged */
void implicit_films_solve(surge_sim *sim, int which, double *x)
{
    implicit_work *w = implicit_of(sim);
    film_blocks *fb = &w->film_blocks;
    if (!fb->factored)
        return;
    size_t at = 0;
    for (int k = 0; k < fb->count; k++) {
        const int first = fb->start[k], rows = 3 * (fb->start[k + 1] - first);
        for (int m = 0; m < rows; m++)
            fb->scratch[m] = x[3 * fb->members[first + m / 3] + m % 3];
        LAPACKE_dgetrs(LAPACK_COL_MAJOR, 'N', rows, 1, fb->lu[which] + at, rows, fb->pivots[which] + 3 * first,
                       fb->scratch, rows);
        for (int m = 0; m < rows; m++)
            x[3 * fb->members[first + m / 3] + m % 3] = fb->scratch[m];
        at += (size_t)rows * rows;
    }
}

void implicit_films_free(film_blocks *fb)
{
    free(fb->of_disc);
    free(fb->place);
    free(fb->first);
    free(fb->members);
    free(fb->start);
    free(fb->lu[0]);
    free(fb->lu[1]);
    free(fb->pivots[0]);
    free(fb->pivots[1]);
    free(fb->scratch);
    free(fb->tangential);
}
