/* The implicit scheme's geometry of a step: the pair coefficients along the neighbour lists, the kernel moments and
 * sums, the free surface, the walls' mirror weights (docs/method.md, "The implicit scheme"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"
#include "boulders/boulders.h"
#include "neighbours/grid.h"
#include "physics/interaction.h"
#include "physics/shifting.h"

/* The velocity each wall's no-slip mirrors about: its own; the belt-wall corner's, the fixed upstream wall's; a disc
 * particle's, the disc's surface's at its ghost's mirror line (as boundary.c) */
void implicit_mirror_velocities(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    boulders_orient(&sim->boulders); /* for boulders_surface_velocity */
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        double vx = sim->wall_of[kw] == WALL_CORNER ? 0.0 : sim->vx[kw], vy = sim->vy[kw];
        if (sim->wall_of[kw] == WALL_BOULDER)
            boulders_surface_velocity(sim, kw, &vx, &vy);
        w->mirror_vx[kw] = vx, w->mirror_vy[kw] = vy;
    }
}

/* The walls' own share of each wall's ghost node's kernel sum, sum_k dp^2 W(r_ghost - r_k): computed once where no
 * wall moves across the kernel (belts move along themselves), at every step where discs move. With the fluid's
 * share it says whether the node lies in the fluid (about 1, also in a corner, where walls fill three quadrants) or
 * above its surface (less). */
void implicit_wall_sums(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const kernel2d *k = &sim->kernel;
    const double vol = sim->mass / sim->rho0;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        const double gx = surge_sim_wrapped_x(sim, sim->x[kw] + sim->ghost_dx[kw]), gy = sim->y[kw] + sim->ghost_dy[kw];
        neighbour_ranges r;
        grid_neighbour_ranges(&sim->grid, sim->grid.wall_start, gx, gy, &r);
        double sum = 0;
        for (int q = 0; q < r.count; q++)
            for (int b = r.begin[q]; b < r.end[q]; b++) {
                const double dx = gx - (sim->x[b] + r.shift_x[q]), dy = gy - sim->y[b], r2 = dx * dx + dy * dy;
                if (r2 < (double)k->support2)
                    sum += vol * kernel2d_w_inside(k->alpha, k->inv_h, (real)sqrt(r2));
            }
        w->wall_sum[kw] = sum;
    }
    w->wall_sum_ready = 1;
}

/* Fluid particle i's per-lane partial sums over its neighbour lists (lanes.h), added in lane order at the end */
typedef struct geometry_lanes {
    real kernel_w[PAIR_LANES], div_r[PAIR_LANES], grad_c_x[PAIR_LANES], grad_c_y[PAIR_LANES];
    real m_xx[PAIR_LANES], m_xy[PAIR_LANES], m_yy[PAIR_LANES]; /* the kernel moments, walls by their wetness */
    real zero[PAIR_LANES];
    double wrx[PAIR_LANES], wry[PAIR_LANES];                    /* sum_b w_ab r_ab */
} geometry_lanes;

/* implicit_geometry()'s pair loop over the list entries from..to of a fluid particle at (mxa, mya), its fluid list or (walls)
 * its wall list: each entry's Laplacian weight and V_b f r_ab, and the particle's sums */
