/* The parameter registry, the case-file parser and the resolved-parameter writer. */
#include "surge/params.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#define OFF(field) offsetof(surge_params, field)
#define BIG 1e30

/* The defaults describe the belt-front scene (cases/belt_front.ini): a valid scene on their own. */
static const surge_param_info registry[] = {
    /* section, key, type, unit, default, min, max, live, enum names, doc, offset */
    {"domain", "length_m", SURGE_PARAM_REAL, "m", 0.6, 1e-6, 1e4, false, NULL,
     "Extent of the domain along x (the period when periodic).", OFF(domain.length_m)},
    {"domain", "height_m", SURGE_PARAM_REAL, "m", 0.08, 1e-6, 1e4, false, NULL,
     "Extent of the domain along y from the bed; the top wall sits here; particles above it have left the domain.",
     OFF(domain.height_m)},
    {"domain", "periodic_x", SURGE_PARAM_BOOL, "-", 1, 0, 1, false, NULL,
     "Periodic in x (conveyor-belt and channel scenes).", OFF(domain.periodic_x)},

    {"fluid", "density_kgpm3", SURGE_PARAM_REAL, "kg m^-3", 1383, 1e-3, 1e5, false, NULL,
     "Reference density rho0.", OFF(fluid.density_kgpm3)},
    {"fluid", "viscosity_m2ps", SURGE_PARAM_REAL, "m^2 s^-1", 5.6 / 1383.0, 0, 1e3, true, NULL,
     "Kinematic viscosity nu0 (dynamic viscosity / density).", OFF(fluid.viscosity_m2ps)},
    {"fluid", "x0_m", SURGE_PARAM_REAL, "m", 0.012, -1e4, 1e4, false, NULL,
     "Upstream end of the initial fluid block.", OFF(fluid.x0_m)},
    {"fluid", "x1_m", SURGE_PARAM_REAL, "m", 0.282, -1e4, 1e4, false, NULL,
     "Downstream end of the initial fluid block.", OFF(fluid.x1_m)},
    {"fluid", "depth_m", SURGE_PARAM_REAL, "m", 0.018, 1e-6, 1e4, false, NULL,
     "Depth of the initial fluid block above the bed (y = 0).", OFF(fluid.depth_m)},
    {"fluid", "shape", SURGE_PARAM_ENUM, "-", SURGE_SHAPE_BLOCK, 0, 1, false, "block|lubrication",
     "Initial fluid: the block, or the steady lubrication front (GMD 2025 Sect. 3.1; docs/references.md) holding the "
     "block's volume, starting at x0_m (needs a belt speed and a slope).", OFF(fluid.shape)},

    {"walls", "layers", SURGE_PARAM_INT, "-", 0, 0, 16, false, NULL,
     "Layers of boundary particles in every wall; 0: ceil(2h/dp), just enough for the kernel support.",
     OFF(walls.layers)},
    {"walls", "bottom", SURGE_PARAM_BOOL, "-", 1, 0, 1, false, NULL, "No-slip bed below y = 0.", OFF(walls.bottom)},
    {"walls", "top", SURGE_PARAM_BOOL, "-", 0, 0, 1, false, NULL, "No-slip lid above y = domain.height_m.",
     OFF(walls.top)},
    {"walls", "left", SURGE_PARAM_BOOL, "-", 0, 0, 1, false, NULL,
     "Wall left of x = 0 (non-periodic domains only).", OFF(walls.left)},
    {"walls", "right", SURGE_PARAM_BOOL, "-", 0, 0, 1, false, NULL,
     "Wall right of x = domain.length_m (non-periodic domains only).", OFF(walls.right)},
    {"walls", "upstream", SURGE_PARAM_BOOL, "-", 1, 0, 1, false, NULL,
     "Fixed vertical wall at upstream_x_m inside a periodic domain, fluid on its downstream (+x) side.",
     OFF(walls.upstream)},
    {"walls", "disc_catcher", SURGE_PARAM_BOOL, "-", 0, 0, 1, false, NULL,
     "With an upstream wall: discs cannot cross the end of the period (x = domain.length_m), a line the fluid passes. "
     "A disc that leaves the front and rolls down the dry belt stops there, like a grate at a flume's end, instead of "
     "going round to the back of the upstream wall (docs/boulders.md).", OFF(walls.disc_catcher)},
    {"walls", "no_penetration", SURGE_PARAM_BOOL, "-", 1, 0, 1, true, NULL,
     "Where fluid approaches a wall or the belt (not a boulder), the wall particle meets it with the mirrored normal "
     "velocity in the continuity equation (compressed as by its mirror image; docs/method.md).",
     OFF(walls.no_penetration)},
    {"walls", "no_penetration_at", SURGE_PARAM_ENUM, "-", SURGE_NO_PENETRATION_AT_FACE, 0, 1, true, "face|ghost",
     "Where no_penetration reads the fluid's approach: face (its normal velocity at the wall face, carried from the "
     "ghost node's first-order interpolation by the rate a volume-keeping flow has, minus the stretch along the wall, "
     "so that pressure waves do not feed it; the ghost node's Shepard value where that is ill-conditioned) or "
     "ghost (at the ghost node, the wall particle's mirror image, up to 2h into the fluid, where a thinning layer's "
     "descent reads as an approach: a thin explicit current then rides high and spreads fast; "
     "docs/validation/spreading.md).",
     OFF(walls.no_penetration_at)},
    {"walls", "quadratic_no_slip", SURGE_PARAM_BOOL, "-", 0, 0, 1, true, NULL,
     "Implicit scheme (the explicit one refuses it): the velocity a no-slip wall particle (not a disc's) takes in "
     "the viscous solve. 0: mDBC's mirror, 2 u_wall - u_ghost, exact where the velocity is linear across the wall; "
     "1: u_wall + n (b0 + b1 t + b2 n) evaluated at the "
     "particle, fitted by kernel-weighted least squares to the fluid around its ghost node (n the distance from the "
     "wall's face, t along it), exact for the parabola of a pressure- or gravity-driven flow, so that a channel or "
     "film a few particles across carries its flux; the mirror where the fit is ill-conditioned (docs/method.md, "
     "\"Quadratic no-slip walls\").",
     OFF(walls.quadratic_no_slip)},
    {"walls", "face_repulsion_reach_dp", SURGE_PARAM_REAL, "dp", 0.25, 0, 0.5, true, NULL,
     "A fluid particle closer than this to the face of the wall particle straight below it, or to a disc's circle, is "
     "pushed back along the wall normal, 0.1 c0^2/dp (1 - d/reach)^2, and loses its velocity toward the face; no "
     "shift brings a particle closer than this (0: off; the explicit scheme's; the implicit scheme's is "
     "implicit.contact_reach_dp; docs/method.md).", OFF(walls.face_repulsion_reach_dp)},
    {"walls", "upstream_x_m", SURGE_PARAM_REAL, "m", 0.012, -1e4, 1e4, false, NULL,
     "Position of the upstream wall's fluid face.", OFF(walls.upstream_x_m)},
    {"walls", "upstream_height_m", SURGE_PARAM_REAL, "m", 0.06, 1e-6, 1e4, false, NULL,
     "Height of the upstream wall above the bed.", OFF(walls.upstream_height_m)},
    {"walls", "bottom_speed_mps", SURGE_PARAM_REAL, "m s^-1", -0.075, -1e3, 1e3, true, NULL,
     "Target x velocity of the bed (the conveyor belt; negative moves upstream).", OFF(walls.bottom_speed_mps)},
    {"walls", "top_speed_mps", SURGE_PARAM_REAL, "m s^-1", 0.0, -1e3, 1e3, true, NULL,
     "Target x velocity of the lid.", OFF(walls.top_speed_mps)},
    {"walls", "ramp_s", SURGE_PARAM_REAL, "s", 0.5, 0, 1e4, true, NULL,
     "Time for moving walls to reach their target speed from rest (smooth cosine ramp; 0: at once).",
     OFF(walls.ramp_s)},

    {"body", "gravity_mps2", SURGE_PARAM_REAL, "m s^-2", 9.81, 0, 1e3, false, NULL, "Magnitude of gravity.",
     OFF(body.gravity_mps2)},
    {"body", "slope_deg", SURGE_PARAM_REAL, "deg", 15.3, -89, 89, true, NULL,
     "Bed inclination theta: gravity = g (sin theta, -cos theta) so that the bed stays along x.",
     OFF(body.slope_deg)},
    {"body", "force_x_mps2", SURGE_PARAM_REAL, "m s^-2", 0.0, -1e4, 1e4, true, NULL,
     "Constant body force per unit mass along x (a pressure gradient |dP/dx|/rho for channels).",
     OFF(body.force_x_mps2)},

    {"numerics", "dp_m", SURGE_PARAM_REAL, "m", 0.002, 1e-7, 1e2, false, NULL, "Initial particle spacing dp. On a periodic domain it must divide domain.length_m; surge run and check move a dp that does not to the nearest that does when that moves it by 1 % or less, and say so.",
     OFF(numerics.dp_m)},
    {"numerics", "ch", SURGE_PARAM_REAL, "-", 1.8, 0.5, 4, false, NULL,
     "Smoothing coefficient C_h: h = C_h sqrt(2) dp; kernel support 2h.", OFF(numerics.ch)},
    {"numerics", "cfl", SURGE_PARAM_REAL, "-", 0.2, 1e-4, 2, false, NULL,
     "Courant coefficient C_CFL of the variable time step.", OFF(numerics.cfl)},
    {"numerics", "c0_mps", SURGE_PARAM_REAL, "m s^-1", 0, 0, 1e5, false, NULL,
     "Numerical speed of sound; 0 derives it as c0_factor times the largest of the scene's expected speed, the "
     "hydrostatic head's speed and, with discs, the viscous speed sqrt(nu u / r) of the smallest disc's radius r "
     "(docs/method.md, \"c0\").",
     OFF(numerics.c0_mps)},
    {"numerics", "c0_factor", SURGE_PARAM_REAL, "-", 10, 1, 1e3, false, NULL,
     "c0 / largest expected speed when c0 is derived (10 keeps density errors near 1 %).",
     OFF(numerics.c0_factor)},
    {"numerics", "density_diffusion", SURGE_PARAM_REAL, "-", 0.1, 0, 1, false, NULL,
     "Density-diffusion coefficient delta (0: off); fluid-fluid pairs only.",
     OFF(numerics.density_diffusion)},
    {"numerics", "density_diffusion_form", SURGE_PARAM_ENUM, "-", SURGE_DIFFUSION_FOURTAKAS, 0, 1, true,
     "fourtakas|antuono",
     "Density-diffusion term: fourtakas (the paper's; density differences less their hydrostatic part) or "
     "antuono (delta-SPH; less the renormalised density gradient, so that no linear density field diffuses, "
     "also where the kernel is truncated at the free surface). docs/method.md.",
     OFF(numerics.density_diffusion_form)},
    {"numerics", "density_relaxation", SURGE_PARAM_REAL, "-", 1.0, 0, 10, true, NULL,
     "kappa: where the kernel is full (no free-surface particle within 2h), each density relaxes "
     "toward the particles' kernel sum sum_b m W_ab at kappa times the local strain rate, so that spacing and "
     "density cannot part where the fluid deforms (0: off; docs/method.md).", OFF(numerics.density_relaxation)},
    {"numerics", "density_relaxation_near_discs", SURGE_PARAM_BOOL, "-", 1, 0, 1, true, NULL,
     "Apply the density relaxation within 2h of a disc too, its particles counted in the kernel sum as the "
     "fluid's (false: left out there, where the fluid around crowded discs then spreads at constant density: "
     "its kernel sum fell to 0.87-0.91 of its density in the densest debris surge; docs/method.md).",
     OFF(numerics.density_relaxation_near_discs)},
    {"numerics", "continuity_correction", SURGE_PARAM_BOOL, "-", 1, 0, 1, true, NULL,
     "Renormalise the velocity divergence of the continuity equation by the kernel moment matrix (exact for "
     "linear velocity fields where the kernel is truncated, as at the free surface).",
     OFF(numerics.continuity_correction)},
    {"numerics", "neighbour_skin_h", SURGE_PARAM_REAL, "h", 0.2, 0, 2, false, NULL,
     "Skin of the neighbour lists in units of h: each fluid particle lists its neighbours within 2h + skin and "
     "the lists are reused until a particle may have moved skin/2 (0: rebuilt every step; the explicit scheme's: the "
     "implicit scheme's lists have no skin and are built at every step; docs/method.md).",
     OFF(numerics.neighbour_skin_h)},
    {"numerics", "viscous_dt_limit", SURGE_PARAM_BOOL, "-", 1, 0, 1, false, NULL,
     "Include the viscous limit dt_nu = h^2/nu0 in the time step.", OFF(numerics.viscous_dt_limit)},
    {"numerics", "dt_fixed_s", SURGE_PARAM_REAL, "s", 0, 0, 1e3, false, NULL,
     "Fixed time step instead of the variable one (0: variable). For tests of the health monitor.",
     OFF(numerics.dt_fixed_s)},

    {"numerics", "scheme", SURGE_PARAM_ENUM, "-", SURGE_SCHEME_EXPLICIT, 0, 1, false, "explicit|implicit",
     "Time stepping: explicit (weakly-compressible SPH, time step at the speed of sound; the paper's) or implicit "
     "(incompressible projection with implicit viscosity, time step at the flow's own speed; for slow viscous "
     "flows; docs/method.md, \"The implicit scheme\").", OFF(numerics.scheme)},

    {"implicit", "cfl", SURGE_PARAM_REAL, "-", 0.25, 1e-4, 2, true, NULL,
     "Implicit scheme: the advective limit, dt <= cfl h / u_max (at C_h 1.8 a particle at u_max then moves 0.64 dp a "
     "step; at 0.85 dp the Freydier front compressed against its upstream wall, where the flow turns; "
     "docs/validation/stability.md). Taken at each step: a run may continue from its checkpoint with another.",
     OFF(implicit.cfl)},
    {"implicit", "force_cfl", SURGE_PARAM_REAL, "-", 0.4, 1e-4, 2, true, NULL,
     "Implicit scheme: the body-force limit, dt <= force_cfl sqrt(h / |g|), the period of the shortest surface wave "
     "the kernel resolves; at 0.4 the advective limit (implicit.cfl) binds on the Freydier front from dp = 0.5 mm "
     "down (docs/method.md).", OFF(implicit.force_cfl)},
    {"implicit", "pressure_tolerance", SURGE_PARAM_REAL, "-", 1e-3, 1e-14, 0.1, true, NULL,
     "Implicit scheme: relative residual at which the pressure Poisson solve (phi, from the last step's phi) stops; "
     "what it leaves is corrected at the next step (docs/method.md).",
     OFF(implicit.pressure_tolerance)},
    {"implicit", "viscous_tolerance", SURGE_PARAM_REAL, "-", 1e-5, 1e-14, 0.1, true, NULL,
     "Implicit scheme: relative residual at which the implicit viscous solve stops (from v_n; backward Euler's own "
     "error in a step is far larger; docs/method.md).",
     OFF(implicit.viscous_tolerance)},
    {"implicit", "density_tolerance", SURGE_PARAM_REAL, "-", 1e-2, 1e-14, 0.5, true, NULL,
     "Implicit scheme: relative residual at which the rest-density solve (psi, which moves particles back to the "
     "rest spacing) stops; what it leaves is corrected at the next step (1e-2 needs about a tenth of 1e-6's "
     "iterations; docs/method.md).",
     OFF(implicit.density_tolerance)},
    {"implicit", "max_iterations", SURGE_PARAM_INT, "-", 2000, 1, 1000000, true, NULL,
     "Implicit scheme: iterations allowed per linear solve; a solve that needs more fails the run (health).",
     OFF(implicit.max_iterations)},
    {"implicit", "preconditioner", SURGE_PARAM_ENUM, "-", SURGE_PRECONDITIONER_AUTO, 0, 2, false, "jacobi|amg|auto",
     "Implicit scheme: how the linear solves (matrix-free BiCGSTAB on the neighbour lists) are preconditioned: jacobi "
     "(the diagonal), amg (a V-cycle of hypre's BoomerAMG, built each step on a sparse stand-in of the operator: the "
     "nearest neighbours' entries, the others moved to the diagonal; a few iterations after a setup) or auto (amg for "
     "the pressure from 2,500 fluid particles and for the viscous solve from 10,000, where it starts to pay; "
     "docs/method.md, \"Linear solvers\").",
     OFF(implicit.preconditioner)},
    {"implicit", "multigrid_rebuild_steps", SURGE_PARAM_INT, "-", 16, 1, 1000, true, NULL,
     "Implicit scheme, amg: a multigrid hierarchy (one for the viscous solve, one for the pressure) serves at most "
     "this many steps, following its particles as they move, and is rebuilt sooner when its solve takes half as many "
     "iterations again as it did just after the build (at least 2 more); 1: rebuilt every step. It only "
     "preconditions: the solves reach their tolerances on each step's own operator (docs/method.md, \"Linear "
     "solvers\").",
     OFF(implicit.multigrid_rebuild_steps)},
    {"implicit", "multigrid_parts", SURGE_PARAM_INT, "-", 1, 1, 256, false, NULL,
     "Implicit scheme, amg: the parts the pressure's multigrid hierarchy is cut into (slices of the fluid across its "
     "longest extent, in the matrix's breadth-first order; the viscous one, whose two components already run side by "
     "side, in half as many, rounded up), each with a hierarchy of its own (Ruge-Stueben coarsening), built and "
     "V-cycled side by side on the threads (block Jacobi between the parts); 1: one hierarchy on the whole fluid (HMIS "
     "coarsening). For machines with many cores: each part "
     "costs iterations; the results depend on the parts, not on the threads (docs/method.md, \"Linear solvers\").",
     OFF(implicit.multigrid_parts)},
    {"implicit", "density_correction", SURGE_PARAM_REAL, "-", 1, 0, 1, true, NULL,
     "Implicit scheme: alpha, the weight of the rest-density source alpha rho0 (rho_kernel/rho0 - 1)/dt^2 of the "
     "solve (psi) that moves the particles back to the rest spacing against drift (0: off); within a kernel's reach "
     "of the free surface, where the kernel sum is truncated, it is read against a flat surface's kernel sum at the "
     "particle's depth, and next to a partly dry wall only compression counts.",
     OFF(implicit.density_correction)},
    {"implicit", "anti_clumping", SURGE_PARAM_REAL, "-", 1, 0, 10, true, NULL,
     "Implicit scheme: w in the shift -2 w (rho_kernel/rho0 - 1) h^2 grad C that moves particles whose kernel sum is "
     "above the rest density's away from the neighbours crowding them, free-surface particles included; zero where "
     "the spacing is at rest or wider (0: off; docs/method.md).",
     OFF(implicit.anti_clumping)},
    {"implicit", "surface_threshold", SURGE_PARAM_REAL, "-", 1.35, 0, 2, true, NULL,
     "Implicit scheme: a particle whose div r (2 in the bulk) is below this is on the free surface and holds p = 0. "
     "On a square lattice the top row reads 1.15-1.25 and the second 1.49-1.85 for C_h 1.0-1.8 (docs/method.md).",
     OFF(implicit.surface_threshold)},
    {"implicit", "surface_kernel_margin", SURGE_PARAM_REAL, "-", 0.03, 0, 1, true, NULL,
     "Implicit scheme: a particle whose kernel sum (fluid and walls, over the lattice's) is below that of the second "
     "row under a flat free surface (0.988, 0.946, 0.869 at C_h 1.0, 1.3, 1.8) by more than this is on the free "
     "surface too: at a contact line (a front's foot on the bed) the wall raises div r but not the kernel sum.",
     OFF(implicit.surface_kernel_margin)},
    {"implicit", "surface_scan_dp", SURGE_PARAM_REAL, "dp", 1.5, 0, 2.5, true, NULL,
     "Implicit scheme: within a kernel of a disc, a particle with no fluid, wall or disc particle in the region beyond "
     "it along -grad C (a cone of 90 degrees, then a circle of this radius centred this far out; Marrone et al. "
     "2010) is on the free surface too: the border of a cavity opening beside discs, whose sums the discs' particles "
     "fill (0: off; docs/method.md).",
     OFF(implicit.surface_scan_dp)},
    {"implicit", "contact_reach_dp", SURGE_PARAM_REAL, "dp", 0.45, 0, 0.5, true, NULL,
     "Implicit scheme: the contact distance (the explicit scheme's is walls.face_repulsion_reach_dp): a fluid particle "
     "within it of the nearest wall face loses its velocity toward the face, and no step or shift ends closer. 0.45, "
     "just inside the lattice's 0.5, lets the belt-wall corner run at implicit.force_cfl 0.35 where 0.25 compressed it; "
     "at 0.5 the rule holds every particle of a wall's first row and Poiseuille's start-up fails (docs/method.md).",
     OFF(implicit.contact_reach_dp)},
    {"implicit", "pair_distance_dp", SURGE_PARAM_REAL, "dp", 0.5, 0, 0.9, true, NULL,
     "Implicit scheme: two fluid particles closer than this lose their speed toward each other (a perfectly inelastic "
     "collision, momentum kept) and are moved apart to it. A pair that has closed on itself has no kernel gradient "
     "left to part it (grad W(0) = 0), and in the debris surge such pairs gathered by the hundred and set off jets "
     "(0: none; docs/method.md, \"Close pairs\").", OFF(implicit.pair_distance_dp)},
    {"implicit", "wall_neumann_offset", SURGE_PARAM_REAL, "-", 0, 0, 1, true, NULL,
     "Implicit scheme: the weight of the walls' inhomogeneous Neumann condition on the correction phi where a "
     "wall's ghost node lies inside the fluid: 1 gives the wall phi_ghost - (rho0/dt) (v*_face - v_wall).(r_ghost - "
     "r_wall), v*_face the normal velocity at the wall's face (the ghost's, less half its distance times its normal "
     "strain), and the normal velocity continued linearly through the face in the divergence, so the projection "
     "itself stops flow into the wall and leaves a flow that turns at it alone; 0 (the default) mirrors phi and puts "
     "the wall's normal velocity in the divergence, and the contact rule stops that flow. The Freydier cases set 1, "
     "where the front's first column against the upstream wall then keeps the rest spacing (at 0 it sits compressed, "
     "below the bulk's pressure; docs/method.md, \"Walls\").", OFF(implicit.wall_neumann_offset)},
    {"implicit", "surface_images", SURGE_PARAM_BOOL, "-", 1, 0, 1, true, NULL,
     "Implicit scheme: how the pressure meets p = 0 on the free surface. 1: each particle whose kernel reaches the "
     "surface sees mirror images of its neighbours across the surface particles' line (pressure negated, velocity "
     "kept), so its gradient, divergence and Laplacian are those of a full kernel; 0: the kernels under the surface "
     "are cut off, which lets a mode under the surface grow at steps shorter than the scheme's own (docs/method.md, "
     "\"Mirror images beyond the surface\").",
     OFF(implicit.surface_images)},
    {"implicit", "pressure_relaxation", SURGE_PARAM_REAL, "-", 0.5, 0, 1, true, NULL,
     "Implicit scheme, under a free surface: the last step's pressure is relaxed by one weighted Jacobi sweep of the "
     "pressure's Laplacian, p - beta (L p)/L_aa, before the step uses it. A linear (hydrostatic) field is kept; a "
     "field that alternates from particle to particle, which the projection's gradient does not see and the "
     "incremental step carries undamped, decays (0: none; docs/method.md, \"Relaxation of the last step's "
     "pressure\").",
     OFF(implicit.pressure_relaxation)},
    {"implicit", "disc_pressure_passes", SURGE_PARAM_INT, "-", 6, 1, 100, true, NULL,
     "Implicit scheme, with discs: passes of the viscous and pressure solves a step. Between passes the pressure "
     "takes p + phi - rho0 nu (div v* - div v_n+1) (Uzawa's iteration on the step's velocity-pressure "
     "system, the rotational update its preconditioner), so the pressure around a disc (its stresslet) is built "
     "within the step whatever dt nu / a^2; one pass builds about 1/(dt nu k^2) of it a step, k the disc's scale, "
     "and the loaded channel's viscosity then depends on the step (1: one pass; docs/method.md, \"Boulders in the "
     "implicit scheme\"). Without discs a step makes one pass.",
     OFF(implicit.disc_pressure_passes)},
    {"implicit", "disc_pressure_history", SURGE_PARAM_INT, "-", 4, 0, 16, true, NULL,
     "Implicit scheme, with discs: the earlier passes each pass's pressure is combined from (Anderson's acceleration "
     "of the Uzawa iteration, GMRES's on a linear map): the pressure that makes the last differences of the updates "
     "smallest in the least-squares sense (0: each pass takes its own update; docs/method.md, \"Boulders in the "
     "implicit scheme\").",
     OFF(implicit.disc_pressure_history)},
    {"implicit", "step_halvings", SURGE_PARAM_INT, "-", 4, 0, 20, true, NULL,
     "Implicit scheme: a step that ends with a fluid particle compressed past the density bound "
     "(health.max_density_deviation, read from the kernel sum at the positions the step ends at) or whose linear solve "
     "does not converge is rolled back and taken again at half its length, at most this many times (down to 1/16 of the "
     "step at 4); the next step starts from the full length again. 0: such a step stops the run. A run that never "
     "meets either takes the same steps whatever this is (docs/method.md, \"Health monitor\").",
     OFF(implicit.step_halvings)},

    {"boulders", "placement", SURGE_PARAM_ENUM, "-", SURGE_BOULDERS_NONE, 0, 4, false, "none|list|random|graded|file",
     "Rigid discs (boulders): none, the list in list_m, random non-overlapping discs up to solid_fraction, graded "
     "(sizes from a grading curve, centres log-normally behind the front; docs/boulders.md), or the CSV in file.",
     OFF(boulders.placement)},
    {"boulders", "list_m", SURGE_PARAM_TEXT, "m, m s^-1, rad s^-1", 0, 0, 0, false, NULL,
     "Discs for placement = list: 'x y r' or 'x y r vx vy omega' per disc, discs separated by commas.",
     OFF(boulders.list_m)},
    {"boulders", "solid_fraction", SURGE_PARAM_REAL, "-", 0.1, 0, 0.8, false, NULL,
     "Random and graded placement: total disc area over the region's (graded: the fluid block's) area (phi).", OFF(boulders.solid_fraction)},
    {"boulders", "radius_m", SURGE_PARAM_REAL, "m", 0.01, 1e-6, 1e3, false, NULL,
     "Random placement: disc radius (the smallest one when radius_max_m is larger).", OFF(boulders.radius_m)},
    {"boulders", "radius_max_m", SURGE_PARAM_REAL, "m", 0, 0, 1e3, false, NULL,
     "Random placement: radii uniform in [radius_m, radius_max_m]; at or below radius_m all discs are equal.",
     OFF(boulders.radius_max_m)},
    {"boulders", "region_x0_m", SURGE_PARAM_REAL, "m", 0, -1e4, 1e4, false, NULL,
     "Random placement: region of the disc centres, lower x (x0 = x1: the fluid block's extent).",
     OFF(boulders.region_x0_m)},
    {"boulders", "region_x1_m", SURGE_PARAM_REAL, "m", 0, -1e4, 1e4, false, NULL,
     "Random placement: region, upper x.", OFF(boulders.region_x1_m)},
    {"boulders", "region_y0_m", SURGE_PARAM_REAL, "m", 0, -1e4, 1e4, false, NULL,
     "Random placement: region, lower y (y0 = y1: from the bed to the fluid depth).", OFF(boulders.region_y0_m)},
    {"boulders", "region_y1_m", SURGE_PARAM_REAL, "m", 0, -1e4, 1e4, false, NULL,
     "Random placement: region, upper y.", OFF(boulders.region_y1_m)},
    {"boulders", "min_gap_m", SURGE_PARAM_REAL, "m", 0, 0, 1e3, false, NULL,
     "Random and graded placement: smallest gap between two discs and between a disc and a wall (0: one dp).",
     OFF(boulders.min_gap_m)},
    {"boulders", "seed", SURGE_PARAM_INT, "-", 1, 0, 2147483647, false, NULL,
     "Random and graded placement: seed of the random sequence (same seed, same discs).", OFF(boulders.seed)},
    {"boulders", "density_ratio", SURGE_PARAM_REAL, "-", 1, 0.01, 1e4, false, NULL,
     "Disc density over the fluid's rho0 (1: neutrally buoyant; a heavy disc, up to 1e4, keeps its motion while "
     "the fluid's resistance to it is measured from its slow decay, docs/boulders.md).", OFF(boulders.density_ratio)},
    {"boulders", "grading_file", SURGE_PARAM_TEXT, "-", 0, 0, 0, false, NULL,
     "Graded placement: grading curve, a CSV of diameter_m,fraction_passing rows (empty: the built-in stand-in "
     "curve of docs/boulders.md; a relative path is from the working folder).", OFF(boulders.grading_file)},
    {"boulders", "count", SURGE_PARAM_INT, "-", 0, 0, 20000, false, NULL,
     "Graded placement: number of discs (0: discs until solid_fraction of the fluid block's area).",
     OFF(boulders.count)},
    {"boulders", "diameter_min_m", SURGE_PARAM_REAL, "m", 0.2, 0, 1e3, false, NULL,
     "Graded placement: smallest diameter drawn (the paper's truncation, 20 cm).", OFF(boulders.diameter_min_m)},
    {"boulders", "diameter_max_m", SURGE_PARAM_REAL, "m", 0, 0, 1e3, false, NULL,
     "Graded placement: largest diameter drawn (0: the fluid depth less two gaps, the paper's h_max).",
     OFF(boulders.diameter_max_m)},
    {"boulders", "front_median_m", SURGE_PARAM_REAL, "m", 3, 1e-6, 1e4, false, NULL,
     "Graded placement: median distance of a disc centre behind the fluid block's front (log-normal, truncated "
     "to the block).", OFF(boulders.front_median_m)},
    {"boulders", "front_sigma", SURGE_PARAM_REAL, "-", 0.8, 0.01, 10, false, NULL,
     "Graded placement: standard deviation of the log of that distance.", OFF(boulders.front_sigma)},
    {"boulders", "file", SURGE_PARAM_TEXT, "-", 0, 0, 0, false, NULL,
     "File placement: CSV with the header x_m,y_m,r_m (and optionally vx_mps,vy_mps,omega_radps), one disc per "
     "row, as a run writes to boulders.csv (a relative path is from the working folder).", OFF(boulders.file)},
    {"boulders", "pack_fluid", SURGE_PARAM_BOOL, "-", 0, 0, 1, false, NULL,
     "Keep every fluid lattice site outside a disc and pack the fluid around the discs before the first step, so "
     "that it fills the room the discs leave at its rest spacing. Off: the sites within a quarter spacing of a "
     "disc's surface are left out, and the fluid is 0.5 phi / ((r/dp) (1 - phi)) of its room short. Packed, the "
     "implicit scheme's rest-density correction counts a deficit next to a disc too. Off by default: the explicit "
     "scheme runs the packed loaded channel at r/dp 4, at r/dp 3 (the shipped channel) only with numerics.cfl = "
     "0.18, and a packing is not mirror-symmetric (a disc settling down the middle of a tank drifts sideways at up "
     "to 5 % of its fall speed; docs/boulders.md, \"Placement\").", OFF(boulders.pack_fluid)},

    {"contacts", "friction", SURGE_PARAM_REAL, "-", 0.5, 0, 10, true, NULL,
     "Coulomb friction coefficient mu between discs and between discs and walls.", OFF(contacts.friction)},
    {"contacts", "restitution", SURGE_PARAM_REAL, "-", 0, 0, 1, true, NULL,
     "Normal restitution coefficient e (0: no bounce).", OFF(contacts.restitution)},
    {"contacts", "restitution_min_mps", SURGE_PARAM_REAL, "m s^-1", 0.01, 0, 1e3, true, NULL,
     "Approach speeds below this do not bounce (resting contacts stay at rest).",
     OFF(contacts.restitution_min_mps)},
    {"contacts", "substeps", SURGE_PARAM_INT, "-", 4, 1, 1000, true, NULL,
     "Contact sub-steps inside one SPH step.", OFF(contacts.substeps)},
    {"contacts", "iterations", SURGE_PARAM_INT, "-", 30, 1, 10000, true, NULL,
     "Projected Gauss-Seidel sweeps over all contacts per sub-step.", OFF(contacts.iterations)},
    {"contacts", "erp", SURGE_PARAM_REAL, "-", 0.2, 0, 1, true, NULL,
     "Fraction of an overlap removed per sub-step (error reduction).", OFF(contacts.erp)},
    {"contacts", "margin_dp", SURGE_PARAM_REAL, "dp", 0, 0, 2, false, NULL,
     "Discs touch each other and the walls this far apart, in dp (0: at their surfaces): a gap narrower than the "
     "particle spacing holds fluid particles the SPH cannot resolve (docs/validation/debris_surge.md).",
     OFF(contacts.margin_dp)},
    {"contacts", "solid_pressure", SURGE_PARAM_BOOL, "-", 1, 0, 1, true, NULL,
     "A disc's particles feel the pressure of the particles of walls and of other discs within the kernel's reach as "
     "they feel the fluid's: the pressure across gaps narrower than the kernel, which the fluid alone leaves out "
     "(docs/boulders.md).", OFF(contacts.solid_pressure)},
    {"contacts", "lubrication", SURGE_PARAM_BOOL, "-", 1, 0, 1, true, NULL,
     "Add the lubrication force of gaps between discs, and between a disc and a wall, that the SPH does not "
     "resolve: the 2D (cylinder) squeeze film and tangential film less what the scheme resolves of them "
     "(lubrication_resolved, lubrication_tangential; docs/boulders.md).", OFF(contacts.lubrication)},
    {"contacts", "lubrication_cutoff_dp", SURGE_PARAM_REAL, "dp", 1, 0.1, 10, true, NULL,
     "The cut-off model's gap (surface to surface, in dp) below which its squeeze film (lubrication_resolved = cutoff) "
     "and the sliding film (lubrication_tangential = sliding) act.", OFF(contacts.lubrication_cutoff_dp)},
    {"contacts", "lubrication_min_gap_dp", SURGE_PARAM_REAL, "dp", 0.01, 1e-4, 1, true, NULL,
     "The lubrication force is taken at this gap (dp) where the gap is narrower (surface roughness; it keeps the "
     "force finite at contact).", OFF(contacts.lubrication_min_gap_dp)},
    {"contacts", "lubrication_resolved", SURGE_PARAM_ENUM, "-", SURGE_LUBRICATION_MEASURED, 0, 1, true, "cutoff|measured",
     "What the SPH resolves of a squeeze film, which the lubrication force leaves out: cutoff, the film's force at "
     "lubrication_cutoff_dp below it; measured, the share of the exact resistance the scheme in use resolves at "
     "each gap, measured for each scheme against the kernel's h (docs/boulders.md).", OFF(contacts.lubrication_resolved)},
    {"contacts", "lubrication_tangential", SURGE_PARAM_ENUM, "-", SURGE_TANGENTIAL_REYNOLDS, 0, 1, true,
     "sliding|reynolds",
     "The film's resistance to tangential motion: sliding, torques from the surfaces' relative sliding speed (its part "
     "below lubrication_cutoff_dp); reynolds, from Reynolds' equation with the gap's shape moving with the discs, a "
     "force against a disc's translation along the gap and a torque against its spin, less the share the scheme "
     "resolves (needs lubrication_resolved = measured; docs/boulders.md).", OFF(contacts.lubrication_tangential)},
    {"contacts", "lubrication_share", SURGE_PARAM_ENUM, "-", SURGE_SHARE_SCHEME, 0, 2, true, "scheme|explicit|implicit",
     "Whose share of a film the measured films leave out as resolved: scheme, the share the scheme in use resolves "
     "of a lone disc's film (each scheme measured its own); explicit or implicit, that scheme's share whatever the "
     "scheme, to run both schemes with one share (needs lubrication_resolved = measured; in a crowd of discs the two "
     "schemes resolve alike, docs/validation/poiseuille_loaded.md, \"Both schemes with the measured films\").",
     OFF(contacts.lubrication_share)},

    {"shifting", "form", SURGE_PARAM_ENUM, "-", SURGE_SHIFT_LIND, 0, 2, true, "none|velocity|lind",
     "Particle shifting: none, velocity-proportional (Skillen) or Lind (no shift in the free-surface layer).",
     OFF(shifting.form)},
    {"shifting", "velocity_coefficient", SURGE_PARAM_REAL, "-", 2.0, 0, 100, true, NULL,
     "A in dr = -A h |u| dt grad C (velocity form).", OFF(shifting.velocity_coefficient)},
    {"shifting", "lind_coefficient", SURGE_PARAM_REAL, "-", 0.5, 0, 100, true, NULL,
     "A_L in dr = -(A_L/2) h c0 dt grad C (Lind form).", OFF(shifting.lind_coefficient)},
    {"shifting", "surface_threshold", SURGE_PARAM_REAL, "-", 1.5, 0, 2, true, NULL,
     "Free-surface detection: a particle with div r below this is on the surface (2 in the 2D bulk).",
     OFF(shifting.surface_threshold)},
    {"shifting", "max_shift_dp", SURGE_PARAM_REAL, "dp", 0.1, 0, 1, true, NULL,
     "Largest shift of a particle in one step, in units of dp.", OFF(shifting.max_shift_dp)},
    {"shifting", "surface_anti_clumping", SURGE_PARAM_REAL, "-", 0, 0, 10, true, NULL,
     "Explicit scheme, lind: w of the shift that parts particles crowded together in the free-surface layer, where "
     "Lind's shift is off: dr = -min(A_L/2, 2 w (k - 1)) h c0 dt grad C with k the kernel sum over the rest "
     "lattice's, zero where the spacing is at rest or wider; in the top two rows the truncated kernel sum stays below "
     "the lattice's and nothing acts (0: off; it spreads a crowded front nose, docs/method.md).",
     OFF(shifting.surface_anti_clumping)},
    {"shifting", "consistent_density", SURGE_PARAM_BOOL, "-", 0, 0, 1, true, NULL,
     "The density also takes on the divergence of each shift, so that densities follow the particles' spacing "
     "(mass moves with the particles; opt-in, docs/method.md).", OFF(shifting.consistent_density)},

    {"time", "end_s", SURGE_PARAM_REAL, "s", 6, 0, 1e7, true, NULL, "Simulated time at which the run ends.",
     OFF(time.end_s)},

    {"output", "snapshot_interval_s", SURGE_PARAM_REAL, "s", 0.1, 0, 1e7, true, NULL,
     "Simulated time between VTK snapshots (0: the initial and final snapshots only).",
     OFF(output.snapshot_interval_s)},
    {"output", "diagnostics_interval_s", SURGE_PARAM_REAL, "s", 0.01, 0, 1e7, true, NULL,
     "Simulated time between rows of diagnostics.csv (0: every step).", OFF(output.diagnostics_interval_s)},
    {"output", "checkpoint_interval_s", SURGE_PARAM_REAL, "s", 0, 0, 1e7, true, NULL,
     "Simulated time between checkpoints (0: only the final one).", OFF(output.checkpoint_interval_s)},
    {"output", "flow_interval_s", SURGE_PARAM_REAL, "s", 0, 0, 1e7, false, NULL,
     "Simulated time between rows of flow.csv, a belt surge's flow height, mean velocity, Froude number and "
     "equivalent viscosity (GMD 2025 eq. 21; docs/validation/debris_surge.md) (0: no flow.csv).", OFF(output.flow_interval_s)},
    {"output", "flow_ignore_m", SURGE_PARAM_REAL, "m", 5, 0, 1e4, false, NULL,
     "flow.csv leaves out the fluid this close downstream of the upstream wall (the paper's 5 m).",
     OFF(output.flow_ignore_m)},
    {"output", "flow_column_m", SURGE_PARAM_REAL, "m", 0.5, 1e-6, 1e4, false, NULL,
     "flow.csv: width of the columns whose tops give the flow height (at least dp/2).", OFF(output.flow_column_m)},
    {"output", "progress_interval_s", SURGE_PARAM_REAL, "s (wall)", 2, 0, 1e5, true, NULL,
     "Wall-clock seconds between progress lines on stderr (0: silent).", OFF(output.progress_interval_s)},

    {"render", "frame_interval_s", SURGE_PARAM_REAL, "s", 0.04, 1e-9, 1e7, true, NULL,
     "Simulated time between rendered frames (--frames, --movie); surge render draws every snapshot unless this "
     "is set on its command line, then one snapshot per interval.", OFF(render.frame_interval_s)},
    {"render", "width_px", SURGE_PARAM_INT, "px", 1280, 16, 8192, false, NULL, "Frame width.", OFF(render.width_px)},
    {"render", "height_px", SURGE_PARAM_INT, "px", 0, 0, 8192, false, NULL,
     "Frame height; 0: fitted to the flow (from the bed to a little above the initial fluid block, over the view's "
     "length: a periodic domain's whole view the initial block's with a margin), between a fifth of the width and the width.",
     OFF(render.height_px)},
    {"render", "style", SURGE_PARAM_ENUM, "-", SURGE_STYLE_FIELD, 0, 1, true, "field|particles",
     "How the fluid is drawn: a continuous field interpolated from the particles with a kernel, its free surface "
     "where the kernel sum falls to half the bulk's; or each particle as a disc of diameter dp.",
     OFF(render.style)},
    {"render", "field", SURGE_PARAM_ENUM, "-", SURGE_FIELD_SPEED, 0, 4, true, "speed|vx_rel|vx|pressure|density",
     "Field that colours the fluid: speed, x velocity relative to the belt, x velocity, pressure, density.",
     OFF(render.field)},
    {"render", "colormap", SURGE_PARAM_ENUM, "-", SURGE_COLORMAP_VIRIDIS, 0, 1, true, "viridis|cividis",
     "Perceptually uniform colour map.", OFF(render.colormap)},
    {"render", "color_min", SURGE_PARAM_REAL, "field unit", 0, -BIG, BIG, true, NULL,
     "Low end of the colour range (equal to color_max: automatic, rounded to the tick step: the range over all frames in surge render; while a run renders, one that starts from the first frame's and only grows).", OFF(render.color_min)},
    {"render", "color_max", SURGE_PARAM_REAL, "field unit", 0, -BIG, BIG, true, NULL,
     "High end of the colour range.", OFF(render.color_max)},
    {"render", "view", SURGE_PARAM_ENUM, "-", SURGE_VIEW_WHOLE, 0, 2, true, "whole|follow|fixed",
     "What the frame shows: everything (on a periodic domain, the part of the period the fluid's body holds, with a "
     "margin), a window following the surge front, or a fixed window.",
     OFF(render.view)},
    {"render", "view_x0_m", SURGE_PARAM_REAL, "m", 0, -1e4, 1e4, true, NULL, "Left end of the fixed view.",
     OFF(render.view_x0_m)},
    {"render", "view_x1_m", SURGE_PARAM_REAL, "m", 0.1, -1e4, 1e4, true, NULL, "Right end of the fixed view.",
     OFF(render.view_x1_m)},
    {"render", "view_width_m", SURGE_PARAM_REAL, "m", 0.2, 1e-6, 1e4, true, NULL,
     "Width of the follow view; the surge front (where the fluid's depth, counted in columns, last exceeds a fifth "
     "of its largest, going downstream from the deepest column) stays at 3/4 of it.",
     OFF(render.view_width_m)},
    {"render", "true_slope", SURGE_PARAM_BOOL, "-", 0, 0, 1, true, NULL,
     "Draw the bed at its slope with gravity pointing down the image (false: bed along the image's x axis, as "
     "the paper's Fig. 7).", OFF(render.true_slope)},
    {"render", "movie_fps", SURGE_PARAM_REAL, "1/s", 25, 1, 240, false, NULL, "Frames per second of the movie.",
     OFF(render.movie_fps)},

    {"health", "max_density_deviation", SURGE_PARAM_REAL, "-", 0.1, 1e-4, 10, true, NULL,
     "A fluid particle with |rho/rho0 - 1| above this fails the run.", OFF(health.max_density_deviation)},
    {"health", "min_dt_ratio", SURGE_PARAM_REAL, "-", 1e-3, 0, 1, true, NULL,
     "A time step below this fraction of the first step's fails the run (dt collapse).", OFF(health.min_dt_ratio)},
};

