/* Boulders: rigid discs made of boundary particles (GMD Sect. 2.2). Each disc is rings of wall particles at
 * the fluid spacing, as deep as the kernel support, with mDBC ghost nodes mirrored across its circle. The
 * fluid acts on a disc through the SPH forces on its particles (eq. 10); the disc moves them rigidly (eq. 11).
 * Discs follow the symplectic scheme: the half-step force moves them over the full step from its start,
 * inside the contact solver's sub-steps. */
#define _DEFAULT_SOURCE /* erand48 */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "surge/boulder_scene.h"
#include "physics/pair_terms.h"
#include "sim_internal.h"
#include "scene/scales.h"
#include "boulders/boulders.h"
#include "boulders/placement.h"

enum { MAX_PLACEMENT_TRIES = 2000000, MAX_RANDOM_DISCS = 20000 };

static int allocate_discs(boulder_set *b, int n)
{
    b->count = n;
    int ok = 1;
#define ALLOC(ptr) ok &= ((ptr) = calloc((size_t)(n > 0 ? n : 1), sizeof *(ptr))) != NULL
    ALLOC(b->x); ALLOC(b->y); ALLOC(b->angle); ALLOC(b->vx); ALLOC(b->vy); ALLOC(b->omega);
    ALLOC(b->x_n); ALLOC(b->y_n); ALLOC(b->angle_n); ALLOC(b->vx_n); ALLOC(b->vy_n); ALLOC(b->omega_n);
    ALLOC(b->radius); ALLOC(b->mass); ALLOC(b->inv_mass); ALLOC(b->inv_inertia);
    ALLOC(b->fx); ALLOC(b->fy); ALLOC(b->torque); ALLOC(b->ax); ALLOC(b->ay); ALLOC(b->alpha);
    ALLOC(b->spin_damping); ALLOC(b->omega_forces); ALLOC(b->angle_build); ALLOC(b->contact_radius);
    ALLOC(b->wetted); ALLOC(b->step_ax); ALLOC(b->step_ay); ALLOC(b->step_ax_n); ALLOC(b->step_ay_n);
    ALLOC(b->drag_stiffness); ALLOC(b->cos_angle); ALLOC(b->sin_angle);
#undef ALLOC
    return ok ? 0 : -1;
}

void boulders_free(boulder_set *b)
{
    void *arrays[] = {b->x, b->y, b->angle, b->vx, b->vy, b->omega, b->x_n, b->y_n, b->angle_n, b->vx_n, b->vy_n,
                      b->omega_n, b->radius, b->mass, b->inv_mass, b->inv_inertia, b->fx, b->fy, b->torque, b->ax,
                      b->ay, b->alpha, b->spin_damping, b->omega_forces, b->spin_coupling, b->of_wall,
                      b->local_x, b->local_y, b->angle_build, b->contact_radius, b->wetted, b->step_ax,
                      b->step_ay, b->step_ax_n, b->step_ay_n, b->drag_stiffness, b->cos_angle, b->sin_angle};
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
        free(arrays[i]);
    contact_solver_destroy(b->contacts);
    memset(b, 0, sizeof *b);
}


/* "x y r [vx vy omega], ..." */
static int parse_list(boulder_set *b, const char *text, char *err, size_t err_len)
{
    int n = 0;
    for (const char *c = text; *c; c++)
        n += *c == ',';
    n += 1;
    if (allocate_discs(b, n) != 0) {
        snprintf(err, err_len, "out of memory for %d boulders", n);
        return -1;
    }
    const char *cursor = text;
    for (int i = 0; i < n; i++) {
        double v[7];
        int got = 0;
        const size_t len = strcspn(cursor, ",");
        char entry[SURGE_TEXT_PARAM_BYTES];
        memcpy(entry, cursor, len);
        entry[len] = '\0';
        char *s = entry;
        while (got < 7) {
            while (isspace((unsigned char)*s))
                s++;
            if (!*s)
                break;
            char *end;
            v[got] = strtod(s, &end);
            if (end == s || !isfinite(v[got])) {
                snprintf(err, err_len, "boulders.list_m: disc %d ('%s'): '%s' is not a number", i + 1, entry, s);
                return -1;
            }
            got++;
            s = end;
        }
        if (got != 3 && got != 6) {
            snprintf(err, err_len, "boulders.list_m: disc %d ('%s') has %d numbers; expected 'x y r' or "
                     "'x y r vx vy omega'", i + 1, entry, got);
            return -1;
        }
        if (!(v[2] > 0)) {
            snprintf(err, err_len, "boulders.list_m: disc %d has radius %g; expected a positive radius in m", i + 1,
                     v[2]);
            return -1;
        }
        b->x[i] = v[0], b->y[i] = v[1], b->radius[i] = v[2];
        if (got == 6)
            b->vx[i] = v[3], b->vy[i] = v[4], b->omega[i] = v[5];
        cursor += len + (cursor[len] == ',');
    }
    return 0;
}

