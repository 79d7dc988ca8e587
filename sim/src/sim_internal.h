/* The solver's state, shared by the files of sim/src. Not part of the public interface. */
#ifndef SURGE_SIM_INTERNAL_H
#define SURGE_SIM_INTERNAL_H

#include <math.h>
#include <stdint.h>

#include "boulders.h"
#include "kernel.h"
#include "lanes.h"
#include "particles/fields.h"
#include "precision.h"
#include "scheme/scheme.h"
#include "surge/sim.h"

/* Which wall a wall particle belongs to. WALL_CORNER is the bed under the upstream wall: it moves with the belt
 * (continuity sees no velocity jump along the bed) but mirrors no-slip about a fixed wall (it does not drag
 * fluid under the upstream wall); docs/method.md, "The belt-upstream-wall corner". */
enum { WALL_FIXED = 0, WALL_BOTTOM = 1, WALL_TOP = 2, WALL_BOULDER = 3, WALL_CORNER = 4, WALL_COUNT = 5 };

/* Uniform cell grid, cells at least 2h wide, periodic in x or not. Wall particles (indices [0, wall_count))
 * and fluid particles ([wall_count, count)) are each sorted by cell and have their own cell ranges. */
typedef struct cell_grid {
    int ncx, ncy;
    double x0, y0;          /* lower-left corner */
    double cell_w, cell_h;
    double period_m;        /* > 0 when periodic in x */
    int *fluid_start;       /* ncx*ncy + 1 */
    int *wall_start;        /* ncx*ncy + 1 */
} cell_grid;

/* The particle index ranges of the 3x3 cells around a point, row by row, with the x shift that brings the
 * periodic image of a range next to the point. */
typedef struct neighbour_ranges {
    int count;
    int begin[6], end[6];
    double shift_x[6]; /* add to the neighbour's x */
} neighbour_ranges;

/* Up to two contiguous cell ranges per row of the 3x3 block around a cell, with the x shift that brings the
 * periodic image next to the particle. */
typedef struct cell_span {
    int first_cell, last_cell; /* inclusive, within one row */
    double shift_x;            /* add to the neighbour's x */
} cell_span;

/* What a fluid neighbour brings to the pair loops, packed in one 32-byte record (8 floats) a particle: the loop's
 * loads of a neighbour touch one cache line instead of eight arrays (interaction.c fills it at each evaluation;
 * docs/performance.md) */
typedef struct pair_state {
    real moved_x, moved_y, vx, vy, rho, inv_rho, pressure, surface;
} pair_state;
_Static_assert(sizeof(pair_state) == PAIR_LANES * sizeof(real), "the pair loop loads a record as one vector");

/* What a wall neighbour brings to the fluid's wall pair loop, packed the same way (boundary.c fills it with the
 * wall's mDBC state): its displacement since the build, density, pressure, the no-slip velocity of the viscous term
 * and the velocity of the continuity term */
typedef struct wall_pair_state {
    real moved_x, moved_y, rho, pressure, noslip_vx, noslip_vy, cont_vx, cont_vy;
} wall_pair_state;
_Static_assert(sizeof(wall_pair_state) == PAIR_LANES * sizeof(real), "the pair loop loads a record as one vector");

/* What a wall neighbour brings to the wall-face search (interaction_wall_face), packed likewise (boundary.c): a fixed
 * wall particle its normal and its depth below the face, disc -1; a disc's particle its disc, the disc's radius in
 * reach_m and its own offset from the disc's centre */
typedef struct wall_face_state {
    real moved_x, moved_y, nx, ny, reach_m, disc, centre_dx, centre_dy;
} wall_face_state;
_Static_assert(sizeof(wall_face_state) == PAIR_LANES * sizeof(real), "the search loads a record as one vector");

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
} neighbour_lists;

#define SURGE_KERNEL_ROWS 13 /* rows under a flat surface whose kernel sums are kept: a kernel reaches 2 sqrt(2) C_h <= 11.4 rows (C_h <= 4) */

struct surge_sim {
    surge_params params;
    surge_derived derived;
    kernel2d kernel;
    double rho0, b_pa, eta2, mass;
    double lattice_kernel_sum; /* sum_b dp^2 W_ab over a square lattice at rest: the kernel sum's own bias */
    double second_row_kernel_ratio; /* the same sum one row under a flat free surface, over lattice_kernel_sum
                                     * (0.988, 0.946, 0.869 at C_h 1.0, 1.3, 1.8) */
    double row_kernel_ratio[SURGE_KERNEL_ROWS]; /* the same with k rows above (k = 0: the surface row itself) */
    double gx, gy;             /* body acceleration (tilted gravity + body force) */
    double rho_h_per_m;        /* hydrostatic density gradient rho0 g_n / c0^2 (density diffusion) */

