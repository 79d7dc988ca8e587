/* BiCGSTAB, matrix-free on the implicit scheme's operators, with the diagonal or a multigrid V-cycle as its
 * preconditioner; dot products in fixed blocks, so the result does not depend on the thread count. A vector update
 * and the dot products of its result share one parallel loop over the blocks: each region wakes the waiting threads
 * (tens of microseconds where they sleep, docs/performance.md, "Waiting threads"), and the block sums are those the
 * dot products alone would add, in the same order. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"

static int dot_blocks(int n) { return (n + DOT_BLOCK - 1) / DOT_BLOCK; }

/* The blocks' partial sums (DOT_BLOCK entries each) added in order */
static double block_total(const double *partial, int blocks)
{
    double sum = 0;
    for (int k = 0; k < blocks; k++)
        sum += partial[k];
    return sum;
}

/* sum_i a_i b_i (b NULL: sum_i a_i) over n, in fixed blocks added in order: the same for any thread count */
double implicit_dot(const implicit_work *w, const double *a, const double *b, int n)
{
    const int blocks = dot_blocks(n);
    #pragma omp parallel for schedule(static) if (n >= WIDE_FLUID_PARTICLES)
    for (int k = 0; k < blocks; k++) {
        const int from = k * DOT_BLOCK, to = from + DOT_BLOCK < n ? from + DOT_BLOCK : n;
        double sum = 0;
        for (int i = from; i < to; i++)
            sum += b ? a[i] * b[i] : a[i];
        w->partial[k] = sum;
    }
    return block_total(w->partial, blocks);
}

/* out -= offset where F is affine (not linear), then rhat . out */
static double unoffset_dot(implicit_work *w, int linear, const double *rhat, double *out, int n)
{
    const int blocks = dot_blocks(n);
    const double *offset = w->offset;
    #pragma omp parallel for schedule(static) if (n >= WIDE_FLUID_PARTICLES)
    for (int k = 0; k < blocks; k++) {
        const int from = k * DOT_BLOCK, to = from + DOT_BLOCK < n ? from + DOT_BLOCK : n;
        double sum = 0;
        for (int i = from; i < to; i++) {
            if (!linear)
                out[i] -= offset[i];
            sum += rhat[i] * out[i];
        }
        w->partial[k] = sum;
    }
    return block_total(w->partial, blocks);
}

/* x += alpha y, s = r - alpha v; returns s . s */
static double step_alpha(implicit_work *w, double alpha, int n)
{
    const int blocks = dot_blocks(n);
    double *x = w->x, *s = w->s;
    const double *y = w->y, *r = w->r, *v = w->v;
    #pragma omp parallel for schedule(static) if (n >= WIDE_FLUID_PARTICLES)
    for (int k = 0; k < blocks; k++) {
        const int from = k * DOT_BLOCK, to = from + DOT_BLOCK < n ? from + DOT_BLOCK : n;
        double sum = 0;
        for (int i = from; i < to; i++) {
            x[i] += alpha * y[i];
            s[i] = r[i] - alpha * v[i];
            sum += s[i] * s[i];
        }
        w->partial[k] = sum;
    }
    return block_total(w->partial, blocks);
}

/* out -= offset where F is affine, then *tt = t . t and *ts = t . s (out is t) */
static void unoffset_dots_t(implicit_work *w, int linear, int n, double *tt, double *ts)
{
    const int blocks = dot_blocks(n);
    double *t = w->t, *second = w->partial + blocks;
    const double *offset = w->offset, *s = w->s;
    #pragma omp parallel for schedule(static) if (n >= WIDE_FLUID_PARTICLES)
    for (int k = 0; k < blocks; k++) {
        const int from = k * DOT_BLOCK, to = from + DOT_BLOCK < n ? from + DOT_BLOCK : n;
        double sum_tt = 0, sum_ts = 0;
        for (int i = from; i < to; i++) {
            if (!linear)
                t[i] -= offset[i];
            sum_tt += t[i] * t[i];
            sum_ts += t[i] * s[i];
        }
        w->partial[k] = sum_tt, second[k] = sum_ts;
    }
    *tt = block_total(w->partial, blocks);
    *ts = block_total(second, blocks);
}

/* x += omega z, r = s - omega t; *rr = r . r and *rhat_r = rhat . r */
static void step_omega(implicit_work *w, double omega, int n, double *rr, double *rhat_r)
{
    const int blocks = dot_blocks(n);
    double *x = w->x, *r = w->r, *second = w->partial + blocks;
    const double *z = w->z, *s = w->s, *t = w->t, *rhat = w->rhat;
    #pragma omp parallel for schedule(static) if (n >= WIDE_FLUID_PARTICLES)
    for (int k = 0; k < blocks; k++) {
        const int from = k * DOT_BLOCK, to = from + DOT_BLOCK < n ? from + DOT_BLOCK : n;
        double sum_rr = 0, sum_rhat_r = 0;
        for (int i = from; i < to; i++) {
            x[i] += omega * z[i];
            r[i] = s[i] - omega * t[i];
            sum_rr += r[i] * r[i];
            sum_rhat_r += rhat[i] * r[i];
        }
        w->partial[k] = sum_rr, second[k] = sum_rhat_r;
    }
    *rr = block_total(w->partial, blocks);
    *rhat_r = block_total(second, blocks);
}