/* The random placement's region: a disc's centre is drawn uniformly where the disc keeps the gap from its edges (in x
 * only where the region does not span the period) */
typedef struct random_region {
    double x0, x1, y0, y1, gap;
    int spans_period;
} random_region;

static int draw_uniform(void *context, double r, unsigned short rng[3], double *x, double *y)
{
    const random_region *g = context;
    const double margin_x = g->spans_period ? 0 : r + g->gap;
    const double lo_x = g->x0 + margin_x, hi_x = g->x1 - margin_x, lo_y = g->y0 + r + g->gap, hi_y = g->y1 - r - g->gap;
    *x = lo_x + (hi_x - lo_x) * erand48(rng);
    *y = lo_y + (hi_y - lo_y) * erand48(rng);
    return 0;
}

/* Random sequential placement: the largest discs first, each at uniform random positions until it overlaps
 * neither another disc nor a wall (with the gap), reproducible from the seed. */
static int place_random(boulder_set *b, const surge_params *q, double period, char *err, size_t err_len)
{
    double x0 = q->boulders.region_x0_m, x1 = q->boulders.region_x1_m;
    double y0 = q->boulders.region_y0_m, y1 = q->boulders.region_y1_m;
    if (x1 <= x0)
        x0 = q->fluid.x0_m, x1 = q->fluid.x1_m;
    if (y1 <= y0)
        y0 = 0, y1 = q->fluid.depth_m;
    const double gap = fmax(q->boulders.min_gap_m > 0 ? q->boulders.min_gap_m : q->numerics.dp_m,
                            q->contacts.margin_dp * q->numerics.dp_m);
    const double r_min = q->boulders.radius_m;
    const double r_max = fmax(q->boulders.radius_max_m, r_min);
    const double target_area = q->boulders.solid_fraction * (x1 - x0) * (y1 - y0);
    /* checked before drawing: the placement below is quadratic in the number of discs */
    if (r_min < 1.5 * q->numerics.dp_m) {
        snprintf(err, err_len, "boulders.radius_m = %g m is below 1.5 dp (%g m); a disc needs a few particles across",
                 r_min, 1.5 * q->numerics.dp_m);
        return -1;
    }
    if (target_area / (SURGE_PI * r_min * r_min) > MAX_RANDOM_DISCS) {
        snprintf(err, err_len, "boulders: solid_fraction %g of the region [%g, %g] x [%g, %g] m would take about "
                 "%.3g discs of radius %g m, more than %d (raise boulders.radius_m or lower the fraction)",
                 q->boulders.solid_fraction, x0, x1, y0, y1, target_area / (SURGE_PI * r_min * r_min), r_min,
                 MAX_RANDOM_DISCS);
        return -1;
    }
    unsigned short rng[3] = {0x330e, (unsigned short)(q->boulders.seed & 0xffff),
                             (unsigned short)((unsigned)q->boulders.seed >> 16)};
    /* radii until the target area is reached (the last disc taken when it brings the area closer) */
    int n = 0, cap = 16;
    double *radii = malloc((size_t)cap * sizeof *radii), area = 0;
    while (radii) {
        const double r = r_min + (r_max - r_min) * erand48(rng);
        if (area + SURGE_PI * r * r - target_area > target_area - area)
            break;
        if (n == cap) {
            double *bigger = realloc(radii, (size_t)(cap *= 2) * sizeof *radii);
            if (!bigger)
                free(radii);
            radii = bigger;
            if (!radii)
                break;
        }
        radii[n++] = r;
        area += SURGE_PI * r * r;
    }
    if (radii && n == 0) {
        free(radii);
        snprintf(err, err_len, "boulders: solid_fraction %g of the region [%g, %g] x [%g, %g] m holds no disc of "
                 "radius %g m", q->boulders.solid_fraction, x0, x1, y0, y1, r_min);
        return -1;
    }
    if (!radii || allocate_discs(b, n) != 0) {
        free(radii);
        snprintf(err, err_len, "out of memory placing boulders");
        return -1;
    }
    for (int i = 0; i < n; i++) /* largest first: insertion sort, n is small */
        for (int j = i; j > 0 && radii[j] > radii[j - 1]; j--) {
            const double t = radii[j];
            radii[j] = radii[j - 1];
            radii[j - 1] = t;
        }
    const int spans_period = period > 0 && x1 - x0 >= period - 1e-12;
    /* the largest disc fits worst: the region must hold it away from its edges by the gap */
    const double margin_x = spans_period ? 0 : radii[0] + gap;
    if (x1 - margin_x < x0 + margin_x || y1 - radii[0] - gap < y0 + radii[0] + gap) {
        snprintf(err, err_len, "boulders: a disc of radius %g m with gap %g m does not fit in the region "
                 "[%g, %g] x [%g, %g] m", radii[0], gap, x0, x1, y0, y1);
        free(radii);
        return -1;
    }
    random_region region = {x0, x1, y0, y1, gap, spans_period};
    const int placed = placement_sequential(radii, n, gap, period, 1, draw_uniform, &region, rng, MAX_PLACEMENT_TRIES,
                                            b->x, b->y);
    for (int i = 0; i < placed; i++)
        b->radius[i] = radii[i];
    free(radii);
    if (placed < n) {
        double placed_area = 0;
        for (int j = 0; j < placed; j++)
            placed_area += SURGE_PI * b->radius[j] * b->radius[j];
        snprintf(err, err_len, "boulders: placed %d of %d discs (solid fraction %.3f of the %.3f asked) in %d "
                 "random tries; lower boulders.solid_fraction or boulders.min_gap_m", placed, n,
                 placed_area / ((x1 - x0) * (y1 - y0)), q->boulders.solid_fraction, MAX_PLACEMENT_TRIES);
        return -1;
    }
    return 0;
}

