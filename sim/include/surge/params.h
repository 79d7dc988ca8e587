/* The parameter set of a run and the one registry that describes it.
 * The registry (name, type, unit, default, range, live-changeable, doc) serves the case-file parser,
 * command-line overrides (-s section.key=value), the control socket and docs/parameters.md. */
#ifndef SURGE_PARAMS_H
#define SURGE_PARAMS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

typedef enum surge_shifting_form {
    SURGE_SHIFT_NONE = 0,
    SURGE_SHIFT_VELOCITY = 1, /* Skillen et al. 2013: dr = -A h |u| dt grad C */
    SURGE_SHIFT_LIND = 2,     /* Lind et al. 2012: dr = -(A/2) h c0 dt grad C, none in the surface layer */
} surge_shifting_form;

typedef enum surge_scheme {
    SURGE_SCHEME_EXPLICIT = 0, /* weakly-compressible SPH, symplectic, time step at the speed of sound */
    SURGE_SCHEME_IMPLICIT = 1, /* incompressible projection with implicit viscosity (sim/src/scheme/implicit/) */
} surge_scheme;

typedef enum surge_preconditioner {
    SURGE_PRECONDITIONER_JACOBI = 0, /* matrix-free BiCGSTAB on the neighbour lists, diagonal preconditioner */
    SURGE_PRECONDITIONER_AMG = 1,    /* matrix-free BiCGSTAB, a V-cycle of hypre's BoomerAMG on a sparse stand-in */
    SURGE_PRECONDITIONER_AUTO = 2,   /* amg from the sizes below, jacobi under them */
} surge_preconditioner;

/* Where the multigrid starts to pay (docs/method.md, "Linear solvers"), on the Freydier front, one thread: for the
 * pressure, jacobi was faster with 2,040 fluid particles and amg with 2,940 (C_h 1.3); for the viscous solve, which
 * starts from v_n, jacobi was faster with 4,591, they were level with 8,161 and amg was faster with 18,361 (C_h 1.8,
 * the multigrid on the sparse stand-in) */
#define SURGE_AMG_MIN_FLUID_PARTICLES 2500
#define SURGE_AMG_MIN_FLUID_PARTICLES_VISCOUS 10000

typedef enum surge_diffusion_form {
    SURGE_DIFFUSION_FOURTAKAS = 0, /* Fourtakas et al. 2019: density differences less their hydrostatic part */
    SURGE_DIFFUSION_ANTUONO = 1,   /* Antuono et al. 2010 (delta-SPH): less the renormalised density gradient */
} surge_diffusion_form;

typedef enum surge_no_penetration_at {
    SURGE_NO_PENETRATION_AT_FACE = 0,  /* the fluid's velocity at the wall face, extrapolated from the ghost node */
    SURGE_NO_PENETRATION_AT_GHOST = 1, /* the fluid's velocity at the ghost node */
} surge_no_penetration_at;

typedef enum surge_fluid_shape {
    SURGE_SHAPE_BLOCK = 0,       /* rectangle [x0, x1] x [0, depth] */
    SURGE_SHAPE_LUBRICATION = 1, /* steady lubrication front with the block's volume, from x0 downstream */
} surge_fluid_shape;

typedef enum surge_lubrication_resolved {
    SURGE_LUBRICATION_CUTOFF = 0,  /* the film's force at lubrication_cutoff_dp, below it */
    SURGE_LUBRICATION_MEASURED = 1 /* the measured share of the exact resistance at each gap over the kernel's h */
} surge_lubrication_resolved;

typedef enum surge_lubrication_tangential {
    SURGE_TANGENTIAL_SLIDING = 0, /* torques from the surfaces' relative sliding speed, the cut-off's part below it */
    SURGE_TANGENTIAL_REYNOLDS = 1 /* Reynolds' equation with the gap's shape moving with the discs, measured share */
} surge_lubrication_tangential;

typedef enum surge_lubrication_share {
    SURGE_SHARE_SCHEME = 0,   /* the share the scheme in use resolves of a lone disc's film */
    SURGE_SHARE_EXPLICIT = 1, /* the explicit scheme's, whatever the scheme */
    SURGE_SHARE_IMPLICIT = 2  /* the implicit scheme's, whatever the scheme */
} surge_lubrication_share;

typedef enum surge_color_field {
    SURGE_FIELD_SPEED = 0,    /* |v| */
    SURGE_FIELD_VX_REL = 1,   /* vx - belt speed: velocity relative to the belt */
    SURGE_FIELD_VX = 2,
    SURGE_FIELD_PRESSURE = 3,
    SURGE_FIELD_DENSITY = 4,
} surge_color_field;

typedef enum surge_colormap_choice {
    SURGE_COLORMAP_VIRIDIS = 0,
    SURGE_COLORMAP_CIVIDIS = 1,
} surge_colormap_choice;