enum { REGISTRY_COUNT = sizeof registry / sizeof registry[0] };

static void fail(char *err, size_t err_len, const char *fmt, ...)
{
    if (!err || err_len == 0)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, err_len, fmt, ap);
    va_end(ap);
}

int surge_param_count(void) { return REGISTRY_COUNT; }

const surge_param_info *surge_param_at(int index)
{
    return (index >= 0 && index < REGISTRY_COUNT) ? &registry[index] : NULL;
}

const surge_param_info *surge_param_find(const char *name)
{
    const char *dot = strchr(name, '.');
    if (!dot)
        return NULL;
    size_t section_len = (size_t)(dot - name);
    for (int i = 0; i < REGISTRY_COUNT; i++) {
        const surge_param_info *r = &registry[i];
        if (strlen(r->section) == section_len && strncmp(r->section, name, section_len) == 0 &&
            strcmp(r->key, dot + 1) == 0)
            return r;
    }
    return NULL;
}

static void *field(surge_params *p, const surge_param_info *info) { return (char *)p + info->offset; }
static const void *cfield(const surge_params *p, const surge_param_info *info)
{
    return (const char *)p + info->offset;
}

surge_params surge_default_params(void)
{
    surge_params p;
    memset(&p, 0, sizeof p);
    for (int i = 0; i < REGISTRY_COUNT; i++) {
        const surge_param_info *r = &registry[i];
        switch (r->type) {
        case SURGE_PARAM_REAL: *(double *)field(&p, r) = r->default_value; break;
        case SURGE_PARAM_INT:
        case SURGE_PARAM_ENUM: *(int *)field(&p, r) = (int)r->default_value; break;
        case SURGE_PARAM_BOOL: *(bool *)field(&p, r) = r->default_value != 0; break;
        case SURGE_PARAM_TEXT: break; /* empty */
        }
    }
    return p;
}

