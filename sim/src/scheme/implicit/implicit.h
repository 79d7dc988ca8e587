/* The implicit scheme's private header: its work arrays and the functions its files share (implicit_step.c has the
 * step and the scheme's description). */
#ifndef SURGE_IMPLICIT_H
#define SURGE_IMPLICIT_H

#include <stdbool.h>
#include <stdio.h>

#include "scheme/implicit/amg.h"
#include "physics/interaction.h"
#include "physics/lanes.h"
#include "physics/pair_terms.h"
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

/* The discs that lubrication films join, as blocks solved directly (films.c) */
enum { FILMS_VISCOUS, FILMS_PRESSURE };
typedef struct film_blocks {
    int count;                           /* blocks this step */
    int *of_disc;                        /* per disc: its block, -1 without a film */
    int *place;                          /* per disc: its place in its block (union-find scratch while they form) */
    int *first;                          /* scratch: the clusters' first members before they are cut into blocks */
    int *members;                        /* the blocks' discs, block k's from start[k] to start[k + 1], in disc order */
    int *start;
    double *lu[2];                       /* per block, one after another: its rows' LU factors (FILMS_VISCOUS,
                                          * FILMS_PRESSURE), column-major */
    int *pivots[2];                      /* 3 per member */
    double *scratch;
    double *tangential;                  /* per film with reynolds set: its K_t (36) and its wall's force (6), this step's
                                          * (films.c, tangential_rows) */
    int factored;                        /* this step's blocks are factored (implicit_films_factor) */
    int singular;                        /* and one of them was found singular */
    size_t disc_capacity, place_capacity, first_capacity, members_capacity, start_capacity, lu_capacity[2],
        pivot_capacity[2], scratch_capacity, tangential_capacity;
} film_blocks;