/* The discs of the graded placement or of the CSV file (surge/boulder_scene.h). */
static int adopt_discs(boulder_set *b, const surge_params *p, char *err, size_t err_len)
{
    surge_disc *discs = NULL;
    const int n = p->boulders.placement == SURGE_BOULDERS_GRADED
                      ? surge_boulders_generate(p, &discs, err, err_len)
                      : surge_discs_read_csv(p->boulders.file, &discs, err, err_len);
    if (n < 0)
        return -1;
    if (allocate_discs(b, n) != 0) {
        free(discs);
        snprintf(err, err_len, "out of memory for %d boulders", n);
        return -1;
    }
    for (int i = 0; i < n; i++) {
        b->x[i] = discs[i].x_m, b->y[i] = discs[i].y_m, b->radius[i] = discs[i].r_m;
        b->vx[i] = discs[i].vx_mps, b->vy[i] = discs[i].vy_mps, b->omega[i] = discs[i].omega_radps;
    }
    free(discs);
    return 0;
}

int boulders_define(surge_sim *sim, char *err, size_t err_len)
{
    const surge_params *p = &sim->params;
    boulder_set *b = &sim->boulders;
    const double period = p->domain.periodic_x ? p->domain.length_m : 0;
    int rc = 0;
    if (p->boulders.placement == SURGE_BOULDERS_LIST)
        rc = parse_list(b, p->boulders.list_m, err, err_len);
    else if (p->boulders.placement == SURGE_BOULDERS_RANDOM)
        rc = place_random(b, p, period, err, err_len);
    else if (p->boulders.placement == SURGE_BOULDERS_GRADED || p->boulders.placement == SURGE_BOULDERS_FILE)
        rc = adopt_discs(b, p, err, err_len);
    if (rc != 0 || b->count == 0)
        return rc;
    const double dp = p->numerics.dp_m;
    for (int i = 0; i < b->count; i++) {
        if (b->radius[i] < 1.5 * dp) {
            snprintf(err, err_len, "boulder %d: radius %g m is below 1.5 dp (%g m); a disc needs a few particles "
                     "across", i + 1, b->radius[i], 1.5 * dp);
            return -1;
        }
        const double r = b->radius[i];
        const int inside_x = period > 0 || (b->x[i] - r >= -1e-12 && b->x[i] + r <= p->domain.length_m + 1e-12);
        if (!inside_x || b->y[i] - r < -1e-12 || b->y[i] + r > p->domain.height_m + 1e-12) {
            snprintf(err, err_len, "boulder %d at (%g, %g) m with radius %g m is not inside the domain [0, %g] x "
                     "[0, %g] m", i + 1, b->x[i], b->y[i], r, p->domain.length_m, p->domain.height_m);
            return -1;
        }
        if (period > 0)
            b->x[i] -= period * floor(b->x[i] / period);
        b->contact_radius[i] = r + 0.5 * p->contacts.margin_dp * dp;
        b->mass[i] = p->boulders.density_ratio * sim->rho0 * SURGE_PI * r * r;
        b->inv_mass[i] = 1.0 / b->mass[i];
        b->inv_inertia[i] = 1.0 / (0.5 * b->mass[i] * r * r);
    }
    /* listed discs must not overlap (random ones never do), nor start closer than the contact margin, which the
     * contact solver would open at once, squeezing the fluid between */
    const double margin = p->contacts.margin_dp * dp;
    for (int i = 0; i < b->count; i++) {
        for (int j = 0; j < i; j++) {
            const double dx = placement_wrap_dx(b->x[i] - b->x[j], period), dy = b->y[i] - b->y[j];
            const double reach = b->radius[i] + b->radius[j] + margin;
            if (dx * dx + dy * dy < reach * reach * (1 - 1e-12)) {
                snprintf(err, err_len, "boulders %d and %d %s: centres %.4g m apart, radii%s add up to %.4g m", j + 1,
                         i + 1, margin > 0 ? "are closer than contacts.margin_dp" : "overlap",
                         sqrt(dx * dx + dy * dy), margin > 0 ? " and margin" : "", reach);
                return -1;
            }
        }
        const double r = b->radius[i];
        const int near_wall = (p->walls.bottom && b->y[i] - r < margin * (1 - 1e-9)) ||
                              (p->walls.top && p->domain.height_m - b->y[i] - r < margin * (1 - 1e-9));
        if (margin > 0 && near_wall) {
            snprintf(err, err_len, "boulder %d at (%g, %g) m with radius %g m is closer than contacts.margin_dp "
                     "(%g m) to the bed or lid", i + 1, b->x[i], b->y[i], r, margin);
            return -1;
        }
    }
    b->contacts = contact_solver_create();
    if (!b->contacts) {
        snprintf(err, err_len, "out of memory for the contact solver");
        return -1;
    }
    return 0;
}

