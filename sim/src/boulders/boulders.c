/* Boulders: rigid discs made of boundary particles (GMD Sect. 2.2). Each disc is rings of wall particles at
 * the fluid spacing, as deep as the kernel support, with mDBC ghost nodes mirrored across its circle. This file
 * defines the discs (a list, a random placement, or the graded placement and file of boulder_scene.c) and their
 * particles; disc_motion.c moves them rigidly (eq. 11), fluid_forces.c sums the fluid's forces on them (eq. 10), and
 * each time-stepping scheme steps them in its own folder. */
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
#define ALLOC_DISC(name, meaning) ok &= (b->name = calloc((size_t)(n > 0 ? n : 1), sizeof(double))) != NULL;
#define ALLOC_DISC_COPY(name, meaning) ok &= (b->name##_n = calloc((size_t)(n > 0 ? n : 1), sizeof(double))) != NULL;
    SURGE_DISC_STEP_FIELDS(ALLOC_DISC)
    SURGE_DISC_STEP_FIELDS(ALLOC_DISC_COPY)
    SURGE_DISC_FIELDS(ALLOC_DISC)
#undef ALLOC_DISC
#undef ALLOC_DISC_COPY
    if (!ok)
        return -1;
    for (int i = 0; i < n; i++) /* not known before a first step */
        b->step_fluid_fx[i] = b->step_fluid_fy[i] = b->step_film_fx[i] = b->step_film_fy[i] =
            b->step_wall_contact_fx[i] = b->step_wall_contact_fy[i] = b->step_disc_contact_fx[i] =
                b->step_disc_contact_fy[i] = NAN;
    return 0;
}

int boulders_allocate_wall_fields(boulder_set *b, int wall_count)
{
    int ok = 1;
#define ALLOC_WALL(name, type, meaning) ok &= (b->name = calloc((size_t)(wall_count > 0 ? wall_count : 1), sizeof(type))) != NULL;
    SURGE_WALL_DISC_FIELDS(ALLOC_WALL)
#undef ALLOC_WALL
    ok &= (b->by_disc_first = calloc((size_t)b->count + 1, sizeof *b->by_disc_first)) != NULL;
    return ok ? 0 : -1;
}

