/* Non-smooth contact dynamics for rigid discs (in the spirit of Chrono's NSC/DVI solver, GMD Sect. 2.2):
 * every sub-step applies the external accelerations, finds the contacts (grid broad phase), solves the
 * impulses of all contacts together by projected Gauss-Seidel with warm starting (Signorini non-penetration,
 * Coulomb friction, restitution), then moves the discs with the new velocities (semi-implicit Euler).
 * Knows nothing of SPH: the solver hands it accelerations and takes back positions and velocities. */
#ifndef SURGE_CONTACT_SOLVER_H
#define SURGE_CONTACT_SOLVER_H

#include <stdint.h>

/* The discs, structure of arrays; per metre of width in 2D. inv_mass or inv_inertia 0: that motion is locked.
 * spin_damping (1/s, NULL: none): a part -k omega of the angular acceleration integrated implicitly, for
 * couplings stiffer than the step (a small disc in a very viscous fluid). */
typedef struct contact_discs {
    int count;
    double *x, *y, *angle;
    double *vx, *vy, *omega;
    const double *radius, *inv_mass, *inv_inertia;
    const double *spin_damping;
    /* NULL, or each disc's contact impulses over an advance (N s per metre of width), x and y, from the walls and from
     * the other discs; the films' not counted */
    double *wall_impulse_x, *wall_impulse_y, *disc_impulse_x, *disc_impulse_y;
} contact_discs;

typedef enum contact_wall_shape {
    CONTACT_PLANE = 0,   /* the half-plane n . p >= offset: discs stay on the side n points to */
    CONTACT_SEGMENT = 1, /* a thin segment from (x0, y0) to (x1, y1), touched from either side and its ends */
} contact_wall_shape;

#define CONTACT_WALLS_MAX 8 /* the most walls an advance takes */

typedef struct contact_wall {
    contact_wall_shape shape;
    double nx, ny, offset;       /* plane */
    double x0, y0, x1, y1;       /* segment */
    double vx_mps, vy_mps;       /* surface velocity (a moving belt) */
} contact_wall;

typedef struct contact_settings {
    double friction;            /* Coulomb mu */
    double restitution;         /* e */
    double restitution_min_mps; /* no bounce below this approach speed */
    int substeps, iterations;
    double erp;                 /* fraction of an overlap removed per sub-step */
    double period_m;            /* > 0: periodic in x with this period, positions kept in [0, period) */
    /* the lubrication force of gaps narrower than lubrication_cutoff_m (lubrication.h), solved implicitly with the
     * contacts; viscosity 0: none. Gaps and radii are the surfaces' (the solver's less gap_offset_m, a contact
     * margin that the discs' radii and the walls carry half each) */
    double lubrication_viscosity_pa_s, lubrication_cutoff_m, lubrication_min_gap_m, gap_offset_m;
    /* > 0: the squeeze film's unresolved part is the measured one (lubrication_measured_damping) for this kernel
     * smoothing length, out to LUBRICATION_RESOLVED_END of it; 0: the film's less its value at the cut-off */
    double lubrication_kernel_h_m;
    const struct lubrication_share *lubrication_share; /* the share the scheme resolves, for the measured film */
    /* 1: the films' tangential part is Reynolds' (lubrication_tangential_damping, for lubrication_kernel_h_m > 0) in
     * place of the sliding film's */
    int lubrication_tangential_reynolds;
} contact_settings;

typedef struct contact_stats {
    int contacts;         /* touching or about to touch in the last sub-step */
    double max_overlap_m; /* largest overlap at the start of any sub-step of the last advance */
    /* the contacts' impulses over the last advance's sub-steps (N s per metre of width), normal and the friction
     * impulses' magnitudes: of each wall on the discs (by wall index) and of discs on each other (each pair once); the
     * films' not counted */
    double wall_normal_impulse[CONTACT_WALLS_MAX], wall_friction_impulse[CONTACT_WALLS_MAX];
    double disc_normal_impulse, disc_friction_impulse;
} contact_stats;

typedef struct contact_solver contact_solver;

contact_solver *contact_solver_create(void);
void contact_solver_destroy(contact_solver *solver);

/* Advances the discs by dt_s under constant accelerations (ax, ay, alpha per disc; NULL: none) and the
 * contacts with each other and with the walls (at most CONTACT_WALLS_MAX). Returns 0, or -1 when out of memory or given
 * more walls. */
int contact_solver_advance(contact_solver *solver, contact_discs *discs, const contact_wall *walls, int wall_count,
                           const contact_settings *settings, double dt_s, const double *ax, const double *ay,
                           const double *alpha);

/* A lubrication film (lubrication.h) between disc b and disc a, or a wall -1 - a where a < 0: the normal n from a to
 * b, the lever arms (a wall's 0), and the unresolved parts of the squeeze film's force per unit approach speed and of
 * the sliding film's per unit sliding speed (N s m^-2); the sliding film acts through torques alone, r_a f and r_b f
 * for f = sliding_damping v_t, v_t the speed of b's surface past a's along t = (-n_y, n_x). With reynolds set,
 * sliding_damping is the tangential film's S instead (lubrication_tangential_matrix, b the disc T, a the disc B) */
typedef struct contact_film {
    int a, b;
    double nx, ny, ra, rb;
    double normal_damping, sliding_damping;
    double wall_vx, wall_vy;
    int reynolds;
} contact_film;

/* The films of the discs' gaps narrower than settings' lubrication cut-off, at their present positions, into films
 * (grown as needed, *capacity its size). Returns 0, or -1 when out of memory. */
int contact_solver_films(contact_solver *solver, const contact_discs *discs, const contact_wall *walls, int wall_count,
                         const contact_settings *settings, contact_film **films, int *count, int *capacity);

contact_stats contact_solver_stats(const contact_solver *solver);

/* The warm-start impulses the next advance starts from (for checkpoints): key, normal and tangent impulse of each
 * contact of the last sub-step. */
int contact_solver_cache_count(const contact_solver *solver);
void contact_solver_cache_get(const contact_solver *solver, int64_t *keys, double *lambda_n, double *lambda_t);
int contact_solver_cache_set(contact_solver *solver, int count, const int64_t *keys, const double *lambda_n,
                             const double *lambda_t); /* -1: out of memory */

#endif
