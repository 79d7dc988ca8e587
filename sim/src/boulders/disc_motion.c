/* How discs move: their particles follow them rigidly (eq. 11: u_k = V + Omega x (r_k - R0), the ghost nodes
 * mirrored across the circle), their state at a step's start is kept and taken back, and a step moves them through
 * the contact solver's sub-steps. The schemes decide the accelerations (scheme/explicit/explicit_discs.c,
 * scheme/implicit/implicit_discs.c). */
#include <math.h>
#include <string.h>

#include "sim_internal.h"
#include "boulders/boulders.h"
#include "scene/scales.h"

/* The offset of the disc particle with id from its disc's centre at the given angle */
static inline void disc_offset(const boulder_set *b, int id, double angle, double *rx, double *ry)
{
    boulders_rotated_offset(b, id, cos(angle), sin(angle), rx, ry);
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

/* The disc particles' wall indices in ascending order (in_order) and by disc (by_disc, a counting sort, ascending within
 * each disc: a loop over one disc's particles adds in the order a loop over all walls would) */
void boulders_index_particles(surge_sim *sim)
{
    boulder_set *b = &sim->boulders;
    if (b->count == 0)
        return;
    int32_t *first = b->by_disc_first;
    memset(first, 0, ((size_t)b->count + 1) * sizeof *first);
    for (int k = 0; k < sim->wall_count; k++) {
        const int i = b->of_wall[sim->id[k]];
        if (i >= 0)
            first[i + 1]++;
    }
    for (int i = 0; i < b->count; i++)
        first[i + 1] += first[i];
    int n = 0;
    for (int k = 0; k < sim->wall_count; k++) {
        const int i = b->of_wall[sim->id[k]];
        if (i >= 0)
            b->by_disc[first[i]++] = k, b->in_order[n++] = k;
    }
    for (int i = b->count; i > 0; i--) /* first[i] now holds the end of disc i: shift back to beginnings */
        first[i] = first[i - 1];
    first[0] = 0;
}

void boulders_place_particles(surge_sim *sim)
{
    const boulder_set *b = &sim->boulders;
    if (b->count == 0)
        return;
    const double period = sim->grid.period_m;
    boulders_orient(b);
    #pragma omp parallel for schedule(static)
    for (int e = 0; e < b->by_disc_first[b->count]; e++) {
        const int k = b->in_order[e], id = sim->id[k], i = b->of_wall[id];
        double rx, ry;
        boulders_rotated_offset(b, id, b->cos_angle[i], b->sin_angle[i], &rx, &ry);
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
    boulders_rotated_offset(b, id, b->cos_angle[i], b->sin_angle[i], &rx, &ry);
    const double to_surface = b->radius[i] / sqrt(rx * rx + ry * ry);
    *vx = b->vx[i] - b->omega[i] * ry * to_surface;
    *vy = b->vy[i] + b->omega[i] * rx * to_surface;
}

/* disc i's state at the step's start: kept, and taken back */
void boulders_save_step_start(boulder_set *b, int i)
{
#define SAVE_DISC(name, meaning) b->name##_n[i] = b->name[i];
    SURGE_DISC_STEP_FIELDS(SAVE_DISC)
#undef SAVE_DISC
}

void boulders_restore_step_start(boulder_set *b, int i)
{
#define RESTORE_DISC(name, meaning) b->name[i] = b->name##_n[i];
    SURGE_DISC_STEP_FIELDS(RESTORE_DISC)
#undef RESTORE_DISC
}

void boulders_restore(surge_sim *sim)
{
    boulder_set *b = &sim->boulders;
    for (int i = 0; i < b->count; i++)
        boulders_restore_step_start(b, i);
    boulders_place_particles(sim);
}

/* The walls discs can touch: the bed (moving with the belt), the lid, the box sides and the upstream wall; planes
 * stand half the contact margin in front of the wall faces (the discs' contact radii carry the other half). The
 * upstream wall is a slab as thick as its particle layers, its front, back and top half the margin out: a disc
 * that went round the periodic channel meets its back face, not its particles (the 60-disc surge of
 * docs/validation/debris_surge.md). The disc catcher is a line at the end of the period, x = length (= 0), from the
 * bed to the domain's top: a disc that rolled off the front stops there, short of the wall's back. */
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

/* The contact solver's settings; with_lubrication 0: no film (a scheme that takes the films into its own solve) */
static contact_settings contact_settings_of(const surge_sim *sim, int with_lubrication)
{
    const surge_params *p = &sim->params;
    const double dp = p->numerics.dp_m;
    return (contact_settings){
        .friction = p->contacts.friction, .restitution = p->contacts.restitution,
        .restitution_min_mps = p->contacts.restitution_min_mps, .substeps = p->contacts.substeps,
        .iterations = p->contacts.iterations, .erp = p->contacts.erp, .period_m = sim->grid.period_m,
        .lubrication_viscosity_pa_s = with_lubrication && p->contacts.lubrication
                                          ? p->fluid.density_kgpm3 * p->fluid.viscosity_m2ps : 0,
        .lubrication_cutoff_m = p->contacts.lubrication_cutoff_dp * dp,
        .lubrication_min_gap_m = p->contacts.lubrication_min_gap_dp * dp, .gap_offset_m = p->contacts.margin_dp * dp,
        .lubrication_kernel_h_m =
            p->contacts.lubrication_resolved == SURGE_LUBRICATION_MEASURED ? sim->derived.h_m : 0,
        .lubrication_share = sim->film_share,
        .lubrication_tangential_reynolds = p->contacts.lubrication_tangential == SURGE_TANGENTIAL_REYNOLDS};
}

static contact_discs contact_discs_of(boulder_set *b)
{
    return (contact_discs){b->count, b->x, b->y, b->angle, b->vx, b->vy, b->omega, b->contact_radius, b->inv_mass,
                           b->inv_inertia, b->spin_damping, b->step_wall_contact_fx, b->step_wall_contact_fy,
                           b->step_disc_contact_fx, b->step_disc_contact_fy};
}

/* The step's mean forces on each disc (boulder_set's step_ fields), from its accelerations without contacts (ax, ay),
 * its velocity at the step's start (the _n copies) and now, and the contact solver's impulses in the contact fields:
 * m dv/dt = m g' + fluid + films + contacts, g' the disc's own acceleration (gravity, a channel's drive) */
static void step_forces(surge_sim *sim, double dt_s)
{
    boulder_set *b = &sim->boulders;
    double gx, gy;
    boulders_own_acceleration(sim, &gx, &gy);
    for (int i = 0; i < b->count; i++) {
        b->step_wall_contact_fx[i] /= dt_s, b->step_wall_contact_fy[i] /= dt_s;
        b->step_disc_contact_fx[i] /= dt_s, b->step_disc_contact_fy[i] /= dt_s;
        const double m = b->mass[i];
        b->step_fluid_fx[i] = m * (b->ax[i] - gx);
        b->step_fluid_fy[i] = m * (b->ay[i] - gy);
        b->step_film_fx[i] = m * ((b->vx[i] - b->vx_n[i]) / dt_s - b->ax[i]) - b->step_wall_contact_fx[i] -
                             b->step_disc_contact_fx[i];
        b->step_film_fy[i] = m * ((b->vy[i] - b->vy_n[i]) / dt_s - b->ay[i]) - b->step_wall_contact_fy[i] -
                             b->step_disc_contact_fy[i];
    }
}

/* The discs' full step from the start, through the contact solver's sub-steps, from the accelerations in ax, ay,
 * alpha; the disc particles follow. -1 when the contact solver runs out of memory. The time since the caller's last
 * phase mark (its accelerations) is the discs' phase, the solver's sub-steps the contacts'. */
int boulders_advance_with_contacts(surge_sim *sim, double dt_s, int with_lubrication)
{
    boulder_set *b = &sim->boulders;
    contact_wall walls[CONTACT_WALLS_MAX];
    const int wall_count = contact_walls(sim, walls);
    contact_discs discs = contact_discs_of(b);
    const contact_settings settings = contact_settings_of(sim, with_lubrication);
    phase_end(sim, &sim->phase_times.discs_s);
    const int advanced = contact_solver_advance(b->contacts, &discs, walls, wall_count, &settings, dt_s, b->ax, b->ay,
                                                b->alpha);
    phase_end(sim, &sim->phase_times.contacts_s);
    if (advanced != 0)
        return -1;
    step_forces(sim, dt_s);
    boulders_place_particles(sim);
    phase_end(sim, &sim->phase_times.discs_s);
    return 0;
}

void boulders_add_contact_impulses(const surge_sim *sim, surge_contact_impulses *sum)
{
    const contact_stats last = contact_solver_stats(sim->boulders.contacts);
    const int bed = sim->params.walls.bottom ? 0 : -1; /* contact_walls puts the bed first */
    for (int w = 0; w < CONTACT_WALLS_MAX; w++) {
        *(w == bed ? &sum->bed_normal_nspm : &sum->wall_normal_nspm) += last.wall_normal_impulse[w];
        *(w == bed ? &sum->bed_friction_nspm : &sum->wall_friction_nspm) += last.wall_friction_impulse[w];
    }
    sum->disc_normal_nspm += last.disc_normal_impulse;
    sum->disc_friction_nspm += last.disc_friction_impulse;
}

int boulders_films(surge_sim *sim, contact_film **films, int *count, int *capacity)
{
    boulder_set *b = &sim->boulders;
    contact_wall walls[CONTACT_WALLS_MAX];
    const int wall_count = contact_walls(sim, walls);
    const contact_discs discs = contact_discs_of(b);
    const contact_settings settings = contact_settings_of(sim, 1);
    return contact_solver_films(b->contacts, &discs, walls, wall_count, &settings, films, count, capacity);
}

/* A disc's acceleration without the fluid: gravity on its mass; the driving force of a channel (a pressure
 * gradient) on its volume */
void boulders_own_acceleration(const surge_sim *sim, double *gx, double *gy)
{
    const surge_params *p = &sim->params;
    *gx = sim->gx - p->body.force_x_mps2 + p->body.force_x_mps2 / p->boulders.density_ratio;
    *gy = sim->gy;
}
