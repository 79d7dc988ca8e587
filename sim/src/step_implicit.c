/* The implicit scheme (numerics.scheme = implicit): an incompressible projection with implicit viscosity for slow
 * viscous flows, whose time step follows the flow's own speed instead of the speed of sound (docs/method.md,
 * "The implicit scheme"). An incremental pressure-correction step (Goda 1979; Cummins & Rudman 1999 for SPH) from
 * t_n, everything evaluated at the step's start positions:
 *  1. v* = v_n + dt (g - grad p_n / rho0 + nu lap v*): backward-Euler viscosity with the last step's pressure (so a
 *     fluid at rest stays at rest), no-slip walls by their mDBC mirror 2 v_wall - v_ghost;
 *  2. -lap phi = -(rho0/dt) div v*, phi = 0 on free-surface particles and, at a wall particle, phi_w = phi_ghost
 *     with the wall's normal velocity in div v* (the Neumann condition that leaves no velocity through the wall);
 *     then, with the same operator, -lap psi = alpha rho0 (rho_k/rho0 - 1)/dt^2, the rest-density correction (the
 *     source after Asai et al. 2012), which moves the particles and not their velocities;
 *  3. v_n+1 = v* - dt grad phi / rho0, p_n+1 = p_n + phi, r_n+1 = r_n + dt v_n+1 - dt^2 grad psi / rho0 + the
 *     shift.
 * The pair coefficients of a step are computed once into arrays along the neighbour lists; the solves (BiCGSTAB,
 * matrix-free) then only gather, preconditioned by the diagonal or by a multigrid V-cycle on a sparse stand-in of
 * the operator (implicit.preconditioner). Every particle gathers in list order and every dot
 * product sums in fixed blocks, so the results do not depend on the thread count. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "amg.h"
#include "lanes.h"
#include "pair_terms.h"
#include "sim_internal.h"

#define DOT_BLOCK 4096        /* dot products: partial sums over fixed blocks, added in order */
#define MIN_SHEPARD_SUM 0.1   /* a ghost node with less fluid around it is dry (as boundary.c) */
#define MIN_DETERMINANT 1e-3  /* below it the first-order interpolation falls back to Shepard's (as boundary.c) */
#define CONTACT_ROUNDING_DP 1e-4 /* a gap this close to the contact distance (dp) is at it */
#define SPARSE_KEEP 0.3       /* the multigrid's stand-in keeps entries at least this fraction of the row's largest:
                               * on a lattice the 20 neighbours within 2.3 dp at C_h 1.8, the 8 within 1.9 dp at
                               * C_h 1.3 (0.2 and 0.5 were slower on the Freydier front, docs/method.md) */

/* A multigrid hierarchy kept over steps (implicit.multigrid_rebuild_steps; checkpointed) */
typedef struct held_multigrid {
    amg_system *amg;
    int64_t built_step;       /* the step whose stand-in it was built on */
    int32_t base_iterations;  /* its solve's iterations at that step (-1 until then) */
    int32_t last_iterations;  /* and at the last step */
} held_multigrid;

enum { MULTIGRID_VISCOUS, MULTIGRID_PRESSURE };

/* The vectors a hierarchy's V-cycle takes at once: the viscous solve's two velocity components, the pressure */
static inline int multigrid_blocks(int which) { return which == MULTIGRID_VISCOUS ? 2 : 1; }

typedef struct implicit_work {
    size_t fluid_cap, wall_cap, mirror_cap, ghost_cap; /* entries the per-entry arrays hold */
    real *fluid_w, *fluid_gx, *fluid_gy; /* per fluid-list entry: Laplacian weight, V_b f r_ab */
    real *wall_w, *wall_gx, *wall_gy;    /* per wall-list entry */
    real *mirror_w;                      /* per wall's ghost-list entry: its weight in the value at the ghost */
    real *mirror_nw;                     /* and in the derivative along the ghost's normal there */
    real *ghost_w, *ghost_nw;            /* the same for a disc particle's ghost list (ghost_span) */
    double *mirror_vx, *mirror_vy;       /* per wall: the wall velocity no-slip mirrors about (mirror_velocities) */
    double *disc_reference_pa;           /* per disc: the mean pressure of its particles (disc_forces) */
    int disc_cap;
    real *fluid_pc, *wall_pc;            /* per list entry: the pressure operator's coefficient (assemble_pressure) */
    double *pressure_diag;               /* per fluid particle: the pressure operator's diagonal */
    held_multigrid multigrid[2];         /* implicit.preconditioner = amg: the viscous and the pressure hierarchy */
    amg_system *amg;                     /* this solve's: one of multigrid[] */
    int pressure_by_multigrid;           /* this step's pressure solves use amg (there is a free surface) */
    int vcycle_blocks;                   /* solve()'s preconditioner: 0 the diagonal, else one V-cycle of amg's
                                          * hierarchy on each of this many blocks of nf unknowns */
    int vcycle_honours_fixed;            /* and the free-surface rows the identity (the pressure's) */
    int64_t *matrix_first;               /* amg: the sparse stand-in, row i's entries from matrix_first[i] */
    int32_t *matrix_col;
    double *matrix_val;
    size_t matrix_cap;
    uint8_t *dry;                        /* per wall: its ghost node sees (almost) no fluid */
    real *wetness;                       /* per wall: 0 (its ghost node above the fluid) to 1 (in it) */
    real *immersion;                     /* per wall: 0 (its ghost node's kernel not full) to 1 (inside the fluid) */
    double *wall_sum;                    /* per fixed wall: sum of dp^2 W of the walls at its ghost node (fixed) */
    int wall_sum_ready;
    double *minv_xx, *minv_xy, *minv_yy; /* per fluid particle: inverse kernel moment matrix (identity if singular) */
    double *kernel_ratio;                /* sum_b m W_ab / (rho0 lattice sum) */
    double *weighted_rx, *weighted_ry;   /* sum_b w_ab r_ab: the Laplacian's first-moment error */
    double *grad_x, *grad_y;             /* scratch: the pressure gradient inside the operator */
    double *pressure_n;                  /* per fluid particle: the last step's pressure p_n, then p_n+1 */
    uint8_t *fixed;                      /* free-surface particle: p = 0 */
    uint8_t *near_disc;                  /* per fluid particle: a disc particle within the kernel's support */
    double *expected_ratio;              /* per fluid particle: the kernel sum at rest spacing at its depth under the
                                          * free surface, where that can be read (else 0) */
    double *wall_x, *wall_y;             /* per wall: a mirrored field (velocity, pressure) */
    double *neumann_pa;                  /* per wall: p_w - p_ghost, the Neumann offset of the field being set */
    double *rhs, *x, *offset, *diag;     /* solves: 2 nf at most */
    double *density_rhs, *phi_saved;     /* the rest-density source; the correction phi while psi is solved */
    double *phi_by_id, *psi_by_id;       /* per particle id: the last step's phi and psi, the next one's guesses */
    double *dvx_by_id, *dvy_by_id;       /* per particle id: the last step's v* - v_n, the next viscous solve's guess */
    double *density_dx, *density_dy;     /* per fluid particle: the rest-density correction's displacement */
    double *pair_dvx, *pair_dvy, *pair_dx, *pair_dy; /* per fluid particle: what close pairs change (part_close_pairs) */
    double *r, *rhat, *p, *v, *s, *t, *y, *z, *partial;
} implicit_work;

typedef void (*affine_operator)(surge_sim *sim, const double *x, double *out);
enum { AFFINE, LINEAR_FROM_ZERO, LINEAR_FROM_GUESS }; /* solve()'s operator and first guess */

/* Whether the scene is large enough for the solves' loops to run on several threads: a BiCGSTAB iteration is ten or
 * so short loops, and below this size waking the other threads at each costs more than it saves (the 800-particle
 * tank: 0.53 s on one thread, 4.75 s on two with passive waiting; docs/method.md) */
#define WIDE_FLUID_PARTICLES 20000
static inline int wide(const surge_sim *sim) { return sim->count - sim->wall_count >= WIDE_FLUID_PARTICLES; }

static int grow(void **array, size_t need, size_t size)
{
    void *grown = realloc(*array, (need + 1) * size);
    if (!grown)
        return -1;
    *array = grown;
    return 0;
}

#define GROW(field, need) (grow((void **)&w->field, need, sizeof *w->field))

/* Sizes the work arrays for the current lists; -1 when out of memory. */
static int reserve_work(surge_sim *sim)
{
    if (!sim->implicit && !(sim->implicit = calloc(1, sizeof *sim->implicit)))
        return -1;
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const size_t nf = (size_t)(sim->count - sim->wall_count), nw = (size_t)sim->wall_count;
    const size_t fe = (size_t)nl->fluid_first[nf], we = (size_t)nl->wall_first[nf];
    const size_t me = (size_t)nl->wall_fluid_first[nw], ge = (size_t)nl->ghost_fluid_first[nw];
    if (fe > w->fluid_cap || !w->fluid_w) {
        if (GROW(fluid_w, fe) || GROW(fluid_gx, fe) || GROW(fluid_gy, fe) || GROW(fluid_pc, fe))
            return -1;
        w->fluid_cap = fe;
    }
    if (we > w->wall_cap || !w->wall_w) {
        if (GROW(wall_w, we) || GROW(wall_gx, we) || GROW(wall_gy, we) || GROW(wall_pc, we))
            return -1;
        w->wall_cap = we;
    }
    if (me > w->mirror_cap || !w->mirror_w) {
        if (GROW(mirror_w, me) || GROW(mirror_nw, me))
            return -1;
        w->mirror_cap = me;
    }
    if (sim->boulders.count > w->disc_cap || !w->disc_reference_pa) {
        if (GROW(disc_reference_pa, (size_t)sim->boulders.count))
            return -1;
        w->disc_cap = sim->boulders.count;
    }
    if (ge > w->ghost_cap || !w->ghost_w) {
        if (GROW(ghost_w, ge) || GROW(ghost_nw, ge))
            return -1;
        w->ghost_cap = ge;
    }
    double **by_id[] = {&w->phi_by_id, &w->psi_by_id, &w->dvx_by_id, &w->dvy_by_id};
    for (size_t k = 0; k < sizeof by_id / sizeof by_id[0]; k++)
        if (!*by_id[k] && !(*by_id[k] = calloc((size_t)sim->count + 1, sizeof **by_id[k])))
            return -1;
    if (!w->minv_xx) {
        const size_t n2 = 2 * nf, nblocks = n2 / DOT_BLOCK + 2;
        if (GROW(minv_xx, nf) || GROW(minv_xy, nf) || GROW(minv_yy, nf) ||
            GROW(kernel_ratio, nf) || GROW(weighted_rx, nf) || GROW(weighted_ry, nf) || GROW(grad_x, nf) ||
            GROW(grad_y, nf) || GROW(pressure_n, nf) || GROW(pressure_diag, nf) || GROW(fixed, nf) || GROW(near_disc, nf) || GROW(expected_ratio, nf) || GROW(rhs, n2) || GROW(x, n2) ||
            GROW(offset, n2) || GROW(diag, n2) || GROW(r, n2) || GROW(rhat, n2) ||
            GROW(p, n2) || GROW(v, n2) || GROW(s, n2) || GROW(t, n2) ||
            GROW(y, n2) || GROW(z, n2) || GROW(partial, nblocks) ||
            GROW(density_rhs, nf) || GROW(phi_saved, nf) || GROW(density_dx, nf) || GROW(density_dy, nf) ||
            GROW(pair_dvx, nf) || GROW(pair_dvy, nf) || GROW(pair_dx, nf) || GROW(pair_dy, nf) ||
            GROW(dry, nw) || GROW(wetness, nw) || GROW(immersion, nw) || GROW(wall_sum, nw) || GROW(wall_x, nw) || GROW(wall_y, nw) || GROW(neumann_pa, nw) ||
            GROW(mirror_vx, nw) || GROW(mirror_vy, nw))
            return -1;
    }
    return 0;
}

