/* The contact solver alone (sim/src/boulders/contact_solver.c), no fluid: a disc at rest on a plane stays at rest; a
 * stack settles without drift or penetration; settled discs report the impulses their weights call for; a disc on an incline sticks or slides (rotation locked) and rolls
 * or slips (free) as Coulomb friction says; a disc set on a moving belt ends rolling at a third of its speed; a
 * bouncing disc keeps e^2 of its height; a head-on elastic collision swaps velocities across the periodic
 * boundary; discs blown up to non-finite or huge positions neither crash the broad phase nor disturb a resting
 * disc. Lubrication: the film's force (lubrication.h) against Reynolds' equation integrated on the exact circular gap;
 * a disc driven onto a wall, and two discs driven together, approach at the force over the film's damping at every
 * gap below the cut-off, and at free fall above it. The sliding film's shear (lubrication.h) against Reynolds'
 * equation for a face sliding past a plane, with the net force its pressure leaves; a disc spinning by a wall, and two
 * discs spinning the same way, slow at the rate its torques give and do not move.
 * The tangential film's resistance (contacts.lubrication_tangential = reynolds) against Reynolds' equation with the
 * gap's shape moving, for a disc by a plane and two discs, and its null motions.
 * The tangential film inside the contact solver's sub-steps (the explicit scheme's): a disc by a plane or a belt slows
 * as implicit Euler on its resistance gives; two discs keep their momentum and a common translation.
 * usage: test_contacts rest|stack|impulses|incline|belt|bounce|collision|blown_up|lubrication|lubrication_measured|
 *        lubrication_tangential|lubrication_reynolds_solver */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "boulders/contact_solver.h"
#include "boulders/lubrication.h"
#include "scheme/scheme.h"

enum { MAX_DISCS = 16 };

static int failures = 0;

static void expect_below(const char *what, double value, double bound)
{
    const int ok = value <= bound;
    printf("%-72s %12.4g  (bound %g)  %s\n", what, value, bound, ok ? "ok" : "FAILED");
    failures += !ok;
}

typedef struct world {
    double x[MAX_DISCS], y[MAX_DISCS], angle[MAX_DISCS], vx[MAX_DISCS], vy[MAX_DISCS], omega[MAX_DISCS];
    double radius[MAX_DISCS], inv_mass[MAX_DISCS], inv_inertia[MAX_DISCS];
    double ax[MAX_DISCS], ay[MAX_DISCS];
    contact_discs discs;
    contact_wall walls[4];
    int wall_count;
    contact_settings settings;
    contact_solver *solver;
    double max_overlap_m;
} world;

static void world_init(world *w, double gx, double gy)
{
    memset(w, 0, sizeof *w);
    w->discs = (contact_discs){0, w->x, w->y, w->angle, w->vx, w->vy, w->omega, w->radius, w->inv_mass,
                               w->inv_inertia};
    w->settings = (contact_settings){.friction = 0.5, .restitution = 0, .restitution_min_mps = 0.01, .substeps = 4,
                                     .iterations = 30, .erp = 0.2, .period_m = 0};
    for (int i = 0; i < MAX_DISCS; i++)
        w->ax[i] = gx, w->ay[i] = gy;
    w->solver = contact_solver_create();
}

/* A disc of density 2000 kg/m3 (per metre of width); rotation locked when lock_rotation. */
static int add_disc(world *w, double x, double y, double r, int lock_rotation)
{
    const int i = w->discs.count++;
    const double mass = 2000 * 3.14159265358979323846 * r * r;
    w->x[i] = x, w->y[i] = y, w->radius[i] = r;
    w->inv_mass[i] = 1 / mass;
    w->inv_inertia[i] = lock_rotation ? 0 : 1 / (0.5 * mass * r * r);
    return i;
}

static void add_plane(world *w, double nx, double ny, double offset)
{
    w->walls[w->wall_count++] = (contact_wall){.shape = CONTACT_PLANE, .nx = nx, .ny = ny, .offset = offset};
}

static void run(world *w, double dt, int steps)
{
    for (int s = 0; s < steps; s++) {
        if (contact_solver_advance(w->solver, &w->discs, w->walls, w->wall_count, &w->settings, dt, w->ax, w->ay,
                                   NULL) != 0) {
            fprintf(stderr, "out of memory\n");
            exit(2);
        }
        w->max_overlap_m = fmax(w->max_overlap_m, contact_solver_stats(w->solver).max_overlap_m);
    }
}

static int test_rest(void)
{
    world w;
    world_init(&w, 0, -9.81);
    add_plane(&w, 0, 1, 0);
    add_disc(&w, 0.3, 0.05, 0.05, 0);
    run(&w, 1e-3, 2000);
    expect_below("rest: |y - r| after 2 s on the plane (m)", fabs(w.y[0] - 0.05), 1e-9);
    expect_below("rest: |v| after 2 s (m/s)", hypot(w.vx[0], w.vy[0]), 1e-9);
    expect_below("rest: |x - x0| (m)", fabs(w.x[0] - 0.3), 1e-12);
    contact_solver_destroy(w.solver);
    return failures;
}

/* The impulses the solver reports over an advance (contact_stats), once settled: two discs stacked on a plane (rotation
 * locked) carry m g and 2 m g; a block held by friction on an incline m g sin and m g cos, on the incline's plane and
 * not on a second plane it does not touch */