double surge_param_get_number(const surge_params *p, const surge_param_info *info)
{
    switch (info->type) {
    case SURGE_PARAM_REAL: return *(const double *)cfield(p, info);
    case SURGE_PARAM_INT:
    case SURGE_PARAM_ENUM: return *(const int *)cfield(p, info);
    case SURGE_PARAM_BOOL: return *(const bool *)cfield(p, info) ? 1 : 0;
    case SURGE_PARAM_TEXT: return 0;
    }
    return 0;
}

bool surge_params_live_differ(const surge_params *a, const surge_params *b)
{
    for (int i = 0; i < REGISTRY_COUNT; i++)
        if (registry[i].live && surge_param_get_number(a, &registry[i]) != surge_param_get_number(b, &registry[i]))
            return true;
    return false;
}

/* The n-th name of "a|b|c" into buf; returns 0 when n is out of range. */
static int enum_name(const char *names, int n, char *buf, size_t len)
{
    const char *s = names;
    for (int i = 0; i < n; i++) {
        s = strchr(s, '|');
        if (!s)
            return 0;
        s++;
    }
    size_t l = strcspn(s, "|");
    if (l + 1 > len)
        l = len - 1;
    memcpy(buf, s, l);
    buf[l] = '\0';
    return 1;
}

/* The shortest %g form that reads back as the same double (0.6, not 0.59999999999999998), without an exponent
 * where plain digits serve (10, not 1e+01). */
