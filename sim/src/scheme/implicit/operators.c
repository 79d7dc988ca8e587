/* The implicit scheme's operators on the neighbour lists: backward-Euler viscosity, the pressure Laplacian and
 * gradient, the walls' mirrored values, and the sparse stand-in the multigrid is built on. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"

/* Backward-Euler viscosity, F(v) = v - dt nu lap v with no-slip walls at 2 v_wall - v_ghost (or the quadratic fit's
 * value, wall_no_slip_value); x = (vx | vy). */
void implicit_viscous_operator(surge_sim *sim, const double *x, double *out)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    const double dt_nu = sim->dt_s * sim->params.fluid.viscosity_m2ps;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++) {
        const double ux = w->mirror_vx[kw], uy = w->mirror_vy[kw];
        w->wall_x[kw] = wall_no_slip_value(sim, kw, x, ux), w->wall_y[kw] = wall_no_slip_value(sim, kw, x + nf, uy);
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const double xa = x[i], ya = x[nf + i];
        double lx[PAIR_LANES] = {0}, ly[PAIR_LANES] = {0};
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int j = nl->fluid_index[e + l] - sim->wall_count;
                lx[l] += w->fluid_w[e + l] * (xa - x[j]), ly[l] += w->fluid_w[e + l] * (ya - x[nf + j]);
            }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int kw = nl->wall_index[e + l];
                lx[l] += w->wall_w[e + l] * (xa - w->wall_x[kw]), ly[l] += w->wall_w[e + l] * (ya - w->wall_y[kw]);
            }
        out[i] = xa + dt_nu * lanes_total(lx), out[nf + i] = ya + dt_nu * lanes_total(ly);
    }
}

/* The walls' pressure from the fluid pressure x: the value at the ghost plus the Neumann offset (none where
 * offset_pa is NULL: the solves' linear operator); dry walls 0. */
void implicit_wall_pressures(surge_sim *sim, const double *x, const double *offset_pa)
{
    implicit_work *w = implicit_of(sim);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int kw = 0; kw < sim->wall_count; kw++)
        w->wall_x[kw] = w->dry[kw] ? 0.0 : ghost_value(sim, kw, x) + (offset_pa ? offset_pa[kw] : 0.0);
}

/* The walls' Neumann offsets are the affine part of phi's operator: they go to the right-hand side, rhs_a -=
 * sum_w c_aw offset_w, and the solve takes the linear part alone */
void implicit_wall_offsets_to_rhs(surge_sim *sim, const double *offset_pa)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        if (w->fixed[i])
            continue;
        double sum = 0;
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
            const int kw = nl->wall_index[e];
            sum += w->dry[kw] ? 0.0 : w->wall_pc[e] * offset_pa[kw];
        }
        w->rhs[i] -= sum;
    }
}

/* The renormalised gradient of the pressure field x (free-surface particles at 0, walls at wall_x), exact for
 * a linear field: grad p_a = M^-1 sum_b V_b (p_b - p_a) f r_ab */
void implicit_pressure_gradient(surge_sim *sim, const double *x)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        if (w->imaged[i]) {
            double sx, sy;
            implicit_image_gradient_sum(sim, i, x, &sx, &sy);
            w->grad_x[i] = w->minv_xx[i] * sx + w->minv_xy[i] * sy;
            w->grad_y[i] = w->minv_xy[i] * sx + w->minv_yy[i] * sy;
            continue;
        }
        const double pa = w->fixed[i] ? 0.0 : x[i];
        double lx[PAIR_LANES] = {0}, ly[PAIR_LANES] = {0};
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int j = nl->fluid_index[e + l] - sim->wall_count;
                const double dpb = (w->fixed[j] ? 0.0 : x[j]) - pa;
                lx[l] += dpb * w->fluid_gx[e + l], ly[l] += dpb * w->fluid_gy[e + l];
            }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e += PAIR_LANES)
            for (int l = 0; l < PAIR_LANES; l++) {
                const int kw = nl->wall_index[e + l];
                const double dpb = (w->wall_x[kw] - pa) * w->wetness[kw]; /* dry walls: air, as in implicit_geometry() */
                lx[l] += dpb * w->wall_gx[e + l], ly[l] += dpb * w->wall_gy[e + l];
            }
        const double sx = lanes_total(lx), sy = lanes_total(ly);
        w->grad_x[i] = w->minv_xx[i] * sx + w->minv_xy[i] * sy;
        w->grad_y[i] = w->minv_xy[i] * sx + w->minv_yy[i] * sy;
    }
}