/* A disc of radius r is rings k = 0, 1, ... at radius r - (k + 1/2) dp, as deep as the wall layers (and
 * while the radius is above dp/4), each of round(2 pi rho / dp) particles, at least one. */
static int ring_count(double r, double dp, int layers)
{
    int k = 0;
    while (k < layers && r - (k + 0.5) * dp > 0.25 * dp)
        k++;
    return k;
}

static int ring_particles(double r, double dp, int ring)
{
    const int n = (int)lround(2 * SURGE_PI * (r - (ring + 0.5) * dp) / dp);
    return n > 1 ? n : 1;
}

int boulders_particles_of(const surge_sim *sim, int disc)
{
    const double dp = sim->params.numerics.dp_m, radius = sim->boulders.radius[disc];
    int n = 0;
    for (int q = 0; q < ring_count(radius, dp, sim->params.walls.layers); q++)
        n += ring_particles(radius, dp, q);
    return n;
}

int boulders_particle_count(const surge_sim *sim)
{
    int n = 0;
    for (int i = 0; i < sim->boulders.count; i++)
        n += boulders_particles_of(sim, i);
    return n;
}

void boulders_create_particles(surge_sim *sim, int first)
{
    boulder_set *b = &sim->boulders;
    const double dp = sim->params.numerics.dp_m;
    const int layers = sim->params.walls.layers;
    int k = first;
    for (int i = 0; i < b->count; i++) {
        const int rings = ring_count(b->radius[i], dp, layers);
        for (int q = 0; q < rings; q++) {
            const double rho = b->radius[i] - (q + 0.5) * dp;
            const int per_ring = ring_particles(b->radius[i], dp, q);
            for (int j = 0; j < per_ring; j++) {
                const double phi = 2 * SURGE_PI * (j + 0.5 * (q % 2)) / per_ring;
                b->of_wall[k] = i;
                b->local_x[k] = rho * cos(phi);
                b->local_y[k] = rho * sin(phi);
                sim->id[k] = k;
                sim->wall_of[k] = WALL_BOULDER;
                sim->kind[k] = SURGE_KIND_BOULDER;
                sim->rho[k] = (real)sim->rho0;
                k++;
            }
        }
    }
}

int boulders_cover(const surge_sim *sim, double x, double y)
{
    const boulder_set *b = &sim->boulders;
    const double period = sim->params.domain.periodic_x ? sim->params.domain.length_m : 0;
    const double clearance = 0.25 * sim->params.numerics.dp_m;
    for (int i = 0; i < b->count; i++) {
        const double dx = placement_wrap_dx(x - b->x[i], period), dy = y - b->y[i], d = b->radius[i] + clearance;
        if (dx * dx + dy * dy < d * d)
            return 1;
    }
    return 0;
}

/* eq. 11: u_k = V + Omega x (r_k - R0); the ghost node mirrors the particle across the circle. */
/* Offset of the disc particle with id from its disc's centre at orientation (cos, sin) = (c, s). */
static inline void rotated_offset(const boulder_set *b, int id, double c, double s, double *rx, double *ry)
{
    *rx = c * b->local_x[id] - s * b->local_y[id];
    *ry = s * b->local_x[id] + c * b->local_y[id];
}

/* The same at the given angle. */
static inline void disc_offset(const boulder_set *b, int id, double angle, double *rx, double *ry)
{
    rotated_offset(b, id, cos(angle), sin(angle), rx, ry);
}

void boulders_orient(const boulder_set *b)
{
    for (int i = 0; i < b->count; i++) {
        b->cos_angle[i] = cos(b->angle[i]);
        b->sin_angle[i] = sin(b->angle[i]);
    }
}

/* The mDBC ghost offset of a disc particle at offset (rx, ry): mirrored across the disc's surface. */
static inline void ghost_offset(const boulder_set *b, int i, double rx, double ry, real *gdx, real *gdy)
{
    const double rho = sqrt(rx * rx + ry * ry), to_ghost = 2 * (b->radius[i] - rho) / rho;
    *gdx = (real)(rx * to_ghost);
    *gdy = (real)(ry * to_ghost);
}