static void format_real(double value, char *buf, size_t len)
{
    const int plain = value == 0 || (fabs(value) >= 1e-4 && fabs(value) < 1e15);
    for (int digits = 1; digits <= 17; digits++) {
        snprintf(buf, len, "%.*g", digits, value);
        if (strtod(buf, NULL) == value && (!plain || !strchr(buf, 'e')))
            return;
    }
}

void surge_param_format(const surge_params *p, const surge_param_info *info, char *buf, size_t len)
{
    switch (info->type) {
    case SURGE_PARAM_REAL: format_real(*(const double *)cfield(p, info), buf, len); break;
    case SURGE_PARAM_INT: snprintf(buf, len, "%d", *(const int *)cfield(p, info)); break;
    case SURGE_PARAM_BOOL: snprintf(buf, len, "%s", *(const bool *)cfield(p, info) ? "true" : "false"); break;
    case SURGE_PARAM_ENUM:
        if (!enum_name(info->enum_names, *(const int *)cfield(p, info), buf, len))
            snprintf(buf, len, "?");
        break;
    case SURGE_PARAM_TEXT: snprintf(buf, len, "%s", (const char *)cfield(p, info)); break;
    }
}

static void describe_allowed(const surge_param_info *info, char *buf, size_t len)
{
    switch (info->type) {
    case SURGE_PARAM_REAL: snprintf(buf, len, "a number in [%g, %g] %s", info->min_value, info->max_value, info->unit); break;
    case SURGE_PARAM_INT: snprintf(buf, len, "an integer in [%d, %d]", (int)info->min_value, (int)info->max_value); break;
    case SURGE_PARAM_BOOL: snprintf(buf, len, "true or false"); break;
    case SURGE_PARAM_ENUM: snprintf(buf, len, "one of %s", info->enum_names); break;
    case SURGE_PARAM_TEXT: snprintf(buf, len, "text of at most %d characters", SURGE_TEXT_PARAM_BYTES - 1); break;
    }
}