static int test_impulses(void)
{
    const double g = 9.81, r = 0.05, dt = 1e-3, mass = 2000 * 3.14159265358979323846 * r * r, theta = atan(0.4);
    world w;
    world_init(&w, 0, -g);
    add_plane(&w, 0, 1, 0);
    add_disc(&w, 0.3, r, r, 1);
    add_disc(&w, 0.3, 3 * r + 0.001, r, 1);
    run(&w, dt, 1000);
    contact_stats stats = contact_solver_stats(w.solver);
    expect_below("impulses, stack of two: |plane's normal / (2 m g dt) - 1|",
                 fabs(stats.wall_normal_impulse[0] / (2 * mass * g * dt) - 1), 1e-6);
    expect_below("impulses, stack of two: |between the discs, normal / (m g dt) - 1|",
                 fabs(stats.disc_normal_impulse / (mass * g * dt) - 1), 1e-6);
    expect_below("impulses, stack of two: friction, plane's and between the discs, / (m g dt)",
                 (stats.wall_friction_impulse[0] + stats.disc_friction_impulse) / (mass * g * dt), 1e-9);
    contact_solver_destroy(w.solver);
    world_init(&w, g * sin(theta), -g * cos(theta));
    add_plane(&w, 0, 1, 0);
    add_plane(&w, -1, 0, -2);
    add_disc(&w, 1, r, r, 1);
    run(&w, dt, 1000);
    stats = contact_solver_stats(w.solver);
    expect_below("impulses, block on an incline, tan = 0.4: |friction / (m g sin dt) - 1|",
                 fabs(stats.wall_friction_impulse[0] / (mass * g * sin(theta) * dt) - 1), 1e-6);
    expect_below("impulses, block on an incline, tan = 0.4: |normal / (m g cos dt) - 1|",
                 fabs(stats.wall_normal_impulse[0] / (mass * g * cos(theta) * dt) - 1), 1e-6);
    expect_below("impulses, block on an incline: the untouched plane's and between discs (N s/m)",
                 stats.wall_normal_impulse[1] + stats.wall_friction_impulse[1] + stats.disc_normal_impulse +
                     stats.disc_friction_impulse, 0);
    contact_solver_destroy(w.solver);
    return failures;
}

/* A pyramid 3-2-1 of equal discs in a box exactly three diameters wide, dropped from small gaps. */
static int test_stack(void)
{
    world w;
    world_init(&w, 0, -9.81);
    const double r = 0.05;
    add_plane(&w, 0, 1, 0);
    add_plane(&w, 1, 0, 0);
    add_plane(&w, -1, 0, -6 * r);
    for (int i = 0; i < 3; i++)
        add_disc(&w, r + 2 * r * i, r + 0.002, r, 0);
    for (int i = 0; i < 2; i++)
        add_disc(&w, 2 * r + 2 * r * i, r + sqrt(3.0) * r + 0.01, r, 0);
    add_disc(&w, 3 * r, r + 2 * sqrt(3.0) * r + 0.02, r, 0);
    run(&w, 1e-3, 1000);
    double settled[MAX_DISCS][2];
    for (int i = 0; i < w.discs.count; i++)
        settled[i][0] = w.x[i], settled[i][1] = w.y[i];
    w.max_overlap_m = 0;
    run(&w, 1e-3, 3000);
    double drift = 0, speed = 0;
    for (int i = 0; i < w.discs.count; i++) {
        drift = fmax(drift, hypot(w.x[i] - settled[i][0], w.y[i] - settled[i][1]));
        speed = fmax(speed, hypot(w.vx[i], w.vy[i]));
    }
    printf("stack: top disc at y = %.6f m (touching: %.6f m)\n", w.y[5], r + 2 * sqrt(3.0) * r);
    expect_below("stack: drift of any disc over 3 s once settled, in radii", drift / r, 1e-4);
    expect_below("stack: largest overlap while resting, in radii", w.max_overlap_m / r, 1e-3);
    expect_below("stack: largest speed at the end (m/s)", speed, 1e-5);
    expect_below("stack: top disc height error, in radii", fabs(w.y[5] - (r + 2 * sqrt(3.0) * r)) / r, 2e-3);
    contact_solver_destroy(w.solver);
    return failures;
}

/* Gravity tilted by theta, the bed along x. Returns the measured acceleration along the bed over 1 s (from rest,
 * after 0.1 s of settling) and the contact point's slip velocity at the end. */
static double incline_acceleration(double tan_theta, int lock_rotation, double *slip_mps)
{
    const double theta = atan(tan_theta), g = 9.81, r = 0.05;
    world w;
    world_init(&w, g * sin(theta), -g * cos(theta));
    add_plane(&w, 0, 1, 0);
    add_disc(&w, 1, r, r, lock_rotation);
    run(&w, 1e-3, 100);
    const double v0 = w.vx[0];
    run(&w, 1e-3, 1000);
    *slip_mps = w.vx[0] + w.omega[0] * r; /* velocity of the contact point along x */
    contact_solver_destroy(w.solver);
    return (w.vx[0] - v0) / 1.0;
}