static inline __attribute__((always_inline)) void geometry_pairs(surge_sim *sim, real mxa, real mya, int64_t from,
                                                                 int64_t to, int walls, geometry_lanes *s)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const kernel2d *k = &sim->kernel;
    const real grad_coef = k->grad_coef, inv_h = k->inv_h, alpha = k->alpha, support2 = k->support2;
    const real mass = (real)sim->mass, vol = (real)(sim->mass / sim->rho0), rho0 = (real)sim->rho0;
    const real eta2 = (real)sim->eta2, four = 4;
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const int32_t *restrict index = walls ? nl->wall_index : nl->fluid_index;
    const real *restrict dx0 = walls ? nl->wall_dx0 : nl->fluid_dx0, *restrict dy0 = walls ? nl->wall_dy0 : nl->fluid_dy0;
    real *restrict lap_w = walls ? w->wall_w : w->fluid_w;
    real *restrict gx = walls ? w->wall_gx : w->fluid_gx, *restrict gy = walls ? w->wall_gy : w->fluid_gy;
    const real *restrict wetness = w->wetness;
    for (int64_t e0 = from; e0 < to; e0 += PAIR_LANES) {
        #pragma omp simd simdlen(PAIR_LANES)
        for (int l = 0; l < PAIR_LANES; l++) {
            const int64_t e = e0 + l;
            const int b = index[e];
            const real dx = dx0[e] + (mxa - moved_x[b]), dy = dy0[e] + (mya - moved_y[b]);
            const real r2 = dx * dx + dy * dy;
            const int inside = (r2 < support2) & (r2 > 0);
            const real r = REAL_SQRT(r2);
            const real f = inside ? kernel2d_grad_factor_inside(grad_coef, inv_h, r) : 0;
            const real vf = vol * f;
            /* the Laplacian's weight: the viscous pair coefficient (eq. 7) per unit viscosity, negated */
            const real weight = -pair_viscous_coef(mass, four, f, r2, pair_viscous_denominator(rho0, rho0, r2, eta2));
            lap_w[e] = weight;
            gx[e] = vf * dx, gy[e] = vf * dy;
            s->wrx[l] += weight * dx, s->wry[l] += weight * dy;
            s->kernel_w[l] += inside ? kernel2d_w_inside(alpha, inv_h, r) : 0;
            /* a wall counts in div r and in the moments as far as fluid wets it: a wall above the free surface does
             * not hide a surface particle, nor hold up the one next to it */
            const real wet = walls ? wetness[b] : 1;
            s->div_r[l] -= wet * vf * r2;
            s->m_xx[l] += wet * pair_moment(vf, dx, dx), s->m_xy[l] += wet * pair_moment(vf, dx, dy);
            s->m_yy[l] += wet * pair_moment(vf, dy, dy);
            s->grad_c_x[l] += vf * dx, s->grad_c_y[l] += vf * dy;
        }
    }
}

/* Below this determinant of the quadratic fit's moment matrix (lengths in dp) the wall keeps mDBC's mirror */
#define MIN_QUADRATIC_DETERMINANT 1e-6

/* Fluid entry e of wall kw's ghost list in the frame of the wall's face (n the distance from the face into the fluid
 * along the unit normal (nx, ny), t along it, both in dp; the face depth dp from the particle and from its ghost
 * node): the basis (n, n t, n^2) of the quadratic no-slip fit, and the entry's kernel weight at the ghost, 0 beyond
 * the support */
static inline double face_basis(const surge_sim *sim, const ghost_span *g, int64_t e, double nx, double ny,
                                double depth, double inv_dp, double basis[3])
{
    const kernel2d *k = &sim->kernel;
    const int j = g->index[e];
    const double dx = g->dx0[e] - sim->neighbours.moved_x[j] + g->shift_x; /* r_g - r_j */
    const double dy = g->dy0[e] - sim->neighbours.moved_y[j] + g->shift_y;
    const double r2 = dx * dx + dy * dy;
    if (!(r2 < k->support2))
        return 0;
    const double n = (-dx * nx - dy * ny) * inv_dp + depth, t = (dx * ny - dy * nx) * inv_dp;
    basis[0] = n, basis[1] = n * t, basis[2] = n * n;
    return kernel2d_w_inside(k->alpha, k->inv_h, (real)sqrt(r2)) * (sim->mass / sim->rho0);
}

/* Wall kw's quadratic no-slip velocity (walls.quadratic_no_slip; walls, not discs): the fluid's u - u_wall =
 * b0 n + b1 n t + b2 n^2 (face_basis), which is u_wall on the face, fitted to the fluid of the ghost's list by least
 * squares weighted with the kernel at the ghost, is evaluated at the particle (n = -depth, t = 0). Each entry's
 * weight c_j and the wall velocity's 1 - sum c_j go to wall_no_slip_value; exact for a velocity quadratic across the
 * wall, as a pressure- or gravity-driven flow's is. */