typedef struct implicit_work {
    size_t fluid_cap, wall_cap, mirror_cap, ghost_cap; /* entries the per-entry arrays hold */
    real *fluid_w, *fluid_gx, *fluid_gy; /* per fluid-list entry: Laplacian weight, V_b f r_ab */
    real *wall_w, *wall_gx, *wall_gy;    /* per wall-list entry */
    real *mirror_w;                      /* per wall's ghost-list entry: its weight in the value at the ghost */
    real *mirror_nw;                     /* and in the derivative along the ghost's normal there */
    real *ghost_w, *ghost_nw;            /* the same for a disc particle's ghost list (ghost_span) */
    real *mirror_qw, *ghost_qw;          /* and its weight in the wall particle's quadratic no-slip velocity */
    double *quadratic_base;              /* per wall: the wall velocity's weight in it (1 - sum of the entries') */
    uint8_t *quadratic_ok;               /* per wall: the quadratic fit is well-conditioned (else the mirror) */
    double *mirror_vx, *mirror_vy;       /* per wall: the wall velocity no-slip mirrors about (implicit_mirror_velocities) */
    int disc_cap;                        /* discs the per-disc arrays hold */
    int disc_rows;                       /* the coupled solves' unknowns beyond the fluid's: 3 per disc (disc_coupling.c) */
    size_t disc_entries;                 /* of disc_entry, which holds as many as the wall lists */
    int64_t *disc_entry;                 /* the fluid's wall-list entries that are disc particles, in fluid order */
    int32_t *disc_entry_fluid;           /* and their fluid particle */
    int64_t *disc_entry_fluid_first;     /* nf + 1: fluid particle i's disc entries are [first[i], first[i + 1]) */
    int64_t *disc_entry_by_disc;         /* the disc entries grouped by disc, ascending within each */
    int64_t *disc_entry_disc_first;      /* discs + 1: disc d's are disc_entry_by_disc[first[d] .. first[d + 1]) */
    double *surface_x, *surface_y;       /* per wall: a disc particle's surface point (its mirror line's) from the
                                          * disc's centre (m) */
    double *lever_x, *lever_y;           /* per wall: a disc particle's offset from the disc's centre (m) */
    double *disc_divergence;             /* 3 per disc entry: d(div v*_a)/dU of its disc (disc_coupling.c) */
    double *disc_velocity;               /* 3 per disc: Vx, Vy (m/s), R Omega (m/s): the coupled solves' answer */
    double *disc_force;                  /* 3 per disc: force (N/m) and torque (N), scratch */
    double *disc_reference_pa;           /* per disc: the mean pressure of its particles */
    double *spin_drag;                   /* per disc: c in the viscous torque's missing part -c Omega (N s) */
    contact_film *films;                 /* the step's lubrication films (contacts.lubrication), taken into the viscous
                                          * solve's disc rows (disc_coupling.c) */
    int film_count, film_capacity;
    film_blocks film_blocks;             /* the discs they join, solved as blocks */
    real *fluid_pc, *wall_pc;            /* per list entry: the pressure operator's coefficient (implicit_assemble_pressure) */
    double *pressure_diag;               /* per fluid particle: the pressure operator's diagonal */
    held_multigrid multigrid[2];         /* implicit.preconditioner = amg: the viscous and the pressure hierarchy */
    amg_system *amg;                     /* this solve's: one of multigrid[] */
    int free_surface;                    /* this step: a free-surface particle (else the pressure is fixed up to a constant) */
    int pressure_by_multigrid;           /* this step's pressure solves use amg (there is a free surface) */
    int vcycle_blocks;                   /* implicit_solve()'s preconditioner: 0 the diagonal, else one V-cycle of amg's
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
    wall_face *other_face;               /* per fluid particle: the nearest face within dp of another solid than its
                                          * nearest face's (interaction_other_face; gap dp: none) */
    real *other_push_x, *other_push_y;   /* per fluid particle: the contact rule's push off the other face, which a
                                          * disc there takes the reaction of (as face_push_x, face_push_y) */
    double *expected_ratio;              /* per fluid particle: the kernel sum at rest spacing at its depth under the
                                          * free surface, where that can be read (else 0) */
    double *wall_x, *wall_y;             /* per wall: a mirrored field (velocity, pressure) */
    double *neumann_pa;                  /* per wall: p_w - p_ghost, the Neumann offset of the field being set */
    double *rhs, *x, *offset, *diag;     /* solves: 2 nf at most */
    double *density_rhs, *phi_saved;     /* the rest-density source; the correction phi while psi is solved */
    double *divergence;                  /* per fluid particle: div v* (the passes' update with discs) */
    double *phi_by_id, *psi_by_id;       /* per particle id: the last step's phi and psi, the next one's guesses */
    double *dvx_by_id, *dvy_by_id;       /* per particle id: the last step's v* - v_n, the next viscous solve's guess */
    double *density_dx, *density_dy;     /* per fluid particle: the rest-density correction's displacement */
    double *pair_dvx, *pair_dvy, *pair_dx, *pair_dy; /* per fluid particle: what close pairs change (implicit_part_close_pairs) */
    double *r, *rhat, *p, *v, *s, *t, *y, *z, *partial; /* partial: two sums' blocks (krylov.c) */
    double *pressure_by_id;              /* per particle id: the fluid's pressure, the next step's p_n (checkpointed) */
    /* a step taken again at half its length (step_retry.c) */
    double *saved_by_id;                 /* the step's start: pressure_by_id, phi, psi, dvx and dvy by id, one after another */
    size_t saved_capacity;               /* particles each of them holds */
    int64_t *saved_contact_keys;         /* and the contact solver's warm start: keys, then lambda_n and lambda_t */
    double *saved_lambdas;
    int saved_contacts, saved_contact_capacity;
    int64_t step_halvings;               /* the times a step was taken again at half its length (diagnostics) */
    /* the free surface's mirror images (surface_images.c) */
    uint8_t *imaged;                     /* per fluid particle: its kernel reaches the surface and sees images */
    int any_imaged;
    real *fluid_iw, *fluid_igx, *fluid_igy; /* per fluid-list entry: the image pair's Laplacian weight, V_b f' r_ab' */
    real *wall_iw, *wall_igx, *wall_igy;    /* per wall-list entry: the same */
    real *wall_side;                     /* per wall-list entry of an imaged particle: 1 on its side of the surface */
    double *own_iw, *own_igx, *own_igy;  /* per fluid particle: its own image's */
    double *wet_grad_x, *wet_grad_y;     /* per fluid particle: the colour gradient, walls by their wetness */
    /* Anderson's acceleration of the passes (pass_mixing.c): per fluid particle x_k, g_k and f_k, and a ring of
     * mixing_cap differences g_j+1 - g_j and f_j+1 - f_j */
    double *mixing_x, *mixing_g, *mixing_f, *mixing_dg, *mixing_df;
    int mixing_cap, mixing_count, mixing_next;
    int32_t pressure_iterations, viscous_iterations; /* the last step's solves (diagnostics) */
    double pressure_residual, viscous_residual;
} implicit_work;

/* The scheme's private data */
static inline implicit_work *implicit_of(const surge_sim *sim) { return sim->scheme_data; }

typedef void (*affine_operator)(surge_sim *sim, const double *x, double *out);
enum { AFFINE, LINEAR_FROM_ZERO, LINEAR_FROM_GUESS }; /* implicit_solve()'s operator and first guess */