static int test_incline(void)
{
    const double g = 9.81, mu = 0.5;
    double slip, a;
    char what[160];
    /* rotation locked: a block. Sticks for tan theta < mu, slides at g (sin - mu cos) above. */
    a = incline_acceleration(0.4, 1, &slip);
    expect_below("incline, rotation locked, tan = 0.4 < mu: |acceleration| (m/s2)", fabs(a), 1e-9);
    a = incline_acceleration(0.6, 1, &slip);
    double theta = atan(0.6), expected = g * (sin(theta) - mu * cos(theta));
    snprintf(what, sizeof what, "incline, rotation locked, tan = 0.6 > mu: |a / %.4f - 1|", expected);
    expect_below(what, fabs(a / expected - 1), 1e-3);
    /* free disc: rolls without slip at 2/3 g sin for tan theta < 3 mu, slips at g (sin - mu cos) above */
    a = incline_acceleration(1.0, 0, &slip);
    theta = atan(1.0), expected = 2.0 / 3.0 * g * sin(theta);
    snprintf(what, sizeof what, "incline, free disc, tan = 1 < 3 mu (rolls): |a / %.4f - 1|", expected);
    expect_below(what, fabs(a / expected - 1), 1e-3);
    expect_below("incline, free disc, tan = 1: contact-point slip speed (m/s)", fabs(slip), 1e-6);
    a = incline_acceleration(2.0, 0, &slip);
    theta = atan(2.0), expected = g * (sin(theta) - mu * cos(theta));
    snprintf(what, sizeof what, "incline, free disc, tan = 2 > 3 mu (slips): |a / %.4f - 1|", expected);
    expect_below(what, fabs(a / expected - 1), 1e-3);
    expect_below("incline, free disc, tan = 2: slips (1 / slip speed, s/m)", 1 / fabs(slip), 10);
    return failures;
}

/* A disc set down at rest on a belt moving at U: friction speeds it up and spins it until it rolls on the belt,
 * which the friction impulse J reaches at v = J/m = U/3 and omega r = 2J/m = 2U/3. */
static int test_belt(void)
{
    world w;
    world_init(&w, 0, -9.81);
    const double belt = 1.0, r = 0.05;
    add_plane(&w, 0, 1, 0);
    w.walls[0].vx_mps = belt;
    add_disc(&w, 0.5, r, r, 0);
    run(&w, 1e-3, 1000);
    expect_below("belt: |v / (U/3) - 1| once rolling", fabs(w.vx[0] / (belt / 3) - 1), 1e-6);
    expect_below("belt: |omega r / (2U/3) - 1| once rolling", fabs(w.omega[0] * r / (2 * belt / 3) - 1), 1e-6);
    expect_below("belt: slip speed of the contact point against the belt (m/s)", fabs(w.vx[0] + w.omega[0] * r - belt),
                 1e-9);
    contact_solver_destroy(w.solver);
    return failures;
}

/* Dropped from 0.2 m with e = 0.8: the rebound peaks at e^2 0.2 m. */
static int test_bounce(void)
{
    world w;
    world_init(&w, 0, -9.81);
    w.settings.restitution = 0.8;
    add_plane(&w, 0, 1, 0);
    const double r = 0.05, drop = 0.2;
    add_disc(&w, 0.5, r + drop, r, 0);
    double peak = 0;
    int bounced = 0;
    for (int s = 0; s < 2000 && !(bounced && w.vy[0] < 0); s++) {
        const double vy_before = w.vy[0];
        run(&w, 2e-4, 1);
        bounced |= vy_before < 0 && w.vy[0] > 0;
        if (bounced)
            peak = fmax(peak, w.y[0] - r);
    }
    printf("bounce: rebound peak %.5f m after a %.3f m drop (e^2 h = %.5f m)\n", peak, drop, 0.64 * drop);
    expect_below("bounce: |rebound height / (e^2 h) - 1|", fabs(peak / (0.64 * drop) - 1), 0.02);
    contact_solver_destroy(w.solver);
    return failures;
}

/* Two equal discs meet head on across the periodic boundary, e = 1, no friction: they swap velocities;
 * momentum is kept to round-off. */
static int test_collision(void)
{
    world w;
    world_init(&w, 0, 0);
    w.settings.restitution = 1;
    w.settings.friction = 0;
    w.settings.period_m = 1.0;
    const double r = 0.05;
    add_disc(&w, 0.95, 0.5, r, 0);
    add_disc(&w, 0.20, 0.5, r, 0);
    w.vx[0] = 1.0, w.vx[1] = -0.5;
    const double p0 = (w.vx[0] + w.vx[1]) / w.inv_mass[0];
    run(&w, 1e-3, 300);
    expect_below("collision: |vx of disc 1 - (-0.5)| (m/s)", fabs(w.vx[0] + 0.5), 1e-9);
    expect_below("collision: |vx of disc 2 - 1| (m/s)", fabs(w.vx[1] - 1.0), 1e-9);
    expect_below("collision: relative momentum change", fabs((w.vx[0] + w.vx[1]) / w.inv_mass[0] - p0) / fabs(p0),
                 1e-12);
    expect_below("collision: positions stay in [0, period) (1 = no)", !(w.x[0] >= 0 && w.x[0] < 1 && w.x[1] >= 0 &&
                 w.x[1] < 1), 0);
    contact_solver_destroy(w.solver);
    return failures;
}

/* A blow-up elsewhere (the health monitor reports it after the step) must not crash the contact solver. */
static int test_blown_up(void)
{
    const double far[] = {NAN, INFINITY, -INFINITY, 1e300, -1e300};
    for (int periodic = 0; periodic <= 1; periodic++) {
        for (size_t k = 0; k < sizeof far / sizeof far[0]; k++) {
            world w;
            world_init(&w, 0, -9.81);
            w.settings.period_m = periodic ? 1.0 : 0;
            add_plane(&w, 0, 1, 0);
            const int resting = add_disc(&w, 0.5, 0.05, 0.05, 0);
            add_disc(&w, 0.3, fabs(far[k]), 0.05, 0); /* above the plane: one below it would shoot up */
            add_disc(&w, far[k], 0.4, 0.05, 0);
            add_disc(&w, far[k], fabs(far[k]), 0.05, 0);
            run(&w, 1e-3, 20);
            char what[96];
            snprintf(what, sizeof what, "blown_up (%s, far = %g): resting disc's drift (m)",
                     periodic ? "periodic" : "open", far[k]);
            const double drift = hypot(w.x[resting] - 0.5, w.y[resting] - 0.05);
            expect_below(what, isfinite(drift) ? drift : INFINITY, 1e-6);
            contact_solver_destroy(w.solver);
        }
    }
    return failures;
}