void step_implicit_free(surge_sim *sim)
{
    implicit_work *w = sim->implicit;
    if (!w)
        return;
    void *arrays[] = {w->fluid_w, w->fluid_gx, w->fluid_gy, w->wall_w, w->wall_gx, w->wall_gy, w->mirror_w,
                      w->mirror_nw, w->ghost_w, w->ghost_nw, w->mirror_vx, w->mirror_vy, w->disc_reference_pa,
                      w->fluid_pc, w->wall_pc, w->pressure_diag, w->dry, w->wetness, w->immersion, w->wall_sum,
                      w->minv_xx, w->minv_xy, w->minv_yy, w->kernel_ratio, w->weighted_rx, w->weighted_ry, w->grad_x,
                      w->grad_y, w->pressure_n, w->fixed, w->near_disc, w->expected_ratio, w->wall_x, w->wall_y,
                      w->neumann_pa, w->density_rhs, w->phi_saved, w->density_dx, w->density_dy, w->pair_dvx, w->pair_dvy, w->pair_dx, w->pair_dy, w->phi_by_id, w->psi_by_id, w->dvx_by_id, w->dvy_by_id, w->rhs, w->x, w->offset, w->diag, w->r, w->rhat, w->p, w->v, w->s, w->t, w->y,
                      w->z, w->partial};
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
        free(arrays[i]);
    amg_destroy(w->multigrid[MULTIGRID_VISCOUS].amg);
    amg_destroy(w->multigrid[MULTIGRID_PRESSURE].amg);
    free(w->matrix_first);
    free(w->matrix_col);
    free(w->matrix_val);
    free(w);
    sim->implicit = NULL;
}

/* The implicit scheme's state beside the particles (checkpoint versions 6 and 7), so that a restarted run repeats the
 * uninterrupted one bit for bit: u32 guesses | phi[f64] by particle id (guesses >= 1) | psi[f64], v*_x - v_x[f64],
 * v*_y - v_y[f64] by particle id (guesses = 2, version 7): the next step's first guesses; guesses = 0 before the first
 * step; then per held multigrid hierarchy i64 built_step | i32 base_iterations | i32 last_iterations | its matrix
 * (amg_write). A version 6 checkpoint (guesses <= 1) restarts psi from 0 and v* from v_n. */
#define ABSURD_GUESS_PA 1e12    /* a guess at phi or psi beyond this is corrupt, as the pressure */
#define ABSURD_GUESS_MPS 1e6    /* and a change of velocity */
static int read_guesses(FILE *f, double *by_id, int count, double absurd)
{
    if (fread(by_id, sizeof *by_id, (size_t)count, f) != (size_t)count)
        return -1;
    for (int i = 0; i < count; i++) /* finite and not absurd */
        if (!(fabs(by_id[i]) < absurd))
            return -1;
    return 0;
}

int step_implicit_write(FILE *f, const surge_sim *sim)
{
    const implicit_work *w = sim->implicit;
    const uint32_t guesses = w && w->phi_by_id ? 2 : 0;
    const size_t count = (size_t)sim->count;
    if (fwrite(&guesses, 4, 1, f) != 1 ||
        (guesses && (fwrite(w->phi_by_id, sizeof *w->phi_by_id, count, f) != count ||
                     fwrite(w->psi_by_id, sizeof *w->psi_by_id, count, f) != count ||
                     fwrite(w->dvx_by_id, sizeof *w->dvx_by_id, count, f) != count ||
                     fwrite(w->dvy_by_id, sizeof *w->dvy_by_id, count, f) != count)))
        return -1;
    for (int k = 0; k < 2; k++) {
        const held_multigrid none = {.base_iterations = -1}, *m = w ? &w->multigrid[k] : &none;
        if (fwrite(&m->built_step, 8, 1, f) != 1 || fwrite(&m->base_iterations, 4, 1, f) != 1 ||
            fwrite(&m->last_iterations, 4, 1, f) != 1 || amg_write(m->amg, f) != 0)
            return -1;
    }
    return 0;
}

int step_implicit_read(FILE *f, surge_sim *sim, uint32_t version)
{
    if (!sim->implicit && !(sim->implicit = calloc(1, sizeof *sim->implicit)))
        return -1;
    implicit_work *w = sim->implicit;
    uint32_t guesses = 0;
    if (fread(&guesses, 4, 1, f) != 1 || guesses > (version >= 7 ? 2u : 1u) || (version >= 7 && guesses == 1))
        return -1;
    double **by_id[] = {&w->phi_by_id, &w->psi_by_id, &w->dvx_by_id, &w->dvy_by_id};
    for (size_t k = 0; k < sizeof by_id / sizeof by_id[0]; k++) /* all of them: a version 6 leaves the others 0 */
        if (!*by_id[k] && !(*by_id[k] = calloc((size_t)sim->count + 1, sizeof **by_id[k])))
            return -1;
    if ((guesses >= 1 && read_guesses(f, w->phi_by_id, sim->count, ABSURD_GUESS_PA) != 0) ||
        (guesses == 2 && (read_guesses(f, w->psi_by_id, sim->count, ABSURD_GUESS_PA) != 0 ||
                          read_guesses(f, w->dvx_by_id, sim->count, ABSURD_GUESS_MPS) != 0 ||
                          read_guesses(f, w->dvy_by_id, sim->count, ABSURD_GUESS_MPS) != 0)))
        return -1;
    for (int k = 0; k < 2; k++) {
        held_multigrid *m = &sim->implicit->multigrid[k];
        char reason[160];
        if (fread(&m->built_step, 8, 1, f) != 1 || fread(&m->base_iterations, 4, 1, f) != 1 ||
            fread(&m->last_iterations, 4, 1, f) != 1 || m->base_iterations < -1 || m->last_iterations < 0 ||
            m->built_step < 0)
            return -1;
        if (!m->amg && !(m->amg = amg_create(reason, sizeof reason, multigrid_blocks(k))))
            return -1;
        if (amg_read(m->amg, f, sim->count) != 0)
            return -1;
    }
    return 0;
}

/* A wall's ghost-node list: a fixed wall's is its wall_fluid list, a disc particle's its ghost_fluid list (the
 * ghost turns with the disc); r_ghost - r_j = dx0[e] - moved_j + shift, and weight[e] the entry's mirror weight */
typedef struct ghost_span {
    int64_t from, to;
    const int32_t *index;
    const real *dx0, *dy0;
    real *weight, *normal_weight;
    real shift_x, shift_y;
} ghost_span;

static inline ghost_span ghost_span_of(const surge_sim *sim, int kw)
{
    const neighbour_lists *nl = &sim->neighbours;
    implicit_work *w = sim->implicit;
    if (sim->wall_of[kw] != WALL_BOULDER)
        return (ghost_span){nl->wall_fluid_first[kw], nl->wall_fluid_first[kw + 1], nl->wall_fluid_index,
                            nl->wall_fluid_dx0, nl->wall_fluid_dy0, w->mirror_w, w->mirror_nw, 0, 0};
    return (ghost_span){nl->ghost_fluid_first[kw], nl->ghost_fluid_first[kw + 1], nl->ghost_fluid_index,
                        nl->ghost_fluid_dx0, nl->ghost_fluid_dy0, w->ghost_w, w->ghost_nw,
                        nl->moved_x[kw] + (sim->ghost_dx[kw] - nl->ghost_dx_build[kw]),
                        nl->moved_y[kw] + (sim->ghost_dy[kw] - nl->ghost_dy_build[kw])};
}

/* The velocity each wall's no-slip mirrors about: its own; the belt-wall corner's, the fixed upstream wall's; a disc
 * particle's, the disc's surface's at its ghost's mirror line (as boundary.c) */
static void mirror_velocities(surge_sim *sim)
{
    implicit_work *w = sim->implicit;
    boulders_orient(&sim->boulders); /* for boulders_surface_velocity */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        double vx = sim->wall_of[kw] == WALL_CORNER ? 0.0 : sim->vx[kw], vy = sim->vy[kw];
        if (sim->wall_of[kw] == WALL_BOULDER)
            boulders_surface_velocity(sim, kw, &vx, &vy);
        w->mirror_vx[kw] = vx, w->mirror_vy[kw] = vy;
    }
}

/* The walls' own share of each wall's ghost node's kernel sum, sum_k dp^2 W(r_ghost - r_k): computed once where no
 * wall moves across the kernel (belts move along themselves), at every step where discs move. With the fluid's
 * share it says whether the node lies in the fluid (about 1, also in a corner, where walls fill three quadrants) or
 * above its surface (less). */
