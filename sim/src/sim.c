/* The solver's public interface: scene set-up, the time-stepping scheme (scheme/scheme.h), snapshots, diagnostics and
 * the state hash. */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "physics/eos.h"
#include "sim_internal.h"
#include "scene/scales.h"
#include "boulders/boulders.h"
#include "boundaries/boundary.h"
#include "neighbours/grid.h"
#include "neighbours/neighbours.h"
#include "scene/scene.h"

/* sum_b dp^2 W(r_ab) over a square lattice of spacing dp, the particle itself included: the kernel sum of an
 * incompressible fluid on that lattice is rho0 times this (1.001 at C_h 1.5, 1.006 at C_h 1.0), not rho0 */
static double lattice_kernel_sum(const kernel2d *k, double dp, int rows_above)
{
    const int reach = (int)ceil(2.0 * k->h / dp);
    double sum = 0;
    for (int i = -reach; i <= reach; i++)
        for (int j = -reach; j <= (rows_above < reach ? rows_above : reach); j++)
            sum += dp * dp * kernel2d_w(k, (real)(dp * sqrt((double)(i * i + j * j))));
    return sum;
}

static void update_body_force(surge_sim *sim)
{
    const surge_params *p = &sim->params;
    const double theta = p->body.slope_deg * SURGE_PI / 180.0;
    scene_body_acceleration(p, &sim->gx, &sim->gy);
    /* hydrostatic density difference per metre along the bed normal, linearised Tait (rho0 g_n / c0^2) */
    sim->rho_h_per_m = sim->rho0 * p->body.gravity_mps2 * cos(theta) / (sim->derived.c0_mps * sim->derived.c0_mps);
}

surge_sim *surge_sim_create(const surge_params *params, char *err, size_t err_len)
{
    return sim_create_checked(params, NULL, NULL, 0, err, err_len);
}