/* The squeeze film's force per unit approach speed under a disc of radius r at gap h0 above a plane, from Reynolds'
 * equation h^3 dp/dx = -12 mu U x on the exact gap h(x) = h0 + r - sqrt(r^2 - x^2), p = 0 at |x| = r (midpoint rule
 * in x = r sin(theta), fine near the gap) */
static double reynolds_damping(double mu, double r, double h0)
{
    enum { N = 400000 };
    double force = 0, p = 0; /* integrate p from x = r inwards, then F = 2 int_0^r p dx */
    const double dth = 0.5 * 3.14159265358979323846 / N;
    for (int k = N - 1; k >= 0; k--) {
        const double th = (k + 0.5) * dth, x = r * sin(th), dx = r * cos(th) * dth;
        const double h = h0 + r - r * cos(th);
        p += 12 * mu * x / (h * h * h) * dx; /* dp = -12 mu U x / h^3 dx, going inwards: p grows */
        force += 2 * p * dx;
    }
    return force;
}

/* The sliding film under a disc of radius r at gap h0 above a plane, its face sliding at U = 1 past the plane: with
 * p = 0 at |x| = r, the flux q = U int h^-2 / (2 int h^-3) on the exact gap, p' = 6 mu U / h^2 - 12 mu q / h^3. Returns
 * the shear force on the disc's face, int (mu U / h + h p' / 2) dx, and in *net the x force with the pressure on the
 * curved face, int (mu U / h + h p' / 2 - p' h) dx (p h' integrated by parts) */
static double reynolds_sliding(double mu, double r, double h0, double *net)
{
    enum { N = 400000 };
    const double dth = 0.5 * 3.14159265358979323846 / N;
    double i2 = 0, i3 = 0;
    for (int k = 0; k < N; k++) {
        const double th = (k + 0.5) * dth, dx = 2 * r * cos(th) * dth, h = h0 + r - r * cos(th); /* both halves */
        i2 += dx / (h * h), i3 += dx / (h * h * h);
    }
    const double q = 0.5 * i2 / i3;
    double shear = 0, pressure = 0;
    for (int k = 0; k < N; k++) {
        const double th = (k + 0.5) * dth, dx = 2 * r * cos(th) * dth, h = h0 + r - r * cos(th);
        const double dp_dx = 6 * mu / (h * h) - 12 * mu * q / (h * h * h);
        shear += (mu / h + 0.5 * h * dp_dx) * dx;
        pressure -= dp_dx * h * dx;
    }
    *net = shear + pressure;
    return shear;
}

/* A disc spinning at omega0 beside a wall at a fixed gap h (no translation: the film turns it, moves it not), and two
 * discs spinning the same way: the spin decays as exp(-c_t(h) r^2 t / I) (each disc's share for the pair) */
static void sliding_decay(int pair, double mu, double r, double dp, double gap_dp)
{
    world w;
    world_init(&w, 0, 0);
    w.settings.lubrication_viscosity_pa_s = mu;
    w.settings.lubrication_cutoff_m = dp;
    w.settings.lubrication_min_gap_m = 0.01 * dp;
    const double gap = gap_dp * dp, omega0 = 10;
    int disc;
    if (pair) {
        add_disc(&w, 0.5, 0.5, r, 0);
        disc = add_disc(&w, 0.5, 0.5 + 2 * r + gap, r, 0);
        w.omega[0] = omega0;
    } else {
        add_plane(&w, 0, 1, 0);
        disc = add_disc(&w, 0.5, r + gap, r, 0);
    }
    w.omega[disc] = omega0;
    const double inertia = 1 / w.inv_inertia[disc], radius = pair ? 0.5 * r : r;
    /* the surfaces slide at (omega_a + omega_b) r for the pair, and each disc takes the film's torque */
    const double rate = (pair ? 2 : 1) * lubrication_sliding_damping(mu, radius, gap, dp, 0.01 * dp) * r * r / inertia;
    const double t_end = 1 / rate, dt = t_end / 200;
    run(&w, dt, 200);
    char what[112];
    snprintf(what, sizeof what, "sliding film, %s at %.2g dp: spin after 1/rate against exp(-1)",
             pair ? "two discs" : "disc by a wall", gap_dp);
    expect_below(what, fabs(w.omega[disc] / omega0 / exp(-1.0) - 1), 0.02);
    snprintf(what, sizeof what, "sliding film, %s at %.2g dp: centre's speed (m/s)", pair ? "two discs" : "disc",
             gap_dp);
    expect_below(what, hypot(w.vx[disc], w.vy[disc]), 1e-12);
    contact_solver_destroy(w.solver);
}