static void wall_sums(surge_sim *sim)
{
    implicit_work *w = sim->implicit;
    const kernel2d *k = &sim->kernel;
    const double vol = sim->mass / sim->rho0;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        const double gx = surge_sim_wrapped_x(sim, sim->x[kw] + sim->ghost_dx[kw]), gy = sim->y[kw] + sim->ghost_dy[kw];
        neighbour_ranges r;
        grid_neighbour_ranges(&sim->grid, sim->grid.wall_start, gx, gy, &r);
        double sum = 0;
        for (int q = 0; q < r.count; q++)
            for (int b = r.begin[q]; b < r.end[q]; b++) {
                const double dx = gx - (sim->x[b] + r.shift_x[q]), dy = gy - sim->y[b], r2 = dx * dx + dy * dy;
                if (r2 < (double)k->support2)
                    sum += vol * kernel2d_w_inside(k->alpha, k->inv_h, (real)sqrt(r2));
            }
        w->wall_sum[kw] = sum;
    }
    w->wall_sum_ready = 1;
}

/* Fluid particle i's per-lane partial sums over its neighbour lists (lanes.h), added in lane order at the end */
typedef struct geometry_lanes {
    real kernel_w[PAIR_LANES], div_r[PAIR_LANES], grad_c_x[PAIR_LANES], grad_c_y[PAIR_LANES];
    real m_xx[PAIR_LANES], m_xy[PAIR_LANES], m_yy[PAIR_LANES]; /* the kernel moments, walls by their wetness */
    real zero[PAIR_LANES];
    double wrx[PAIR_LANES], wry[PAIR_LANES];                    /* sum_b w_ab r_ab */
} geometry_lanes;

/* geometry()'s pair loop over the list entries from..to of a fluid particle at (mxa, mya), its fluid list or (walls)
 * its wall list: each entry's Laplacian weight and V_b f r_ab, and the particle's sums */
static inline __attribute__((always_inline)) void geometry_pairs(surge_sim *sim, real mxa, real mya, int64_t from,
                                                                 int64_t to, int walls, geometry_lanes *s)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const kernel2d *k = &sim->kernel;
    const real grad_coef = k->grad_coef, inv_h = k->inv_h, alpha = k->alpha, support2 = k->support2;
    const real mass = (real)sim->mass, vol = (real)(sim->mass / sim->rho0), rho0 = (real)sim->rho0;
    const real eta2 = (real)sim->eta2, four = 4;
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const int32_t *restrict index = walls ? nl->wall_index : nl->fluid_index;
    const real *restrict dx0 = walls ? nl->wall_dx0 : nl->fluid_dx0, *restrict dy0 = walls ? nl->wall_dy0 : nl->fluid_dy0;
    real *restrict lap_w = walls ? w->wall_w : w->fluid_w;
    real *restrict gx = walls ? w->wall_gx : w->fluid_gx, *restrict gy = walls ? w->wall_gy : w->fluid_gy;
    const real *restrict wetness = w->wetness;
    for (int64_t e0 = from; e0 < to; e0 += PAIR_LANES) {
        #pragma omp simd simdlen(PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            const int b = index[e];
            const real dx = dx0[e] + (mxa - moved_x[b]), dy = dy0[e] + (mya - moved_y[b]);
            const real r2 = dx * dx + dy * dy;
            const int inside = (r2 < support2) & (r2 > 0);
            const real r = REAL_SQRT(r2);
            const real f = inside ? kernel2d_grad_factor_inside(grad_coef, inv_h, r) : 0;
            const real vf = vol * f;
            /* the Laplacian's weight: the viscous pair coefficient (eq. 7) per unit viscosity, negated */
            const real weight = -pair_viscous_coef(mass, four, f, r2, pair_viscous_denominator(rho0, rho0, r2, eta2));
            lap_w[e] = weight;
            gx[e] = vf * dx, gy[e] = vf * dy;
            s->wrx[l] += weight * dx, s->wry[l] += weight * dy;
            s->kernel_w[l] += inside ? kernel2d_w_inside(alpha, inv_h, r) : 0;
            /* a wall counts in div r and in the moments as far as fluid wets it: a wall above the free surface does
             * not hide a surface particle, nor hold up the one next to it */
            const real wet = walls ? wetness[b] : 1;
            s->div_r[l] -= wet * vf * r2;
            s->m_xx[l] += wet * pair_moment(vf, dx, dx), s->m_xy[l] += wet * pair_moment(vf, dx, dy);
            s->m_yy[l] += wet * pair_moment(vf, dy, dy);
            s->grad_c_x[l] += vf * dx, s->grad_c_y[l] += vf * dy;
        }
    }
}

/* The pair coefficients of the step (fluid and wall entries), the inverse moment matrices, kernel sums, the
 * free-surface flags and what shifting needs (div r, grad C, the surface layer); the walls' Shepard weights. */
static void geometry(surge_sim *sim)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const kernel2d *k = &sim->kernel;
    const real grad_coef = k->grad_coef, inv_h = k->inv_h, alpha = k->alpha, support2 = k->support2;
    const real mass = (real)sim->mass, vol = (real)(sim->mass / sim->rho0);
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const double inv_lattice = 1.0 / sim->lattice_kernel_sum;
    const int first = sim->wall_count, n = sim->count;
    const int offsets = sim->params.implicit.wall_neumann_offset > 0;
    if (!w->wall_sum_ready || sim->boulders.count > 0)
        wall_sums(sim);
    /* the walls' ghost nodes: each fluid neighbour's weight in the first-order (kernel-corrected) interpolation at
     * the node, as boundary.c's mDBC; Shepard's where the correction matrix is ill-conditioned */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        const ghost_span g = ghost_span_of(sim, kw);
        double lane[3][3][PAIR_LANES] = {{{0}}}; /* per-lane partial sums (lanes.h) */
        for (int64_t e0 = g.from; e0 < g.to; e0 += PAIR_LANES)
            #pragma omp simd simdlen(PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int j = g.index[e0 + l];
                const real dx = g.dx0[e0 + l] - moved_x[j] + g.shift_x, dy = g.dy0[e0 + l] - moved_y[j] + g.shift_y; /* r_g - r_j */
                const real r2 = dx * dx + dy * dy, r = REAL_SQRT(r2);
                const int inside = r2 < support2;
                const double w_vol = inside ? kernel2d_w_inside(alpha, inv_h, r) * vol : 0;
                const double f_vol = inside ? kernel2d_grad_factor_inside(grad_coef, inv_h, r) * vol : 0;
                const double u[3] = {w_vol, f_vol * dx, f_vol * dy}, rel[3] = {1, -(double)dx, -(double)dy};
                for (int q = 0; q < 3; q++)
                    for (int c = 0; c < 3; c++)
                        lane[q][c][l] += u[q] * rel[c];
            }
        double a[3][3];
        for (int q = 0; q < 3; q++)
            for (int c = 0; c < 3; c++)
                a[q][c] = lanes_total(lane[q][c]);
        const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        double row[3] = {0, 0, 0}; /* the first row of a^-1: the value at the node from the sums */
        double normal_row[3] = {0, 0, 0}; /* n . (its second and third rows): the derivative along the normal */
        if (fabs(det) >= MIN_DETERMINANT && a[0][0] >= MIN_SHEPARD_SUM) {
            row[0] = (a[1][1] * a[2][2] - a[1][2] * a[2][1]) / det;
            row[1] = -(a[0][1] * a[2][2] - a[0][2] * a[2][1]) / det;
            row[2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / det;
            if (offsets) {
                const double glen = sqrt((double)sim->ghost_dx[kw] * sim->ghost_dx[kw] +
                                         (double)sim->ghost_dy[kw] * sim->ghost_dy[kw]);
                const double nx = sim->ghost_dx[kw] / glen, ny = sim->ghost_dy[kw] / glen;
                normal_row[0] = (-nx * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) + ny * (a[1][0] * a[2][1] - a[1][1] * a[2][0])) / det;
                normal_row[1] = (nx * (a[0][0] * a[2][2] - a[0][2] * a[2][0]) - ny * (a[0][0] * a[2][1] - a[0][1] * a[2][0])) / det;
                normal_row[2] = (-nx * (a[0][0] * a[1][2] - a[0][2] * a[1][0]) + ny * (a[0][0] * a[1][1] - a[0][1] * a[1][0])) / det;
            }
        } else if (a[0][0] >= MIN_SHEPARD_SUM) {
            row[0] = 1.0 / a[0][0];
        }
        w->dry[kw] = a[0][0] < MIN_SHEPARD_SUM;
        /* the node's kernel sum of fluid and walls: 1.00 in the fluid (corners included), 0.77 level with the top
         * row next to the tank's side wall, 0.58 a dp above it (C_h 1.8); wetness ramps from 0 at 0.6 to 1 at 0.75,
         * immersion (the node's kernel is full: phi's Neumann offset applies) from 0 at 0.90 to 1 at 0.98 */
        w->wetness[kw] = (real)fmin(1.0, fmax(0.0, (a[0][0] + w->wall_sum[kw] - 0.6) / 0.15));
        w->immersion[kw] = (real)fmin(1.0, fmax(0.0, (a[0][0] + w->wall_sum[kw] - 0.9) / 0.08));
        for (int64_t e = g.from; e < g.to; e++) {
            const int j = g.index[e];
            const real dx = g.dx0[e] - moved_x[j] + g.shift_x, dy = g.dy0[e] - moved_y[j] + g.shift_y;
            const real r2 = dx * dx + dy * dy, r = REAL_SQRT(r2);
            double c = 0, cn = 0;
            if (r2 < support2 && !w->dry[kw]) {
                const double f_vol = kernel2d_grad_factor_inside(grad_coef, inv_h, r) * vol;
                c = row[0] * kernel2d_w_inside(alpha, inv_h, r) * vol + row[1] * f_vol * dx + row[2] * f_vol * dy;
                cn = normal_row[0] * kernel2d_w_inside(alpha, inv_h, r) * vol + normal_row[1] * f_vol * dx +
                     normal_row[2] * f_vol * dy;
            }
            g.weight[e] = (real)c;
            if (offsets)
                g.normal_weight[e] = (real)cn;
        }
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = first; a < n; a++) {
        const int i = a - first;
        const real mxa = moved_x[a], mya = moved_y[a];
        geometry_lanes sums;
        memset(&sums, 0, sizeof sums);
        geometry_pairs(sim, mxa, mya, nl->fluid_first[i], nl->fluid_first[i + 1], 0, &sums);
        geometry_pairs(sim, mxa, mya, nl->wall_first[i], nl->wall_first[i + 1], 1, &sums);
        const real *const first_eight[8] = {sums.kernel_w, sums.div_r, sums.grad_c_x, sums.grad_c_y,
                                            sums.m_xx, sums.m_xy, sums.m_yy, sums.zero};
        real total[8];
        lanes_totals(first_eight, total);
        const real kernel_w = total[0], div_r = total[1], grad_c_x = total[2], grad_c_y = total[3];
        const real m_xx = total[4], m_xy = total[5], m_yy = total[6];
        const double wrx = lanes_total(sums.wrx), wry = lanes_total(sums.wry);
        w->kernel_ratio[i] = mass * (alpha + kernel_w) * inv_lattice / sim->rho0;
        /* the nearest wall face within dp, for the contact rule and shifting (as the explicit scheme's) */
        int near_disc = 0;
        const wall_face face = interaction_wall_face(sim, a, (real)sim->params.numerics.dp_m, &near_disc);
        sim->face_nx[a] = face.nx, sim->face_ny[a] = face.ny, sim->face_gap_m[a] = face.gap_m;
        sim->face_vn_mps[a] = face.vn_mps, sim->face_disc[a] = face.disc;
        w->near_disc[i] = (uint8_t)near_disc;
        /* a free-surface particle: div r low, or a kernel sum short of the second row's under a flat surface (a
         * contact line, where the wall raises div r; docs/method.md). Not the latter next to a disc, whose rings
         * fill its circle less evenly than a wall's rows their half-plane: a particle 0.7 dp off a disc of radius 5
         * dp has 0.87 of the lattice's kernel sum in fluid at rest */
        sim->surface[a] = div_r < (real)sim->params.implicit.surface_threshold ||
                          (!near_disc && w->kernel_ratio[i] < sim->second_row_kernel_ratio -
                                                                  sim->params.implicit.surface_kernel_margin);
        const double det = (double)m_xx * m_yy - (double)m_xy * m_xy;
        if (det > 0.25) {
            w->minv_xx[i] = m_yy / det, w->minv_xy[i] = -m_xy / det, w->minv_yy[i] = m_xx / det;
        } else {
            w->minv_xx[i] = 1, w->minv_xy[i] = 0, w->minv_yy[i] = 1;
        }
        w->weighted_rx[i] = wrx, w->weighted_ry[i] = wry;
        sim->div_r[a] = div_r;
        sim->inv_rho[a] = (real)(1.0 / sim->rho0);
        sim->grad_c_x[a] = grad_c_x, sim->grad_c_y[a] = grad_c_y;
        w->fixed[i] = (uint8_t)sim->surface[a];
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = first; a < n; a++) {
        const int i = a - first;
        int near = sim->surface[a];
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1] && !near; e++)
            near = w->fluid_w[e] != 0 && sim->surface[nl->fluid_index[e]];
        sim->near_surface[a] = (uint8_t)near;
        /* the surface's normal for the shift (shifting.c): the neighbours' grad C, weighted as the Laplacian */
        double nx = 0, ny = 0;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1] && near; e++) {
            const int b = nl->fluid_index[e];
            nx += w->fluid_w[e] * sim->grad_c_x[b], ny += w->fluid_w[e] * sim->grad_c_y[b];
        }
        const double length = sqrt(nx * nx + ny * ny);
        sim->surface_nx[a] = (real)(length > 0 ? nx / length : 0), sim->surface_ny[a] = (real)(length > 0 ? ny / length : 0);
        /* the kernel sum at rest spacing at this depth under a flat surface (the nearest surface particle's distance
         * in rows, between the lattice's rows), where no wall in reach is partly dry (a contact line, where the
         * walls' share is uncertain): 0 where it cannot be read */
        double depth2 = near && !sim->surface[a] ? INFINITY : 0;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1] && depth2 > 0; e++) {
            const int b = nl->fluid_index[e];
            if (!sim->surface[b] || w->fluid_w[e] == 0)
                continue;
            const double dx = nl->fluid_dx0[e] + (moved_x[a] - moved_x[b]), dy = nl->fluid_dy0[e] + (moved_y[a] - moved_y[b]);
            depth2 = fmin(depth2, dx * dx + dy * dy);
        }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1] && depth2 > 0; e++)
            if (w->wall_w[e] != 0 && w->wetness[nl->wall_index[e]] < 1)
                depth2 = 0;
        const double rows = sqrt(depth2) / sim->params.numerics.dp_m;
        const int row = rows < SURGE_KERNEL_ROWS - 1 ? (int)rows : SURGE_KERNEL_ROWS - 2;
        const double f = fmin(1.0, rows - row);
        w->expected_ratio[i] = depth2 > 0 ? (1 - f) * sim->row_kernel_ratio[row] + f * sim->row_kernel_ratio[row + 1] : 0;
    }
}