void boulders_place_particles(surge_sim *sim)
{
    const boulder_set *b = &sim->boulders;
    if (b->count == 0)
        return;
    const double period = sim->grid.period_m;
    boulders_orient(b);
    #pragma omp parallel for schedule(static)
    for (int k = 0; k < sim->wall_count; k++) {
        const int id = sim->id[k], i = b->of_wall[id];
        if (i < 0)
            continue;
        double rx, ry;
        rotated_offset(b, id, b->cos_angle[i], b->sin_angle[i], &rx, &ry);
        double x = b->x[i] + rx;
        if (period > 0) {
            /* the periodic image nearest the particle's neighbour-list build position, so that the lists' images
             * hold (neighbours.c); before the lists exist, wrapped into the period */
            const double *x_build = sim->neighbours.x_build;
            x -= x_build ? period * round((x - x_build[k]) / period) : period * floor(x / period);
            if (!x_build && x >= period)
                x = 0;
        }
        sim->x[k] = x;
        sim->y[k] = b->y[i] + ry;
        sim->vx[k] = (real)(b->vx[i] - b->omega[i] * ry);
        sim->vy[k] = (real)(b->vy[i] + b->omega[i] * rx);
        ghost_offset(b, i, rx, ry, &sim->ghost_dx[k], &sim->ghost_dy[k]);
    }
}

void boulders_ghost_offset(const surge_sim *sim, int k, double angle, real *gdx, real *gdy)
{
    const boulder_set *b = &sim->boulders;
    const int id = sim->id[k], i = b->of_wall[id];
    double rx, ry;
    disc_offset(b, id, angle, &rx, &ry);
    ghost_offset(b, i, rx, ry, gdx, gdy);
}

void boulders_surface_velocity(const surge_sim *sim, int k, double *vx, double *vy)
{
    const boulder_set *b = &sim->boulders;
    const int id = sim->id[k], i = b->of_wall[id];
    double rx, ry;
    rotated_offset(b, id, b->cos_angle[i], b->sin_angle[i], &rx, &ry);
    const double to_surface = b->radius[i] / sqrt(rx * rx + ry * ry);
    *vx = b->vx[i] - b->omega[i] * ry * to_surface;
    *vy = b->vy[i] + b->omega[i] * rx * to_surface;
}

/* eq. 10: the force on each disc particle is minus the pair forces it exerts on its fluid neighbours
 * (the terms of interaction.c's wall loop), so momentum is exchanged exactly.
 * The viscous pair force (Lo & Shao) is the Laplacian form: it carries the traction mu (grad v) n, not
 * mu (grad v + grad v^T) n. On a no-slip rigid surface the missing part is -mu omega x n: no net force on a
 * closed surface, but a torque -mu omega (r . n) per unit area of wetted surface, -2 mu A omega on a wholly
 * wetted disc of area A (half the torque on a spinning disc). It is added here over the outer ring, each
 * particle weighted by how wetted its ghost node is.
 * A uniform pressure exerts no force on a closed surface, but the discrete sum of (p_a + p_k) grad W around a disc
 * is not zero on an irregular arrangement: reference_pa[disc] is subtracted from the pressures, where given (the
 * implicit scheme's pressure in a closed domain carries an arbitrary constant). */