static int test_lubrication(void)
{
    const double mu = 467, r = 0.02, dp = 0.02 / 11.8;
    /* the film's formula against Reynolds' equation: the paraboloid gap's result, exact as h0 / r -> 0 */
    const double ratios[] = {1e-4, 1e-3, 1e-2};
    const double bounds[] = {0.001, 0.006, 0.05}; /* the paraboloid's error, about 3.4 h/r */
    /* the sliding film's formula is the leading order: the next, about 2.4 (h/r)^(1/2) of it, and a net force
     * about 1.2 (h/r)^(1/2) of the shear */
    const double sliding_bounds[] = {0.03, 0.09, 0.3}, sliding_net_bounds[] = {0.015, 0.045, 0.15};
    for (int k = 0; k < 3; k++) {
        const double h0 = ratios[k] * r, numeric = reynolds_damping(mu, r, h0);
        char what[96];
        snprintf(what, sizeof what, "lubrication: film formula against Reynolds' equation, h/r = %g", ratios[k]);
        expect_below(what, fabs(lubrication_film_damping(mu, r, h0) / numeric - 1), bounds[k]);
        double net;
        const double shear = reynolds_sliding(mu, r, h0, &net);
        snprintf(what, sizeof what, "sliding film: shear formula against Reynolds' equation, h/r = %g", ratios[k]);
        expect_below(what, fabs(lubrication_sliding_film_damping(mu, r, h0) / shear - 1), sliding_bounds[k]);
        snprintf(what, sizeof what, "sliding film: net x force over the shear force, h/r = %g", ratios[k]);
        expect_below(what, fabs(net / shear), sliding_net_bounds[k]);
    }
    for (int pair = 0; pair <= 1; pair++)
        for (int g = 0; g < 3; g++)
            sliding_decay(pair, mu, r, dp, (const double[]){0.8, 0.3, 0.05}[g]);
    /* a disc driven onto a plane (and, by symmetry, two discs driven together) by a = 10 m/s2 */
    for (int pair = 0; pair <= 1; pair++) {
        world w;
        world_init(&w, 0, 0);
        w.settings.lubrication_viscosity_pa_s = mu;
        w.settings.lubrication_cutoff_m = dp;
        w.settings.lubrication_min_gap_m = 0.01 * dp;
        const double a = 100.0, start_gap = 2.5 * dp;
        int disc;
        if (pair) {
            add_disc(&w, 0.5, 0.5, r, 0);
            disc = add_disc(&w, 0.5, 0.5 + 2 * r + start_gap, r, 0);
            w.ay[0] = a, w.ay[1] = -a;
        } else {
            add_plane(&w, 0, 1, 0);
            disc = add_disc(&w, 0.5, r + start_gap, r, 0);
            w.ay[disc] = -a;
        }
        const double mass = 1 / w.inv_mass[disc], radius = pair ? 0.5 * r : r;
        const double targets[] = {1.5, 0.8, 0.5, 0.2, 0.1}; /* gaps in dp */
        int next = 0;
        double worst = 0, free_fall = 0;
        for (int step = 0; step < 100000 && next < 5; step++) {
            const double gap = pair ? w.y[1] - w.y[0] - 2 * r : w.y[disc] - r;
            run(&w, gap > 1.2 * dp ? 1e-5 : 1e-3, 1); /* free fall finely, the film's creep coarsely */
            if (gap > targets[next] * dp)
                continue;
            const double approach = pair ? w.vy[0] - w.vy[1] : -w.vy[disc];
            if (targets[next] > 1) { /* beyond the cut-off: free fall from rest over one dp */
                free_fall = fabs(approach / sqrt(2 * (pair ? 2 * a : a) * (start_gap - gap)) - 1);
            } else {
                /* the terminal speed: the driving force over the film's damping (relative speed for the pair) */
                const double gap_after = pair ? w.y[1] - w.y[0] - 2 * r : w.y[disc] - r, mid = 0.5 * (gap + gap_after);
                const double expected = mass * a / lubrication_damping(mu, radius, mid, dp, 0.01 * dp);
                worst = fmax(worst, fabs(approach / expected - 1));
            }
            next++;
        }
        char what[96];
        snprintf(what, sizeof what, "lubrication, %s: approach speed at 0.8-0.1 dp against F / c(h), worst",
                 pair ? "two discs" : "disc on a wall");
        expect_below(what, next == 5 ? worst : INFINITY, 0.02);
        snprintf(what, sizeof what, "lubrication, %s: beyond the cut-off, free fall", pair ? "two discs" : "disc");
        expect_below(what, free_fall, 0.02);
        contact_solver_destroy(w.solver);
    }
    return failures;
}

/* The measured model (contacts.lubrication_resolved = measured): the exact resistance, the share the SPH resolves,
 * and a disc driven onto a plane through the contact solver with it */