/* Whether the scene is large enough for the solves' loops to run on several threads: a BiCGSTAB iteration is ten or
 * so short loops, and below this size waking the other threads at each costs more than it saves (passive waiting,
 * the 2-core Xeon VM: the 800-particle tank 0.53 s on one thread, 4.75 s on two; Freydier ID1 at 4,590 fluid
 * particles 3.2 s and 4.2 s; at 10,075, 5.23 and 4.77 s; docs/performance.md) */
#define WIDE_FLUID_PARTICLES 10000
/* The entries an array sized to the neighbour lists is given when they outgrow it: an eighth to spare. The lists
 * change a little at each build; arrays grown to the exact count were copied and their new pages faulted in at nearly
 * every build (Freydier ID1 at dp 0.5 mm, 104 steps: 60,208 page faults, about 32,900 of them in the first step; with
 * an eighth to spare 48,767, with half 49,181; docs/performance.md). amg.c's kept matrix follows the same rule */
static inline size_t implicit_room_for(size_t need) { return need + need / 8 + 64; }

static inline int wide(const surge_sim *sim) { return sim->count - sim->wall_count >= WIDE_FLUID_PARTICLES; }

/* A wall's ghost-node list: a fixed wall's is its wall_fluid list, a disc particle's its ghost_fluid list (the
 * ghost turns with the disc); r_ghost - r_j = dx0[e] - moved_j + shift, and weight[e] the entry's mirror weight */
typedef struct ghost_span {
    int64_t from, to;
    const int32_t *index;
    const real *dx0, *dy0;
    real *weight, *normal_weight, *quadratic_weight;
    real shift_x, shift_y;
} ghost_span;

