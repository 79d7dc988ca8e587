/* Anderson's acceleration of the passes with discs (implicit.disc_pressure_history): the pressure of the next pass
 * combined from the last passes' results, as Walker and Ni (2011, SIAM J. Numer. Anal. 49, 1715), eqs. 2.1-2.3:
 *
 *     x_k+1 = g_k - sum_j gamma_j (g_j+1 - g_j),   gamma = argmin || f_k - sum_j gamma_j (f_j+1 - f_j) ||,
 *
 * x_k the pressure a pass starts from, g_k = x_k + the pass's update (what the plain iteration takes next) and
 * f_k = g_k - x_k, over the last m differences. On a linear map it is GMRES's iteration (their Sect. 4). The
 * particles that take no update (the free surface and its kernel) take g_k as the plain iteration does. Dot
 * products in fixed blocks (implicit_dot): the same result for any thread count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"

#define MAX_HISTORY 16

/* The arrays for `depth` differences over nf particles; -1 when out of memory */
int implicit_mixing_reserve(implicit_work *w, int depth, int nf)
{
    if (depth <= w->mixing_cap)
        return 0;
    const size_t ring = (size_t)depth * (size_t)nf;
    double *dg = realloc(w->mixing_dg, ring * sizeof *dg);
    if (dg)
        w->mixing_dg = dg;
    double *df = realloc(w->mixing_df, ring * sizeof *df);
    if (df)
        w->mixing_df = df;
    if (!dg || !df)
        return -1;
    double **single[] = {&w->mixing_x, &w->mixing_g, &w->mixing_f};
    for (size_t k = 0; k < sizeof single / sizeof single[0]; k++)
        if (!*single[k] && !(*single[k] = malloc(((size_t)nf + 1) * sizeof **single[k])))
            return -1;
    w->mixing_cap = depth;
    return 0;
}

/* Solves the normal equations G gamma = b of the least-squares problem (G symmetric, n x n) by Cholesky's
 * factorisation; 0 when G is numerically singular: a pivot below 1e-12 of its diagonal entry, or below 1e-12 of
 * f_squared, the squared norm of the residual f_k that the differences are to reduce (a difference a millionth of
 * the residual is round-off, and its gamma of order 1e10 threw a disc in shear at 13 rad/s in one pass) */
static int solve_normal(double g[MAX_HISTORY][MAX_HISTORY], double *b, int n, double f_squared)
{
    for (int j = 0; j < n; j++) {
        const double diagonal = g[j][j];
        for (int k = 0; k < j; k++)
            g[j][j] -= g[j][k] * g[j][k];
        if (!(g[j][j] > 1e-12 * diagonal && g[j][j] > 1e-12 * f_squared))
            return 0;
        g[j][j] = sqrt(g[j][j]);
        for (int i = j + 1; i < n; i++) {
            for (int k = 0; k < j; k++)
                g[i][j] -= g[i][k] * g[j][k];
            g[i][j] /= g[j][j];
        }
    }
    for (int i = 0; i < n; i++) { /* L y = b, then L^T gamma = y */
        for (int k = 0; k < i; k++)
            b[i] -= g[i][k] * b[k];
        b[i] /= g[i][i];
    }
    for (int i = n - 1; i >= 0; i--) {
        for (int k = i + 1; k < n; k++)
            b[i] -= g[k][i] * b[k];
        b[i] /= g[i][i];
    }
    return 1;
}

/* The pass's update (w->divergence, 0 where a particle takes none) into w->pressure_n, which holds x_k (as the pass
 * used it); pass counts from 1 and starts the history afresh */
void implicit_mix_pressure(surge_sim *sim, int pass)
{
    implicit_work *w = implicit_of(sim);
    const int first = sim->wall_count, nf = sim->count - first;
    const int depth = sim->params.implicit.disc_pressure_history < MAX_HISTORY
                          ? sim->params.implicit.disc_pressure_history : MAX_HISTORY;
    double *x = w->pressure_n;
    const double *update = w->divergence;
    if (pass == 1)
        w->mixing_count = 0, w->mixing_next = 0;
    /* g_k, f_k (the relaxation under a free surface changes the pressure at the start of a pass: f_k is measured from
     * the pressure this mixing left, x_k before it), and the difference from the last pass's into the ring */
    const int have_last = pass > 1;
    double *dg = w->mixing_dg + (size_t)w->mixing_next * nf, *df = w->mixing_df + (size_t)w->mixing_next * nf;
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        const int takes = !(w->fixed[i] || sim->near_surface[first + i]);
        const double g = x[i] + update[i];
        const double f = takes ? g - (have_last ? w->mixing_x[i] : x[i]) : 0.0;
        if (have_last)
            dg[i] = takes ? g - w->mixing_g[i] : 0.0, df[i] = f - w->mixing_f[i];
        w->mixing_g[i] = g, w->mixing_f[i] = f;
    }
    if (have_last)
        w->mixing_next = (w->mixing_next + 1) % depth, w->mixing_count += w->mixing_count < depth;
    /* gamma over the newest differences; the oldest dropped while their normal equations are singular */
    double gamma[MAX_HISTORY] = {0};
    int used = w->mixing_count;
    const double f_squared = used > 0 ? implicit_dot(w, w->mixing_f, w->mixing_f, nf) : 0.0;
    while (used > 0) {
        double gram[MAX_HISTORY][MAX_HISTORY], b[MAX_HISTORY];
        for (int j = 0; j < used; j++) {
            const int cj = (w->mixing_next - 1 - j + depth) % depth; /* j = 0 the newest */
            const double *dfj = w->mixing_df + (size_t)cj * nf;
            b[j] = implicit_dot(w, dfj, w->mixing_f, nf);
            for (int l = 0; l <= j; l++) {
                const int cl = (w->mixing_next - 1 - l + depth) % depth;
                gram[j][l] = gram[l][j] = implicit_dot(w, dfj, w->mixing_df + (size_t)cl * nf, nf);
            }
        }
        if (solve_normal(gram, b, used, f_squared)) {
            memcpy(gamma, b, (size_t)used * sizeof *gamma);
            break;
        }
        used--;
    }
    #pragma omp parallel for schedule(static) if (wide(sim))
    for (int i = 0; i < nf; i++) {
        double next = w->mixing_g[i];
        for (int j = 0; j < used; j++)
            next -= gamma[j] * w->mixing_dg[(size_t)((w->mixing_next - 1 - j + depth) % depth) * nf + i];
        x[i] = next;
        w->mixing_x[i] = next;
    }
}