surge_sim *sim_create_checked(const surge_params *params,
                              int (*check)(const surge_sim *sim, long long walls, long long fluid, void *user,
                                           char *err, size_t err_len),
                              void *user, int narrow_gap_sites, char *err, size_t err_len)
{
    if (surge_params_validate(params, err, err_len) != 0)
        return NULL;
    surge_sim *sim = calloc(1, sizeof *sim);
    if (!sim) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    sim->scene_check = check;
    sim->scene_check_user = user;
    sim->narrow_gap_sites = narrow_gap_sites;
    sim->params = *params;
    sim->params.walls.layers = surge_params_wall_layers(params); /* resolve the automatic value */
    const surge_params *p = &sim->params;
    sim->scheme = scheme_of(p);
    sim->film_share = film_share_of(p);
    const double dp = p->numerics.dp_m;
    sim->derived.h_m = p->numerics.ch * sqrt(2.0) * dp;
    sim->rho0 = p->fluid.density_kgpm3;
    /* the discs before c0: the smallest one's radius sets c0's viscous term */
    if (boulders_define(sim, err, err_len) != 0) {
        boulders_free(&sim->boulders);
        free(sim);
        return NULL;
    }
    sim->derived.smallest_boulder_radius_m = INFINITY;
    for (int i = 0; i < sim->boulders.count; i++)
        sim->derived.smallest_boulder_radius_m = fmin(sim->derived.smallest_boulder_radius_m, sim->boulders.radius[i]);
    sim->derived.expected_speed_mps = scene_expected_speed(p);
    /* c0: the case's, or c0_factor times the largest of the expected speed, the hydrostatic head's speed (at the
     * default factor 10 the head's term holds the hydrostatic density variation within 1 %) and, with discs, the
     * viscous speed (scene_viscous_speed) */
    sim->derived.head_c0_mps = p->numerics.c0_factor * scene_head_speed(p);
    sim->derived.viscous_c0_mps = p->numerics.c0_factor * scene_viscous_speed(p, sim->derived.expected_speed_mps,
                                                                               sim->derived.smallest_boulder_radius_m);
    sim->derived.c0_mps = p->numerics.c0_mps > 0 ? p->numerics.c0_mps
                                                : fmax(fmax(p->numerics.c0_factor * sim->derived.expected_speed_mps,
                                                            sim->derived.head_c0_mps),
                                                       sim->derived.viscous_c0_mps);
    if (!(sim->derived.c0_mps > 0)) {
        snprintf(err, err_len, "cannot derive c0: the scene has no gravity, body force or moving wall to set a speed "
                 "scale; set numerics.c0_mps");
        boulders_free(&sim->boulders);
        free(sim);
        return NULL;
    }
    sim->b_pa = sim->derived.c0_mps * sim->derived.c0_mps * sim->rho0 / 7.0;
    sim->mass = sim->rho0 * dp * dp;
    sim->derived.particle_mass_kg = sim->mass;
    sim->eta2 = 0.01 * sim->derived.h_m * sim->derived.h_m;
    sim->kernel = kernel2d_make(sim->derived.h_m);
    sim->lattice_kernel_sum = lattice_kernel_sum(&sim->kernel, dp, INT_MAX);
    sim->second_row_kernel_ratio = lattice_kernel_sum(&sim->kernel, dp, 1) / sim->lattice_kernel_sum;
    for (int k = 0; k < SURGE_KERNEL_ROWS; k++)
        sim->row_kernel_ratio[k] = lattice_kernel_sum(&sim->kernel, dp, k) / sim->lattice_kernel_sum;
    sim->list_lookahead_s = sim->scheme->lookahead_s(sim);
    update_body_force(sim);
    const int built = scene_build(sim, err, err_len);
    sim->scene_check = NULL;
    if (built != 0 || grid_init(sim, err, err_len) != 0 || neighbours_init(sim, err, err_len) != 0 ||
        scene_pack_fluid(sim, err, err_len) != 0) {
        surge_sim_destroy(sim);
        return NULL;
    }
    sim->derived.wall_count = sim->wall_count;
    sim->derived.fluid_count = sim->count - sim->wall_count;
    if (sim->scheme->create && sim->scheme->create(sim, err, err_len) != 0) {
        surge_sim_destroy(sim);
        return NULL;
    }
    sim->derived.boulder_count = sim->boulders.count;
    grid_sort_walls(sim);
    boulders_index_particles(sim);
    grid_sort_fluid(sim);
    boundary_wall_speeds(sim, 0.0);
    return sim;
}

void surge_sim_destroy(surge_sim *sim)
{
    if (!sim)
        return;
    fields_free(sim);
    free(sim->pack_interior);
    free(sim->sort_key);
    free(sim->sort_scratch_i);
    free(sim->sort_scratch_d);
    if (sim->scheme_data)
        sim->scheme->destroy(sim);
    grid_free(&sim->grid);
    neighbours_free(&sim->neighbours);
    boulders_free(&sim->boulders);
    free(sim);
}

int surge_sim_step(surge_sim *sim)
{
    const double start_s = omp_get_wtime();
    sim->phase_mark_s = start_s;
    const int rc = sim->scheme->step(sim);
    sim->phase_times.total_s += omp_get_wtime() - start_s;
    sim->phase_times.steps++;
    if (rc == 0 && sim->boulders.count > 0) /* a step with discs ends with one advance of the contact solver */
        boulders_add_contact_impulses(sim, &sim->contact_impulses);
    return rc;
}

surge_contact_impulses surge_sim_contact_impulses(const surge_sim *sim) { return sim->contact_impulses; }

void surge_sim_phase_times(const surge_sim *sim, surge_phase_times *times)
{
    const surge_phase_times *t = &sim->phase_times;
    *times = *t;
    const double named_s = t->neighbours_s + t->interaction_s + t->boundary_s + t->discs_s + t->contacts_s +
                           t->geometry_s + t->surface_s + t->assembly_s + t->multigrid_s + t->viscous_solve_s + t->pressure_solve_s +
                           t->disc_coupling_s + t->update_s;
    /* the phases are disjoint spans of each step: only rounding takes their sum past the total */
    times->other_s = fmax(0.0, t->total_s - named_s);
}