void boulders_fluid_forces(surge_sim *sim, const double *reference_pa)
{
    boulder_set *b = &sim->boulders;
    if (b->count == 0)
        return;
    const neighbour_lists *nl = &sim->neighbours;
    const real grad_coef = sim->kernel.grad_coef, inv_h = sim->kernel.inv_h;
    const real mass = (real)sim->mass, eta2 = (real)sim->eta2, support2 = sim->kernel.support2;
    const real four_nu = (real)(4.0 * sim->params.fluid.viscosity_m2ps);
    const real *restrict rho = sim->rho, *restrict inv_rho = sim->inv_rho, *restrict pres = sim->pressure;
    const pair_state *restrict st = sim->pair_state;
    real *restrict fx = sim->ax, *restrict fy = sim->ay; /* wall entries are free scratch */
    #pragma omp parallel for schedule(static)
    for (int k = 0; k < sim->wall_count; k++) {
        fx[k] = fy[k] = 0;
        if (b->of_wall[sim->id[k]] < 0)
            continue;
        const real mxk = nl->moved_x[k], myk = nl->moved_y[k], rhok = rho[k], pk = pres[k], inv_rhok = inv_rho[k];
        const real wall_vx = sim->wall_vx[k], wall_vy = sim->wall_vy[k];
        const real reference = reference_pa ? (real)reference_pa[b->of_wall[sim->id[k]]] : 0;
        const int32_t *restrict index = nl->wall_fluid_index;
        const real *restrict dx0 = nl->wall_fluid_dx0, *restrict dy0 = nl->wall_fluid_dy0;
        /* one partial sum per lane over the padded list, fluid records transposed (as in interaction.c) */
        real sum_x[PAIR_LANES] = {0}, sum_y[PAIR_LANES] = {0}, sum_viscous[PAIR_LANES] = {0};
        for (int64_t e0 = nl->wall_fluid_first[k]; e0 < nl->wall_fluid_first[k + 1]; e0 += PAIR_LANES) {
            lanes_vector field[PAIR_LANES];
            lanes_gather_records(st, index + e0, field); /* field[q][l]: lane l's fluid neighbour's q-th field (pair_state) */
            #pragma omp simd simdlen(PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int64_t e = e0 + l;
                /* r_a - r_k, as the fluid's wall loop has it (interaction.c) */
                const real dx = -(dx0[e] + (mxk - field[0][l])), dy = -(dy0[e] + (myk - field[1][l]));
                const real r2 = dx * dx + dy * dy;
                const real f = r2 < support2 ? kernel2d_grad_factor_inside(grad_coef, inv_h, REAL_SQRT(r2)) : 0;
                /* the terms of the fluid particle a's acceleration by k (interaction.c's wall loop); none beyond 2h */
                const real pressure_coef = pair_pressure_coef(mass, field[6][l] - reference, pk - reference, field[5][l],
                                                              inv_rhok);
                const real inv_denominator = pair_viscous_denominator(field[4][l], rhok, r2, eta2);
                const real viscous_coef = pair_viscous_coef(mass, four_nu, f, r2, inv_denominator);
                sum_x[l] += pair_acceleration(pressure_coef, f, dx, viscous_coef, field[2][l] - wall_vx);
                sum_y[l] += pair_acceleration(pressure_coef, f, dy, viscous_coef, field[3][l] - wall_vy);
                sum_viscous[l] += viscous_coef;
            }
        }
        const real zero[PAIR_LANES] = {0};
        const real *const lanes[8] = {sum_x, sum_y, sum_viscous, zero, zero, zero, zero, zero};
        real total[8];
        lanes_totals(lanes, total);
        fx[k] = -mass * total[0];
        fy[k] = -mass * total[1];
        b->spin_coupling[k] = total[2];
    }
    for (int i = 0; i < b->count; i++) {
        b->fx[i] = b->fy[i] = b->torque[i] = b->spin_damping[i] = b->drag_stiffness[i] = 0;
        b->omega_forces[i] = b->omega[i];
    }
    const double mu = sim->rho0 * sim->params.fluid.viscosity_m2ps, dp = sim->params.numerics.dp_m;
    boulders_orient(b);
    for (int k = 0; k < sim->wall_count; k++) { /* in index order: the same sums whatever the thread count */
        const int id = sim->id[k], i = b->of_wall[id];
        if (i < 0)
            continue;
        double rx, ry;
        rotated_offset(b, id, b->cos_angle[i], b->sin_angle[i], &rx, &ry);
        b->fx[i] += fx[k];
        b->fy[i] += fy[k];
        b->torque[i] += rx * fy[k] - ry * fx[k];
        /* stiffness: the no-slip velocity 2 v_surface - v_ghost moves by 2 R per unit omega */
        const double lever = sqrt(rx * rx + ry * ry);
        b->spin_damping[i] -= 2 * sim->mass * b->radius[i] * lever * b->spin_coupling[k];
        b->drag_stiffness[i] -= 2 * sim->mass * b->spin_coupling[k];
        if (lever > b->radius[i] - dp) { /* outer ring; r . n = radius */
            const double a = b->radius[i], arc = 2 * SURGE_PI * a / ring_particles(a, dp, 0);
            const double wetted = fmin(1.0, (double)sim->ghost_fluid_sum[k]);
            b->torque[i] -= mu * b->omega[i] * a * arc * wetted;
            b->spin_damping[i] += mu * a * arc * wetted;
        }
    }
    for (int i = 0; i < b->count; i++)
        b->spin_damping[i] *= b->inv_inertia[i];
    /* the reaction to the face repulsion of fluid particles too close to a disc (interaction.c); radial, no torque */
    for (int a = sim->wall_count; a < sim->count; a++)
        if (sim->face_disc[a] >= 0) {
            b->fx[sim->face_disc[a]] -= sim->mass * sim->face_push_x[a];
            b->fy[sim->face_disc[a]] -= sim->mass * sim->face_push_y[a];
        }
}

/* disc i's state at the step's start: kept, and taken back */
static inline void save_step_start(boulder_set *b, int i)
{
    b->x_n[i] = b->x[i], b->y_n[i] = b->y[i], b->angle_n[i] = b->angle[i];
    b->vx_n[i] = b->vx[i], b->vy_n[i] = b->vy[i], b->omega_n[i] = b->omega[i];
}

static inline void restore_step_start(boulder_set *b, int i)
{
    b->x[i] = b->x_n[i], b->y[i] = b->y_n[i], b->angle[i] = b->angle_n[i];
    b->vx[i] = b->vx_n[i], b->vy[i] = b->vy_n[i], b->omega[i] = b->omega_n[i];
}