static int test_lubrication_measured(void)
{
    const double mu = 467, r = 0.02, dp = 0.02 / 4, kernel_h = 1.8 * sqrt(2.0) * dp;
    /* the exact resistance tends to the film's at contact, the next order 21/20 h/R above it (its series); the two
     * ways it is evaluated meet at alpha = 0.1 (h/R = cosh 0.1 - 1) */
    for (int k = 0; k < 3; k++) {
        const double ratio = (const double[]){1e-3, 1e-2, 1e-1}[k];
        const double h0 = ratio * r;
        const double excess = lubrication_exact_damping(mu, r, h0) / lubrication_film_damping(mu, r, h0) - 1;
        char what[96];
        snprintf(what, sizeof what, "exact resistance over the film's, less 1, over h/R - 1.05, at h/R %g", ratio);
        expect_below(what, fabs(excess / ratio - 1.05), 0.01);
    }
    const double switch_gap = (cosh(0.1) - 1) * r;
    expect_below("exact resistance: the series and tanh meet at alpha 0.1",
                 fabs(lubrication_exact_damping(mu, r, switch_gap * (1 - 1e-9)) /
                          lubrication_exact_damping(mu, r, switch_gap * (1 + 1e-9)) - 1), 1e-8);
    /* each scheme's share: 0 at contact, never falling, 1 from the table's end on */
    const time_scheme *schemes[] = {&scheme_implicit, &scheme_explicit};
    for (int k = 0; k < 2; k++) {
        const lubrication_share *share = schemes[k]->film_share;
        char what[96];
        double worst_fall = 0, last = lubrication_resolved_share(share, 0);
        for (double x = 0; x < LUBRICATION_RESOLVED_END + 0.5; x += 0.01) {
            worst_fall = fmax(worst_fall, last - lubrication_resolved_share(share, x));
            last = lubrication_resolved_share(share, x);
        }
        snprintf(what, sizeof what, "%s scheme: resolved share at contact", schemes[k]->name);
        expect_below(what, lubrication_resolved_share(share, 0), 1e-12);
        snprintf(what, sizeof what, "%s scheme: resolved share, largest fall with the gap", schemes[k]->name);
        expect_below(what, worst_fall, 0);
        snprintf(what, sizeof what, "%s scheme: resolved share beyond the table's end, less 1", schemes[k]->name);
        expect_below(what, fabs(lubrication_resolved_share(share, 4) - 1), 1e-12);
    }
    /* the damping: the exact less the share; none from the end on; the gap taken at least min_gap */
    const lubrication_share *share = scheme_implicit.film_share;
    const double gap = 0.6 * kernel_h;
    expect_below("measured damping at 0.6 h against (1 - share) exact",
                 fabs(lubrication_measured_damping(share, mu, r, gap, kernel_h, 0.01 * dp) /
                          ((1 - lubrication_resolved_share(share, 0.6)) * lubrication_exact_damping(mu, r, gap)) - 1),
                 1e-12);
    expect_below("measured damping at the table's end",
                 lubrication_measured_damping(share, mu, r, LUBRICATION_RESOLVED_END * kernel_h, kernel_h, 0.01 * dp),
                 0);
    expect_below("measured damping below the smallest gap, against at it",
                 fabs(lubrication_measured_damping(share, mu, r, 1e-5 * dp, kernel_h, 0.01 * dp) /
                          lubrication_measured_damping(share, mu, r, 0.01 * dp, kernel_h, 0.01 * dp) - 1), 1e-12);
    /* a disc driven onto a plane through the contact solver: free fall beyond the model's reach, then the terminal
     * speed F / c(h) of the measured damping */
    world w;
    world_init(&w, 0, 0);
    w.settings.lubrication_viscosity_pa_s = mu;
    w.settings.lubrication_cutoff_m = dp;
    w.settings.lubrication_min_gap_m = 0.01 * dp;
    w.settings.lubrication_kernel_h_m = kernel_h;
    w.settings.lubrication_share = share;
    const double a = 100.0, reach = LUBRICATION_RESOLVED_END * kernel_h, start_gap = reach + 0.5 * dp;
    add_plane(&w, 0, 1, 0);
    const int disc = add_disc(&w, 0.5, r + start_gap, r, 0);
    w.ay[disc] = -a;
    const double mass = 1 / w.inv_mass[disc];
    const double targets[] = {(reach + 0.1 * dp) / dp, 2, 1, 0.5, 0.2}; /* gaps in dp */
    int next = 0;
    double worst = 0, free_fall = 0;
    for (int step = 0; step < 100000 && next < 5; step++) {
        const double gap_before = w.y[disc] - r;
        run(&w, gap_before > reach ? 1e-6 : 1e-3, 1);
        if (gap_before > targets[next] * dp)
            continue;
        const double gap_after = w.y[disc] - r, approach = -w.vy[disc];
        if (next == 0)
            free_fall = fabs(approach / sqrt(2 * a * (start_gap - gap_before)) - 1);
        else
            worst = fmax(worst, fabs(approach / (mass * a / lubrication_measured_damping(
                                                    share, mu, r, 0.5 * (gap_before + gap_after), kernel_h, 0.01 * dp)) -
                                     1));
        next++;
    }
    expect_below("measured model, disc on a plane: beyond the reach, free fall", free_fall, 0.02);
    expect_below("measured model, disc on a plane: approach at 2-0.2 dp against F / c(h), worst",
                 next == 5 ? worst : INFINITY, 0.02);
    contact_solver_destroy(w.solver);
    return failures;
}

/* Reynolds' equation on the exact gap between disc T (radius rt, above) and disc B (radius rb, below; rb <= 0: a
 * plane at rest), their centres moving along the gap at UT, UB and turning at WT, WB: the gap's shape moves,
 * dh/dt = -UT x / sqrt(rt^2 - x^2) - UB x / sqrt(rb^2 - x^2), the surfaces slide at uT = UT + WT sqrt(rt^2 - x^2) and
 * uB = UB - WB sqrt(rb^2 - x^2), and h^3 p'/(12 mu) = int_0^x dh/dt + h (uT + uB)/2 + C with p = 0 at both ends of
 * |x| < 0.999 min(rt, rb). Returns in out the x forces and the torques (F_T, T_T, F_B, T_B): the pressure on each
 * curved face and the shear, -mu (uT - uB)/h - h p'/2 on T, +mu (uT - uB)/h - h p'/2 on B, its torque about each
 * centre with the lever sqrt(r^2 - x^2) */