void surge_sim_reset_phase_times(surge_sim *sim)
{
    sim->phase_times = (surge_phase_times){0};
}

double surge_sim_time(const surge_sim *sim) { return sim->time_s; }
int64_t surge_sim_step_count(const surge_sim *sim) { return sim->step; }
double surge_sim_last_dt(const surge_sim *sim) { return sim->dt_s; }
const surge_params *surge_sim_params(const surge_sim *sim) { return &sim->params; }
const surge_derived *surge_sim_derived(const surge_sim *sim) { return &sim->derived; }
const surge_health *surge_sim_health(const surge_sim *sim) { return &sim->health; }

int surge_sim_set_param(surge_sim *sim, const char *name, const char *value, char *err, size_t err_len)
{
    const surge_param_info *info = surge_param_find(name);
    if (!info) {
        snprintf(err, err_len, "unknown parameter '%s'", name);
        return -1;
    }
    if (!info->live) {
        snprintf(err, err_len, "%s cannot change while the simulation runs", name);
        return -1;
    }
    surge_params candidate = sim->params;
    if (surge_param_set(&candidate, info, value, err, err_len) != 0 ||
        surge_params_validate(&candidate, err, err_len) != 0)
        return -1;
    /* a change that holds every later step below the collapse limit would stop the run at the next step */
    const double bound_s = sim->scheme->step_bound_s(sim, &candidate);
    const double collapse_s = candidate.health.min_dt_ratio * sim->first_dt_s;
    if (sim->first_dt_s > 0 && candidate.numerics.dt_fixed_s == 0 && !(bound_s >= collapse_s)) {
        snprintf(err, err_len, "%s = %s would hold the time step to at most %.3g s, below health.min_dt_ratio (%g) "
                 "times the first step (%.3g s): the run would stop on a collapsed time step", name, value, bound_s,
                 candidate.health.min_dt_ratio, sim->first_dt_s);
        return -1;
    }
    sim->params = candidate;
    sim->film_share = film_share_of(&sim->params);
    update_body_force(sim);
    return 0;
}

bool surge_sim_reports_solves(const surge_sim *sim) { return sim->scheme->reports_solves; }

void surge_sim_check_report(const surge_sim *sim, FILE *out, int verbose)
{
    /* list entries per fluid particle: the particles within 2h + the scheme's skin; 12 bytes each, about 200 bytes of
     * state */
    const double dp = sim->params.numerics.dp_m, reach = 2.0 * sim->derived.h_m + sim_neighbour_skin_m(sim);
    const double entries = SURGE_PI * reach * reach / (dp * dp);
    const double bytes = sim->derived.fluid_count * (12 * entries + 200) + sim->derived.wall_count * (6 * entries + 150);
    sim->scheme->check_report(sim, out, verbose, entries, bytes);
}

double surge_sim_expected_speed_mps(const surge_sim *sim) { return scene_expected_speed(&sim->params); }