static void quadratic_no_slip_weights(surge_sim *sim, int kw, const ghost_span *g)
{
    implicit_work *w = implicit_of(sim);
    const double inv_dp = 1.0 / sim->params.numerics.dp_m;
    const double glen = sqrt((double)sim->ghost_dx[kw] * sim->ghost_dx[kw] + (double)sim->ghost_dy[kw] * sim->ghost_dy[kw]);
    const double nx = sim->ghost_dx[kw] / glen, ny = sim->ghost_dy[kw] / glen, depth = 0.5 * glen * inv_dp;
    double a[3][3] = {{0}}, basis[3];
    for (int64_t e = g->from; e < g->to; e++) {
        const double kernel = face_basis(sim, g, e, nx, ny, depth, inv_dp, basis);
        if (kernel > 0)
            for (int q = 0; q < 3; q++)
                for (int c = 0; c < 3; c++)
                    a[q][c] += kernel * basis[q] * basis[c];
    }
    const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                       a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                       a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    w->quadratic_ok[kw] = !w->dry[kw] && fabs(det) >= MIN_QUADRATIC_DETERMINANT;
    if (!w->quadratic_ok[kw])
        return;
    /* the particle's basis (-depth, 0, depth^2) times a^-1: rows 0 and 2 of the inverse */
    const double inv0[3] = {(a[1][1] * a[2][2] - a[1][2] * a[2][1]) / det, -(a[0][1] * a[2][2] - a[0][2] * a[2][1]) / det,
                            (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / det};
    const double inv2[3] = {(a[1][0] * a[2][1] - a[1][1] * a[2][0]) / det, -(a[0][0] * a[2][1] - a[0][1] * a[2][0]) / det,
                            (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / det};
    double row[3], base = 1.0;
    for (int c = 0; c < 3; c++)
        row[c] = -depth * inv0[c] + depth * depth * inv2[c];
    for (int64_t e = g->from; e < g->to; e++) {
        const double kernel = face_basis(sim, g, e, nx, ny, depth, inv_dp, basis);
        const double weight = kernel > 0 ? kernel * (row[0] * basis[0] + row[1] * basis[1] + row[2] * basis[2]) : 0;
        g->quadratic_weight[e] = (real)weight;
        base -= (real)weight;
    }
    w->quadratic_base[kw] = base;
}

/* The walls' ghost nodes: each fluid neighbour's weight in the first-order (kernel-corrected) interpolation at the
 * node, as boundary.c's mDBC; Shepard's where the correction matrix is ill-conditioned; the node's wetness and
 * immersion; the quadratic no-slip weights where asked for */
static void mirror_weights(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const kernel2d *k = &sim->kernel;
    const real grad_coef = k->grad_coef, inv_h = k->inv_h, alpha = k->alpha, support2 = k->support2;
    const real vol = (real)(sim->mass / sim->rho0);
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const int offsets = sim->params.implicit.wall_neumann_offset > 0;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        const ghost_span g = ghost_span_of(sim, kw);
        double lane[3][3][PAIR_LANES] = {{{0}}}; /* per-lane partial sums (lanes.h) */
        for (int64_t e0 = g.from; e0 < g.to; e0 += PAIR_LANES)
            #pragma omp simd simdlen(PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int j = g.index[e0 + l];
                const real dx = g.dx0[e0 + l] - moved_x[j] + g.shift_x, dy = g.dy0[e0 + l] - moved_y[j] + g.shift_y; /* r_g - r_j */
                const real r2 = dx * dx + dy * dy, r = REAL_SQRT(r2);
                const int inside = r2 < support2;
                const double w_vol = inside ? kernel2d_w_inside(alpha, inv_h, r) * vol : 0;
                const double f_vol = inside ? kernel2d_grad_factor_inside(grad_coef, inv_h, r) * vol : 0;
                const double u[3] = {w_vol, f_vol * dx, f_vol * dy}, rel[3] = {1, -(double)dx, -(double)dy};
                for (int q = 0; q < 3; q++)
                    for (int c = 0; c < 3; c++)
                        lane[q][c][l] += u[q] * rel[c];
            }
        double a[3][3];
        for (int q = 0; q < 3; q++)
            for (int c = 0; c < 3; c++)
                a[q][c] = lanes_total(lane[q][c]);
        const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        double row[3] = {0, 0, 0}; /* the first row of a^-1: the value at the node from the sums */
        double normal_row[3] = {0, 0, 0}; /* n . (its second and third rows): the derivative along the normal */
        if (fabs(det) >= MIN_DETERMINANT && a[0][0] >= MIN_SHEPARD_SUM) {
            row[0] = (a[1][1] * a[2][2] - a[1][2] * a[2][1]) / det;
            row[1] = -(a[0][1] * a[2][2] - a[0][2] * a[2][1]) / det;
            row[2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / det;
            if (offsets) {
                const double glen = sqrt((double)sim->ghost_dx[kw] * sim->ghost_dx[kw] +
                                         (double)sim->ghost_dy[kw] * sim->ghost_dy[kw]);
                const double nx = sim->ghost_dx[kw] / glen, ny = sim->ghost_dy[kw] / glen;
                normal_row[0] = (-nx * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) + ny * (a[1][0] * a[2][1] - a[1][1] * a[2][0])) / det;
                normal_row[1] = (nx * (a[0][0] * a[2][2] - a[0][2] * a[2][0]) - ny * (a[0][0] * a[2][1] - a[0][1] * a[2][0])) / det;
                normal_row[2] = (-nx * (a[0][0] * a[1][2] - a[0][2] * a[1][0]) + ny * (a[0][0] * a[1][1] - a[0][1] * a[1][0])) / det;
            }
        } else if (a[0][0] >= MIN_SHEPARD_SUM) {
            row[0] = 1.0 / a[0][0];
        }
        w->dry[kw] = a[0][0] < MIN_SHEPARD_SUM;
        /* the node's kernel sum of fluid and walls: 1.00 in the fluid (corners included), 0.77 level with the top
         * row next to the tank's side wall, 0.58 a dp above it (C_h 1.8); wetness ramps from 0 at 0.6 to 1 at 0.75,
         * immersion (the node's kernel is full: phi's Neumann offset applies) from 0 at 0.90 to 1 at 0.98 */
        w->wetness[kw] = (real)fmin(1.0, fmax(0.0, (a[0][0] + w->wall_sum[kw] - 0.6) / 0.15));
        w->immersion[kw] = (real)fmin(1.0, fmax(0.0, (a[0][0] + w->wall_sum[kw] - 0.9) / 0.08));
        w->quadratic_ok[kw] = 0;
        if (sim->params.walls.quadratic_no_slip && sim->wall_of[kw] != WALL_BOULDER)
            quadratic_no_slip_weights(sim, kw, &g);
        for (int64_t e = g.from; e < g.to; e++) {
            const int j = g.index[e];
            const real dx = g.dx0[e] - moved_x[j] + g.shift_x, dy = g.dy0[e] - moved_y[j] + g.shift_y;
            const real r2 = dx * dx + dy * dy, r = REAL_SQRT(r2);
            double c = 0, cn = 0;
            if (r2 < support2 && !w->dry[kw]) {
                const double f_vol = kernel2d_grad_factor_inside(grad_coef, inv_h, r) * vol;
                c = row[0] * kernel2d_w_inside(alpha, inv_h, r) * vol + row[1] * f_vol * dx + row[2] * f_vol * dy;
                cn = normal_row[0] * kernel2d_w_inside(alpha, inv_h, r) * vol + normal_row[1] * f_vol * dx +
                     normal_row[2] * f_vol * dy;
            }
            g.weight[e] = (real)c;
            if (offsets)
                g.normal_weight[e] = (real)cn;
        }
    }
}