    int32_t count, wall_count;
    /* the per-particle fields, structure of arrays in cell order (particles/fields.h) */
    SURGE_STEP_FIELDS(FIELD_MEMBER)
    SURGE_STEP_FIELDS(FIELD_COPY_MEMBER)
    SURGE_PARTICLE_FIELDS(FIELD_MEMBER)
    double wall_speed[WALL_COUNT];

    boulder_set boulders;

    cell_grid grid;
    neighbour_lists neighbours;
    int32_t *sort_key, *sort_scratch_i; /* the cell sort's keys (2 count) and scratch (count each) */
    double *sort_scratch_d;

    double time_s, dt_s, first_dt_s;
    int64_t step;
    surge_health health;

    double list_lookahead_s;       /* how far ahead of a step's start its force evaluations reach (neighbours.c) */
    const time_scheme *scheme;    /* the time-stepping scheme (scheme/scheme.h) */
    void *scheme_data;             /* and its own state */
};

/* Particle a's copies at the step's start (the step fields of particles/fields.h) */
static inline void fields_save_step_start(surge_sim *sim, int a)
{
#define SAVE_FIELD(name, type, extent, roles, meaning) sim->name##_n[a] = sim->name[a];
    SURGE_STEP_FIELDS(SAVE_FIELD)
#undef SAVE_FIELD
}

/* x wrapped into [0, period) in a periodic domain (positions are wrapped only at neighbour-list builds) */
static inline double surge_sim_wrapped_x(const surge_sim *sim, double x)
{
    const double period = sim->grid.period_m;
    if (period > 0)
        x -= period * floor(x / period);
    return x;
}

/* The contact distance of the scheme in use (m): no step or shift ends closer to a wall face */
static inline double sim_contact_reach_m(const surge_sim *sim)
{
    return sim->scheme->contact_reach_dp(&sim->params) * sim->params.numerics.dp_m;
}

/* The neighbour lists' skin (m) of the scheme in use */
static inline double sim_neighbour_skin_m(const surge_sim *sim)
{
    return sim->scheme->neighbour_skin_h(&sim->params) * sim->derived.h_m;
}

/* scene.c */
int scene_build(surge_sim *sim, char *err, size_t err_len);
double scene_expected_speed(const surge_params *p);
double scene_head_speed(const surge_params *p);
/* Where the upstream wall's particles end behind it (m): its front layers, then as many layers again with their face
 * turned upstream where the room behind the wall allows. Fluid that comes round a periodic channel (past a caught
 * disc, say) meets a wall there, not the back of the front layers, whose mDBC and face act only downstream. */
double scene_upstream_back_m(const surge_params *p);

/* grid.c */
int grid_init(surge_sim *sim, char *err, size_t err_len);
void grid_free(cell_grid *grid);
int grid_cell_x(const cell_grid *g, double x);
int grid_cell_y(const cell_grid *g, double y);
int grid_row_spans(const cell_grid *g, int cx, cell_span spans[2]);
/* start: the grid's fluid_start or wall_start; x inside the domain (wrapped when periodic). */
void grid_neighbour_ranges(const cell_grid *g, const int *start, double x, double y, neighbour_ranges *r);
/* Both kinds at once, for a loop over fluid and wall neighbours cell by cell. */
void grid_fluid_and_wall_ranges(const cell_grid *g, double x, double y, neighbour_ranges *fluid,
                                neighbour_ranges *walls);
/* Walls in cell order of their build positions, within a cell by id: the same order whatever the order before
 * (restarts). Fluid in cell order of the build positions, stable. */
void grid_sort_walls(surge_sim *sim);
void grid_sort_fluid(surge_sim *sim);

/* neighbours.c */
int neighbours_init(surge_sim *sim, char *err, size_t err_len); /* build positions = positions; no lists yet */
void neighbours_free(neighbour_lists *nl);
/* At the start of a step: rebuilds (wraps positions into the period, sorts, lists) when a particle may come
 * within skin/2 of leaving its list's reach by the corrector's evaluation; -1 when out of memory. */
int neighbours_update(surge_sim *sim);
/* Sorts by the build positions as they are and builds the lists (restarts: the same lists as the saved run). */
int neighbours_adopt_build_positions(surge_sim *sim);
/* Worksharing functions: their loops are `omp for`, to be called by every thread of a parallel region (one force
 * evaluation shares one region: step_explicit.c); called outside one, they run on the calling thread alone. */