int surge_sim_snapshot(const surge_sim *sim, surge_snapshot *snap)
{
    if (surge_snapshot_reserve(snap, sim->count) != 0)
        return -1;
    snap->step = sim->step;
    snap->time_s = sim->time_s;
    snap->dt_s = sim->dt_s;
    const real rho0 = (real)sim->rho0, b_pa = (real)sim->b_pa;
    const int solved_pressure = sim->scheme->incompressible;
    for (int i = 0; i < sim->count; i++) {
        const int k = sim->id[i];
        snap->x_m[k] = surge_sim_wrapped_x(sim, sim->x[i]);
        snap->y_m[k] = sim->y[i];
        snap->vx_mps[k] = (float)sim->vx[i];
        snap->vy_mps[k] = (float)sim->vy[i];
        snap->density_kgpm3[k] = (float)sim->rho[i];
        /* an incompressible scheme's pressure is its solve's (walls: their mirror), not the equation of state's */
        snap->pressure_pa[k] = solved_pressure ? (float)sim->pressure[i] : (float)tait_pressure(sim->rho[i], rho0, b_pa);
        snap->kind[k] = sim->kind[k];
        snap->id[k] = k;
    }
    const boulder_set *b = &sim->boulders;
    if (surge_snapshot_reserve_boulders(snap, b->count) != 0)
        return -1;
    for (int i = 0; i < b->count; i++) {
        snap->boulders.x_m[i] = b->x[i];
        snap->boulders.y_m[i] = b->y[i];
        snap->boulders.angle_rad[i] = b->angle[i];
        snap->boulders.vx_mps[i] = b->vx[i];
        snap->boulders.vy_mps[i] = b->vy[i];
        snap->boulders.omega_radps[i] = b->omega[i];
        snap->boulders.radius_m[i] = b->radius[i];
        snap->boulders.fluid_fx_npm[i] = b->step_fluid_fx[i];
        snap->boulders.fluid_fy_npm[i] = b->step_fluid_fy[i];
        snap->boulders.film_fx_npm[i] = b->step_film_fx[i];
        snap->boulders.film_fy_npm[i] = b->step_film_fy[i];
        snap->boulders.wall_contact_fx_npm[i] = b->step_wall_contact_fx[i];
        snap->boulders.wall_contact_fy_npm[i] = b->step_wall_contact_fy[i];
        snap->boulders.disc_contact_fx_npm[i] = b->step_disc_contact_fx[i];
        snap->boulders.disc_contact_fy_npm[i] = b->step_disc_contact_fy[i];
    }
    return 0;
}

surge_diagnostics surge_sim_diagnostics(const surge_sim *sim)
{
    surge_diagnostics d = {0};
    d.time_s = sim->time_s;
    d.dt_s = sim->dt_s;
    d.step = sim->step;
    d.bottom_wall_speed_mps = sim->wall_speed[WALL_BOTTOM];
    double ke = 0, vmax2 = 0, dev = 0, vol = 0, sum_vx = 0;
    const double rho0 = sim->rho0, m = sim->mass;
    #pragma omp parallel for schedule(static) reduction(+ : ke, vol, sum_vx) reduction(max : vmax2, dev)
    for (int a = sim->wall_count; a < sim->count; a++) {
        const double v2 = (double)sim->vx[a] * sim->vx[a] + (double)sim->vy[a] * sim->vy[a];
        ke += 0.5 * m * v2;
        vmax2 = v2 > vmax2 ? v2 : vmax2;
        const double e = fabs(sim->rho[a] / rho0 - 1.0);
        dev = e > dev ? e : dev;
        vol += m / sim->rho[a];
        sum_vx += sim->vx[a];
    }
    d.kinetic_energy_jpm = ke;
    d.max_speed_mps = sqrt(vmax2);
    d.max_density_deviation = dev;
    d.fluid_volume_m2 = vol;
    d.mean_vx_mps = sim->count > sim->wall_count ? sum_vx / (sim->count - sim->wall_count) : 0;
    if (sim->scheme->diagnostics)
        sim->scheme->diagnostics(sim, &d);
    return d;
}

uint64_t surge_sim_state_hash(const surge_sim *sim)
{
    uint64_t h = 14695981039346656037ull;
    h = fields_fnv1a(h, &sim->step, sizeof sim->step);
    h = fields_fnv1a(h, &sim->time_s, sizeof sim->time_s);
    h = fields_hash(sim, h);
    const boulder_set *b = &sim->boulders;
    const size_t nb = (size_t)b->count * sizeof(double);
    if (b->count > 0) {
#define HASH_DISC(name, meaning) h = fields_fnv1a(h, b->name, nb);
        SURGE_DISC_STEP_FIELDS(HASH_DISC)
#undef HASH_DISC
    }
    return h;
}