/* The interpolated value at wall kw's ghost node of the fluid field x */
static inline double ghost_value(const surge_sim *sim, int kw, const double *x)
{
    const ghost_span g = ghost_span_of(sim, kw);
    double sum[PAIR_LANES] = {0};
    for (int64_t e = g.from; e < g.to; e += PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++)
            sum[l] += g.weight[e + l] * x[g.index[e + l] - sim->wall_count];
    return lanes_total(sum);
}

/* The fluid's velocity interpolated at wall kw's ghost node */
static inline void ghost_velocity(const surge_sim *sim, int kw, double *vx, double *vy)
{
    const ghost_span g = ghost_span_of(sim, kw);
    double sx = 0, sy = 0;
    for (int64_t e = g.from; e < g.to; e++)
        sx += g.weight[e] * sim->vx[g.index[e]], sy += g.weight[e] * sim->vy[g.index[e]];
    *vx = sx, *vy = sy;
}

/* The derivative of the velocity's component along the ghost's normal n (from the wall into the fluid), along n,
 * at the wall's ghost node: n . grad (v . n), from the first-order interpolation's gradient rows (geometry) */
static inline double ghost_normal_strain(const surge_sim *sim, int kw)
{
    const ghost_span g = ghost_span_of(sim, kw);
    const double glen = sqrt((double)sim->ghost_dx[kw] * sim->ghost_dx[kw] + (double)sim->ghost_dy[kw] * sim->ghost_dy[kw]);
    const double nx = sim->ghost_dx[kw] / glen, ny = sim->ghost_dy[kw] / glen;
    double s = 0;
    for (int64_t e = g.from; e < g.to; e++)
        s += g.normal_weight[e] * (sim->vx[g.index[e]] * nx + sim->vy[g.index[e]] * ny);
    return s;
}

/* Backward-Euler viscosity, F(v) = v - dt nu lap v with no-slip walls at 2 v_wall - v_ghost; x = (vx | vy). */
static void viscous_operator(surge_sim *sim, const double *x, double *out)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    const double dt_nu = sim->dt_s * sim->params.fluid.viscosity_m2ps;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        const double ux = w->mirror_vx[kw], uy = w->mirror_vy[kw];
        const double gx = w->dry[kw] ? ux : ghost_value(sim, kw, x), gy = w->dry[kw] ? uy : ghost_value(sim, kw, x + nf);
        w->wall_x[kw] = 2.0 * ux - gx, w->wall_y[kw] = 2.0 * uy - gy;
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const double xa = x[i], ya = x[nf + i];
        double lx[PAIR_LANES] = {0}, ly[PAIR_LANES] = {0};
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int j = nl->fluid_index[e + l] - sim->wall_count;
                lx[l] += w->fluid_w[e + l] * (xa - x[j]), ly[l] += w->fluid_w[e + l] * (ya - x[nf + j]);
            }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int kw = nl->wall_index[e + l];
                lx[l] += w->wall_w[e + l] * (xa - w->wall_x[kw]), ly[l] += w->wall_w[e + l] * (ya - w->wall_y[kw]);
            }
        out[i] = xa + dt_nu * lanes_total(lx), out[nf + i] = ya + dt_nu * lanes_total(ly);
    }
}

/* The walls' pressure from the fluid pressure x: the value at the ghost plus the Neumann offset (none where
 * offset_pa is NULL: the solves' linear operator); dry walls 0. */
static void wall_pressures(surge_sim *sim, const double *x, const double *offset_pa)
{
    implicit_work *w = sim->implicit;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++)
        w->wall_x[kw] = w->dry[kw] ? 0.0 : ghost_value(sim, kw, x) + (offset_pa ? offset_pa[kw] : 0.0);
}

/* The walls' Neumann offsets are the affine part of phi's operator: they go to the right-hand side, rhs_a -=
 * sum_w c_aw offset_w, and the solve takes the linear part alone */
static void wall_offsets_to_rhs(surge_sim *sim, const double *offset_pa)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        if (w->fixed[i])
            continue;
        double sum = 0;
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
            const int kw = nl->wall_index[e];
            sum += w->dry[kw] ? 0.0 : w->wall_pc[e] * offset_pa[kw];
        }
        w->rhs[i] -= sum;
    }
}

/* The renormalised gradient of the pressure field x (free-surface particles at 0, walls at wall_x), exact for
 * a linear field: grad p_a = M^-1 sum_b V_b (p_b - p_a) f r_ab */
static void pressure_gradient(surge_sim *sim, const double *x)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const double pa = w->fixed[i] ? 0.0 : x[i];
        double lx[PAIR_LANES] = {0}, ly[PAIR_LANES] = {0};
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int j = nl->fluid_index[e + l] - sim->wall_count;
                const double dpb = (w->fixed[j] ? 0.0 : x[j]) - pa;
                lx[l] += dpb * w->fluid_gx[e + l], ly[l] += dpb * w->fluid_gy[e + l];
            }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int kw = nl->wall_index[e + l];
                const double dpb = (w->wall_x[kw] - pa) * w->wetness[kw]; /* dry walls: air, as in geometry() */
                lx[l] += dpb * w->wall_gx[e + l], ly[l] += dpb * w->wall_gy[e + l];
            }
        const double sx = lanes_total(lx), sy = lanes_total(ly);
        w->grad_x[i] = w->minv_xx[i] * sx + w->minv_xy[i] * sy;
        w->grad_y[i] = w->minv_xy[i] * sx + w->minv_yy[i] * sy;
    }
}