static inline ghost_span ghost_span_of(const surge_sim *sim, int kw)
{
    const neighbour_lists *nl = &sim->neighbours;
    implicit_work *w = implicit_of(sim);
    if (sim->wall_of[kw] != WALL_BOULDER)
        return (ghost_span){nl->wall_fluid_first[kw], nl->wall_fluid_first[kw + 1], nl->wall_fluid_index,
                            nl->wall_fluid_dx0, nl->wall_fluid_dy0, w->mirror_w, w->mirror_nw, w->mirror_qw, 0, 0};
    return (ghost_span){nl->ghost_fluid_first[kw], nl->ghost_fluid_first[kw + 1], nl->ghost_fluid_index,
                        nl->ghost_fluid_dx0, nl->ghost_fluid_dy0, w->ghost_w, w->ghost_nw, w->ghost_qw,
                        nl->moved_x[kw] + (sim->ghost_dx[kw] - nl->ghost_dx_build[kw]),
                        nl->moved_y[kw] + (sim->ghost_dy[kw] - nl->ghost_dy_build[kw])};
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

/* Wall kw's no-slip velocity component in the viscous solve, the fluid's component x and the wall's own u_wall:
 * mDBC's mirror 2 u_wall - x(ghost), or the quadratic fit's value at the particle (walls.quadratic_no_slip;
 * geometry.c) */
static inline double wall_no_slip_value(const surge_sim *sim, int kw, const double *x, double u_wall)
{
    const implicit_work *w = implicit_of(sim);
    if (w->dry[kw])
        return u_wall;
    if (!sim->params.walls.quadratic_no_slip || !w->quadratic_ok[kw])
        return 2.0 * u_wall - ghost_value(sim, kw, x);
    const ghost_span g = ghost_span_of(sim, kw);
    double sum[PAIR_LANES] = {0};
    for (int64_t e = g.from; e < g.to; e += PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++)
            sum[l] += g.quadratic_weight[e + l] * x[g.index[e + l] - sim->wall_count];
    return w->quadratic_base[kw] * u_wall + lanes_total(sum);
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
 * at the wall's ghost node: n . grad (v . n), from the first-order interpolation's gradient rows (implicit_geometry) */
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

/* The weight of wall kw in fluid particle i's row of the pressure operator (implicit_assemble_pressure, which stores
 * it negated): the Laplacian's weight corrected for truncation, w_ak + wetness_k u_i . V_k f r_ak with
 * u_i = M_i^-1 sum_b w_ab r_ab, list entry e */
static inline double pressure_wall_weight(const implicit_work *w, int i, int64_t e, int kw)
{
    const double wrx = w->weighted_rx[i], wry = w->weighted_ry[i];
    const double ux = w->minv_xx[i] * wrx + w->minv_xy[i] * wry, uy = w->minv_xy[i] * wrx + w->minv_yy[i] * wry;
    return w->wall_w[e] + w->wetness[kw] * (ux * w->wall_gx[e] + uy * w->wall_gy[e]);
}

/* work.c */
int implicit_reserve_work(surge_sim *sim); /* sizes the work arrays for the current lists; -1 when out of memory */
int implicit_create(surge_sim *sim, char *err, size_t err_len);
void implicit_destroy(surge_sim *sim);
/* implicit_checkpoint.c */
int implicit_checkpoint_write(FILE *f, const surge_sim *sim);
int implicit_checkpoint_read(FILE *f, surge_sim *sim, uint32_t version);
/* geometry.c */
void implicit_mirror_velocities(surge_sim *sim);
void implicit_geometry(surge_sim *sim);
/* operators.c */
void implicit_viscous_operator(surge_sim *sim, const double *x, double *out);
void implicit_wall_pressures(surge_sim *sim, const double *x, const double *offset_pa);
void implicit_wall_offsets_to_rhs(surge_sim *sim, const double *offset_pa);
void implicit_pressure_gradient(surge_sim *sim, const double *x);
void implicit_assemble_pressure(surge_sim *sim);
int implicit_assemble_sparse(surge_sim *sim, const double *diag, const real *fluid_coef, double fluid_scale,
                             const real *wall_coef, double wall_scale, int honour_fixed);
void implicit_pressure_operator(surge_sim *sim, const double *x, double *out);
void implicit_relax_pressure(surge_sim *sim, double *p, const double *offset_pa, double beta);
/* krylov.c */
double implicit_dot(const implicit_work *w, const double *a, const double *b, int n);
int implicit_solve(surge_sim *sim, affine_operator op, int n, int homogeneous, double tolerance, int max_iterations,
                   double *residual);
/* multigrid.c */
int implicit_multigrid(const surge_sim *sim, bool viscous);
int implicit_multigrid_setup(surge_sim *sim, int which, const char *what, const double *diag, const real *fluid_coef,
                             double fluid_scale, const real *wall_coef, double wall_scale, int honour_fixed);
void implicit_multigrid_record(surge_sim *sim, int which, int iterations);
int implicit_pressure_solve(surge_sim *sim, affine_operator op, int from_guess, double tolerance, double *residual);
/* surface_images.c */
void implicit_surface_images(surge_sim *sim);
void implicit_image_gradient_sum(const surge_sim *sim, int i, const double *x, double *sx, double *sy);
void implicit_image_velocity_gradient(const surge_sim *sim, int i, double g[4]);
double implicit_image_laplacian_row(surge_sim *sim, int i, double ux, double uy);
/* implicit_report.c */
void implicit_check_report(const surge_sim *sim, FILE *out, int verbose, double list_entries, double bytes);
/* disc_coupling.c: the discs' velocities as unknowns of the viscous and the pressure solves */
void implicit_discs_prepare(surge_sim *sim);
/* films.c: the lubrication films in the viscous solve's disc rows and the pressure correction's change */
int implicit_discs_films(surge_sim *sim); /* -1 when out of memory */
void implicit_film_forces(const surge_sim *sim, const double *disc_x, double *force);
void implicit_films_factor(surge_sim *sim, double dt, double *diag);
void implicit_films_solve(surge_sim *sim, int which, double *x);
void implicit_films_free(film_blocks *fb);
void implicit_discs_viscous_system(surge_sim *sim, double dt);
void implicit_coupled_viscous_operator(surge_sim *sim, const double *x, double *out);
void implicit_discs_mirror(surge_sim *sim, const double *disc_velocity);
void implicit_coupled_pressure_operator(surge_sim *sim, const double *x, double *out);
void implicit_discs_pressure_answer(surge_sim *sim, double dt);
/* implicit_discs.c: the discs' step from the coupled solves' velocities through the contact solver (-1 when it runs
 * out of memory) */
int implicit_discs_advance(surge_sim *sim, double dt_s);
/* pass_mixing.c: Anderson's acceleration of the passes with discs */
int implicit_mixing_reserve(implicit_work *w, int depth, int nf);
void implicit_mix_pressure(surge_sim *sim, int pass);
/* coupling.c */
void implicit_part_close_pairs(surge_sim *sim);
/* step_retry.c: the solver's state at a step's start, kept (-1 when out of memory) and restored for a step taken
 * again (-1 when out of memory); and, once the step has moved the particles, -1 with sim->health where a fluid
 * particle's kernel sum there is compressed past the density bound (the step at `share` of its length) */
int implicit_retry_save(surge_sim *sim);
int implicit_retry_restore(surge_sim *sim);
int implicit_end_compression(surge_sim *sim, double share);

#endif