typedef enum surge_boulder_placement {
    SURGE_BOULDERS_NONE = 0,   /* no boulders */
    SURGE_BOULDERS_LIST = 1,   /* the discs of boulders.list_m */
    SURGE_BOULDERS_RANDOM = 2, /* random non-overlapping discs up to boulders.solid_fraction of the region */
    SURGE_BOULDERS_GRADED = 3, /* sizes from a grading curve, more discs near the front (surge/boulder_scene.h) */
    SURGE_BOULDERS_FILE = 4,   /* the discs of the CSV boulders.file (as a run writes to boulders.csv) */
} surge_boulder_placement;

/* Longest value of a text parameter, terminating NUL included. */
#define SURGE_TEXT_PARAM_BYTES 1000

typedef enum surge_view_mode {
    SURGE_VIEW_WHOLE = 0,  /* every particle */
    SURGE_VIEW_FOLLOW = 1, /* a window of view_width_m that keeps the surge front at 3/4 of its width */
    SURGE_VIEW_FIXED = 2,  /* x from view_x0_m to view_x1_m */
} surge_view_mode;

typedef enum surge_render_style {
    SURGE_STYLE_FIELD = 0,     /* the fluid as a continuous field interpolated with a kernel, free surface drawn */
    SURGE_STYLE_PARTICLES = 1, /* each particle as a disc of diameter dp */
} surge_render_style;