int surge_param_set(surge_params *p, const surge_param_info *info, const char *value, char *err, size_t err_len)
{
    char allowed[160];
    describe_allowed(info, allowed, sizeof allowed);
    while (isspace((unsigned char)*value))
        value++;
    if (info->type == SURGE_PARAM_TEXT) {
        const size_t len = strlen(value);
        if (len >= SURGE_TEXT_PARAM_BYTES) {
            fail(err, err_len, "%s.%s: %zu characters; expected %s", info->section, info->key, len, allowed);
            return -1;
        }
        memcpy(field(p, info), value, len + 1);
        return 0;
    }
    if (*value == '\0') {
        fail(err, err_len, "%s.%s: empty value; expected %s", info->section, info->key, allowed);
        return -1;
    }
    switch (info->type) {
    case SURGE_PARAM_REAL:
    case SURGE_PARAM_INT: {
        char *end;
        errno = 0;
        double v = strtod(value, &end);
        while (isspace((unsigned char)*end))
            end++;
        if (end == value || *end != '\0' || errno == ERANGE || !isfinite(v)) {
            fail(err, err_len, "%s.%s: '%s' is not a number; expected %s", info->section, info->key, value, allowed);
            return -1;
        }
        if (info->type == SURGE_PARAM_INT && v != floor(v)) {
            fail(err, err_len, "%s.%s: '%s' is not an integer; expected %s", info->section, info->key, value,
                 allowed);
            return -1;
        }
        if (v < info->min_value || v > info->max_value) {
            fail(err, err_len, "%s.%s: %s is out of range; expected %s", info->section, info->key, value, allowed);
            return -1;
        }
        if (info->type == SURGE_PARAM_REAL)
            *(double *)field(p, info) = v;
        else
            *(int *)field(p, info) = (int)v;
        return 0;
    }
    case SURGE_PARAM_BOOL:
        if (!strcmp(value, "true") || !strcmp(value, "1") || !strcmp(value, "yes") || !strcmp(value, "on")) {
            *(bool *)field(p, info) = true;
            return 0;
        }
        if (!strcmp(value, "false") || !strcmp(value, "0") || !strcmp(value, "no") || !strcmp(value, "off")) {
            *(bool *)field(p, info) = false;
            return 0;
        }
        fail(err, err_len, "%s.%s: '%s' is not a boolean; expected %s", info->section, info->key, value, allowed);
        return -1;
    case SURGE_PARAM_ENUM: {
        char name[64];
        for (int i = 0; enum_name(info->enum_names, i, name, sizeof name); i++) {
            if (!strcmp(name, value)) {
                *(int *)field(p, info) = i;
                return 0;
            }
        }
        fail(err, err_len, "%s.%s: '%s' is not allowed; expected %s", info->section, info->key, value, allowed);
        return -1;
    }
    case SURGE_PARAM_TEXT: break; /* handled above */
    }
    return -1;
}