void boulders_wetted_fraction(surge_sim *sim, const real *wetness)
{
    boulder_set *b = &sim->boulders;
    const double dp = sim->params.numerics.dp_m;
    for (int i = 0; i < b->count; i++)
        b->wetted[i] = 0;
    for (int k = 0; k < sim->wall_count; k++) { /* in index order: the same sums whatever the thread count */
        const int id = sim->id[k], i = b->of_wall[id];
        if (i >= 0 && hypot(b->local_x[id], b->local_y[id]) > b->radius[i] - dp) /* the outer ring */
            b->wetted[i] += wetness[k] / ring_particles(b->radius[i], dp, 0);
    }
}

void boulders_predict(surge_sim *sim, double half_dt_s)
{
    boulder_set *b = &sim->boulders;
    const double period = sim->grid.period_m;
    const double gx = sim->gx - sim->params.body.force_x_mps2, gy = sim->gy;
    const double force_x = sim->params.body.force_x_mps2 / sim->params.boulders.density_ratio;
    for (int i = 0; i < b->count; i++) {
        save_step_start(b, i);
        b->x[i] += half_dt_s * b->vx[i];
        if (period > 0)
            b->x[i] -= period * floor(b->x[i] / period);
        b->y[i] += half_dt_s * b->vy[i];
        b->angle[i] += half_dt_s * b->omega[i];
        b->vx[i] += half_dt_s * (b->fx[i] * b->inv_mass[i] + gx + force_x);
        b->vy[i] += half_dt_s * (b->fy[i] * b->inv_mass[i] + gy);
        /* the viscous torque's linear part in omega implicitly (spin_damping) */
        b->omega[i] = (b->omega[i] + half_dt_s * (b->torque[i] * b->inv_inertia[i] +
                                                   b->spin_damping[i] * b->omega_forces[i])) /
                      (1 + half_dt_s * b->spin_damping[i]);
    }
    boulders_place_particles(sim);
}

void boulders_restore(surge_sim *sim)
{
    boulder_set *b = &sim->boulders;
    for (int i = 0; i < b->count; i++)
        restore_step_start(b, i);
    boulders_place_particles(sim);
}

void boulders_restore_implicit(surge_sim *sim)
{
    boulder_set *b = &sim->boulders;
    for (int i = 0; i < b->count; i++)
        b->step_ax[i] = b->step_ax_n[i], b->step_ay[i] = b->step_ay_n[i];
    boulders_restore(sim);
}

/* The walls discs can touch: the bed (moving with the belt), the lid, the box sides and the upstream wall; planes
 * stand half the contact margin in front of the wall faces (the discs' contact radii carry the other half). The
 * upstream wall is a slab as thick as its particle layers, its front, back and top half the margin out: a disc
 * that went round the periodic channel meets its back face, not its particles (the 60-disc surge of
 * docs/validation/debris_surge.md). The disc catcher is a line at the end of the period, x = length (= 0), from the
 * bed to the domain's top: a disc that rolled off the front stops there, short of the wall's back. */
#define CONTACT_WALLS_MAX 8
static int contact_walls(const surge_sim *sim, contact_wall walls[CONTACT_WALLS_MAX])
{
    const surge_params *p = &sim->params;
    const double half_margin = 0.5 * p->contacts.margin_dp * p->numerics.dp_m;
    int n = 0;
    if (p->walls.bottom)
        walls[n++] = (contact_wall){CONTACT_PLANE, 0, 1, half_margin, 0, 0, 0, 0, sim->wall_speed[WALL_BOTTOM], 0};
    if (p->walls.top)
        walls[n++] = (contact_wall){CONTACT_PLANE, 0, -1, -p->domain.height_m + half_margin, 0, 0, 0, 0,
                                    sim->wall_speed[WALL_TOP], 0};
    if (p->walls.left)
        walls[n++] = (contact_wall){CONTACT_PLANE, 1, 0, half_margin, 0, 0, 0, 0, 0, 0};
    if (p->walls.right)
        walls[n++] = (contact_wall){CONTACT_PLANE, -1, 0, -p->domain.length_m + half_margin, 0, 0, 0, 0, 0, 0};
    if (p->walls.upstream) {
        const double front_m = p->walls.upstream_x_m + half_margin;
        const double back_m = scene_upstream_back_m(p) - half_margin;
        const double top_m = p->walls.upstream_height_m + half_margin;
        walls[n++] = (contact_wall){CONTACT_SEGMENT, 0, 0, 0, front_m, 0, front_m, top_m, 0, 0};
        walls[n++] = (contact_wall){CONTACT_SEGMENT, 0, 0, 0, back_m, 0, back_m, top_m, 0, 0};
        walls[n++] = (contact_wall){CONTACT_SEGMENT, 0, 0, 0, back_m, top_m, front_m, top_m, 0, 0};
    }
    if (p->walls.disc_catcher) {
        const double end_m = p->domain.length_m;
        walls[n++] = (contact_wall){CONTACT_SEGMENT, 0, 0, 0, end_m, 0, end_m, p->domain.height_m, 0, 0};
    }
    return n;
}