#define SCAN_DIV_R_MAX 1.9 /* only a particle whose div r is below this is scanned */
/* a particle whose kernel sum reaches the lattice's full one has no air in its kernel: it is not on a free surface,
 * whatever its div r (the border of a void in the bulk, pressed together as the void closes; docs/method.md) */
#define SURFACE_FULL_KERNEL_RATIO 1.0

/* Whether the region beyond fluid particle a along the unit normal (nx, ny) holds no particle of list entries
 * from..to (Marrone et al. 2010, sect. 2.2): with T the point radius_m out along the normal, a particle b blocks it
 * within sqrt(2) radius_m of a if it lies in the square |(r_b - T).n| + |(r_b - T).t| < radius_m (a cone of 90
 * degrees from a), and farther out if it lies within radius_m of T. */
static int scan_empty(const surge_sim *sim, int a, int64_t from, int64_t to, int walls, double nx, double ny,
                      double radius_m)
{
    const neighbour_lists *nl = &sim->neighbours;
    const int32_t *restrict index = walls ? nl->wall_index : nl->fluid_index;
    const real *restrict dx0 = walls ? nl->wall_dx0 : nl->fluid_dx0, *restrict dy0 = walls ? nl->wall_dy0 : nl->fluid_dy0;
    const double cone2 = 2 * radius_m * radius_m, support2 = sim->kernel.support2;
    for (int64_t e = from; e < to; e++) {
        const int b = index[e];
        /* r_b - r_a */
        const double bx = -(dx0[e] + (nl->moved_x[a] - nl->moved_x[b])), by = -(dy0[e] + (nl->moved_y[a] - nl->moved_y[b]));
        const double r2 = bx * bx + by * by;
        if (r2 >= support2 || r2 == 0)
            continue;
        const double along = bx * nx + by * ny - radius_m, across = by * nx - bx * ny; /* r_b - T */
        if (r2 < cone2 ? fabs(along) + fabs(across) < radius_m : along * along + across * across < radius_m * radius_m)
            return 0;
    }
    return 1;
}

