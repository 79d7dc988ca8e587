/* The free surface by mirror images (implicit.surface_images; docs/method.md, "The implicit scheme", "Mirror images
 * beyond the surface"). A particle whose kernel reaches the free surface sees, beyond the line of the surface
 * particles near it (held at p = 0), the mirror image of each neighbour on its side of the line: the image's
 * pressure is the neighbour's negated (so p = 0 on the line), its velocity the neighbour's own. Its gradient, divergence and Laplacian are then those of a
 * full kernel, and the step's gradient and divergence pair closely enough that no mode under the surface grows at
 * steps shorter than the scheme's own (docs/validation/stability.md, "Short steps in a thin fluid"). Wall particles
 * beyond the line (a side wall above the fluid) are left out: the images of those below it take their place. */
#include <math.h>
#include <string.h>

#include "scheme/implicit/implicit.h"

/* The colour gradient sum_b V_b f r_ab of each fluid particle, walls by their wetness (a wall above the fluid does
 * not turn the surface's normal toward itself) */
static void wet_colour_gradients(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        double gx = 0, gy = 0;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
            gx += w->fluid_gx[e], gy += w->fluid_gy[e];
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
            const double wet = w->wetness[nl->wall_index[e]];
            gx += wet * w->wall_gx[e], gy += wet * w->wall_gy[e];
        }
        w->wet_grad_x[i] = gx, w->wet_grad_y[i] = gy;
    }
}

/* One image pair: r_ab' = r_ab - 2 depth_b n (the neighbour b at depth_b under the plane, n its outward normal), its
 * Laplacian weight (the viscous pair coefficient per unit viscosity, negated, as implicit_geometry's) and V f r_ab' */
typedef struct image_pair {
    double rx, ry, weight, gx, gy;
} image_pair;

static image_pair image_of(const surge_sim *sim, double dx, double dy, double depth_b, double nx, double ny)
{
    const kernel2d *k = &sim->kernel;
    image_pair p = {dx - 2 * depth_b * nx, dy - 2 * depth_b * ny, 0, 0, 0};
    const double r2 = p.rx * p.rx + p.ry * p.ry;
    if (!(r2 < (double)k->support2) || r2 <= 0)
        return p;
    const real f = kernel2d_grad_factor_inside(k->grad_coef, k->inv_h, (real)sqrt(r2));
    const real rho0 = (real)sim->rho0;
    p.weight = -pair_viscous_coef((real)sim->mass, 4, f, (real)r2,
                                  pair_viscous_denominator(rho0, rho0, (real)r2, (real)sim->eta2));
    const double vf = sim->mass / sim->rho0 * f;
    p.gx = vf * p.rx, p.gy = vf * p.ry;
    return p;
}

/* The kernel moment -sum V_b f r (x) r and the Laplacian's first moment sum_b w r of a pair, added */
typedef struct moments {
    double xx, xy, yy, wrx, wry;
} moments;

static inline void add_pair(moments *m, double scale, double dx, double dy, double gx, double gy, double weight)
{
    m->xx -= scale * gx * dx, m->xy -= scale * gx * dy, m->yy -= scale * gy * dy;
    m->wrx += scale * weight * dx, m->wry += scale * weight * dy;
}

/* The depth of fluid particle a along its outward normal n under the outermost surface particle in reach (a itself
 * included); -1 where none is */
static double plane_depth(const surge_sim *sim, int a, double nx, double ny)
{
    const neighbour_lists *nl = &sim->neighbours;
    const implicit_work *w = implicit_of(sim);
    const int i = a - sim->wall_count;
    double outermost = sim->surface[a] ? 0.0 : -INFINITY;
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
        const int b = nl->fluid_index[e];
        if (!sim->surface[b] || w->fluid_w[e] == 0)
            continue;
        const double dx = nl->fluid_dx0[e] + (nl->moved_x[a] - nl->moved_x[b]);
        const double dy = nl->fluid_dy0[e] + (nl->moved_y[a] - nl->moved_y[b]);
        outermost = fmax(outermost, -(dx * nx + dy * ny));
    }
    return isfinite(outermost) ? outermost : -1.0;
}