/* -lap p, corrected for the kernel's truncation: sum_b w_ab (p_a - p_b - r_ab . grad p_a), which is exact (zero)
 * for a linear field also next to the free surface and the walls, where the plain sum is not; p = 0 held on
 * free-surface particles (their rows are the identity). With grad p_a = M^-1 sum_b V_b (p_b - p_a) f r_ab (walls
 * by their wetness) and u_a = M^-1 sum_b w_ab r_ab, each neighbour's term is (w_ab + q_ab)(p_a - p_b) with
 * q_ab = u_a . V_b f r_ab: the step's coefficients, computed once here for the two solves (phi and psi) that use
 * them, so that an iteration is one gather (a free-surface neighbour's coefficient is 0, its p held at 0). */
void implicit_assemble_pressure(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const double wrx = w->weighted_rx[i], wry = w->weighted_ry[i];
        const double ux = w->minv_xx[i] * wrx + w->minv_xy[i] * wry, uy = w->minv_xy[i] * wrx + w->minv_yy[i] * wry;
        if (w->imaged[i] && !w->fixed[i]) {
            w->pressure_diag[i] = implicit_image_laplacian_row(sim, i, ux, uy);
            continue;
        }
        double diag = 0;
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
            const double c = w->fluid_w[e] + ux * w->fluid_gx[e] + uy * w->fluid_gy[e];
            diag += c;
            w->fluid_pc[e] = (real)(w->fixed[nl->fluid_index[e] - sim->wall_count] ? 0.0 : -c);
        }
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) {
            const double c = pressure_wall_weight(w, i, e, nl->wall_index[e]);
            diag += c;
            w->wall_pc[e] = (real)-c;
        }
        w->pressure_diag[i] = w->fixed[i] ? 1.0 : diag;
    }
}

/* The multigrid's sparse stand-in for an operator on the fluid particles whose row i is diag[i], fluid_scale
 * fluid_coef[e] for each fluid neighbour and wall_scale wall_coef[e] for each wet wall neighbour, whose value the
 * operator takes from the wall's ghost node (with honour_fixed a free-surface particle's row is its diagonal
 * alone, the pressure's). Of each row's fluid entries only those at least SPARSE_KEEP of the row's largest (the
 * nearest neighbours) stay; the others, and each wet wall
 * neighbour's entry (its ghost's interpolation taken at the particle itself), are added to the diagonal, which
 * keeps every row's sum: the same operator on a constant and on smooth fields, a few entries a row instead of a
 * kernel's 80. A preconditioner only: the solve iterates on the operator itself. -1 when out of memory. */