typedef struct surge_params {
    struct {
        double length_m;  /* x extent; the period when periodic */
        double height_m;  /* y extent of the box; top wall position when there is one */
        bool periodic_x;
    } domain;
    struct {
        double density_kgpm3;
        double viscosity_m2ps; /* kinematic viscosity nu0 */
        double x0_m, x1_m;     /* initial fluid block, along x */
        double depth_m;        /* initial fluid block depth from the bed (y = 0) */
        int shape;             /* surge_fluid_shape */
    } fluid;
    struct {
        int layers;
        bool bottom, top, left, right;
        bool upstream;            /* vertical wall at upstream_x_m inside a periodic domain, fluid on its +x side */
        bool disc_catcher;        /* discs (not fluid) cannot cross the end of the period, x = domain.length_m */
        bool no_penetration;      /* continuity sees approaching fluid met by the mirrored normal velocity */
        int no_penetration_at;    /* surge_no_penetration_at: where the approach is read */
        bool quadratic_no_slip;   /* no-slip walls' velocity from a quadratic fit (else mDBC's mirror) */
        double face_repulsion_reach_dp; /* fluid closer than this to a wall face is pushed back (dp; 0: off) */
        double upstream_x_m;
        double upstream_height_m;
        double bottom_speed_mps;  /* target x velocity of the bottom wall (the belt; negative = upstream) */
        double top_speed_mps;     /* target x velocity of the top wall (a lid) */
        double ramp_s;            /* time to reach the target wall speeds from rest (smooth ramp) */
    } walls;
    struct {
        double gravity_mps2;
        double slope_deg;    /* gravity tilted by this angle so that the bed stays along x */
        double force_x_mps2; /* constant body force along x (pressure-driven channels) */
    } body;
    struct {
        double dp_m;
        double ch;                /* h = ch sqrt(2) dp */
        double cfl;
        double c0_mps;            /* 0: derived from the scene's scales */
        double c0_factor;         /* c0 = c0_factor * largest expected speed when derived */
        double density_diffusion; /* delta of the density-diffusion term */
        int density_diffusion_form; /* surge_diffusion_form */
        double density_relaxation;  /* kappa: bulk densities relax toward the kernel sum at kappa |2D| (0: off) */
        bool density_relaxation_near_discs; /* the relaxation within 2h of a disc too */
        bool continuity_correction; /* velocity divergence renormalised by the kernel moment matrix */
        double neighbour_skin_h;    /* neighbour-list skin in units of h (0: rebuilt every step) */
        bool viscous_dt_limit;
        double dt_fixed_s;        /* 0: variable time step */
        int scheme;               /* surge_scheme */
    } numerics;
    struct { /* the implicit scheme (numerics.scheme = implicit) */
        double cfl;                /* the advective limit: dt <= cfl h / u_max */
        double force_cfl;          /* the body-force limit: dt <= force_cfl sqrt(h / |g|) */
        double pressure_tolerance; /* relative residual of the pressure Poisson solve */
        double viscous_tolerance;  /* relative residual of the implicit viscous solve */
        double density_tolerance;  /* relative residual of the rest-density solve (psi) */
        int max_iterations;        /* per solve; more is a health failure */
        int preconditioner;        /* surge_preconditioner, for the solves */
        int multigrid_rebuild_steps; /* amg: a hierarchy serves at most this many steps */
        int multigrid_parts;         /* amg: diagonal blocks, a hierarchy each, V-cycled side by side */
        double density_correction; /* alpha: weight of the rest-density source (psi's solve) */
        double anti_clumping;      /* w in the compressed particles' shift -2 w (rho_k/rho0 - 1) h^2 grad C */
        double surface_threshold;  /* div r below this: a free-surface particle, p = 0 */
        double surface_kernel_margin; /* kernel sum this far below a flat surface's second row's: surface too */
        double surface_scan_dp;    /* radius (dp) of the region beyond a particle that, empty, puts it on the surface */
        double contact_reach_dp;   /* no step or shift ends closer than this to a wall face (dp) */
        double pair_distance_dp;   /* two fluid particles closer than this (dp) are parted, their approach stopped */
        double wall_neumann_offset; /* 0..1: weight of phi's inhomogeneous Neumann offset at walls inside the fluid */
        bool surface_images;       /* p = 0 on the free surface by mirror images beyond it (else on its particles) */
        double pressure_relaxation; /* beta: p_n relaxed by p - beta (L p)/L_aa at each step under a free surface */
        int disc_pressure_passes;  /* with discs: passes of the viscous and pressure solves a step (Uzawa) */
        int disc_pressure_history; /* and the earlier passes each pass's pressure is combined from (Anderson; 0: none) */
        int step_halvings;         /* a step that compresses past the density bound or whose solve fails is taken
                                    * again at half its length, at most this many times (0: the run stops) */
    } implicit;
    struct {
        int placement;           /* surge_boulder_placement */
        char list_m[SURGE_TEXT_PARAM_BYTES]; /* "x y r [vx vy omega], ...": m, m/s, rad/s */
        double solid_fraction;   /* random: disc area / region area */
        double radius_m;         /* random: disc radius (the smallest when radius_max_m > radius_m) */
        double radius_max_m;     /* random: radii uniform in [radius_m, radius_max_m]; <= radius_m: monodisperse */
        double region_x0_m, region_x1_m, region_y0_m, region_y1_m; /* random: where centres may go */
        double min_gap_m;        /* random: smallest gap between discs and from walls */
        int seed;
        double density_ratio;    /* rho_body / rho0 */
        char grading_file[SURGE_TEXT_PARAM_BYTES]; /* graded: CSV diameter_m,fraction_passing; "": built-in */
        int count;                      /* graded: number of discs (0: up to solid_fraction of the fluid block) */
        double diameter_min_m;          /* graded: sizes below are not drawn (the paper's truncation, 0.2 m) */
        double diameter_max_m;          /* graded: nor above (0: the fluid depth less two gaps) */
        double front_median_m;          /* graded: median distance of a centre behind the front (log-normal) */
        double front_sigma;             /* graded: the log-normal's sigma (of ln distance) */
        char file[SURGE_TEXT_PARAM_BYTES]; /* file: CSV x_m,y_m,r_m[,vx_mps,vy_mps,omega_radps] */
        bool pack_fluid;                /* keep every fluid site outside a disc and pack the fluid around the discs */
    } boulders;
    struct {
        double friction;         /* Coulomb coefficient mu */
        double restitution;      /* normal restitution coefficient e */
        double restitution_min_mps; /* approach speeds below this do not bounce */
        int substeps;            /* contact sub-steps per SPH step */
        int iterations;          /* projected Gauss-Seidel sweeps per sub-step */
        double erp;              /* fraction of an overlap removed per sub-step */
        double margin_dp;        /* discs touch each other and walls this far apart (dp): fluid gaps below dp */
        bool solid_pressure;     /* discs feel the pressure of wall and other discs' particles in reach (fluid_forces.c) */
        bool lubrication;        /* the lubrication force of gaps narrower than the cut-off (lubrication.h) */
        double lubrication_cutoff_dp;  /* gaps below this (dp) take the unresolved part of the lubrication force */
        double lubrication_min_gap_dp; /* the force's gap is at least this (dp): surface roughness */
        surge_lubrication_resolved lubrication_resolved; /* what the SPH is taken to resolve of a squeeze film */
        surge_lubrication_tangential lubrication_tangential; /* the tangential film's form (lubrication.h) */
        surge_lubrication_share lubrication_share; /* whose measured share the films leave out */
    } contacts;
    struct {
        int form;                    /* surge_shifting_form */
        double velocity_coefficient; /* A of the velocity-proportional form */
        double lind_coefficient;     /* A_L of Lind's form */
        double surface_threshold;    /* div r below this marks a free-surface particle (2D bulk: 2) */
        double max_shift_dp;         /* largest shift in one step, in units of dp */
        double surface_anti_clumping; /* explicit lind: w of the shift of crowded particles in the surface layer */
        bool consistent_density;     /* the shift's divergence changes the density too (volume follows spacing) */
    } shifting;
    struct {
        double end_s;
    } time;
    struct {
        double snapshot_interval_s;    /* 0: no snapshots but the final one */
        double diagnostics_interval_s; /* 0: every step */
        double checkpoint_interval_s;  /* 0: only the final checkpoint */
        double progress_interval_s;    /* wall-clock seconds between progress lines; 0: none */
        double flow_interval_s;        /* between rows of flow.csv, a belt surge's eq. 21 numbers; 0: none */
        double flow_ignore_m;          /* flow.csv leaves out this much next to the upstream wall */
        double flow_column_m;          /* column width for the flow height */
    } output;
    struct { /* read by the renderer (render/); the solver ignores them */
        double frame_interval_s;  /* simulated time between rendered frames */
        int width_px, height_px;
        int style;                /* surge_render_style */
        int field;                /* surge_color_field */
        int colormap;             /* surge_colormap_choice */
        double color_min, color_max; /* colour range; equal: from each frame's data */
        int view;                 /* surge_view_mode */
        double view_x0_m, view_x1_m; /* the fixed view */
        double view_width_m;      /* the follow view */
        bool true_slope;          /* draw the bed at its slope (gravity down the image), not along x */
        double movie_fps;         /* frames per second of the movie */
    } render;
    struct {
        double max_density_deviation; /* |rho/rho0 - 1| above this is a failure */
        double min_dt_ratio;          /* dt below this fraction of the first step's dt is a failure */
    } health;
} surge_params;