/* The free surface's plane at fluid particle a, its outward normal n and its depth under it: the line through the
 * surface particles in reach (a itself included), weighted as the Laplacian (its normal the direction of their
 * positions' least spread, turned against the colour gradient of fluid and wet walls); where fewer than two surface
 * particles are in reach or they lie in a clump, the colour gradient's direction through the outermost. 0 where
 * neither can be read. */
static int surface_plane(const surge_sim *sim, int a, double *nx, double *ny, double *depth)
{
    const implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int i = a - sim->wall_count;
    double gx = 0, gy = 0, sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, largest = 0;
    int points = 0;
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
        const int b = nl->fluid_index[e], j = b - sim->wall_count;
        const double weight = w->fluid_w[e];
        gx += weight * w->wet_grad_x[j], gy += weight * w->wet_grad_y[j];
        largest = fmax(largest, weight);
        if (!sim->surface[b] || weight == 0)
            continue;
        const double rx = -(nl->fluid_dx0[e] + (nl->moved_x[a] - nl->moved_x[b])); /* r_b - r_a */
        const double ry = -(nl->fluid_dy0[e] + (nl->moved_y[a] - nl->moved_y[b]));
        sw += weight, sx += weight * rx, sy += weight * ry;
        sxx += weight * rx * rx, sxy += weight * rx * ry, syy += weight * ry * ry;
        points++;
    }
    if (sim->surface[a])
        sw += largest, points++; /* a itself, at r = 0 */
    const double length = sqrt(gx * gx + gy * gy);
    if (!(length > 0))
        return 0;
    *nx = -gx / length, *ny = -gy / length;
    *depth = plane_depth(sim, a, *nx, *ny);
    if (points < 2)
        return 1;
    const double cx = sx / sw, cy = sy / sw;
    const double cxx = sxx / sw - cx * cx, cxy = sxy / sw - cx * cy, cyy = syy / sw - cy * cy;
    const double mean = 0.5 * (cxx + cyy), spread = sqrt(0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy);
    const double dp = sim->params.numerics.dp_m;
    if (mean + spread < 0.2 * dp * dp) /* a clump, not a line */
        return 1;
    /* the eigenvector of the smaller eigenvalue mean - spread of the positions' covariance */
    double ex = cxy, ey = mean - spread - cxx;
    if (ex * ex + ey * ey < 1e-24 * dp * dp * dp * dp)
        ex = cxx <= cyy ? 1.0 : 0.0, ey = cxx <= cyy ? 0.0 : 1.0;
    const double e_length = sqrt(ex * ex + ey * ey);
    const double sign = ex * *nx + ey * *ny < 0 ? -1.0 : 1.0;
    *nx = sign * ex / e_length, *ny = sign * ey / e_length;
    *depth = cx * *nx + cy * *ny;
    return 1;
}

/* Fluid particle a's images about the plane (n, depth): each list entry's image pair, the walls' side of the plane,
 * its own image, and its moments with them; 0 where it has none (the plane beyond its kernel) */