/* -lap p, corrected for the kernel's truncation: sum_b w_ab (p_a - p_b - r_ab . grad p_a), which is exact (zero)
 * for a linear field also next to the free surface and the walls, where the plain sum is not; p = 0 held on
 * free-surface particles (their rows are the identity). With grad p_a = M^-1 sum_b V_b (p_b - p_a) f r_ab (walls
 * by their wetness) and u_a = M^-1 sum_b w_ab r_ab, each neighbour's term is (w_ab + q_ab)(p_a - p_b) with
 * q_ab = u_a . V_b f r_ab: the step's coefficients, computed once here for the two solves (phi and psi) that use
 * them, so that an iteration is one gather (a free-surface neighbour's coefficient is 0, its p held at 0). */
static void assemble_pressure(surge_sim *sim)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const double wrx = w->weighted_rx[i], wry = w->weighted_ry[i];
        const double ux = w->minv_xx[i] * wrx + w->minv_xy[i] * wry, uy = w->minv_xy[i] * wrx + w->minv_yy[i] * wry;
        double diag = 0;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
            const double c = w->fluid_w[e] + ux * w->fluid_gx[e] + uy * w->fluid_gy[e];
            diag += c;
            w->fluid_pc[e] = (real)(w->fixed[nl->fluid_index[e] - sim->wall_count] ? 0.0 : -c);
        }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
            const double c = w->wall_w[e] + w->wetness[nl->wall_index[e]] * (ux * w->wall_gx[e] + uy * w->wall_gy[e]);
            diag += c;
            w->wall_pc[e] = (real)-c;
        }
        w->pressure_diag[i] = w->fixed[i] ? 1.0 : diag;
    }
}

/* The multigrid's sparse stand-in for an operator on the fluid particles whose row i is diag[i], fluid_scale
 * fluid_coef[e] for each fluid neighbour and wall_scale wall_coef[e] for each wet wall neighbour, whose value the
 * operator takes from the wall's ghost node (with honour_fixed a free-surface particle's row is its diagonal
 * alone, the pressure's). Of each row's fluid entries only those at least SPARSE_KEEP of the row's largest (the
 * nearest neighbours) stay; the others, and each wet wall
 * neighbour's entry (its ghost's interpolation taken at the particle itself), are added to the diagonal, which
 * keeps every row's sum: the same operator on a constant and on smooth fields, a few entries a row instead of a
 * kernel's 80. A preconditioner only: the solve iterates on the operator itself. -1 when out of memory. */
static int assemble_sparse(surge_sim *sim, const double *diag, const real *fluid_coef, double fluid_scale,
                           const real *wall_coef, double wall_scale, int honour_fixed)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const int first = sim->wall_count, nf = sim->count - first;
    /* each row is written once, where it has room for all its entries (fluid_first[i] + i: its fluid neighbours and
     * the diagonal), then the rows are closed up */
    const size_t room = (size_t)nl->fluid_first[nf] + (size_t)nf;
    if (!w->matrix_first && !(w->matrix_first = malloc((size_t)(nf + 1) * sizeof *w->matrix_first)))
        return -1;
    if (room > w->matrix_cap || !w->matrix_col) {
        int32_t *col = realloc(w->matrix_col, room * sizeof *col);
        if (col)
            w->matrix_col = col;
        double *val = col ? realloc(w->matrix_val, room * sizeof *val) : NULL;
        if (!val)
            return -1;
        w->matrix_val = val, w->matrix_cap = room;
    }
    int64_t *row_first = w->matrix_first;
    int32_t *restrict col = w->matrix_col;
    double *restrict val = w->matrix_val;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int64_t start = nl->fluid_first[i] + i;
        int64_t at = start;
        double d = diag[i];
        col[at] = i;
        if (honour_fixed && w->fixed[i]) {
            /* a free-surface row is its diagonal alone, at the size it has off the surface, so that a hierarchy
             * held over steps (multigrid_setup) serves the particle when it leaves the surface */
            double coupled = 0;
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
                coupled -= fluid_scale * fluid_coef[e];
            for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++)
                coupled -= w->dry[nl->wall_index[e]] ? 0.0 : wall_scale * wall_coef[e];
            d = coupled > 0 ? coupled : d;
        } else {
            double largest = 0;
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
                largest = fabs((double)fluid_coef[e]) > largest ? fabs((double)fluid_coef[e]) : largest;
            const double smallest_kept = SPARSE_KEEP * largest;
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
                if (fluid_coef[e] == 0)
                    continue;
                if (fabs((double)fluid_coef[e]) >= smallest_kept)
                    ++at, col[at] = nl->fluid_index[e] - first, val[at] = fluid_scale * fluid_coef[e];
                else
                    d += fluid_scale * fluid_coef[e];
            }
            for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) /* the weights sum to 1 */
                d += w->dry[nl->wall_index[e]] ? 0.0 : wall_scale * wall_coef[e];
        }
        val[start] = d;
        row_first[i + 1] = at + 1 - start;
    }
    row_first[0] = 0;
    for (int i = 0; i < nf; i++) {
        const int64_t start = nl->fluid_first[i] + i, count = row_first[i + 1];
        row_first[i + 1] = row_first[i] + count;
        memmove(col + row_first[i], col + start, (size_t)count * sizeof *col);
        memmove(val + row_first[i], val + start, (size_t)count * sizeof *val);
    }
    return 0;
}

/* The operator of assemble_pressure applied to x, the walls at their ghosts' values (the linear part: no offsets) */
static void pressure_operator(surge_sim *sim, const double *x, double *out)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    wall_pressures(sim, x, NULL);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        double sum[PAIR_LANES] = {0};
        if (!w->fixed[i]) {
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e += PAIR_LANES)
                for (int l = 0; l < PAIR_LANES; l++)
                    sum[l] += w->fluid_pc[e + l] * x[nl->fluid_index[e + l] - sim->wall_count];
            for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e += PAIR_LANES)
                for (int l = 0; l < PAIR_LANES; l++)
                    sum[l] += w->wall_pc[e + l] * w->wall_x[nl->wall_index[e + l]];
        }
        out[i] = w->pressure_diag[i] * x[i] + lanes_total(sum);
    }
}

/* sum_i a_i b_i (b NULL: sum_i a_i) over n, in fixed blocks added in order: the same for any thread count */
static double dot(const implicit_work *w, const double *a, const double *b, int n)
{
    const int blocks = (n + DOT_BLOCK - 1) / DOT_BLOCK;
    #pragma omp parallel for schedule(static) if (n >= WIDE_FLUID_PARTICLES)
    for (int k = 0; k < blocks; k++) {
        const int from = k * DOT_BLOCK, to = from + DOT_BLOCK < n ? from + DOT_BLOCK : n;
        double sum = 0;
        for (int i = from; i < to; i++)
            sum += b ? a[i] * b[i] : a[i];
        w->partial[k] = sum;
    }
    double sum = 0;
    for (int k = 0; k < blocks; k++)
        sum += w->partial[k];
    return sum;
}

/* The linear part of the operator: F(x) - F(0) (offset holds F(0)), or F(x) itself where F is linear */
static void apply_linear(surge_sim *sim, affine_operator op, int linear, const double *x, double *out, int n)
{
    op(sim, x, out);
    if (linear)
        return;
    const double *offset = sim->implicit->offset;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < n; i++)
        out[i] -= offset[i];
}

/* out = M^-1 in: the diagonal (Jacobi) or one V-cycle per block of nf unknowns; -1 when hypre fails */
static int precondition(surge_sim *sim, const double *in, double *out, int n)
{
    implicit_work *w = sim->implicit;
    if (w->vcycle_blocks == 0) {
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < n; i++)
            out[i] = in[i] / w->diag[i];
        return 0;
    }
    const int nf = n / w->vcycle_blocks;
    if (amg_vcycle(w->amg, w->vcycle_blocks, in, out) != 0)
        return -1;
    if (w->vcycle_honours_fixed) /* the pressure's free-surface rows are the identity (held hierarchies differ) */
        for (int i = 0; i < nf; i++)
            if (w->fixed[i])
                out[i] = in[i];
    return 0;
}

/* Solves F(x) = rhs for the affine operator op (n unknowns) by BiCGSTAB, preconditioned as precondition() says
 * (van der Vorst 1992), to |residual| <= tolerance |rhs - F(0)|, from the guess in x. homogeneous: F is linear
 * (F(0) = 0), LINEAR_FROM_ZERO where x is 0 too (no operator call before the iterations), LINEAR_FROM_GUESS from the
 * guess in x. Returns the iterations, or -1 when max_iterations pass first or the method breaks down; *residual: the
 * relative residual reached. */
static int solve(surge_sim *sim, affine_operator op, int n, int homogeneous, double tolerance, int max_iterations,
                 double *residual)
{
    implicit_work *w = sim->implicit;
    double *x = w->x, *r = w->r, *rhat = w->rhat, *p = w->p, *v = w->v, *s = w->s, *t = w->t, *y = w->y, *z = w->z;
    const int from_guess = homogeneous == LINEAR_FROM_GUESS;
    if (from_guess)
        op(sim, x, r);
    else if (!homogeneous) {
        op(sim, (memset(y, 0, (size_t)n * sizeof *y), y), w->offset);
        apply_linear(sim, op, 0, x, r, n);
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < n; i++) {
        const double b = homogeneous ? w->rhs[i] : w->rhs[i] - w->offset[i];
        r[i] = homogeneous == LINEAR_FROM_ZERO ? b : b - r[i];
        rhat[i] = b; /* the shadow residual: the right-hand side (nonzero whenever there is work) */
        p[i] = v[i] = 0;
    }
    const double b_norm = sqrt(dot(w, rhat, rhat, n));
    double r_norm = sqrt(dot(w, r, r, n));
    *residual = b_norm > 0 ? r_norm / b_norm : 0;
    if (b_norm == 0 || r_norm <= tolerance * b_norm)
        return 0;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < n; i++)
        rhat[i] = r[i];
    double rho = 1, alpha = 1, omega = 1;
    for (int it = 1; it <= max_iterations; it++) {
        const double rho_new = dot(w, rhat, r, n);
        if (rho_new == 0 || omega == 0)
            return -1;
        const double beta = rho_new / rho * alpha / omega;
        rho = rho_new;
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < n; i++)
            p[i] = r[i] + beta * (p[i] - omega * v[i]);
        if (precondition(sim, p, y, n) != 0)
            return -1;
        apply_linear(sim, op, homogeneous, y, v, n);
        const double rv = dot(w, rhat, v, n);
        if (rv == 0)
            return -1;
        alpha = rho / rv;
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < n; i++) {
            x[i] += alpha * y[i];
            s[i] = r[i] - alpha * v[i];
        }
        const double s_norm = sqrt(dot(w, s, s, n));
        if (s_norm <= tolerance * b_norm) {
            *residual = s_norm / b_norm;
            return it;
        }
        if (precondition(sim, s, z, n) != 0)
            return -1;
        apply_linear(sim, op, homogeneous, z, t, n);
        const double tt = dot(w, t, t, n);
        omega = tt > 0 ? dot(w, t, s, n) / tt : 0;
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < n; i++) {
            x[i] += omega * z[i];
            r[i] = s[i] - omega * t[i];
        }
        r_norm = sqrt(dot(w, r, r, n));
        *residual = r_norm / b_norm;
        if (!isfinite(r_norm))
            return -1;
        if (r_norm <= tolerance * b_norm)
            return it;
    }
    return -1;
}