/* Each fluid particle's pair coefficients (fluid and wall entries), inverse moment matrix, kernel sum, nearest wall
 * face, free-surface flag, div r and grad C */
static void fluid_geometry(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const real alpha = sim->kernel.alpha, mass = (real)sim->mass;
    const double inv_lattice = 1.0 / sim->lattice_kernel_sum;
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const int first = sim->wall_count, n = sim->count;
    /* the scan's radius, at most h: the region reaches 2 radii, the kernel's support */
    const double scan_m = fmin(sim->params.implicit.surface_scan_dp * sim->params.numerics.dp_m,
                               0.5 * sqrt((double)sim->kernel.support2));
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = first; a < n; a++) {
        const int i = a - first;
        const real mxa = moved_x[a], mya = moved_y[a];
        geometry_lanes sums;
        memset(&sums, 0, sizeof sums);
        geometry_pairs(sim, mxa, mya, nl->fluid_first[i], nl->fluid_first[i + 1], 0, &sums);
        geometry_pairs(sim, mxa, mya, nl->wall_first[i], nl->wall_first[i + 1], 1, &sums);
        const real *const first_eight[8] = {sums.kernel_w, sums.div_r, sums.grad_c_x, sums.grad_c_y,
                                            sums.m_xx, sums.m_xy, sums.m_yy, sums.zero};
        real total[8];
        lanes_totals(first_eight, total);
        const real kernel_w = total[0], div_r = total[1], grad_c_x = total[2], grad_c_y = total[3];
        const real m_xx = total[4], m_xy = total[5], m_yy = total[6];
        const double wrx = lanes_total(sums.wrx), wry = lanes_total(sums.wry);
        w->kernel_ratio[i] = mass * (alpha + kernel_w) * inv_lattice / sim->rho0;
        /* the nearest wall face within dp, for the contact rule and shifting (as the explicit scheme's) */
        int near_disc = 0;
        const wall_face face = interaction_wall_face(sim, a, (real)sim->params.numerics.dp_m, &near_disc);
        sim->face_nx[a] = face.nx, sim->face_ny[a] = face.ny, sim->face_gap_m[a] = face.gap_m;
        /* and, next to a disc, the nearest face of another solid: a particle in a wedge is kept off both */
        const real dp = (real)sim->params.numerics.dp_m;
        w->other_face[i] = near_disc && face.gap_m < dp ? interaction_other_face(sim, a, dp, &face)
                                                         : (wall_face){dp, 0, 0, 0, -1, -1};
        sim->face_vn_mps[a] = face.vn_mps, sim->face_disc[a] = face.disc;
        w->near_disc[i] = (uint8_t)near_disc;
        /* a free-surface particle: div r low, or a kernel sum short of the second row's under a flat surface (a
         * contact line, where the wall raises div r; docs/method.md). Not the latter next to a disc, whose rings
         * fill its circle less evenly than a wall's rows their half-plane: a particle 0.7 dp off a disc of radius 5
         * dp has 0.87 of the lattice's kernel sum in fluid at rest */
        const int full_kernel = w->kernel_ratio[i] >= SURFACE_FULL_KERNEL_RATIO;
        sim->surface[a] = !full_kernel && (div_r < (real)sim->params.implicit.surface_threshold ||
                                           (!near_disc && w->kernel_ratio[i] < sim->second_row_kernel_ratio -
                                                                                   sim->params.implicit.surface_kernel_margin));
        /* or, next to a disc, where the kernel-sum test is left out, nothing beyond it: a cavity's border, whose
         * sums the disc's particles fill (div r up to 1.7 at the 60-disc surge's; the bulk's is 2, and the scan is
         * spared there) */
        const double grad_c = !full_kernel && !sim->surface[a] && near_disc && scan_m > 0 && div_r < SCAN_DIV_R_MAX
                                  ? sqrt((double)grad_c_x * grad_c_x + (double)grad_c_y * grad_c_y) : 0;
        if (grad_c > 0) {
            const double nx = -grad_c_x / grad_c, ny = -grad_c_y / grad_c;
            sim->surface[a] = scan_empty(sim, a, nl->fluid_first[i], nl->fluid_first[i + 1], 0, nx, ny, scan_m) &&
                              scan_empty(sim, a, nl->wall_first[i], nl->wall_first[i + 1], 1, nx, ny, scan_m);
        }
        const double det = (double)m_xx * m_yy - (double)m_xy * m_xy;
        if (det > 0.25) {
            w->minv_xx[i] = m_yy / det, w->minv_xy[i] = -m_xy / det, w->minv_yy[i] = m_xx / det;
        } else {
            w->minv_xx[i] = 1, w->minv_xy[i] = 0, w->minv_yy[i] = 1;
        }
        w->weighted_rx[i] = wrx, w->weighted_ry[i] = wry;
        sim->div_r[a] = div_r;
        sim->inv_rho[a] = (real)(1.0 / sim->rho0);
        sim->grad_c_x[a] = grad_c_x, sim->grad_c_y[a] = grad_c_y;
        w->fixed[i] = (uint8_t)sim->surface[a];
    }
}