/* The discs' full step from the start, through the contact solver's sub-steps, from the accelerations in ax, ay,
 * alpha; the disc particles follow. -1 when the contact solver runs out of memory. */
static int advance_with_contacts(surge_sim *sim, double dt_s)
{
    boulder_set *b = &sim->boulders;
    const surge_params *p = &sim->params;
    contact_wall walls[CONTACT_WALLS_MAX];
    const int wall_count = contact_walls(sim, walls);
    contact_discs discs = {b->count, b->x, b->y, b->angle, b->vx, b->vy, b->omega, b->contact_radius, b->inv_mass,
                           b->inv_inertia, b->spin_damping};
    const contact_settings settings = {p->contacts.friction, p->contacts.restitution, p->contacts.restitution_min_mps,
                                       p->contacts.substeps, p->contacts.iterations, p->contacts.erp,
                                       sim->grid.period_m};
    if (contact_solver_advance(b->contacts, &discs, walls, wall_count, &settings, dt_s, b->ax, b->ay, b->alpha) != 0)
        return -1;
    boulders_place_particles(sim);
    return 0;
}

/* A disc's acceleration without the fluid: gravity on its mass; the driving force of a channel (a pressure
 * gradient) on its volume */
static void own_acceleration(const surge_sim *sim, double *gx, double *gy)
{
    const surge_params *p = &sim->params;
    *gx = sim->gx - p->body.force_x_mps2 + p->body.force_x_mps2 / p->boulders.density_ratio;
    *gy = sim->gy;
}

int boulders_correct(surge_sim *sim, double dt_s)
{
    boulder_set *b = &sim->boulders;
    double gx, gy;
    own_acceleration(sim, &gx, &gy);
    for (int i = 0; i < b->count; i++) {
        restore_step_start(b, i);
        b->ax[i] = b->fx[i] * b->inv_mass[i] + gx;
        b->ay[i] = b->fy[i] * b->inv_mass[i] + gy;
        b->alpha[i] = b->torque[i] * b->inv_inertia[i] + b->spin_damping[i] * b->omega_forces[i];
    }
    return advance_with_contacts(sim, dt_s);
}

/* The implicit scheme's disc step (docs/method.md, "Boulders in the implicit scheme"). The fluid forces come from a
 * fluid step that saw the discs at their velocity at the step's start, so the fluid's answer to a disc's change of
 * velocity lags a step. Its added mass m_a answers the last step's acceleration, m a_n+1 = F - m_a a_n, which grows
 * when m_a > m (a disc lighter than the fluid); its drag c answers the velocity, m a_n+1 = F* - c v_n, which
 * overshoots when c dt > 2 m (a step longer than the disc's drag time). The disc is stepped with
 * (m + m~ + k dt) a_n+1 = F + m g + m~ a_n: the same steady answer; the added mass's lag factor (m~ - m_a) / (m + m~),
 * below 1 in size for m_a < m + 2 m~; the drag as backward Euler, F(v_n+1) = F - k (v_n+1 - v_n), stable for
 * k > c / 2. m~ = added_mass rho0 pi r^2 of wetted disc; k, the drag with the fluid held still
 * (boulders_fluid_forces): 1.2-1.3 c at 5 particles a radius, more at finer ones (slower to settle, not unstable). */
int boulders_advance_implicit(surge_sim *sim, double dt_s, double added_mass)
{
    boulder_set *b = &sim->boulders;
    double gx, gy;
    own_acceleration(sim, &gx, &gy);
    for (int i = 0; i < b->count; i++) {
        save_step_start(b, i);
        const double mass = b->mass[i];
        const double extra = added_mass * sim->rho0 * SURGE_PI * b->radius[i] * b->radius[i] * b->wetted[i];
        const double inertia = mass + extra + b->drag_stiffness[i] * dt_s;
        b->ax[i] = (b->fx[i] + mass * gx + extra * b->step_ax[i]) / inertia;
        b->ay[i] = (b->fy[i] + mass * gy + extra * b->step_ay[i]) / inertia;
        b->alpha[i] = b->torque[i] * b->inv_inertia[i] + b->spin_damping[i] * b->omega_forces[i];
    }
    if (advance_with_contacts(sim, dt_s) != 0)
        return -1;
    for (int i = 0; i < b->count; i++) {
        b->step_ax_n[i] = b->step_ax[i], b->step_ay_n[i] = b->step_ay[i];
        b->step_ax[i] = (b->vx[i] - b->vx_n[i]) / dt_s;
        b->step_ay[i] = (b->vy[i] - b->vy_n[i]) / dt_s;
    }
    return 0;
}
