/* The solver's state: what a step reads and writes, shared by the files of sim/src. Not part of the public
 * interface. Each module's functions are declared in its own header beside it. */
#ifndef SURGE_SIM_INTERNAL_H
#define SURGE_SIM_INTERNAL_H

#include <math.h>
#include <omp.h>
#include <stdint.h>

#include "boulders/boulder_set.h"
#include "neighbours/grid.h"
#include "neighbours/lists.h"
#include "particles/fields.h"
#include "physics/kernel.h"
#include "physics/records.h"
#include "precision.h"
#include "scheme/scheme.h"
#include "surge/sim.h"

/* Which wall a wall particle belongs to. WALL_CORNER is the bed under the upstream wall: it moves with the belt
 * (continuity sees no velocity jump along the bed) but mirrors no-slip about a fixed wall (it does not drag
 * fluid under the upstream wall); docs/method.md, "The belt–upstream-wall corner". */
enum { WALL_FIXED = 0, WALL_BOTTOM = 1, WALL_TOP = 2, WALL_BOULDER = 3, WALL_CORNER = 4, WALL_COUNT = 5 };

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
    const struct lubrication_share *film_share; /* the share the measured films leave out (film_share_of) */
    void *scheme_data;             /* and its own state */

    /* while the scene is built (sim_create_checked): its particle counts, known before anything is allocated for
     * them, with the boulders defined; 0 to go on, or -1 with err to refuse the scene */
    int (*scene_check)(const surge_sim *sim, long long walls, long long fluid, void *user, char *err, size_t err_len);
    void *scene_check_user;
    int narrow_gap_sites; /* the scene keeps fluid sites in gaps too narrow beside a disc (checkpoints up to version 9) */
    uint8_t *pack_interior; /* while the scene is built: by fluid id, 1 where the packing may move it (packing.c) */

    surge_contact_impulses contact_impulses; /* summed over the steps taken (surge_sim_contact_impulses) */
    surge_phase_times phase_times; /* the steps' time by phase (surge_sim_phase_times; other_s stays 0 here) */
    double phase_mark_s;           /* omp_get_wtime() where the running phase began */
};

/* surge_sim_create, with check (may be NULL) called with the scene's particle counts before they are allocated (a
 * checkpoint's reader compares them with what the file holds); narrow_gap_sites 1 builds the scene of a checkpoint
 * written before fluid sites in gaps too narrow beside a disc were left out (boulders_cover) */
surge_sim *sim_create_checked(const surge_params *params,
                              int (*check)(const surge_sim *sim, long long walls, long long fluid, void *user,
                                           char *err, size_t err_len),
                              void *user, int narrow_gap_sites, char *err, size_t err_len);

/* Particle a's copies at the step's start (the step fields of particles/fields.h) */
static inline void fields_save_step_start(surge_sim *sim, int a)
{
#define SAVE_FIELD(name, type, extent, roles, meaning) sim->name##_n[a] = sim->name[a];
    SURGE_STEP_FIELDS(SAVE_FIELD)
#undef SAVE_FIELD
}

/* Phase timers (surge_phase_times): a phase runs from a mark to the phase_end that names it. The stepping thread reads
 * the clock outside parallel regions (or, inside one, as its master thread just after a barrier), a few reads a step
 * that change no result. */
/* Starts a phase: the time since the last mark is no named phase's (other_s) */
static inline void phase_begin(surge_sim *sim)
{
    sim->phase_mark_s = omp_get_wtime();
}

/* Ends a phase: the time since the last mark is added to *phase_s (a member of sim->phase_times), and the next phase
 * starts here */
static inline void phase_end(surge_sim *sim, double *phase_s)
{
    const double now_s = omp_get_wtime();
    *phase_s += now_s - sim->phase_mark_s;
    sim->phase_mark_s = now_s;
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

#endif