int implicit_assemble_sparse(surge_sim *sim, const double *diag, const real *fluid_coef, double fluid_scale,
                           const real *wall_coef, double wall_scale, int honour_fixed)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int first = sim->wall_count, nf = sim->count - first;
    /* each row is written once, where it has room for all its entries (fluid_first[i] + i: its fluid neighbours and
     * the diagonal), then the rows are closed up */
    const size_t room = (size_t)nl->fluid_first[nf] + (size_t)nf;
    if (!w->matrix_first && !(w->matrix_first = malloc((size_t)(nf + 1) * sizeof *w->matrix_first)))
        return -1;
    if (room > w->matrix_cap || !w->matrix_col) {
        const size_t grown = implicit_room_for(room);
        int32_t *col = realloc(w->matrix_col, grown * sizeof *col);
        if (col)
            w->matrix_col = col;
        double *val = col ? realloc(w->matrix_val, grown * sizeof *val) : NULL;
        if (!val)
            return -1;
        w->matrix_val = val, w->matrix_cap = grown;
    }
    int64_t *row_first = w->matrix_first;
    int32_t *restrict col = w->matrix_col;
    double *restrict val = w->matrix_val;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int64_t start = nl->fluid_first[i] + i;
        int64_t at = start;
        double d = diag[i];
        col[at] = i;
        if (honour_fixed && w->fixed[i]) {
            /* a free-surface row is its diagonal alone, at the size it has off the surface, so that a hierarchy
             * held over steps (implicit_multigrid_setup) serves the particle when it leaves the surface */
            double coupled = 0;
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
                coupled -= fluid_scale * fluid_coef[e];
            for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++)
                coupled -= w->dry[nl->wall_index[e]] ? 0.0 : wall_scale * wall_coef[e];
            d = coupled > 0 ? coupled : d;
        } else {
            double largest = 0;
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
                largest = fabs((double)fluid_coef[e]) > largest ? fabs((double)fluid_coef[e]) : largest;
            const double smallest_kept = SPARSE_KEEP * largest;
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++) {
                if (fluid_coef[e] == 0)
                    continue;
                if (fabs((double)fluid_coef[e]) >= smallest_kept)
                    ++at, col[at] = nl->fluid_index[e] - first, val[at] = fluid_scale * fluid_coef[e];
                else
                    d += fluid_scale * fluid_coef[e];
            }
            for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++) /* the weights sum to 1 */
                d += w->dry[nl->wall_index[e]] ? 0.0 : wall_scale * wall_coef[e];
        }
        val[start] = d;
        row_first[i + 1] = at + 1 - start;
    }
    row_first[0] = 0;
    for (int i = 0; i < nf; i++) {
        const int64_t start = nl->fluid_first[i] + i, count = row_first[i + 1];
        row_first[i + 1] = row_first[i] + count;
        memmove(col + row_first[i], col + start, (size_t)count * sizeof *col);
        memmove(val + row_first[i], val + start, (size_t)count * sizeof *val);
    }
    return 0;
}

/* The operator of assemble_pressure applied to x, the walls at their ghosts' values (the linear part: no offsets) */
void implicit_pressure_operator(surge_sim *sim, const double *x, double *out)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    implicit_wall_pressures(sim, x, NULL);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        double sum[PAIR_LANES] = {0};
        if (!w->fixed[i]) {
            for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e += PAIR_LANES)
                for (int l = 0; l < PAIR_LANES; l++)
                    sum[l] += w->fluid_pc[e + l] * x[nl->fluid_index[e + l] - sim->wall_count];
            for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e += PAIR_LANES)
                for (int l = 0; l < PAIR_LANES; l++)
                    sum[l] += w->wall_pc[e + l] * w->wall_x[nl->wall_index[e + l]];
        }
        out[i] = w->pressure_diag[i] * x[i] + lanes_total(sum);
    }
}

/* p relaxed by one weighted Jacobi sweep of the corrected Laplacian, p_a - beta (L p)_a / L_aa, the walls at their
 * ghosts' values plus offset_pa (implicit.pressure_relaxation; docs/method.md, "Relaxation of the last step's pressure"): a linear field
 * (the hydrostatic pressure, also next to the walls and, with its images, the free surface) is kept, a field that
 * alternates from particle to particle decays. Those are the near-null modes of the step's divergence of the
 * gradient, which the incremental projection carries from step to step undamped and a small asymmetry then grows. */
void implicit_relax_pressure(surge_sim *sim, double *p, const double *offset_pa, double beta)
{
    implicit_work *w = implicit_of(sim);
    const neighbour_lists *nl = &sim->neighbours;
    const int nf = sim->count - sim->wall_count;
    double *relaxed = w->phi_saved;
    implicit_wall_pressures(sim, p, offset_pa);
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        if (w->fixed[i]) {
            relaxed[i] = 0;
            continue;
        }
        double sum = w->pressure_diag[i] * p[i];
        for (int64_t e = nl->fluid_first[i]; e < nl->fluid_first[i + 1]; e++)
            sum += w->fluid_pc[e] * p[nl->fluid_index[e] - sim->wall_count];
        for (int64_t e = nl->wall_first[i]; e < nl->wall_first[i + 1]; e++)
            sum += w->wall_pc[e] * w->wall_x[nl->wall_index[e]];
        relaxed[i] = p[i] - beta * sum / w->pressure_diag[i];
    }
    memcpy(p, relaxed, (size_t)nf * sizeof *p);
}