/* Every particle's displacement since the build: before each force evaluation (positions changed). */
void neighbours_track(surge_sim *sim);
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
/* The fluid particles [begin, end) that the calling thread of a parallel region takes in a pass over the fluid's lists:
 * contiguous shares of equal cost (list entries plus a part per particle), so that the thread with the bed's wall
 * entries does not leave the other waiting; outside a region, all of them. The pass ends with `omp barrier`. Each
 * particle sums its own pairs, so results do not depend on the shares. */
void neighbours_fluid_share(const surge_sim *sim, int *begin, int *end);
/* boundary.c: mDBC density and no-slip velocity of wall particles (worksharing); where the scheme is not
 * incompressible also their Tait pressure and 1/density (an incompressible scheme solves for its own) */
void boundary_update(surge_sim *sim);
/* interaction.c (worksharing): before boundary_update, every moving particle's displacement since the build
 * (neighbours_track) and the fluid's pair_state records (which the mDBC ghost nodes read), where the scheme is not
 * incompressible first the fluid's Tait pressure and 1/density; after it, the fluid's rates */
void interaction_prepare(surge_sim *sim);
void interaction_compute(surge_sim *sim, int corrector);
/* boundary.c: the moving walls' speeds at time_s (the start ramp), and the particles' kinds that follow them */
void boundary_wall_speeds(surge_sim *sim, double time_s);
/* What fluid particle a's wall neighbours within 2h say besides the pair terms: whether one is a boulder's, and the
 * nearest fixed wall face within search_m straight below the particle (the wall particle within dp/2 of its normal
 * line), or the nearest face of a disc among them: its distance (search_m when none), normal, the wall's velocity
 * along it, and the wall particle or the disc (-1: none). */
typedef struct wall_face {
    real gap_m, nx, ny, vn_mps;
    int wall, disc;
} wall_face;
wall_face interaction_wall_face(const surge_sim *sim, int a, real search_m, int *near_boulder);

/* boulders.c */
int boulders_define(surge_sim *sim, char *err, size_t err_len);   /* the discs of the case, before the walls */
int boulders_particle_count(const surge_sim *sim);
int boulders_particles_of(const surge_sim *sim, int disc);   /* the particles of one disc */
/* Appends disc particles to the wall arrays from index first (ids too); ghost offsets follow the discs. */
void boulders_create_particles(surge_sim *sim, int first);
int boulders_cover(const surge_sim *sim, double x, double y); /* a fluid particle here would sit in a disc */
void boulders_place_particles(surge_sim *sim);                /* positions and velocities from the discs */
/* The mDBC ghost offset wall particle k of a disc has when the disc's orientation is angle. */
void boulders_ghost_offset(const surge_sim *sim, int k, double angle, real *gdx, real *gdy);
/* eq. 10, after interaction_compute; the pressures taken relative to reference_pa[disc] (NULL: 0) */
void boulders_fluid_forces(surge_sim *sim, const double *reference_pa);
/* Fills the discs' cos_angle and sin_angle from their angles (scratch; writes through the const set's arrays). */
void boulders_orient(const boulder_set *b);
/* Velocity of the disc's surface where wall particle k's ghost is mirrored (the no-slip target), at the orientation of
 * the last boulders_orient. */
void boulders_surface_velocity(const surge_sim *sim, int k, double *vx, double *vy);
void boulders_predict(surge_sim *sim, double half_dt_s);      /* saves the step start, moves to the half step */
int boulders_correct(surge_sim *sim, double dt_s);            /* full step from the start, with contacts */
void boulders_restore(surge_sim *sim);                        /* back to the step start (roll-back) */
/* the implicit scheme's full step from the fluid forces, with added_mass (implicit.added_mass) */
int boulders_advance_implicit(surge_sim *sim, double dt_s, double added_mass);
void boulders_restore_implicit(surge_sim *sim);               /* roll-back of boulders_advance_implicit */
/* each disc's wetted fraction: the mean over its outer ring of wetness (per wall particle, 0 dry to 1 wet) */
void boulders_wetted_fraction(surge_sim *sim, const real *wetness);
void boulders_free(boulder_set *b);

/* shifting.c: this step's shifting displacements and their divergence (after the corrector's pass; worksharing) */
void shifting_compute(surge_sim *sim, double dt_s);

/* health.c */
int health_check(surge_sim *sim);

#endif
