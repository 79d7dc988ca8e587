/* Modified dynamic boundary condition (mDBC, English et al. 2021): each wall particle takes its density from a
 * first-order kernel-corrected interpolation of the fluid at its ghost node, mirrored into the fluid across the
 * wall face, and, for no-slip, the velocity 2 v_wall - v_ghost. */
#include <math.h>

#include "physics/eos.h"
#include "sim_internal.h"
#include "boulders/boulders.h"
#include "boundaries/boundary.h"

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

/* The ghost node's sums over a list of fluid particles j at r_ghost - r_j = dx0 + (g - moved_j) (nothing beyond 2h):
 * a vector loop over the list in pair precision, pairs beyond 2h masked; the solve that follows is in double. */
static ghost_sums ghost_node_sums(const surge_sim *sim, const int32_t *restrict index, const real *restrict dx0,
                                  const real *restrict dy0, int64_t first, int64_t last, real gx, real gy)
{
    const kernel2d *k = &sim->kernel;
    const real support2 = k->support2, alpha = k->alpha, inv_h = k->inv_h, grad_coef = k->grad_coef;
    const real mass = (real)sim->mass;
    const pair_state *restrict st = sim->pair_state;
    /* one partial sum per lane, the lanes added in order at the end (lanes.h; the lists hold whole vectors) */
    real a00[PAIR_LANES] = {0}, a01[PAIR_LANES] = {0}, a02[PAIR_LANES] = {0}, a10[PAIR_LANES] = {0};
    real a11[PAIR_LANES] = {0}, a12[PAIR_LANES] = {0}, a20[PAIR_LANES] = {0}, a21[PAIR_LANES] = {0};
    real a22[PAIR_LANES] = {0}, r00[PAIR_LANES] = {0}, r01[PAIR_LANES] = {0}, r02[PAIR_LANES] = {0};
    real r10[PAIR_LANES] = {0}, r11[PAIR_LANES] = {0}, r12[PAIR_LANES] = {0}, r20[PAIR_LANES] = {0};
    real r21[PAIR_LANES] = {0}, r22[PAIR_LANES] = {0};
    for (int64_t e0 = first; e0 < last; e0 += PAIR_LANES) {
        lanes_vector field[PAIR_LANES];
        lanes_gather_records(st, index + e0, field); /* field[q][l]: lane l's fluid neighbour's q-th field */
        #pragma omp simd simdlen(PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            const real moved_x = field[PAIR_MOVED_X][l], moved_y = field[PAIR_MOVED_Y][l], vx = field[PAIR_VX][l], vy = field[PAIR_VY][l];
            const real rho = field[PAIR_RHO][l];
            const real dx = dx0[e] + (gx - moved_x), dy = dy0[e] + (gy - moved_y);
            const real r2 = dx * dx + dy * dy;
            const real r = REAL_SQRT(r2);
            const real vol = r2 < support2 ? mass / rho : 0; /* beyond 2h: no contribution */
            const real w_vol = kernel2d_w_inside(alpha, inv_h, r) * vol;
            const real f_vol = kernel2d_grad_factor_inside(grad_coef, inv_h, r) * vol;
            const real wx_vol = f_vol * dx, wy_vol = f_vol * dy; /* gradient at the ghost node */
            const real rx = -dx, ry = -dy;                       /* r_j - r_ghost */
            a00[l] += w_vol, a01[l] += rx * w_vol, a02[l] += ry * w_vol;
            a10[l] += wx_vol, a11[l] += rx * wx_vol, a12[l] += ry * wx_vol;
            a20[l] += wy_vol, a21[l] += rx * wy_vol, a22[l] += ry * wy_vol;
            r00[l] += rho * w_vol, r01[l] += rho * wx_vol, r02[l] += rho * wy_vol;
            r10[l] += vx * w_vol, r11[l] += vx * wx_vol, r12[l] += vx * wy_vol;
            r20[l] += vy * w_vol, r21[l] += vy * wx_vol, r22[l] += vy * wy_vol;
        }
    }
    const real zero[PAIR_LANES] = {0};
    const real *const lanes[3][8] = {{a00, a01, a02, a10, a11, a12, a20, a21},
                                     {a22, r00, r01, r02, r10, r11, r12, r20},
                                     {r21, r22, zero, zero, zero, zero, zero, zero}};
    real t[24];
    for (int q = 0; q < 3; q++)
        lanes_totals(lanes[q], t + 8 * q);
    return (ghost_sums){{{t[0], t[1], t[2]}, {t[3], t[4], t[5]}, {t[6], t[7], t[8]}},
                        {{t[9], t[10], t[11]}, {t[12], t[13], t[14]}, {t[15], t[16], t[17]}}};
}

/* Wall particle b's records for the fluid's pair loops (wall_pair_state) and the wall-face search (wall_face_state) */
static inline void pack_wall_records(surge_sim *sim, int b)
{
    const neighbour_lists *nl = &sim->neighbours;
    sim->wall_state[b] = (wall_pair_state){nl->moved_x[b], nl->moved_y[b], sim->rho[b], sim->pressure[b],
                                           sim->wall_vx[b], sim->wall_vy[b], sim->wall_cont_vx[b],
                                           sim->wall_cont_vy[b]};
    const int disc = sim->boulders.count > 0 ? sim->boulders.of_wall[sim->id[b]] : -1;
    if (disc < 0) {
        sim->face_state[b] = (wall_face_state){nl->moved_x[b], nl->moved_y[b], sim->wall_nx[b], sim->wall_ny[b],
                                               sim->wall_depth_m[b], -1, 0, 0};
    } else {
        const double period = sim->grid.period_m;
        double centre_dx = sim->x[b] - sim->boulders.x[disc];
        if (period > 0)
            centre_dx -= period * floor(centre_dx / period + 0.5);
        sim->face_state[b] = (wall_face_state){nl->moved_x[b], nl->moved_y[b], 0, 0,
                                               (real)sim->boulders.radius[disc], (real)disc, (real)centre_dx,
                                               (real)(sim->y[b] - sim->boulders.y[disc])};
    }
}