static char *trim(char *s)
{
    while (isspace((unsigned char)*s))
        s++;
    char *e = s + strlen(s);
    while (e > s && isspace((unsigned char)e[-1]))
        *--e = '\0';
    return s;
}

/* A comment starts at '#' or ';' at the start of a line or after white space. One glued to a value ("0.01;")
 * stays in it, so the value is refused instead of silently cut short (`list_m = 0.1 0.05 0.01; 0.2 0.05 0.01`). */
static char *find_comment(char *line)
{
    for (char *c = line; *c; c++)
        if ((*c == '#' || *c == ';') && (c == line || *(c - 1) == ' ' || *(c - 1) == '\t'))
            return c;
    return NULL;
}

/* " (did you mean section.key?)" when name's last part is the key of a parameter in another section, else "". */
static void suggestion(const char *name, char *out, size_t len)
{
    const char *dot = strrchr(name, '.');
    const char *key = dot ? dot + 1 : name;
    out[0] = '\0';
    for (int i = 0; i < REGISTRY_COUNT; i++)
        if (!strcmp(registry[i].key, key)) {
            snprintf(out, len, " (did you mean %s.%s?)", registry[i].section, registry[i].key);
            return;
        }
}

/* Parameters that no longer exist, still accepted in files (and ignored) so that earlier runs' params.ini and
 * checkpoints load: the implicit scheme's discs' added-mass estimate and coupling limit, which the coupled solve
 * replaced (docs/method.md, "Boulders in the implicit scheme") */
static bool retired(const char *name)
{
    static const char *const names[] = {"implicit.added_mass", "implicit.disc_coupling"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(names[i], name))
            return true;
    return false;
}