/* The linear part of the operator: F(x) - F(0) (offset holds F(0)), or F(x) itself where F is linear */
static void apply_linear(surge_sim *sim, affine_operator op, int linear, const double *x, double *out, int n)
{
    op(sim, x, out);
    if (linear)
        return;
    const double *offset = implicit_of(sim)->offset;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < n; i++)
        out[i] -= offset[i];
}

/* out = M^-1 in: the diagonal (Jacobi) or one V-cycle per block of nf unknowns (the fluid's) and the diagonal on the
 * rows after them (the discs'), where lubrication films join discs their blocks solved directly (films.c); -1 when
 * hypre fails */
static int precondition(surge_sim *sim, const double *in, double *out, int n)
{
    implicit_work *w = implicit_of(sim);
    const int nf = sim->count - sim->wall_count;
    if (w->vcycle_blocks == 0) {
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < n; i++)
            out[i] = in[i] / w->diag[i];
    } else {
        if (amg_vcycle(w->amg, w->vcycle_blocks, in, out) != 0)
            return -1;
        for (int i = w->vcycle_blocks * nf; i < n; i++)
            out[i] = in[i] / w->diag[i];
    }
    if (w->film_blocks.factored && n == 2 * nf + w->disc_rows) { /* the viscous solve's disc rows */
        memcpy(out + 2 * nf, in + 2 * nf, (size_t)w->disc_rows * sizeof *out);
        implicit_films_solve(sim, FILMS_VISCOUS, out + 2 * nf);
        for (int q = 0; q < w->disc_rows; q++) /* the discs outside blocks keep the diagonal */
            if (w->film_blocks.of_disc[q / 3] < 0)
                out[2 * nf + q] = in[2 * nf + q] / w->diag[2 * nf + q];
    }
    if (w->vcycle_blocks > 0 && w->vcycle_honours_fixed) /* the pressure's free-surface rows are the identity (held hierarchies differ) */
        for (int i = 0; i < nf; i++)
            if (w->fixed[i])
                out[i] = in[i];
    return 0;
}

/* Solves F(x) = rhs for the affine operator op (n unknowns) by BiCGSTAB, preconditioned as precondition() says
 * (van der Vorst 1992), to |residual| <= tolerance |rhs - F(0)|, from the guess in x. homogeneous: F is linear
 * (F(0) = 0), LINEAR_FROM_ZERO where x is 0 too (no operator call before the iterations), LINEAR_FROM_GUESS from the
 * guess in x. Returns the iterations, or -1 when max_iterations pass first or the method breaks down; *residual: the
 * relative residual reached. */
int implicit_solve(surge_sim *sim, affine_operator op, int n, int homogeneous, double tolerance, int max_iterations,
                 double *residual)
{
    implicit_work *w = implicit_of(sim);
    double *x = w->x, *r = w->r, *rhat = w->rhat, *p = w->p, *v = w->v, *s = w->s, *t = w->t, *y = w->y, *z = w->z;
    const int from_guess = homogeneous == LINEAR_FROM_GUESS;
    if (from_guess)
        op(sim, x, r);
    else if (!homogeneous) {
        op(sim, (memset(y, 0, (size_t)n * sizeof *y), y), w->offset);
        apply_linear(sim, op, 0, x, r, n);
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < n; i++) {
        const double b = homogeneous ? w->rhs[i] : w->rhs[i] - w->offset[i];
        r[i] = homogeneous == LINEAR_FROM_ZERO ? b : b - r[i];
        rhat[i] = b; /* the shadow residual: the right-hand side (nonzero whenever there is work) */
        p[i] = v[i] = 0;
    }
    const double b_norm = sqrt(implicit_dot(w, rhat, rhat, n));
    double r_norm = sqrt(implicit_dot(w, r, r, n));
    *residual = b_norm > 0 ? r_norm / b_norm : 0;
    if (b_norm == 0 || r_norm <= tolerance * b_norm)
        return 0;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < n; i++)
        rhat[i] = r[i];
    double rho = 1, alpha = 1, omega = 1, rho_new = implicit_dot(w, rhat, r, n);
    for (int it = 1; it <= max_iterations; it++) {
        if (rho_new == 0 || omega == 0)
            return -1;
        const double beta = rho_new / rho * alpha / omega;
        rho = rho_new;
        #pragma omp parallel for schedule(static) if (wide(sim))
        for (int i = 0; i < n; i++)
            p[i] = r[i] + beta * (p[i] - omega * v[i]);
        if (precondition(sim, p, y, n) != 0)
            return -1;
        op(sim, y, v);
        const double rv = unoffset_dot(w, homogeneous, rhat, v, n);
        if (rv == 0)
            return -1;
        alpha = rho / rv;
        const double s_norm = sqrt(step_alpha(w, alpha, n));
        if (s_norm <= tolerance * b_norm) {
            *residual = s_norm / b_norm;
            return it;
        }
        if (precondition(sim, s, z, n) != 0)
            return -1;
        op(sim, z, t);
        double tt, ts, rr;
        unoffset_dots_t(w, homogeneous, n, &tt, &ts);
        omega = tt > 0 ? ts / tt : 0;
        step_omega(w, omega, n, &rr, &rho_new);
        r_norm = sqrt(rr);
        *residual = r_norm / b_norm;
        if (!isfinite(r_norm))
            return -1;
        if (r_norm <= tolerance * b_norm)
            return it;
    }
    return -1;
}
