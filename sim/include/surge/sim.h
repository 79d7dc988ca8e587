/* The solver: a 2D weakly-compressible SPH simulation behind an opaque handle. */
#ifndef SURGE_SIM_H
#define SURGE_SIM_H

#include <stdint.h>
#include <stdio.h>

#include "surge/params.h"
#include "surge/snapshot.h"

typedef struct surge_sim surge_sim;

/* Quantities derived from the parameters (c0, h, ...), fixed for the run. */
typedef struct surge_derived {
    double h_m;            /* smoothing length */
    double c0_mps;         /* speed of sound actually used */
    double expected_speed_mps; /* the scene's largest expected speed c0 was derived from */
    double head_c0_mps;        /* c0_factor x the hydrostatic head's speed sqrt(g_n H) (1 % density at factor 10) */
    double viscous_c0_mps;     /* c0_factor x sqrt(nu u / r), r the smallest disc's radius (0 without discs) */
    double particle_mass_kg;   /* per metre of width (2D) */
    int32_t fluid_count;
    int32_t wall_count;        /* boulders' particles included */
    int32_t boulder_count;
    double smallest_boulder_radius_m; /* infinity without boulders */
} surge_derived;

typedef enum surge_health_check {
    SURGE_HEALTHY = 0,
    SURGE_CHECK_NOT_FINITE,   /* NaN or Inf in position, velocity or density */
    SURGE_CHECK_DENSITY,      /* |rho/rho0 - 1| above health.max_density_deviation */
    SURGE_CHECK_LEFT_DOMAIN,  /* outside the domain box */
    SURGE_CHECK_CROSSED_WALL, /* inside a wall, past its first layer */
    SURGE_CHECK_DT_COLLAPSE,  /* dt below health.min_dt_ratio of the first dt */
    SURGE_CHECK_OUT_OF_MEMORY, /* a step could not allocate what it needed (the contact solver's arrays) */
    SURGE_CHECK_SOLVER,       /* a linear solve of the implicit scheme did not converge */
    SURGE_CHECK_SPEED,        /* explicit scheme: a particle faster than the speed of sound c0 */
} surge_health_check;

typedef struct surge_health {
    surge_health_check check;
    int32_t particle_id; /* -1 when the failure is not about one particle */
    int64_t step;
    double time_s;
    double value;        /* the offending value (density ratio, position, dt, ...) */
    char message[256];
} surge_health;

/* "healthy", "density far from rho0", ... */
const char *surge_health_check_name(surge_health_check check);

/* Builds the scene described by params. NULL on error, with the reason in err. */
surge_sim *surge_sim_create(const surge_params *params, char *err, size_t err_len);
void surge_sim_destroy(surge_sim *sim);

/* Advances one symplectic step. Returns 0, or -1 when the health monitor fails the new state; the state is
 * then rolled back to the last good one (the start of the step) and surge_sim_health says why. */
int surge_sim_step(surge_sim *sim);

double surge_sim_time(const surge_sim *sim);
int64_t surge_sim_step_count(const surge_sim *sim);
double surge_sim_last_dt(const surge_sim *sim);
const surge_params *surge_sim_params(const surge_sim *sim);
const surge_derived *surge_sim_derived(const surge_sim *sim);
const surge_health *surge_sim_health(const surge_sim *sim);

/* Changes a parameter marked live between steps; -1 with a message if not live or out of range. */
int surge_sim_set_param(surge_sim *sim, const char *name, const char *value, char *err, size_t err_len);

/* The scene's largest expected speed for the parameters in force now (live changes included); c0 stays what
 * it was derived as at the start (surge_derived). */
double surge_sim_expected_speed_mps(const surge_sim *sim);

/* Copies the current state (all particles, ordered by id). */
int surge_sim_snapshot(const surge_sim *sim, surge_snapshot *snap);

typedef struct surge_diagnostics {
    double time_s, dt_s;
    int64_t step;
    double kinetic_energy_jpm;     /* fluid, per metre of width */
    double max_speed_mps;
    double max_density_deviation;  /* max |rho/rho0 - 1| over fluid */
    double fluid_volume_m2;        /* sum m/rho (per metre of width) */
    double mean_vx_mps;            /* fluid mean x velocity */
    double bottom_wall_speed_mps;  /* current belt velocity */
    int32_t pressure_iterations;   /* a scheme with linear solves, last step: iterations of the pressure solve (else 0) */
    int32_t viscous_iterations;    /* and of the viscous solve */
    double pressure_residual;      /* relative residuals the solves reached */
    double viscous_residual;
    int64_t step_halvings;         /* a scheme that retries steps: the times it took a step again at half the length
                                    * since the simulation was created or read from a checkpoint (else 0) */
} surge_diagnostics;