void boulders_free(boulder_set *b)
{
#define FREE_DISC(name, meaning) free(b->name);
#define FREE_DISC_COPY(name, meaning) free(b->name##_n);
#define FREE_WALL(name, type, meaning) free(b->name);
    SURGE_DISC_STEP_FIELDS(FREE_DISC)
    SURGE_DISC_STEP_FIELDS(FREE_DISC_COPY)
    SURGE_DISC_FIELDS(FREE_DISC)
    SURGE_WALL_DISC_FIELDS(FREE_WALL)
    free(b->by_disc_first);
#undef FREE_DISC
#undef FREE_DISC_COPY
#undef FREE_WALL
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
        double v[6];
        int got = 0;
        const size_t len = strcspn(cursor, ",");
        char entry[SURGE_TEXT_PARAM_BYTES];
        memcpy(entry, cursor, len);
        entry[len] = '\0';
        char *s = entry;
        for (;;) { /* every number counted, the first six kept */
            while (isspace((unsigned char)*s))
                s++;
            if (!*s)
                break;
            char *end;
            const double value = strtod(s, &end);
            if (end == s && !isprint((unsigned char)*s)) {
                snprintf(err, err_len, "boulders.list_m: disc %d: character 0x%02x is not part of a number", i + 1,
                         (unsigned char)*s);
                return -1;
            }
            if (end == s || !isfinite(value)) {
                snprintf(err, err_len, "boulders.list_m: disc %d ('%s'): '%s' is not a number", i + 1, entry, s);
                return -1;
            }
            if (got < 6)
                v[got] = value;
            got++;
            s = end;
        }
        if (got != 3 && got != 6) {
            snprintf(err, err_len, "boulders.list_m: disc %d ('%s') has %d numbers; expected 'x y r' or "
                     "'x y r vx vy omega'%s", i + 1, entry, got,
                     got > 6 ? " (discs are separated by commas)" : "");
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

int boulders_ring_particles(double r, double dp, int ring)
{
    const int n = (int)lround(2 * SURGE_PI * (r - (ring + 0.5) * dp) / dp);
    return n > 1 ? n : 1;
}

int boulders_particles_of(const surge_sim *sim, int disc)
{
    const double dp = sim->params.numerics.dp_m, radius = sim->boulders.radius[disc];
    int n = 0;
    for (int q = 0; q < ring_count(radius, dp, sim->params.walls.layers); q++)
        n += boulders_ring_particles(radius, dp, q);
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
            const int per_ring = boulders_ring_particles(b->radius[i], dp, q);
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

/* Distance (m) from (x, y) to the nearest wall face of the domain on the fluid's side (the bed, the lid, the side
 * walls, the upstream wall's face below its top); INFINITY without walls */
double boulders_wall_face_distance_m(const surge_params *p, double x, double y)
{
    double d = INFINITY;
    if (p->walls.bottom)
        d = fmin(d, y);
    if (p->walls.top)
        d = fmin(d, p->domain.height_m - y);
    if (p->walls.left && !p->domain.periodic_x)
        d = fmin(d, x);
    if (p->walls.right && !p->domain.periodic_x)
        d = fmin(d, p->domain.length_m - x);
    if (p->walls.upstream && y < p->walls.upstream_height_m && x > p->walls.upstream_x_m)
        d = fmin(d, x - p->walls.upstream_x_m);
    return d;
}

/* Whether any fluid particle lies within reach_m of disc i's surface (periodic in x where the domain is); a scan of the
 * fluid that stops at the first, asked only of discs whose surface outruns every fluid particle */
int boulders_fluid_within(const surge_sim *sim, int i, double reach_m)
{
    const boulder_set *b = &sim->boulders;
    const double period = sim->params.domain.periodic_x ? sim->params.domain.length_m : 0;
    const double reach2 = (b->radius[i] + reach_m) * (b->radius[i] + reach_m);
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double dx = placement_wrap_dx(sim->x[a] - b->x[i], period), dy = sim->y[a] - b->y[i];
        if (dx * dx + dy * dy < reach2)
            return 1;
    }
    return 0;
}

/* A fluid site is covered within a quarter spacing of a disc's surface (inside it where the fluid is packed,
 * boulders.pack_fluid: scene/packing.c moves the sites near the surface out), and where the disc leaves less room
 * between its surface and the next face (another disc, a wall) than twice the scheme's contact distance: a particle
 * there would sit closer to both faces than that distance, and each face's contact rule would push it into the other
 * (a disc a third of a spacing under the lid of the loaded channel squeezed such a particle to 1.14 rho0 in two
 * implicit steps). The quarter spacing leaves the fluid 0.25 dp times the discs' perimeter short, 0.5 phi / ((r/dp)
 * (1 - phi)) of its room: 12.5 % in the loaded channel at phi 0.5 and r/dp 4 */
int boulders_cover(const surge_sim *sim, double x, double y)
{
    const boulder_set *b = &sim->boulders;
    const double period = sim->params.domain.periodic_x ? sim->params.domain.length_m : 0;
    const double dp = sim->params.numerics.dp_m;
    const double clearance = sim->params.boulders.pack_fluid ? 0.0 : 0.25 * dp;
    double nearest_m = INFINITY, second_m = INFINITY; /* distances to the two nearest disc surfaces */
    for (int i = 0; i < b->count; i++) {
        const double dx = placement_wrap_dx(x - b->x[i], period), dy = y - b->y[i];
        const double surface_m = sqrt(dx * dx + dy * dy) - b->radius[i];
        if (surface_m < clearance)
            return 1;
        if (sim->narrow_gap_sites)
            continue;
        if (surface_m < nearest_m)
            second_m = nearest_m, nearest_m = surface_m;
        else if (surface_m < second_m)
            second_m = surface_m;
    }
    return boulders_room_too_narrow(sim, x, y, nearest_m, second_m);
}

int boulders_room_too_narrow(const surge_sim *sim, double x, double y, double nearest_m, double second_m)
{
    const double room_m = 2.0 * sim_contact_reach_m(sim);
    return nearest_m < room_m && nearest_m + fmin(second_m, boulders_wall_face_distance_m(&sim->params, x, y)) < room_m;
}
