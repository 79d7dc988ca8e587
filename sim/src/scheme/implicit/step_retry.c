/* A step taken again at half its length (implicit.step_halvings; docs/method.md, "Health monitor"). The scheme holds
 * rho0 through its solves, and what it leaves shows only in the spacing: a step long against the time two discs take
 * to close a thin gap squeezes the film's particles together within the step. So each step ends by reading the
 * kernel sum at the positions it ends at; where a fluid particle is compressed past the density bound, or where a
 * linear solve did not converge, the step is rolled back to its start (its fluid, discs, walls, the solver's guesses
 * and the contact solver's warm start) and taken again at half the length. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"
#include "boulders/contact_solver.h"
#include "health.h"

enum { SAVED_PRESSURE, SAVED_PHI, SAVED_PSI, SAVED_DVX, SAVED_DVY, SAVED_ARRAYS };

/* The by-id arrays a step changes and the next one starts from */
static void guess_arrays(implicit_work *w, double *arrays[SAVED_ARRAYS])
{
    arrays[SAVED_PRESSURE] = w->pressure_by_id, arrays[SAVED_PHI] = w->phi_by_id, arrays[SAVED_PSI] = w->psi_by_id;
    arrays[SAVED_DVX] = w->dvx_by_id, arrays[SAVED_DVY] = w->dvy_by_id;
}

int implicit_retry_save(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const size_t count = (size_t)sim->count;
    if (w->saved_capacity < count) {
        double *grown = realloc(w->saved_by_id, SAVED_ARRAYS * count * sizeof *grown);
        if (!grown)
            return -1;
        w->saved_by_id = grown, w->saved_capacity = count;
    }
    double *arrays[SAVED_ARRAYS];
    guess_arrays(w, arrays);
    for (int k = 0; k < SAVED_ARRAYS; k++)
        memcpy(w->saved_by_id + k * count, arrays[k], count * sizeof(double));
    const contact_solver *contacts = sim->boulders.contacts;
    w->saved_contacts = contacts ? contact_solver_cache_count(contacts) : 0;
    if (w->saved_contacts > w->saved_contact_capacity) {
        const size_t n = (size_t)w->saved_contacts;
        int64_t *keys = realloc(w->saved_contact_keys, n * sizeof *keys);
        if (keys)
            w->saved_contact_keys = keys;
        double *lambdas = realloc(w->saved_lambdas, 2 * n * sizeof *lambdas);
        if (lambdas)
            w->saved_lambdas = lambdas;
        if (!keys || !lambdas)
            return -1;
        w->saved_contact_capacity = w->saved_contacts;
    }
    if (w->saved_contacts > 0)
        contact_solver_cache_get(contacts, w->saved_contact_keys, w->saved_lambdas,
                                 w->saved_lambdas + w->saved_contacts);
    return 0;
}

int implicit_retry_restore(surge_sim *sim)
{
    implicit_work *w = implicit_of(sim);
    const size_t count = (size_t)sim->count;
    double *arrays[SAVED_ARRAYS];
    guess_arrays(w, arrays);
    for (int k = 0; k < SAVED_ARRAYS; k++)
        memcpy(arrays[k], w->saved_by_id + k * count, count * sizeof(double));
    if (!sim->boulders.contacts)
        return 0;
    return contact_solver_cache_set(sim->boulders.contacts, w->saved_contacts, w->saved_contact_keys, w->saved_lambdas,
                                    w->saved_lambdas + w->saved_contacts);
}

/* Fluid particle a's kernel sum over the lattice's, sum_b m W_ab / (rho0 lattice sum), its own term included, at the
 * positions the step ends at: the step's lists (built at its start, no skin) with each particle's displacement since
 * their build. A pair that came within the kernel's support during the step from beyond it is missed; it adds at most
 * W at 2h less the step's approach, about nothing. */
static double end_kernel_ratio(const surge_sim *sim, int a)
{
    const neighbour_lists *nl = &sim->neighbours;
    const kernel2d *k = &sim->kernel;
    const int i = a - sim->wall_count;
    const double ax = sim->x[a] - nl->x_build[a], ay = sim->y[a] - nl->y_build[a];
    double sum = k->alpha;
    for (int walls = 0; walls < 2; walls++) {
        const int64_t from = walls ? nl->wall_first[i] : nl->fluid_first[i];
        const int64_t to = walls ? nl->wall_first[i + 1] : nl->fluid_first[i + 1];
        const int32_t *index = walls ? nl->wall_index : nl->fluid_index;
        const real *dx0 = walls ? nl->wall_dx0 : nl->fluid_dx0, *dy0 = walls ? nl->wall_dy0 : nl->fluid_dy0;
        for (int64_t e = from; e < to; e++) {
            const int b = index[e];
            const double dx = dx0[e] + (ax - (sim->x[b] - nl->x_build[b]));
            const double dy = dy0[e] + (ay - (sim->y[b] - nl->y_build[b]));
            const double r2 = dx * dx + dy * dy;
            if (r2 < k->support2 && r2 > 0)
                sum += kernel2d_w_inside(k->alpha, k->inv_h, (real)sqrt(r2));
        }
    }
    return sim->mass * sum / (sim->lattice_kernel_sum * sim->rho0);
}

int implicit_end_compression(surge_sim *sim, double share)
{
    const int first = sim->wall_count, n = sim->count;
    const double bound = sim->params.health.max_density_deviation;
    int worst = n;
    #pragma omp parallel for schedule(static) reduction(min : worst) if (wide(sim))
    for (int a = first; a < n; a++)
        if (a < worst && end_kernel_ratio(sim, a) > 1.0 + bound)
            worst = a;
    if (worst == n)
        return 0;
    const double ratio = end_kernel_ratio(sim, worst);
    surge_health *h = &sim->health;
    *h = (surge_health){.check = SURGE_CHECK_DENSITY, .particle_id = sim->id[worst], .step = sim->step,
                        .time_s = sim->time_s, .value = ratio};
    snprintf(h->message, sizeof h->message,
             "health check failed: %s at particle %d, step %lld, t = %.9g s (rho/rho0 = %.6g where the step ends, "
             "allowed 1 +- %g, the step at %g of its length; the run keeps its start)",
             surge_health_check_name(h->check), h->particle_id, (long long)h->step, h->time_s, ratio, bound, share);
    return -1;
}