/* dt = min(cfl h / u_max, force_cfl sqrt(h / |g|)) from the velocities at the step's start */
static double implicit_dt(const surge_sim *sim)
{
    const surge_params *p = &sim->params;
    if (p->numerics.dt_fixed_s > 0)
        return p->numerics.dt_fixed_s;
    double max_v2 = 0;
    #pragma omp parallel for schedule(static) reduction(max : max_v2) if (wide(sim))
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double v2 = (double)sim->vx[a] * sim->vx[a] + (double)sim->vy[a] * sim->vy[a];
        max_v2 = v2 > max_v2 ? v2 : max_v2;
    }
    const boulder_set *b = &sim->boulders;
    for (int i = 0; i < b->count; i++) { /* a disc's surface moves with it */
        const double v = sqrt(b->vx[i] * b->vx[i] + b->vy[i] * b->vy[i]) + fabs(b->omega[i]) * b->radius[i];
        max_v2 = fmax(max_v2, v * v);
    }
    const double h = sim->derived.h_m, g = sqrt(sim->gx * sim->gx + sim->gy * sim->gy);
    double dt = surge_implicit_dt_s(p, h, g, sqrt(max_v2));
    /* the discs' coupling: a disc's drag stiffness k (its last step's) against its mass and added mass
     * (boulders_advance_implicit; docs/method.md) */
    for (int i = 0; i < b->count && p->implicit.disc_coupling > 0; i++)
        if (b->drag_stiffness[i] > 0) {
            const double added = p->implicit.added_mass * sim->rho0 * SURGE_PI * b->radius[i] * b->radius[i] * b->wetted[i];
            dt = fmin(dt, p->implicit.disc_coupling * (b->mass[i] + added) / b->drag_stiffness[i]);
        }
    if (isfinite(dt))
        return dt;
    /* no gravity and at rest: the walls' speeds set the scale */
    return p->implicit.cfl * h / fmax(fabs(p->walls.bottom_speed_mps) + fabs(p->walls.top_speed_mps), 1e-12);
}

static void fail_solve(surge_sim *sim, const char *what, int iterations, double residual, double t_n)
{
    sim->health = (surge_health){.check = SURGE_CHECK_SOLVER, .particle_id = -1, .step = sim->step + 1,
                                 .time_s = t_n, .value = residual};
    snprintf(sim->health.message, sizeof sim->health.message,
             "health check failed: %s at step %lld, t = %.9g s (the %s solve reached a relative residual of %.3g "
             "in %d iterations; implicit.max_iterations = %d, tolerance %g; try a smaller implicit.cfl)",
             surge_health_check_name(SURGE_CHECK_SOLVER), (long long)sim->step + 1, t_n, what, residual,
             iterations, sim->params.implicit.max_iterations,
             what[0] == 'v' ? sim->params.implicit.viscous_tolerance
             : what[0] == 'r' ? sim->params.implicit.density_tolerance : sim->params.implicit.pressure_tolerance);
}

/* Whether this step's pressure (or viscous) solves use the multigrid (implicit.preconditioner) */
static int multigrid(const surge_sim *sim, bool viscous)
{
    return surge_implicit_uses_amg(&sim->params, sim->count - sim->wall_count, viscous);
}

/* The multigrid hierarchy of a system (which: MULTIGRID_VISCOUS or _PRESSURE; what names it) for this step's solves:
 * the held one while it is younger than implicit.multigrid_rebuild_steps and its solve has not slowed, else one
 * built on the sparse stand-in of assemble_sparse (its arguments after which); a health failure (with the reason)
 * when it cannot be built */
static int multigrid_setup(surge_sim *sim, int which, const char *what, const double *diag, const real *fluid_coef,
                           double fluid_scale, const real *wall_coef, double wall_scale, int honour_fixed)
{
    implicit_work *w = sim->implicit;
    held_multigrid *m = &w->multigrid[which];
    char reason[160] = "";
    if (!m->amg)
        m->amg = amg_create(reason, sizeof reason, multigrid_blocks(which));
    const int first = sim->wall_count, nf = sim->count - first;
    w->amg = m->amg;
    const int slowed = m->base_iterations >= 0 &&
                       m->last_iterations > m->base_iterations + (m->base_iterations / 2 > 2 ? m->base_iterations / 2 : 2);
    if (m->amg && amg_rows(m->amg) == nf && sim->step - m->built_step < sim->params.implicit.multigrid_rebuild_steps &&
        !slowed && amg_follow(m->amg, sim->id + first, nf) == 0)
        return 0;
    if (m->amg && assemble_sparse(sim, diag, fluid_coef, fluid_scale, wall_coef, wall_scale, honour_fixed) != 0)
        snprintf(reason, sizeof reason, "out of memory for the %s matrix's sparse stand-in", what);
    else if (m->amg && amg_setup(m->amg, nf, w->matrix_first, w->matrix_col, w->matrix_val, sim->id + first,
                                 sim->count) != 0)
        snprintf(reason, sizeof reason, "hypre could not build the multigrid hierarchy of the %s matrix", what);
    if (!reason[0]) {
        m->built_step = sim->step, m->base_iterations = -1;
        return 0;
    }
    sim->health = (surge_health){.check = SURGE_CHECK_SOLVER, .particle_id = -1, .step = sim->step + 1,
                                 .time_s = sim->time_s};
    snprintf(sim->health.message, sizeof sim->health.message, "health check failed: %s at step %lld, t = %.9g s (%s)",
             surge_health_check_name(SURGE_CHECK_SOLVER), (long long)sim->step + 1, sim->time_s, reason);
    return -1;
}

/* Records a solve's iterations with the hierarchy of which (the first after its build is its base) */
static void multigrid_record(surge_sim *sim, int which, int iterations)
{
    held_multigrid *m = &sim->implicit->multigrid[which];
    if (m->base_iterations < 0)
        m->base_iterations = iterations;
    m->last_iterations = iterations;
}

/* A solve of the pressure operator (phi or psi; linear, the walls' Neumann offsets being 0 in step 2) from x = 0
 * or (from_guess) the guess in x, by the preconditioner the parameters choose */
static int pressure_solve(surge_sim *sim, int from_guess, double tolerance, double *residual)
{
    const int nf = sim->count - sim->wall_count, max_iterations = sim->params.implicit.max_iterations;
    sim->implicit->vcycle_blocks = sim->implicit->vcycle_honours_fixed = sim->implicit->pressure_by_multigrid;
    const int iterations = solve(sim, pressure_operator, nf, from_guess ? LINEAR_FROM_GUESS : LINEAR_FROM_ZERO,
                                 tolerance, max_iterations, residual);
    sim->implicit->vcycle_blocks = sim->implicit->vcycle_honours_fixed = 0;
    return iterations;
}

/* Close pairs (implicit.pair_distance_dp, docs/method.md): each fluid particle closer than the distance to another
 * loses half their speed toward each other and moves half the way to the distance apart (the MPS collision model,
 * Lee et al. 2011, at restitution 0), from the step's velocities and positions, so each pair's changes are equal and
 * opposite and momentum is kept. */
static void part_close_pairs(surge_sim *sim)
{
    implicit_work *w = sim->implicit;
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

/* eq. 10 with the step's answer: the fluid's v_n+1 and p_n+1 at the step's start positions (the walls' pressures
 * continued from their ghosts, the disc particles' velocities mirrored about the disc's surface), summed over each
 * disc's particles by boulders_fluid_forces as the explicit scheme's pair forces are, relative to the mean pressure
 * of the disc's particles, and the reactions of the contact rule. The fluid's density is rho0 (the scheme holds
 * it). */
static void disc_forces(surge_sim *sim)
{
    implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const real rho0 = (real)sim->rho0, inv_rho0 = (real)(1.0 / sim->rho0);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        if (sim->wall_of[kw] != WALL_BOULDER)
            continue;
        double gvx = w->mirror_vx[kw], gvy = w->mirror_vy[kw];
        if (!w->dry[kw])
            ghost_velocity(sim, kw, &gvx, &gvy);
        sim->wall_vx[kw] = (real)(2.0 * w->mirror_vx[kw] - gvx);
        sim->wall_vy[kw] = (real)(2.0 * w->mirror_vy[kw] - gvy);
        sim->rho[kw] = rho0, sim->inv_rho[kw] = inv_rho0;
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = sim->wall_count; a < sim->count; a++)
        sim->pair_state[a] = (pair_state){nl->moved_x[a], nl->moved_y[a], sim->vx[a], sim->vy[a], rho0, inv_rho0,
                                          sim->pressure[a], (real)sim->surface[a]};
    const boulder_set *b = &sim->boulders;
    double *reference = w->disc_reference_pa;
    memset(reference, 0, (size_t)b->count * sizeof *reference);
    for (int kw = 0; kw < sim->wall_count; kw++) /* in index order: the same sums whatever the thread count */
        if (sim->wall_of[kw] == WALL_BOULDER)
            reference[b->of_wall[sim->id[kw]]] += sim->pressure[kw];
    for (int i = 0; i < b->count; i++)
        reference[i] /= boulders_particles_of(sim, i);
    boulders_fluid_forces(sim, reference);
    boulders_wetted_fraction(sim, w->wetness);
}

/* Fluid particle i's per-lane partial sums of the velocity gradient G = -sum_b V_b f v_ab (x) r_ab and of its
 * Laplacian weights (lanes.h), added in lane order at the end */