static void reynolds_tangential(double mu, double rt, double rb, double h0, const double motion[4], double out[4])
{
    enum { N = 200000 };
    const int plane = !(rb > 0);
    const double half = 0.999 * (plane ? rt : fmin(rt, rb)), dx = 2 * half / N;
    static double h[N], source[N], mean[N], grad[N];
    double flux_sum = 0, inv_sum = 0, integral = 0;
    for (int k = 0; k < N; k++) { /* midpoints; int_0^x dh/dt by the midpoint sums from the left end (a constant) */
        const double x = -half + (k + 0.5) * dx, st = sqrt(rt * rt - x * x), sb = plane ? 0 : sqrt(rb * rb - x * x);
        h[k] = h0 + rt - st + (plane ? 0 : rb - sb);
        const double dhdt = -motion[0] * x / st - (plane ? 0 : motion[2] * x / sb);
        const double ut = motion[0] + motion[1] * st, ub = plane ? 0 : motion[2] - motion[3] * sb;
        integral += dhdt * dx;
        mean[k] = ut - ub; /* kept for the shear */
        source[k] = integral - 0.5 * dhdt * dx + 0.5 * h[k] * (ut + ub);
        const double g = 12 * mu / (h[k] * h[k] * h[k]);
        flux_sum += g * source[k] * dx, inv_sum += g * dx;
    }
    const double c = -flux_sum / inv_sum;
    double p = 0;
    for (int k = 0; k < 4; k++)
        out[k] = 0;
    for (int k = 0; k < N; k++) {
        const double x = -half + (k + 0.5) * dx, st = sqrt(rt * rt - x * x), sb = plane ? 0 : sqrt(rb * rb - x * x);
        grad[k] = 12 * mu * (source[k] + c) / (h[k] * h[k] * h[k]);
        const double p_mid = p + 0.5 * grad[k] * dx;
        p += grad[k] * dx;
        const double shear_t = -mu * mean[k] / h[k] - 0.5 * h[k] * grad[k];
        const double shear_b = mu * mean[k] / h[k] - 0.5 * h[k] * grad[k];
        out[0] += (-p_mid * x / st + shear_t) * dx;
        out[1] += st * shear_t * dx;
        if (!plane) {
            out[2] += (-p_mid * x / sb + shear_b) * dx;
            out[3] += -sb * shear_b * dx;
        }
    }
}

/* The tangential film (contacts.lubrication_tangential = reynolds): lubrication_tangential_matrix against Reynolds'
 * equation on the exact gap (a disc by a plane, two equal discs, a disc by one twice its size), unit motions one
 * coordinate at a time; its null motions; lubrication_tangential_damping near contact and at the model's reach */
static int test_lubrication_tangential(void)
{
    const double mu = 467, r = 0.02;
    const double ratios[] = {1e-4, 1e-3, 1e-2}, bounds[] = {0.045, 0.14, 0.45}; /* leading order: next 2-4 (h/R)^1/2 */
    const double pairs[][2] = {{r, 0}, {r, r}, {r, 2 * r}};
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 3; k++) {
            const double rt = pairs[c][0], rb = pairs[c][1], R = rb > 0 ? rt * rb / (rt + rb) : rt;
            const double h0 = ratios[k] * R, S = 3.14159265358979323846 * mu * sqrt(2 * R / h0);
            double K[4][4], worst = 0, scale = 0;
            lubrication_tangential_matrix(S, rt, rb, K);
            const int n = rb > 0 ? 4 : 2;
            double numeric[4][4];
            for (int j = 0; j < n; j++) {
                double motion[4] = {0, 0, 0, 0}, out[4];
                motion[j] = 1; /* velocities in m/s, spins in rad/s: columns scaled by r below */
                reynolds_tangential(mu, rt, rb, h0, motion, out);
                for (int i = 0; i < n; i++)
                    numeric[i][j] = -out[i];
            }
            /* in units where every coordinate is a surface speed: U, r Omega; forces and torques over r */
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++) {
                    const double si = (i % 2 ? (i < 2 ? rt : rb) : 1), sj = (j % 2 ? (j < 2 ? rt : rb) : 1);
                    scale = fmax(scale, fabs(K[i][j]) / (si * sj));
                    worst = fmax(worst, fabs(K[i][j] - numeric[i][j]) / (si * sj));
                }
            char what[112];
            snprintf(what, sizeof what, "tangential film, %s, h/R = %g: largest entry error over the largest entry",
                     rb > 0 ? (rb == rt ? "two equal discs" : "disc by one twice its size") : "disc by a plane",
                     ratios[k]);
            expect_below(what, worst / scale, bounds[k]);
        }
    /* symmetric; no resistance to a common translation or to the pair turning as one body about its contact */
    double K[4][4], asym = 0;
    const double rt = r, rb = 1.5 * r;
    lubrication_tangential_matrix(1.0, rt, rb, K);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            asym = fmax(asym, fabs(K[i][j] - K[j][i]));
    expect_below("tangential film: K - K^T, largest", asym, 1e-15);
    const double translation[4] = {1, 0, 1, 0}, turn[4] = {-rt, 1, rb, 1}; /* Omega = 1 about the contact point */
    double worst_null = 0;
    for (int i = 0; i < 4; i++) {
        double a = 0, b = 0;
        for (int j = 0; j < 4; j++)
            a += K[i][j] * translation[j], b += K[i][j] * turn[j];
        worst_null = fmax(worst_null, fmax(fabs(a), fabs(b) / r));
    }
    expect_below("tangential film: force of a common translation and of the pair turning as one body", worst_null,
                 1e-14);
    /* the damping: pi mu (2R/h)^(1/2) near contact (next order about (2h/R)^(1/2)), times 1 - share; none at reach */
    const double dp = r / 4, kernel_h = 1.8 * sqrt(2.0) * dp;
    const double near = 1e-4 * r, lead = 3.14159265358979323846 * mu * sqrt(2 * r / near);
    const lubrication_share *share = scheme_implicit.film_share;
    expect_below("tangential damping at h/R 1e-4 over pi mu (2R/h)^1/2 (1 - share), less 1",
                 fabs(lubrication_tangential_damping(share, mu, r, near, kernel_h, 1e-6 * dp) /
                          ((1 - lubrication_resolved_share(share, near / kernel_h)) * lead) - 1), 0.02);
    expect_below("tangential damping at the model's reach",
                 lubrication_tangential_damping(share, mu, r, LUBRICATION_RESOLVED_END * kernel_h, kernel_h,
                                                0.01 * dp), 0);
    return failures;
}

