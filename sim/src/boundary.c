/* Modified dynamic boundary condition (mDBC, English et al. 2021): each wall particle takes its density from a
 * first-order kernel-corrected interpolation of the fluid at its ghost node, mirrored into the fluid across the
 * wall face, and, for no-slip, the velocity 2 v_wall - v_ghost. */
#include <math.h>

#include "sim_internal.h"

/* Smooth start of moving walls: v(t) = v_target (1 - cos(pi t / T)) / 2 for t < T. Sets the velocity of every
 * wall particle but the boulders' (theirs follows their disc). */
void boundary_wall_speeds(surge_sim *sim, double time_s)
{
    const surge_params *p = &sim->params;
    double ramp = 1.0;
    if (p->walls.ramp_s > 0 && time_s < p->walls.ramp_s)
        ramp = 0.5 * (1.0 - cos(SURGE_PI * time_s / p->walls.ramp_s));
    sim->wall_speed[WALL_FIXED] = 0.0;
    sim->wall_speed[WALL_BOTTOM] = ramp * p->walls.bottom_speed_mps;
    sim->wall_speed[WALL_TOP] = ramp * p->walls.top_speed_mps;
    sim->wall_speed[WALL_BOULDER] = 0.0;
    sim->wall_speed[WALL_CORNER] = sim->wall_speed[WALL_BOTTOM];
    /* the kind (an output: snapshots, stream, colours; indexed by particle id) follows wall_of and the set speed,
     * which may change live */
    const uint8_t kind_of[WALL_COUNT] = {
        [WALL_FIXED] = SURGE_KIND_WALL, [WALL_BOULDER] = SURGE_KIND_BOULDER,
        [WALL_BOTTOM] = p->walls.bottom_speed_mps != 0 ? SURGE_KIND_MOVING_WALL : SURGE_KIND_WALL,
        [WALL_CORNER] = p->walls.bottom_speed_mps != 0 ? SURGE_KIND_MOVING_WALL : SURGE_KIND_WALL,
        [WALL_TOP] = p->walls.top_speed_mps != 0 ? SURGE_KIND_MOVING_WALL : SURGE_KIND_WALL};
    for (int b = 0; b < sim->wall_count; b++) {
        sim->kind[sim->id[b]] = kind_of[sim->wall_of[b]];
        if (sim->wall_of[b] != WALL_BOULDER) {
            sim->vx[b] = (real)sim->wall_speed[sim->wall_of[b]];
            sim->vy[b] = 0;
        }
    }
}

/* Below this determinant of the correction matrix the first-order interpolation is ill-conditioned and the
 * zeroth-order (Shepard) value is used instead; below MIN_SHEPARD_SUM the ghost sees no fluid. */
#define MIN_DETERMINANT 1e-3
#define MIN_SHEPARD_SUM 0.1

/* The sums of the first-order interpolation at a ghost node: the correction matrix a and the right-hand sides of
 * density, vx and vy */
typedef struct ghost_sums {
    double a[3][3];
    double rhs[3][3];
} ghost_sums;

/* Fluid particle j at r_ghost - r_j = (dx, dy) in the ghost's sums (nothing beyond 2h) */
static inline void add_fluid_neighbour(ghost_sums *s, const kernel2d *k, double mass, real dx, real dy, real rho_j,
                                       real vx_j, real vy_j)
{
    const real r2 = dx * dx + dy * dy;
    if (r2 >= k->support2)
        return;
    const real r = REAL_SQRT(r2);
    const double w = kernel2d_w_inside(k->alpha, k->inv_h, r);
    const double f = kernel2d_grad_factor_inside(k->grad_coef, k->inv_h, r);
    const double vol = mass / rho_j;
    const double wx = f * dx, wy = f * dy; /* gradient at the ghost node */
    const double rx = -(double)dx, ry = -(double)dy; /* r_j - r_ghost */
    const double basis[3] = {w * vol, wx * vol, wy * vol};
    const double fields[3] = {rho_j, vx_j, vy_j};
    for (int row = 0; row < 3; row++) {
        s->a[row][0] += basis[row];
        s->a[row][1] += rx * basis[row];
        s->a[row][2] += ry * basis[row];
    }
    for (int q = 0; q < 3; q++)
        for (int row = 0; row < 3; row++)
            s->rhs[q][row] += fields[q] * basis[row];
}