void boundary_update(surge_sim *sim)
{
    const neighbour_lists *nl = &sim->neighbours;
    const double rho0 = sim->rho0;
    const real *restrict vx = sim->vx, *restrict vy = sim->vy;
    const int tait = !sim->scheme->incompressible; /* the walls' pressure from their density (else the scheme's) */
    if (sim->boulders.count > 0) { /* every thread sees the same count: all or none meet the single's barrier */
        #pragma omp single
        boulders_orient(&sim->boulders); /* for boulders_surface_velocity */
    }

    const int at_face = sim->params.walls.no_penetration_at == SURGE_NO_PENETRATION_AT_FACE;
    #pragma omp for schedule(static)
    for (int b = 0; b < sim->wall_count; b++) {
        /* A s = rhs for s = (value, d/dx, d/dy) of density, vx, vy at the ghost node */
        ghost_sums sums;
        if (sim->wall_of[b] != WALL_BOULDER) /* the ghost does not move: r_ghost - r_j = dx0 - moved_j */
            sums = ghost_node_sums(sim, nl->wall_fluid_index, nl->wall_fluid_dx0, nl->wall_fluid_dy0,
                                   nl->wall_fluid_first[b], nl->wall_fluid_first[b + 1], 0, 0);
        else /* a boulder's ghost turns with the disc: add how far the particle has moved and the ghost turned */
            sums = ghost_node_sums(sim, nl->ghost_fluid_index, nl->ghost_fluid_dx0, nl->ghost_fluid_dy0,
                                   nl->ghost_fluid_first[b], nl->ghost_fluid_first[b + 1],
                                   nl->moved_x[b] + (sim->ghost_dx[b] - nl->ghost_dx_build[b]),
                                   nl->moved_y[b] + (sim->ghost_dy[b] - nl->ghost_dy_build[b]));
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
        /* the stretch along the wall at the ghost node, t.grad(v).t (t the unit tangent; first order where it can
         * be): where the fluid keeps its volume, the normal velocity's rate along the normal is its negative */
        double stretch_per_s = 0.0;
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
            const double g2 = (double)sim->ghost_dx[b] * sim->ghost_dx[b] + (double)sim->ghost_dy[b] * sim->ghost_dy[b];
            const double tx = -sim->ghost_dy[b], ty = sim->ghost_dx[b]; /* along the wall, |t|^2 = g2 */
            stretch_per_s = (tx * (tx * sol[1][1] + ty * sol[1][2]) + ty * (tx * sol[2][1] + ty * sol[2][2])) / g2;
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
        /* no penetration: where the fluid at the wall face (by default; or at the ghost node) approaches a fixed
         * wall or a belt, the wall particle meets it with the mirrored normal velocity in the continuity equation, so
         * the approach compresses the fluid as a mirror image would (fluid moving away sees the wall's own velocity).
         * At the face: the ghost node's approach carried over the half particle-ghost distance d by the gradient the
         * fluid has where it keeps its volume, v.n(face) = v.n(ghost) + d t.grad(v).t, so that the fluid's own
         * compression (the rest of n.grad(v).n) does not feed the term: carried by the full gradient, it pumped
         * pressure waves in a pocket of fluid next to the belt. At the ghost node, up to 2h into the fluid, a
         * thinning layer's descent reads as an approach that the fluid at the face does not make. Not on boulders: a
         * disc driven into the fluid would compress it twice over (docs/method.md). */
        const double glen = sqrt((double)sim->ghost_dx[b] * sim->ghost_dx[b] + (double)sim->ghost_dy[b] * sim->ghost_dy[b]);
        const double nx = sim->ghost_dx[b] / glen, ny = sim->ghost_dy[b] / glen; /* into the fluid */
        sim->wall_nx[b] = (real)nx;
        sim->wall_ny[b] = (real)ny;
        sim->wall_depth_m[b] = (real)(0.5 * glen);
        double cont_vx = vx[b], cont_vy = vy[b];
        if (sim->params.walls.no_penetration && sim->wall_of[b] != WALL_BOULDER) {
            const double ghost_approach_mps = -((vgx - wall_vx) * nx + (vgy - wall_vy) * ny);
            const double approach = at_face ? ghost_approach_mps - 0.5 * glen * stretch_per_s : ghost_approach_mps;
            if (approach > 0) {
                cont_vx += approach * nx;
                cont_vy += approach * ny;
            }
        }
        sim->wall_cont_vx[b] = (real)cont_vx;
        sim->wall_cont_vy[b] = (real)cont_vy;
        if (tait) {
            sim->pressure[b] = tait_pressure(sim->rho[b], (real)rho0, (real)sim->b_pa);
            sim->inv_rho[b] = (real)1 / sim->rho[b];
        }
        pack_wall_records(sim, b);
    }
}