static int particle_images(surge_sim *sim, int a, double nx, double ny, double depth)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int i = a - sim->wall_count;
    if (depth < -0.5 * sim->params.numerics.dp_m || depth * depth >= (double)sim->kernel.support2)
        return 0;
    /* the surface particles lie on the plane, at p = 0, and have no image; nor has a wall level with them */
    const double half_dp = 0.5 * sim->params.numerics.dp_m;
    moments m = {0};
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
        const int b = nl->fluid_index[e];
        const double dx = nl->fluid_dx0[e] + (nl->moved_x[a] - nl->moved_x[b]);
        const double dy = nl->fluid_dy0[e] + (nl->moved_y[a] - nl->moved_y[b]);
        add_pair(&m, 1.0, dx, dy, w->fluid_gx[e], w->fluid_gy[e], w->fluid_w[e]);
        const double depth_b = depth + dx * nx + dy * ny;
        const image_pair p = !sim->surface[b] && depth_b > half_dp ? image_of(sim, dx, dy, depth_b, nx, ny)
                                                                    : (image_pair){0};
        add_pair(&m, 1.0, p.rx, p.ry, p.gx, p.gy, p.weight);
        w->fluid_iw[e] = (real)p.weight, w->fluid_igx[e] = (real)p.gx, w->fluid_igy[e] = (real)p.gy;
    }
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
        const int kw = nl->wall_index[e];
        const double dx = nl->wall_dx0[e] + (nl->moved_x[a] - nl->moved_x[kw]);
        const double dy = nl->wall_dy0[e] + (nl->moved_y[a] - nl->moved_y[kw]);
        const double depth_w = depth + dx * nx + dy * ny;
        /* a wall level with the surface particles (within half a spacing of their line) stays, as they do */
        const double side = depth_w > -half_dp ? 1.0 : 0.0;
        add_pair(&m, side, dx, dy, w->wall_gx[e], w->wall_gy[e], w->wall_w[e]);
        const image_pair p = depth_w > half_dp ? image_of(sim, dx, dy, depth_w, nx, ny) : (image_pair){0};
        add_pair(&m, 1.0, p.rx, p.ry, p.gx, p.gy, p.weight);
        w->wall_side[e] = (real)side;
        w->wall_iw[e] = (real)p.weight, w->wall_igx[e] = (real)p.gx, w->wall_igy[e] = (real)p.gy;
    }
    const image_pair own = depth > half_dp ? image_of(sim, 0, 0, depth, nx, ny) : (image_pair){0};
    add_pair(&m, 1.0, own.rx, own.ry, own.gx, own.gy, own.weight);
    w->own_iw[i] = own.weight, w->own_igx[i] = own.gx, w->own_igy[i] = own.gy;
    const double det = m.xx * m.yy - m.xy * m.xy;
    if (det > 0.25)
        w->minv_xx[i] = m.yy / det, w->minv_xy[i] = -m.xy / det, w->minv_yy[i] = m.xx / det;
    else
        w->minv_xx[i] = 1, w->minv_xy[i] = 0, w->minv_yy[i] = 1;
    w->weighted_rx[i] = m.wrx, w->weighted_ry[i] = m.wry;
    return 1;
}

/* What the shift (shifting.c) sees near the free surface: the plane's normal, and the colour gradient of the fluid
 * and of the walls on the fluid's side of the plane (a wall above the fluid is air, as for the images: counted, it
 * pushes the surface particles next to it away along the surface; by its wetness, toward it) */
static void surface_shift_gradient(surge_sim *sim, int a, double nx, double ny, double depth)
{
    const implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int i = a - sim->wall_count;
    const double half_dp = 0.5 * sim->params.numerics.dp_m;
    double gx = 0, gy = 0;
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
        gx += w->fluid_gx[e], gy += w->fluid_gy[e];
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
        const int kw = nl->wall_index[e];
        const double dx = nl->wall_dx0[e] + (nl->moved_x[a] - nl->moved_x[kw]);
        const double dy = nl->wall_dy0[e] + (nl->moved_y[a] - nl->moved_y[kw]);
        if (depth + dx * nx + dy * ny > -half_dp)
            gx += w->wall_gx[e], gy += w->wall_gy[e];
    }
    sim->grad_c_x[a] = (real)gx, sim->grad_c_y[a] = (real)gy;
    sim->surface_nx[a] = (real)nx, sim->surface_ny[a] = (real)ny;
}

void implicit_surface_images(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const int first = sim->wall_count, nf = sim->count - first;
    memset(w->imaged, 0, (size_t)nf * sizeof *w->imaged);
    w->any_imaged = 0;
    if (!sim->params.implicit.surface_images)
        return;
    wet_colour_gradients(sim);
    int any = 0;
    #pragma omp parallel for schedule(dynamic, 64) reduction(| : any) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int a = first + i;
        double nx, ny, depth;
        if (!sim->near_surface[a] || !surface_plane(sim, a, &nx, &ny, &depth))
            continue;
        surface_shift_gradient(sim, a, nx, ny, depth);
        if (sim->surface[a] || !particle_images(sim, a, nx, ny, depth))
            continue;
        w->imaged[i] = 1;
        any = 1;
    }
    w->any_imaged = any;
}