typedef struct gradient_lanes {
    double xx[PAIR_LANES], xy[PAIR_LANES], yx[PAIR_LANES], yy[PAIR_LANES], w[PAIR_LANES];
} gradient_lanes;

/* The pairs of list entries from..to of a fluid particle with velocity (vxa, vya): its fluid list (neighbours at
 * sim->vx, vy) or (walls) its wall list (walls at wall_x, wall_y) */
static inline __attribute__((always_inline)) void gradient_pairs(const surge_sim *sim, double vxa, double vya,
                                                                 int64_t from, int64_t to, int walls, gradient_lanes *s)
{
    const implicit_work *w = sim->implicit;
    const neighbour_lists *nl = &sim->neighbours;
    const int32_t *restrict index = walls ? nl->wall_index : nl->fluid_index;
    const real *restrict gx = walls ? w->wall_gx : w->fluid_gx, *restrict gy = walls ? w->wall_gy : w->fluid_gy;
    const real *restrict weight = walls ? w->wall_w : w->fluid_w;
    for (int64_t e0 = from; e0 < to; e0 += PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            const int b = index[e];
            const double dvx = vxa - (walls ? w->wall_x[b] : sim->vx[b]), dvy = vya - (walls ? w->wall_y[b] : sim->vy[b]);
            s->xx[l] -= dvx * gx[e], s->xy[l] -= dvx * gy[e];
            s->yx[l] -= dvy * gx[e], s->yy[l] -= dvy * gy[e];
            s->w[l] += weight[e];
        }
}