int surge_params_load_text(surge_params *p, const char *text, const char *source, char *err, size_t err_len)
{
    char section[64] = "";
    int line_no = 0, assignments = 0;
    const char *cursor = text;
    while (*cursor) {
        line_no++;
        size_t len = strcspn(cursor, "\n");
        char line[1024];
        if (len >= sizeof line) {
            fail(err, err_len, "%s:%d: line longer than %zu characters", source, line_no, sizeof line - 1);
            return -1;
        }
        memcpy(line, cursor, len);
        line[len] = '\0';
        cursor += len + (cursor[len] == '\n');

        char *comment = find_comment(line);
        if (comment)
            *comment = '\0';
        char *s = trim(line);
        if (*s == '\0')
            continue;
        if (*s == '[') {
            char *close = strchr(s, ']');
            if (!close || *trim(close + 1) != '\0') {
                fail(err, err_len, "%s:%d: malformed section header '%s'; expected [section]", source, line_no, s);
                return -1;
            }
            *close = '\0';
            char *name = trim(s + 1);
            bool known = false;
            char sections[400] = "";
            for (int i = 0; i < REGISTRY_COUNT; i++) {
                known = known || !strcmp(registry[i].section, name);
                if (i == 0 || strcmp(registry[i].section, registry[i - 1].section))
                    snprintf(sections + strlen(sections), sizeof sections - strlen(sections), "%s%s",
                             i ? ", " : "", registry[i].section);
            }
            if (!known) {
                fail(err, err_len, "%s:%d: unknown section [%s]; sections are %s", source, line_no, name, sections);
                return -1;
            }
            snprintf(section, sizeof section, "%s", name);
            continue;
        }
        char *eq = strchr(s, '=');
        if (!eq) {
            fail(err, err_len, "%s:%d: expected 'key = value', got '%s'", source, line_no, s);
            return -1;
        }
        *eq = '\0';
        char *key = trim(s);
        char *value = trim(eq + 1);
        if (section[0] == '\0') {
            fail(err, err_len, "%s:%d: '%s' appears before any [section]", source, line_no, key);
            return -1;
        }
        char name[160];
        const int fits = snprintf(name, sizeof name, "%s.%s", section, key) < (int)sizeof name;
        const surge_param_info *info = fits ? surge_param_find(name) : NULL; /* never a truncated name's match */
        if (!info && fits && retired(name))
            continue;
        if (!info) {
            char hint[160];
            suggestion(key, hint, sizeof hint);
            fail(err, err_len, "%s:%d: unknown key '%s' in [%s]%s (see 'surge params')", source, line_no, key, section,
                 hint);
            return -1;
        }
        char msg[400];
        if (surge_param_set(p, info, value, msg, sizeof msg) != 0) {
            fail(err, err_len, "%s:%d: %s", source, line_no, msg);
            return -1;
        }
        assignments++;
    }
    if (assignments == 0) { /* would silently be the default scene */
        fail(err, err_len, "%s: no parameters set (an empty case file); 'surge run' without a CASE runs the default "
             "scene", source);
        return -1;
    }
    return 0;
}

int surge_params_load(surge_params *p, const char *path, char *err, size_t err_len)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fail(err, err_len, "%s: cannot open case file: %s", path, strerror(errno));
        return -1;
    }
    size_t cap = 4096, n = 0;
    char *text = malloc(cap);
    size_t got;
    while (text && (got = fread(text + n, 1, cap - n - 1, f)) > 0) {
        n += got;
        if (n + 1 == cap) {
            if (cap > (1u << 24)) {
                fclose(f);
                free(text);
                fail(err, err_len, "%s: case file larger than 16 MiB", path);
                return -1;
            }
            char *bigger = realloc(text, cap *= 2);
            if (!bigger)
                free(text);
            text = bigger;
        }
    }
    int read_error = ferror(f);
    fclose(f);
    if (!text || read_error) {
        free(text);
        fail(err, err_len, "%s: cannot read case file", path);
        return -1;
    }
    text[n] = '\0';
    if (memchr(text, '\0', n)) {
        free(text);
        fail(err, err_len, "%s: not a text file (contains NUL bytes)", path);
        return -1;
    }
    int rc = surge_params_load_text(p, text, path, err, err_len);
    free(text);
    return rc;
}

int surge_params_override(surge_params *p, const char *assignment, bool live_only, char *err, size_t err_len)
{
    const char *eq = strchr(assignment, '=');
    if (!eq) {
        fail(err, err_len, "-s %s: expected section.key=value", assignment);
        return -1;
    }
    char name[160];
    size_t len = (size_t)(eq - assignment);
    if (len >= sizeof name) { /* no parameter name is this long: never match a truncated one */
        fail(err, err_len, "-s %.60s...: unknown parameter (a name of %zu characters; see 'surge params')", assignment,
             len);
        return -1;
    }
    memcpy(name, assignment, len);
    name[len] = '\0';
    const surge_param_info *info = surge_param_find(trim(name));
    if (!info) {
        char hint[160];
        suggestion(trim(name), hint, sizeof hint);
        fail(err, err_len, "-s %s: unknown parameter '%s'%s (see 'surge params')", assignment, trim(name), hint);
        return -1;
    }
    if (live_only && !info->live) {
        fail(err, err_len, "-s %s: %s.%s is fixed once a run has started and cannot change on restart",
             assignment, info->section, info->key);
        return -1;
    }
    char msg[400];
    if (surge_param_set(p, info, eq + 1, msg, sizeof msg) != 0) {
        fail(err, err_len, "-s: %s", msg);
        return -1;
    }
    return 0;
}

int surge_params_wall_layers(const surge_params *p)
{
    const double support = 2.0 * p->numerics.ch * sqrt(2.0) * p->numerics.dp_m;
    const int needed = (int)ceil(support / p->numerics.dp_m - 1e-9);
    return p->walls.layers > 0 ? p->walls.layers : needed;
}

double surge_implicit_dt_s(const surge_params *p, double h_m, double g_mps2, double u_max_mps)
{
    double dt = INFINITY;
    if (g_mps2 > 0)
        dt = p->implicit.force_cfl * sqrt(h_m / g_mps2);
    if (u_max_mps > 0)
        dt = fmin(dt, p->implicit.cfl * h_m / u_max_mps);
    return dt;
}

bool surge_implicit_uses_amg(const surge_params *p, int fluid_count, bool viscous)
{
    return p->implicit.preconditioner == SURGE_PRECONDITIONER_AMG ||
           (p->implicit.preconditioner == SURGE_PRECONDITIONER_AUTO &&
            fluid_count >= (viscous ? SURGE_AMG_MIN_FLUID_PARTICLES_VISCOUS : SURGE_AMG_MIN_FLUID_PARTICLES));
}

/* The output and rendering settings that depend on each other */
static int validate_outputs(const surge_params *p, char *err, size_t err_len)
{
    if (p->output.flow_interval_s > 0 && p->output.flow_column_m < 0.5 * p->numerics.dp_m) {
        fail(err, err_len, "output.flow_column_m (%g m) must be at least half of numerics.dp_m (%g m): a column "
             "narrower holds no particle column", p->output.flow_column_m, 0.5 * p->numerics.dp_m);
        return -1;
    }
    if (p->render.view_x1_m <= p->render.view_x0_m) {
        fail(err, err_len, "render.view_x1_m (%g) must be greater than render.view_x0_m (%g)", p->render.view_x1_m,
             p->render.view_x0_m);
        return -1;
    }
    if (p->render.color_max < p->render.color_min) {
        fail(err, err_len, "render.color_max (%g) must not be below render.color_min (%g)", p->render.color_max,
             p->render.color_min);
        return -1;
    }
    return 0;
}

/* The fluid block inside the domain, and a periodic domain that holds whole particle spacings */
static int validate_fluid(const surge_params *p, char *err, size_t err_len)
{
    const double dp = p->numerics.dp_m, L = p->domain.length_m, H = p->domain.height_m;
    const double support = 2.0 * p->numerics.ch * sqrt(2.0) * dp;
    if (p->fluid.x1_m <= p->fluid.x0_m) {
        fail(err, err_len, "fluid.x1_m (%g) must be greater than fluid.x0_m (%g)", p->fluid.x1_m, p->fluid.x0_m);
        return -1;
    }
    if (p->fluid.x0_m < 0 || p->fluid.x1_m > L + 1e-12) {
        fail(err, err_len, "the fluid block [%g, %g] m must lie inside the domain [0, %g] m (domain.length_m)",
             p->fluid.x0_m, p->fluid.x1_m, L);
        return -1;
    }
    if (p->fluid.depth_m > H + 1e-12) {
        fail(err, err_len, "fluid.depth_m (%g) exceeds domain.height_m (%g)", p->fluid.depth_m, H);
        return -1;
    }
    if ((p->fluid.x1_m - p->fluid.x0_m) < dp || p->fluid.depth_m < dp) {
        fail(err, err_len, "the fluid block (%g x %g m) is smaller than one particle (numerics.dp_m = %g)",
             p->fluid.x1_m - p->fluid.x0_m, p->fluid.depth_m, dp);
        return -1;
    }
    if (p->domain.periodic_x && L < 3.0 * support) {
        fail(err, err_len, "a periodic domain must be at least 3 kernel supports long: domain.length_m = %g < %g m",
             L, 3.0 * support);
        return -1;
    }
    if (p->domain.periodic_x && fabs(remainder(L / dp, 1.0)) > 1e-6) {
        const double whole = fmax(1.0, round(L / dp));
        fail(err, err_len, "domain.length_m (%g) must be a whole number of particle spacings dp (%g) when periodic: "
             "it is %.6g of them; dp = %.6g m gives %.0f", L, dp, L / dp, L / whole, whole);
        return -1;
    }
    return 0;
}