/* The renormalised gradient's sum for an imaged particle: sum_b V_b [(p_b - p_a) f r_ab + (-p_b - p_a) f' r_ab']
 * over its neighbours and the walls on its side, and its own image's (-2 p_a) f' r_aa' */
void implicit_image_gradient_sum(const surge_sim *sim, int i, const double *x, double *sx, double *sy)
{
    const implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const double pa = w->fixed[i] ? 0.0 : x[i];
    double gx = -2 * pa * w->own_igx[i], gy = -2 * pa * w->own_igy[i];
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
        const int j = nl->fluid_index[e] - sim->wall_count;
        const double pb = w->fixed[j] ? 0.0 : x[j];
        gx += (pb - pa) * w->fluid_gx[e] - (pb + pa) * w->fluid_igx[e];
        gy += (pb - pa) * w->fluid_gy[e] - (pb + pa) * w->fluid_igy[e];
    }
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
        const double pw = w->wall_x[nl->wall_index[e]], side = w->wall_side[e];
        gx += side * ((pw - pa) * w->wall_gx[e] - (pw + pa) * w->wall_igx[e]);
        gy += side * ((pw - pa) * w->wall_gy[e] - (pw + pa) * w->wall_igy[e]);
    }
    *sx = gx, *sy = gy;
}

/* The velocity gradient's sum G = -sum_b V_b v_ab (x) (f r_ab + f' r_ab') for an imaged particle (the images carry
 * their particle's velocity; its own image adds nothing), walls at wall_x, wall_y on its side */
void implicit_image_velocity_gradient(const surge_sim *sim, int i, double g[4])
{
    const implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int a = sim->wall_count + i;
    const double vxa = sim->vx[a], vya = sim->vy[a];
    g[0] = g[1] = g[2] = g[3] = 0;
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
        const int b = nl->fluid_index[e];
        const double dvx = vxa - sim->vx[b], dvy = vya - sim->vy[b];
        const double fx = w->fluid_gx[e] + w->fluid_igx[e], fy = w->fluid_gy[e] + w->fluid_igy[e];
        g[0] -= dvx * fx, g[1] -= dvx * fy, g[2] -= dvy * fx, g[3] -= dvy * fy;
    }
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
        const int kw = nl->wall_index[e];
        const double side = w->wall_side[e];
        const double dvx = side * (vxa - w->wall_x[kw]), dvy = side * (vya - w->wall_y[kw]);
        const double fx = w->wall_gx[e] + w->wall_igx[e], fy = w->wall_gy[e] + w->wall_igy[e];
        g[0] -= dvx * fx, g[1] -= dvx * fy, g[2] -= dvy * fx, g[3] -= dvy * fy;
    }
}

/* The corrected Laplacian's row of an imaged particle (implicit_assemble_pressure): a neighbour's term
 * (w_ab + u.V f r_ab)(p_a - p_b), its image's (w_ab' + u.V f' r_ab')(p_a + p_b), its own image's 2 (..) p_a; the
 * coefficients into fluid_pc and wall_pc, the diagonal returned */
double implicit_image_laplacian_row(surge_sim *sim, int i, double ux, double uy)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    double diag = 2 * (w->own_iw[i] + ux * w->own_igx[i] + uy * w->own_igy[i]);
    for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
        const double c = w->fluid_w[e] + ux * w->fluid_gx[e] + uy * w->fluid_gy[e];
        const double image = w->fluid_iw[e] + ux * w->fluid_igx[e] + uy * w->fluid_igy[e];
        diag += c + image;
        w->fluid_pc[e] = (real)(w->fixed[nl->fluid_index[e] - sim->wall_count] ? 0.0 : image - c);
    }
    for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
        const double side = w->wall_side[e];
        const double c = side * (w->wall_w[e] + ux * w->wall_gx[e] + uy * w->wall_gy[e]);
        const double image = w->wall_iw[e] + ux * w->wall_igx[e] + uy * w->wall_igy[e];
        diag += c + image;
        w->wall_pc[e] = (real)(image - c);
    }
    return diag;
}