int step_implicit(surge_sim *sim)
{
    const int first = sim->wall_count, n = sim->count, nf = n - first;
    const double t_n = sim->time_s;
    const surge_params *prm = &sim->params;
    if (neighbours_update(sim) != 0 || reserve_work(sim) != 0) {
        sim->health = (surge_health){.check = SURGE_CHECK_OUT_OF_MEMORY, .particle_id = -1, .step = sim->step + 1,
                                     .time_s = t_n};
        snprintf(sim->health.message, sizeof sim->health.message, "out of memory for the implicit scheme's arrays");
        return -1;
    }
    implicit_work *w = sim->implicit;
    const double dt = implicit_dt(sim);
    sim->dt_s = dt;
    if (sim->step == 0 && sim->first_dt_s == 0)
        sim->first_dt_s = dt;
    boundary_wall_speeds(sim, t_n + dt); /* backward Euler: the walls' velocities at the end of the step (the discs':
                                          * at its start; their fluid forces come after the step) */
    #pragma omp parallel
    {
        interaction_prepare(sim, 0);
        boundary_update(sim, 0); /* the walls' normals and depths (the contact rule) */
    }
    geometry(sim);
    mirror_velocities(sim);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = first; a < n; a++) {
        sim->x_n[a] = sim->x[a], sim->y_n[a] = sim->y[a];
        sim->vx_n[a] = sim->vx[a], sim->vy_n[a] = sim->vy[a], sim->rho_n[a] = sim->rho[a];
    }

    /* 1. v* = v_n + dt (g - grad p_n / rho0 + nu lap v*): backward-Euler viscosity with the last step's pressure,
     * from the guess v_n */
    const double rho0 = sim->rho0, dt_nu = dt * prm->fluid.viscosity_m2ps;
    const neighbour_lists *nl = &sim->neighbours;
    double *by_id = sim->implicit_pressure_by_id;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++)
        w->pressure_n[i] = w->fixed[i] ? 0.0 : by_id[sim->id[first + i]];
    /* the walls' p_n: the fluid's at the ghost node continued by the body force's hydrostatic gradient rho0 g */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < first; kw++)
        w->neumann_pa[kw] = -rho0 * (sim->gx * sim->ghost_dx[kw] + sim->gy * sim->ghost_dy[kw]);
    wall_pressures(sim, w->pressure_n, w->neumann_pa);
    pressure_gradient(sim, w->pressure_n);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        double lane_w[PAIR_LANES] = {0}; /* per-lane partial sums (lanes.h) */
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++)
                lane_w[l] += w->fluid_w[e + l];
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++)
                lane_w[l] += w->wall_w[e + l];
        const double sum_w = lanes_total(lane_w);
        w->rhs[i] = sim->vx_n[a] + dt * (sim->gx - w->grad_x[i] / rho0);
        w->rhs[nf + i] = sim->vy_n[a] + dt * (sim->gy - w->grad_y[i] / rho0);
        /* from v_n plus the last step's change: a slow flow's is much the same from step to step */
        w->x[i] = sim->vx_n[a] + w->dvx_by_id[sim->id[a]], w->x[nf + i] = sim->vy_n[a] + w->dvy_by_id[sim->id[a]];
        w->diag[i] = w->diag[nf + i] = 1.0 + dt_nu * sum_w;
    }
    double residual = 0;
    int iterations = 0;
    if (dt_nu > 0) {
        /* by multigrid: one hierarchy for both components (the walls mirror each component on its own) */
        if (multigrid(sim, true) &&
            multigrid_setup(sim, MULTIGRID_VISCOUS, "viscous", w->diag, w->fluid_w, -dt_nu, w->wall_w, dt_nu, 0))
            iterations = -2;
        else {
            w->vcycle_blocks = multigrid(sim, true) ? 2 : 0;
            iterations = solve(sim, viscous_operator, 2 * nf, AFFINE, prm->implicit.viscous_tolerance,
                               prm->implicit.max_iterations, &residual);
            w->vcycle_blocks = 0;
            if (multigrid(sim, true))
                multigrid_record(sim, MULTIGRID_VISCOUS, iterations);
        }
        sim->viscous_iterations = iterations, sim->viscous_residual = residual;
        if (iterations == -2) {
            boundary_wall_speeds(sim, t_n);
            return -1;
        }
        if (iterations < 0) {
            fail_solve(sim, "viscous", prm->implicit.max_iterations, residual, t_n);
            boundary_wall_speeds(sim, t_n);
            return -1;
        }
    } else /* no viscosity: the operator is the identity */
        memcpy(w->x, w->rhs, 2 * (size_t)nf * sizeof *w->x);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        sim->vx[a] = (real)w->x[i], sim->vy[a] = (real)w->x[nf + i];
        w->dvx_by_id[sim->id[a]] = w->x[i] - sim->vx_n[a], w->dvy_by_id[sim->id[a]] = w->x[nf + i] - sim->vy_n[a];
    }

    /* 2. the correction phi: the walls' Neumann offsets from v* at their ghosts, the source from div v* and the
     * density */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < first; kw++) {
        /* the wall's own velocity: only its normal part matters, and the belt-wall corner's (mirrored through the
         * corner point, its normal slanted) is the fixed upstream wall's, not the belt's */
        const double wall_vx = w->mirror_vx[kw], wall_vy = w->mirror_vy[kw];
        double gvx = wall_vx, gvy = wall_vy;
        if (!w->dry[kw])
            ghost_velocity(sim, kw, &gvx, &gvy);
        /* a wall whose ghost node lies inside the fluid: the wall's phi is the ghost's plus the inhomogeneous
         * Neumann offset, so that -(dt/rho0) dphi/dn takes the normal velocity at the wall's face away, that at the
         * ghost less half the ghost's distance times its normal strain (the first-order interpolation's gradient:
         * a flow that turns at the wall has none to take away, a column moving into it all of its own), and
         * continuity sees the normal velocity continued linearly through the face, (v_g - v_w).n - |g| strain;
         * where the free surface or a contact line cuts the ghost's kernel (its velocity extrapolated from a few
         * particles), and by default everywhere (implicit.wall_neumann_offset 0): the wall's own normal velocity in
         * the divergence, no offset; in between by the immersion (docs/method.md, "Walls": without the offset the
         * first column against a wall sits compressed and below the bulk's pressure) */
        const double immersed = prm->implicit.wall_neumann_offset * w->immersion[kw];
        const double glen2 = (double)sim->ghost_dx[kw] * sim->ghost_dx[kw] + (double)sim->ghost_dy[kw] * sim->ghost_dy[kw];
        const double into = ((gvx - wall_vx) * sim->ghost_dx[kw] + (gvy - wall_vy) * sim->ghost_dy[kw]) / glen2;
        const double strain = immersed > 0 ? ghost_normal_strain(sim, kw) : 0.0;
        w->wall_x[kw] = gvx - ((1.0 - immersed) * into + immersed * strain) * sim->ghost_dx[kw];
        w->wall_y[kw] = gvy - ((1.0 - immersed) * into + immersed * strain) * sim->ghost_dy[kw];
        w->neumann_pa[kw] = -immersed * rho0 / dt * (into - 0.5 * strain) * glen2;
    }
    const double alpha = prm->implicit.density_correction, h = sim->derived.h_m;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        const double vxa = sim->vx[a], vya = sim->vy[a];
        gradient_lanes lanes;
        memset(&lanes, 0, sizeof lanes);
        gradient_pairs(sim, vxa, vya, nl->fluid_first[i], nl->fluid_first[i + 1], 0, &lanes);
        gradient_pairs(sim, vxa, vya, nl->wall_first[i], nl->wall_first[i + 1], 1, &lanes);
        const double g_xx = lanes_total(lanes.xx), g_xy = lanes_total(lanes.xy), g_yx = lanes_total(lanes.yx);
        const double g_yy = lanes_total(lanes.yy), sum_w = lanes_total(lanes.w);
        /* div v = tr(G M^-1) */
        const double div_v = g_xx * w->minv_xx[i] + (g_xy + g_yx) * w->minv_xy[i] + g_yy * w->minv_yy[i];
        /* near the surface the kernel sum is truncated: it is read against a flat surface's at the particle's depth;
         * where that cannot be read (a partly dry wall in reach), a deficit is not an expansion and only an excess
         * counts (clumped particles, which nothing else pushes apart where the pressure is near 0) */
        const double compression = w->near_disc[i] ? fmax(0.0, w->kernel_ratio[i] - 1.0)
                                   : !sim->near_surface[a] ? w->kernel_ratio[i] - 1.0
                                   : w->expected_ratio[i] > 0 ? w->kernel_ratio[i] / w->expected_ratio[i] - 1.0
                                   : fmax(0.0, w->kernel_ratio[i] - 1.0);
        w->density_rhs[i] = w->fixed[i] ? 0.0 : alpha * rho0 * compression / (dt * dt);
        w->rhs[i] = w->fixed[i] ? 0.0 : -rho0 / dt * div_v;
        w->diag[i] = w->fixed[i] || sum_w <= 0 ? 1.0 : sum_w;
        /* the correction starts from the last step's: a steady flow's is much the same from step to step */
        w->x[i] = w->fixed[i] ? 0.0 : w->phi_by_id[sim->id[a]];
    }
    assemble_pressure(sim);
    /* without a free surface (a closed channel) the pressure is fixed only up to a constant: the singular matrix
     * defeats the multigrid's coarsest level, and the matrix-free solve takes it (docs/method.md) */
    int free_surface = 0;
    for (int i = 0; i < nf && !free_surface; i++)
        free_surface = w->fixed[i];
    /* ... and, with a disc, need not be consistent either: the ghosts' normal velocities over a disc need not sum to
     * zero. There the fluid takes the explicit scheme's compressibility, -lap phi + phi/(c0 dt)^2 (the Tait equation
     * of state linearised, p = c0^2 (rho - rho0)): a source the incompressible equation cannot meet becomes a
     * uniform pressure instead of a solve that does not converge (docs/method.md, "Closed domains") */
    const double closed_kappa = free_surface ? 0.0 : 1.0 / (sim->derived.c0_mps * sim->derived.c0_mps * dt * dt);
    if (!free_surface)
        for (int i = 0; i < nf; i++)
            w->pressure_diag[i] += closed_kappa, w->diag[i] += closed_kappa;
    w->pressure_by_multigrid = multigrid(sim, false) && free_surface;
    if (w->pressure_by_multigrid &&
        multigrid_setup(sim, MULTIGRID_PRESSURE, "pressure", w->pressure_diag, w->fluid_pc, 1.0, w->wall_pc, 1.0, 1)) {
        sim_restore_step_start(sim);
        boundary_wall_speeds(sim, t_n);
        return -1;
    }
    if (prm->implicit.wall_neumann_offset > 0)
        wall_offsets_to_rhs(sim, w->neumann_pa);
    iterations = pressure_solve(sim, 1, prm->implicit.pressure_tolerance, &residual);
    if (w->pressure_by_multigrid)
        multigrid_record(sim, MULTIGRID_PRESSURE, iterations);
    sim->pressure_iterations = iterations, sim->pressure_residual = residual;
    if (iterations < 0) {
        fail_solve(sim, "pressure", prm->implicit.max_iterations, residual, t_n);
        sim_restore_step_start(sim);
        boundary_wall_speeds(sim, t_n);
        return -1;
    }
    if (!free_surface) { /* the uniform part is no flow: the fluid's mean pressure keeps its start value */
        const double mean = dot(w, w->x, NULL, nf) / nf;
        for (int i = 0; i < nf; i++)
            w->x[i] -= mean;
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++)
        w->phi_by_id[sim->id[first + i]] = w->x[i];
    /* 2b. the rest-density correction psi, -lap psi = alpha rho0 (rho_k/rho0 - 1)/dt^2 with the same operator, moves
     * the particles by -dt^2 grad psi / rho0 and leaves their velocities alone: a spacing error is not a flow, and
     * in one equation with the divergence its kicks were 0.34 u_max in Poiseuille's start-up (docs/method.md) */
    if (alpha > 0) {
        memcpy(w->phi_saved, w->x, (size_t)nf * sizeof *w->x);
        memcpy(w->rhs, w->density_rhs, (size_t)nf * sizeof *w->x);
        /* from the last step's psi: a spacing error the last step left is corrected again */
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < nf; i++)
            w->x[i] = w->fixed[i] ? 0.0 : w->psi_by_id[sim->id[first + i]];
        const int density_iterations = pressure_solve(sim, 1, prm->implicit.density_tolerance, &residual);
        if (density_iterations < 0) {
            fail_solve(sim, "rest-density", prm->implicit.max_iterations, residual, t_n);
            sim_restore_step_start(sim);
            boundary_wall_speeds(sim, t_n);
            return -1;
        }
        sim->pressure_iterations += density_iterations;
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < nf; i++)
            w->psi_by_id[sim->id[first + i]] = w->x[i];
        wall_pressures(sim, w->x, NULL);
        pressure_gradient(sim, w->x);
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < nf; i++) {
            /* plus a shift where the kernel sum says compressed, -2 w (rho_k/rho0 - 1) h^2 grad C with grad C =
             * sum_b V_b grad W_ab (walls by their wetness): zero on a regular lattice and where the spacing is at
             * rest or wider, it pushes apart particles that have closed on each other, also on the free surface,
             * where psi is 0 (docs/method.md) */
            const double compression = fmax(0.0, w->kernel_ratio[i] - 1.0);
            double sx = 0, sy = 0;
            if (compression > 0) {
                for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
                    sx += w->fluid_gx[e], sy += w->fluid_gy[e];
                for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
                    const double wet = w->wetness[nl->wall_index[e]];
                    sx += wet * w->wall_gx[e], sy += wet * w->wall_gy[e];
                }
            }
            const double shift = 2.0 * prm->implicit.anti_clumping * compression * h * h;
            w->density_dx[i] = -dt * dt / rho0 * w->grad_x[i] - shift * sx;
            w->density_dy[i] = -dt * dt / rho0 * w->grad_y[i] - shift * sy;
        }
        memcpy(w->x, w->phi_saved, (size_t)nf * sizeof *w->x);
    } else {
        memset(w->density_dx, 0, (size_t)nf * sizeof *w->density_dx);
        memset(w->density_dy, 0, (size_t)nf * sizeof *w->density_dy);
    }
    wall_pressures(sim, w->x, w->neumann_pa);

    /* 3. v_n+1 = v* - dt grad phi / rho0, p_n+1 = p_n + phi */
    pressure_gradient(sim, w->x);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        const double p_new = w->fixed[i] ? 0.0 : w->pressure_n[i] + w->x[i];
        by_id[sim->id[a]] = p_new;
        sim->pressure[a] = (real)p_new;
        w->pressure_n[i] = p_new;
        w->x[i] = sim->vx[a] - dt / rho0 * w->grad_x[i];
        w->x[nf + i] = sim->vy[a] - dt / rho0 * w->grad_y[i];
        /* the density the spacing says in the bulk (an output; the scheme holds rho0); next to a disc only an
         * excess (above) */
        sim->rho[a] = (real)(sim->near_surface[a] ? rho0
                             : w->near_disc[i] ? rho0 * fmax(1.0, w->kernel_ratio[i]) : rho0 * w->kernel_ratio[i]);
    }
    /* the walls' pressure for the outputs: p_n+1 continued hydrostatically, as the next step takes it */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < first; kw++)
        sim->pressure[kw] = (real)(w->dry[kw] ? 0.0 : ghost_value(sim, kw, w->pressure_n) -
                                   rho0 * (sim->gx * sim->ghost_dx[kw] + sim->gy * sim->ghost_dy[kw]));
    const double face_reach_m = sim_contact_reach_m(sim);
    /* a particle the contact rule on positions (below) left at the reach is in contact: its gap, read back in
     * single precision, may come out a rounding either side of the reach */
    const double contact_m = face_reach_m + CONTACT_ROUNDING_DP * prm->numerics.dp_m;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        double vx1 = w->x[i], vy1 = w->x[nf + i];
        /* within reach of a wall face: no approach to it (the explicit scheme's contact rule; docs/method.md); a
         * disc takes the reaction */
        const double approach_mps = vx1 * sim->face_nx[a] + vy1 * sim->face_ny[a] - sim->face_vn_mps[a];
        const int contact = sim->face_gap_m[a] < contact_m && approach_mps < 0;
        if (contact)
            vx1 -= approach_mps * sim->face_nx[a], vy1 -= approach_mps * sim->face_ny[a];
        sim->face_push_x[a] = (real)(contact ? -approach_mps * sim->face_nx[a] / dt : 0.0);
        sim->face_push_y[a] = (real)(contact ? -approach_mps * sim->face_ny[a] / dt : 0.0);
        sim->vx[a] = (real)vx1, sim->vy[a] = (real)vy1;
    }
    if (prm->implicit.pair_distance_dp > 0)
        part_close_pairs(sim);
    else {
        memset(w->pair_dx, 0, (size_t)nf * sizeof *w->pair_dx);
        memset(w->pair_dy, 0, (size_t)nf * sizeof *w->pair_dy);
    }
    if (sim->boulders.count > 0)
        disc_forces(sim);
    #pragma omp parallel
    shifting_compute(sim, dt);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = first; a < n; a++) {
        double dx = dt * sim->vx[a] + sim->shift_x[a] + w->density_dx[a - first] + w->pair_dx[a - first];
        double dy = dt * sim->vy[a] + sim->shift_y[a] + w->density_dy[a - first] + w->pair_dy[a - first];
        /* the contact rule on positions: a step that would end closer to the nearest wall face than its reach ends
         * at the reach (the explicit scheme's face repulsion acts over many small steps; one large step needs the
         * constraint itself; docs/method.md) */
        const double gap_after = sim->face_gap_m[a] + dx * sim->face_nx[a] + dy * sim->face_ny[a] -
                                 dt * sim->face_vn_mps[a];
        if (sim->face_gap_m[a] < prm->numerics.dp_m && gap_after < face_reach_m)
            dx += (face_reach_m - gap_after) * sim->face_nx[a], dy += (face_reach_m - gap_after) * sim->face_ny[a];
        sim->x[a] = sim->x_n[a] + dx;
        sim->y[a] = sim->y_n[a] + dy;
    }
    if (sim->boulders.count > 0 && boulders_advance_implicit(sim, dt, prm->implicit.added_mass) != 0) {
        sim->health = (surge_health){.check = SURGE_CHECK_OUT_OF_MEMORY, .particle_id = -1, .step = sim->step + 1,
                                     .time_s = t_n + dt};
        snprintf(sim->health.message, sizeof sim->health.message, "out of memory in the contact solver");
        sim_restore_step_start(sim);
        boulders_restore(sim);
        boundary_wall_speeds(sim, t_n);
        return -1;
    }
    sim->time_s = t_n + dt;
    sim->step++;
    if (health_check(sim) != 0) {
        sim_restore_step_start(sim);
        if (sim->boulders.count > 0)
            boulders_restore_implicit(sim);
        sim->time_s = t_n;
        sim->step--;
        boundary_wall_speeds(sim, t_n);
        return -1;
    }
    return 0;
}