/* The walls the domain allows and the kernel needs, and sizes refused before anything is allocated */
static int validate_walls_and_size(const surge_params *p, char *err, size_t err_len)
{
    const double dp = p->numerics.dp_m, L = p->domain.length_m;
    const double support = 2.0 * p->numerics.ch * sqrt(2.0) * dp;
    const int layers = surge_params_wall_layers(p);
    if (p->domain.periodic_x && (p->walls.left || p->walls.right)) {
        fail(err, err_len, "walls.left/walls.right need a non-periodic domain (domain.periodic_x = false)");
        return -1;
    }
    if (p->walls.upstream && !p->domain.periodic_x) {
        fail(err, err_len, "walls.upstream is for periodic domains; use walls.left in a closed box");
        return -1;
    }
    if (p->walls.disc_catcher && !p->walls.upstream) {
        fail(err, err_len, "walls.disc_catcher stops discs behind an upstream wall: it needs walls.upstream = true");
        return -1;
    }
    if (p->walls.upstream &&
        (p->walls.upstream_x_m - layers * dp < -1e-12 || p->walls.upstream_x_m > p->fluid.x0_m + 1e-12)) {
        fail(err, err_len, "walls.upstream_x_m (%g) must leave room for %d wall layers after x = 0 (at least %g m at "
             "dp = %g m) and lie upstream of the fluid (fluid.x0_m = %g)", p->walls.upstream_x_m, layers, layers * dp,
             dp, p->fluid.x0_m);
        return -1;
    }
    double layers_needed = ceil(support / dp - 1e-9);
    if ((p->walls.bottom || p->walls.top || p->walls.left || p->walls.right || p->walls.upstream) &&
        layers < layers_needed) {
        fail(err, err_len, "walls.layers = %d is thinner than the kernel support: %g layers needed at "
             "numerics.ch = %g", layers, layers_needed, p->numerics.ch);
        return -1;
    }
    if (!p->walls.bottom && !p->walls.top && !p->walls.left && !p->walls.right && !p->walls.upstream &&
        p->body.gravity_mps2 > 0) {
        fail(err, err_len, "the scene has gravity but no walls: enable walls.bottom");
        return -1;
    }
    double n_estimate = (p->fluid.x1_m - p->fluid.x0_m) * p->fluid.depth_m / (dp * dp);
    if (n_estimate > 5e7) {
        fail(err, err_len, "the fluid block would need about %.3g particles (more than 5e7): raise numerics.dp_m",
             n_estimate);
        return -1;
    }
    /* the walls and the cell grid, checked here so that a huge domain is refused before anything is allocated */
    const double margin_m = layers * dp + support;
    const double walls_estimate = ((p->walls.bottom + p->walls.top) * (L + 2 * margin_m) +
                                   (p->walls.left + p->walls.right) * p->domain.height_m +
                                   p->walls.upstream * p->walls.upstream_height_m) / dp * layers;
    if (walls_estimate > 5e7) {
        fail(err, err_len, "the walls would need about %.3g particles (more than 5e7): shorten domain.length_m or "
             "raise numerics.dp_m", walls_estimate);
        return -1;
    }
    const double cells_estimate = (L + 2 * margin_m) / support * ((p->domain.height_m + 2 * margin_m) / support);
    if (cells_estimate > 2e8) {
        fail(err, err_len, "the cell grid would have about %.3g cells (more than 2e8): the domain is too large for "
             "numerics.dp_m", cells_estimate);
        return -1;
    }
    return 0;
}

/* The lubrication force is the film's less its value at the cut-off: a floor at or above the cut-off would make it
 * pull approaching surfaces together */
static int validate_contacts(const surge_params *p, char *err, size_t err_len)
{
    if (p->contacts.lubrication_min_gap_dp >= p->contacts.lubrication_cutoff_dp) {
        fail(err, err_len, "contacts.lubrication_min_gap_dp (%g) must be below contacts.lubrication_cutoff_dp (%g)",
             p->contacts.lubrication_min_gap_dp, p->contacts.lubrication_cutoff_dp);
        return -1;
    }
    /* the quadratic no-slip fit sits inside the implicit scheme's viscous solve */
    if (p->walls.quadratic_no_slip && p->numerics.scheme != SURGE_SCHEME_IMPLICIT) {
        fail(err, err_len, "walls.quadratic_no_slip = true needs numerics.scheme = implicit: in the explicit scheme the "
                           "fit's extrapolation stiffens the viscous term beyond what its step limit sees "
                           "(docs/method.md, \"Quadratic no-slip walls\")");
        return -1;
    }
    /* the tangential film leaves out the share of the film the scheme resolves, which the measured model holds */
    if (p->contacts.lubrication_tangential == SURGE_TANGENTIAL_REYNOLDS &&
        p->contacts.lubrication_resolved != SURGE_LUBRICATION_MEASURED) {
        fail(err, err_len, "contacts.lubrication_tangential = reynolds needs contacts.lubrication_resolved = measured "
             "(here cutoff), whose share of the film it leaves out; with the cut-off model take "
             "contacts.lubrication_tangential = sliding");
        return -1;
    }
    /* the share table is the measured model's */
    if (p->contacts.lubrication_share != SURGE_SHARE_SCHEME &&
        p->contacts.lubrication_resolved != SURGE_LUBRICATION_MEASURED) {
        fail(err, err_len, "contacts.lubrication_share = %s needs contacts.lubrication_resolved = measured (here "
             "cutoff): the cut-off model takes no share", p->contacts.lubrication_share == SURGE_SHARE_EXPLICIT
                                                               ? "explicit" : "implicit");
        return -1;
    }
    return 0;
}

int surge_params_validate(const surge_params *p, char *err, size_t err_len)
{
    return validate_outputs(p, err, err_len) != 0 || validate_fluid(p, err, err_len) != 0 ||
                   validate_walls_and_size(p, err, err_len) != 0 || validate_contacts(p, err, err_len) != 0
               ? -1
               : 0;
}

void surge_params_write(const surge_params *p, FILE *out)
{
    const char *section = "";
    for (int i = 0; i < REGISTRY_COUNT; i++) {
        const surge_param_info *r = &registry[i];
        if (strcmp(section, r->section)) {
            fprintf(out, "%s[%s]\n", i ? "\n" : "", r->section);
            section = r->section;
        }
        char value[SURGE_TEXT_PARAM_BYTES];
        surge_param_format(p, r, value, sizeof value);
        fprintf(out, "%s = %s\n", r->key, value);
    }
}

void surge_params_write_reference(FILE *out)
{
    fprintf(out, "# Parameter reference\n\n"
                 "Generated by `surge params` from the parameter registry (sim/src/params.c); do not edit by hand.\n"
                 "Case files are INI-style: `[section]` then `key = value`; a `#` or `;` at the start of a line or after a\n"
                 "space starts a comment (one glued to a value is part of the value).\n"
                 "Any parameter can be overridden on the command line with `-s section.key=value`.\n"
                 "*Live* parameters may change while a run is going (control socket, restart overrides).\n");
    const char *section = "";
    for (int i = 0; i < REGISTRY_COUNT; i++) {
        const surge_param_info *r = &registry[i];
        if (strcmp(section, r->section)) {
            fprintf(out, "\n## [%s]\n\n| key | type | unit | default | allowed | live | meaning |\n"
                         "|---|---|---|---|---|---|---|\n", r->section);
            section = r->section;
        }
        surge_params defaults = surge_default_params();
        char def[64], allowed[160];
        surge_param_format(&defaults, r, def, sizeof def);
        static const char *type_names[] = {"real", "integer", "boolean", "choice", "text"};
        switch (r->type) {
        case SURGE_PARAM_REAL: snprintf(allowed, sizeof allowed, "[%g, %g]", r->min_value, r->max_value); break;
        case SURGE_PARAM_INT: snprintf(allowed, sizeof allowed, "[%d, %d]", (int)r->min_value, (int)r->max_value); break;
        case SURGE_PARAM_BOOL: snprintf(allowed, sizeof allowed, "true, false"); break;
        case SURGE_PARAM_ENUM: snprintf(allowed, sizeof allowed, "%s", r->enum_names); break;
        case SURGE_PARAM_TEXT: snprintf(allowed, sizeof allowed, "up to %d characters", SURGE_TEXT_PARAM_BYTES - 1); break;
        }
        for (char *c = allowed; *c; c++)
            if (*c == '|')
                *c = '/';
        fprintf(out, "| `%s` | %s | %s | %s | %s | %s | %s |\n", r->key, type_names[r->type], r->unit, def, allowed,
                r->live ? "yes" : "no", r->doc);
    }
}