/* The tangential film inside the contact solver's sub-steps (the explicit scheme's films): a disc held a gap g above a
 * plane (no gravity, its normal speed zero) that slides and turns slows as implicit Euler on K's diagonal gives,
 * (1 + 2 S h W)^-n over n sub-steps, its speed and spin each on its own; by a belt moving at u_b the same for U - u_b.
 * Two equal discs side by side sliding along their gap in opposite directions keep their total momentum and
 * slow, and a common translation of the pair is not slowed. */
static void reynolds_world(world *w, double mu, double dp, double kernel_h, const lubrication_share *share)
{
    world_init(w, 0, 0);
    w->settings.lubrication_viscosity_pa_s = mu, w->settings.lubrication_cutoff_m = dp;
    w->settings.lubrication_min_gap_m = 0.01 * dp, w->settings.lubrication_kernel_h_m = kernel_h;
    w->settings.lubrication_share = share, w->settings.lubrication_tangential_reynolds = 1;
}

static int test_lubrication_reynolds_solver(void)
{
    const double mu = 4.67, r = 0.02, dp = r / 4, kernel_h = 1.8 * sqrt(2.0) * dp, g = 0.5 * dp;
    const lubrication_share *share = scheme_explicit.film_share;
    const double S = lubrication_tangential_damping(share, mu, r, g, kernel_h, 0.01 * dp);
    for (int belt = 0; belt < 2; belt++) {
        world w;
        reynolds_world(&w, mu, dp, kernel_h, share);
        add_plane(&w, 0, 1, 0);
        const double u_b = belt ? -0.3 : 0;
        w.walls[0].vx_mps = u_b;
        const int d = add_disc(&w, 0.5, r + g, r, 0);
        w.vx[d] = 0.1, w.omega[d] = 2.0;
        const double dt = 1e-3, h = dt / w.settings.substeps;
        const int steps = 20;
        run(&w, dt, steps);
        /* t' = (n_y, -n_x) = (1, 0) for the plane's normal (0, 1): U along x */
        const double n = steps * w.settings.substeps;
        const double speed = u_b + (0.1 - u_b) * pow(1 + 2 * S * h * w.inv_mass[d], -n);
        const double spin = 2.0 * pow(1 + 2 * S * r * r * h * w.inv_inertia[d], -n);
        char what[112];
        snprintf(what, sizeof what, "reynolds in the solver, disc by a %s: speed over implicit Euler's, less 1",
                 belt ? "belt" : "plane");
        expect_below(what, fabs((w.vx[d] - u_b) / (speed - u_b) - 1), 1e-9);
        snprintf(what, sizeof what, "reynolds in the solver, disc by a %s: spin over implicit Euler's, less 1",
                 belt ? "belt" : "plane");
        expect_below(what, fabs(w.omega[d] / spin - 1), 1e-9);
        snprintf(what, sizeof what, "reynolds in the solver, disc by a %s: the speed fell by at least a tenth",
                 belt ? "belt" : "plane");
        expect_below(what, (w.vx[d] - u_b) / (0.1 - u_b), 0.9);
        expect_below("reynolds in the solver: no normal speed", fabs(w.vy[d]), 1e-15);
        contact_solver_destroy(w.solver);
    }
    for (int common = 0; common < 2; common++) {
        world w;
        reynolds_world(&w, mu, dp, kernel_h, share);
        const int a = add_disc(&w, 0.5, 0.5, r, 0), b = add_disc(&w, 0.5 + 2 * r + g, 0.5, r, 0);
        w.vy[a] = common ? 0.1 : -0.1, w.vy[b] = 0.1;
        run(&w, 1e-3, 20);
        const double momentum = w.vy[a] + w.vy[b], before = common ? 0.2 : 0;
        expect_below(common ? "reynolds in the solver, two discs in a common translation: change of speed"
                            : "reynolds in the solver, two discs sliding past each other: total momentum",
                     common ? fmax(fabs(w.vy[a] - 0.1), fabs(w.vy[b] - 0.1)) : fabs(momentum - before), 1e-12);
        if (!common)
            expect_below("reynolds in the solver, two discs sliding past each other: sliding speed kept",
                         (w.vy[b] - w.vy[a]) / 0.2, 0.9);
        contact_solver_destroy(w.solver);
    }
    return failures;
}

int main(int argc, char **argv)
{
    const char *which = argc > 1 ? argv[1] : "";
    if (!strcmp(which, "rest"))
        return test_rest() != 0;
    if (!strcmp(which, "stack"))
        return test_stack() != 0;
    if (!strcmp(which, "impulses"))
        return test_impulses() != 0;
    if (!strcmp(which, "incline"))
        return test_incline() != 0;
    if (!strcmp(which, "belt"))
        return test_belt() != 0;
    if (!strcmp(which, "bounce"))
        return test_bounce() != 0;
    if (!strcmp(which, "collision"))
        return test_collision() != 0;
    if (!strcmp(which, "blown_up"))
        return test_blown_up() != 0;
    if (!strcmp(which, "lubrication"))
        return test_lubrication() != 0;
    if (!strcmp(which, "lubrication_measured"))
        return test_lubrication_measured() != 0;
    if (!strcmp(which, "lubrication_tangential"))
        return test_lubrication_tangential() != 0;
    if (!strcmp(which, "lubrication_reynolds_solver"))
        return test_lubrication_reynolds_solver() != 0;
    fprintf(stderr, "usage: test_contacts rest|stack|impulses|incline|belt|bounce|collision|blown_up|lubrication|"
                    "lubrication_measured|lubrication_tangential|lubrication_reynolds_solver\n");
    return 2;
}