surge_diagnostics surge_sim_diagnostics(const surge_sim *sim);
/* Whether the scheme in use solves linear systems: the diagnostics' iterations and residuals mean something */
bool surge_sim_reports_solves(const surge_sim *sim);

/* The contact solver's impulses on the discs, summed over the steps taken since the simulation was created or read
 * from a checkpoint (N s per metre of width), normal and the friction impulses' magnitudes: of the bed (the belt, where
 * it moves), of the other walls (the upstream wall, the lid, the sides, the disc catcher), and between discs (each
 * pair once); the lubrication films' not counted. Their change over a span of simulated time, divided by it, is the
 * span's mean contact force (flow.csv). All 0 without discs. */
typedef struct surge_contact_impulses {
    double bed_normal_nspm, bed_friction_nspm;
    double wall_normal_nspm, wall_friction_nspm;
    double disc_normal_nspm, disc_friction_nspm;
} surge_contact_impulses;

surge_contact_impulses surge_sim_contact_impulses(const surge_sim *sim);

/* What `surge check` says of the scene for the scheme in use, before it runs: its warnings on steps and resolution,
 * its time step, memory and cost estimate (verbose: all of it, else only warnings and an estimate past 4 GB) */
void surge_sim_check_report(const surge_sim *sim, FILE *out, int verbose);

/* 64-bit FNV-1a hash of the fluid's positions, velocities and densities, the boulders' state, step and time:
 * equal hashes mean bit-identical states. */
uint64_t surge_sim_state_hash(const surge_sim *sim);

/* Wall-clock seconds the steps spent in each phase since the simulation was created or its times were reset, read on
 * the thread that steps, at the phases' boundaries: a phase that several threads share ends at their barrier, so its
 * time includes their waits there. A phase the scheme or the scene does not have stays 0 (docs/performance.md,
 * "Where a step's time goes"). */
typedef struct surge_phase_times {
    int64_t steps;           /* surge_sim_step calls timed, failed ones included */
    double total_s;          /* their wall time */
    double neighbours_s;     /* the neighbour lists: the rebuild test, the cell sort and the lists' build */
    double interaction_s;    /* explicit: the fluid's pair loops (the rates of density and velocity, the wall-face
                              * repulsion) and the packed records they read */
    double boundary_s;       /* the walls' mDBC states at their ghost nodes; implicit: also the velocities no-slip
                              * mirrors about and the walls' conditions on the projection */
    double discs_s;          /* the fluid's forces on the discs and the discs' motion outside the contact solver */
    double contacts_s;       /* the contact solver's sub-steps (one thread) */
    double geometry_s;       /* implicit: the step's pair coefficients, moment matrices, kernel sums, mirror weights */
    double surface_s;        /* implicit: the free-surface layer and the surface's mirror images */
    double assembly_s;       /* implicit: the operators' coefficients, the solves' right-hand sides and diagonals */
    double multigrid_s;      /* implicit: the multigrid hierarchies: their builds (the matrix's sparse stand-in,
                              * hypre's coarsening; on one thread, or the parts side by side), and the check that
                              * a held one still serves */
    double viscous_solve_s;  /* implicit: the viscous solve's iterations */
    double pressure_solve_s; /* implicit: the pressure and rest-density solves' iterations and their gradients */
    double disc_coupling_s;  /* implicit: the discs' rows of the coupled solves outside their iterations, and the
                              * pressure passes between them */
    double update_s;         /* the time step, the particles' new state (shifting and the contact rule included), the
                              * health check */
    double other_s;          /* total_s less the phases above: the rest of the step, on the stepping thread alone */
} surge_phase_times;

/* The phase times so far (other_s computed from the rest) */
void surge_sim_phase_times(const surge_sim *sim, surge_phase_times *times);
/* Sets the phase times and their step count to zero */
void surge_sim_reset_phase_times(surge_sim *sim);

/* Checkpoint: everything needed to continue bit-for-bit. */
int surge_sim_checkpoint_write(const surge_sim *sim, const char *path, char *err, size_t err_len);
/* Restores a checkpoint; overrides are "section.key=value" of live parameters (may be NULL/0). */
surge_sim *surge_sim_checkpoint_read(const char *path, const char *const *overrides, int override_count,
                                     char *err, size_t err_len);

#endif