typedef enum surge_param_type {
    SURGE_PARAM_REAL,
    SURGE_PARAM_INT,
    SURGE_PARAM_BOOL,
    SURGE_PARAM_ENUM,
    SURGE_PARAM_TEXT, /* up to SURGE_TEXT_PARAM_BYTES - 1 characters */
} surge_param_type;

typedef struct surge_param_info {
    const char *section;
    const char *key;
    surge_param_type type;
    const char *unit;
    double default_value;
    double min_value, max_value; /* inclusive; for ENUM the index range */
    bool live;                   /* may change while the simulation runs */
    const char *enum_names;      /* "a|b|c" for ENUM, NULL otherwise */
    const char *doc;
    size_t offset;               /* into surge_params */
} surge_param_info;

surge_params surge_default_params(void);

int surge_param_count(void);
const surge_param_info *surge_param_at(int index);
/* "section.key"; NULL when unknown. */
const surge_param_info *surge_param_find(const char *name);

/* Parses and range-checks value; on error returns -1 and writes a message naming the parameter and its
 * allowed range/values to err. */
int surge_param_set(surge_params *p, const surge_param_info *info, const char *value, char *err, size_t err_len);
/* Current value as text, formatted so that surge_param_set reads it back exactly (buf of
   SURGE_TEXT_PARAM_BYTES holds any value). */
void surge_param_format(const surge_params *p, const surge_param_info *info, char *buf, size_t len);
double surge_param_get_number(const surge_params *p, const surge_param_info *info);
/* Whether any parameter marked live differs between a and b (text parameters are never live). */
bool surge_params_live_differ(const surge_params *a, const surge_params *b);

/* Reads an INI-style case file over p. Errors name path:line. */
int surge_params_load(surge_params *p, const char *path, char *err, size_t err_len);
/* Same from text in memory; source names it in errors. */
int surge_params_load_text(surge_params *p, const char *text, const char *source, char *err, size_t err_len);
/* "section.key=value" from the command line. */
int surge_params_override(surge_params *p, const char *assignment, bool live_only, char *err, size_t err_len);
/* walls.layers, or the automatic value (ceil(2h/dp)) when it is 0. */
int surge_params_wall_layers(const surge_params *p);
/* Whether the implicit scheme solves its pressure (viscous = false) or viscous (true) systems by the multigrid with
 * fluid_count fluid particles: implicit.preconditioner, auto by the sizes above. */
bool surge_implicit_uses_amg(const surge_params *p, int fluid_count, bool viscous);

/* The implicit scheme's time step (s) with smoothing length h_m, gravity g_mps2 and largest speed u_max_mps:
 * min(implicit.cfl h / u_max, implicit.force_cfl sqrt(h / g)); infinite with neither speed nor gravity. */
double surge_implicit_dt_s(const surge_params *p, double h_m, double g_mps2, double u_max_mps);
/* Checks that the parameters together describe a scene that can be built (block inside the box...). */
int surge_params_validate(const surge_params *p, char *err, size_t err_len);

/* The full resolved set as a case file that reloads to the same values. */
void surge_params_write(const surge_params *p, FILE *out);
/* The parameter reference (docs/parameters.md). */
void surge_params_write_reference(FILE *out);

#endif