/* The free-surface layer (on or next to the surface), the surface's normal for the shift, and the kernel sum a
 * particle near the surface has at rest spacing at its depth */
static void surface_layer(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const real *restrict moved_x = nl->moved_x, *restrict moved_y = nl->moved_y;
    const int first = sim->wall_count, n = sim->count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int a = first; a < n; a++) {
        const int i = a - first;
        int near = sim->surface[a];
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1] && !near; e++)
            near = w->fluid_w[e] != 0 && sim->surface[nl->fluid_index[e]];
        sim->near_surface[a] = (uint8_t)near;
        /* the surface's normal for the shift (shifting.c): the neighbours' grad C, weighted as the Laplacian */
        double nx = 0, ny = 0;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1] && near; e++) {
            const int b = nl->fluid_index[e];
            nx += w->fluid_w[e] * sim->grad_c_x[b], ny += w->fluid_w[e] * sim->grad_c_y[b];
        }
        const double length = sqrt(nx * nx + ny * ny);
        sim->surface_nx[a] = (real)(length > 0 ? nx / length : 0), sim->surface_ny[a] = (real)(length > 0 ? ny / length : 0);
        /* the kernel sum at rest spacing at this depth under a flat surface (the nearest surface particle's distance
         * in rows, between the lattice's rows), where no wall in reach is partly dry (a contact line, where the
         * walls' share is uncertain): 0 where it cannot be read */
        double depth2 = near && !sim->surface[a] ? INFINITY : 0;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1] && depth2 > 0; e++) {
            const int b = nl->fluid_index[e];
            if (!sim->surface[b] || w->fluid_w[e] == 0)
                continue;
            const double dx = nl->fluid_dx0[e] + (moved_x[a] - moved_x[b]), dy = nl->fluid_dy0[e] + (moved_y[a] - moved_y[b]);
            depth2 = fmin(depth2, dx * dx + dy * dy);
        }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1] && depth2 > 0; e++)
            if (w->wall_w[e] != 0 && w->wetness[nl->wall_index[e]] < 1)
                depth2 = 0;
        const double rows = sqrt(depth2) / sim->params.numerics.dp_m;
        const int row = rows < SURGE_KERNEL_ROWS - 1 ? (int)rows : SURGE_KERNEL_ROWS - 2;
        const double f = fmin(1.0, rows - row);
        w->expected_ratio[i] = depth2 > 0 ? (1 - f) * sim->row_kernel_ratio[row] + f * sim->row_kernel_ratio[row + 1] : 0;
    }
}

/* The pair coefficients of the step (fluid and wall entries), the inverse moment matrices, kernel sums, the
 * free-surface flags and what shifting needs (div r, grad C, the surface layer); the walls' Shepard weights. The
 * surface layer and the surface's images are the surface phase, the rest the geometry's. */
void implicit_geometry(surge_sim *sim)
{
    if (!implicit_of(sim)->wall_sum_ready || sim->boulders.count > 0)
        implicit_wall_sums(sim);
    mirror_weights(sim);
    fluid_geometry(sim);
    phase_end(sim, &sim->phase_times.geometry_s);
    surface_layer(sim);
    implicit_surface_images(sim);
    phase_end(sim, &sim->phase_times.surface_s);
}