void boundary_update(surge_sim *sim)
{
    const cell_grid *g = &sim->grid;
    const neighbour_lists *nl = &sim->neighbours;
    const kernel2d *k = &sim->kernel;
    const double rho0 = sim->rho0, mass = sim->mass;
    const double *restrict x = sim->x, *restrict y = sim->y;
    const real *restrict vx = sim->vx, *restrict vy = sim->vy, *restrict rho = sim->rho;

    #pragma omp parallel for schedule(static)
    for (int b = 0; b < sim->wall_count; b++) {
        /* A s = rhs for s = (value, d/dx, d/dy) of density, vx, vy at the ghost node */
        ghost_sums sums = {0};
        if (sim->wall_of[b] != WALL_BOULDER) {
            /* the ghost does not move: r_ghost - r_j = its offset at the build less j's displacement since */
            for (int64_t e = nl->wall_fluid_first[b]; e < nl->wall_fluid_first[b + 1]; e++) {
                const int j = nl->wall_fluid_index[e];
                add_fluid_neighbour(&sums, k, mass, nl->wall_fluid_dx0[e] - nl->moved_x[j], nl->wall_fluid_dy0[e] - nl->moved_y[j],
                                    rho[j], vx[j], vy[j]);
            }
        } else {
            /* a boulder's ghost turns with the disc: the fluid in the cells around it */
            const double xg = surge_sim_wrapped_x(sim, x[b] + sim->ghost_dx[b]), yg = y[b] + sim->ghost_dy[b];
            neighbour_ranges nr;
            grid_neighbour_ranges(g, g->fluid_start, xg, yg, &nr);
            for (int s = 0; s < nr.count; s++)
                for (int j = nr.begin[s]; j < nr.end[s]; j++)
                    add_fluid_neighbour(&sums, k, mass, (real)(xg - (x[j] + nr.shift_x[s])), (real)(yg - y[j]),
                                        rho[j], vx[j], vy[j]);
        }
        const double a00 = sums.a[0][0], a01 = sums.a[0][1], a02 = sums.a[0][2], a10 = sums.a[1][0],
                     a11 = sums.a[1][1], a12 = sums.a[1][2], a20 = sums.a[2][0], a21 = sums.a[2][1],
                     a22 = sums.a[2][2];
        const double *rhs_rho = sums.rhs[0], *rhs_vx = sums.rhs[1], *rhs_vy = sums.rhs[2];
        /* no-slip: mirrored about the wall's velocity where the wall face lies between particle and ghost; the
         * belt-wall corner mirrors about the fixed upstream wall */
        double wall_vx = sim->wall_of[b] == WALL_CORNER ? 0.0 : vx[b], wall_vy = vy[b];
        if (sim->wall_of[b] == WALL_BOULDER)
            boulders_surface_velocity(sim, b, &wall_vx, &wall_vy);
        double rho_b = rho0, vgx = wall_vx, vgy = wall_vy;
        const double det = a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20) +
                           a02 * (a10 * a21 - a11 * a20);
        if (fabs(det) >= MIN_DETERMINANT) {
            /* Cramer's rule; density extrapolated from the ghost node back to the particle */
            double sol[3][3];
            const double *rhs[3] = {rhs_rho, rhs_vx, rhs_vy};
            for (int q = 0; q < 3; q++) {
                const double *c = rhs[q];
                sol[q][0] = (c[0] * (a11 * a22 - a12 * a21) - a01 * (c[1] * a22 - a12 * c[2]) +
                             a02 * (c[1] * a21 - a11 * c[2])) / det;
                sol[q][1] = (a00 * (c[1] * a22 - a12 * c[2]) - c[0] * (a10 * a22 - a12 * a20) +
                             a02 * (a10 * c[2] - c[1] * a20)) / det;
                sol[q][2] = (a00 * (a11 * c[2] - c[1] * a21) - a01 * (a10 * c[2] - c[1] * a20) +
                             c[0] * (a10 * a21 - a11 * a20)) / det;
            }
            rho_b = sol[0][0] - sim->ghost_dx[b] * sol[0][1] - sim->ghost_dy[b] * sol[0][2];
            vgx = sol[1][0];
            vgy = sol[2][0];
        } else if (a00 >= MIN_SHEPARD_SUM) {
            rho_b = rhs_rho[0] / a00;
            vgx = rhs_vx[0] / a00;
            vgy = rhs_vy[0] / a00;
        }
        /* walls never pull fluid: no density below rho0 (no tensile wall pressure) */
        sim->rho[b] = (real)fmax(rho_b, rho0);
        sim->ghost_fluid_sum[b] = (real)a00;
        sim->wall_vx[b] = (real)(2.0 * wall_vx - vgx);
        sim->wall_vy[b] = (real)(2.0 * wall_vy - vgy);
        /* no penetration: where the fluid at the ghost node approaches a fixed wall or a belt, the wall particle
         * meets it with the mirrored normal velocity in the continuity equation, so the approach compresses the
         * fluid as a mirror image would (fluid moving away sees the wall's own velocity). Not on boulders: a disc
         * driven into the fluid would compress it twice over (docs/method.md). */
        const double glen = sqrt((double)sim->ghost_dx[b] * sim->ghost_dx[b] + (double)sim->ghost_dy[b] * sim->ghost_dy[b]);
        const double nx = sim->ghost_dx[b] / glen, ny = sim->ghost_dy[b] / glen; /* into the fluid */
        sim->wall_nx[b] = (real)nx;
        sim->wall_ny[b] = (real)ny;
        sim->wall_depth_m[b] = (real)(0.5 * glen);
        double cont_vx = vx[b], cont_vy = vy[b];
        if (sim->params.walls.no_penetration && sim->wall_of[b] != WALL_BOULDER) {
            const double approach = -((vgx - wall_vx) * nx + (vgy - wall_vy) * ny);
            if (approach > 0) {
                cont_vx += approach * nx;
                cont_vy += approach * ny;
            }
        }
        sim->wall_cont_vx[b] = (real)cont_vx;
        sim->wall_cont_vy[b] = (real)cont_vy;
    }
}
